"""Routes that act on one live session: parameters, playback, state, horizon, QP, seek, push.

Thin: each route writes intent (and waits until the loop has carried it out) or reads the
frame the displays show. The same routes serve ``/api/...`` (the shared session, or the one
named by the ``X-Pelvic-Session`` header) and ``/api/sessions/{sid}/...``.

Paused, speed, the instant shown and the kept range come from the session's one account of
its playback (:meth:`~app.live.session.SessionView.playback`), as in the panel and
``GET /api/sessions``. With an instructor (``serve --instructor-token``), a route that changes
the shared session needs ``Authorization: Bearer <token>``: 401 without, 403 with a wrong one.
A private session answers only to its holder and the instructor (``app.web.api.sessions``):
every route, reading ones included, is 404 to anyone else.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from fastapi import APIRouter, Depends, HTTPException, Query, Request
from fastapi.security import HTTPAuthorizationCredentials

from app.live.intent import check_methods
from app.live.pool import PoolFull
from app.live.registry import SHARED
from app.live.session import SessionView
from app.web.api.edges import conflict, finite, router, unprocessable
from app.web.api.models import (
    HorizonResponse,
    ParamsModel,
    ParamsUpdate,
    PushRequest,
    QpResponse,
    SeekRequest,
    SpeedRequest,
    StateResponse,
    StepRequest,
    params_dict,
    robot_of,
    updates,
)
from app.web.auth import BEARER, INSTRUCTOR_COOKIE, Instructor
from controller import strategy
from pelvic_walk.core import robots as robots_
from pelvic_walk.core.frames import LiveFrame, RobotFrame

# How long a handler waits for the loop to take its intent before answering anyway (a
# playback answer then says "applied": false): well under the 5 s clients often default to
# (httpx, requests' common settings), so a busy machine gives a late answer, not a timeout.
APPLY_TIMEOUT_S = 3.0


def _shown(session: SessionView) -> LiveFrame:
    frame = session.shown_frame() or session.wait_frame(timeout=APPLY_TIMEOUT_S)
    if frame is None:
        raise HTTPException(503, detail="the live simulation has not produced a frame yet")
    return frame


def state_of(sid: str, session: SessionView) -> dict[str, Any]:
    """``GET /api/state``: the shown frame of every robot, the clock and what is kept."""
    frame = _shown(session)
    playback = session.playback()
    span = playback.kept
    differ = robots_.differing(session.intent.robots)
    robots = [
        {
            "label": r.method,
            "method": r.method,  # (its label: the key of old)
            "strategy": r.strategy,
            "settings": differ.get(r.method, {}),
            "t": r.t,
            "step_index": r.step_index,
            "in_dsp": r.in_dsp,
            "step_length": r.step_length,
            "status": r.status,
            "fell": r.fell,
            "fall_reason": r.fall_reason,
            "error": r.error,
            "strategy_ms": r.strategy_ms,
            "fell_at": r.fell_clock,
            "finished": r.finished,
            "waiting": r.waiting,
            "success": r.last_walk_success,
            "walks_completed": r.walks_completed,
            "falls": r.falls,
            "waist_angle_deg": math.degrees(r.waist_angle),
            "kappa": r.kappa_low,  # the key of old: kappa_low's value
            "kappa_low": r.kappa_low,
            "kappa_legs": r.kappa_legs,
            "yaw_momentum": r.yaw_momentum,
            "reach": r.reach,
            "zmp_ref": r.zmp_ref,
            "zmp_measured": r.cop,
            "pushing": r.pushing,
            "solver_failures": r.solver_failures,
            "params": dict(vars(r.params.walk)),
        }
        for r in frame.robots
    ]
    return finite(
        {
            "session": sid,
            "seq": frame.seq,
            "clock": frame.clock,
            "shown_t": playback.shown_t,
            "present": playback.present,
            "kept": {
                "start": span[0] if span else None,
                "end": span[1] if span else None,
                "frames": len(session.frames),
                "megabytes": round(session.frames.nbytes() / 1e6, 2),
            },
            "paused": playback.paused,
            "speed": playback.speed,
            "realtime_factor": playback.realtime_factor,
            "compute_realtime_factor": playback.compute_realtime_factor,
            "robots": robots,
        }
    )


def _shown_robot(session: SessionView, method: str | None) -> tuple[LiveFrame, RobotFrame]:
    """The shown frame and its robot labelled ``method`` (by default the first running the
    MPC, else the first); 422 naming the robots shown when there is no such robot."""
    frame = _shown(session)
    robot = (
        frame.robot(method)
        if method
        else next((r for r in frame.robots if r.strategy == strategy.MPC), frame.robots[0])
    )
    if robot is None:
        shown = ", ".join(r.method for r in frame.robots)
        raise unprocessable(f"no robot {method!r} is shown (robots: {shown})")
    return frame, robot


def horizon_of(sid: str, session: SessionView, method: str | None) -> dict[str, Any]:
    """``GET /api/horizon``: one robot's plan over the horizon at the shown instant."""
    frame, robot = _shown_robot(session, method)
    h = robot.horizon
    if h is None:
        raise conflict("the robot has not ticked since it (re)started: resume or step first")
    deg = 180.0 / math.pi
    return finite(
        {
            "session": sid,
            "method": robot.method,
            "strategy": robot.strategy,
            "clock": frame.clock,
            "t": h.t,
            **h.plane_columns(),
            "theta_ref_deg": h.theta_ref * deg,
            "theta_deg": h.theta * deg,
        }
    )


