"""Layer 1: footstep plan, step phases, the feet's trajectories (eq. 20-21) and the ZMP
reference and bounds (paper Sec. III-IV).

The paper takes its ZMP reference as "pre-generated" (Sec. IV-A, used by eq. 18) from the
footholds P^f_k of eq. (21); it does not spell out the plan. This module writes it down.

Paper symbols -> code names:
    l_step -> ``WalkParams.step_length``, w_step -> ``WalkParams.step_width``,
    P^f_{k-1} (prior foot, eq. 21) -> ``FootstepPlan.swing_from[k]``,
    P^f_{k+1} (foothold, eq. 21) -> ``FootstepPlan.swing_to[k]``,
    Z^ref (eq. 18) -> ``PlanSample.zmp_ref``,
    Z^min / Z^max (eq. 18) -> ``PlanSample.zmp_lo`` / ``zmp_hi`` (:meth:`FootstepPlan.sample`),
    x_sp (eq. 20, support foot) -> stays at ``FootstepPlan.support_pos[k]`` with zero velocity
    (``PlanSample.p_left`` / ``p_right`` of the support side),
    x_sw(t) (eq. 21, swing foot) -> :func:`_swing_point`; t_0 / t_f -> start / end of step
    k's SSP.

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
- ``walk.dsp_split = "both_ends"`` (the authors' public implementation; docs/DESIGN.md,
  "Double-support timing") puts half
  of that DSP at the start of the step and half at its end, after the touch-down: the ZMP moves
  from the midpoint of the feet to the support foot in the first half, stays in the SSP, and
  moves on to the midpoint between the support foot and the landed foot in the second. Between
  two swings the robot stands on both feet for the same ``dsp_ratio * step_time`` and the ZMP
  follows the same line; what changes is where a step begins (mid-DSP) and the first and
  closing steps (half a DSP from standing, half a DSP into the final stand).
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
- The swing foot stays on the ground during the DSP and moves during the SSP only, with
  s = (t - t_0) / (t_f - t_0) in [0, 1]. x and y follow the cubic of eq. (21) with zero velocity
  at both ends: p = p0 + (p1 - p0) (3 s^2 - 2 s^3). The lift (z, not specified by the paper)
  is z = h (1 - cos(2 pi s)) / 2 on top of the cubic between the lift-off and touch-down
  heights: zero velocity at both ends, peak h = ``step_height[k]`` (``WalkParams.foot_height``)
  at s = 0.5. The feet keep a zero orientation (straight walking), so only positions are
  sampled; velocities are the analytic time derivatives.
- Times outside [0, t_end] are clamped. The one query, :meth:`FootstepPlan.sample`, is
  compiled and takes any number of ``times`` (a binary search of ``step_start`` each), so a
  tick asks for the present, the next tick and the whole MPC horizon at once.
- :meth:`FootstepPlan.replanned` keeps every step that has started and re-plans the rest with
  new parameters; steps then have their own durations, so the authoritative timing is in the
  per-step arrays ``step_duration``, ``step_dsp`` and ``step_height``; the scalar
  ``dsp_time`` / ``ssp_time`` are those of ``walk`` (the newest parameters).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from functools import cached_property
from operator import itemgetter
from typing import NamedTuple

import numpy as np

from controller.compiled import kernel
from controller.params import WalkParams
from models.dyros_jet import FOOT_SIZE

LEFT, RIGHT = 0, 1
FINAL_STAND = 1.0  # [s] stand after the ZMP reached the final midpoint


class PlanSample(NamedTuple):
    """The plan at N instants: phase, ZMP reference and bounds (eq. 18), feet (eq. 20-21).

    Every array has N rows, one per queried time. While standing (before the first step or
    after the last) ``standing`` is True, ``in_dsp`` and ``in_ssp`` are False, ``swing_side``
    is -1 and ``support_side`` is the support foot of the nearest step.
    """

    t: np.ndarray  # (N,) [s] the times, clamped to [0, t_end]
    step: np.ndarray  # (N,) int, step in progress: -1 before the first, n after the last
    standing: np.ndarray  # (N,) bool
    in_dsp: np.ndarray  # (N,) bool, both feet down inside a step
    in_ssp: np.ndarray  # (N,) bool, the swing foot in the air
    swing_side: np.ndarray  # (N,) int, LEFT / RIGHT, -1 while standing
    support_side: np.ndarray  # (N,) int, LEFT / RIGHT
    s_ssp: np.ndarray  # (N,) SSP progress in [0, 1] (0 in the DSP and before walking, 1 after)
    zmp_ref: np.ndarray  # (N, 2) [m] ZMP reference: linear shift in the DSP, foot centre in SSP
    zmp_lo: np.ndarray  # (N, 2) [m] ZMP box (eq. 18): the feet on the ground less the margin
    zmp_hi: np.ndarray  # (N, 2) [m]
    p_left: np.ndarray  # (N, 3) [m] left sole centre (world)
    v_left: np.ndarray  # (N, 3) [m/s]
    p_right: np.ndarray  # (N, 3) [m]
    v_right: np.ndarray  # (N, 3) [m/s]

    @property
    def on_ground(self) -> np.ndarray:
        """(N, 2) bool, [left, right] on the ground according to the plan."""
        in_air = self.in_ssp[:, None] & (self.swing_side[:, None] == np.array([LEFT, RIGHT]))
        return ~in_air


class PlanSteps(NamedTuple):
    """The plan as :meth:`FootstepPlan.sample` reads it: one row per step, and how the walk
    ends (:attr:`FootstepPlan.steps`)."""

    start: np.ndarray  # (n,) [s] start of each step
    dsp: np.ndarray  # (n,) [s] DSP before the lift-off
    ssp: np.ndarray  # (n,) [s] SSP, at least 1e-9
    dsp_end: np.ndarray  # (n,) [s] DSP after the touch-down
    height: np.ndarray  # (n,) [m] swing-foot lift
    swing_side: np.ndarray  # (n,) int, LEFT / RIGHT
    swing_from: np.ndarray  # (n, 3) [m] lift-off point
    swing_to: np.ndarray  # (n, 3) [m] foothold
    support: np.ndarray  # (n, 3) [m] support foot
    zmp_from: np.ndarray  # (n, 2) [m] ZMP reference at the step's start
    t_end: float  # [s] end of the final stand
    walk_end: float  # [s] end of the closing step
    feet_init: np.ndarray  # (2, 3) [m] left, right before the first step
    feet_final: np.ndarray  # (2, 3) [m] left, right after the last step
    zmp_at_walk_end: np.ndarray  # (2,) [m] the ZMP reference when the closing step ends
    final_dsp: float  # [s] the ZMP's shift to the final midpoint, at least 1e-9
    has_end_dsp: bool  # some step has a DSP after its touch-down


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
    # -- per-step details (authoritative when a replan changed the timing) --
    step_duration: np.ndarray  # (n,) [s] DSP + SSP (+ DSP at the end) of each step
    step_dsp: np.ndarray  # (n,) [s] DSP at the start of each step (before the lift-off)
    step_height: np.ndarray  # (n,) [m] swing-foot lift of each step
    zmp_from: np.ndarray  # (n, 2) [m] ZMP reference at the start of each step's DSP
    feet_init: np.ndarray  # (2, 3) [m] left, right before the first step
    feet_final: np.ndarray  # (2, 3) [m] left, right after the last step
    final_dsp_time: float  # [s] ZMP shift to the final midpoint after the last step
    step_dsp_end: np.ndarray  # (n,) [s] DSP at the end of each step, after the touch-down

    # -- timing -------------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of steps, the closing step included."""
        return int(self.step_start.shape[0])

    @cached_property
    def walk_end(self) -> float:
        """[s] end of the last (closing) step."""
        return float(self.step_start[-1] + self.step_duration[-1])

    def liftoff_times(self) -> np.ndarray:
        """(n,) [s] end of each step's DSP (the swing foot leaves the ground)."""
        return self.step_start + self.step_dsp

    def landing_times(self) -> np.ndarray:
        """(n,) [s] the swing foot touches down (the step's end, less its end DSP)."""
        return self.step_start + self.step_duration - self.step_dsp_end

    def dsp_after_landing(self, k: int) -> float:
        """[s] double support from step ``k``'s touch-down to the next lift-off (or stand)."""
        nxt = self.step_dsp[k + 1] if k + 1 < self.n else self.final_dsp_time
        return float(self.step_dsp_end[k] + nxt)

    def step_length(self, k: int) -> float:
        """[m] forward length of step ``k`` (clipped to the walking steps), 0 without any."""
        if self.n_walking_steps <= 0:
            return 0.0
        k = min(max(int(k), 0), self.n_walking_steps - 1)
        return float(self.swing_to[k, 0] - self.support_pos[k, 0])

    def footholds(self) -> np.ndarray:
        """(n + 2, 3) [m] every planned foot position in order: left, right initial, landings."""
        return np.vstack([self.feet_init, self.swing_to])

    # -- the sampler ----------------------------------------------------------------------
    @cached_property
    def steps(self) -> PlanSteps:
        """The plan as the sampler reads it: the per-step arrays and how the walk ends."""
        dsp, dsp_end = self.step_dsp, self.step_dsp_end
        return PlanSteps(
            start=self.step_start,
            dsp=dsp,
            ssp=np.maximum(self.step_duration - dsp - dsp_end, 1e-9),
            dsp_end=dsp_end,
            height=self.step_height,
            swing_side=self.swing_side,
            swing_from=self.swing_from,
            swing_to=self.swing_to,
            support=self.support_pos,
            zmp_from=np.ascontiguousarray(self.zmp_from[:, :2]),
            t_end=self.t_end,
            walk_end=self.walk_end,
            feet_init=self.feet_init,
            feet_final=self.feet_final,
            zmp_at_walk_end=self.zmp_at_walk_end,
            final_dsp=max(self.final_dsp_time, 1e-9),
            has_end_dsp=self.has_end_dsp,
        )

    def sample(self, times: float | np.ndarray, margin: float = 0.0) -> PlanSample:
        """The plan at ``times`` [s] (scalar or (N,)): phase, ZMP reference and box, feet.

        The one query of the plan: the control tick (horizon, foot targets, phase), the
        displays and the metrics all read it. Times outside [0, t_end] are clamped.

        Args:
            times: [s] query times.
            margin: [m] distance the ZMP box keeps from the foot edges (eq. 18 bounds).
        """
        half = np.maximum(np.array(FOOT_SIZE) / 2.0 - margin, 0.0)
        return _sample(np.atleast_1d(np.asarray(times, dtype=float)), self.steps, half)

    @cached_property
    def has_end_dsp(self) -> bool:
        """Some step has a DSP after its touch-down (``dsp_split = "both_ends"``)."""
        return bool(np.any(self.step_dsp_end > 0.0))

    @cached_property
    def zmp_at_walk_end(self) -> np.ndarray:
        """(2,) [m] the ZMP reference when the closing step ends."""
        return _zmp_at_step_end(self.support_pos[-1], self.swing_to[-1], self.step_dsp_end[-1])

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
                self,
                walk=walk,
                dsp_time=walk.dsp_ratio * walk.step_time,
                ssp_time=walk.step_time - walk.dsp_ratio * walk.step_time,
            )
        steps = _Steps()
        for j in range(started):
            steps.add(
                start=float(self.step_start[j]),
                duration=float(self.step_duration[j]),
                dsp=float(self.step_dsp[j]),
                height=float(self.step_height[j]),
                side=int(self.swing_side[j]),
                frm=self.swing_from[j],
                to=self.swing_to[j],
                support=self.support_pos[j],
                zmp_from=self.zmp_from[j],
                dsp_end=float(self.step_dsp_end[j]),
            )
        feet = self.feet_init.copy()
        for j in range(started):
            feet[int(self.swing_side[j])] = self.swing_to[j]
        n_walk = max(walk.n_steps, started)
        return _finish(walk, self.t_start, self.feet_init, steps, feet, n_walk - started)


