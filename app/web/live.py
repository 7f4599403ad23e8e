"""The live simulation of the web tool: one thread owns the loop, displays read frames.

Pattern (STYLE.md, mujoco_playground / pink's gizmo example):

- **One owner of the loop.** :class:`LiveSim` runs one thread that ticks one
  :class:`app.runs.Session` per selected method (same parameters, the method differs), paced to
  real time x ``speed``: it sleeps to the wall clock and, when it cannot keep up, runs as fast as
  it can and reports the real-time factor it measured.
- **Callbacks only write intent.** The web handlers and viser callbacks replace an immutable
  :class:`Intent` (controller parameters plus playback: pause, single step, speed, reset,
  methods) under a lock. The loop picks it up on its next tick: gains and horizon go to every
  walker with ``walker.set_params`` (they act on the next tick; the walker re-plans the
  footsteps from the next step when walking parameters change).
- **Immutable frames out.** After a tick the loop publishes a :class:`LiveFrame` holding one
  :class:`RobotFrame` per robot (numpy copies of what the scene needs) and, a few times per
  second, a :class:`History` snapshot for the plots. No display code runs in the loop. While
  running, frames go out at most every ``PUBLISH_INTERVAL_S`` of wall time (the displays
  read 25 per second; a frame costs about 0.1 ms per robot, 200 times a second would be a
  few per cent of the loop); a tick that applies a new intent or a single step always
  publishes.

Live choices: plans are long (``LIVE_STEPS`` = 200 steps); a robot whose plan ends starts
again; a robot that falls is shown fallen for ``FALL_RESET_S`` seconds of simulated time and
then reset (the other robots walk on). Changing the methods or pressing reset restarts all
robots together so they stay in step.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from app.runs import RunConfig, Session
from controller.footsteps import FootstepPlan
from controller.params import METHODS, ControllerParams
from controller.walker import TickOutput
from models.dyros_jet import ANKLE_BODIES, FOOT_GEOMS, HIP_BODIES

log = logging.getLogger(__name__)

LIVE_STEPS = 200  # steps per live plan; the robot restarts when it ends
DEFAULT_METHODS: tuple[str, ...] = ("fixed", "mpc")
FALL_RESET_S = 2.0  # [s] of simulated time a fallen robot stays down before it is reset
SPEED_MIN, SPEED_MAX = 0.1, 4.0  # playback speed range (x real time)
RTF_WINDOW_S = 3.0  # [s] of wall time over which the real-time factor is measured
HISTORY_DECIMATION = 4  # one history row every 4 control ticks (50 Hz)
HISTORY_PUBLISH_ROWS = 5  # publish a history snapshot every 5 rows (10 Hz)
PUBLISH_INTERVAL_S = 0.02  # [s] of wall time between frames while running (displays read 25/s)
HISTORY_COLUMNS = (
    "t",  # [s] the robot's own time (resets with it)
    "waist_deg",  # measured waist yaw [deg]
    "waist_rate_deg_s",  # commanded waist yaw rate [deg/s]
    "yaw_momentum",  # whole-body yaw momentum about the CoM [kg m^2/s]
    "kappa",  # condition number of J (eq. 45)
    "energy",  # cumulative positive joint work since the robot's reset [J] (eq. 44)
    "energy_two_step",  # energy of the last two steps [J] (NaN until two steps are done)
)


def live_params(params: ControllerParams | None = None) -> ControllerParams:
    """The default live parameters: the controller's defaults with a long plan."""
    base = params or ControllerParams()
    return base.replace(walk={"n_steps": LIVE_STEPS})


# -- intent (written by callbacks) ---------------------------------------------------------
@dataclass(frozen=True)
class Intent:
    """What the users want; replaced as a whole under a lock, read by the loop each tick."""

    params: ControllerParams  # shared by every robot (its ``method`` field is not used)
    methods: tuple[str, ...] = DEFAULT_METHODS
    paused: bool = False
    speed: float = 1.0  # x real time
    step_requests: int = 0  # single steps asked for so far (monotonic)
    reset_requests: int = 0  # resets asked for so far (monotonic)
    version: int = 0  # bumped on every change


