"""Worker processes for the live sessions, seen from the web process.

The web process keeps the viser broadcast, FastAPI and the display threads; the simulation
runs in ``n_workers`` worker processes (``app.live.worker``), so the robots keep real time
whatever the number of viewers, as long as their worker has the compute. Each worker holds up
to ``sessions_per_worker`` sessions; :meth:`WorkerPool.open` places a session on the worker
with the most room or raises :class:`PoolFull` (admission control).

A :class:`RemoteSession` is a :class:`~app.live.session.SessionView` whose intent changes are
sent to its worker and whose frames come back from it. A receiver thread per worker reads
the frames; when a worker dies (the pipe closes), the pool records it, starts a new process
and re-opens the dead worker's sessions there with their current intent (their robots start
again from standing; frames, plots and kept history continue on the display side).
"""

from __future__ import annotations

import itertools
import logging
import multiprocessing
import os
import pickle
import threading
import time
from dataclasses import dataclass, field

from app.live.frames import LiveFrame
from app.live.intent import Intent
from app.live.loop import PUBLISH_HZ
from app.live.session import KEEP_S, SessionView
from app.live.worker import FrameCodec, worker_main

log = logging.getLogger(__name__)
START_TIMEOUT_S = 60.0  # a new worker imports numpy, MuJoCo and Pinocchio first


class PoolFull(RuntimeError):
    """Every worker holds as many sessions as it may."""


@dataclass
class WorkerDeath:
    """A worker that stopped without being asked (for /api/health and the page)."""

    worker: int
    pid: int | None
    exitcode: int | None
    time: float  # time.time()
    sessions: tuple[str, ...]  # the sessions it held, restarted elsewhere

    def describe(self) -> str:
        when = time.strftime("%H:%M:%S", time.localtime(self.time))
        what = f"exit code {self.exitcode}" if self.exitcode is not None else "lost"
        n = len(self.sessions)
        return (f"worker {self.worker} (pid {self.pid}) stopped at {when} ({what}); "
                f"{n} session{'s' if n != 1 else ''} restarted")


class RemoteSession(SessionView):
    """A live session run by a worker process."""

    def __init__(self, sid: str, intent: Intent, pool: WorkerPool, keep_s: float = KEEP_S):
        super().__init__(intent, keep_s)
        self.sid = sid
        self.pool = pool
        self.worker: _Worker | None = None

    def _intent_changed(self) -> None:
        if self.worker is not None:
            self.worker.send(("intent", self.sid, self.intent))

    @property
    def running(self) -> bool:
        return not self._closed.is_set() and self.worker is not None

    def close(self) -> None:
        self.pool.close(self)


@dataclass
class _Worker:
    index: int
    process: multiprocessing.process.BaseProcess
    commands: object  # Connection (web -> worker)
    frames: object  # Connection (worker -> web)
    sessions: dict[str, RemoteSession] = field(default_factory=dict)
    lock: threading.Lock = field(default_factory=threading.Lock)
    ready: threading.Event = field(default_factory=threading.Event)
    codec: FrameCodec = field(default_factory=FrameCodec)
    stopping: bool = False

    def send(self, message: tuple) -> None:
        with self.lock:
            try:
                self.commands.send(message)  # type: ignore[attr-defined]
            except (BrokenPipeError, OSError):
                pass  # the receiver thread notices the death and restarts the sessions


