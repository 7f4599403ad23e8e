"""The live loop: it reads intent, ticks the robots, paces to the wall clock and publishes.

Pattern (docs/ARCHITECTURE.md, "Principles"; as in mujoco_playground and pink's gizmo
example): one owner of the simulation.
:class:`LiveLoop` holds one :class:`~pelvic_walk.core.session.Session` per selected method (same
parameters, the method differs) and knows nothing of displays or the web: it reads the
latest :class:`~app.live.intent.Intent` from a callable and hands each
:class:`~pelvic_walk.core.frames.LiveFrame` to a callable. It runs in a thread of a worker
of the pool (:mod:`app.live.pool`: a process, or a thread of the web process); one
iteration is:

1. apply new intent (rebuild the robots on a reset or a change of methods, hand new
   parameters to every walker, re-anchor the clock on pause / speed changes, pushes);
2. tick every robot one control period (or, paused, carry out one single-step request);
3. record a plot row every ``HISTORY_DECIMATION`` ticks;
4. publish a frame at the display rate (always after an intent or a single step);
5. sleep to the wall clock x ``speed`` once a frame is out: the ticks of one display
   interval run back to back, ahead of the wall clock by less than that interval plus a
   tick, then the loop sleeps off its lead, so it wakes once per frame, not once per tick.
   A frame is due after a display interval of wall time or, while ahead, of simulated time.
   When the loop cannot keep up it runs as fast as it can and reports the real-time factor
   it measured.

Why bursts: a thread that sleeps after every 5-ms tick wakes 200 times a second, and a tick
right after a wake costs more CPU (ticks alone, ``time.sleep(0.0025)`` after each: 2.45 ms
of CPU a tick against 1.79-1.90 ms back to back; the cause, cold caches or the virtual CPU's
idle states, is not measured). Per-thread CPU from ``/proc`` on the 2-core machine, ``serve``
with no viewers: one robot 0.61 of a core paced per tick, 0.48 in bursts; three robots
0.51-0.53 each, 0.42-0.47. Under ``loadtest --viewers 20 --robots 3`` (two rounds of 60 s
each): 0.53-0.56 per tick, 0.46-0.53 in bursts. A frame shows the robots at most one display
interval (plus a tick) ahead of the time base, too little to see.

Time base: the intent carries the session's anchor (a session clock at a monotonic wall
time, and the speed), so loops running parts of one session in different processes keep the
same clock: each one sleeps while ahead of it and runs flat out while behind.

Live choices: plans are long (``LIVE_STEPS``). A robot that falls stops its controller and
lies where it fell (its servos hold the last targets while the physics runs on), marked in
its frames (``fell_clock``); a robot whose plan ends stands still the same way, and so does
one whose pelvis strategy failed (``error``: a user's code raised or returned no rate; the
message names their file and line) while the others walk on. The loop never restarts a robot
alone: the session restarts all of its robots together
(:meth:`app.live.session.SessionView.receive`, ``FALL_HOLD_S`` after a fall, or once every
robot finished), so side-by-side robots always compare the same instants. A reset or a
change of methods rebuilds all robots, which start walking together at the intent's
``start_clock``; a loop that builds its robots too late for it (a slow part of a session
split over processes) has them stand by until they are in phase with the session's rhythm.
"""

from __future__ import annotations

import logging
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from app.live.intent import Intent
from controller.footsteps import FootstepPlan
from controller.params import ControllerParams
from controller.strategy import StrategyError
from pelvic_walk.core.frames import (
    HISTORY_DECIMATION,
    ROW_COLUMNS,
    LiveFrame,
    TwoStepEnergy,
    plot_row,
    robot_frame,
)
from pelvic_walk.core.session import RunConfig, Session
from pelvic_walk.core.summary import unsuccessful

log = logging.getLogger(__name__)

LIVE_STEPS = 200  # steps per live plan; the session restarts its robots when they end
RTF_WINDOW_S = 3.0  # [s] of wall time over which the real-time factor is measured
PUBLISH_HZ = 30.0  # frames per second of wall time while running (the display rate)
STEP_UNTIL_MAX_S = 3.0  # [s] a "next lift-off / landing" step gives up after this


def live_params(params: ControllerParams | None = None) -> ControllerParams:
    """The default live parameters: the controller's defaults with a long plan."""
    return (params or ControllerParams()).replace(walk={"n_steps": LIVE_STEPS})