def check_methods(methods: Sequence[str]) -> tuple[str, ...]:
    """Validated, de-duplicated methods in the canonical order; ValueError otherwise."""
    methods = tuple(methods)
    bad = [m for m in methods if m not in METHODS]
    if bad:
        raise ValueError(f"unknown method {bad[0]!r}: choose from {', '.join(METHODS)}")
    if not methods:
        raise ValueError("choose at least one method")
    return tuple(m for m in METHODS if m in methods)


# -- frames (read by displays) -------------------------------------------------------------
@dataclass(frozen=True)
class RobotFrame:
    """One robot after one tick: copies of what the scene, plots and API need."""

    method: str
    slot: int  # position among the robots shown (0 = first)
    t: float  # [s] the robot's own time since its (re)start
    step_index: int
    step_length: float  # [m] length of the step in progress (the one in force)
    fell: bool
    fall_reason: str | None
    walks_completed: int  # plans finished since the last reset of the live session
    falls: int
    last_walk_success: bool | None  # outcome of the last finished or failed walk
    body_xpos: np.ndarray  # (nbody, 3) [m] MuJoCo body positions
    body_xmat: np.ndarray  # (nbody, 3, 3) body orientations
    hips: np.ndarray  # (2, 3) [m] left, right hip points (measured)
    ankles: np.ndarray  # (2, 3) [m] left, right ankle points (measured)
    soles: np.ndarray  # (2, 3) [m] left, right sole centres (measured)
    sole_yaws: np.ndarray  # (2,) [rad]
    in_contact: np.ndarray  # (2,) bool, left / right foot on the floor
    cop: np.ndarray | None  # (2,) [m] measured ZMP (centre of pressure); None when airborne
    com: np.ndarray  # (3,) [m] measured CoM
    waist_angle: float  # [rad] measured waist yaw
    yaw_momentum: float  # [kg m^2/s] measured, whole body about the CoM
    energy: float  # [J] cumulative positive joint work of this walk (eq. 44)
    solver_failures: int
    tick: TickOutput | None  # the controller's last output (None before the first tick)
    plan: FootstepPlan  # the footstep plan in force (immutable; replaced on replans)
    params: ControllerParams  # the parameters in force in this robot's walker


@dataclass(frozen=True)
class History:
    """Recent metrics for the plots: a rolling window, one array per method and column."""

    clock: np.ndarray  # (n,) [s] loop clock (simulated time since the live session started)
    columns: tuple[str, ...]
    values: dict[str, np.ndarray]  # method -> (n, len(columns)); NaN where not yet recorded


@dataclass(frozen=True)
class LiveFrame:
    """Everything the displays and the API read, published after each loop iteration."""

    seq: int  # increases with every published frame
    clock: float  # [s] simulated time since the live session started
    paused: bool
    speed: float
    realtime_factor: float | None  # simulated / wall time over the last few seconds
    compute_realtime_factor: float | None  # simulated / compute time (headroom when paced)
    intent_version: int  # the intent this frame reflects
    robots: tuple[RobotFrame, ...]
    history: History | None = field(default=None, repr=False)


# -- the loop ------------------------------------------------------------------------------
class _Robot:
    """A session of one method plus the live bookkeeping around it (loop thread only)."""

    def __init__(self, method: str, params: ControllerParams, capacity: int):
        self.method = method
        self.capacity = capacity
        self.walks_completed = 0
        self.falls = 0
        self.last_walk_success: bool | None = None
        self.error: str | None = None
        self.session = self._new_session(params)

    def _new_session(self, params: ControllerParams) -> Session:
        self.error = None
        self.fell_at: float | None = None  # robot time of the fall
        return Session(RunConfig(params=dataclasses.replace(params, method=self.method)),
                       capacity=self.capacity)

    def restart(self, params: ControllerParams) -> None:
        self.session = self._new_session(params)

    @property
    def fell(self) -> bool:
        return self.session.fell or self.error is not None


