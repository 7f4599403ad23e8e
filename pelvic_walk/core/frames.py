"""Immutable frames: what the displays, the API and the recordings read of a live session.

A :class:`LiveFrame` is published by the loop after it ticks (at the display rate) or applies
an intent. It holds one :class:`RobotFrame` per robot, built by :func:`robot_frame` from the
robot's :class:`~pelvic_walk.core.session.Session` (its world, its walker's last output and its last
measurement): copies of plain arrays, no live object, so a frame can cross to another thread
or process and be kept for scrubbing and recording. Metric rows for the plots
(:data:`ROW_COLUMNS`, one every :data:`HISTORY_DECIMATION` ticks, built by :func:`plot_row`)
ride along with the frame that follows them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from controller.explain import TickExplain
from controller.footsteps import FootstepPlan
from controller.params import ControllerParams
from controller.tick_explain import explain_tick
from models.dyros_jet import ANKLE_BODIES, HIP_BODIES
from pelvic_walk.core.metrics import KAPPA_SINGULAR
from pelvic_walk.core.session import Session
from pelvic_walk.core.summary import solver_failure_share, unsuccessful, unsuccessful_text

HISTORY_DECIMATION = 4  # one plot row every 4 control ticks (50 Hz)
ROW_COLUMNS = (
    "clock",  # [s] session clock (simulated time since the session started)
    "t",  # [s] the robot's own time (resets with it)
    "waist_deg",  # measured waist yaw [deg]
    "waist_rate_deg_s",  # commanded waist yaw rate [deg/s]
    "yaw_momentum",  # whole-body yaw momentum about the CoM [kg m^2/s]
    "kappa_legs",  # kappa of J_low's leg columns (eq. 45): it explodes as a knee straightens
    "energy_two_step",  # energy of the last completed two-step window [J] (as Table 1)
    "in_dsp",  # 1 in a double support, 0 in a single support, NaN standing
    "step_index",
    "fell",  # 1 while fallen
)


class TwoStepEnergy:
    """The last completed two-step window's energy [J] (the quantity of Table 1) of one
    session, recomputed only when a step has started since it was last read."""

    def __init__(self) -> None:
        self._key, self._value = -1, math.nan

    def __call__(self, session: Session) -> float:
        key = len(session.energy_at_step_start)
        if key != self._key:
            windows = session.energy_windows()
            self._key, self._value = key, float(windows[-1].sum()) if len(windows) else math.nan
        return self._value


def plot_row(session: Session, clock: float, energy: float) -> np.ndarray | None:
    """One plot row (:data:`ROW_COLUMNS`) of ``session`` after its last tick, at session
    ``clock``; None before its first tick (a gap in the plots)."""
    out, m = session.last, session.measured
    if out is None or m is None:
        return None
    walking = 0 <= out.step_index < session.plan.n
    return np.array(
        [
            clock,
            session.t,
            math.degrees(m.waist_angle),
            math.degrees(out.waist_rate),
            m.yaw_momentum,
            out.kappa_legs,
            energy,
            (0.0 if out.in_ssp else 1.0) if walking else math.nan,
            out.step_index,
            float(session.fell),
        ]
    )


@dataclass(frozen=True)
class Horizon:
    """One robot's plan over the MPC horizon at a tick (paper Fig. 5-7), N samples each."""

    t: np.ndarray  # (N,) [s] from the tick
    com: np.ndarray  # (N, 2) [m] predicted CoM (eq. 25-26)
    zmp: np.ndarray  # (N, 2) [m] predicted ZMP (eq. 16-17)
    zmp_ref: np.ndarray  # (N, 2) [m] ZMP reference
    zmp_lo: np.ndarray  # (N, 2) [m] ZMP bounds (eq. 18)
    zmp_hi: np.ndarray  # (N, 2) [m]
    left_foot: np.ndarray  # (N, 2) [m] planned feet (eq. 20-21)
    right_foot: np.ndarray  # (N, 2) [m]
    theta_ref: np.ndarray  # (N,) [rad] reference pelvic angle (eq. 30-33)
    theta: np.ndarray  # (N,) [rad] the pelvic MPC's optimised angle (eq. 35); for the other
    # methods the commanded angle now, held
    planned: bool  # theta is a plan over the horizon (a strategy that optimises: the MPC)
    lateral: np.ndarray  # (N, 2) [m] pelvis-to-foot lateral distance used by eq. (31)-(32)
    com_height: float  # [m] the LIPM's constant CoM height

    def plane_columns(self) -> dict[str, np.ndarray]:
        """The horizon's ground-plane paths as named columns [m] (``GET /api/horizon`` and
        ``pelvic_walk``'s ``Run.horizon`` share these names)."""
        return {
            "com_x": self.com[:, 0],
            "com_y": self.com[:, 1],
            "zmp_x": self.zmp[:, 0],
            "zmp_y": self.zmp[:, 1],
            "zmp_ref_x": self.zmp_ref[:, 0],
            "zmp_ref_y": self.zmp_ref[:, 1],
            "zmp_min_x": self.zmp_lo[:, 0],
            "zmp_max_x": self.zmp_hi[:, 0],
            "zmp_min_y": self.zmp_lo[:, 1],
            "zmp_max_y": self.zmp_hi[:, 1],
            "left_foot_x": self.left_foot[:, 0],
            "left_foot_y": self.left_foot[:, 1],
            "right_foot_x": self.right_foot[:, 0],
            "right_foot_y": self.right_foot[:, 1],
        }


