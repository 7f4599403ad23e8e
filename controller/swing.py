"""Foot trajectories of eq. (20)-(21): support foot fixed, swing foot cubic.

Paper symbols -> code names:
    x_sp (eq. 20, support foot) -> the support foot's row of :class:`FootTrajectory`,
        constant at ``FootstepPlan.support_pos[k]`` with zero velocity;
    x_sw(t) (eq. 21) -> the swing foot's row; P^f_{k-1} -> ``plan.swing_from[k]``,
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
  analytic time derivatives. Everything is vectorised over ``times`` and can be queried at
  any (future) time, e.g. over an MPC horizon; times outside the plan are clamped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controller.footsteps import LEFT, RIGHT, FootstepPlan


@dataclass(frozen=True)
class FootTrajectory:
    """Planned sole positions and velocities of both feet at N times (world frame)."""

    p_left: np.ndarray  # (N, 3) [m]
    v_left: np.ndarray  # (N, 3) [m/s]
    p_right: np.ndarray  # (N, 3) [m]
    v_right: np.ndarray  # (N, 3) [m/s]


def foot_trajectories(plan: FootstepPlan, times: np.ndarray) -> FootTrajectory:
    """Both feet's planned positions and velocities at ``times`` [s] (eq. 20-21).

    Args:
        plan: the footstep plan.
        times: (N,) [s] query times (a scalar gives arrays of shape (3,)).
    """
    t = np.asarray(times, dtype=float)
    idx, k, s = plan.ssp_progress(t)
    walking = (idx >= 0) & (idx < plan.n)
    in_air = walking & (s > 0.0) & (s < 1.0)
    ssp = np.maximum(plan.step_duration[k] - plan.step_dsp[k], 1e-9)  # [s]
    p0, p1 = plan.swing_from[k], plan.swing_to[k]
    h = plan.step_height[k]
    # cubic with zero end velocities, eq. (21), in x, y (and z between the end heights)
    blend = (3.0 * s**2 - 2.0 * s**3)[..., None]
    dblend = ((6.0 * s - 6.0 * s**2) / ssp)[..., None]
    p_sw = p0 + (p1 - p0) * blend
    v_sw = (p1 - p0) * dblend
    p_sw[..., 2] += h * (1.0 - np.cos(2.0 * np.pi * s)) / 2.0
    v_sw[..., 2] += h * np.pi * np.sin(2.0 * np.pi * s) / ssp
    # where the swing foot is on the ground: at lift-off before the SSP, at the foothold after
    p_sw = np.where((s >= 1.0)[..., None], p1, p_sw)
    p_sw = np.where((s <= 0.0)[..., None], p0, p_sw)
    v_sw = np.where(in_air[..., None], v_sw, 0.0)

    out = []
    for side in (LEFT, RIGHT):
        swinging = walking & (plan.swing_side[k] == side)
        p = np.where(swinging[..., None], p_sw, plan.support_pos[k])
        p = np.where((idx < 0)[..., None], plan.feet_init[side], p)
        p = np.where((idx >= plan.n)[..., None], plan.feet_final[side], p)
        v = np.where(swinging[..., None], v_sw, 0.0)  # eq. (20): the support foot is still
        out += [p, v]
    return FootTrajectory(*out)
