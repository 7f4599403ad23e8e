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

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from controller.footsteps import FOOT_SIZE, LEFT, RIGHT, FootstepPlan


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
    if np.ndim(times) == 0:
        return _foot_state_one(plan, float(times))
    t = np.asarray(times, dtype=float)
    idx, k, s = plan.ssp_progress(t)
    walking = (idx >= 0) & (idx < plan.n)
    in_air = walking & (s > 0.0) & (s < 1.0)
    ssp = np.maximum(plan.step_duration[k] - plan.step_dsp[k], 1e-9)  # [s]
    p0, p1 = plan.swing_from[k], plan.swing_to[k]
    h = plan.step_height[k]
    # cubic with zero end velocities, eq. (21), in x, y (and z between the end heights)
    s2 = s**2
    blend = (3.0 * s2 - 2.0 * s**3)[..., None]
    dblend = ((6.0 * s - 6.0 * s2) / ssp)[..., None]
    dp = p1 - p0
    p_sw = p0 + dp * blend
    v_sw = dp * dblend
    p_sw[..., 2] += h * (1.0 - np.cos(2.0 * np.pi * s)) / 2.0
    v_sw[..., 2] += h * np.pi * np.sin(2.0 * np.pi * s) / ssp
    # where the swing foot is on the ground: at lift-off before the SSP, at the foothold after
    p_sw = np.where((s >= 1.0)[..., None], p1, p_sw)
    p_sw = np.where((s <= 0.0)[..., None], p0, p_sw)
    v_sw = np.where(in_air[..., None], v_sw, 0.0)

    before, after = idx < 0, idx >= plan.n
    clamp = bool(before.any() or after.any())
    support = plan.support_pos[k]
    side_k = plan.swing_side[k]
    out = []
    for side in (LEFT, RIGHT):
        swinging = (walking & (side_k == side))[..., None]
        p = np.where(swinging, p_sw, support)
        if clamp:
            p = np.where(before[..., None], plan.feet_init[side], p)
            p = np.where(after[..., None], plan.feet_final[side], p)
        v = np.where(swinging, v_sw, 0.0)  # eq. (20): the support foot is still
        out += [p, v]
    return FootTrajectory(*out)


class HorizonQueries(NamedTuple):
    """What a tick reads from the plan over the MPC horizon (see :func:`horizon_queries`)."""

    zmp_ref: np.ndarray  # (N, 2) [m] FootstepPlan.zmp_reference
    zmp_lo: np.ndarray  # (N, 2) [m] FootstepPlan.zmp_bounds
    zmp_hi: np.ndarray  # (N, 2) [m]
    p_left_xy: np.ndarray  # (N, 2) [m] foot_trajectories(...).p_left[:, :2]
    p_right_xy: np.ndarray  # (N, 2) [m] foot_trajectories(...).p_right[:, :2]


