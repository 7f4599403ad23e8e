"""Foot trajectories of eq. (20)-(21): support foot fixed, swing foot cubic.

This module holds the swing curve itself; :meth:`controller.footsteps.FootstepPlan.sample`
(the one sampler of the plan) evaluates it for whichever step is in progress at each queried
time, so the feet can be read at any (future) instant, e.g. over the MPC horizon.

Paper symbols -> code names:
    x_sp (eq. 20, support foot) -> the support foot stays at ``FootstepPlan.support_pos[k]``
        with zero velocity (``PlanSample.p_left`` / ``p_right`` of the support side);
    x_sw(t) (eq. 21) -> :func:`swing_state`; P^f_{k-1} -> ``plan.swing_from[k]``,
        P^f_{k+1} -> ``plan.swing_to[k]``; t_0 / t_f -> start / end of step k's SSP.

Choices where the paper is vague:
- The swing foot stays on the ground during the DSP and moves during the SSP only, with
  s = (t - t_0) / (t_f - t_0) in [0, 1]. x and y follow the cubic of eq. (21) with zero velocity
  at both ends: p = p0 + (p1 - p0) (3 s^2 - 2 s^3).
- The lift (z, not specified by the paper) is z = h (1 - cos(2 pi s)) / 2 on top of the cubic
  between the lift-off and touch-down heights: zero velocity at both ends, peak h =
  ``plan.step_height[k]`` (``WalkParams.foot_height``) at s = 0.5.
- Positions are the sole centres in the world frame, z = 0 on the ground; the feet keep a
  zero orientation (straight walking), so only positions are returned. Velocities are the
  analytic time derivatives.
"""

from __future__ import annotations

import numpy as np


def swing_state(
    s: np.ndarray, p0: np.ndarray, p1: np.ndarray, height: np.ndarray, ssp: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Swing-foot position and velocity (eq. 21) at SSP progress ``s``.

    Args:
        s: (N,) SSP progress in [0, 1].
        p0, p1: (N, 3) [m] lift-off point and foothold.
        height: (N,) [m] lift at mid-swing.
        ssp: (N,) [s] SSP duration (> 0).

    Returns:
        (position (N, 3) [m], velocity (N, 3) [m/s]); exactly ``p0`` at s <= 0 and ``p1`` at
        s >= 1, with zero velocity there.
    """
    s2 = s * s
    blend = (3.0 * s2 - 2.0 * s2 * s)[:, None]
    dblend = ((6.0 * s - 6.0 * s2) / ssp)[:, None]
    dp = p1 - p0
    p = p0 + dp * blend
    v = dp * dblend
    two_pi_s = 2.0 * np.pi * s
    p[:, 2] += height * (1.0 - np.cos(two_pi_s)) / 2.0
    v[:, 2] += height * np.pi * np.sin(two_pi_s) / ssp
    # On the ground: exactly at the lift-off point before the SSP and at the foothold after
    # (the cubic's rounding would leave the landed foot a few 1e-17 m off).
    ground = ((s <= 0.0) | (s >= 1.0))[:, None]
    p = np.where(ground, np.where((s >= 1.0)[:, None], p1, p0), p)
    v = np.where(ground, 0.0, v)
    return p, v