@kernel
def _swing_point(s, p0, p1, height, ssp, p, v):
    """The swing foot of eq. (21) at SSP progress ``s`` (module docstring): position into
    ``p`` (3,) [m], velocity into ``v`` (3,) [m/s]. On the ground (s <= 0 or s >= 1) exactly
    at the lift-off point or the foothold, at rest (the cubic's rounding would leave the
    landed foot a few 1e-17 m off)."""
    if s <= 0.0 or s >= 1.0:
        for a in range(3):
            p[a] = p1[a] if s >= 1.0 else p0[a]
            v[a] = 0.0
        return
    s2 = s * s
    blend = 3.0 * s2 - 2.0 * s2 * s  # 3 s^2 - 2 s^3: zero velocity at both ends
    dblend = (6.0 * s - 6.0 * s2) / ssp
    for a in range(3):
        dp = p1[a] - p0[a]
        p[a] = p0[a] + dp * blend
        v[a] = dp * dblend
    two_pi_s = 2.0 * math.pi * s  # the lift: h (1 - cos(2 pi s)) / 2, peak h at s = 0.5
    p[2] = p[2] + height * (1.0 - math.cos(two_pi_s)) / 2.0
    v[2] = v[2] + height * math.pi * math.sin(two_pi_s) / ssp


