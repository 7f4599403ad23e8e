"""``/api/sessions``: which live sessions run, where, and private ones for scripts.

Every session-scoped route exists twice: ``/api/<route>`` acts on the shared session, or on the
session named by the ``X-Pelvic-Session`` header; ``/api/sessions/{sid}/<route>`` on session
``sid``. ``mine`` names the caller's own private session in both. With ``--sessions private``
each browser gets its own session; scripts may open one with ``POST /api/sessions`` (it ends
after the server's idle timeout without calls).

Who may use a session (:mod:`app.live.registry`, :mod:`app.web.auth`): the shared one, everyone
reads it and (without an instructor) changes it. A private one answers only to its holder
(the browser whose page opened it, by its seat cookie; the script that opened it, by the token
it was given) and to the instructor: anyone else is told there is no such session (404, the
same whether it exists or not), and is shown neither its id nor its state.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from fastapi import APIRouter, Depends, Header, HTTPException, Path, Request, Response
from fastapi.security import HTTPAuthorizationCredentials

from app.live.pool import PoolFull
from app.live.registry import (
    NO_SHARED,
    SHARED,
    AddressFull,
    NoSuchSession,
    SessionRegistry,
    SessionsDisabled,
)
from app.live.session import SessionView
from app.web.addresses import ClientAddresses
from app.web.api.edges import conflict, finite, router
from app.web.auth import BEARER, INSTRUCTOR_COOKIE, SEAT_COOKIE, Instructor, new_credential

HEADER = "X-Pelvic-Session"
MINE = "mine"  # names the caller's own private session
RETRY_S = 30  # [s] the Retry-After of "the workers are full"
Bearer = Depends(BEARER)


@dataclass(frozen=True)
class Caller:
    """Who sent a request: the instructor or not, the credentials it presented (a bearer
    token, the browser's seat cookie) and the address it came from."""

    instructor: bool
    credentials: tuple[str, ...]
    address: str | None


def caller_of(instructor: Instructor, addresses: ClientAddresses | None = None):
    """A FastAPI dependency: the :class:`Caller` of a request (its address read by
    ``addresses``, the one source the scene's connections are read by too)."""
    source = addresses or ClientAddresses()

    def caller(
        request: Request, credentials: HTTPAuthorizationCredentials | None = Bearer
    ) -> Caller:
        bearer = credentials.credentials if credentials is not None else None
        seat = request.cookies.get(SEAT_COOKIE)
        teacher = request.cookies.get(INSTRUCTOR_COOKIE)
        return Caller(
            instructor=instructor.is_token(bearer) or instructor.is_cookie(teacher),
            credentials=tuple(c for c in (bearer, seat) if c),
            address=source.of_request(request),
        )

    return caller


def not_yours(sid: str) -> HTTPException:
    """The answer to anyone but its holder and the instructor, whether ``sid`` exists or not."""
    return HTTPException(
        404,
        detail=f"no session {sid!r} that you may use: a private session answers only to its "
        "holder (the browser whose page opened it; the script that opened it, with "
        "'Authorization: Bearer <its token>') and to the instructor. Your own is "
        f"/api/sessions/{MINE}/...",
    )


def no_own(registry: SessionRegistry) -> HTTPException:
    if registry.mode != "private":
        return HTTPException(
            404,
            detail="this server runs one shared session (no private ones): address it as "
            "/api/<route>",
        )
    return HTTPException(
        404,
        detail="you hold no private session: the page / gives your browser one (while the "
        "workers have room); a script opens one with POST /api/sessions and sends the token "
        "it answers with as 'Authorization: Bearer <token>'",
    )


def private_session(registry: SessionRegistry, sid: str, caller: Caller) -> tuple[str, SessionView]:
    """The one access check of a private session: ``mine`` is the caller's own; any other id
    answers only to its holder and the instructor (404 :func:`not_yours` otherwise, whether it
    exists or not, and if it ended meanwhile)."""
    if sid == MINE:
        own = registry.owned(caller.credentials)
        if own is None:
            raise no_own(registry)
        sid = own
    elif not (caller.instructor or registry.may_use(sid, caller.credentials)):
        raise not_yours(sid)
    try:
        return sid, registry.get(sid)
    except NoSuchSession:
        raise not_yours(sid) from None


def resolvers(registry: SessionRegistry, caller_dep):
    """FastAPI dependencies: (by header or the shared session, by path); each returns (session
    id, session) once the caller may use it."""
    Who = Depends(caller_dep)

    def lookup(sid: str | None, caller: Caller) -> tuple[str, SessionView]:
        sid = sid or SHARED
        if sid == SHARED:
            try:
                return SHARED, registry.get(SHARED)
            except NoSuchSession:
                raise HTTPException(404, detail=NO_SHARED) from None
        return private_session(registry, sid, caller)

    def by_header(
        x_pelvic_session: str | None = Header(
            None,
            description="a session id, or `mine` for your own private session (default: the "
            "shared session)",
        ),
        caller: Caller = Who,
    ) -> tuple[str, SessionView]:
        return lookup(x_pelvic_session, caller)

    def by_path(
        sid: str = Path(
            ...,
            description="`shared`, `mine` (your own private session) or a private session's "
            "id (yours, or any for the instructor)",
        ),
        caller: Caller = Who,
    ) -> tuple[str, SessionView]:
        return lookup(sid, caller)

    return by_header, by_path


def reveal_to(registry: SessionRegistry, caller: Caller):
    """Which private sessions' ids and state ``caller`` may see: all for the instructor, its
    own for a holder, none for anyone else."""
    if caller.instructor:
        return lambda _sid: True
    own = registry.owned(caller.credentials)
    return lambda sid: sid == own


def sessions_router(
    registry: SessionRegistry, instructor: Instructor | None = None, caller_dep=None
) -> APIRouter:
    r = router("/api/sessions", "sessions")
    teacher = instructor or Instructor(None)
    Who = Depends(caller_dep or caller_of(teacher))

    def ends(opened_by: str) -> str:
        if opened_by == "api":
            return f"it ends after {registry.idle_s:g} s without calls"
        return f"it ends {registry.linger_s:g} s after its last page closed"

    @r.get("")
    def list_sessions(caller: Caller = Who) -> dict[str, Any]:
        """The sessions that run, their worker and real-time factor, and the capacity. A
        private session is listed (with its id) only to its holder and to the instructor's
        bearer token; everyone else reads how many there are and the lowest real-time factor
        of all sessions (how well the server keeps up)."""
        reveal = reveal_to(registry, caller)
        return finite(
            {
                "mode": registry.mode,
                "shared_demo": registry.has_shared,
                "sessions": registry.list(reveal),
                "private_sessions": registry.count_private(),
                "realtime_factor_min": registry.realtime_factor_min(),  # every session's
                "robot_slots_free": registry.capacity_private,
                "sessions_per_address": registry.per_address,
                "workers": registry.workers(reveal),
            }
        )

    @r.get(f"/{MINE}")
    def my_session(caller: Caller = Who) -> dict[str, Any]:
        """Your own private session (your browser's, by its seat cookie, or your script's, by
        its token): its line of GET /api/sessions and where its routes are; `id` null (and
        `why`) when you hold none, so that a page can ask every second without an error."""
        own = registry.owned(caller.credentials)
        rows = [s for s in registry.list(lambda sid: sid == own) if s["id"] == own]
        if own is None or not rows:
            return {"id": None, "why": no_own(registry).detail}
        registry.get(own)  # a call: a page's session lingers from here
        return finite({**rows[0], "api": f"/api/sessions/{own}"})

    @r.post("", status_code=201)
    def open_session(response: Response, caller: Caller = Who) -> dict[str, Any]:
        """Open a private session (private mode only). The answer's `token`, given only here,
        is its credential: send 'Authorization: Bearer <token>' with every call to
        /api/sessions/{id}/... (or /api/sessions/mine/...). One client (an address) holds
        one; asking again with your credential answers 200 with the session you hold."""
        own = registry.owned(caller.credentials)
        if own is not None and not caller.instructor:
            response.status_code = 200
            return {
                "id": own,
                "token": None,
                "api": f"/api/sessions/{own}",
                "note": "you hold this private session already (one a client): use it with "
                "the credential you have",
            }
        token = new_credential()
        try:
            sid, _session = registry.open_private(
                credential=token,
                address=caller.address,
                opened_by="api",
                beyond_limit=caller.instructor,  # with an instructor, the instructor decides
            )
        except SessionsDisabled as exc:
            raise conflict(f"{exc}; its routes are /api/<route>") from None
        except AddressFull as exc:
            ask = " or ask the instructor for one" if teacher.enabled else ""
            raise HTTPException(
                429,
                detail=f"{exc}: use the one you hold (GET /api/sessions/{MINE} with your "
                f"credential), end it (DELETE /api/sessions/{MINE}){ask}",
                headers={"Retry-After": f"{registry.linger_s:.0f}"},
            ) from None
        except PoolFull:
            watch = (
                " Meanwhile watch the shared demo: GET /api/state." if registry.has_shared else ""
            )
            ask = " The instructor may end one." if teacher.enabled else ""
            raise HTTPException(
                503,
                detail=f"the workers are full: {registry.count_private()} private sessions "
                f"hold every robot slot. Try again in {RETRY_S} s or later (a browser's "
                f"session ends {registry.linger_s:g} s after its page closed, a script's after "
                f"{registry.idle_s:g} s without calls).{watch}{ask}",
                headers={"Retry-After": str(RETRY_S)},
            ) from None
        return {
            "id": sid,
            "token": token,
            "api": f"/api/sessions/{sid}",
            "note": "send 'Authorization: Bearer <token>' with every call to "
            f"/api/sessions/{sid}/...; the token is shown only now; {ends('api')}",
        }

    @r.delete("/{sid}")
    def close_session(
        sid: str = Path(..., description="`mine` or a private session's id"),
        caller: Caller = Who,
    ) -> dict[str, Any]:
        """End a private session: your own, or (the instructor) any."""
        if sid == SHARED:
            raise conflict("the shared session runs as long as the server")
        sid, _session = private_session(registry, sid, caller)
        registry.close(sid)
        return {"id": sid, "closed": True}

    return r
