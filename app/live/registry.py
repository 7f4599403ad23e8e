"""The live sessions a server runs: the shared demo and, in private mode, one per browser.

Modes (``pelvic-walk serve --sessions shared|private``):
- ``shared`` (the default, a lecture demo): one session that every browser watches and
  changes;
- ``private``: each browser gets its own session (robots, parameters, plots, playback) while
  a worker has room; beyond that a browser is told so and watches the shared demo. A private
  session ends when its browser disconnects, or after ``idle_s`` without a browser or an API
  call (sessions opened through the API). The shared demo runs too, holding its robots'
  worker slots, unless the server is started without it (``serve --no-shared-demo``): then
  every slot is for private sessions and there is no shared session to watch.

Sessions run in worker processes (:class:`~app.live.pool.WorkerPool`) or, with no pool, the
shared one in a thread of this process (:class:`~app.live.session.LiveSim`).
"""

from __future__ import annotations

import secrets
import threading
import time
from dataclasses import dataclass

from app.live.intent import Intent
from app.live.pool import PoolFull, WorkerPool
from app.live.session import LiveSim, SessionView

SHARED = "shared"
MODES = ("shared", "private")


class NoSuchSession(KeyError):
    """No session has this id."""


class SessionsDisabled(RuntimeError):
    """Private sessions asked for while the server runs in shared mode."""


NO_SHARED = (
    "this server runs no shared demo (serve --no-shared-demo): open a private session with "
    "POST /api/sessions and address it as /api/sessions/{id}/..."
)


@dataclass
class _Entry:
    session: SessionView
    owner: str | None  # the browser (viser client) it belongs to; None: the API's
    last_used: float  # time.monotonic()