def qp_of(sid: str, session: SessionView, method: str | None) -> dict[str, Any]:
    """``GET /api/qp``: what one robot's four QPs did at the shown instant."""
    frame, robot = _shown_robot(session, method)
    rec = robot.qp
    if rec is None:
        raise conflict(
            "the robot has not ticked since it (re)started, or its strategy stopped it: "
            "resume or step first"
        )
    return finite(
        {
            **rec.to_dict(),  # (its "method" is the strategy's: the label goes below)
            "session": sid,
            "method": robot.method,
            "strategy": robot.strategy,
            "clock": frame.clock,
        }
    )


ROBOT_QUERY = (
    "the robot's label (GET /api/state; default: the first running the MPC, else the first)"
)


def _one(method: str | None, robot: str | None) -> str | None:
    """The robot a query names (``robot`` or ``method``, the name of old); 422 if both differ."""
    if method and robot and method != robot:
        raise unprocessable(f"robot {robot!r} and method {method!r}: name one")
    return robot or method


def instructor_check(
    instructor: Instructor,
    resolve: Callable[..., tuple[str, SessionView]],
    private: bool = False,
) -> Callable[..., tuple[str, SessionView]]:
    """A FastAPI dependency: the session to change, once the caller may change it (a private
    session: its holder or the instructor, checked by ``resolve``; the shared one: anyone,
    unless an instructor drives it: then its token). ``private``: the server runs private
    sessions (the refusal tells students how to get one)."""

    session, bearer = Depends(resolve), Depends(BEARER)
    students = (
        "students: your browser's page drives your own session (the API: "
        "/api/sessions/mine/...), a script opens one with POST /api/sessions; or watch"
        if private
        else "students: watch it (reading needs no token)"
    )

    def writable(
        s: tuple[str, SessionView] = session,
        credentials: HTTPAuthorizationCredentials | None = bearer,
        # (FastAPI always gives it; None only when called directly, as a test does)
        request: Request = None,  # type: ignore[assignment]
    ) -> tuple[str, SessionView]:
        if not instructor.enabled or s[0] != SHARED:
            return s
        cookie = request.cookies.get(INSTRUCTOR_COOKIE) if request is not None else None
        if credentials is None and instructor.is_cookie(cookie):
            return s  # the instructor's browser (its page gave the token once)
        if credentials is None:
            raise HTTPException(
                401,
                detail="the instructor drives the shared session: send the header "
                f"'Authorization: Bearer <instructor token>' to change it ({students})",
                headers={"WWW-Authenticate": "Bearer"},
            )
        if not instructor.is_token(credentials.credentials):
            raise HTTPException(
                403,
                detail="wrong instructor token: the shared session was not changed"
                + (
                    " (a private session's token acts on /api/sessions/mine/...)" if private else ""
                ),
            )
        return s

    return writable


