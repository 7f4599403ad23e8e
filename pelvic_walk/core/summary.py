"""A run's summary: the keys of ``simulate --json`` (docs/REFERENCE.md, "simulate JSON")
plus extras.

Definitions (docs/DESIGN.md, "Metrics"):
- peaks (waist angle and rate, yaw momentum, kappa) over the walking phase, up to a fall;
- energy per two-step window (eq. 44): :meth:`pelvic_walk.core.session.Session.energy_windows`, from
  one sample of servo torque and joint speed per control period (200 Hz, as a robot logs
  them); the figure from every 1 ms substep, which also counts the servo chatter inside a
  period, is reported beside it (``*_substep``). Units: J per two-step window (the paper's
  Table 1 header says W, but eq. 44 sums power x time);
- kappa(J) of eq. (45) on the same matrices for every method: ``condition_number_max`` of
  J_low (12 x 13, eq. 9) and ``condition_number_legs_max`` of its 12 leg columns. A straight
  knee makes the leg columns singular, but the waist column restores J_low's rank (at a
  straight left knee: kappa 82 for J_low, 1.2e8 for the legs: tests/test_kinematics.py), so
  the clean criterion reads the legs' figure, for every method alike;
- *success* (:func:`unsuccessful`): no fall, the pelvis strategy did not stop the walk (an
  exception or no rate from a user's strategy), the plan finished (the final stand included) and
  every step landed, every landing within ``LANDING_ERROR_CLEAN`` (2 cm) of its foothold, and
  QPs failed on at most ``SOLVER_FAILURE_SHARE`` (1 %) of the ticks; ``unsuccessful`` lists
  the reasons of a run that is not one (empty for a success);
- *clean*: success, every landing within ``LANDING_ERROR_CLEAN``, no QP failure, no servo
  saturation, no IK tick at the joint-speed limit, kappa of the leg columns below
  ``KAPPA_SINGULAR``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from controller.kinematics import KAPPA_CAP
from controller.strategy import own_fields
from pelvic_walk.core.metrics import KAPPA_SINGULAR, LANDING_ERROR_CLEAN

if TYPE_CHECKING:
    from pelvic_walk.core.session import Session

# A success's share of ticks on which some QP failed (its layer fell back) at most: a failed
# QP holds a layer's last command, so more than 2 ticks a second at 200 Hz is no walk of the
# controller's own (every QP failing, the robot stood still and counted as a success).
SOLVER_FAILURE_SHARE = 0.01
# Why a run is not a success (``unsuccessful``), in this order.
FELL, STRATEGY_ERROR, INCOMPLETE, MISSED_FOOTHOLDS, SOLVER_FAILURES = (
    "fell",
    "strategy_error",
    "incomplete",
    "missed_footholds",
    "solver_failures",
)

SUMMARY_KEYS = (
    "method",
    "arms",
    "step_length",
    "step_time",
    "steps_planned",
    "steps_completed",
    "success",
    "unsuccessful",
    "fell",
    "fall_time",
    "landing_error_max",
    "waist_yaw_max_deg",
    "waist_yaw_rate_max_deg_s",
    "yaw_momentum_peak",
    "energy_two_step_mean",
    "energy_two_step_std",
    "condition_number_max",
    "zmp_in_support_ratio",
    "solver_failures",
    "solver_failure_share",
    "sim_time",
    "wall_time",
    "realtime_factor",
    "tick_ms_median",
    "tick_ms_p99",
)
# keys that measure the machine and its load, not the robot: two runs of the same walk
# differ in these only
TIMING_KEYS = (
    "wall_time",
    "realtime_factor",
    "tick_ms_median",
    "tick_ms_p99",
    "strategy_ms_median",
    "strategy_ms_max",
)
# the keys that compare walks (pelvic_walk.compare's columns, the live tables): what the
# paper compares, then what says whether the walk was sound
COMPARE_KEYS = (
    "success",
    "clean",
    "fell",
    "steps_completed",
    "landing_error_max",
    "waist_yaw_max_deg",
    "waist_yaw_rate_max_deg_s",
    "yaw_momentum_peak",
    "energy_two_step_mean",
    "energy_two_step_std",
    "condition_number_legs_max",
    "zmp_in_support_ratio",
    "solver_failures",
    "strategy_error",
)
DEG = 180.0 / np.pi


def outcome(summary: dict[str, Any], clean: bool = True) -> str:
    """A run's outcome in a word, as the command line and a notebook's run print it: clean
    (with ``clean``), success, FELL, STOPPED by its strategy, or NO SUCCESS."""
    if clean and summary["clean"]:
        return "clean"
    if summary["success"]:
        return "success"
    if summary["fell"]:
        return "FELL"
    return "STOPPED by its strategy" if summary["strategy_error"] else "NO SUCCESS"


def solver_failure_share(session: Session) -> float:
    """The share of the run's ticks on which some QP failed (0 before the first tick)."""
    w = session.walker
    return w.failed_ticks / w.ticks if w.ticks else 0.0