@dataclass(frozen=True)
class RobotFrame:
    """One robot after one tick: copies of what the scene, plots and API need."""

    method: str  # the robot's key in its session: its label (pelvic_walk.core.robots)
    slot: int  # position among the robots shown (0 = first)
    clock: float  # [s] the session clock of this robot's state (its loop's clock)
    t: float  # [s] the robot's own time since its (re)start
    step_index: int  # -1 before the first step, n after the last
    in_dsp: bool
    swing_side: int  # LEFT / RIGHT, -1 while standing
    step_length: float  # [m] length of the step in progress (the one in force)
    fell: bool
    fall_reason: str | None
    error: str | None  # its pelvis strategy failed (message, file and line): it stopped, the
    # others walk on; the session restarts it with them at their next restart
    fell_clock: float | None  # [s] session clock of the fall: it is shown down from then
    # until the session restarts every robot (FALL_HOLD_S later, app.live.session)
    finished: bool  # walked its whole plan and stands (the session then restarts them all)
    walks_completed: int  # plans finished since the live session (re)started
    falls: int
    last_walk_success: bool | None  # outcome of the last finished or failed walk
    waiting: bool  # restarted robot standing by to start in phase with the others
    strategy_ms: float  # [ms] its strategy's waist_rate call, median of the last second
    body_xpos: np.ndarray  # (nbody, 3) [m] MuJoCo body positions
    body_xmat: np.ndarray  # (nbody, 3, 3) body orientations
    hips: np.ndarray  # (2, 3) [m] left, right hip points (measured)
    ankles: np.ndarray  # (2, 3) [m] left, right ankle points (measured)
    soles: np.ndarray  # (2, 3) [m] left, right sole centres (measured)
    sole_yaws: np.ndarray  # (2,) [rad]
    in_contact: np.ndarray  # (2,) bool, left / right foot on the floor
    support: np.ndarray  # (M, 2) [m] support polygon of the feet in contact
    cop: np.ndarray | None  # (2,) [m] measured ZMP (centre of pressure); None when airborne
    com: np.ndarray  # (3,) [m] measured CoM
    waist_angle: float  # [rad] measured waist yaw
    waist_angle_cmd: float  # [rad] commanded waist yaw
    yaw_momentum: float  # [kg m^2/s] measured, whole body about the CoM
    energy: float  # [J] cumulative positive joint work of this walk (eq. 44)
    solver_failures: int
    pushing: bool  # a push acts on the torso now
    kappa_low: float  # kappa(J_low) of eq. (45)
    kappa_legs: float  # kappa of J_low's 12 leg columns: it explodes as a knee straightens
    reach: np.ndarray  # (2,) hip-to-ankle / leg length, left and right
    speed_limited: bool  # the IK held a joint at its speed limit this tick
    zmp_ref: np.ndarray | None  # (2,) [m] ZMP reference now
    pelvis_des: np.ndarray | None  # (3,) [m] desired pelvis position (eq. 19)
    horizon: Horizon | None  # None before the first tick
    plan: FootstepPlan  # the footstep plan in force (immutable; replaced on replans)
    params: ControllerParams  # the parameters in force in this robot's walker
    # why its finished plan is no success, in words ("" otherwise: pelvic_walk.core.summary)
    unsuccessful: str = ""
    # what each layer's QP did at the tick (controller.explain), made with the frame: at the
    # display's or the recording's rate, never in a tick; None before the first tick or once
    # its strategy failed
    qp: TickExplain | None = None

    @property
    def strategy(self) -> str:
        """The pelvis strategy it runs (two robots may run one, with other settings)."""
        return self.params.method

    @property
    def status(self) -> str:
        """One badge: stopped / fell / knee nearly straight / IK at the speed limit / clean.

        The same test as the study's *clean* (``pelvic_walk/core/run.py``): the knee is "nearly
        straight"
        when kappa(J) of the leg columns reaches KAPPA_SINGULAR, so a robot the report calls
        clean never shows another badge live. The reach gauges show the leg's extension
        continuously (red near 1) for the eye."""
        if self.error is not None:
            return "stopped"
        if self.fell:
            return "fell"
        if self.kappa_legs >= KAPPA_SINGULAR:
            return "knee nearly straight"
        if self.speed_limited:
            return "IK at the speed limit"
        return "clean"


