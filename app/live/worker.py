"""A worker process: it runs live sessions and sends their frames to the web process.

The web process (``app.live.pool``) starts workers with ``spawn`` and talks to each over two
pipes: commands in (open a session with its first intent, a new intent, close, stop) and
frames out. Each session runs its :class:`~app.live.loop.LiveLoop` in a thread of the worker,
paced to real time on its own; the worker holds no display or web object.

Frames cross as one pickled message each (a few kB: plain arrays). A robot's footstep plan
changes only on a replan or a restart, so it is sent once and then referred to by
:class:`FrameCodec` (the receiver fills it back in).
"""

from __future__ import annotations

import dataclasses
import logging
import os
import pickle
import threading
import traceback
from multiprocessing.connection import Connection
from typing import Any

from app.live.frames import LiveFrame
from app.live.intent import Intent
from app.live.loop import LiveLoop

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
                r = dataclasses.replace(r, plan=None)
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


class _Hosted:
    """One session in this worker: its latest intent and the thread running its loop."""

    def __init__(self, sid: str, intent: Intent, send, publish_hz: float):
        self.sid = sid
        self._intent = intent
        self._wake = threading.Event()
        self._stop = threading.Event()
        self.loop = LiveLoop(lambda: self._intent, lambda f: send(("frame", sid, f)),
                             sleep=self._wait, publish_hz=publish_hz)
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
        self._wake.wait(seconds)
        self._wake.clear()

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                self.loop.iterate()
        except Exception as exc:  # noqa: BLE001 - reported to the web process
            self._send(("error", self.sid, f"{type(exc).__name__}: {exc}\n"
                        f"{traceback.format_exc(limit=5)}"))


def worker_main(commands: Connection, frames: Connection, publish_hz: float) -> None:
    """Entry point of a worker process: serve commands until told to stop or orphaned."""
    logging.basicConfig(level=logging.WARNING)
    codec = FrameCodec()
    lock = threading.Lock()
    hosted: dict[str, _Hosted] = {}

    def send(message: tuple) -> None:
        kind, sid, payload = message
        if kind == "frame":
            payload = codec.encode(sid, payload)
        data = pickle.dumps((kind, sid, payload), protocol=pickle.HIGHEST_PROTOCOL)
        with lock:  # one writer at a time on the pipe
            try:
                frames.send_bytes(data)
            except (BrokenPipeError, OSError):
                os._exit(0)  # the web process is gone

    send(("ready", "", os.getpid()))
    while True:
        try:
            kind, sid, payload = commands.recv()
        except (EOFError, OSError):
            break  # the web process is gone
        if kind == "open":
            intent, = payload
            hosted[sid] = _Hosted(sid, intent, send, publish_hz)
            hosted[sid].thread.start()
        elif kind == "intent" and sid in hosted:
            hosted[sid].set_intent(payload)
        elif kind == "close" and sid in hosted:
            hosted.pop(sid).stop()
            with lock:
                codec.forget(sid)
        elif kind == "stop":
            break
    for h in hosted.values():
        h.stop()
    for h in hosted.values():
        h.thread.join(2.0)
