"""The one live mode: workers for the live sessions, seen from the web process.

The web process keeps the viser broadcast, FastAPI and the display thread; the robots run in
``n_workers`` workers (``app.live.worker``), by default processes, so they keep real time
whatever the number of viewers, as long as their worker has the compute. How a worker is started
and reached is the pool's *engine* (``app.live.engines``): processes over pipes (the product's),
threads of this process over queues (``serve --workers 0``, the tests), or Ray actors over Ray
calls (``serve --ray``, ``app.live.ray_engine``); the placement, the
parts, the merge and the restarts below are the same on both. Each robot of a session runs in a
*part* (a :class:`~app.live.loop.LiveLoop` with that one robot) placed on the worker with the
most free robot slots (``robots_per_worker`` each), so one session's robots use every core. The
parts share the session's time base (the intent's anchor) and rebuild together, so the robots
stay in step; :class:`RemoteSession` merges their frames into one.

:meth:`WorkerPool.open` raises :class:`PoolFull` when the robots would not fit (admission
control). A receiver thread per worker reads the frames; when a worker dies (its pipe
closes), the pool records it, starts a new process, re-opens the dead worker's parts there
and, once they have built their robots, restarts the robots of every session it held, all
together.
"""

from __future__ import annotations

import collections
import dataclasses
import logging
import pickle
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from app.live.engines import START_DELAY_S, Engine, InProcessEngine, ProcessEngine, WorkerHandle
from app.live.intent import Intent
from app.live.loop import PUBLISH_HZ
from app.live.session import KEEP_S, SessionView
from app.live.worker import FrameCodec
from controller import strategy
from pelvic_walk.core import robots as robots_
from pelvic_walk.core.frames import LiveFrame
from pelvic_walk.core.robots import Robot

ALIGN_S = 3.0  # [s] of each part's frames kept to show all robots at one instant

log = logging.getLogger(__name__)
START_TIMEOUT_S = 60.0  # a new worker imports numpy, MuJoCo and Pinocchio first
__all__ = ["START_DELAY_S", "InProcessEngine", "PoolFull", "RemoteSession", "WorkerPool"]


class PoolFull(RuntimeError):
    """The workers have no room for the robots asked for."""


@dataclass
class WorkerDeath:
    """A worker that stopped without being asked (for /api/health and the page)."""

    worker: int
    pid: int | None
    exitcode: int | None
    time: float  # time.time()
    sessions: tuple[str, ...]  # the sessions it held, restarted
    where: str = ""  # " on node ..." (a Ray actor)

    def describe(self) -> str:
        when = time.strftime("%H:%M:%S", time.localtime(self.time))
        what = f"exit code {self.exitcode}" if self.exitcode is not None else "lost"
        n = len(self.sessions)
        return (
            f"worker {self.worker} (pid {self.pid}{self.where}) stopped at {when} ({what}); "
            f"{n} session{'s' if n != 1 else ''} restarted"
        )