def unsuccessful(session: Session) -> list[str]:
    """Why the run is not a success, in the order of :data:`FELL` ..; empty for a success
    (the module docstring). A live run asks again after every tick: until its plan is over
    it is ``INCOMPLETE``."""
    reasons = []
    if session.fell:
        reasons.append(FELL)
    elif session.error is not None:
        reasons.append(STRATEGY_ERROR)
    elif not (session.walker.finished and len(session.landings) == session.plan.n):
        reasons.append(INCOMPLETE)
    if session.landings and max(session.landings.values()) >= LANDING_ERROR_CLEAN:
        reasons.append(MISSED_FOOTHOLDS)
    if solver_failure_share(session) > SOLVER_FAILURE_SHARE:
        reasons.append(SOLVER_FAILURES)
    return reasons


def unsuccessful_text(reasons: list[str], landing_error_max: float | None, share: float) -> str:
    """The reasons in words, for the command line and the live label."""
    words = {
        FELL: "it fell",
        STRATEGY_ERROR: "its pelvis strategy stopped it",
        INCOMPLETE: "its plan did not finish",
        MISSED_FOOTHOLDS: (
            f"a landing missed its foothold by {(landing_error_max or 0.0) * 100:.1f} cm "
            f"({LANDING_ERROR_CLEAN * 100:.0f} cm allowed)"
        ),
        SOLVER_FAILURES: (
            f"QPs failed on {share * 100:.0f} % of the ticks "
            f"({SOLVER_FAILURE_SHARE * 100:.0f} % allowed)"
        ),
    }
    return "; ".join(words[r] for r in reasons)