@dataclass(frozen=True)
class LiveFrame:
    """Everything the displays and the API read, published by the loop."""

    seq: int  # increases with every published frame
    clock: float  # [s] simulated time since the live session started
    paused: bool
    speed: float
    realtime_factor: float | None  # simulated / wall time over the last few seconds
    compute_realtime_factor: float | None  # simulated / compute time (headroom when paced)
    intent_version: int  # the newest intent the loop has read
    steps_done: int  # single-step requests carried out (compare with Intent.step_requests)
    pushes_done: int  # number of the last push carried out
    robots: tuple[RobotFrame, ...]
    rows: dict[str, np.ndarray] = field(default_factory=dict, repr=False)  # new plot rows
    restarted: bool = False  # the robots were rebuilt (reset, methods): plots start anew
    # [s] the loop's wall clock when it published (time.monotonic: one clock for every process
    # of the machine), so a late delivery is not mistaken for a late simulation; 0: unknown
    wall: float = 0.0

    def robot(self, method: str) -> RobotFrame | None:
        return next((r for r in self.robots if r.method == method), None)


_IDS: dict[tuple[str, ...], np.ndarray] = {}


def _body_ids(model, names: tuple[str, ...]) -> np.ndarray:
    """Body ids by name (cached: every session loads the same model file)."""
    if names not in _IDS:
        _IDS[names] = np.array([model.body(n).id for n in names])
    return _IDS[names]