class WorkerPool:
    """``n_workers`` processes running live sessions (see the module docstring)."""

    def __init__(self, n_workers: int, sessions_per_worker: int = 1,
                 publish_hz: float = PUBLISH_HZ):
        if n_workers < 1 or sessions_per_worker < 1:
            raise ValueError("need at least one worker and one session per worker")
        self.n_workers = n_workers
        self.sessions_per_worker = sessions_per_worker
        self.publish_hz = publish_hz
        self._ctx = multiprocessing.get_context("spawn")
        self._lock = threading.RLock()
        self._workers: list[_Worker] = []
        self._ids = itertools.count(1)
        self.deaths: list[WorkerDeath] = []
        self._stopped = False

    # -- workers ---------------------------------------------------------------------------
    def start(self) -> WorkerPool:
        with self._lock:
            self._workers = [self._spawn(i) for i in range(self.n_workers)]
        for w in self._workers:
            w.ready.wait(START_TIMEOUT_S)
        return self

    def _spawn(self, index: int) -> _Worker:
        cmd_parent, cmd_child = self._ctx.Pipe(duplex=False)[::-1]  # (send end, recv end)
        frm_child, frm_parent = self._ctx.Pipe(duplex=False)[::-1]
        # One BLAS thread per worker: the matrices are small and the cores are for workers.
        env = {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")}
        os.environ.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
        try:
            proc = self._ctx.Process(target=worker_main, args=(cmd_child, frm_child,
                                                               self.publish_hz),
                                     name=f"pelvic-walk-worker-{index}", daemon=True)
            proc.start()
        finally:
            for k, v in env.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v
        cmd_child.close()
        frm_child.close()
        w = _Worker(index, proc, cmd_parent, frm_parent)
        threading.Thread(target=self._receive, args=(w,), name=f"worker-{index}-frames",
                         daemon=True).start()
        return w

    def _receive(self, w: _Worker) -> None:
        """Read one worker's messages until its pipe closes; then handle its death."""
        while True:
            try:
                kind, sid, payload = pickle.loads(w.frames.recv_bytes())  # type: ignore
            except (EOFError, OSError):
                break
            if kind == "ready":
                w.ready.set()
            elif kind == "frame":
                session = w.sessions.get(sid)
                if session is not None:
                    frame: LiveFrame = w.codec.decode(sid, payload)
                    session.receive(frame)
            elif kind == "error":
                session = w.sessions.get(sid)
                if session is not None:
                    session.error = payload.splitlines()[0]
                    log.error("session %s: %s", sid, payload)
        if not w.stopping and not self._stopped:
            self._replace(w)

    def _replace(self, dead: _Worker) -> None:
        """A worker died: record it, start another, re-open its sessions there."""
        dead.process.join(1.0)
        with self._lock:
            self.deaths.append(WorkerDeath(dead.index, dead.process.pid,
                                           dead.process.exitcode, time.time(),
                                           tuple(dead.sessions)))
            log.error(self.deaths[-1].describe())
            new = self._spawn(dead.index)
            self._workers[dead.index] = new
        new.ready.wait(START_TIMEOUT_S)
        for session in list(dead.sessions.values()):
            self._place(session, new)

    def _place(self, session: RemoteSession, w: _Worker) -> None:
        session.worker = w
        w.sessions[session.sid] = session
        w.send(("open", session.sid, (session.intent,)))

    # -- sessions --------------------------------------------------------------------------
    def open(self, intent: Intent, keep_s: float = KEEP_S, sid: str | None = None
             ) -> RemoteSession:
        """A new session on the worker with the most room; PoolFull when all are full."""
        with self._lock:
            free = [w for w in self._workers if len(w.sessions) < self.sessions_per_worker]
            if not free:
                raise PoolFull(f"{self.count()} sessions run, the most "
                               f"{self.n_workers} x {self.sessions_per_worker} workers hold")
            w = min(free, key=lambda x: len(x.sessions))
            session = RemoteSession(sid or f"s{next(self._ids)}", intent, self, keep_s)
            self._place(session, w)
            return session

    def close(self, session: RemoteSession) -> None:
        """End a session and free its room on the worker."""
        with self._lock:
            w = session.worker
            session._closed.set()
            session.worker = None
            if w is not None and w.sessions.pop(session.sid, None) is not None:
                w.send(("close", session.sid, None))
                w.codec.forget(session.sid)
        with session._changed:
            session._changed.notify_all()

    def count(self) -> int:
        return sum(len(w.sessions) for w in self._workers)

    @property
    def capacity(self) -> int:
        return self.n_workers * self.sessions_per_worker

    def workers(self) -> list[dict]:
        """One line per worker for /api/health and /api/sessions."""
        with self._lock:
            return [{"index": w.index, "pid": w.process.pid, "alive": w.process.is_alive(),
                     "sessions": sorted(w.sessions)} for w in self._workers]

    def pid(self, session: RemoteSession) -> int | None:
        return session.worker.process.pid if session.worker is not None else None

    def stop(self) -> None:
        self._stopped = True
        with self._lock:
            workers = list(self._workers)
        for w in workers:
            w.stopping = True
            w.send(("stop", "", None))
        for w in workers:
            w.process.join(3.0)
            if w.process.is_alive():
                w.process.kill()
                w.process.join(1.0)