class LiveSim:
    """The live simulation: a thread ticking the robots, intent in, frames out.

    Args:
        params: the initial parameters (default: :func:`live_params`).
        methods: the robots to show, one per method.
        speed: playback speed (x real time).
        history_s: [s] length of the rolling window kept for the plots.
        clock, sleep: the wall clock and the sleep function used for pacing (tests may pass
            a no-op sleep to run unpaced; the controller and simulation are always real).
    """

    def __init__(
        self,
        params: ControllerParams | None = None,
        methods: Sequence[str] = DEFAULT_METHODS,
        speed: float = 1.0,
        history_s: float = 12.0,
        clock: Callable[[], float] = time.perf_counter,
        sleep: Callable[[float], None] | None = None,
    ):
        params = (params or live_params()).validated()
        self._lock = threading.Lock()
        self._changed = threading.Condition(self._lock)  # notified when a frame is published
        self._intent = Intent(params=params, methods=check_methods(methods),
                              speed=_check_speed(speed))
        self._frame: LiveFrame | None = None
        self._history: History | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._wake = threading.Event()  # set on every intent change (wakes a paused loop)
        self._clock = clock
        self._sleep = sleep or self._wake.wait  # an intent change cuts a pacing sleep short
        self._history_rows = max(10, int(history_s / (params.control_dt * HISTORY_DECIMATION)))
        self.history_s = self._history_rows * params.control_dt * HISTORY_DECIMATION  # [s]
        self.robots: dict[str, _Robot] = {}  # loop thread only (tests may read)
        self.error: str | None = None  # set if the loop thread itself died

    # -- intent API (any thread) ---------------------------------------------------------
    @property
    def intent(self) -> Intent:
        with self._lock:
            return self._intent

    def _update(self, **changes) -> int:
        return self._modify(lambda _cur: changes)

    def _modify(self, changes_of: Callable[[Intent], dict]) -> int:
        """Read, change and write the intent atomically (concurrent writers lose nothing)."""
        with self._lock:
            cur = self._intent
            new = dataclasses.replace(cur, version=cur.version + 1, **changes_of(cur))
            self._intent = new
        self._wake.set()
        return new.version

    def set_params(self, params: ControllerParams) -> int:
        """Replace the shared parameters (validated); returns the intent version."""
        params = params.validated()
        return self._update(params=params)

    def update_params(self, **groups) -> int:
        """Partial change, e.g. ``update_params(walk={"step_length": 0.3})``; ValueError."""
        return self._modify(lambda cur: {"params": cur.params.replace(**groups)})

    def set_methods(self, methods: Sequence[str]) -> int:
        methods = check_methods(methods)
        if methods == self.intent.methods:
            return self.intent.version
        return self._update(methods=methods)

    def set_speed(self, speed: float) -> int:
        return self._update(speed=_check_speed(speed))

    def pause(self) -> int:
        return self._update(paused=True)

    def resume(self) -> int:
        return self._update(paused=False)

    def step(self) -> int:
        """Pause (if running) and advance exactly one control period."""
        return self._modify(lambda cur: {"paused": True, "step_requests": cur.step_requests + 1})

    def reset(self) -> int:
        """Restart every robot from standing (t = 0)."""
        return self._modify(lambda cur: {"reset_requests": cur.reset_requests + 1})

    # -- frames (any thread) -------------------------------------------------------------
    def frame(self) -> LiveFrame | None:
        """The latest published frame (immutable)."""
        with self._lock:
            return self._frame

    def wait_applied(self, version: int, timeout: float = 5.0) -> LiveFrame | None:
        """Block until a frame reflects intent ``version`` (or newer); None on timeout."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                f = self._frame
                if f is not None and f.intent_version >= version:
                    return f
                left = deadline - time.monotonic()
                if left <= 0 or self._stop.is_set() or not self.running:
                    return None
                self._changed.wait(left)

    def wait_frame(self, after_seq: int = -1, timeout: float = 5.0) -> LiveFrame | None:
        """Block until a frame newer than ``after_seq`` is published; None on timeout."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                f = self._frame
                if f is not None and f.seq > after_seq:
                    return f
                left = deadline - time.monotonic()
                if left <= 0 or self._stop.is_set():
                    return None
                self._changed.wait(left)

    # -- thread ---------------------------------------------------------------------------
    def start(self) -> LiveSim:
        if self._thread is None:
            self._stop.clear()
            self._thread = threading.Thread(target=self._run, name="live-sim", daemon=True)
            self._thread.start()
        return self

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None
        with self._changed:
            self._changed.notify_all()

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def _run(self) -> None:
        try:
            self._loop()
        except Exception as exc:  # noqa: BLE001 - keep the web server up; report the cause
            log.exception("live simulation stopped")
            self.error = f"{type(exc).__name__}: {exc}"
        finally:
            with self._changed:
                self._changed.notify_all()

    def _loop(self) -> None:
        intent = self.intent
        dt = intent.params.control_dt
        applied: Intent | None = None
        steps_done = resets_done = 0
        clock = 0.0  # simulated time since start [s]
        seq = 0
        tick_count = 0
        anchor_wall, anchor_sim = self._clock(), 0.0
        rtf_samples: deque[tuple[float, float, float]] = deque()  # (wall, sim, busy)
        busy = 0.0
        hist = _HistoryBuffer(self._history_rows)
        last_publish, published_version = -math.inf, -1

        while not self._stop.is_set():
            intent = self.intent
            # 1. Apply new intent: methods, resets, parameters, speed.
            if applied is None or intent.version != applied.version:
                rebuild = (
                    applied is None
                    or intent.methods != applied.methods
                    or intent.reset_requests != resets_done
                )
                if rebuild:
                    self._build_robots(intent)
                    resets_done = intent.reset_requests
                    hist.clear()
                    self._history = None
                elif intent.params != applied.params:
                    for robot in self.robots.values():
                        robot.session.walker.set_params(
                            dataclasses.replace(intent.params, method=robot.method)
                        )
                if applied is None or intent.speed != applied.speed or (
                    intent.paused != applied.paused
                ):
                    anchor_wall, anchor_sim = self._clock(), clock
                    rtf_samples.clear()
                if intent.step_requests < steps_done or not intent.paused:
                    steps_done = intent.step_requests  # resuming drops pending single steps
                applied = intent

            pending_steps = intent.step_requests - steps_done
            run_tick = not intent.paused or pending_steps > 0
            if not run_tick:
                seq += 1
                self._publish(seq, clock, intent, intent.version, None, None, hist, force=True)
                self._wake.wait(0.05)
                self._wake.clear()
                continue

            # 2. One control period for every robot.
            t0 = self._clock()
            for robot in self.robots.values():
                self._tick_robot(robot, intent.params)
            busy += self._clock() - t0
            clock += dt
            tick_count += 1
            if intent.paused:
                steps_done += 1
            if tick_count % HISTORY_DECIMATION == 0 or intent.paused:
                hist.record(clock, self.robots)

            # 3. Real-time factor over the last seconds, then pace to the wall clock.
            now = self._clock()
            rtf_samples.append((now, clock, busy))
            while rtf_samples and now - rtf_samples[0][0] > RTF_WINDOW_S:
                rtf_samples.popleft()
            rtf, compute_rtf = _rates(rtf_samples)
            if intent.paused:
                rtf = compute_rtf = None
            # The intent counts as applied once its single steps are all done.
            done = intent.step_requests - steps_done <= 0 or not intent.paused
            version = intent.version if done else intent.version - 1
            if (intent.paused or version != published_version
                    or now - last_publish >= PUBLISH_INTERVAL_S):
                seq += 1
                self._publish(seq, clock, intent, version, rtf, compute_rtf, hist,
                              force=intent.paused)
                last_publish, published_version = now, version
            if not intent.paused:
                target = anchor_wall + (clock - anchor_sim) / intent.speed
                ahead = target - self._clock()
                if ahead > 0:
                    self._sleep(ahead)
                    self._wake.clear()
                elif ahead < -0.25:  # cannot keep up: run as fast as possible from here
                    anchor_wall, anchor_sim = self._clock(), clock

    def _build_robots(self, intent: Intent) -> None:
        capacity = int(4.0 / intent.params.control_dt)  # series ring: the last 4 s
        self.robots = {m: _Robot(m, intent.params, capacity) for m in intent.methods}

    def _tick_robot(self, robot: _Robot, params: ControllerParams) -> None:
        s = robot.session
        if robot.fell:
            if robot.fell_at is None:
                robot.fell_at = s.t
                robot.falls += 1
                robot.last_walk_success = False
            if s.t - robot.fell_at >= FALL_RESET_S:
                robot.restart(params)
                return
        elif s.walker.finished:
            robot.walks_completed += 1
            robot.last_walk_success = True
            robot.restart(params)
            return
        if robot.error is not None:
            # The controller raised: let the time run so the robot is shown down, then reset.
            s.walker.t += s.params.control_dt
            return
        try:
            s.tick()
        except Exception as exc:  # noqa: BLE001 - one robot's failure must not stop the loop
            log.exception("robot %s: controller tick failed", robot.method)
            robot.error = f"{type(exc).__name__}: {exc}"

    def _publish(
        self,
        seq: int,
        clock: float,
        intent: Intent,
        version: int,
        rtf: float | None,
        compute_rtf: float | None,
        hist: _HistoryBuffer,
        force: bool,
    ) -> None:
        robots = tuple(
            _robot_frame(robot, slot) for slot, robot in enumerate(self.robots.values())
        )
        if force or hist.rows_since_publish >= HISTORY_PUBLISH_ROWS or self._history is None:
            self._history = hist.snapshot()
        frame = LiveFrame(
            seq=seq, clock=clock, paused=intent.paused,
            speed=intent.speed, realtime_factor=rtf, compute_realtime_factor=compute_rtf,
            intent_version=version, robots=robots, history=self._history,
        )
        with self._changed:
            self._frame = frame
            self._changed.notify_all()