@kernel
def _clamp(x, lo, hi):
    """min(max(x, lo), hi), NaN kept (numpy's minimum / maximum / clip)."""
    if x != x:
        return x
    x = x if x > lo else lo
    return x if x < hi else hi


@kernel
def _sample(times, plan, half):
    """:meth:`FootstepPlan.sample` at ``times`` of the plan's :class:`PlanSteps`, one time
    after the other: the step in progress (a binary search of the step starts), its phase,
    the feet of eq. (20)-(21) and the ZMP reference and box of eq. (18) (``half``: (2,) [m]
    the foot's half size less the margin)."""
    N, n = times.shape[0], plan.start.shape[0]
    feet_init, feet_final = plan.feet_init, plan.feet_final
    t_out = np.empty(N)
    step = np.empty(N, np.int64)
    standing = np.empty(N, np.bool_)
    in_dsp = np.empty(N, np.bool_)
    in_ssp = np.empty(N, np.bool_)
    swing_side = np.empty(N, np.int64)
    support_side = np.empty(N, np.int64)
    s_ssp = np.empty(N)
    zmp_ref, zmp_lo, zmp_hi = np.empty((N, 2)), np.empty((N, 2)), np.empty((N, 2))
    p_left, v_left = np.empty((N, 3)), np.empty((N, 3))
    p_right, v_right = np.empty((N, 3)), np.empty((N, 3))
    p_sw, v_sw = np.empty(3), np.empty(3)
    for i in range(N):
        t = _clamp(times[i], 0.0, plan.t_end)
        idx = np.searchsorted(plan.start, t, side="right") - 1
        after = t >= plan.walk_end
        if after:
            idx = n
        before = idx < 0
        k = min(max(idx, 0), n - 1)  # the step whose row is read
        dsp, ssp, side = plan.dsp[k], plan.ssp[k], plan.swing_side[k]
        support, frm, to = plan.support[k], plan.swing_from[k], plan.swing_to[k]
        tau = t - plan.start[k]  # [s] into the step
        walking = not (before or after)
        ssp_now = walking and tau >= dsp and tau < dsp + ssp
        s = 0.0 if before else (1.0 if after else _clamp((tau - dsp) / ssp, 0.0, 1.0))
        # eq. (20)-(21): the support foot stays, the swing foot follows the curve of swing
        _swing_point(s, frm, to, plan.height[k], ssp, p_sw, v_sw)
        for a in range(3):
            if before:
                p_left[i, a], p_right[i, a] = feet_init[LEFT, a], feet_init[RIGHT, a]
            elif after:
                p_left[i, a], p_right[i, a] = feet_final[LEFT, a], feet_final[RIGHT, a]
            else:
                p_left[i, a] = p_sw[a] if side == LEFT else support[a]
                p_right[i, a] = p_sw[a] if side == RIGHT else support[a]
            v_left[i, a] = v_sw[a] if walking and side == LEFT else 0.0
            v_right[i, a] = v_sw[a] if walking and side == RIGHT else 0.0
        # ZMP reference: from the previous support to this one in the DSP, then on it (eq. 18)
        s_dsp = _clamp(tau / max(dsp, 1e-9), 0.0, 1.0)
        s_end = _clamp((tau - dsp - ssp) / max(plan.dsp_end[k], 1e-9), 0.0, 1.0)
        s_final = _clamp((t - plan.walk_end) / plan.final_dsp, 0.0, 1.0)
        for a in range(2):
            z0 = plan.zmp_from[k, a]
            ref = z0 + s_dsp * (support[a] - z0)
            if plan.has_end_dsp:  # then on to the midpoint of the support and the landed foot
                ref = ref + s_end * 0.5 * (to[a] - support[a])
            if before:  # the feet's midpoint
                ref = (feet_init[LEFT, a] + feet_init[RIGHT, a]) / 2.0
            elif after:  # after the closing step: on to the feet's midpoint, then stay
                mid = (feet_final[LEFT, a] + feet_final[RIGHT, a]) / 2.0
                ref = plan.zmp_at_walk_end[a] + s_final * (mid - plan.zmp_at_walk_end[a])
            zmp_ref[i, a] = ref
            # ZMP box: both feet's bounding box, or the support foot alone in the SSP
            lo_a = support[a] if ssp_now else p_left[i, a]
            hi_a = support[a] if ssp_now else p_right[i, a]
            if hi_a < lo_a:
                lo_a, hi_a = hi_a, lo_a
            zmp_lo[i, a] = lo_a - half[a]
            zmp_hi[i, a] = hi_a + half[a]
        t_out[i], step[i], standing[i] = t, idx, not walking
        in_dsp[i], in_ssp[i], s_ssp[i] = walking and not ssp_now, ssp_now, s
        swing_side[i] = side if walking else -1
        support_side[i] = 1 - side
    return PlanSample(
        t=t_out, step=step, standing=standing, in_dsp=in_dsp, in_ssp=in_ssp,
        swing_side=swing_side, support_side=support_side, s_ssp=s_ssp, zmp_ref=zmp_ref,
        zmp_lo=zmp_lo, zmp_hi=zmp_hi, p_left=p_left, v_left=v_left, p_right=p_right,
        v_right=v_right,
    )  # fmt: skip