def horizon_of(session: Session) -> Horizon | None:
    """The last tick's plan over the horizon (what the horizon inspector draws)."""
    out = session.last
    if out is None:
        return None
    cp = out.com_plan
    h = slice(2, None)  # the tick's plan sample: now, next tick, then the horizon
    ps = out.plan_sample
    theta = (
        np.asarray(out.pelvis_plan.angles)
        if out.pelvis_plan is not None
        else np.full(len(cp.times), out.waist_angle)
    )
    return Horizon(
        t=cp.times - out.t,
        com=cp.com.copy(),
        zmp=cp.zmp.copy(),
        zmp_ref=cp.zmp_ref.copy(),
        zmp_lo=np.asarray(cp.zmp_lo).copy(),
        zmp_hi=np.asarray(cp.zmp_hi).copy(),
        left_foot=ps.p_left[h, :2].copy(),
        right_foot=ps.p_right[h, :2].copy(),
        theta_ref=out.theta_ref.copy(),
        theta=theta.copy(),
        planned=out.pelvis_plan is not None,
        lateral=out.lateral.copy(),
        com_height=session.walker.com_height,
    )


def robot_frame(
    session: Session,
    slot: int,
    clock: float,
    method: str,
    falls: int,
    walks: int,
    last_success: bool | None,
    waiting: bool,
    error: str | None,
    fell_clock: float | None = None,
) -> RobotFrame:
    """A frame of one robot from its session (called by the loop, at the display rate)."""
    world, out, m = session.world, session.last, session.measured
    model, data = world.model, world.data
    plan = session.plan
    step_index = out.step_index if out is not None else -1
    if error is not None and session.error_step is not None:
        step_index = session.error_step  # the s.step it stopped in, not the tick before's
    return RobotFrame(
        method=method,
        slot=slot,
        clock=clock,
        t=float(session.t),
        step_index=int(step_index),
        in_dsp=bool(out is not None and not out.in_ssp and 0 <= step_index < plan.n),
        swing_side=int(out.swing_side) if out is not None else -1,
        step_length=plan.step_length(step_index),
        fell=session.fell,
        fall_reason=session.fall_reason,
        error=error,
        fell_clock=fell_clock,
        finished=bool(session.walker.finished and not session.fell and error is None),
        walks_completed=walks,
        falls=falls,
        last_walk_success=last_success,
        waiting=waiting,
        strategy_ms=session.strategy_ms_recent,
        body_xpos=data.xpos.astype(np.float32),
        body_xmat=data.xmat.reshape(-1, 3, 3).astype(np.float32),
        hips=data.xpos[_body_ids(model, HIP_BODIES)].copy(),
        ankles=data.xpos[_body_ids(model, ANKLE_BODIES)].copy(),
        soles=world.sole_positions(),
        sole_yaws=world.sole_yaws(),
        in_contact=(m.contacts.in_contact.copy() if m is not None else np.ones(2, dtype=bool)),
        support=m.support.copy() if m is not None else np.zeros((0, 2)),
        cop=(m.contacts.cop.copy() if m is not None and m.contacts.cop is not None else None),
        com=world.com(),
        waist_angle=float(data.qpos[world.qpos_idx[0]]),
        waist_angle_cmd=out.waist_angle if out is not None else 0.0,
        yaw_momentum=m.yaw_momentum if m is not None else 0.0,
        energy=m.energy if m is not None else 0.0,
        solver_failures=int(sum(session.walker.failure_counts.values())),
        pushing=world.pushing,
        kappa_low=out.kappa_low if out is not None else math.nan,
        kappa_legs=out.kappa_legs if out is not None else math.nan,
        reach=out.reach.copy() if out is not None else np.full(2, math.nan),
        speed_limited=bool(out is not None and out.speed_limited),
        zmp_ref=out.zmp_ref.copy() if out is not None else None,
        pelvis_des=out.p_world_pelvis_des.copy() if out is not None else None,
        horizon=horizon_of(session),
        plan=plan,
        params=session.walker.snapshot_params(),
        unsuccessful=_unsuccessful(session) if session.walker.finished else "",
        qp=explain_tick(session.walker, out) if out is not None and error is None else None,
    )


def _unsuccessful(session: Session) -> str:
    """Why a finished walk is no success, in words ("" for a success)."""
    landed = session.landings.values()
    return unsuccessful_text(
        unsuccessful(session), max(landed) if landed else None, solver_failure_share(session)
    )