@dataclass
class _Robot:
    """One robot's session plus the live bookkeeping around it (loop only)."""

    method: str
    session: Session
    falls: int = 0  # since the last restart asked for (kept through the session's own)
    walks_completed: int = 0
    last_walk_success: bool | None = None
    error: str | None = None  # its strategy (or controller) failed: it stops, the others go on
    fell_clock: float | None = None  # session clock of its fall
    finished_clock: float | None = None  # session clock at which its plan ended
    waiting_since: float | None = None  # session clock when it began standing by
    ref: tuple[FootstepPlan, float] | None = None  # the plan to keep in phase with, and the
    # session clock at which that plan's time was 0 (a robot built late)
    two_step_energy: TwoStepEnergy = field(default_factory=TwoStepEnergy)

    @property
    def fell(self) -> bool:
        return self.session.fell

    @property
    def waiting(self) -> bool:
        return self.waiting_since is not None

    @property
    def held(self) -> bool:
        """Down after a fall, standing at the end of its plan or stopped by an error: no
        controller runs."""
        return (
            self.fell_clock is not None or self.finished_clock is not None or self.error is not None
        )


@dataclass
class _Rates:
    """Real-time factors over the last RTF_WINDOW_S of wall time."""

    samples: deque[tuple[float, float, float]] = field(default_factory=deque)  # wall, sim, busy

    def add(self, wall: float, sim: float, busy: float) -> None:
        self.samples.append((wall, sim, busy))
        while self.samples and wall - self.samples[0][0] > RTF_WINDOW_S:
            self.samples.popleft()

    def get(self) -> tuple[float | None, float | None]:
        """(simulated / wall, simulated / compute), None until 0.5 s of data."""
        if len(self.samples) < 2:
            return None, None
        (w0, s0, b0), (w1, s1, b1) = self.samples[0], self.samples[-1]
        if w1 - w0 < 0.5:
            return None, None
        return (s1 - s0) / (w1 - w0), ((s1 - s0) / (b1 - b0) if b1 > b0 else None)


