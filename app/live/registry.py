"""The live sessions a server runs: the shared demo and, in private mode, one per browser.

Modes (``pelvic-walk serve --sessions shared|private``):
- ``shared`` (the default, a lecture demo): one session that every browser watches and
  changes;
- ``private``: each browser gets its own session (robots, parameters, plots, playback) while
  a worker has room; beyond that a browser is told so and watches the shared demo. The shared
  demo runs too, holding its robots' worker slots, unless the server is started without it
  (``serve --no-shared-demo``): then every slot is for private sessions and there is no
  shared session to watch.

A private session belongs to whoever holds its *credential*, a secret that is never its id:
the seat cookie of the browser whose page opened it (``opened_by="page"``), or the token
``POST /api/sessions`` answered with (``"api"``); a scene connected without a page's cookie
(``"scene"``) gets a session only that connection sees. Only the holder and the instructor may
read, change or end it, and only they are shown its id (:meth:`SessionRegistry.list`,
:meth:`SessionRegistry.workers`); everyone else is told of it by a count. A holder that asks
again gets its own session back (:meth:`SessionRegistry.owned`), and one client address holds
at most ``per_address`` of them (:class:`AddressFull`; the server's own machine, loopback, is
not limited, and the instructor may open more through the API).

A private session ends: a page's ``linger_s`` after its last view closed and its last API call
(a reload or a reconnect within that time gets it back); a scene's when its connection closes;
an API-opened one after ``idle_s`` without calls.

Sessions run in the worker pool (:class:`~app.live.pool.WorkerPool`, the one live mode); a
registry started without one runs its own, in threads of this process (its in-process
engine), and stops it with the sessions.
"""

from __future__ import annotations

import builtins
import hmac
import ipaddress
import re
import secrets
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from app.live.engines import InProcessEngine
from app.live.intent import Intent
from app.live.pool import PoolFull, RemoteSession, WorkerPool
from app.live.session import SessionView

SHARED = "shared"
MODES = ("shared", "private")
OPENED_BY = ("page", "scene", "api")  # who opens a private session (module docstring)
LINGER_S = 20.0  # [s] a page's session outlives its last view and API call (a reload)
PER_ADDRESS = 1  # private sessions one client address holds (serve --sessions-per-address)
CREDENTIAL_MIN = 20  # characters a credential has at least (a seat cookie, a token)


class NoSuchSession(KeyError):
    """No session has this id."""


class SessionsDisabled(RuntimeError):
    """Private sessions asked for while the server runs in shared mode."""


class AddressFull(RuntimeError):
    """This client address holds as many private sessions as one may."""


def limited(address: str | None) -> bool:
    """Whether ``address`` counts against the per-address limit: every address but the
    server's own machine (loopback; its users could start a server of their own)."""
    if not address:
        return True
    try:
        ip = ipaddress.ip_address(address)
    except ValueError:
        return True
    mapped = getattr(ip, "ipv4_mapped", None)
    return not (mapped or ip).is_loopback


_CREDENTIAL = re.compile(rf"[A-Za-z0-9_\-]{{{CREDENTIAL_MIN},256}}")  # secrets.token_urlsafe's


def usable_credential(value: str | None) -> str | None:
    """``value`` if it can serve as a credential (URL-safe characters, long enough to be
    unguessable), else None."""
    if value is None or _CREDENTIAL.fullmatch(value) is None:
        return None
    return value


NO_SHARED = (
    "this server runs no shared demo (serve --no-shared-demo): a browser's page gets a private "
    "session of its own; a script opens one with POST /api/sessions and addresses it as "
    "/api/sessions/mine/... with the header 'Authorization: Bearer <the token it was given>'"
)