def _check_speed(speed: float) -> float:
    speed = float(speed)
    if not math.isfinite(speed) or not SPEED_MIN <= speed <= SPEED_MAX:
        raise ValueError(f"speed must be between {SPEED_MIN} and {SPEED_MAX}, got {speed}")
    return speed


def _rates(samples: deque[tuple[float, float, float]]) -> tuple[float | None, float | None]:
    """(simulated / wall, simulated / compute) over the samples, None until 0.5 s of data."""
    if len(samples) < 2:
        return None, None
    (w0, s0, b0), (w1, s1, b1) = samples[0], samples[-1]
    if w1 - w0 < 0.5:
        return None, None
    compute = (s1 - s0) / (b1 - b0) if b1 > b0 else None
    return (s1 - s0) / (w1 - w0), compute


# -- frame building (loop thread) ------------------------------------------------------------
_BODY_IDS: dict[str, np.ndarray] = {}


def _ids(model, names: Sequence[str], kind: str) -> np.ndarray:
    key = f"{kind}:{','.join(names)}"
    if key not in _BODY_IDS:
        getter = model.body if kind == "body" else model.geom
        _BODY_IDS[key] = np.array([getter(n).id for n in names])
    return _BODY_IDS[key]


def foot_contacts(model, data) -> np.ndarray:
    """(2,) bool: left / right foot geom touches a geom of the world body (the floor)."""
    feet = _ids(model, FOOT_GEOMS, "geom")
    geoms = np.asarray(data.contact.geom[: data.ncon]).reshape(-1, 2)
    if len(geoms) == 0:
        return np.zeros(2, dtype=bool)
    on_world = model.geom_bodyid[geoms] == 0  # (ncon, 2)
    out = np.zeros(2, dtype=bool)
    for side, g in enumerate(feet):
        out[side] = bool(np.any((geoms[:, 0] == g) & on_world[:, 1])
                         or np.any((geoms[:, 1] == g) & on_world[:, 0]))
    return out