class LiveLoop:
    """The robots of one live session, advanced from intent to frames (one thread).

    Args:
        intents: returns the latest intent (called every iteration).
        publish: receives every published frame.
        clock: the wall clock (seconds).
        sleep: the pacing sleep: waits up to the given seconds (returning early when the
            intent changes is welcome).
        idle: waits up to the given seconds while paused; must return early when the intent
            changes (default: ``sleep``).
        publish_hz: frames per second of wall time while running.
    """

    def __init__(
        self,
        intents: Callable[[], Intent],
        publish: Callable[[LiveFrame], None],
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
        idle: Callable[[float], None] | None = None,
        publish_hz: float = PUBLISH_HZ,
    ):
        self._intents = intents
        self._publish_to = publish
        self._clock = clock
        self._sleep = sleep
        self._idle = idle or sleep
        self.publish_interval = 1.0 / publish_hz
        self.robots: dict[str, _Robot] = {}
        self.applied: Intent | None = None
        self.clock = 0.0  # [s] simulated time since the session started (its time base)
        self.steps_done = 0
        self.pushes_done = 0
        self.seq = 0
        self._resets_done = 0
        self._user_resets = 0
        self._ticks = 0
        self._busy = 0.0
        self._rates = _Rates()
        self._rows: dict[str, list[np.ndarray]] = {}
        self._last_publish = -math.inf  # wall time of the last frame
        self._last_publish_clock = -math.inf  # and its session clock
        self._restarted = True
        self._dirty = True  # something to publish even if paused
        self._errors_logged: set[str] = set()  # strategy errors already in the log

    # -- one iteration ---------------------------------------------------------------------
    def iterate(self) -> None:
        """Apply intent, tick (or wait while paused), publish, pace."""
        intent = self._intents()
        if self.applied is None or intent.version != self.applied.version:
            self._apply(intent)
        pending = intent.step_requests - self.steps_done
        if intent.paused and pending <= 0:
            if self._dirty:
                self._publish(intent)
            self._idle(0.05)
            return
        t0 = self._clock()
        if intent.paused:  # one single-step request
            self._single_step(intent)
            self.steps_done += 1
        else:
            self._tick_all(intent)
        self._busy += self._clock() - t0
        now = self._clock()
        if intent.paused:
            self._publish(intent)
            return
        # A frame is due, and the burst of ticks ends with it (step 5), after a display
        # interval of simulated time (x speed) while ahead of the time base, or of wall time
        # while behind. (Wall time alone while ahead ended every other burst early after a long
        # sleep where the interval is not whole ticks: frames alternated 4 and 7 ticks at 30 Hz.)
        due = (
            self.clock - self._last_publish_clock >= self.publish_interval * intent.speed - 1e-9
            if self.ahead(intent) > 0
            else now - self._last_publish >= self.publish_interval
        )
        if due:
            # The factor's samples are taken at the ends of bursts only: a window from a
            # burst's first tick (the loop just woke, least ahead) to a burst's end (most
            # ahead) would read fast by up to a display interval over the window (1.006 where
            # the loop kept 1.000 on average).
            self._rates.add(now, self.clock, self._busy)
            self._publish(intent)
            self._pace(intent)

    def _apply(self, intent: Intent) -> None:
        old = self.applied
        dt = intent.params.control_dt
        if old is None:  # join the session's time base (a part may start late)
            self.clock = round(max(self._target(intent), 0.0) / dt) * dt
            # what was asked before this loop existed was carried out by the others (a part
            # added later would replay every single step and push of the session's past)
            self.steps_done = intent.step_requests
            self.pushes_done = intent.pushes[-1].number if intent.pushes else 0
        rebuild = (
            old is None
            or intent.methods != old.methods
            or [r.strategy for r in intent.robots] != [r.strategy for r in old.robots]
            or (intent.reset_requests != self._resets_done)
        )
        if rebuild and intent.paused and self.clock < intent.start_clock - dt / 2:
            # Paused, the time base stands where it was last anchored (the last resume), while
            # single steps moved the session on: a loop built now (a robot added while paused,
            # a worker replaced) would join there, behind the others. Its merged frames would
            # take the session clock back, the catch-up would move the base back with it, and
            # the other loops would wait out the difference, their robots standing at t = 0.
            # Rebuilt robots stand still until start_clock (the session's present) anyway:
            # go there.
            self.clock = round(intent.start_clock / dt) * dt
        if rebuild:
            user_reset = (intent.reset_requests - intent.auto_restarts) != self._user_resets
            before = self.robots
            self.robots = {m: self._robot(m, intent.params_of(m)) for m in intent.methods}
            for m, robot in self.robots.items():  # the counts of the session go on
                if m in before:
                    old_robot = before[m]
                    # falls count from the last restart someone asked for (a lesson's too):
                    # the session's own restarts after a fall keep counting
                    robot.falls = 0 if user_reset else old_robot.falls
                    robot.walks_completed = old_robot.walks_completed
                    robot.last_walk_success = old_robot.last_walk_success
            self._resets_done = intent.reset_requests
            self._user_resets = intent.reset_requests - intent.auto_restarts
            late = self.clock > intent.start_clock + intent.params.control_dt / 2
            for robot in self.robots.values():
                # The robots of every loop of the session start at start_clock; one built too
                # late for it (a slow part) joins them in phase instead.
                robot.ref = (robot.session.plan, intent.start_clock)
                robot.waiting_since = self.clock if late else None
            # plots and kept frames start anew for other robots or a restart asked for; a
            # restart the session made itself (after a fall) keeps them: the fall can be
            # scrubbed back to and its plot rows stay
            if old is None or intent.methods != old.methods or user_reset:
                self._rows = {}
                self._restarted = True
        elif old is not None and (intent.params, intent.robots) != (old.params, old.robots):
            for robot in self.robots.values():  # each robot's own, from the next tick
                new = intent.params_of(robot.method)
                if new != old.params_of(robot.method):
                    robot.session.walker.set_params(new)
        # a pause or a new speed starts a new measurement; a moved time base (a catch-up after
        # the loop fell behind) does not: the factor must show the lag, not hide it
        if old is None or intent.paused != old.paused or intent.speed != old.speed:
            self._rates = _Rates()
        if not intent.paused:
            self.steps_done = intent.step_requests  # resuming drops pending single steps
        for push in intent.pushes:
            if push.number > self.pushes_done:
                pushed = self.robots.get(push.method)
                if pushed is not None and not pushed.fell:
                    pushed.session.push(np.asarray(push.force), push.duration)
                self.pushes_done = push.number
        self.applied = intent
        self._dirty = True

    # -- ticking -----------------------------------------------------------------------------
    def _robot(self, method: str, params: ControllerParams) -> _Robot:
        """Robot ``method`` (its key: a label) with its own parameters (their ``method``: its
        strategy)."""
        cfg = RunConfig(params=params)
        # no series: the displays ask for measurements and kappa when they draw a frame
        return _Robot(method, Session(cfg, record=False))

    def _tick_all(self, intent: Intent) -> None:
        """One control period for every robot; a plot row every HISTORY_DECIMATION ticks.
        Robots rebuilt by a reset stand still until the session clock reaches
        ``intent.start_clock``."""
        if self.clock + 1e-9 >= intent.start_clock:  # before it, the robots stand still
            for robot in self.robots.values():
                self._tick_robot(robot, intent.params)
        self.clock += intent.params.control_dt
        self._ticks += 1
        if self._ticks % HISTORY_DECIMATION == 0 or intent.paused:
            self._record_rows()

    def _single_step(self, intent: Intent) -> None:
        """Advance to the next tick, lift-off or landing of the first walking robot."""
        n_max = int(STEP_UNTIL_MAX_S / intent.params.control_dt)
        ref = self._reference()
        if ref is None and all(r.held for r in self.robots.values()):
            self._tick_all(intent)  # every robot is down or done: one period of physics
            return
        if ref is None or ref.session.last is None:
            # Nobody walks yet: through the start delay (or a wait to start in phase) the
            # robots stand still, and a step that shows nothing would puzzle a student. Tick
            # until one moves; that is the tick asked for, or the start of the search.
            if not self._until_moving(intent, n_max) or intent.step_until == "tick":
                return
            ref = self._reference()
            if ref is None:
                return
        elif intent.step_until == "tick":
            self._tick_all(intent)
            return
        last = ref.session.last
        was_ssp, step = (last.in_ssp, last.step_index) if last is not None else (False, -1)
        for _ in range(n_max):
            self._tick_all(intent)
            out = ref.session.last
            if ref.fell:
                return
            if out is None:  # before the session's start the robots stand still
                continue
            if intent.step_until == "liftoff" and out.in_ssp and not was_ssp:
                return
            if (
                intent.step_until == "landing"
                and was_ssp
                and (not out.in_ssp or out.step_index != step)
            ):
                return
            was_ssp, step = out.in_ssp, out.step_index

    def _until_moving(self, intent: Intent, n_max: int) -> bool:
        """Tick until some robot's time advances (at most ``n_max`` ticks); True if one did."""
        before = [r.session.t for r in self.robots.values()]
        for _ in range(n_max):
            self._tick_all(intent)
            if [r.session.t for r in self.robots.values()] != before:
                return True
        return False

    def _tick_robot(self, robot: _Robot, params: ControllerParams) -> None:
        s = robot.session
        if robot.waiting:
            self._start_if_in_phase(robot)
            return
        if not robot.held:
            if robot.fell:
                robot.fell_clock = self.clock
                robot.falls += 1
                robot.last_walk_success = False
            elif s.walker.finished:
                robot.finished_clock = self.clock
                robot.walks_completed += 1
                robot.last_walk_success = not unsuccessful(s)
        if robot.held:
            self._hold(robot)
            return
        try:
            s.tick()
        except StrategyError as exc:  # a user's mistake, not the server's: one line, once
            if str(exc) not in self._errors_logged:
                self._errors_logged.add(str(exc))
                log.warning("robot %s stopped: %s", robot.method, exc)
            robot.error = str(exc)
            robot.last_walk_success = False
            self._hold(robot)  # this period's physics, the servos on the last targets
            return
        except Exception as exc:  # noqa: BLE001 - one robot's failure must not stop the loop
            log.exception("robot %s: controller tick failed", robot.method)
            robot.error = f"{type(exc).__name__}: {exc}"
            robot.last_walk_success = False
            self._hold(robot)
            return
        # marked at once: a frame never shows a fall without its time, nor a finished walk
        # uncounted (the session restarts every robot from the frame that shows them all
        # finished, and the restart can be applied before this robot's next tick)
        if robot.fell:
            robot.fell_clock = self.clock + params.control_dt
            robot.falls += 1
            robot.last_walk_success = False
        elif s.walker.finished:
            robot.finished_clock = self.clock + params.control_dt
            robot.walks_completed += 1
            robot.last_walk_success = not unsuccessful(s)

    @staticmethod
    def _hold(robot: _Robot) -> None:
        """One control period of physics with the servos holding the last targets: a fallen
        robot lies where it fell, a finished one stands (until the session restarts them)."""
        s = robot.session
        target = s.last.q_target if s.last is not None else s.world.q_joints()
        s.world.step(target)

    def _reference(self) -> _Robot | None:
        """The first robot that walks (not held, not standing by)."""
        return next((r for r in self.robots.values() if not r.held and not r.waiting), None)

    def _start_if_in_phase(self, robot: _Robot) -> None:
        """Start a waiting robot when the reference is where a fresh plan would be at t = 0.

        A fresh plan stands ``t_start`` and then steps with the left foot; it joins when the
        reference robot is ``t_start`` before the start of one of its own left steps (same
        timing from then on; past the end of its walk the rhythm is extended), or alone, or
        after two step cycles of waiting at most.
        """
        other = self._reference()
        plan = robot.session.plan
        if other is not None:  # a robot of this loop that walks
            ref_plan, ref_t = other.session.plan, other.session.t
        elif robot.ref is not None:  # its own previous plan, which the others follow too
            ref_plan, ref_t = robot.ref[0], self.clock - robot.ref[1]
        else:
            robot.waiting_since = None
            return
        waited = self.clock - (robot.waiting_since or self.clock)
        start = waited > 2 * 2 * plan.walk.step_time + plan.t_start
        if not start:
            dt = robot.session.params.control_dt
            n = ref_plan.n_walking_steps
            left = ref_plan.step_start[:n][ref_plan.swing_side[:n] == plan.swing_side[0]]
            if len(left):
                # Past the end of the reference's walk its left steps go on in the same rhythm
                # (robots that finished a walk restart together, one cycle later).
                period = 2 * ref_plan.walk.step_time
                k = max(0, math.ceil((ref_t + plan.t_start - left[-1]) / period))
                left = np.append(left, left[-1] + period * np.arange(1, k + 2))
                lead = left - plan.t_start - ref_t
                start = bool(np.any((lead > -dt / 2) & (lead <= dt / 2)))
        if start:
            robot.waiting_since = None

    # -- rows, frames, pacing -----------------------------------------------------------------
    def _record_rows(self) -> None:
        for method, robot in self.robots.items():
            row = plot_row(robot.session, self.clock, robot.two_step_energy(robot.session))
            if row is not None:  # None: not started yet (or standing by), a gap
                self._rows.setdefault(method, []).append(row)

    def _publish(self, intent: Intent) -> None:
        rtf, compute = self._rates.get()
        if intent.paused:
            rtf = compute = None
        rows = {m: np.array(r).reshape(-1, len(ROW_COLUMNS)) for m, r in self._rows.items()}
        self._rows = {}
        self.seq += 1
        frame = LiveFrame(
            seq=self.seq,
            clock=self.clock,
            wall=self._clock(),
            paused=intent.paused,
            speed=intent.speed,
            realtime_factor=rtf,
            compute_realtime_factor=compute,
            intent_version=intent.version,
            steps_done=self.steps_done,
            pushes_done=self.pushes_done,
            robots=tuple(
                robot_frame(
                    r.session,
                    slot,
                    self.clock,
                    r.method,
                    r.falls,
                    r.walks_completed,
                    r.last_walk_success,
                    r.waiting,
                    r.error,
                    r.fell_clock,
                )
                for slot, r in enumerate(self.robots.values())
            ),
            rows=rows,
            restarted=self._restarted,
        )
        self._restarted = self._dirty = False
        self._last_publish, self._last_publish_clock = self._clock(), self.clock
        self._publish_to(frame)

    def _target(self, intent: Intent) -> float:
        """The session clock now on the intent's time base [s]."""
        wall0, clock0 = intent.anchor
        if intent.paused:
            return clock0
        return clock0 + (self._clock() - wall0) * intent.speed

    def ahead(self, intent: Intent) -> float:
        """[s] of wall time the loop leads its time base by (< 0: behind)."""
        return (self.clock - self._target(intent)) / intent.speed

    def _pace(self, intent: Intent) -> None:
        """Sleep while ahead of the time base; while behind, run on without sleeping."""
        ahead = self.ahead(intent)
        if ahead > 0:
            self._sleep(ahead)