TICK_BLOCK = 100  # ticks a :class:`TickSamples` covers (0.5 s at 200 Hz)


class TickSamples:
    """The plan's samples for the next ``n_ticks`` control ticks, taken ahead in one call.

    A tick at time t reads the plan at t (phase, anchoring), t + dt (foot targets) and the
    MPC horizon t + offsets (N samples): N + 2 times of :meth:`FootstepPlan.sample`, whose
    call (15 arrays returned) costs more than its work on so few. Here one call of that same
    sampler fills the rows of
    ``n_ticks`` ticks at once, and a tick's rows are then one index (:meth:`at`), with the
    values the tick would have sampled itself, bit for bit: the times are the walker's own
    (its clock advances by ``t += dt``, reproduced by a sequential sum) and every row of
    the sampler depends on its own time only.

    Args:
        plan: the plan in force.
        margin: [m] ZMP box margin (``ComMpcParams.zmp_margin``).
        dt: [s] control period.
        offsets: (N,) [s] the horizon's sample offsets k T_p (``ComMpc.sample_offsets``).
        t0: [s] time of the first tick covered.
        n_ticks: ticks covered.
    """

    def __init__(
        self,
        plan: FootstepPlan,
        margin: float,
        dt: float,
        offsets: np.ndarray,
        t0: float,
        n_ticks: int = TICK_BLOCK,
    ):
        self.plan, self.margin, self.dt, self.offsets = plan, margin, dt, offsets
        steps = np.full(n_ticks, dt)
        steps[0] = t0
        self.ticks = np.add.accumulate(steps)  # [s] t0, t0 + dt, (t0 + dt) + dt, ...
        k = 2 + len(offsets)
        times = np.empty((n_ticks, k))
        times[:, 0] = self.ticks
        times[:, 1] = self.ticks + dt
        times[:, 2:] = self.ticks[:, None] + offsets
        self.times = times  # (n_ticks, N + 2) [s] the queried times (unclamped)
        sample = plan.sample(times.ravel(), margin)
        self._rows = [a.reshape(n_ticks, k, *a.shape[1:]) for a in sample]
        for rows in self._rows:  # a tick's rows are views: read-only for every reader
            rows.flags.writeable = False
        self.n_ticks = n_ticks

    def covers(self, plan: FootstepPlan, margin: float, offsets: np.ndarray, t: float, j: int):
        """True if row ``j`` holds the tick at ``t`` of this plan, margin and horizon."""
        return (
            j < self.n_ticks
            and self.ticks[j] == t
            and plan is self.plan
            and offsets is self.offsets
            and margin == self.margin
        )

    def at(self, j: int) -> PlanSample:
        """The plan at tick ``j``'s t, t + dt and horizon (N + 2 rows, views of the table)."""
        return PlanSample._make(map(itemgetter(j), self._rows))  # the loop in C


