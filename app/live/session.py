"""A live session as its users see it: intent in, frames out, the past kept for scrubbing.

:class:`SessionView` is the display side of a session whose loops run in the worker pool
(:class:`~app.live.pool.RemoteSession`, the one live mode): it keeps the latest frame, the
plot rows (:class:`PlotHistory`) and the last seconds of frames (:class:`FrameStore`).
Callers (web handlers, GUI callbacks, tests) only write intent through its methods, each of
which returns the new :class:`~app.live.intent.Intent`: a ticket that
:meth:`SessionView.wait_applied` waits on (the loops report in every frame which intent they
have read, how many single steps and which pushes they have carried out).

While paused, :meth:`SessionView.seek` shows a kept instant: :meth:`SessionView.shown_frame` is then
the kept frame nearest to it (scene, horizon inspector, plot cursor); resuming returns to the
present. :meth:`SessionView.playback` is the one account of the playback state (paused, speed,
the instant shown, the timeline's range) that the panel, ``GET /api/state`` and
``GET /api/sessions`` all read.

Failures that teach: a robot that falls lies where it fell, marked, for ``FALL_HOLD_S`` of
session time (longer while paused: the hold ends only while running), and then the session
restarts all of its robots together (:meth:`SessionView.receive`); so does the end of the
plans. The loops never restart a robot alone.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from app.live.history import FrameStore, PlotHistory
from app.live.intent import (
    DEFAULT_METHODS,
    PUSHES_KEPT,
    STEP_UNTIL,
    Intent,
    IntentBox,
    Push,
    check_methods,
    check_push,
    check_speed,
)
from app.live.loop import live_params
from controller.params import ControllerParams
from pelvic_walk.core import robots as robots_
from pelvic_walk.core.frames import LiveFrame
from pelvic_walk.core.robots import Robot

log = logging.getLogger(__name__)
KEEP_S = 40.0  # [s] of frames kept for scrubbing and recording (at least 30 s)
PLOT_HISTORY_S = 60.0  # [s] of plot rows kept
# [s] of session time a fallen robot lies where it fell, marked, before the session restarts
# every robot together. The fall is detected at 30 deg of torso tilt; the body reaches the
# floor about a second later; the rest is time to read the marker ("fell at t = ...") and see
# the other robots walk on (two to three steps at 1.2 s). Longer, and a lesson whose robot
# falls every few seconds (0.42 m) would be mostly waiting.
FALL_HOLD_S = 4.0


@dataclass(frozen=True)
class Playback:
    """The playback state of a session, read in one place (:meth:`SessionView.playback`)."""

    paused: bool  # as asked (the loop applies it within a frame)
    speed: float  # [x real time]
    clock: float | None  # [s] session clock of the instant shown (None before any frame)
    shown_t: float | None  # [s] the sought instant while paused, None when showing the present
    present: float | None  # [s] session clock of the newest frame
    kept: tuple[float, float] | None  # [s] oldest and newest kept instant: the timeline's range
    realtime_factor: float | None  # simulated / wall time lately (None while paused)
    compute_realtime_factor: float | None

    def describe(self) -> str:
        """One line for people: "Paused at t = 12.30 s (of 20.00 s kept)", "Running at 1x"."""
        if self.paused:
            at = f" at t = {self.clock:.2f} s" if self.clock is not None else ""
            if self.shown_t is not None and self.present is not None:
                at += f" (replaying; the present is {self.present:.2f} s)"
            return f"Paused{at}"
        rtf = self.realtime_factor
        return f"Running at {self.speed:g}x, real-time factor " + (
            f"{rtf:.2f}" if rtf is not None else "-"
        )


def initial_intent(
    params: ControllerParams | None = None,
    methods: Sequence[str] = DEFAULT_METHODS,
    speed: float = 1.0,
    robots: Sequence[Robot] | None = None,
) -> Intent:
    """A session's first intent (validated); its time base starts when the session opens.
    ``robots`` (strategies with settings of their own) replace ``methods`` when given."""
    params = (params or live_params()).validated()
    shown = robots_.check_all(robots) if robots else robots_.of_methods(check_methods(methods))
    for r in shown:
        robots_.params_of(params, r)  # each robot's settings in range over these params
    return Intent(
        params=params,
        robots=shown,
        speed=check_speed(speed),
        anchor=(time.monotonic(), 0.0),
    )


# [s] a loop this far behind its time base: the base moves (the loops of the other parts,
# ahead of it, wait: a session's robots stay this close). A smaller lag the loop makes up by
# running flat out for a moment, so a busy second costs no simulated time: at 0.3 s, 20
# viewers on 2 cores moved the base every ~40 s and a 3-s real-time factor read 0.88.
CATCH_UP_S = 1.0


class SessionView:
    """The display side of one live session (any thread).

    Args:
        intent: the first intent (:func:`initial_intent`).
        keep_s: seconds of frames kept for scrubbing and recording.
    """

    def __init__(
        self,
        intent: Intent,
        keep_s: float = KEEP_S,
        wall: Callable[[], float] = time.monotonic,
        start_delay: float = 0.0,
    ):
        self._wall = wall  # the monotonic wall clock of the time base (shared by processes)
        self.start_delay = (
            start_delay  # [s of wall time] robots (re)built start this much later, so that
        )
        # loops in other processes, which take a moment to build theirs, start with them, and
        # a loop a frame ahead of the time base is not already past the start
        self._auto_version = -1  # the intent of the last restart the session made itself
        intent = dataclasses.replace(
            intent, anchor=(wall(), 0.0), start_clock=start_delay * intent.speed
        )
        self._box = IntentBox(intent, on_change=self._intent_changed)
        self._last_catch_up = -math.inf
        self._changed = threading.Condition()  # notified when a frame arrives
        self._frame: LiveFrame | None = None
        self._shown: float | None = None  # session clock shown while paused (seek)
        self.history = PlotHistory(PLOT_HISTORY_S)
        self.frames = FrameStore(keep_s)
        self._closed = threading.Event()
        self.error: str | None = None  # set if the loop itself died

    def _intent_changed(self) -> None:
        """Called after every intent change (the runner forwards or wakes the loop)."""

    @property
    def running(self) -> bool:
        raise NotImplementedError

    # -- intent (any thread); each returns the new intent, a ticket for wait_applied --------
    @property
    def intent(self) -> Intent:
        return self._box.get()

    def set_params(self, params: ControllerParams) -> Intent:
        params = params.validated()
        return self._box.modify(lambda _cur: {"params": params})

    def update_params(self, target: str | None = None, **groups) -> Intent:
        """Partial change, e.g. ``update_params(walk={"step_length": 0.3})``; ValueError.

        ``target`` None: every robot (the shared value, and no robot keeps a setting of its
        own for these parameters); a robot's key: that robot's own settings only."""

        def change(cur: Intent) -> dict:
            values = {
                f"{g}.{k}": v
                for g, d in groups.items()
                if isinstance(d, dict)
                for k, v in d.items()
            }
            if target is None:
                params = cur.params.replace(**groups)
                stored = {robots_.stored_name(k) for k in values}
                shown = tuple(
                    dataclasses.replace(
                        r, overrides=tuple((k, v) for k, v in r.overrides if k not in stored)
                    )
                    for r in cur.robots
                )
                return {"params": params, "robots": shown}
            robot = cur.robot(target)
            new = robots_.with_settings(robot, values, cur.params)
            return {"robots": tuple(new if r.key == target else r for r in cur.robots)}

        return self._box.modify(change)

    def set_methods(self, methods: Sequence[str]) -> Intent:
        """Show one robot per strategy (no settings of their own); all are rebuilt and start
        together."""
        return self.set_robots(robots_.of_methods(check_methods(methods)))

    def set_robots(self, robots: Sequence[Robot]) -> Intent:
        """Show these robots (strategies with their own settings and labels); all are rebuilt
        and start together."""
        robots = robots_.check_all(robots)
        for r in robots:
            robots_.params_of(self.intent.params, r)
        if robots == self.intent.robots:
            return self.intent
        newest = self._newest_clock()  # read before the intent's lock (lock order)
        return self._box.modify(lambda cur: {"robots": robots, **self._restart_at(cur, newest)})

    def set_speed(self, speed: float) -> Intent:
        speed = check_speed(speed)
        return self._box.modify(lambda cur: {"speed": speed, "anchor": self._anchor_now(cur)})

    def pause(self) -> Intent:
        return self._box.modify(lambda _cur: {"paused": True})

    def resume(self) -> Intent:
        """Run again from the present: the time base restarts at the clock now."""
        self._shown = None
        return self._box.modify(lambda cur: {"paused": False, "anchor": self._anchor_now(cur)})

    # -- the time base ---------------------------------------------------------------------
    def clock_now(self, intent: Intent | None = None) -> float:
        """The session clock now [s]: the latest frame's while paused, else the time base's."""
        intent = intent or self.intent
        frame = self.frame()
        if intent.paused:
            return frame.clock if frame is not None else intent.anchor[1]
        return intent.anchor[1] + (self._wall() - intent.anchor[0]) * intent.speed

    def _anchor_now(self, cur: Intent) -> tuple[float, float]:
        frame = self.frame()
        clock = frame.clock if cur.paused and frame is not None else self.clock_now(cur)
        return (self._wall(), clock)

    def _restart_at(self, cur: Intent, newest: float | None) -> dict:
        """Fields that rebuild every robot, to start together ``start_delay`` from now, and
        never before a loop's present: a loop already past the start would have its robots
        stand by for a whole step cycle to keep the rhythm, two steps behind the others."""
        delay = 0.0 if cur.paused else self.start_delay * cur.speed  # wall s -> session s
        now = self.clock_now(cur)
        return {
            "reset_requests": cur.reset_requests + 1,
            "start_clock": max(now, newest if newest is not None else now) + delay,
        }

    def _newest_clock(self) -> float | None:
        """[s] the newest session clock a loop of the session has reached (published). Not
        called under the intent's lock: a session's frame merger takes its own lock first."""
        frame = self.frame()
        return frame.clock if frame is not None else None

    def step(self, until: str = "tick") -> Intent:
        """Pause (if running) and advance one tick, or to the next lift-off or landing."""
        if until not in STEP_UNTIL:
            raise ValueError(f"step until must be one of {', '.join(STEP_UNTIL)}, got {until!r}")
        self._shown = None
        return self._box.modify(
            lambda cur: {
                "paused": True,
                "step_requests": cur.step_requests + 1,
                "step_until": until,
            }
        )

    def reset(self) -> Intent:
        """Restart every robot from standing (t = 0), all together."""
        self._shown = None
        newest = self._newest_clock()
        return self._box.modify(lambda cur: self._restart_at(cur, newest))

    def _restart_when_due(self, frame: LiveFrame) -> None:
        """The session's own restart: all robots together, ``FALL_HOLD_S`` after a robot fell
        (not while paused: a paused fall stays shown until the session runs again) or once
        every robot has walked its whole plan. Runs where the frames arrive, so a session
        whose robots run in several processes restarts them all at once."""
        intent = self.intent
        if intent.paused or frame.paused or not frame.robots:
            return
        if frame.intent_version < self._auto_version:  # the last one is not carried out yet
            return
        fallen = [
            r.fell_clock
            for r in frame.robots
            if r.fell and r.fell_clock is not None and not r.waiting
        ]
        # a robot stopped by its strategy's error neither restarts the others (its error would
        # come back every few seconds) nor holds them back when they finish
        going = [r for r in frame.robots if r.error is None]
        due = any(frame.clock >= c + FALL_HOLD_S - 1e-9 for c in fallen) or bool(
            going and all(r.finished for r in going)
        )
        if not due:
            return

        newest = self._newest_clock()

        def restart(cur: Intent) -> dict:
            if cur.paused or cur.reset_requests != intent.reset_requests:
                return {}  # paused meanwhile, or restarted by someone: nothing to add
            return {**self._restart_at(cur, newest), "auto_restarts": cur.auto_restarts + 1}

        self._auto_version = self._box.modify(restart).version

    def push(self, method: str, force: Sequence[float], duration: float) -> Intent:
        """Push one robot's torso horizontally; ValueError on an unknown robot or size."""

        def change(cur: Intent) -> dict:
            f, d = check_push(method, force, duration, cur.methods)
            number = (cur.pushes[-1].number if cur.pushes else 0) + 1
            return {"pushes": (*cur.pushes, Push(number, method, f, d))[-PUSHES_KEPT:]}

        return self._box.modify(change)

    def seek(self, clock: float) -> LiveFrame:
        """While paused, show the kept instant nearest to ``clock`` [s]; ValueError otherwise."""
        if not self.intent.paused:
            raise ValueError("pause first: seeking shows a kept instant of a paused session")
        if not math.isfinite(clock):
            raise ValueError(f"t must be finite, got {clock}")
        frame = self.frames.nearest(clock)
        if frame is None:
            raise ValueError("nothing kept yet")
        self._shown = frame.clock
        return frame

    # -- frames (any thread) ---------------------------------------------------------------
    def frame(self) -> LiveFrame | None:
        """The latest published frame (immutable)."""
        with self._changed:
            return self._frame

    def shown_frame(self) -> LiveFrame | None:
        """The frame the displays show: the sought one while paused, else the latest."""
        shown = self._shown
        if shown is not None and self.intent.paused:
            kept = self.frames.nearest(shown)
            if kept is not None:
                return kept
        return self.frame()

    @property
    def shown_clock(self) -> float | None:
        """The session clock of the instant shown, or None when showing the present."""
        return self._shown if self.intent.paused else None

    def playback(self) -> Playback:
        """Paused, speed, the instant shown and the timeline's range, from one place: the
        intent says whether the session is paused and how fast it runs (a frame shown from
        the past was made while running, so its own ``paused`` says nothing of now), the
        kept frames give the range."""
        intent = self.intent
        latest, shown = self.frame(), self.shown_frame()
        sought = self._shown if intent.paused else None
        return Playback(
            paused=intent.paused,
            speed=intent.speed,
            clock=shown.clock if shown is not None else None,
            shown_t=shown.clock if sought is not None and shown is not None else None,
            present=latest.clock if latest is not None else None,
            kept=self.frames.span(),
            realtime_factor=None if intent.paused or latest is None else latest.realtime_factor,
            compute_realtime_factor=(
                None if intent.paused or latest is None else latest.compute_realtime_factor
            ),
        )

    def wait_frame(self, after_seq: int = -1, timeout: float = 5.0) -> LiveFrame | None:
        """Block until a frame newer than ``after_seq`` is published; None on timeout."""
        return self._wait(lambda f: f.seq > after_seq, timeout)

    def wait_applied(self, ticket: Intent | int, timeout: float = 5.0) -> LiveFrame | None:
        """Block until a frame shows ``ticket`` carried out (its version read, its single
        steps and pushes done); None on timeout. An int is taken as a version."""
        if isinstance(ticket, int):
            ticket = Intent(params=self.intent.params, version=ticket)
        last_push = ticket.pushes[-1].number if ticket.pushes else 0
        return self._wait(
            lambda f: (
                f.intent_version >= ticket.version
                and (f.steps_done >= ticket.step_requests or not f.paused)
                and f.pushes_done >= last_push
            ),
            timeout,
        )

    def _wait(self, ok: Callable[[LiveFrame], bool], timeout: float) -> LiveFrame | None:
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                f = self._frame
                if f is not None and ok(f):
                    return f
                left = deadline - time.monotonic()
                if left <= 0 or self._closed.is_set() or not self.running:
                    return None
                self._changed.wait(left)

    def receive(self, frame: LiveFrame) -> None:
        """A frame from the loop: keep it and its rows, and wake the waiters."""
        if frame.restarted:
            self.history.clear()
            self.frames.clear()
        self.history.extend(frame.rows)
        self.frames.add(frame)
        with self._changed:
            self._frame = frame
            self._changed.notify_all()
        self._catch_up(frame)
        self._restart_when_due(frame)

    def _catch_up(self, frame: LiveFrame) -> None:
        """Move the time base when the loops fell behind it by more than CATCH_UP_S (e.g.
        the machine was busy): otherwise they would rush to catch up.

        Behind is judged where the frame was made (its ``wall`` time against the time base
        it ran on), not when it arrived here: a frame delivered late by a busy web process
        must not move the base back and make punctual loops wait."""
        intent = self.intent
        if intent.paused or frame.paused or frame.wall <= 0.0:
            return
        if frame.intent_version < intent.version:  # made on an older time base
            return
        now = self._wall()
        if now - self._last_catch_up < CATCH_UP_S:
            return
        wall0, clock0 = intent.anchor
        target = clock0 + (frame.wall - wall0) * intent.speed
        if target - frame.clock > CATCH_UP_S:
            self._last_catch_up = now
            anchor = intent.anchor
            self._box.modify(
                lambda cur: (
                    {"anchor": (frame.wall, frame.clock)}
                    if not cur.paused and cur.anchor == anchor
                    else {}
                )
            )