def summarize(session: Session) -> dict[str, Any]:
    """Every key of :data:`SUMMARY_KEYS` (all present in every run) plus extras."""
    p, plan, s, world = session.params, session.plan, session.series, session.world
    n_walk = plan.n_walking_steps
    landed = [session.landings[j] for j in sorted(session.landings)]
    steps_completed = sum(1 for j in session.landings if j < n_walk)
    if session.error_step is not None:  # stopped in step k (s.step): steps 0..k-1 touched down
        # (a landing is measured half a DSP after it; a stop before that still landed it)
        steps_completed = max(steps_completed, min(session.error_step, n_walk))
    step_index = s.column("step_index")
    walking = (step_index >= 0) & (step_index < plan.n)
    if session.fell:  # peaks up to the fall, not the impact after it
        walking &= s.column("t") <= session.fall_time

    def peak(name: str, scale: float = 1.0) -> float:
        col = s.column(name)[walking]
        # NaN = not recorded; an exactly singular J (kappa = inf) counts, capped so the
        # summary stays valid JSON.
        col = np.nan_to_num(col[~np.isnan(col)], posinf=KAPPA_CAP)
        return float(np.max(np.abs(col)) * scale) if len(col) else 0.0

    # eq. (44) from 200 Hz samples, as a robot logs them (the 1 ms substep figure beside it)
    per_joint = session.energy_windows()  # (windows, joints)
    windows = per_joint.sum(axis=1)
    windows_substep = session.energy_windows(substep=True).sum(axis=1)
    tick = s.column("tick_ms")
    tick = tick[np.isfinite(tick)] if len(tick) else np.zeros(1)
    strategy_ms = s.column("strategy_ms")
    strategy_ms = strategy_ms[np.isfinite(strategy_ms)] if len(strategy_ms) else np.zeros(1)
    sim_time = float(session.t)
    failures = sum(session.walker.failure_counts.values())
    reasons = unsuccessful(session)
    success = not reasons
    margin = s.column("balance_margin")[walking]
    margin = margin[np.isfinite(margin)]
    tilt = s.column("sole_tilt")[walking]
    tilt = tilt[np.isfinite(tilt)]
    kappa_legs_max = peak("kappa_legs")
    return {
        "method": p.method,
        "arms": bool(p.arms.enabled),
        "step_length": p.walk.step_length,
        "step_time": p.walk.step_time,
        "steps_planned": n_walk,
        "steps_completed": int(steps_completed),
        "success": bool(success),
        "unsuccessful": reasons,
        "fell": bool(session.fell),
        "fall_time": session.fall_time,
        "landing_error_max": float(max(landed)) if landed else None,
        "waist_yaw_max_deg": peak("waist_angle", DEG),
        "waist_yaw_rate_max_deg_s": peak("waist_rate", DEG),
        "yaw_momentum_peak": peak("yaw_momentum"),
        "energy_two_step_mean": float(np.mean(windows)) if len(windows) else None,
        "energy_two_step_std": float(np.std(windows)) if len(windows) else None,
        "condition_number_max": peak("kappa_low"),
        "zmp_in_support_ratio": (
            session.zmp_inside / session.zmp_ticks if session.zmp_ticks else 0.0
        ),
        "solver_failures": int(failures),
        "solver_failure_share": solver_failure_share(session),
        "sim_time": sim_time,
        "wall_time": session.wall_time,
        "realtime_factor": sim_time / session.wall_time if session.wall_time > 0 else None,
        "tick_ms_median": float(np.median(tick)),
        "tick_ms_p99": float(np.percentile(tick, 99)),
        # further keys (docs/REFERENCE.md, "simulate JSON", the further keys):
        "fall_reason": session.fall_reason,
        # the pelvis strategy's fault ("ZeroDivisionError: ... (my_pelvis.py:14)") and when
        "strategy_error": session.error,
        "strategy_error_time": session.error_time,
        "strategy_error_step": session.error_step,  # the s.step it stopped in (from 0)
        # [ms] its waist_rate calls: a strategy slower than the 5 ms tick cannot run live
        "strategy_ms_median": float(np.median(strategy_ms)) if len(strategy_ms) else 0.0,
        "strategy_ms_max": float(np.max(strategy_ms)) if len(strategy_ms) else 0.0,
        # the strategy's own parameters in force, by NAME.FIELD (its Params, and the paper's
        # it owns: mpc.alpha ...); {} for a strategy without any
        "own_params": {name: p.value(name) for name in own_fields(p.method)},
        "servo_saturation_substeps": int(world.saturated_substeps),
        "speed_limited_ticks": int(session.speed_limited_ticks),
        "solver_failures_by_layer": dict(session.walker.failure_counts),
        "landing_errors": landed,
        "energy_two_step_windows": windows.tolist(),
        "energy_two_step_per_joint_mean": (
            per_joint.mean(axis=0).tolist() if len(per_joint) else None
        ),
        "energy_two_step_mean_substep": (
            float(np.mean(windows_substep)) if len(windows_substep) else None
        ),
        "energy_two_step_windows_substep": windows_substep.tolist(),
        "condition_number_legs_max": kappa_legs_max,
        # the whole run: eq. (44) at 200 Hz and at 1 ms, and the net work [J]
        "energy_total": float(world.energy_ctrl_per_joint.sum()),
        "energy_total_substep": float(world.energy_substep_per_joint.sum()),
        "work_net_total": float(world.work_net),
        "work_net_total_ctrl": float(world.work_net_ctrl),
        "balance_margin_min": float(np.min(margin)) if len(margin) else None,
        "balance_margin_p5": float(np.percentile(margin, 5)) if len(margin) else None,
        "sole_tilt_max_deg": float(np.max(tilt) * DEG) if len(tilt) else None,
        "clean": bool(
            success
            and landed
            and max(landed) < LANDING_ERROR_CLEAN
            and failures == 0
            and kappa_legs_max < KAPPA_SINGULAR
            and world.saturated_substeps == 0
            and session.speed_limited_ticks == 0
        ),
    }