def step_length_in_force(plan: FootstepPlan, step_index: int) -> float:
    """[m] forward length of the step in progress (or the next/last walking step)."""
    n_walk = plan.n_walking_steps
    if n_walk <= 0:
        return 0.0
    k = int(np.clip(step_index, 0, n_walk - 1))
    return float(plan.swing_to[k, 0] - plan.support_pos[k, 0])


def _robot_frame(robot: _Robot, slot: int) -> RobotFrame:
    s = robot.session
    world = s.world
    m, d = world.model, world.data
    last = s.series.data[(s.series.count - 1) % s.series.capacity] if s.series.count else None
    ix = s.series.index

    def col(name: str, default: float = math.nan) -> float:
        return float(last[ix[name]]) if last is not None else default

    cop = None
    if last is not None and np.isfinite(last[ix["cop_x"]]):
        cop = np.array([last[ix["cop_x"]], last[ix["cop_y"]]])
    out = s.last
    step_index = out.step_index if out is not None else -1
    return RobotFrame(
        method=robot.method,
        slot=slot,
        t=float(s.t),
        step_index=int(step_index),
        step_length=step_length_in_force(s.walker.plan, step_index),
        fell=robot.fell,
        fall_reason=robot.error or s.fall_reason,
        walks_completed=robot.walks_completed,
        falls=robot.falls,
        last_walk_success=robot.last_walk_success,
        body_xpos=d.xpos.copy(),
        body_xmat=d.xmat.reshape(-1, 3, 3).copy(),
        hips=d.xpos[_ids(m, HIP_BODIES, "body")].copy(),
        ankles=d.xpos[_ids(m, ANKLE_BODIES, "body")].copy(),
        soles=world.sole_positions(),
        sole_yaws=world.sole_yaws(),
        in_contact=foot_contacts(m, d),
        cop=cop,
        com=d.subtree_com[world.root_id].copy(),
        waist_angle=float(d.qpos[world.qpos_idx[0]]),
        yaw_momentum=col("yaw_momentum", 0.0),
        energy=float(world.energy_per_joint.sum()),
        solver_failures=int(sum(s.walker.failure_counts.values())),
        tick=out,
        plan=s.walker.plan,
        params=s.walker.snapshot_params(),
    )