def session_router(
    prefix: str,
    resolve: Callable[..., tuple[str, SessionView]],
    instructor: Instructor | None = None,
    private: bool = False,
) -> APIRouter:
    """The session-scoped routes under ``prefix``; ``resolve`` is a FastAPI dependency
    returning (session id, session) once the caller may use it; changes go through
    :func:`instructor_check`."""
    r = router(prefix, None)  # each route is tagged (/docs)
    Session = Depends(resolve)
    Writable = Depends(instructor_check(instructor or Instructor(None), resolve, private))

    def _playback(session: SessionView, action: Callable[[], Any]) -> dict[str, Any]:
        try:
            ticket = action()
        except ValueError as exc:
            raise unprocessable(str(exc)) from None
        frame = session.wait_applied(ticket, APPLY_TIMEOUT_S)
        intent = session.intent
        return {
            "paused": intent.paused,
            "speed": intent.speed,
            "applied": frame is not None,
            "t": [x.t for x in frame.robots] if frame else None,
            "clock": frame.clock if frame else None,
        }

    @r.get("/params", response_model=ParamsModel, tags=["params"])
    def get_params(s: tuple[str, SessionView] = Session) -> dict[str, Any]:
        """The shared parameters (the paper's groups, then each strategy's own as a group
        named by it), the robots shown (``robots``: label, strategy, their own settings)."""
        intent = s[1].intent
        return finite(params_dict(intent.params, intent.robots))

    @r.put("/params", response_model=ParamsModel, tags=["params"])
    def put_params(
        body: ParamsUpdate,  # type: ignore[valid-type]
        s: tuple[str, SessionView] = Writable,
    ) -> dict[str, Any]:
        """Change some parameters (others keep their value): gains and a strategy's own
        parameters act on the next tick, walking parameters from the next step. With
        ``robot`` (a label) only that robot's own settings change; without, every robot's
        (the shared value). ``robots`` (or ``methods``, one robot per strategy) replaces the
        robots shown first; then the parameters apply."""
        session = s[1]
        b: Any = body
        try:  # everything checked before anything changes
            groups = updates(body)
            session.intent.params.replace(**groups)  # known parameters, in range
            shown = session.intent.robots
            if b.robots is not None:
                shown = robots_.check_all([robot_of(x) for x in b.robots])
            elif b.methods is not None:
                shown = robots_.of_methods(check_methods(b.methods))
            if b.robot is not None and b.robot not in [r.key for r in shown]:
                keys = ", ".join(r.key for r in shown)
                raise ValueError(f"no robot {b.robot!r} is shown (robots: {keys})")
            ticket = None
            if b.robots is not None or b.methods is not None:
                ticket = session.set_robots(shown)
            if groups or ticket is None:
                ticket = session.update_params(target=b.robot, **groups)
        except (ValueError, TypeError) as exc:
            raise unprocessable(str(exc)) from None
        except PoolFull as exc:
            raise HTTPException(503, detail=f"no room for these robots now: {exc}") from None
        session.wait_applied(ticket, APPLY_TIMEOUT_S)
        intent = session.intent
        return finite(params_dict(intent.params, intent.robots))

    @r.post("/sim/pause", tags=["playback"])
    def pause(s: tuple[str, SessionView] = Writable) -> dict[str, Any]:
        """Stop the clock (the robots hold still)."""
        return _playback(s[1], s[1].pause)

    @r.post("/sim/resume", tags=["playback"])
    def resume(s: tuple[str, SessionView] = Writable) -> dict[str, Any]:
        """Run again, from the present (a sought instant is left)."""
        return _playback(s[1], s[1].resume)

    @r.post("/sim/reset", tags=["playback"])
    def reset(s: tuple[str, SessionView] = Writable) -> dict[str, Any]:
        """Restart every robot from standing (t = 0), all together."""
        return _playback(s[1], s[1].reset)

    @r.post("/sim/step", tags=["playback"])
    def step(
        body: StepRequest | None = None, s: tuple[str, SessionView] = Writable
    ) -> dict[str, Any]:
        """Pause and advance one control period (5 ms), or to the next lift-off or landing
        (``{"until": "liftoff"}``) of the first walking robot."""
        until = body.until if body is not None else "tick"
        return _playback(s[1], lambda: s[1].step(until))

    @r.put("/sim/speed", tags=["playback"])
    def put_speed(body: SpeedRequest, s: tuple[str, SessionView] = Writable) -> dict[str, Any]:
        return _playback(s[1], lambda: s[1].set_speed(body.speed))

    @r.post("/sim/seek", response_model=StateResponse, tags=["playback"])
    def seek(body: SeekRequest, s: tuple[str, SessionView] = Writable) -> dict[str, Any]:
        """When paused, show the kept instant nearest to ``t`` [s of session clock] in the
        scene, the horizon inspector and the plots; ``GET /api/state`` reports it."""
        sid, session = s
        if not session.intent.paused:
            raise conflict("pause first: seeking shows a kept instant of a paused session")
        try:
            session.seek(body.t)
        except ValueError as exc:
            raise unprocessable(str(exc)) from None
        return state_of(sid, session)

    @r.post("/sim/push", tags=["playback"])
    def push(body: PushRequest, s: tuple[str, SessionView] = Writable) -> dict[str, Any]:
        """Push one robot's torso horizontally (MuJoCo ``xfrc_applied``) for ``duration`` s.
        The CoM MPC keeps its plan and eq. (19) moves the pelvis to bring the measured CoM back
        onto it; nothing moves the footsteps."""
        name = body.robot or body.method
        if body.robot and body.method and body.robot != body.method:
            raise unprocessable(f"robot {body.robot!r} and method {body.method!r}: name one")
        if not name:
            raise unprocessable("name the robot to push: robot (its label)")
        return _playback(s[1], lambda: s[1].push(name, body.force, body.duration))

    @r.get("/state", response_model=StateResponse, tags=["state"])
    def get_state(s: tuple[str, SessionView] = Session) -> dict[str, Any]:
        """Latest state and metrics of every robot (the sought instant while paused)."""
        return state_of(*s)

    @r.get("/horizon", response_model=HorizonResponse, tags=["state"])
    def get_horizon(
        method: str | None = Query(None, description=ROBOT_QUERY),
        robot: str | None = Query(None, description="the same as method"),
        s: tuple[str, SessionView] = Session,
    ) -> dict[str, Any]:
        """The robot's plan over the horizon at the shown instant (Fig. 5-7): predicted CoM
        and ZMP, ZMP reference and bounds, planned feet, reference and optimised pelvic angle;
        lists of equal length, one per horizon sample."""
        return horizon_of(s[0], s[1], _one(method, robot))

    @r.get("/qp", response_model=QpResponse, tags=["state"])
    def get_qp(
        method: str | None = Query(None, description=ROBOT_QUERY),
        robot: str | None = Query(None, description="the same as method"),
        s: tuple[str, SessionView] = Session,
    ) -> dict[str, Any]:
        """What each of the robot's four optimisations did at the shown instant (the CoM MPC,
        the pelvic MPC, the IK, the arm swing): status, iterations and time, the cost split
        into its named terms, every active constraint by name with its multiplier, and what
        the fallback did when a solve failed. Follows pause and seek like the horizon."""
        return qp_of(s[0], s[1], _one(method, robot))

    return r
