"""One closed-loop run: controller + MuJoCo world + metrics.

``Session`` steps one robot one control period at a time; the headless ``run`` (used by
``pelvic-walk simulate``, ``POST /api/runs``, the experiments and the bench) loops it to the
end, and the live web session paces the same ``Session`` to real time and publishes frames.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from app.sim.metrics import Series, two_step_windows
from app.sim.world import World, point_in_polygon
from controller.kinematics import RobotKinematics
from controller.params import ControllerParams
from controller.walker import TickOutput, Walker
from models.dyros_jet import ROBOT_XML

GRAVITY = 9.81
# A walk is "clean" (the issues' criterion for the longest step) when it succeeds with every
# landing within 2 cm, no QP failure, no servo saturation, no joint at its speed limit, and the
# legs never at the straight-knee singularity: kappa(J) above this bound means the knee is
# within ~0.01 rad of straight (kappa 1283 there, 128 at 0.1 rad: tests/test_kinematics.py).
KAPPA_SINGULAR = 1000.0
LANDING_ERROR_CLEAN = 0.02  # [m]
KAPPA_EXACTLY_SINGULAR = 1e16  # reported for kappa = inf (sigma_min at machine precision)
SUMMARY_KEYS = (
    "method", "arms", "step_length", "step_time", "steps_planned", "steps_completed",
    "success", "fell", "fall_time", "landing_error_max", "waist_yaw_max_deg",
    "waist_yaw_rate_max_deg_s", "yaw_momentum_peak", "energy_two_step_mean",
    "energy_two_step_std", "condition_number_max", "zmp_in_support_ratio", "solver_failures",
    "sim_time", "wall_time", "realtime_factor", "tick_ms_median", "tick_ms_p99",
)


@lru_cache(maxsize=1)
def _shared_kinematics() -> RobotKinematics:
    return RobotKinematics(ROBOT_XML)


@dataclass(frozen=True)
class RunConfig:
    """What a run needs besides the controller parameters."""

    params: ControllerParams = field(default_factory=ControllerParams)
    seed: int | None = None
    perturbation: float = 0.0  # [rad] std of the seeded initial perturbation (arms, base vel)
    sim_dt: float = 0.001  # [s] MuJoCo timestep
    backend: str = "daqp"  # QP back-end of every layer (daqp exact / osqp)
    settle_time: float = 0.3  # [s] after a fall before the session counts as over (live)


class Session:
    """One robot: world + walker + metrics, advanced one control period per :meth:`tick`."""

    def __init__(self, cfg: RunConfig, capacity: int | None = None):
        self.cfg = cfg
        params = cfg.params.validated()
        self.kin = _shared_kinematics()
        self.world = World(cfg.sim_dt, params.control_dt)
        self.world.reset(cfg.seed, cfg.perturbation)
        q0 = self.world.keyframe_joints()
        self.walker = Walker(
            params, self.kin, q0, self.world.base_position(), backend=cfg.backend,
            clock=time.perf_counter,
        )
        plan = self.walker.plan
        n_ticks = int(math.ceil(plan.t_end / params.control_dt)) + 10
        self.series = Series(capacity or n_ticks)
        self.fell = False
        self.fall_time: float | None = None
        self.fall_reason: str | None = None
        self.landings: dict[int, float] = {}  # step index -> landing error [m]
        self.energy_at_step_start: dict[int, float] = {}
        self.zmp_ticks = 0
        self.zmp_inside = 0
        self.speed_limited_ticks = 0
        self.last: TickOutput | None = None
        self._com_vel_prev: np.ndarray | None = None
        self.wall_time = 0.0

    @property
    def params(self) -> ControllerParams:
        return self.walker.params

    @property
    def t(self) -> float:
        return self.walker.t

    @property
    def done(self) -> bool:
        return self.fell or self.walker.finished

    def tick(self) -> TickOutput:
        """Controller tick from the measured state, then one control period of simulation."""
        w, world = self.walker, self.world
        wall0 = time.perf_counter()
        q_meas = world.q_joints()
        t0 = time.perf_counter()
        out = w.tick(q_meas)
        tick_ms = (time.perf_counter() - t0) * 1e3
        world.step(out.q_target)
        self._measure(out, tick_ms, q_meas)
        self.last = out
        self.wall_time += time.perf_counter() - wall0
        return out

    # -- measurement -------------------------------------------------------------------------
    def _measure(self, out: TickOutput, tick_ms: float, q_meas: np.ndarray) -> None:
        world, plan, s = self.world, self.walker.plan, self.series
        t = self.walker.t  # time after the step
        contacts = world.contacts()
        row = s.new_row()
        ix = s.index
        row[ix["t"]] = t
        row[ix["waist_angle"]] = q_meas[0]  # measured at the start of the tick
        row[ix["waist_angle_cmd"]] = out.waist_angle
        row[ix["waist_rate"]] = out.waist_rate
        row[ix["theta_ref"]] = out.theta_ref[0]
        row[ix["yaw_momentum"]] = world.yaw_momentum()
        row[ix["h_low"]] = out.h_low
        row[ix["h_up"]] = out.h_up
        row[ix["kappa"]] = out.kappa
        row[ix["zmp_ref_x"]], row[ix["zmp_ref_y"]] = out.zmp_ref
        com = world.com()
        row[ix["com_x"]], row[ix["com_y"]], row[ix["com_z"]] = com
        row[ix["com_des_x"]], row[ix["com_des_y"]] = out.p_world_com_des
        vel = world.data.subtree_linvel[world.root_id][:2].copy()
        acc = np.zeros(2) if self._com_vel_prev is None else (vel - self._com_vel_prev) / (
            world.control_dt
        )
        self._com_vel_prev = vel
        lipm = com[:2] - (com[2] / GRAVITY) * acc
        row[ix["lipm_zmp_x"]], row[ix["lipm_zmp_y"]] = lipm
        row[ix["reach_left"]], row[ix["reach_right"]] = out.reach
        row[ix["energy"]] = world.energy_per_joint.sum()
        row[ix["tick_ms"]] = tick_ms
        row[ix["step_index"]] = out.step_index
        row[ix["in_ssp"]] = float(out.in_ssp)
        if out.speed_limited:
            self.speed_limited_ticks += 1

        # ZMP (centre of pressure) in the support polygon of the feet in contact.
        if contacts.cop is not None:
            row[ix["cop_x"]], row[ix["cop_y"]] = contacts.cop
            hull = world.support_polygon(contacts.in_contact)
            inside = point_in_polygon(contacts.cop, hull)
            row[ix["zmp_in_support"]] = float(inside)
            if not self.fell:
                self.zmp_ticks += 1
                self.zmp_inside += int(inside)
        s.append(row)

        # Step bookkeeping: energy at step starts, landing error half a DSP after touch-down.
        k = out.step_index
        n = len(plan.step_start)
        if 0 <= k < n and k not in self.energy_at_step_start and not self.fell:
            self.energy_at_step_start[k] = float(world.energy_per_joint.sum())
        j = len(self.landings)  # landings are recorded in order: the first one not yet checked
        if j < n:
            # half of the next DSP after this step's touch-down (per-step timing: a replan
            # changes the timing of later steps only)
            next_dsp = plan.step_dsp[j + 1] if j + 1 < n else plan.final_dsp_time
            check_time = plan.step_start[j] + plan.step_duration[j] + 0.5 * next_dsp
            if t >= check_time and not self.fell:
                soles = world.sole_positions()
                side = int(plan.swing_side[j])
                landed = soles[side, :2] - soles[1 - side, :2]
                planned = plan.swing_to[j, :2] - plan.support_pos[j, :2]
                self.landings[j] = float(np.linalg.norm(landed - planned))

        # Falls (SPEC 4).
        if not self.fell:
            reason = world.fall_reason()
            if reason is None and contacts.other_contact:
                reason = "a body other than the feet touched the floor"
            if reason is not None:
                self.fell, self.fall_time, self.fall_reason = True, t, reason

    # -- summary -----------------------------------------------------------------------------
    def summary(self) -> dict[str, Any]:
        """The keys of ``simulate --json`` (INTERFACES.md), from the recorded run."""
        p = self.params
        plan = self.walker.plan
        s = self.series
        n_walk = plan.n_walking_steps
        landed = [self.landings[j] for j in sorted(self.landings)]
        steps_completed = sum(1 for j in self.landings if j < n_walk)
        walking = (s.column("step_index") >= 0) & (s.column("step_index") < len(plan.step_start))
        if self.fell:  # peaks up to the fall, not the impact after it
            walking &= s.column("t") <= self.fall_time
        # Energy per two-step window (eq. 44): windows start at step 1, skipping step 0 (the
        # start from standing moves the foot one step length, later swings two); the last
        # window closes at the start of the closing step (index n_walk).
        starts = [self.energy_at_step_start[k] for k in range(1, n_walk + 1)
                  if k in self.energy_at_step_start]
        windows = two_step_windows(np.array(starts))
        tick = s.column("tick_ms")
        tick = tick[np.isfinite(tick)] if len(tick) else np.zeros(1)
        sim_time = float(self.walker.t)
        failures = sum(self.walker.failure_counts.values())
        success = (not self.fell) and self.walker.finished and len(self.landings) == len(
            plan.step_start
        )

        def peak(name: str, scale: float = 1.0) -> float:
            col = s.column(name)[walking]
            # NaN = not recorded; an exactly singular J (kappa = inf) counts, capped so the
            # summary stays valid JSON.
            col = np.nan_to_num(col[~np.isnan(col)], posinf=KAPPA_EXACTLY_SINGULAR)
            return float(np.max(np.abs(col)) * scale) if len(col) else 0.0

        return {
            "method": p.method,
            "arms": bool(p.arms.enabled),
            "step_length": p.walk.step_length,
            "step_time": p.walk.step_time,
            "steps_planned": n_walk,
            "steps_completed": int(steps_completed),
            "success": bool(success),
            "fell": bool(self.fell),
            "fall_time": self.fall_time,
            "landing_error_max": float(max(landed)) if landed else None,
            "waist_yaw_max_deg": peak("waist_angle", 180 / np.pi),
            "waist_yaw_rate_max_deg_s": peak("waist_rate", 180 / np.pi),
            "yaw_momentum_peak": peak("yaw_momentum"),
            "energy_two_step_mean": float(np.mean(windows)) if len(windows) else None,
            "energy_two_step_std": float(np.std(windows)) if len(windows) else None,
            "condition_number_max": peak("kappa"),
            "zmp_in_support_ratio": self.zmp_inside / self.zmp_ticks if self.zmp_ticks else 0.0,
            "solver_failures": int(failures),
            "sim_time": sim_time,
            "wall_time": self.wall_time,
            "realtime_factor": sim_time / self.wall_time if self.wall_time > 0 else None,
            "tick_ms_median": float(np.median(tick)),
            "tick_ms_p99": float(np.percentile(tick, 99)),
            # extras beyond INTERFACES.md (free to add):
            "fall_reason": self.fall_reason,
            "servo_saturation_substeps": int(self.world.saturated_substeps),
            "speed_limited_ticks": int(self.speed_limited_ticks),
            "solver_failures_by_layer": dict(self.walker.failure_counts),
            "landing_errors": landed,
            "energy_two_step_windows": windows.tolist(),
            "clean": bool(
                success
                and landed
                and max(landed) < LANDING_ERROR_CLEAN
                and failures == 0
                and peak("kappa") < KAPPA_SINGULAR
                and self.world.saturated_substeps == 0
                and self.speed_limited_ticks == 0
            ),
        }


def run(cfg: RunConfig, max_wall_s: float | None = None) -> Session:
    """Run a whole plan headless (stops at a fall); returns the session with its series."""
    session = Session(cfg)
    start = time.perf_counter()
    settle_ticks = int(cfg.settle_time / cfg.params.control_dt)
    while not session.walker.finished:
        session.tick()
        if session.fell:
            settle_ticks -= 1
            if settle_ticks <= 0:
                break
        if max_wall_s is not None and time.perf_counter() - start > max_wall_s:
            break
    return session