class _HistoryBuffer:
    """Rolling window of per-method metrics for the plots (loop thread only)."""

    def __init__(self, rows: int):
        self.rows = rows
        self.clear()

    def clear(self) -> None:
        self.clock = np.full(self.rows, np.nan)
        self.values: dict[str, np.ndarray] = {}
        self.count = 0
        self.rows_since_publish = 0
        self._energy: dict[str, deque[tuple[float, float]]] = {}

    def record(self, clock: float, robots: dict[str, _Robot]) -> None:
        i = self.count % self.rows
        self.clock[i] = clock
        for method, robot in robots.items():
            arr = self.values.get(method)
            if arr is None:
                arr = self.values[method] = np.full((self.rows, len(HISTORY_COLUMNS)), np.nan)
            s = robot.session
            if not s.series.count:
                arr[i] = np.nan
                continue
            last = s.series.data[(s.series.count - 1) % s.series.capacity]
            ix = s.series.index
            energy = float(s.world.energy_per_joint.sum())
            arr[i] = (
                s.t,
                np.degrees(last[ix["waist_angle"]]),
                np.degrees(last[ix["waist_rate"]]),
                last[ix["yaw_momentum"]],
                last[ix["kappa"]],
                energy,
                self._two_step_energy(method, s, energy),
            )
        self.count += 1
        self.rows_since_publish += 1

    def _two_step_energy(self, method: str, s: Session, energy: float) -> float:
        """Energy spent over the last two step times [J] (eq. 44 on a rolling window)."""
        ring = self._energy.setdefault(method, deque())
        if ring and s.t < ring[-1][0]:  # the robot restarted
            ring.clear()
        ring.append((s.t, energy))
        window = 2.0 * s.params.walk.step_time
        while len(ring) > 2 and s.t - ring[1][0] >= window:
            ring.popleft()
        t0, e0 = ring[0]
        walking = s.last is not None and s.last.step_index >= 0
        if s.t - t0 < window - 1e-9 or not walking:
            return math.nan
        return energy - e0

    def snapshot(self) -> History:
        self.rows_since_publish = 0
        n = min(self.count, self.rows)
        order = np.arange(self.count - n, self.count) % self.rows
        return History(
            clock=self.clock[order].copy(),
            columns=HISTORY_COLUMNS,
            values={m: a[order].copy() for m, a in self.values.items()},
        )
