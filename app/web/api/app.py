""":func:`create_app`: the FastAPI app around the server's live sessions."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from fastapi import Depends, FastAPI
from fastapi.exceptions import RequestValidationError

from app.live.registry import SessionRegistry
from app.live.session import SessionView
from app.web.addresses import ClientAddresses
from app.web.api.edges import finite, router, validation_handler
from app.web.api.headless import RunManager, run_client, runs_router
from app.web.api.live import session_router
from app.web.api.pages import mount_docs_assets, pages_router
from app.web.api.recording import recording_router
from app.web.api.sessions import Caller, caller_of, resolvers, reveal_to, sessions_router
from app.web.api.strategies import strategies_router
from app.web.auth import Instructor
from controller.params import GROUPS, OWN_PARAMS, ControllerParams, spec
from pelvic_walk.core.report_dir import ReportChoice, choose_report


def create_app(
    live: SessionView | SessionRegistry,
    viser_port: int = 8080,
    runs: RunManager | None = None,
    report_dir: Path | None = None,
    health_extra: Callable[[], dict[str, Any]] | None = None,
    instructor: Instructor | None = None,
    addresses: ClientAddresses | None = None,
) -> FastAPI:
    """The app around the server's sessions (started and stopped by the caller).

    Args:
        live: the sessions (a registry), or one session served as the shared one.
        viser_port: where the page finds the 3-D scene.
        runs: the headless-run manager (default: a new one).
        report_dir: what ``/report`` serves (``serve --report DIR``); None: the latest
            report this user's ``pelvic-walk experiments`` wrote outside temporary folders,
            looked up at each request, else the reference report
            (:func:`pelvic_walk.core.report_dir.choose_report`).
        health_extra: more fields for ``GET /api/health`` (e.g. the display's state).
        instructor: with a token, only its bearer changes the shared session.
        addresses: how a request's client address is read (behind a trusted proxy, its
            X-Forwarded-For); the display reads the scene's connections with the same.
    """
    instructor = instructor or Instructor(None)
    addresses = addresses or ClientAddresses()
    registry = live if isinstance(live, SessionRegistry) else SessionRegistry.around(live)
    runs = runs or RunManager()
    app = FastAPI(
        title="pelvic-walk",
        description="Humanoid walking with pelvic rotation planned by MPC: the live teaching "
        "tool's API. The 3-D scene is served by viser on its own port. Session-scoped routes "
        "act on the shared session unless an `X-Pelvic-Session` header or the "
        "`/api/sessions/{sid}/...` prefix names another (`mine`: your own private session). "
        "A private session answers only to its holder (a browser's seat cookie, or the "
        "bearer token POST /api/sessions gave) and to the instructor's bearer token.",
        version="0.1.0",
        docs_url=None,  # served by pages_router from local files: the default uses a CDN
        redoc_url=None,
    )
    app.state.registry = registry
    app.state.runs = runs
    app.state.instructor = instructor
    app.state.viser_port = viser_port
    app.add_exception_handler(RequestValidationError, validation_handler)  # type: ignore[arg-type]

    health = router("/api", "health")
    caller = caller_of(instructor, addresses)
    Who = Depends(caller)

    @health.get("/health")
    def get_health(who: Caller = Who) -> dict[str, Any]:
        """``ok`` while every session's loop runs; workers and their deaths, if any (a
        worker's robots name a private session only to its holder and the instructor); with
        ``serve --ray`` the cluster: its seats and nodes, their workers, robots and load."""
        shared = registry.shared if registry.has_shared else None
        frame = shared.frame() if shared is not None else None
        pool = registry.pool
        deaths = [d.describe() for d in pool.deaths[-5:]] if pool is not None else []
        workers = registry.workers(reveal_to(registry, who))
        shared_ok = shared is None or (shared.running and shared.error is None)
        healthy = shared_ok and all(w["alive"] for w in workers)
        out: dict[str, Any] = {
            "status": "ok" if healthy else "degraded",
            "live_running": shared.running if shared is not None else None,
            "live_error": shared.error if shared is not None else None,
            "frame_seq": frame.seq if frame else None,
            "realtime_factor": frame.realtime_factor if frame else None,
            "viser_port": viser_port,
            "sessions_mode": registry.mode,
            "shared_demo": shared is not None,
            "instructor": instructor.enabled,
            "sessions": int(shared is not None) + registry.count_private(),
            "workers": workers,
            "worker_deaths": deaths,
        }
        nodes = pool.nodes() if pool is not None else None
        if nodes is not None and pool is not None:  # serve --ray: the cluster behind
            out["cluster"] = {
                "where": getattr(pool.engine, "where", None),
                "robot_cpu": getattr(pool.engine, "robot_cpu", None),
                "robot_seats": pool.capacity,
                "robots": pool.robots(),
                "nodes": nodes,
            }
        if health_extra is not None:
            out.update(health_extra())
        return finite(out)

    spec_router = router("/api", "params")  # (its own router: tagged once in /docs)

    @spec_router.get("/params/spec")
    def get_params_spec() -> dict[str, Any]:
        """Ranges, steps, units, defaults and paper values of every parameter
        (controller/params.py, the one source of them), then the server's strategies' own
        (a group named by the strategy: ``gain.k`` is ``{"gain": {"k": {...}}}``)."""
        defaults = ControllerParams()
        out = {g: spec(getattr(defaults, g)) for g in GROUPS}
        for name, cls in list(OWN_PARAMS.items()):
            out.setdefault(name, spec(cls))
        return finite(out)

    by_header, by_path = resolvers(registry, caller)

    def reports() -> ReportChoice:
        return choose_report(report_dir)

    for r in (
        health,
        spec_router,
        session_router("/api", by_header, instructor, private=registry.mode == "private"),
        sessions_router(registry, instructor, caller),
        session_router(
            "/api/sessions/{sid}", by_path, instructor, private=registry.mode == "private"
        ),
        recording_router("/api", by_header),
        recording_router("/api/sessions/{sid}", by_path),
        runs_router(runs, run_client(registry), caller),
        strategies_router(),
        pages_router(app, viser_port, reports, instructor, private=registry.mode == "private"),
    ):
        app.include_router(r)
    mount_docs_assets(app)
    return app
