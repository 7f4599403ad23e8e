"""A worker: it runs live sessions and sends their frames to the web process.

The web process (``app.live.pool``) starts workers through its engine (``app.live.engines``: a
process started with ``spawn``, or a thread of the web process) and talks to each over two pipes
(or queues standing in for them): commands in (open a part of a session with its first intent, a
new intent, close, stop) and frames out. Each part runs its :class:`~app.live.loop.LiveLoop` in
a thread of the worker, paced to the session's time base; the worker holds no display or web
object.

Frames cross as one pickled message each (a few kB: plain arrays), sent by a thread of their
own (:class:`Outbox`) so that a busy web process never slows the simulation (in a thread of
the web process they go straight into the queue, which never blocks). A robot's
footstep plan changes only on a replan or a restart, so it is sent once and then referred to
by :class:`FrameCodec` (the receiver fills it back in).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
import pickle
import signal
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from app.live.intent import Intent
from app.live.loop import LiveLoop
from controller import strategy
from pelvic_walk.core.frames import LiveFrame

log = logging.getLogger(__name__)


class FrameCodec:
    """Strips plans already sent from frames (sender) and restores them (receiver)."""

    def __init__(self) -> None:
        self._plans: dict[tuple[str, str], Any] = {}

    def encode(self, sid: str, frame: LiveFrame) -> LiveFrame:
        robots = []
        for r in frame.robots:
            key = (sid, r.method)
            if self._plans.get(key) is r.plan:
                r = dataclasses.replace(r, plan=cast(Any, None))  # decode() restores it
            else:
                self._plans[key] = r.plan
            robots.append(r)
        return dataclasses.replace(frame, robots=tuple(robots))

    def decode(self, sid: str, frame: LiveFrame) -> LiveFrame:
        robots = []
        for r in frame.robots:
            key = (sid, r.method)
            if r.plan is None:
                r = dataclasses.replace(r, plan=self._plans[key])
            else:
                self._plans[key] = r.plan
            robots.append(r)
        return dataclasses.replace(frame, robots=tuple(robots))

    def forget(self, sid: str) -> None:
        for key in [k for k in self._plans if k[0] == sid]:
            del self._plans[key]


@dataclass
class InProcess:
    """A worker run by a thread of the web process (``app.live.engines.InProcessEngine``):
    the loops' wall clock (a ``VirtualClock`` too: ``enter()``, ``wait(seconds, wake,
    token)``, ``leave(token)``), and the parts it hosts, which the engine reads (their robots)."""

    clock: Callable[[], float] = time.monotonic
    virtual: Any = None
    hosted: dict[str, _Hosted] = field(default_factory=dict)


class _Hosted:
    """One session in this worker: its latest intent and the thread running its loop."""

    def __init__(
        self,
        sid: str,
        intent: Intent,
        send,
        publish_hz: float,
        clock: Callable[[], float] = time.monotonic,
        virtual: Any = None,
    ):
        self.sid = sid
        self._intent = intent
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._virtual = virtual  # a VirtualClock, or None: the real one
        # counted from now: the clock waits for its robots to be built
        self._token = virtual.enter() if virtual is not None else 0
        self.loop = LiveLoop(
            lambda: self._intent,
            lambda f: send(("frame", sid, f)),
            clock=clock,
            sleep=self._wait,
            idle=self._idle if virtual is not None else None,
            publish_hz=publish_hz,
        )
        self._send = send
        self.thread = threading.Thread(target=self._run, name=f"session-{sid}", daemon=True)

    def set_intent(self, intent: Intent) -> None:
        if intent.version >= self._intent.version:  # messages may overtake each other
            self._intent = intent
            self._wake.set()

    def stop(self) -> None:
        self._stop.set()
        self._wake.set()

    def _wait(self, seconds: float) -> None:
        if self._virtual is not None:
            self._virtual.wait(seconds, self._wake, self._token)
        else:
            self._wake.wait(seconds)
        self._wake.clear()

    def _idle(self, _seconds: float) -> None:
        """Paused on a virtual clock: wait for a new intent, without moving the clock."""
        self._wait(math.inf)

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                self.loop.iterate()
        except Exception as exc:  # noqa: BLE001 - reported to the web process
            self._send(
                ("error", self.sid, f"{type(exc).__name__}: {exc}\n{traceback.format_exc(limit=5)}")
            )
        finally:
            if self._virtual is not None:
                self._virtual.leave(self._token)


class Outbox:
    """Frames waiting for the pipe, one slot per part: a loop never waits for the web process.

    When the web process reads slower than a part publishes (it is busy sending the scene to
    many viewers), a part's unsent frame is replaced by its newer one, the plot rows of both
    kept, so the simulation runs on at real time and only the display rate drops.
    """

    def __init__(self, send_bytes) -> None:
        self._send_bytes = send_bytes
        self._cond = threading.Condition()
        self._frames: dict[str, LiveFrame] = {}
        self._other: list[tuple] = []  # messages that are never dropped (errors, ready)
        self.codec = FrameCodec()
        self.dropped = 0

    def put_frame(self, pid: str, frame: LiveFrame) -> None:
        with self._cond:
            old = self._frames.get(pid)
            if old is not None:  # unsent: keep its rows, show the newer state
                self.dropped += 1
                rows = {
                    m: np.concatenate([old.rows[m], r]) if m in old.rows else r
                    for m, r in frame.rows.items()
                }
                frame = dataclasses.replace(
                    frame, rows={**old.rows, **rows}, restarted=old.restarted or frame.restarted
                )
            self._frames[pid] = frame
            self._cond.notify()

    def put(self, message: tuple) -> None:
        with self._cond:
            self._other.append(message)
            self._cond.notify()

    def forget(self, pid: str) -> None:
        with self._cond:
            self._frames.pop(pid, None)
            self.codec.forget(pid)

    def run(self) -> None:
        """The sender thread: pickle and send whatever waits, oldest kind first."""
        while True:
            with self._cond:
                while not self._frames and not self._other:
                    self._cond.wait()
                other, self._other = self._other, []
                frames, self._frames = self._frames, {}
                batch = other + [
                    ("frame", pid, self.codec.encode(pid, f)) for pid, f in frames.items()
                ]
            for message in batch:
                try:
                    self._send_bytes(pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL))
                except (BrokenPipeError, OSError):
                    os._exit(0)  # the web process is gone


def worker_main(
    commands,
    frames,
    publish_hz: float,
    strategies: tuple[str, ...] = (),
    host: InProcess | None = None,
    clock: Callable[[], float] = time.monotonic,
    own_signals: bool = True,
) -> None:
    """Entry point of a worker: serve commands until told to stop or orphaned. ``commands``
    and ``frames``: the ends of two pipes (``recv``, ``send_bytes``), or of two queues.
    ``strategies``: the files of a user's strategies the web process loaded (``serve
    --strategy``), loaded here too so the robots' names mean the same classes. ``host``: run
    in a thread of the web process (its strategies loaded, its signals its own), whose queue
    never blocks a loop: frames go straight to it, none dropped, with its clock. ``clock``:
    the sessions' wall clock elsewhere (a Ray actor's: ``time.time``, shared by the hosts);
    ``own_signals``: a process of its own, whose signals it sets (not a Ray actor's thread)."""
    host_clock, virtual = clock, None
    lock = threading.Lock()  # in a thread of the web process: the loops' threads send in turn
    if host is None:
        logging.basicConfig(level=logging.WARNING)
        strategy.load_files(strategies)
        # The web process stops its workers (Ctrl-C reaches the whole process group): ignore
        # the signals; a worker also ends when the web process's pipe closes.
        if own_signals:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            signal.signal(signal.SIGTERM, signal.SIG_IGN)
        outbox = Outbox(frames.send_bytes)
        threading.Thread(target=outbox.run, name="outbox", daemon=True).start()
        hosted: dict[str, _Hosted] = {}
    else:
        outbox = Outbox(frames.send_bytes)  # (its codec; no thread: sent at once)
        host_clock, virtual, hosted = host.clock, host.virtual, host.hosted

    def send(message: tuple) -> None:
        kind, pid, payload = message
        if host is not None:
            with lock:
                if kind == "frame":
                    message = ("frame", pid, outbox.codec.encode(pid, payload))
                frames.send_bytes(pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL))
        elif kind == "frame":
            outbox.put_frame(pid, payload)
        else:
            outbox.put(message)

    send(("ready", "", os.getpid()))
    while True:
        try:
            kind, pid, payload = commands.recv()
        except (EOFError, OSError):
            break  # the web process is gone
        if kind == "open":
            (intent,) = payload
            hosted[pid] = _Hosted(pid, intent, send, publish_hz, host_clock, virtual)
            hosted[pid].thread.start()
        elif kind == "intent" and pid in hosted:
            hosted[pid].set_intent(payload)
        elif kind == "close" and pid in hosted:
            hosted.pop(pid).stop()
            if host is None:
                outbox.forget(pid)
            else:
                with lock:
                    outbox.codec.forget(pid)
        elif kind == "stop":
            break
    for h in hosted.values():
        h.stop()
    for h in hosted.values():
        h.thread.join(2.0)
