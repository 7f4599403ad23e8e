"""One control tick chaining the paper's layers (Fig. 3), at 200 Hz.

``Walker.tick`` is Fig. 3 as one method per block, called in this order (docs/DESIGN.md, "One
control tick"); each hands its results by name to the blocks after it:
 1-2, 5. ``_plan_rows``: the footstep plan (re-planned from the next step when walking
    parameters change) sampled for the tick: ZMP reference and bounds over the horizon, foot
    trajectories (eq. 20-21),
 3. ``_predicted_com``: CoM MPC (eq. 10-18), predicted CoM (eq. 25-26),
 4. ``_pelvis_position``: the CoM from the measured joints and the pelvis position (eq. 19),
 6. ``_reference_angles``: reference pelvic angle over the horizon (eq. 27-33),
 7. ``_pelvis_strategy``: the pelvis strategy's waist rate (``controller.strategy``: the
    pelvic-rotation MPC of eq. 34-38 for the paper's method, 0 for the fixed pelvis, free for
    redundancy, or a user's own) from its inputs built by field name,
 8. ``_inverse_kinematics``: QP inverse kinematics of the 13 lower-body joints (eq. 39-40),
 9. ``_arm_swing``: arm swing on the centroidal momentum matrix (eq. 41-43),
10. ``_joint_targets``: joint targets for the position servos (eq. 40).

Paper symbols -> names here:
    X_pel (eq. 19)           -> ``p_world_pelvis_des``
    X_c^d, X_c^m (eq. 19)    -> ``p_world_com_des``, ``p_world_com_meas``
    K_p (eq. 19)             -> ``params.com.pelvis_gain``
    X_c (eq. 25-26)          -> ``com_plan.com`` (the predicted CoM over the horizon)
    Delta d_FP,y (eq. 31-32) -> ``lateral``
    Theta_pel^ref (eq. 33)   -> ``theta_ref``
    theta_pel, theta_dot     -> ``StrategyInputs.theta`` (``q_cmd[0]``, commanded), ``.theta_dot``
    q_low, q_up (eq. 6-7)    -> ``q_cmd[lower]``, ``q_cmd[arms]``
    h_low^yaw, h_up^yaw      -> ``TickOutput.h_low``, ``TickOutput.h_up``

Choices where the paper is vague (documented here once):
- Eq. (19) is applied with a feed-forward term: the desired pelvis moves with the desired CoM
  and the ``K_p`` term slowly removes the offset between the desired CoM and the CoM measured
  from the *measured* joint angles with the support sole anchored at its planned foothold (as
  a real robot would estimate it). Without the feed-forward the pelvis would lag the moving CoM
  by v dt / K_p; with K_p = 1 (deadbeat) the servo delay makes it oscillate.
- The IK runs on the *commanded* joint state (closed-loop IK on q_cmd), so nothing drifts;
  the desired foot velocity is the feed-forward plus ``ik.foot_gain`` times the pose error.
- The waist angle a strategy reads (``StrategyInputs.theta``) is the commanded waist angle,
  its rate the one the IK commanded at the last tick; the pelvic MPC integrates its own rate
  (eq. 38).
- ``controller/`` never reads a clock: the caller may pass ``clock`` (e.g. time.perf_counter)
  to get per-layer timings; without it the timings are zero.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from controller.arm_swing import (
    arm_constants,
    build_arm_qp,
    solve_arm,
    solve_arm_step,
    yaw_momentum,
)
from controller.com_mpc import ComMpc, ComPlan
from controller.compiled import kernel
from controller.footsteps import (
    LEFT,
    RIGHT,
    FootstepPlan,
    PlanSample,
    TickSamples,
    plan_footsteps,
)
from controller.ik import (
    build_ik,
    flat_foot_velocity_command,
    foot_targets,
    ik_constants,
    solve_ik,
    solve_ik_step,
)
from controller.kinematics import KinState, RobotKinematics, jacobian_conditions, leg_reach
from controller.params import ControllerParams
from controller.pelvis_mpc import PelvisPlan
from controller.pelvis_reference import reference_with_lateral
from controller.qp import QpSolver
from controller.strategy import Runner, StrategyInputs, create

LAYERS = ("plan", "kinematics", "com_mpc", "pelvis_mpc", "ik", "arm_swing")


@dataclass(slots=True, eq=False)
class TickOutput:
    """Everything one tick produced: joint targets plus what the displays and metrics need.

    Read-only by contract (nothing changes one once returned). The diagnostics of eq. (45)
    and the leg reach (``kappa_low``, ``kappa_legs``, ``reach``) are not inputs of any layer:
    they are computed from this tick's kinematics on first read, so a reader pays for them at
    its own rate (a headless run's series every tick, the live displays at their frame rate).
    """

    t: float  # [s] time of the tick
    q_target: np.ndarray  # (n_joints,) joint position targets for the servos [rad]
    q_dot: np.ndarray  # (n_joints,) commanded joint velocities [rad/s]
    com_plan: ComPlan  # predicted CoM over the horizon (eq. 25-26)
    theta_ref: np.ndarray  # (N,) reference pelvic angle over the horizon (eq. 33) [rad]
    lateral: np.ndarray  # (N, 2) lateral distances of eq. (31)-(32) [m] (left > 0, right < 0)
    plan_sample: PlanSample  # the plan at t, t + dt and the N horizon samples
    pelvis_plan: PelvisPlan | None  # the strategy's optimised pelvic angles (the MPC's) or None
    p_world_pelvis_des: np.ndarray  # (3,) desired pelvis position (eq. 19) [m]
    p_world_com_des: np.ndarray  # (2,) desired CoM x, y [m]
    p_world_com_meas: np.ndarray  # (3,) CoM from measured joints, support-anchored [m]
    zmp_ref: np.ndarray  # (2,) ZMP reference now [m]
    waist_angle: float  # [rad] commanded waist yaw (theta_pel)
    waist_rate: float  # [rad/s]
    h_low: float  # [kg m^2/s] commanded lower-body yaw momentum (eq. 41)
    h_up: float  # [kg m^2/s] commanded upper-body yaw momentum (eq. 42)
    kin: KinState  # kinematics of the commanded joints the IK ran on (J_low, soles, hips)
    step_index: int  # current step (-1 before the first, n after the last)
    in_ssp: bool
    swing_side: int
    failures: dict[str, bool]  # which QP failed this tick (layer -> bool)
    speed_limited: bool  # a joint velocity sat at its limit
    layer_s: dict[str, float] = field(default_factory=dict)  # [s] per layer (Walker.layer_times)
    strategy_s: float = 0.0  # [s] the strategy's waist_rate call alone (0 without a clock)
    _diagnostics: tuple[float, float, np.ndarray] | None = None  # cache of the three below

    def _diagnosed(self) -> tuple[float, float, np.ndarray]:
        if self._diagnostics is None:
            # eq. (45) on the same matrices for every method (the waist rate is pinned in
            # fixed and mpc alike, so neither matrix favours a method)
            kappa_low, kappa_legs = jacobian_conditions(self.kin.J_low)
            self._diagnostics = (kappa_low, kappa_legs, leg_reach(self.kin))
        return self._diagnostics

    @property
    def kappa_low(self) -> float:
        """kappa(J_low) (eq. 45 on the 12 x 13 J of eq. 9), every method alike."""
        return self._diagnosed()[0]

    @property
    def kappa_legs(self) -> float:
        """kappa of J_low's 12 leg columns (without the waist), every method: the one that
        sees a straight knee (the waist column hides it in J_low)."""
        return self._diagnosed()[1]

    @property
    def reach(self) -> np.ndarray:
        """(2,) hip-to-ankle distance / leg length, left and right (commanded joints)."""
        return self._diagnosed()[2]


class Walker:
    """The controller of one robot. Owns the plan, the MPC/QP warm starts and the commanded state.

    Args:
        params: validated controller parameters.
        kin: Pinocchio kinematics of the same MJCF as the simulation.
        q_init: (n_joints,) initial joint angles (walk-ready pose) [rad].
        p_world_pelvis_init: (3,) initial pelvis (base) position [m].
        backend: QP back-end of every layer ("daqp": exact active set, the default; "osqp").
        clock: optional zero-argument timer: the strategy's time (``TickOutput.strategy_s``)
            and, with :attr:`layer_times` set, every layer's (``TickOutput.layer_s``).

    Raises:
        ValueError: ``params.method`` names no registered strategy.
        controller.strategy.StrategyError: the strategy's constructor failed; from
            :meth:`tick`: the strategy raised or returned no rate (the walker then stops).
    """

    def __init__(
        self,
        params: ControllerParams,
        kin: RobotKinematics,
        q_init: np.ndarray,
        p_world_pelvis_init: np.ndarray,
        backend: str = "daqp",
        clock: Callable[[], float] | None = None,
    ):
        self.kin = kin
        self.clock = clock
        self.layer_times = False  # time every layer (bench): a clock reading between blocks
        self.backend = backend
        self.params = params.validated()
        self.dt = params.control_dt
        self._constants(self.params)
        self.t = 0.0
        self.q_cmd = np.array(q_init, dtype=float)
        self.q_init = self.q_cmd.copy()
        self.lower = np.arange(13)  # q_cmd starts with the 13 lower joints (LOWER_JOINTS order)
        self.arms = kin.arm_qp_joint_idx  # positions of the 4 arm-QP joints in q_cmd
        # constant per tick: the joint limits of the two groups
        self._q_min_low, self._q_max_low = kin.q_min[self.lower], kin.q_max[self.lower]
        self._q_min_arms, self._q_max_arms = kin.q_min[self.arms], kin.q_max[self.arms]
        self._q_init_arms = self.q_init[self.arms]
        self._limits_low = np.array([self._q_min_low, self._q_max_low])  # (2, 13)
        self._limits_arms = np.array([self._q_min_arms, self._q_max_arms])  # (2, 4)
        self.p_world_pelvis_des = np.array(p_world_pelvis_init, dtype=float)
        self.pelvis_height = float(self.p_world_pelvis_des[2])

        ks = kin.compute(self.q_cmd)
        self.x0 = float(self.p_world_pelvis_des[0] + ks.T_pelvis_left_sole[0, 3])
        com0 = self.p_world_pelvis_des + ks.p_pelvis_com
        self.com_height = float(com0[2])
        self.plan: FootstepPlan = plan_footsteps(params.walk, x0=self.x0)
        self.com_state = np.zeros((3, 2))
        self.com_state[0] = com0[:2]
        self.com_mpc = ComMpc(params.com, self.com_height, self.dt, backend)
        # how the pelvis turns: the registered strategy named by params.method
        self.strategy: Runner = create(params.method, backend)
        self.ik_solver = QpSolver(backend)
        self.arm_solver = QpSolver(backend)
        self._last_waist_rate = 0.0  # [rad/s] waist rate of the last IK solution
        self.failure_counts = {name: 0 for name in ("com_mpc", "pelvis_mpc", "ik", "arm_swing")}
        self.ticks = 0  # ticks run
        self.failed_ticks = 0  # ticks on which some QP failed (the layer fell back)
        self._pending: ControllerParams | None = None
        self._com_des_prev: np.ndarray | None = None
        self._plan_table: TickSamples | None = None  # the plan's rows of the coming ticks
        self._plan_row = 0  # the row of the next tick in it

    # -- parameters --------------------------------------------------------------------------
    def set_params(self, params: ControllerParams) -> None:
        """Take new parameters on the next tick (gains, horizon) or next step (walking)."""
        self._pending = params.validated()

    def _apply_pending(self) -> None:
        new, self._pending = self._pending, None
        assert new is not None
        old = self.params
        if new.walk != old.walk:
            self.plan = self.plan.replanned(new.walk, self.t)
        if new.com != old.com:
            self.com_mpc.set_params(new.com)
        if new.method != old.method:
            # another strategy: reset at this tick, from the waist rate the IK last commanded
            self.strategy = create(new.method, self.backend)
            self.ik_solver.reset()
        self._constants(new)
        self.params = new

    def _constants(self, p: ControllerParams) -> None:
        """The compiled steps' constants of the parameters ``p`` (arrays made once)."""
        self._ik_constants = ik_constants(p.ik, self.dt)
        self._arm_constants = arm_constants(p.arms, self.dt, p.ik.joint_speed_limit)
        self._floor_and_gain = np.array([p.pelvis.lateral_floor, p.pelvis.k_pel])

    @property
    def finished(self) -> bool:
        """True once the plan (all steps and the final stand) is over."""
        return self.t >= self.plan.t_end

    def snapshot_params(self) -> ControllerParams:
        """The parameters in force (pending ones included)."""
        return self._pending or self.params

    def replace_params(self, **groups) -> None:
        """Convenience: ``w.replace_params(walk=dict(step_length=0.3))``."""
        self.set_params(self.snapshot_params().replace(**groups))

    # -- the tick: one method per block of Fig. 3 -------------------------------------------
    def tick(self, q_meas: np.ndarray) -> TickOutput:
        """Run one control period from the measured joint angles; return the new targets.

        One method per block of Fig. 3 (the numbers are the module docstring's); with a clock,
        ``c0``-``c7`` read it between the blocks (``TickOutput.layer_s``)."""
        if self._pending is not None:
            self._apply_pending()
        t = self.t
        clock = self.clock or float  # no clock: every reading is float() = 0.0
        lc = clock if self.layer_times else float  # the layers' readings: only when asked
        c0 = lc()
        plan, times = self._plan_rows(t, self.params.com.zmp_margin)  # 1-2, 5
        # the rows every block reads, as one view each: the soles over the horizon and now,
        # the ZMP reference now (the plan's table is read-only)
        h = _HORIZON
        soles = (plan.p_left[h], plan.p_right[h], plan.p_left[0], plan.p_right[0])
        zmp_now = plan.zmp_ref[0]
        c1 = lc()
        com_plan, p_world_com_des = self._predicted_com(t, plan, times)  # 3
        c2 = lc()
        p_pelvis_com, p_pelvis_soles = self.kin.com_and_soles(q_meas)  # 4: X_c^m's kinematics
        c3 = lc()
        p_world_com_meas, v_world_pelvis = self._pelvis_position(  # 4
            p_world_com_des, p_pelvis_com, p_pelvis_soles, soles, zmp_now
        )
        theta_ref, lateral = self._reference_angles(soles, com_plan, p_world_com_des)  # 6
        s0 = clock()
        waist_rate, pelvis_plan = self._pelvis_strategy(  # 7
            t, plan, soles, com_plan, p_world_com_des, theta_ref
        )
        c4 = clock()
        ks = self.kin.compute(self.q_cmd)  # the kinematics the IK and the arms run on
        c5 = lc()
        q_dot_low, ik_ok = self._inverse_kinematics(plan, ks, v_world_pelvis, waist_rate)  # 8
        c6 = lc()
        q_dot_up, arm_ok = self._arm_swing(ks, q_dot_low)  # 9
        c7 = lc()
        q_dot, q_new = np.empty(len(self.q_cmd)), np.empty(len(self.q_cmd))
        speed_limited, h_low, h_up = _joint_targets(  # 10
            self.q_cmd, q_dot_low, q_dot_up, self.arms, self.dt,
            self.params.ik.joint_speed_limit, ks.cmm_yaw_low, ks.cmm_yaw_up, q_dot, q_new,
        )  # fmt: skip
        self.q_cmd = q_new  # replaced every tick, never written: q_target below is this array
        failures = self._count_failures(com_plan, pelvis_plan, ik_ok, arm_ok)
        self.t = t + self.dt
        return TickOutput(
            t=t,
            q_target=q_new,
            q_dot=q_dot,
            com_plan=com_plan,
            theta_ref=theta_ref,
            lateral=lateral,
            plan_sample=plan,
            pelvis_plan=pelvis_plan,
            p_world_pelvis_des=self.p_world_pelvis_des.copy(),
            p_world_com_des=p_world_com_des,
            p_world_com_meas=p_world_com_meas,
            zmp_ref=zmp_now,
            waist_angle=float(q_new[0]),
            waist_rate=self._last_waist_rate,
            h_low=h_low,
            h_up=h_up,
            kin=ks,
            step_index=int(plan.step[0]),
            in_ssp=bool(plan.in_ssp[0]),
            swing_side=int(plan.swing_side[0]),
            failures=failures,
            speed_limited=bool(speed_limited),
            layer_s=_layer_times(c0, c1, c2, c3, c4, c5, c6, c7) if lc is not float else {},
            strategy_s=c4 - s0,
        )

    def _plan_rows(self, t: float, margin: float) -> tuple[PlanSample, np.ndarray]:
        """1-2, 5. The plan at t, t + dt and the CoM MPC's N samples (``PlanSample`` of N + 2
        rows: phase, ZMP reference and bounds, feet), and the N sample times t + k T_p: a row
        of the table of the coming ticks, filled again by the plan's sampler when the plan, the
        margin or the horizon changed, or the table ran out
        (``controller.footsteps.TickSamples``: the values the sampler gives)."""
        offsets = self.com_mpc.sample_offsets
        table, j = self._plan_table, self._plan_row
        if table is None or not table.covers(self.plan, margin, offsets, t, j):
            table = TickSamples(self.plan, margin, self.dt, offsets, t)
            self._plan_table, j = table, 0
        self._plan_row = j + 1
        return table.at(j), table.times[j, 2:]

    def _predicted_com(
        self, t: float, plan: PlanSample, times: np.ndarray
    ) -> tuple[ComPlan, np.ndarray]:
        """3. The CoM MPC (eq. 10-18) on the ZMP reference and bounds over the horizon: the
        predicted CoM (eq. 25-26) and X_c^d, the desired CoM x, y its first input reaches."""
        h = _HORIZON
        com_plan = self.com_mpc.solve_references(
            self.com_state, t, times, plan.zmp_ref[h], plan.zmp_lo[h], plan.zmp_hi[h]
        )
        self.com_state = com_plan.next_state
        return com_plan, self.com_state[0].copy()

    def _pelvis_position(
        self,
        p_world_com_des: np.ndarray,
        p_pelvis_com: np.ndarray,
        p_pelvis_soles: np.ndarray,
        soles: tuple[np.ndarray, ...],
        zmp_now: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """4. X_c^m, the CoM from the measured joints (``p_pelvis_com``, ``p_pelvis_soles``:
        their kinematics with the base at the identity) with the base placed so the soles are
        where planned now; then X_pel by eq. (19) with its feed-forward (module docstring), in
        place on ``p_world_pelvis_des``. Returns X_c^m (3,) and the pelvis velocity (3,) over
        the tick.

        Each sole anchors one estimate of X_c^m (the base placed by a sole is
        ``sole - p_pelvis_sole``: what :meth:`RobotKinematics.support_anchored_base` +
        :meth:`RobotKinematics.com_world` compute in two passes); they are blended by
        :func:`support_share`, which follows the ZMP reference: the support sole alone in
        single support, a continuous hand-over in the double support. The two estimates differ
        by a few millimetres (the measured legs do not close the loop between the planned
        soles exactly); switching between them at lift-off and touch-down made eq. (19) jerk
        the pelvis sideways by that much within a few ticks, which threw the centre of pressure
        to the support foot's outer edge.
        """
        prev = self._com_des_prev  # X_c^d of the last tick (the feed-forward), never written
        self._com_des_prev = p_world_com_des
        com_meas, v_pelvis = np.empty(3), np.empty(3)
        _pelvis_step(
            self.p_world_pelvis_des, p_world_com_des, p_world_com_des if prev is None else prev,
            p_pelvis_com, p_pelvis_soles, soles[2], soles[3], zmp_now,
            self.params.com.pelvis_gain, self.pelvis_height, self.dt, com_meas, v_pelvis,
        )  # fmt: skip
        return com_meas, v_pelvis

    def _reference_angles(
        self, soles: tuple[np.ndarray, ...], com_plan: ComPlan, p_world_com_des: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """6. Theta_pel^ref over the horizon (eq. 27-33) from the predicted CoM and the planned
        soles (``soles``: left and right over the horizon, then now; x, y read), and the
        lateral distances Delta d_FP,y of eq. (31)-(32) it used."""
        p = self.params.pelvis
        com_h, feet_l, feet_r, left_now, right_now = com_plan.com, *soles
        if p.reference == "now":  # ablation: no prediction, the state now held
            n_h = len(com_h)
            com_h = np.tile(p_world_com_des[:2], (n_h, 1))
            feet_l = np.tile(left_now[:2], (n_h, 1))
            feet_r = np.tile(right_now[:2], (n_h, 1))
        return reference_with_lateral(  # lateral_distances, then reference_pelvic_angles
            p.lateral_distance,
            com_h,
            feet_l,
            feet_r,
            p_world_com_des,  # the CoM MPC's state now (the estimate would feed noise in)
            left_now,
            right_now,
            self.params.walk.step_width / 2,
            self._floor_and_gain,
        )

    def _pelvis_strategy(
        self,
        t: float,
        plan: PlanSample,
        soles: tuple[np.ndarray, ...],
        com_plan: ComPlan,
        p_world_com_des: np.ndarray,
        theta_ref: np.ndarray,
    ) -> tuple[float | None, PelvisPlan | None]:
        """7. The pelvis strategy's waist rate theta_dot (the paper's: the pelvic-rotation MPC,
        eq. 34-38; ``None``: the waist free to the IK) and the plan it drew, if any."""
        # read-only for the strategy (and the displays); the soles are views of the plan's
        # read-only table
        theta_ref.flags.writeable = False
        com_plan.com.flags.writeable = False
        p_world_com_des.flags.writeable = False
        rate = self.strategy.waist_rate(
            StrategyInputs(
                t=t,
                dt=self.dt,
                theta=float(self.q_cmd[0]),
                theta_dot=self._last_waist_rate,
                theta_ref=theta_ref,
                horizon_t=self.com_mpc.sample_offsets,
                com=com_plan.com,
                com_now=p_world_com_des,
                left_sole=soles[0],
                right_sole=soles[1],
                left_sole_now=soles[2],
                right_sole_now=soles[3],
                support=_SIDE[plan.support_side[0]] if plan.in_ssp[0] else "both",
                swing=_SIDE.get(plan.swing_side[0]),
                step=int(plan.step[0]),
                phase=float(plan.s_ssp[0]),
                params=self.params,
            )
        )
        return rate, self.strategy.plan

    def _inverse_kinematics(
        self,
        plan: PlanSample,
        ks: KinState,
        v_world_pelvis: np.ndarray,
        waist_rate: float | None,
    ) -> tuple[np.ndarray, bool]:
        """8. QP inverse kinematics (eq. 39-40) on the commanded state: q_dot_low (13,) toward
        the feet's targets at the next tick (row 1 of the plan's rows, relative to the pelvis),
        the waist pinned to ``waist_rate``; 0 (the last command held) if the QP failed."""
        q_low = self.q_cmd[:13]  # the lower joints (a view: q_cmd is replaced, never written)
        feet = (plan.p_left, plan.v_left, plan.p_right, plan.v_right)
        pelvis, T_left, T_right = (
            self.p_world_pelvis_des,
            ks.T_pelvis_left_sole,
            ks.T_pelvis_right_sole,
        )
        step = solve_ik_step(
            self.ik_solver, ks.J_low, T_left, T_right, feet, pelvis, v_world_pelvis, q_low,
            self._limits_low, self._ik_constants, waist_rate,
        )  # fmt: skip
        if step is not None:  # the four calls below in one compiled step
            q_dot_low, ok = step
        else:
            p_des_l, p_des_r, v_ff_l, v_ff_r = foot_targets(
                plan.p_left[1], plan.v_left[1], plan.p_right[1], plan.v_right[1], pelvis,
                v_world_pelvis,
            )  # fmt: skip
            v_des = flat_foot_velocity_command(  # flat feet: desired poses given as positions
                T_left, p_des_l, v_ff_l, T_right, p_des_r, v_ff_r, self.params.ik.foot_gain
            )
            qp = build_ik(
                ks.J_low, v_des, q_low, self._q_min_low, self._q_max_low, self.params.ik,
                self.dt, waist_rate,
            )  # fmt: skip
            q_dot_low, ok = solve_ik(qp, self.ik_solver)
        if not ok:
            q_dot_low = np.zeros(13)
        self._last_waist_rate = float(q_dot_low[0])
        return q_dot_low, ok

    def _arm_swing(self, ks: KinState, q_dot_low: np.ndarray) -> tuple[np.ndarray, bool]:
        """9. q_dot_up of the arm swing (eq. 41-43) on the centroidal momentum matrix, against
        the lower body's q_dot_low just computed; 0 if the QP failed. Arms off: back gently to
        the initial pose (and stay there)."""
        p, arms = self.params, self.arms
        if not p.arms.enabled:
            return np.clip((self._q_init_arms - self.q_cmd[arms]) / 0.2, -1.0, 1.0), True
        q_up = self.q_cmd[arms]
        step = solve_arm_step(
            self.arm_solver, ks.cmm_yaw_low, q_dot_low, ks.cmm_yaw_up, q_up, self._q_init_arms,
            self._limits_arms, self._arm_constants,
        )  # fmt: skip
        if step is not None:  # the two calls below in one compiled step
            q_dot_up, ok = step
        else:
            aqp = build_arm_qp(
                ks.cmm_yaw_low, q_dot_low, ks.cmm_yaw_up, q_up, self._q_init_arms,
                self._q_min_arms, self._q_max_arms, p.ik.joint_speed_limit, p.arms, self.dt,
            )  # fmt: skip
            q_dot_up, ok = solve_arm(aqp, self.arm_solver)
        return (q_dot_up, True) if ok else (np.zeros(len(arms)), False)

    def _count_failures(
        self, com_plan: ComPlan, pelvis_plan: PelvisPlan | None, ik_ok: bool, arm_ok: bool
    ) -> dict[str, bool]:
        """Which QP failed this tick (layer -> bool), counted per layer and per tick."""
        failures = {
            "com_mpc": not com_plan.ok,
            "pelvis_mpc": pelvis_plan is not None and not pelvis_plan.ok,
            "ik": not ik_ok,
            "arm_swing": not arm_ok,
        }
        self.ticks += 1
        if True in failures.values():  # rare: the loop only then
            self.failed_ticks += 1
            for name, failed in failures.items():
                self.failure_counts[name] += failed
        return failures


_HORIZON = slice(2, None)  # the horizon's rows of the tick's PlanSample (after t and t + dt)
# StrategyInputs.support and .swing by side (LEFT, RIGHT; a numpy integer hashes as its int)
_SIDE = {LEFT: "left", RIGHT: "right"}


def _layer_times(c0, c1, c2, c3, c4, c5, c6, c7) -> dict[str, float]:
    """``TickOutput.layer_s`` from the clock's readings around the layers: the kinematics are
    the measured CoM (c2-c3) and the commanded joints' (c4-c5); the pelvis position and
    reference count with the strategy (c3-c4)."""
    return {
        "plan": c1 - c0,
        "com_mpc": c2 - c1,
        "kinematics": (c3 - c2) + (c5 - c4),
        "pelvis_mpc": c4 - c3,
        "ik": c6 - c5,
        "arm_swing": c7 - c6,
    }


@kernel
def support_share(p_left, p_right, zmp_ref):
    """The left sole's share in [0, 1] of the weight: where the ZMP reference lies on the line
    from the right sole (0) to the left (1). 1 or 0 in single support (the reference sits on
    the support foot), a linear hand-over in the double support, 0.5 standing between the feet.
    """
    d = p_left[:2] - p_right[:2]
    share = (zmp_ref[:2] - p_right[:2]) @ d / (d @ d)
    return min(max(share, 0.0), 1.0)


@kernel
def _anchored_com(p_pelvis_com, p_pelvis_soles, foot_l, foot_r, zmp_ref):
    """(3,) the CoM anchored at each planned sole, blended by :func:`support_share`."""
    w_left = support_share(foot_l, foot_r, zmp_ref)
    com_l = (foot_l - p_pelvis_soles[0]) + p_pelvis_com
    com_r = (foot_r - p_pelvis_soles[1]) + p_pelvis_com
    return w_left * com_l + (1.0 - w_left) * com_r


@kernel
def _pelvis_step(
    pelvis, com_des, com_des_prev, p_pelvis_com, p_pelvis_soles, foot_l, foot_r, zmp_ref, gain,
    height, dt, com_meas, v_pelvis,
):  # fmt: skip
    """X_c^m (:func:`_anchored_com`) into ``com_meas`` (3,), then eq. (19) with its
    feed-forward in place on ``pelvis`` (3,): X_pel += (X_c^d - X_c^d,prev) + K_p (X_c^d -
    X_c^m) in x, y, and z at ``height``; the pelvis velocity over the tick into ``v_pelvis``."""
    com_meas[:] = _anchored_com(p_pelvis_com, p_pelvis_soles, foot_l, foot_r, zmp_ref)
    prev = pelvis.copy()
    pelvis[:2] += (com_des - com_des_prev) + gain * (com_des - com_meas[:2])
    pelvis[2] = height
    v_pelvis[:] = (pelvis - prev) / dt


@kernel
def _joint_targets(q_cmd, q_dot_low, q_dot_up, arms, dt, limit, a_low, a_up, q_dot, q_new):
    """Eq. (40): the joint velocities into ``q_dot`` (n,) (the lower joints first, the arms'
    at ``arms``), the new commanded joints q + dt q_dot into ``q_new`` (q_cmd is replaced,
    never written). Returns whether a lower joint's velocity sits at the speed limit and the
    yaw momenta h_low, h_up of eq. (41)-(42) commanded (``a_low``, ``a_up``: their CMM rows).
    """
    q_dot[:] = 0.0
    q_dot[: q_dot_low.shape[0]] = q_dot_low
    for i in range(arms.shape[0]):
        q_dot[arms[i]] = q_dot_up[i]
    q_new[:] = q_cmd + dt * q_dot
    limited = np.abs(q_dot_low).max() >= limit * 0.999
    return limited, yaw_momentum(a_low, q_dot_low), yaw_momentum(a_up, q_dot_up)
