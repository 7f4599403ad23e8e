"""Layer 1: footstep plan, step phases and the ZMP reference and bounds (paper Sec. III-IV).

The paper takes its ZMP reference as "pre-generated" (Sec. IV-A, used by eq. 18) from the
footholds P^f_k of eq. (21); it does not spell out the plan. This module writes it down.

Paper symbols -> code names:
    l_step -> ``WalkParams.step_length``, w_step -> ``WalkParams.step_width``,
    P^f_{k-1} (prior foot, eq. 21) -> ``FootstepPlan.swing_from[k]``,
    P^f_{k+1} (foothold, eq. 21) -> ``FootstepPlan.swing_to[k]``,
    Z^ref (eq. 18) -> :meth:`FootstepPlan.zmp_reference`,
    Z^min / Z^max (eq. 18) -> :meth:`FootstepPlan.zmp_bounds`.

Choices where the paper is vague:
- Feet start side by side at x = x0, y = +/- step_width / 2, z = 0 (positions are the sole
  centres, z = 0 on the ground). The robot stands until ``t_start`` (default 0.8 s).
- ``walk.n_steps`` walking steps alternate sides starting with ``first_swing``. Foothold k
  (k = 1..n) lands at x = x0 + k * step_length: the first swing moves a foot by one step
  length, later swings by two. One closing step then brings the trailing foot alongside the
  last foothold (feet together), so the plan has ``n_steps + 1`` steps in all.
- Every step is a double support (DSP, ``dsp_ratio * step_time``, both feet down) followed by
  a single support (SSP, the swing foot in the air). In the DSP of step k the ZMP reference
  moves linearly from the previous support foot centre (for the first step: the midpoint of
  the feet) to the support foot of step k; in the SSP it stays at the support foot centre.
- After the closing step the ZMP moves linearly to the midpoint of the feet over one more
  ``dsp_time`` (``final_dsp_time``) and stays there for a final stand of 1.0 s;
  ``t_end`` = end of the closing step + final_dsp_time + 1.0 s.
- ZMP bounds (eq. 18 constraint): in SSP the support foot box (``FOOT_SIZE`` = 0.30 x 0.17 m,
  centred on the foothold, axis-aligned: the feet never yaw in this plan) shrunk by
  ``margin``; in DSP and while standing, the axis-aligned bounding box of both feet shrunk by
  ``margin``. The true support polygon in DSP is the convex hull of the two feet; the
  bounding box contains it and is larger only at the corners between the feet. It is the
  simple, per-axis choice the decoupled x / y LIPM QP needs (box bounds per axis); the
  reference itself always lies on the segment between the foot centres, well inside the hull.
- Times outside [0, t_end] are clamped. All queries are vectorised over ``times``
  (``np.searchsorted`` on ``step_start``), so the MPC can ask for a whole horizon at once.
- :meth:`FootstepPlan.replanned` keeps every step that has started and re-plans the rest with
  new parameters; steps then have their own durations, so the authoritative timing is in the
  per-step arrays ``step_duration``, ``step_dsp`` and ``step_height``; the scalar
  ``dsp_time`` / ``ssp_time`` are those of ``walk`` (the newest parameters).
"""

from __future__ import annotations

import dataclasses
from bisect import bisect_right
from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np

from controller.params import WalkParams

LEFT, RIGHT = 0, 1
FOOT_SIZE = (0.30, 0.17)  # [m] sole length (x) and width (y); models.dyros_jet.FOOT_SIZE
FINAL_STAND = 1.0  # [s] stand after the ZMP reached the final midpoint


class StepPhase(NamedTuple):
    """Where the plan is at one instant.

    ``index`` is the step (-1 before the first, n after the last). While standing (before the
    first step or after the last) ``standing`` is True, ``in_dsp`` and ``in_ssp`` are False,
    ``swing_side`` is -1 and ``support_side`` is the support foot of the nearest step.
    ``s_ssp`` is the SSP progress in [0, 1] (0 in the DSP and before walking, 1 after).
    """

    index: int
    in_dsp: bool
    in_ssp: bool
    support_side: int
    swing_side: int
    s_ssp: float
    standing: bool