class _Step(NamedTuple):
    """One step of a plan being built (the per-step columns of :class:`FootstepPlan`)."""

    start: float  # [s]
    duration: float  # [s]
    dsp: float  # [s] before the lift-off
    height: float  # [m]
    side: int  # the swinging foot, LEFT / RIGHT
    frm: np.ndarray  # (3,) [m] lift-off point
    to: np.ndarray  # (3,) [m] foothold
    support: np.ndarray  # (3,) [m]
    zmp_from: np.ndarray  # (2,) [m]
    dsp_end: float  # [s] after the touch-down


class _Steps:
    """Accumulates steps (plans have tens of steps: a loop here is fine)."""

    def __init__(self) -> None:
        self.rows: list[_Step] = []

    def add(self, *, frm, to, support, zmp_from, **scalars) -> None:
        """One step: the points as float arrays, the rest as given (:class:`_Step`)."""
        self.rows.append(
            _Step(
                frm=np.array(frm, float),
                to=np.array(to, float),
                support=np.array(support, float),
                zmp_from=np.array(zmp_from, float)[:2],
                **scalars,
            )
        )

    def column(self, name: str, dtype: type = float) -> np.ndarray:
        """One field of every step, stacked ((n,) or (n, k))."""
        return np.array([getattr(r, name) for r in self.rows], dtype=dtype)


