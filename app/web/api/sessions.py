"""``/api/sessions``: which live sessions run, where, and private ones for scripts.

Every session-scoped route exists twice: ``/api/<route>`` acts on the shared session, or on the
session named by the ``X-Pelvic-Session`` header; ``/api/sessions/{sid}/<route>`` on session
``sid``. With ``--sessions private`` each browser gets its own session; scripts may open one
with ``POST /api/sessions`` (it ends after the server's idle timeout without calls).
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Depends, Header, HTTPException, Path
from fastapi.security import HTTPAuthorizationCredentials

from app.live.pool import PoolFull
from app.live.registry import (
    NO_SHARED,
    SHARED,
    NoSuchSession,
    SessionRegistry,
    SessionsDisabled,
)
from app.live.session import SessionView
from app.web.api.edges import conflict, finite, router
from app.web.auth import BEARER, Instructor

HEADER = "X-Pelvic-Session"


def resolvers(registry: SessionRegistry):
    """FastAPI dependencies: (by header or the shared session, by path)."""

    def lookup(sid: str | None) -> tuple[str, SessionView]:
        try:
            return sid or SHARED, registry.get(sid)
        except NoSuchSession:
            if (sid or SHARED) == SHARED:
                raise HTTPException(404, detail=NO_SHARED) from None
            raise HTTPException(
                404, detail=f"no session {sid!r}: GET /api/sessions lists them"
            ) from None

    def by_header(
        x_pelvic_session: str | None = Header(
            None, description="a session id (default: the shared session)"
        ),
    ) -> tuple[str, SessionView]:
        return lookup(x_pelvic_session)

    def by_path(
        sid: str = Path(..., description="a session id, see GET /api/sessions"),
    ) -> tuple[str, SessionView]:
        return lookup(sid)

    return by_header, by_path


def sessions_router(registry: SessionRegistry, instructor: Instructor | None = None) -> APIRouter:
    r = router("/api/sessions", "sessions")
    teacher = instructor or Instructor(None)
    bearer = Depends(BEARER)

    @r.get("")
    def list_sessions(
        credentials: HTTPAuthorizationCredentials | None = bearer,
    ) -> dict[str, Any]:
        """The sessions that run, their worker and real-time factor, and the capacity. With an
        instructor (serve --instructor-token), private sessions' ids are listed only to the
        instructor's bearer token: whoever names a session may change it, so students do not
        see each other's (each browser knows its own; a script gets its id from POST)."""
        pool = registry.pool
        sessions = registry.list()
        if teacher.enabled and not teacher.is_token(
            credentials.credentials if credentials else None
        ):
            sessions = [
                {**s, "id": None, "owner": None} if s["kind"] == "private" else s for s in sessions
            ]
        return finite(
            {
                "mode": registry.mode,
                "shared_demo": registry.has_shared,
                "sessions": sessions,
                "private_sessions": registry.count_private(),
                "robot_slots_free": registry.capacity_private,
                "workers": pool.workers() if pool is not None else [],
            }
        )

    @r.post("", status_code=201)
    def open_session() -> dict[str, Any]:
        """Open a private session (private mode only); it ends after the idle timeout."""
        try:
            sid, _session = registry.open_private(owner=None)
        except SessionsDisabled as exc:
            raise conflict(str(exc)) from None
        except PoolFull as exc:
            raise HTTPException(
                503, detail=f"the workers are full: {exc}; watch the shared session instead"
            ) from None
        return {"id": sid, "api": f"/api/sessions/{sid}/state"}

    @r.delete("/{sid}")
    def close_session(sid: str) -> dict[str, Any]:
        if sid == SHARED:
            raise conflict("the shared session runs as long as the server")
        try:
            registry.get(sid)
        except NoSuchSession:
            raise HTTPException(404, detail=f"no session {sid!r}") from None
        registry.close(sid)
        return {"id": sid, "closed": True}

    return r