def horizon_queries(plan: FootstepPlan, times: np.ndarray, margin: float) -> HorizonQueries:
    """ZMP reference and bounds (eq. 18) and both feet's x-y (eq. 20-21) at ``times``, one pass.

    Equal to :meth:`FootstepPlan.zmp_reference`, :meth:`FootstepPlan.zmp_bounds` (with
    ``margin`` [m]) and the x-y of :func:`foot_trajectories`' positions (the same arithmetic,
    without the lift and the velocities), but the step lookup and the per-step rows are
    fetched once for all of them: what a tick reads over the MPC horizon.
    """
    t, idx, k, tau = plan._locate(times)
    before, after = idx < 0, idx >= plan.n
    clamp = bool(before.any() or after.any())  # times outside the walking steps
    rows = plan._rows.table[k]  # (N, 16), see _PlanRows
    dsp = rows[:, 0]
    support, frm, to = rows[:, 3:5], rows[:, 5:7], rows[:, 7:9]
    # ZMP reference: linear shift in DSP, support foot centre in SSP
    s_dsp = np.minimum(np.maximum(tau / rows[:, 2], 0.0), 1.0)[..., None]
    ref = rows[:, 9:11] + s_dsp * rows[:, 13:15]  # zmp_from + s (support - zmp_from)
    # ZMP box corners: the support foot in SSP, both feet otherwise
    a = support
    b = np.where((tau >= dsp)[..., None], a, frm)
    # swing foot x-y (eq. 21) from the SSP progress s
    s = np.minimum(np.maximum((tau - dsp) / rows[:, 1], 0.0), 1.0)
    if clamp:
        s = np.where(before, 0.0, np.where(after, 1.0, s))
    blend = (3.0 * s**2 - 2.0 * s**3)[..., None]
    p_sw = frm + rows[:, 11:13] * blend  # from + (to - from) blend
    p_sw = np.where((s >= 1.0)[..., None], to, p_sw)
    p_sw = np.where((s <= 0.0)[..., None], frm, p_sw)
    walking = ~(before | after)
    left_swings = rows[:, 15] == 1.0
    left = np.where((walking & left_swings)[..., None], p_sw, support)
    right = np.where((walking & ~left_swings)[..., None], p_sw, support)
    if clamp:
        pr = plan._rows
        b1, a1 = before[..., None], after[..., None]
        ref = np.where(b1, pr.mid_init, ref)
        if after.any():
            last = plan.support_pos[-1, :2]
            s_end = np.clip((t - plan.walk_end) / max(plan.final_dsp_time, 1e-9), 0.0, 1.0)
            ref = np.where(a1, last + s_end[..., None] * (pr.mid_final - last), ref)
        init, final = plan.feet_init[:, :2], plan.feet_final[:, :2]
        a = np.where(b1, init[LEFT], np.where(a1, final[LEFT], a))
        b = np.where(b1, init[RIGHT], np.where(a1, final[RIGHT], b))
        left = np.where(a1, final[LEFT], np.where(b1, init[LEFT], left))
        right = np.where(a1, final[RIGHT], np.where(b1, init[RIGHT], right))
    half = np.array([max(FOOT_SIZE[0] / 2.0 - margin, 0.0), max(FOOT_SIZE[1] / 2.0 - margin, 0.0)])
    return HorizonQueries(ref, np.minimum(a, b) - half, np.maximum(a, b) + half, left, right)


def _foot_state_one(plan: FootstepPlan, t: float) -> FootTrajectory:
    """:func:`foot_trajectories` at one instant, in Python scalars (the same arithmetic)."""
    r = plan._rows
    idx, k, s = plan.ssp_progress_one(t)
    walking = 0 <= idx < r.n
    p0, p1 = r.swing_from[k], r.swing_to[k]
    if walking and 0.0 < s < 1.0:  # in the air
        ssp = max(r.duration[k] - r.dsp[k], 1e-9)
        h = r.height[k]
        blend = 3.0 * s**2 - 2.0 * s**3
        dblend = (6.0 * s - 6.0 * s**2) / ssp
        p_sw = [a + (b - a) * blend for a, b in zip(p0, p1, strict=True)]
        v_sw = [(b - a) * dblend for a, b in zip(p0, p1, strict=True)]
        p_sw[2] += h * (1.0 - math.cos(2.0 * math.pi * s)) / 2.0
        v_sw[2] += h * math.pi * math.sin(2.0 * math.pi * s) / ssp
    else:  # on the ground: at lift-off before the SSP, at the foothold after
        p_sw = p1 if s >= 1.0 else p0
        v_sw = [0.0, 0.0, 0.0]
    out = []
    for side in (LEFT, RIGHT):
        swinging = walking and r.swing_side[k] == side
        if idx < 0:
            p = r.feet_init[side]
        elif idx >= r.n:
            p = r.feet_final[side]
        else:
            p = p_sw if swinging else r.support_pos[k]
        out += [np.array(p), np.array(v_sw if swinging else (0.0, 0.0, 0.0))]
    return FootTrajectory(*out)