@dataclass
class _Entry:
    session: SessionView
    opened_by: str  # "shared", or one of OPENED_BY
    credential: str | None  # the secret its holder presents; None: only its scene connections
    address: str | None  # the client address that opened it
    last_used: float  # time.monotonic() of the last API call (or a view closing)
    viewers: set[str] = field(default_factory=set)  # the scene connections showing it

    def held_by(self, credentials: Iterable[str]) -> bool:
        """Whether one of ``credentials`` is this session's (constant time each)."""
        mine = self.credential
        if mine is None:
            return False
        return any(hmac.compare_digest(mine.encode(), c.encode()) for c in credentials)


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
        per_address: int = PER_ADDRESS,
        linger_s: float = LINGER_S,
    ):
        """``shared`` is the shared demo, or None (private mode only) for none; ``initial``
        (or else ``intent``, or the shared demo's) is a private session's first intent;
        ``per_address``: private sessions one client address holds at most."""
        if mode not in MODES:
            raise ValueError(f"sessions mode must be one of {', '.join(MODES)}, got {mode!r}")
        if mode == "private" and pool is None:
            raise ValueError("private sessions need a worker pool")
        if shared is None and mode != "private":
            raise ValueError("only private mode runs without a shared demo")
        first = initial or intent or (shared.intent if shared is not None else None)
        if first is None:
            raise ValueError("give the first intent of a private session")
        self.mode = mode
        self.pool = pool
        self.idle_s = idle_s
        self.per_address = per_address
        self.linger_s = linger_s
        self._initial = first  # a private session's first intent
        self._lock = threading.Lock()
        self._opening = threading.Lock()  # one open at a time: the address count holds
        self._entries: dict[str, _Entry] = {}
        if shared is not None:
            self._entries[SHARED] = _Entry(shared, "shared", None, None, time.monotonic())
        self._own_pool: WorkerPool | None = None  # started by start(), stopped by shutdown()
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
        per_address: int = PER_ADDRESS,
    ) -> SessionRegistry:
        """Start the shared session in the pool (none when ``shared_demo`` is False, private
        mode only) and the registry. Without a pool, one of the demo's size runs in threads
        of this process (the registry stops it)."""
        own = None
        if pool is None:
            own = pool = WorkerPool(1, len(intent.methods), engine=InProcessEngine()).start()
        shared = pool.open(intent, sid=SHARED) if shared_demo else None
        registry = cls(mode, shared, pool, idle_s, intent, per_address=per_address)
        registry._own_pool = own
        return registry

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

    def open_private(
        self,
        credential: str | None = None,
        address: str | None = None,
        opened_by: str = "api",
        viewer: str | None = None,
        beyond_limit: bool = False,
    ) -> tuple[str, SessionView]:
        """A new private session held by ``credential`` (None: only its ``viewer``, a scene
        connection, sees it), opened from client ``address``. PoolFull when the workers are
        full, AddressFull when the address holds ``per_address`` sessions already (unless
        ``beyond_limit``: the instructor decides). A credential that holds a session already
        gets that one back."""
        if self.mode != "private" or self.pool is None:
            raise SessionsDisabled(
                "the server runs one shared session (start it with --sessions private)"
            )
        if opened_by not in OPENED_BY:
            raise ValueError(f"opened_by must be one of {', '.join(OPENED_BY)}")
        if credential is not None and usable_credential(credential) is None:
            raise ValueError(f"a credential has {CREDENTIAL_MIN} to 256 characters")
        with self._opening:
            mine = self.owned([credential])
            if mine is not None:  # a holder asking again gets its own (two tabs at once)
                return mine, self.attach(mine, viewer) if viewer else self.get(mine)
            if not beyond_limit and limited(address):
                with self._lock:
                    held = sum(
                        1
                        for sid, e in self._entries.items()
                        if sid != SHARED and e.address == address
                    )
                if held >= self.per_address:
                    raise AddressFull(
                        f"this address ({address}) holds {held} private session"
                        f"{'s' if held != 1 else ''} already, the most one client may hold"
                    )
            # an id says which session, never who may use it (that is the credential); still
            # unguessable, so that an id seen once tells nothing of the next
            sid = f"p-{secrets.token_urlsafe(9)}"
            session = self.pool.open(self._initial, sid=sid, label="a private session")
            with self._lock:
                entry = _Entry(session, opened_by, credential, address, time.monotonic())
                if viewer is not None:
                    entry.viewers.add(viewer)
                self._entries[sid] = entry
        return sid, session

    def owned(self, credentials: Iterable[str | None]) -> str | None:
        """The id of the private session one of ``credentials`` holds, or None."""
        given = [c for c in credentials if usable_credential(c)]
        if not given:
            return None
        with self._lock:
            entries = list(self._entries.items())
        return next((sid for sid, e in entries if e.held_by(given)), None)  # type: ignore[arg-type]

    def may_use(self, sid: str, credentials: Iterable[str | None]) -> bool:
        """Whether ``credentials`` hold private session ``sid`` (False if there is none)."""
        given = [c for c in credentials if usable_credential(c)]
        with self._lock:
            entry = self._entries.get(sid)
        return entry is not None and sid != SHARED and entry.held_by(given)  # type: ignore[arg-type]

    def attach(self, sid: str, viewer: str) -> SessionView:
        """Show session ``sid`` to one more scene connection (a reload, a second tab)."""
        with self._lock:
            entry = self._entries.get(sid)
            if entry is None:
                raise NoSuchSession(sid)
            entry.viewers.add(viewer)
            return entry.session

    def detach(self, viewer: str) -> None:
        """A scene connection closed: a session only it saw ends now; a page's lingers
        ``linger_s`` (a reload gets it back)."""
        ended = []
        now = time.monotonic()
        with self._lock:
            for sid, e in self._entries.items():
                if viewer in e.viewers:
                    e.viewers.discard(viewer)
                    e.last_used = now
                    if not e.viewers and e.opened_by == "scene":
                        ended.append(sid)
        for sid in ended:
            self.close(sid)

    def close(self, sid: str, only_if: Callable[[_Entry], bool] = lambda _e: True) -> None:
        """End a private session and free its room in the workers (``only_if`` its entry
        passes, checked under the lock: the reaper's idle session may have been found again
        by a reload meanwhile)."""
        if sid == SHARED:
            return
        with self._lock:
            entry = self._entries.get(sid)
            if entry is None or not only_if(entry):
                return
            del self._entries[sid]
        if self.pool is not None:
            self.pool.close(entry.session)  # type: ignore[arg-type]

    def _idle(self, e: _Entry, now: float) -> bool:
        """Nothing showed or used a private session for its time: an API-opened one
        ``idle_s``, a page's ``linger_s``."""
        limit = self.idle_s if e.opened_by == "api" else self.linger_s
        return not e.viewers and now - e.last_used > limit

    def list(self, reveal: Callable[[str], bool] = lambda _sid: False) -> list[dict]:
        """One line per session the caller may see: the shared one, and the private ones
        ``reveal(sid)`` allows (the instructor: all; a holder: its own): id, kind, who opened
        it, from where, viewers, worker, robots, playback."""
        with self._lock:
            entries = [
                (sid, e, len(e.viewers))
                for sid, e in self._entries.items()
                if sid == SHARED or reveal(sid)
            ]
        out = []
        for sid, e, viewers in entries:
            playback = e.session.playback()  # the same account as GET /api/state's
            out.append(
                {
                    "id": sid,
                    "kind": "shared" if sid == SHARED else "private",
                    "opened_by": e.opened_by,
                    "address": e.address,
                    "viewers": viewers if sid != SHARED else None,  # (not counted)
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

    def workers(self, reveal: Callable[[str], bool] = lambda _sid: False) -> builtins.list[dict]:
        """The workers (:meth:`WorkerPool.workers`) with each robot as ``<session>/<method>``:
        a private session's id only where ``reveal(sid)`` allows, else ``private``."""
        if self.pool is None:
            return []
        out = []
        for w in self.pool.workers():
            robots = []
            for part in w["robots"]:
                sid, _, method = part.partition("/")  # (a label may hold a '/')
                robots.append(part if sid == SHARED or reveal(sid) else f"private/{method}")
            out.append({**w, "robots": sorted(robots)})
        return out

    def realtime_factor_min(self) -> float | None:
        """The lowest real-time factor among the sessions running (paused ones left out): how
        well the server keeps real time, told to anyone without telling whose session."""
        with self._lock:
            sessions = [e.session for e in self._entries.values()]
        factors = [
            p.realtime_factor
            for p in (s.playback() for s in sessions)
            if p.realtime_factor is not None and not p.paused
        ]
        return min(factors) if factors else None

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
                    sid for sid, e in self._entries.items() if sid != SHARED and self._idle(e, now)
                ]
            for sid in idle:
                self.close(sid, only_if=lambda e: self._idle(e, time.monotonic()))

    def shutdown(self, stop_shared: bool = True) -> None:
        """End the private sessions (and the shared one, unless the caller owns it)."""
        self._stop.set()
        with self._lock:
            sids = [s for s in self._entries if s != SHARED]
        for sid in sids:
            self.close(sid)
        if stop_shared and self.has_shared:
            shared = self.shared
            if isinstance(shared, RemoteSession):
                shared.pool.close(shared)
        if self._own_pool is not None:
            self._own_pool.stop()


__all__ = [
    "LINGER_S",
    "MODES",
    "SHARED",
    "AddressFull",
    "NoSuchSession",
    "PoolFull",
    "SessionRegistry",
    "SessionsDisabled",
    "limited",
    "usable_credential",
]