class RemoteSession(SessionView):
    """A live session whose robots run in worker processes, one part per robot."""

    def __init__(
        self,
        sid: str,
        intent: Intent,
        pool: WorkerPool,
        keep_s: float = KEEP_S,
        label: str | None = None,
    ):
        super().__init__(intent, keep_s, wall=pool.clock, start_delay=pool.start_delay)
        self.sid = sid
        self.label = label or f"session {sid}"  # in logs (a private session: not its id)
        self.pool = pool
        self.parts: dict[str, _Worker] = {}  # method -> the worker running it
        # method -> its part's recent frames (newest last): the merged frame shows every robot
        # at the slowest part's instant, so side-by-side robots compare the same moment even
        # when one worker runs late (a busy machine, a worker that started later)
        self._recent: dict[str, collections.deque[LiveFrame]] = {}
        self._rows: dict[str, list[np.ndarray]] = {}  # rows since the last merged frame
        self._restarted = False
        self._seq = 0
        # held while a merged frame is made *and handed on*: the parts' receiver threads all
        # merge while paused, and a frame handed on after a newer one would read as a clock
        # going back and clear the kept frames (the first pause kept only the last instants).
        # Re-entrant: receive() may ask for the newest clock (_newest_clock) under it.
        self._merge_lock = threading.RLock()

    def part_id(self, method: str) -> str:
        return f"{self.sid}/{method}"

    def part_intent(self, method: str, intent: Intent | None = None) -> Intent:
        intent = intent or self.intent
        return dataclasses.replace(intent, robots=(intent.robot(method),))

    def set_robots(self, robots: Sequence[Robot]) -> Intent:
        """Show these robots (PoolFull when the workers have no room for the new ones)."""
        robots = robots_.check_all(robots)
        self.pool.reserve(self, tuple(r.key for r in robots))
        return super().set_robots(robots)

    def _newest_clock(self) -> float | None:
        """The fastest part's newest clock (the merged frame shows the slowest part's): a
        paused session's parts stand at different clocks, and after the time base moved back
        to a slow part the others run ahead of it."""
        with self._merge_lock:
            clocks = [r[-1].clock for r in self._recent.values() if r]
        return max(clocks) if clocks else super()._newest_clock()

    def _intent_changed(self) -> None:
        intent = self.intent
        self.pool.sync_parts(self, intent)
        for method, w in list(self.parts.items()):
            w.send(("intent", self.part_id(method), self.part_intent(method, intent)))

    @property
    def running(self) -> bool:
        return not self._closed.is_set() and bool(self.parts)

    @property
    def worker_pids(self) -> list[int]:
        return sorted({cast(int, w.process.pid) for w in self.parts.values()})  # started in _spawn

    def loops(self) -> dict[str, Any]:
        """Each robot's :class:`~app.live.loop.LiveLoop`, where the engine can reach it (the
        in-process one; tests read them). TypeError on worker processes."""
        return {m: self.pool.engine.loop(w.process, self.part_id(m)) for m, w in self.parts.items()}

    @property
    def robots(self) -> dict[str, Any]:
        """The robots of an in-process engine's parts, by method (the loops' threads own
        them; tests may read)."""
        return {m: loop.robots[m] for m, loop in self.loops().items() if m in loop.robots}

    def close(self) -> None:
        self.pool.close(self)

    def receive_part(self, method: str, frame: LiveFrame) -> None:
        """A part's frame: merge the parts' latest frames into one session frame."""
        with self._merge_lock:
            recent = self._recent.get(method)
            if recent is None or frame.restarted:
                recent = self._recent[method] = collections.deque(
                    maxlen=int(ALIGN_S * self.pool.publish_hz) + 1
                )
            recent.append(frame)
            for m, rows in frame.rows.items():
                self._rows.setdefault(m, []).append(rows)
            self._restarted |= frame.restarted
            methods = self.intent.methods
            order = [m for m in methods if m in self._recent and m in self.parts]
            if not order or (method != order[0] and not frame.paused):
                return  # merge on the lead part's frames (and every frame while paused)
            latest = [self._recent[m][-1] for m in order]
            slowest = min(latest, key=lambda p: p.clock)
            instant = slowest.clock
            paused = all(p.paused for p in latest)
            # running: each robot as it was at that instant; paused: as it stands (a single
            # step must show every part's new tick)
            parts = latest if paused else [_at(self._recent[m], instant) for m in order]
            lead = latest[0]
            rtf = [p.realtime_factor for p in parts]
            crtf = [p.compute_realtime_factor for p in parts]
            self._seq += 1
            merged = dataclasses.replace(
                lead,
                seq=self._seq,
                clock=instant,
                wall=slowest.wall,  # when the slowest part was there
                paused=paused,
                realtime_factor=None if None in rtf else min(rtf),  # type: ignore[type-var]
                compute_realtime_factor=None if None in crtf else min(crtf),  # type: ignore
                # what is shown; none yet while a robot asked for has sent no frame (a
                # change of robots is carried out once every new robot is shown)
                intent_version=(
                    min(p.intent_version for p in parts) if len(order) == len(methods) else -1
                ),
                steps_done=min(p.steps_done for p in parts),
                pushes_done=min(p.pushes_done for p in parts),
                robots=tuple(
                    dataclasses.replace(p.robots[0], slot=i)
                    for i, p in enumerate(parts)
                    if p.robots
                ),
                rows={m: np.concatenate(r) for m, r in self._rows.items()},
                restarted=self._restarted,
            )
            self._rows, self._restarted = {}, False
            self.receive(merged)  # in merge order (see _merge_lock)


def _at(recent: collections.deque[LiveFrame], instant: float) -> LiveFrame:
    """The newest of a part's ``recent`` frames not later than ``instant`` (its oldest kept
    frame when all are later: the part ran ahead by more than the kept window)."""
    for f in reversed(recent):
        if f.clock <= instant + 1e-9:
            return f
    return recent[0]