def _zmp_at_step_end(support: np.ndarray, to: np.ndarray, dsp_end: float) -> np.ndarray:
    """(2,) [m] where a step leaves the ZMP reference: on its support foot, or, with a DSP
    after the touch-down, at the midpoint of the support and the landed foot."""
    return support[:2] + (0.5 * (to[:2] - support[:2]) if dsp_end > 0 else 0.0)


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
    # the DSP before the lift-off and after the touch-down of each step (docs/DESIGN.md,
    # "Double-support timing")
    dsp_end = 0.5 * dsp if walk.dsp_split == "both_ends" else 0.0
    dsp_start = dsp - dsp_end
    half_w = walk.step_width / 2.0
    if steps.rows:
        last = steps.rows[-1]
        t = last.start + last.duration
        swing = 1 - last.side
        zmp_prev = _zmp_at_step_end(last.support, last.to, last.dsp_end)
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
        steps.add(
            start=t,
            duration=walk.step_time,
            dsp=dsp_start,
            height=walk.foot_height,
            side=swing,
            frm=feet[swing],
            to=to,
            support=support,
            zmp_from=zmp_prev,
            dsp_end=dsp_end,
        )
        feet[swing] = to
        zmp_prev = _zmp_at_step_end(support, to, dsp_end)
        t += walk.step_time
        swing = 1 - swing
    final_dsp = dsp
    return FootstepPlan(
        walk=walk,
        t_start=float(t_start),
        step_start=steps.column("start"),
        dsp_time=dsp,
        ssp_time=walk.step_time - dsp,
        swing_side=steps.column("side", int),
        swing_from=steps.column("frm"),
        swing_to=steps.column("to"),
        support_pos=steps.column("support"),
        t_end=float(t + final_dsp + FINAL_STAND),
        n_walking_steps=int(n_walk),
        step_duration=steps.column("duration"),
        step_dsp=steps.column("dsp"),
        step_height=steps.column("height"),
        zmp_from=steps.column("zmp_from"),
        feet_init=np.array(feet_init, dtype=float),
        feet_final=feet,
        final_dsp_time=float(final_dsp),
        step_dsp_end=steps.column("dsp_end"),
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
