"""A run's summary: the keys of ``simulate --json`` (docs/REFERENCE.md, "simulate JSON")
plus extras.

Definitions (docs/DESIGN.md, "Metrics"):
- peaks (waist angle and rate, yaw momentum, kappa) over the walking phase, up to a fall;
- energy per two-step window (eq. 44): :meth:`app.sim.session.Session.energy_windows`, from
  one sample of servo torque and joint speed per control period (200 Hz, as a robot logs
  them); the figure from every 1 ms substep, which also counts the servo chatter inside a
  period, is reported beside it (``*_substep``). Units: J per two-step window (the paper's
  Table 1 header says W, but eq. 44 sums power x time);
- kappa(J) of eq. (45) on the same matrices for every method: ``condition_number_max`` of
  J_low (12 x 13, eq. 9) and ``condition_number_legs_max`` of its 12 leg columns. A straight
  knee makes the leg columns singular, but the waist column restores J_low's rank (at a
  straight left knee: kappa 82 for J_low, 1.2e8 for the legs: tests/test_kinematics.py), so
  the clean criterion reads the legs' figure, for every method alike;
- *clean*: success, every landing within ``LANDING_ERROR_CLEAN``, no QP failure, no servo
  saturation, no IK tick at the joint-speed limit, kappa of the leg columns below
  ``KAPPA_SINGULAR``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from app.sim.metrics import KAPPA_SINGULAR, LANDING_ERROR_CLEAN
from controller.kinematics import KAPPA_CAP

if TYPE_CHECKING:
    from app.sim.session import Session

SUMMARY_KEYS = (
    "method",
    "arms",
    "step_length",
    "step_time",
    "steps_planned",
    "steps_completed",
    "success",
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
DEG = 180.0 / np.pi


def summarize(session: Session) -> dict[str, Any]:
    """Every key of :data:`SUMMARY_KEYS` (all present in every run) plus extras."""
    p, plan, s, world = session.params, session.plan, session.series, session.world
    n_walk = plan.n_walking_steps
    landed = [session.landings[j] for j in sorted(session.landings)]
    steps_completed = sum(1 for j in session.landings if j < n_walk)
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
    success = (
        (not session.fell)
        and session.error is None
        and session.walker.finished
        and len(session.landings) == plan.n
    )
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
        # [ms] its waist_rate calls: a strategy slower than the 5 ms tick cannot run live
        "strategy_ms_median": float(np.median(strategy_ms)) if len(strategy_ms) else 0.0,
        "strategy_ms_max": float(np.max(strategy_ms)) if len(strategy_ms) else 0.0,
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
