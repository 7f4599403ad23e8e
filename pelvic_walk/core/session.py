"""One robot in closed loop: controller + MuJoCo world + what each control period measured.

A :class:`Session` advances one control period per :meth:`Session.tick`: the controller ticks
from the measured joint angles, the world holds the new servo targets for one period, and a
:class:`Measurement` records what a robot's sensors and a force plate would report. The
headless run (``pelvic_walk.core.run.run``), the bench and the live tool all step the same
``Session``;
the live tool differs only in pacing and publishing frames.

Every session owns its whole workspace (MuJoCo model and data, Pinocchio model and data, QP
solvers), so sessions in different threads or processes never change each other's results.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from controller.compiled import kernel
from controller.footsteps import FootstepPlan
from controller.kinematics import RobotKinematics
from controller.params import ControllerParams
from controller.strategy import StrategyError
from controller.tick_explain import active_counts
from controller.walker import TickOutput, Walker
from models.dyros_jet import ROBOT_XML
from pelvic_walk.core.metrics import COL, COLUMNS, Series, two_step_windows
from pelvic_walk.core.world import Contacts, World

GRAVITY = 9.81  # [m/s^2]
_sum = np.add.reduce  # ndarray.sum without its Python-level wrapper (the same reduction)
STRATEGY_TICKS = 200  # the ticks (1 s) over which the live label reads the strategy's time
_NAN_ROW = [math.nan] * len(COLUMNS)  # a series row before it is written (a column not
# written, such as the CoP while airborne, stays NaN)


@kernel
def _lipm_zmp(com, vel, vel_prev, dt, g):
    """(2,) the ZMP of the LIPM, p - (z / g) a, with the CoM's horizontal acceleration a
    from its velocities at the end of two consecutive periods dt apart."""
    zmp = np.empty(2)
    for i in range(2):
        zmp[i] = com[i] - (com[2] / g) * ((vel[i] - vel_prev[i]) / dt)
    return zmp


@dataclass(frozen=True)
class RunConfig:
    """What a run needs besides the controller parameters."""

    params: ControllerParams = field(default_factory=ControllerParams)
    seed: int | None = None
    perturbation: float = 0.0  # [rad] std of the seeded initial perturbation (arms, base vel)
    # A seeded disturbance that lasts the whole run (needs a seed): a horizontal force on the
    # torso, each axis drawn from N(0, disturbance) [N] and held for disturbance_period [s].
    disturbance: float = 0.0  # [N]
    disturbance_period: float = 0.1  # [s]
    sim_dt: float = 0.001  # [s] MuJoCo timestep
    backend: str = "daqp"  # QP back-end of every layer (daqp exact / osqp)
    settle_time: float = 0.3  # [s] after a fall before a headless run stops


@dataclass(slots=True)  # not frozen: a frozen init costs a setattr call per field
class Measurement:
    """What one control period measured, at its end (world frame, SI units). Read-only by
    contract."""

    t: float  # [s] time after the period
    waist_angle: float  # [rad] measured waist yaw at the start of the tick
    contacts: Contacts  # feet in contact, forces, centre of pressure
    support: np.ndarray  # (M, 2) [m] support polygon of the feet in contact (CCW)
    cop_inside: bool | None  # CoP inside the support polygon (None when airborne)
    balance_margin: float  # [m] CoP to the polygon edge, > 0 inside (nan when airborne)
    sole_tilt: float  # [rad] largest tilt of a foot in contact (nan when airborne)
    com: np.ndarray  # (3,) [m]
    lipm_zmp: np.ndarray  # (2,) [m] ZMP of the LIPM from the measured CoM (paper Fig. 15)
    yaw_momentum: float  # [kg m^2/s] whole body about the CoM
    energy: float  # [J] cumulative eq. (44) from 200 Hz samples
    energy_substep: float  # [J] cumulative eq. (44) from every 1 ms substep


class Session:
    """One robot: world + walker + metrics, advanced one control period per :meth:`tick`.

    What is measured when (``record``):

    - every tick, always: the controller, the physics, the landing error half a DSP after
      each touch-down (a success needs them: ``pelvic_walk.core.summary``), the energy at each
      step's
      start and the fall test (pelvis height, torso tilt, a body other than the feet on the
      floor);
    - ``record=True`` (headless runs: ``simulate``, the study, the bench): also every tick,
      because the summary and the study read every tick (maxima, ratios, events): the
      :class:`Measurement`, its row of the time series and the counts of CoP-in-support and
      speed-limited ticks;
    - ``record=False`` (the live tool): no series; :attr:`measured` (contacts, CoP, support
      polygon, CoM, yaw momentum) and the tick's kappa and reach are computed when a reader
      first asks after a tick, i.e. at the display rate. Its LIPM ZMP is NaN unless the
      previous tick was measured too (it differentiates the CoM velocity of two ticks).

    Args:
        cfg: parameters, seed and simulation settings.
        capacity: rows kept in the time series (default: the whole plan).
        record: measure and record every tick (above).
    """

    def __init__(self, cfg: RunConfig, capacity: int | None = None, record: bool = True):
        self.cfg = cfg
        self.record = record
        params = cfg.params.validated()
        # Its own Pinocchio model and Data: a Data is a mutable workspace, so sessions that
        # share one in different threads corrupt each other's results (2 ms to build).
        self.kin = RobotKinematics(ROBOT_XML)
        self.world = World(cfg.sim_dt, params.control_dt)
        self.world.reset(cfg.seed, cfg.perturbation)
        # the disturbance's own stream (the reset's draws do not shift it)
        self._disturb_rng = (
            np.random.default_rng((cfg.seed, 1))
            if cfg.seed is not None and cfg.disturbance > 0
            else None
        )
        self._disturb_every = max(1, int(round(cfg.disturbance_period / params.control_dt)))
        self._ticks = 0
        q0 = self.world.keyframe_joints()
        self.walker = Walker(
            params,
            self.kin,
            q0,
            self.world.base_position(),
            backend=cfg.backend,
            clock=time.perf_counter,
        )
        n_ticks = int(math.ceil(self.walker.plan.t_end / params.control_dt)) + 10
        self.series = Series((capacity or n_ticks) if record else 1)
        self.fell = False
        self.fall_time: float | None = None
        self.fall_reason: str | None = None
        # the pelvis strategy raised or returned no rate (its file and line): the walker
        # stopped at error_time; only this robot stops
        self.error: str | None = None
        self.error_time: float | None = None
        self.error_step: int | None = None  # the s.step it failed at (steps before it landed)
        # [ms] the strategy's waist_rate call at the last STRATEGY_TICKS ticks (a ring), for
        # the live label: a strategy slower than the tick cannot run in real time. Their
        # median, not a peak: on a busy machine any call may be preempted now and then
        self._strategy_ms = np.full(STRATEGY_TICKS, np.nan)
        self.landings: dict[int, float] = {}  # step index -> landing error [m]
        self._landing_key: tuple[FootstepPlan, int, float] | None = None  # plan, step, time
        # step index -> cumulative energy per joint at its start: (200 Hz, substep) [J]
        self.energy_at_step_start: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self.zmp_ticks = 0
        self.zmp_inside = 0
        self.speed_limited_ticks = 0
        self.last: TickOutput | None = None
        self._measured: Measurement | None = None
        self._measured_tick = -1  # the tick (count) the last Measurement was taken at
        self._waist_meas = 0.0  # [rad] measured waist yaw at the start of the last tick
        self._com_vel_prev: np.ndarray | None = None
        self.wall_time = 0.0
        # [s] summed over the ticks: where the time of a control period goes (bench)
        self.time_split = {"controller": 0.0, "simulation": 0.0, "measurement": 0.0}

    @property
    def params(self) -> ControllerParams:
        return self.walker.params

    @property
    def plan(self) -> FootstepPlan:
        return self.walker.plan

    @property
    def t(self) -> float:
        return self.walker.t

    @property
    def strategy_ms_recent(self) -> float:
        """[ms] the median time of the strategy's waist_rate over the last ticks (0 before)."""
        kept = self._strategy_ms[np.isfinite(self._strategy_ms)]
        return float(np.median(kept)) if len(kept) else 0.0

    @property
    def done(self) -> bool:
        return self.fell or self.error is not None or self.walker.finished

    def push(self, force_xy: np.ndarray, duration: float) -> None:
        """A horizontal push [N] on the torso for ``duration`` [s] from the next period."""
        self.world.push(force_xy, duration)

    def tick(self) -> TickOutput:
        """Controller tick from the measured state, then one control period of simulation."""
        w, world, clock, split = self.walker, self.world, time.perf_counter, self.time_split
        wall0 = clock()
        q_meas = world.q_joints()
        if self._disturb_rng is not None and self._ticks % self._disturb_every == 0:
            force = self._disturb_rng.normal(0.0, self.cfg.disturbance, 2)
            world.push(force, self.cfg.disturbance_period)
        self._ticks += 1
        t0 = clock()
        try:
            out = w.tick(q_meas)
        except StrategyError as exc:  # the strategy's fault: this robot stops here
            self.error, self.error_time, self.error_step = str(exc), w.t, exc.step
            raise
        t1 = clock()
        self._strategy_ms[self._ticks % STRATEGY_TICKS] = out.strategy_s * 1e3
        world.step(out.q_target)
        t2 = clock()
        self.last, self._measured, self._waist_meas = out, None, float(q_meas[0])
        if self.record:
            m = self.measured
            assert m is not None
            self._record(out, m, (t1 - t0) * 1e3)
            self._bookkeep(out, m)
        else:
            self._energy_and_falls(out, self.t, None)
        t3 = clock()
        split["controller"] += t1 - t0
        split["simulation"] += t2 - t1
        split["measurement"] += t3 - t2
        self.wall_time += t3 - wall0
        return out

    # -- measurement -------------------------------------------------------------------------
    @property
    def measured(self) -> Measurement | None:
        """What the last control period measured (None before the first tick); taken when
        first read after a tick (every tick with ``record``)."""
        if self._measured is None and self.last is not None:
            m = self._measure(self._waist_meas)
            if not self.record and self._measured_tick != self._ticks - 1:
                # the CoM velocity of the tick before is not known: no LIPM ZMP
                m = dataclasses.replace(m, lipm_zmp=np.full(2, math.nan))
            self._measured, self._measured_tick = m, self._ticks
        return self._measured

    def _measure(self, waist_angle: float) -> Measurement:
        world = self.world
        contacts = world.contacts()
        com = world.com()
        # MuJoCo's step leaves subtree_linvel as the last mj_subtreeVel left it (the period
        # before): yaw_momentum runs mj_subtreeVel, so read the CoM velocity after it, and the
        # LIPM ZMP's acceleration pairs this period's velocities with this period's CoM.
        yaw_momentum = world.yaw_momentum()
        vel = world.data.subtree_linvel[world.root_id][:2].copy()
        prev = vel if self._com_vel_prev is None else self._com_vel_prev  # at first: no acc
        self._com_vel_prev = vel
        support, inside, margin, tilt = world.support(contacts)
        return Measurement(
            t=self.walker.t,
            waist_angle=waist_angle,
            contacts=contacts,
            support=support,
            cop_inside=inside,
            balance_margin=margin,
            sole_tilt=tilt,
            com=com,
            lipm_zmp=_lipm_zmp(com, vel, prev, world.control_dt, GRAVITY),
            yaw_momentum=yaw_momentum,
            energy=float(_sum(world.energy_ctrl_per_joint)),
            energy_substep=float(_sum(world.energy_substep_per_joint)),
        )

    def _record(self, out: TickOutput, m: Measurement, tick_ms: float) -> None:
        """One row of the time series (pelvic_walk.core.metrics.COLUMNS), written by column name.

        The values go into a Python list first (a list item costs a fraction of a numpy
        element's assignment) and into the series' buffer in one assignment; arrays are read
        with ``tolist`` (one call, the same float values)."""
        row, c = _NAN_ROW.copy(), COL
        row[c.t] = m.t
        row[c.waist_angle] = m.waist_angle
        row[c.waist_angle_cmd] = out.waist_angle
        row[c.waist_rate] = out.waist_rate
        row[c.theta_ref] = out.theta_ref[0]
        row[c.yaw_momentum] = m.yaw_momentum
        row[c.h_low] = out.h_low
        row[c.h_up] = out.h_up
        row[c.kappa_low] = out.kappa_low
        row[c.kappa_legs] = out.kappa_legs
        cop = m.contacts.cop
        if cop is not None:  # else NaN
            row[c.cop_x], row[c.cop_y] = cop.tolist()
        if m.cop_inside is not None:
            row[c.zmp_in_support] = m.cop_inside
        row[c.balance_margin] = m.balance_margin
        row[c.sole_tilt] = m.sole_tilt
        row[c.zmp_ref_x], row[c.zmp_ref_y] = out.zmp_ref.tolist()
        row[c.lipm_zmp_x], row[c.lipm_zmp_y] = m.lipm_zmp.tolist()
        row[c.com_x], row[c.com_y], row[c.com_z] = m.com.tolist()
        row[c.com_des_x], row[c.com_des_y] = out.p_world_com_des.tolist()
        row[c.reach_left], row[c.reach_right] = out.reach.tolist()
        row[c.energy] = m.energy
        row[c.energy_substep] = m.energy_substep
        row[c.tick_ms] = tick_ms
        row[c.strategy_ms] = out.strategy_s * 1e3
        row[c.step_index] = out.step_index
        row[c.in_ssp] = out.in_ssp
        row[c.speed_limited] = out.speed_limited
        (
            row[c.active_com_mpc],
            row[c.active_pelvis_mpc],
            row[c.active_ik],
            row[c.active_arm_swing],
        ) = active_counts(self.walker)
        self.series.append_values(row)

    def _bookkeep(self, out: TickOutput, m: Measurement) -> None:
        """Recorded runs: ZMP and speed-limit counts, then what every run keeps."""
        if out.speed_limited:
            self.speed_limited_ticks += 1
        if m.cop_inside is not None and not self.fell:
            self.zmp_ticks += 1
            self.zmp_inside += int(m.cop_inside)
        self._energy_and_falls(out, m.t, m.contacts.other_contact)

    def _energy_and_falls(self, out: TickOutput, t: float, other_contact: bool | None) -> None:
        """Every tick: landing errors, the energy at each step's start and the fall test
        (docs/DESIGN.md, "What counts as a fall");
        ``other_contact`` from the tick's measured contacts, or None to look it up."""
        if self.fell:
            return
        # Landing error half a DSP after each touch-down, relative to the support foot
        # (per-step timing: a replan changes the timing of later steps only).
        plan = self.walker.plan
        j = len(self.landings)  # landings are recorded in order
        if j < plan.n and t >= self._landing_check_time(plan, j):
            soles = self.world.sole_positions()
            side = int(plan.swing_side[j])
            landed = soles[side, :2] - soles[1 - side, :2]
            planned = plan.swing_to[j, :2] - plan.support_pos[j, :2]
            self.landings[j] = float(np.linalg.norm(landed - planned))
        k = out.step_index
        if 0 <= k < self.walker.plan.n and k not in self.energy_at_step_start:
            world = self.world
            self.energy_at_step_start[k] = (
                world.energy_ctrl_per_joint.copy(),
                world.energy_substep_per_joint.copy(),
            )
        reason = self.world.fall_reason()
        if reason is None:
            if other_contact is None:
                other_contact = self.world.other_contact()
            if other_contact:
                reason = "a body other than the feet touched the floor"
        if reason is not None:
            self.fell, self.fall_time, self.fall_reason = True, t, reason

    def _landing_check_time(self, plan: FootstepPlan, j: int) -> float:
        """[s] when step ``j``'s landing error is measured: half a DSP after its touch-down
        (kept until the plan or the step changes, instead of rebuilt every tick)."""
        key = self._landing_key
        if key is None or key[0] is not plan or key[1] != j:
            when = float(plan.landing_times()[j] + 0.5 * plan.dsp_after_landing(j))
            self._landing_key = key = (plan, j, when)
        return key[2]

    # -- derived figures ---------------------------------------------------------------------
    def energy_windows(self, substep: bool = False) -> np.ndarray:
        """Energy per two-step window [J] (eq. 44), per joint: (windows, joints).

        Windows start at step 1: step 0 starts from standing and moves the foot one step
        length, later swings two; the last window closes at the start of the closing step.
        The live plots and Table 1 both read this.
        """
        n_walk = self.walker.plan.n_walking_steps
        starts = [
            self.energy_at_step_start[k][int(substep)]
            for k in range(1, n_walk + 1)
            if k in self.energy_at_step_start
        ]
        n_joints = len(self.world.energy_ctrl_per_joint)
        return two_step_windows(np.array(starts).reshape(len(starts), n_joints))