class SessionRegistry:
    """Sessions by id (any thread). ``close()`` ends them all."""

    def __init__(
        self,
        mode: str,
        shared: SessionView | None,
        pool: WorkerPool | None = None,
        idle_s: float = 300.0,
        intent: Intent | None = None,
        initial: Intent | None = None,
    ):
        """``shared`` is the shared demo, or None (private mode only) for none; ``initial``
        (or else ``intent``, or the shared demo's) is a private session's first intent."""
        if mode not in MODES:
            raise ValueError(f"sessions mode must be one of {', '.join(MODES)}, got {mode!r}")
        if mode == "private" and pool is None:
            raise ValueError("private sessions need worker processes (--workers >= 1)")
        if shared is None and mode != "private":
            raise ValueError("only private mode runs without a shared demo")
        first = initial or intent or (shared.intent if shared is not None else None)
        if first is None:
            raise ValueError("give the first intent of a private session")
        self.mode = mode
        self.pool = pool
        self.idle_s = idle_s
        self._initial = first  # a private session's first intent
        self._lock = threading.Lock()
        self._entries: dict[str, _Entry] = {}
        if shared is not None:
            self._entries[SHARED] = _Entry(shared, None, time.monotonic())
        self._stop = threading.Event()
        self._reaper = threading.Thread(target=self._reap, name="session-reaper", daemon=True)
        self._reaper.start()

    @classmethod
    def start(
        cls,
        mode: str,
        intent: Intent,
        pool: WorkerPool | None = None,
        idle_s: float = 300.0,
        shared_demo: bool = True,
    ) -> SessionRegistry:
        """Start the shared session (in a worker, or a thread without a pool; none when
        ``shared_demo`` is False, private mode only) and the registry."""
        shared: SessionView | None
        if not shared_demo:
            shared = None
        elif pool is None:
            shared = LiveSim(intent.params, intent.methods, intent.speed).start()
        else:
            shared = pool.open(intent, sid=SHARED)
        return cls(mode, shared, pool, idle_s, intent)

    @classmethod
    def around(cls, session: SessionView) -> SessionRegistry:
        """One session served as the shared one (no private sessions)."""
        return cls("shared", session)

    @property
    def has_shared(self) -> bool:
        """Whether a shared demo runs (always, but with ``serve --no-shared-demo``)."""
        return SHARED in self._entries

    @property
    def shared(self) -> SessionView:
        """The shared demo; NoSuchSession when the server runs none."""
        entry = self._entries.get(SHARED)
        if entry is None:
            raise NoSuchSession(NO_SHARED)
        return entry.session

    def get(self, sid: str | None) -> SessionView:
        """The session with this id (the shared one for None); NoSuchSession otherwise."""
        sid = sid or SHARED
        with self._lock:
            entry = self._entries.get(sid)
            if entry is None:
                raise NoSuchSession(sid)
            entry.last_used = time.monotonic()
            return entry.session

    def open_private(self, owner: str | None = None) -> tuple[str, SessionView]:
        """A new private session (PoolFull when the workers are full)."""
        if self.mode != "private" or self.pool is None:
            raise SessionsDisabled(
                "the server runs one shared session (start it with --sessions private)"
            )
        # unguessable: a session is changed by whoever names it, so one student cannot
        # address another's by counting (an instructor's listing shows them all)
        sid = f"p-{secrets.token_urlsafe(9)}"
        session = self.pool.open(self._initial, sid=sid)
        with self._lock:
            self._entries[sid] = _Entry(session, owner, time.monotonic())
        return sid, session

    def close(self, sid: str) -> None:
        """End a private session and free its room in the workers."""
        if sid == SHARED:
            return
        with self._lock:
            entry = self._entries.pop(sid, None)
        if entry is not None and self.pool is not None:
            self.pool.close(entry.session)  # type: ignore[arg-type]

    def close_owned_by(self, owner: str) -> None:
        with self._lock:
            sids = [sid for sid, e in self._entries.items() if e.owner == owner]
        for sid in sids:
            self.close(sid)

    def list(self) -> list[dict]:
        """One line per session: id, kind, owner, worker, robots, real-time factor."""
        with self._lock:
            entries = list(self._entries.items())
        out = []
        for sid, e in entries:
            playback = e.session.playback()  # the same account as GET /api/state's
            out.append(
                {
                    "id": sid,
                    "kind": "shared" if sid == SHARED else "private",
                    "owner": e.owner,
                    "worker_pids": getattr(e.session, "worker_pids", []),
                    "methods": list(e.session.intent.methods),
                    "realtime_factor": playback.realtime_factor,
                    "paused": playback.paused,
                    "speed": playback.speed,
                    "clock": playback.clock,
                    "shown_t": playback.shown_t,
                    "idle_s": round(time.monotonic() - e.last_used, 1),
                }
            )
        return out

    def count_private(self) -> int:
        with self._lock:
            return len([sid for sid in self._entries if sid != SHARED])

    @property
    def capacity_private(self) -> int:
        """Robots the workers have room for beside those running (private mode)."""
        if self.pool is None or self.mode != "private":
            return 0
        return self.pool.capacity - self.pool.robots()

    def _reap(self) -> None:
        while not self._stop.wait(1.0):
            now = time.monotonic()
            with self._lock:
                idle = [
                    sid
                    for sid, e in self._entries.items()
                    if sid != SHARED and e.owner is None and now - e.last_used > self.idle_s
                ]
            for sid in idle:
                self.close(sid)

    def shutdown(self, stop_shared: bool = True) -> None:
        """End the private sessions (and the shared one, unless the caller owns it)."""
        self._stop.set()
        with self._lock:
            sids = [s for s in self._entries if s != SHARED]
        for sid in sids:
            self.close(sid)
        if not stop_shared or not self.has_shared:
            return
        shared = self.shared
        if isinstance(shared, LiveSim):
            shared.stop()
        elif self.pool is not None:
            self.pool.close(shared)  # type: ignore[arg-type]


__all__ = ["MODES", "SHARED", "NoSuchSession", "PoolFull", "SessionRegistry", "SessionsDisabled"]