@dataclass(frozen=True)
class FootstepPlan:
    """Footholds and timing of a straight walk; arrays have one row per step (n in all)."""

    walk: WalkParams
    t_start: float  # [s] time the first step starts
    step_start: np.ndarray  # (n,) [s] start time of each step
    dsp_time: float  # [s] double support of the current parameters (dsp_ratio * step_time)
    ssp_time: float  # [s] single support of the current parameters
    swing_side: np.ndarray  # (n,) int, LEFT or RIGHT: the foot that swings in step k
    swing_from: np.ndarray  # (n, 3) [m] where the swing foot lifts off
    swing_to: np.ndarray  # (n, 3) [m] foothold where it lands
    support_pos: np.ndarray  # (n, 3) [m] the support foot during step k
    t_end: float  # [s] end of the final stand
    n_walking_steps: int  # steps that advance the feet (excludes the closing step)
    # -- per-step details (added; authoritative when a replan changed the timing) --
    step_duration: np.ndarray  # (n,) [s] DSP + SSP of each step
    step_dsp: np.ndarray  # (n,) [s] DSP of each step
    step_height: np.ndarray  # (n,) [m] swing-foot lift of each step
    zmp_from: np.ndarray  # (n, 2) [m] ZMP reference at the start of each step's DSP
    feet_init: np.ndarray  # (2, 3) [m] left, right before the first step
    feet_final: np.ndarray  # (2, 3) [m] left, right after the last step
    final_dsp_time: float  # [s] ZMP shift to the final midpoint after the last step

    # -- timing -------------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of steps, the closing step included."""
        return int(self.step_start.shape[0])

    @cached_property
    def walk_end(self) -> float:
        """[s] end of the last (closing) step."""
        return float(self.step_start[-1] + self.step_duration[-1])

    @cached_property
    def _rows(self) -> _PlanRows:
        """The per-step arrays as Python lists, for the scalar (one-instant) queries."""
        return _PlanRows(self)

    def _locate(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Clamped times, step index (-1..n), index clipped to 0..n-1, time into that step."""
        # np.minimum(np.maximum(.)) is np.clip without its Python-level overhead
        t = np.minimum(np.maximum(np.asarray(times, dtype=float), 0.0), self.t_end)
        idx = np.searchsorted(self.step_start, t, side="right") - 1
        idx = np.where(t >= self.walk_end, self.n, idx)
        k = np.minimum(np.maximum(idx, 0), self.n - 1)
        return t, idx, k, t - self.step_start[k]

    def _locate_one(self, t: float) -> tuple[float, int, int, float]:
        """:meth:`_locate` for one instant, in Python scalars (same arithmetic)."""
        r = self._rows
        t = min(max(float(t), 0.0), self.t_end)
        idx = bisect_right(r.start, t) - 1
        if t >= self.walk_end:
            idx = r.n
        k = min(max(idx, 0), r.n - 1)
        return t, idx, k, t - r.start[k]

    def step_index(self, t: float | np.ndarray) -> int | np.ndarray:
        """Step in progress at ``t``: -1 before the first step, n after the last."""
        _, idx, _, _ = self._locate(t)
        return int(idx) if np.ndim(idx) == 0 else idx

    def phase(self, t: float) -> StepPhase:
        """The phase of the plan at time ``t`` [s] (see :class:`StepPhase`)."""
        _, i, k, tau = self._locate_one(t)
        r = self._rows
        if i < 0 or i >= r.n:
            support = 1 - r.swing_side[k]
            return StepPhase(i, False, False, support, -1, 0.0 if i < 0 else 1.0, True)
        dsp = r.dsp[k]
        ssp = r.duration[k] - dsp
        in_dsp = tau < dsp
        s = 0.0 if in_dsp else min(max((tau - dsp) / max(ssp, 1e-9), 0.0), 1.0)
        swing = r.swing_side[k]
        return StepPhase(i, in_dsp, not in_dsp, 1 - swing, swing, s, False)

    def ssp_progress(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Vectorised: (step index -1..n, index clipped to 0..n-1, SSP progress in [0, 1]).

        The progress is 0 in the DSP and before walking, 1 after the last step.
        """
        _, idx, k, tau = self._locate(times)
        dsp = self.step_dsp[k]
        ssp = np.maximum(self.step_duration[k] - dsp, 1e-9)
        s = np.minimum(np.maximum((tau - dsp) / ssp, 0.0), 1.0)
        s = np.where(idx < 0, 0.0, np.where(idx >= self.n, 1.0, s))
        return idx, k, s

    def ssp_progress_one(self, t: float) -> tuple[int, int, float]:
        """:meth:`ssp_progress` for one instant ``t`` [s], in Python scalars."""
        _, idx, k, tau = self._locate_one(t)
        r = self._rows
        if idx < 0:
            return idx, k, 0.0
        if idx >= r.n:
            return idx, k, 1.0
        dsp = r.dsp[k]
        ssp = max(r.duration[k] - dsp, 1e-9)
        return idx, k, min(max((tau - dsp) / ssp, 0.0), 1.0)

    # -- ZMP ------------------------------------------------------------------------------
    def zmp_reference(self, times: np.ndarray) -> np.ndarray:
        """ZMP reference (N, 2) [m] at ``times`` [s]: linear shift in DSP, foot centre in SSP."""
        if np.ndim(times) == 0:
            return self.zmp_reference_one(float(times))
        return self._zmp_reference(self._locate(times))

    def _zmp_reference(self, loc: tuple[np.ndarray, ...]) -> np.ndarray:
        t, idx, k, tau = loc
        s = np.minimum(np.maximum(tau / np.maximum(self.step_dsp[k], 1e-9), 0.0), 1.0)[..., None]
        zmp_from = self.zmp_from[k]
        out = zmp_from + s * (self.support_pos[k, :2] - zmp_from)
        if (idx < 0).any():
            out = np.where((idx < 0)[..., None], self._rows.mid_init, out)
        if (idx >= self.n).any():
            last = self.support_pos[-1, :2]
            s_end = np.clip((t - self.walk_end) / max(self.final_dsp_time, 1e-9), 0.0, 1.0)
            after = last + s_end[..., None] * (self._rows.mid_final - last)
            out = np.where((idx >= self.n)[..., None], after, out)
        return out

    def zmp_reference_one(self, t: float) -> np.ndarray:
        """:meth:`zmp_reference` at one instant ``t`` [s]: (2,) [m] (same arithmetic)."""
        t, idx, k, tau = self._locate_one(t)
        r = self._rows
        if idx < 0:
            return r.mid_init.copy()
        if idx >= r.n:
            last = self.support_pos[-1, :2]
            s_end = min(max((t - self.walk_end) / max(self.final_dsp_time, 1e-9), 0.0), 1.0)
            return last + s_end * (r.mid_final - last)
        s = min(max(tau / max(r.dsp[k], 1e-9), 0.0), 1.0)
        (fx, fy), (sx, sy) = r.zmp_from[k], r.support_xy[k]
        return np.array([fx + s * (sx - fx), fy + s * (sy - fy)])

    def zmp_reference_and_bounds(
        self, times: np.ndarray, margin: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`zmp_reference` and :meth:`zmp_bounds` at the same ``times`` in one pass.

        Returns:
            (reference, lo, hi), each (N, 2) [m].
        """
        loc = self._locate(times)
        return (self._zmp_reference(loc), *self._zmp_bounds(loc, margin))

    def _ground_feet_at(self, loc: tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray]:
        _, idx, k, tau = loc
        in_ssp = tau >= self.step_dsp[k]
        a = self.support_pos[k, :2]
        b = np.where(in_ssp[..., None], a, self.swing_from[k, :2])
        before, after = idx < 0, idx >= self.n
        if before.any() or after.any():
            before, after = before[..., None], after[..., None]
            init, final = self.feet_init[:, :2], self.feet_final[:, :2]
            a = np.where(before, init[LEFT], np.where(after, final[LEFT], a))
            b = np.where(before, init[RIGHT], np.where(after, final[RIGHT], b))
        return a, b

    def zmp_bounds(self, times: np.ndarray, margin: float) -> tuple[np.ndarray, np.ndarray]:
        """ZMP box (lo (N, 2), hi (N, 2)) [m]: support foot in SSP, both feet's box otherwise.

        Args:
            times: (N,) [s] query times.
            margin: [m] distance kept from the foot edges.
        """
        return self._zmp_bounds(self._locate(times), margin)

    def _zmp_bounds(
        self, loc: tuple[np.ndarray, ...], margin: float
    ) -> tuple[np.ndarray, np.ndarray]:
        a, b = self._ground_feet_at(loc)
        half = np.maximum(np.array(FOOT_SIZE) / 2.0 - margin, 0.0)
        return np.minimum(a, b) - half, np.maximum(a, b) + half

    def feet_on_ground(self, times: np.ndarray) -> np.ndarray:
        """(N, 2) bool, [left, right] on the ground according to the plan."""
        _, idx, k, tau = self._locate(times)
        walking = (idx >= 0) & (idx < self.n)
        in_air = walking & (tau >= self.step_dsp[k])
        side = self.swing_side[k]
        return np.stack([~(in_air & (side == LEFT)), ~(in_air & (side == RIGHT))], axis=-1)

    def footholds(self) -> np.ndarray:
        """(n + 2, 3) [m] every planned foot position in order: left, right initial, landings."""
        return np.vstack([self.feet_init, self.swing_to])

    # -- replanning -----------------------------------------------------------------------
    def replanned(self, walk: WalkParams, t_now: float) -> FootstepPlan:
        """A plan that keeps every step started by ``t_now`` and re-plans the rest with ``walk``.

        The next foothold advances ``walk.step_length`` from the current step's landing point;
        the total number of walking steps becomes ``walk.n_steps`` (at least the steps already
        started). Once the closing step has started nothing but ``walk`` changes.
        """
        started = int(np.searchsorted(self.step_start, t_now, side="right"))  # steps kept
        if started == 0:
            return plan_footsteps(
                walk, self.t_start, int(self.swing_side[0]), float(self.feet_init[LEFT, 0])
            )
        if started > self.n_walking_steps:  # the closing step has started
            return dataclasses.replace(
                self, walk=walk, dsp_time=walk.dsp_ratio * walk.step_time,
                ssp_time=walk.step_time - walk.dsp_ratio * walk.step_time,
            )
        steps = _Steps()
        for j in range(started):
            steps.add(
                float(self.step_start[j]), float(self.step_duration[j]), float(self.step_dsp[j]),
                float(self.step_height[j]), int(self.swing_side[j]), self.swing_from[j],
                self.swing_to[j], self.support_pos[j], self.zmp_from[j],
            )
        feet = self.feet_init.copy()
        for j in range(started):
            feet[int(self.swing_side[j])] = self.swing_to[j]
        n_walk = max(walk.n_steps, started)
        return _finish(walk, self.t_start, self.feet_init, steps, feet, n_walk - started)


class _PlanRows:
    """A plan's per-step arrays as Python lists (scalar queries avoid numpy's call overhead)."""

    def __init__(self, plan: FootstepPlan):
        self.n = plan.n
        self.start = plan.step_start.tolist()
        self.duration = plan.step_duration.tolist()
        self.dsp = plan.step_dsp.tolist()
        self.height = plan.step_height.tolist()
        self.swing_side = [int(v) for v in plan.swing_side]
        self.swing_from = plan.swing_from.tolist()
        self.swing_to = plan.swing_to.tolist()
        self.support_pos = plan.support_pos.tolist()
        self.support_xy = plan.support_pos[:, :2].tolist()
        self.zmp_from = plan.zmp_from[:, :2].tolist()
        self.feet_init = plan.feet_init.tolist()
        self.feet_final = plan.feet_final.tolist()
        self.mid_init = plan.feet_init[:, :2].mean(axis=0)  # (2,) [m]
        self.mid_final = plan.feet_final[:, :2].mean(axis=0)
        # One row per step with what a horizon query reads (one gather instead of many);
        # the derived columns are the same arithmetic the queries did per sample.
        dsp, sup = plan.step_dsp, plan.support_pos[:, :2]
        frm, to, zf = plan.swing_from[:, :2], plan.swing_to[:, :2], plan.zmp_from[:, :2]
        self.table = np.column_stack([
            dsp,  # 0: DSP [s]
            np.maximum(plan.step_duration - dsp, 1e-9),  # 1: SSP [s]
            np.maximum(dsp, 1e-9),  # 2: DSP, > 0 [s]
            sup, frm, to, zf,  # 3-4 support, 5-6 swing from, 7-8 swing to, 9-10 ZMP from
            to - frm,  # 11-12
            sup - zf,  # 13-14
            plan.swing_side == LEFT,  # 15: 1.0 if the left foot swings
        ])


class _Steps:
    """Accumulates steps as lists (plans have tens of steps: a loop here is fine)."""

    def __init__(self) -> None:
        self.rows: list[tuple] = []

    def add(self, start, duration, dsp, height, side, frm, to, support, zmp_from) -> None:
        self.rows.append(
            (start, duration, dsp, height, side, np.array(frm, float), np.array(to, float),
             np.array(support, float), np.array(zmp_from, float)[:2])
        )

    def column(self, i: int, dtype: type = float) -> np.ndarray:
        return np.array([r[i] for r in self.rows], dtype=dtype)


def _finish(
    walk: WalkParams,
    t_start: float,
    feet_init: np.ndarray,
    steps: _Steps,
    feet: np.ndarray,
    n_more_walking: int,
    first_swing: int = LEFT,
) -> FootstepPlan:
    """Append ``n_more_walking`` walking steps and the closing step to ``steps``.

    ``first_swing`` is used only when ``steps`` is empty; otherwise the sides alternate.
    """
    feet = np.array(feet, dtype=float)
    dsp = walk.dsp_ratio * walk.step_time
    half_w = walk.step_width / 2.0
    if steps.rows:
        last = steps.rows[-1]
        t = last[0] + last[1]
        swing = 1 - last[4]
        zmp_prev = last[7][:2]
    else:
        t = t_start
        swing = first_swing
        zmp_prev = feet[:, :2].mean(axis=0)
    n_walk = len(steps.rows) + n_more_walking
    for j in range(n_more_walking + 1):
        support = feet[1 - swing].copy()
        y = half_w if swing == LEFT else -half_w
        if j < n_more_walking:
            to = np.array([support[0] + walk.step_length, y, 0.0])
        else:  # closing step: alongside the last foothold
            to = np.array([support[0], y, 0.0])
        steps.add(t, walk.step_time, dsp, walk.foot_height, swing, feet[swing], to, support,
                  zmp_prev)
        feet[swing] = to
        zmp_prev = support[:2]
        t += walk.step_time
        swing = 1 - swing
    final_dsp = dsp
    return FootstepPlan(
        walk=walk,
        t_start=float(t_start),
        step_start=steps.column(0),
        dsp_time=dsp,
        ssp_time=walk.step_time - dsp,
        swing_side=steps.column(4, int),
        swing_from=np.array([r[5] for r in steps.rows]),
        swing_to=np.array([r[6] for r in steps.rows]),
        support_pos=np.array([r[7] for r in steps.rows]),
        t_end=float(t + final_dsp + FINAL_STAND),
        n_walking_steps=int(n_walk),
        step_duration=steps.column(1),
        step_dsp=steps.column(2),
        step_height=steps.column(3),
        zmp_from=np.array([r[8] for r in steps.rows]),
        feet_init=np.array(feet_init, dtype=float),
        feet_final=feet,
        final_dsp_time=float(final_dsp),
    )


def plan_footsteps(
    walk: WalkParams, t_start: float = 0.8, first_swing: int = LEFT, x0: float = 0.0
) -> FootstepPlan:
    """Plan ``walk.n_steps`` straight steps plus a closing step, from feet side by side at x0.

    Args:
        walk: step length, time, DSP share, foot height, width and count.
        t_start: [s] time the first step starts (the robot stands before).
        first_swing: LEFT or RIGHT, the foot that swings first.
        x0: [m] initial x of both feet.
    """
    if first_swing not in (LEFT, RIGHT):
        raise ValueError(f"first_swing must be LEFT (0) or RIGHT (1), got {first_swing!r}")
    half_w = walk.step_width / 2.0
    feet = np.array([[x0, half_w, 0.0], [x0, -half_w, 0.0]])
    return _finish(walk, t_start, feet, _Steps(), feet, int(walk.n_steps), first_swing)