@dataclass
class _Worker:
    index: int
    process: WorkerHandle  # a process, or a thread of this one (the engine's)
    commands: object  # Connection (web -> worker)
    frames: object  # Connection (worker -> web)
    parts: dict[str, tuple[RemoteSession, str]] = field(default_factory=dict)  # id -> (s, m)
    lock: threading.Lock = field(default_factory=threading.Lock)
    ready: threading.Event = field(default_factory=threading.Event)
    codec: FrameCodec = field(default_factory=FrameCodec)
    stopping: bool = False
    receiver: threading.Thread | None = None
    shown: set[str] = field(default_factory=set)  # parts that have sent a frame (robots built)

    def send(self, message: tuple) -> None:
        with self.lock:
            try:
                self.commands.send(message)  # type: ignore[attr-defined]
            except (BrokenPipeError, OSError):
                pass  # the receiver thread notices the death and restarts the parts

    @property
    def robots(self) -> int:
        return len(self.parts)


class WorkerPool:
    """``n_workers`` workers running the robots of live sessions (module docstring).

    ``engine``: how workers are started and reached (default: :class:`ProcessEngine`,
    processes; :class:`InProcessEngine`: threads of this process)."""

    def __init__(
        self,
        n_workers: int,
        robots_per_worker: int = 3,
        publish_hz: float = PUBLISH_HZ,
        engine: Engine | None = None,
    ):
        if n_workers < 1 or robots_per_worker < 1:
            raise ValueError("need at least one worker and one robot per worker")
        self.n_workers = n_workers
        self.robots_per_worker = robots_per_worker
        self.publish_hz = publish_hz
        self.engine: Engine = engine or ProcessEngine()
        self._lock = threading.RLock()
        self._workers: list[_Worker] = []
        self.sessions: dict[str, RemoteSession] = {}
        self.deaths: list[WorkerDeath] = []
        self._stopped = False

    @property
    def clock(self):
        """The wall clock of the sessions' time base (the engine's)."""
        return self.engine.clock

    @property
    def start_delay(self) -> float:
        """[s of wall time] rebuilt robots start this much later (the engine's)."""
        return self.engine.start_delay

    @property
    def in_process(self) -> bool:
        """The robots run in threads of this process (the in-process engine)."""
        return isinstance(self.engine, InProcessEngine)

    # -- workers ---------------------------------------------------------------------------
    def start(self) -> WorkerPool:
        with self._lock:
            self._workers = [self._spawn(i) for i in range(self.n_workers)]
        for w in self._workers:
            w.ready.wait(START_TIMEOUT_S)
        return self

    def _spawn(self, index: int) -> _Worker:
        proc, cmd_send, frm_recv = self.engine.start(
            index, self.publish_hz, strategy.user_sources()
        )
        w = _Worker(index, proc, cmd_send, frm_recv)
        w.receiver = threading.Thread(
            target=self._receive, args=(w,), name=f"worker-{index}-frames", daemon=True
        )
        w.receiver.start()
        return w

    def receiver_thread_ids(self) -> set[int]:
        """Native ids of the threads that receive the workers' frames (and start a
        replacement when a worker dies, so it must keep the workers' priority)."""
        with self._lock:
            return {
                w.receiver.native_id
                for w in self._workers
                if w.receiver is not None and w.receiver.native_id is not None
            }

    def _receive(self, w: _Worker) -> None:
        """Read one worker's messages until its pipe closes; then handle its death."""
        while True:
            try:
                kind, pid, payload = pickle.loads(w.frames.recv_bytes())  # type: ignore
            except (EOFError, OSError):
                break
            if kind == "ready":
                w.ready.set()
                continue
            owner = w.parts.get(pid)
            if owner is None:
                continue
            session, method = owner
            if kind == "frame":
                try:
                    frame = w.codec.decode(pid, payload)
                except KeyError:
                    # sent by a part closed and opened again under the same id before the
                    # worker read the close (its plan went with it): stale, and no reason to
                    # stop reading this worker's frames
                    continue
                w.shown.add(pid)
                session.receive_part(method, frame)
            elif kind == "error":
                session.error = payload.splitlines()[0]
                log.error("%s, robot %s: %s", session.label, method, payload)
        if not w.stopping and not self._stopped:
            self._replace(w)

    def _replace(self, dead: _Worker) -> None:
        """A worker died: record it, start another, re-open its parts there and restart the
        robots of every session it held (all of them together, to stay in step)."""
        dead.process.join(1.0)
        with self._lock:
            held = {s.sid: s for s, _m in dead.parts.values()}
            self.deaths.append(
                WorkerDeath(
                    dead.index,
                    dead.process.pid,
                    dead.process.exitcode,
                    time.time(),
                    tuple(held),
                    getattr(dead.process, "where", ""),
                )
            )
            log.error(self.deaths[-1].describe())
            new = self._spawn(dead.index)
            self._workers[dead.index] = new
        new.ready.wait(START_TIMEOUT_S)
        with self._lock:
            for session, method in dead.parts.values():
                self._open_part(new, session, method)
        # the restart once the new worker has built its robots (its first frames): a fresh
        # worker builds its first robots slowly (models loaded, kernels read), and a part
        # built after the restart's start clock would join its session only in phase, later
        deadline = time.monotonic() + START_TIMEOUT_S
        while time.monotonic() < deadline and not self._stopped:
            with self._lock:
                if all(pid in new.shown or pid not in new.parts for pid in dead.parts):
                    break
            time.sleep(0.02)
        for session in held.values():
            session.reset()

    # -- parts and sessions ----------------------------------------------------------------
    def _open_part(self, w: _Worker, session: RemoteSession, method: str) -> None:
        pid = session.part_id(method)
        session.parts[method] = w
        w.parts[pid] = (session, method)
        w.send(("open", pid, (session.part_intent(method),)))

    def _close_part(self, session: RemoteSession, method: str) -> None:
        w = session.parts.pop(method, None)
        pid = session.part_id(method)
        if w is not None and w.parts.pop(pid, None) is not None:
            w.send(("close", pid, None))
            w.codec.forget(pid)

    def _free(self) -> list[_Worker]:
        return [w for w in self._workers if w.robots < self.robots_per_worker]

    def reserve(self, session: RemoteSession, methods: Sequence[str]) -> None:
        """PoolFull unless the workers have room for the robots ``session`` would add (its
        robots not among ``methods`` are closed first: their slots count as free)."""
        with self._lock:
            need = len([m for m in methods if m not in session.parts])
            # the session's robots not kept are closed before the new ones open (sync_parts)
            freed = len([m for m in session.parts if m not in methods])
            room = sum(self.robots_per_worker - w.robots for w in self._workers) + freed
            if need > room:
                raise PoolFull(
                    f"the workers hold {self.n_workers} x {self.robots_per_worker}"
                    f" robots and have room for {room} more, not {need}"
                )

    def sync_parts(self, session: RemoteSession, intent: Intent) -> None:
        """Open a part for every new robot of the session, close those it no longer shows."""
        if session._closed.is_set():
            return
        with self._lock:
            for method in [m for m in session.parts if m not in intent.methods]:
                self._close_part(session, method)
            for method in intent.methods:
                if method not in session.parts:
                    free = self._free()
                    if not free:
                        raise PoolFull("no worker has room for another robot")
                    self._open_part(min(free, key=lambda x: x.robots), session, method)

    def open(
        self,
        intent: Intent,
        keep_s: float = KEEP_S,
        sid: str | None = None,
        label: str | None = None,
    ) -> RemoteSession:
        """A new session (its robots placed where there is room); PoolFull otherwise.
        ``label``: how logs name it (default: its id)."""
        with self._lock:
            sid = sid or f"s{len(self.sessions) + 1}"
            while sid in self.sessions:
                sid += "'"
            session = RemoteSession(sid, intent, self, keep_s, label=label)
            self.reserve(session, intent.methods)
            self.sessions[sid] = session
            self.sync_parts(session, session.intent)
            return session

    def close(self, session: RemoteSession) -> None:
        """End a session and free its robots' slots."""
        with self._lock:
            session._closed.set()
            for method in list(session.parts):
                self._close_part(session, method)
            self.sessions.pop(session.sid, None)
        with session._changed:
            session._changed.notify_all()

    def robots(self) -> int:
        return sum(w.robots for w in self._workers)

    @property
    def capacity(self) -> int:
        """Robots the workers hold in all."""
        return self.n_workers * self.robots_per_worker

    def workers(self) -> list[dict]:
        """One line per worker for /api/health and /api/sessions."""
        with self._lock:
            out: list[dict[str, Any]] = [
                {
                    "index": w.index,
                    "pid": w.process.pid,
                    "alive": w.process.is_alive(),
                    "robots": sorted(w.parts),
                }
                for w in self._workers
            ]
            for line, w in zip(out, self._workers, strict=True):
                info = getattr(w.process, "info", None)  # a Ray actor: its node and load
                if info is not None:
                    line.update(node=(info.get("node") or "")[:8] or None, load=info.get("load"))
            return out

    def nodes(self) -> list[dict] | None:
        """The cluster's nodes with the workers and robots on each (a Ray engine), else None."""
        nodes = getattr(self.engine, "nodes", None)
        return nodes(self.workers()) if nodes is not None else None

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
        close = getattr(self.engine, "close", None)
        if close is not None:
            close()  # (a Ray engine: its actors, and a local Ray instance it started)
