"""The HTTP API (FastAPI): thin routes that write intent and read published frames.

Routes (INTERFACES.md): ``GET /api/health``; ``GET``/``PUT /api/params``;
``POST /api/sim/pause|resume|reset|step`` (and ``PUT /api/sim/speed``); ``GET /api/state``;
``POST /api/runs`` and ``GET /api/runs/{id}``; ``GET /`` (the page framing the viser scene)
and ``GET /report``.

The request and response models are generated from :func:`controller.params.spec`, so every
range lives in ``controller/params.py``; requests are converted to
:class:`~controller.params.ControllerParams` at the edge (cross-field checks such as
"horizon >= one MPC sample" come from its ``validated()``). Bad input -- NaN or infinity (as
numbers or strings), out of range, wrong type, unknown fields or methods -- gets a 422 whose
``detail`` is one readable line (the full list is under ``errors``); the live simulation
never sees it.
"""

from __future__ import annotations

import math
import threading
import time
import traceback
import uuid
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any, Literal

from fastapi import APIRouter, FastAPI, HTTPException, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse
from pydantic import BaseModel, ConfigDict, Field, create_model

from app.web.live import SPEED_MAX, SPEED_MIN, LiveSim
from app.web.report_page import render_report_page
from controller.params import GROUPS, METHODS, ControllerParams, spec

ROOT = Path(__file__).resolve().parents[2]
STATIC_DIR = ROOT / "static"
MethodName = Literal[METHODS]  # type: ignore[valid-type]
APPLY_TIMEOUT_S = 5.0  # how long a handler waits for the loop to take its intent


# -- models generated from controller.params.spec ------------------------------------------
def _field(meta: dict[str, Any], required: bool) -> tuple[Any, Any]:
    """A pydantic (type, Field) pair from one field's metadata (strict, finite, ranged)."""
    default = ... if required else None
    desc = meta.get("label", "")
    if meta.get("unit"):
        desc += f" [{meta['unit']}]"
    if meta["type"] == "bool":
        typ: Any = bool
        return (typ if required else typ | None, Field(default, strict=True, description=desc))
    typ = int if meta["type"] == "int" else float
    return (
        typ if required else typ | None,
        Field(default, ge=meta.get("min"), le=meta.get("max"), strict=True,
              allow_inf_nan=False, description=desc),
    )


def _group_models() -> tuple[dict[str, type[BaseModel]], dict[str, type[BaseModel]]]:
    """(full models, partial-update models) per parameter group."""
    full, partial = {}, {}
    defaults = ControllerParams()
    for group in GROUPS:
        meta = spec(getattr(defaults, group))
        cls_name = type(getattr(defaults, group)).__name__
        cfg = ConfigDict(extra="forbid")
        full[group] = create_model(
            f"{cls_name}Model", __config__=cfg,
            **{k: _field(m, required=True) for k, m in meta.items()},
        )
        partial[group] = create_model(
            f"{cls_name}Update", __config__=cfg,
            **{k: _field(m, required=False) for k, m in meta.items()},
        )
    return full, partial


GROUP_MODELS, GROUP_UPDATES = _group_models()
ParamsModel = create_model(
    "ParamsModel",
    __config__=ConfigDict(extra="forbid"),
    **{g: (GROUP_MODELS[g], ...) for g in GROUPS},
    methods=(list[MethodName], Field(..., description="robots shown live, one per method")),
    control_dt=(float, Field(..., description="control period [s] (fixed)")),
)
ParamsUpdate = create_model(
    "ParamsUpdate",
    __config__=ConfigDict(extra="forbid"),
    **{g: (GROUP_UPDATES[g] | None, None) for g in GROUPS},
    methods=(list[MethodName] | None,
             Field(None, min_length=1, max_length=len(METHODS),
                   description="methods to show live (fixed, redundancy, mpc)")),
)
RunRequest = create_model(
    "RunRequest",
    __config__=ConfigDict(extra="forbid"),
    method=(MethodName, Field("mpc", description="walking method")),
    seed=(int | None, Field(None, strict=True, description="seed of a small perturbation")),
    **{g: (GROUP_UPDATES[g] | None, None) for g in GROUPS},
)


class SpeedRequest(BaseModel):
    model_config = ConfigDict(extra="forbid")
    speed: float = Field(..., ge=SPEED_MIN, le=SPEED_MAX, strict=True, allow_inf_nan=False,
                         description="playback speed [x real time]")


class RobotState(BaseModel):
    method: str
    t: float = Field(description="the robot's time since its (re)start [s]")
    step_index: int
    step_length: float = Field(description="length of the step in progress [m]")
    fell: bool
    fall_reason: str | None
    success: bool | None = Field(description="outcome of the last finished (or failed) walk")
    walks_completed: int
    falls: int
    waist_angle_deg: float
    kappa: float | None
    yaw_momentum: float
    reach: list[float] | None = Field(description="hip-to-ankle / leg length, left and right")
    zmp_ref: list[float] | None
    zmp_measured: list[float] | None = Field(description="centre of pressure [m]")
    solver_failures: int
    params: dict[str, Any] = Field(description="walking parameters in force in this robot")


class StateResponse(BaseModel):
    seq: int
    clock: float = Field(description="simulated time since the live session started [s]")
    paused: bool
    speed: float
    realtime_factor: float | None = Field(description="simulated / wall time, last seconds")
    compute_realtime_factor: float | None = Field(
        description="simulated / compute time: how fast the loop could run unpaced")
    robots: list[RobotState]


class RunStatus(BaseModel):
    id: str
    status: Literal["queued", "running", "done", "error"]
    summary: dict[str, Any] | None = None
    error: str | None = None


# -- helpers --------------------------------------------------------------------------------
def _finite(x: Any) -> Any:
    """JSON-safe: non-finite floats -> None, recursively."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    if hasattr(x, "item") and not isinstance(x, (str, bytes)):  # numpy scalar
        return _finite(x.item())
    return x


def params_dict(params: ControllerParams, methods: tuple[str, ...]) -> dict[str, Any]:
    out: dict[str, Any] = {g: dict(vars(getattr(params, g))) for g in GROUPS}
    out["methods"] = list(methods)
    out["control_dt"] = params.control_dt
    return out


def _updates(body: BaseModel) -> dict[str, dict[str, Any]]:
    return {
        g: getattr(body, g).model_dump(exclude_none=True)
        for g in GROUPS
        if getattr(body, g) is not None
    }


def _unprocessable(message: str) -> HTTPException:
    return HTTPException(status_code=422, detail=message)


def _error_line(err: dict[str, Any]) -> str:
    loc = ".".join(str(p) for p in err.get("loc", ()) if p != "body")
    msg = err.get("msg", "invalid")
    given = err.get("input")
    tail = f" (got {given!r})" if given is not None and not isinstance(given, dict) else ""
    return f"{loc}: {msg}{tail}" if loc else f"{msg}{tail}"


class RunBusy(RuntimeError):
    """Too many headless runs queued or running."""


class RunManager:
    """Headless runs (``app.runs.run``) in one background worker thread.

    Bounded: at most ``max_pending`` runs queued or running (they share the CPU with the live
    loop), and only the ``keep`` most recent records are kept.
    """

    def __init__(self, max_wall_s: float = 600.0, max_pending: int = 4, keep: int = 100):
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="headless-run")
        self._lock = threading.Lock()
        self._runs: dict[str, dict[str, Any]] = {}
        self.max_wall_s = max_wall_s
        self.max_pending = max_pending
        self.keep = keep

    def submit(self, params: ControllerParams, seed: int | None) -> str:
        """Queue a run; RunBusy if ``max_pending`` runs are already queued or running."""
        run_id = uuid.uuid4().hex[:12]
        with self._lock:
            pending = sum(r["status"] in ("queued", "running") for r in self._runs.values())
            if pending >= self.max_pending:
                raise RunBusy(f"{pending} headless runs are already queued or running; "
                              "poll GET /api/runs/{id} and try again when one is done")
            self._runs[run_id] = {"id": run_id, "status": "queued", "summary": None,
                                  "error": None, "submitted": time.time()}
            finished = [k for k, r in self._runs.items() if r["status"] in ("done", "error")]
            for old in finished[: max(0, len(self._runs) - self.keep)]:
                del self._runs[old]
        self._pool.submit(self._work, run_id, params, seed)
        return run_id

    def _work(self, run_id: str, params: ControllerParams, seed: int | None) -> None:
        from app.runs import RunConfig, run

        self._set(run_id, status="running")
        try:
            cfg = RunConfig(params=params, seed=seed,
                            perturbation=0.01 if seed is not None else 0.0)
            summary = run(cfg, max_wall_s=self.max_wall_s).summary()
            self._set(run_id, status="done", summary=_finite(summary))
        except Exception as exc:  # noqa: BLE001 - reported through GET /api/runs/{id}
            traceback.print_exc()
            self._set(run_id, status="error", error=f"{type(exc).__name__}: {exc}")

    def _set(self, run_id: str, **changes: Any) -> None:
        with self._lock:
            self._runs[run_id].update(changes)

    def get(self, run_id: str) -> dict[str, Any] | None:
        with self._lock:
            rec = self._runs.get(run_id)
            return dict(rec) if rec else None

    def shutdown(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)


# -- the app --------------------------------------------------------------------------------
def create_app(live: LiveSim, viser_port: int = 8080, runs: RunManager | None = None) -> FastAPI:
    """The FastAPI app around a running :class:`LiveSim` (started and stopped by the caller)."""
    runs = runs or RunManager()
    app = FastAPI(
        title="pelvic-walk",
        description="Humanoid walking with pelvic rotation planned by MPC: the live teaching "
        "tool's API. The 3-D scene is served by viser on its own port.",
        version="0.1.0",
    )
    app.state.live = live
    app.state.runs = runs
    app.state.viser_port = viser_port

    @app.exception_handler(RequestValidationError)
    async def _validation(_request: Request, exc: RequestValidationError) -> JSONResponse:
        errors = exc.errors()
        detail = "; ".join(_error_line(e) for e in errors[:3]) or "invalid request"
        safe = [{k: _finite(v) if k != "ctx" else str(v) for k, v in e.items()} for e in errors]
        return JSONResponse(status_code=422, content={"detail": detail, "errors": safe})

    health = APIRouter(prefix="/api", tags=["health"])
    params_router = APIRouter(prefix="/api/params", tags=["params"])
    sim = APIRouter(prefix="/api/sim", tags=["playback"])
    state = APIRouter(prefix="/api/state", tags=["state"])
    runs_router = APIRouter(prefix="/api/runs", tags=["runs"])
    pages = APIRouter(tags=["pages"])

    @health.get("/health")
    def get_health() -> dict[str, Any]:
        frame = live.frame()
        return {
            "status": "ok" if live.running else "degraded",
            "live_running": live.running,
            "live_error": live.error,
            "frame_seq": frame.seq if frame else None,
            "viser_port": viser_port,
        }

    @params_router.get("", response_model=ParamsModel)
    def get_params() -> dict[str, Any]:
        intent = live.intent
        return params_dict(intent.params, intent.methods)

    @params_router.get("/spec")
    def get_params_spec() -> dict[str, Any]:
        """Ranges, steps, units and defaults of every parameter (controller/params.py)."""
        defaults = ControllerParams()
        return _finite({g: spec(getattr(defaults, g)) for g in GROUPS})

    @params_router.put("", response_model=ParamsModel)
    def put_params(body: ParamsUpdate) -> dict[str, Any]:  # type: ignore[valid-type]
        try:
            version = live.update_params(**_updates(body))
        except (ValueError, TypeError) as exc:
            raise _unprocessable(str(exc)) from None
        if body.methods is not None:  # type: ignore[attr-defined]
            version = live.set_methods(body.methods)  # type: ignore[attr-defined]
        live.wait_applied(version, APPLY_TIMEOUT_S)
        intent = live.intent
        return params_dict(intent.params, intent.methods)

    def _playback(action) -> dict[str, Any]:
        version = action()
        frame = live.wait_applied(version, APPLY_TIMEOUT_S)
        intent = live.intent
        return {
            "paused": intent.paused,
            "speed": intent.speed,
            "applied": frame is not None,
            "t": [r.t for r in frame.robots] if frame else None,
        }

    @sim.post("/pause")
    def pause() -> dict[str, Any]:
        """Stop the clock (the robots hold still)."""
        return _playback(live.pause)

    @sim.post("/resume")
    def resume() -> dict[str, Any]:
        return _playback(live.resume)

    @sim.post("/reset")
    def reset() -> dict[str, Any]:
        """Restart every robot from standing (t = 0)."""
        return _playback(live.reset)

    @sim.post("/step")
    def step() -> dict[str, Any]:
        """Pause and advance exactly one control period (5 ms)."""
        return _playback(live.step)

    @sim.put("/speed")
    def put_speed(body: SpeedRequest) -> dict[str, Any]:
        return _playback(lambda: live.set_speed(body.speed))

    @state.get("", response_model=StateResponse)
    def get_state() -> dict[str, Any]:
        frame = live.frame() or live.wait_frame(timeout=APPLY_TIMEOUT_S)
        if frame is None:
            raise HTTPException(503, detail="the live simulation has not produced a frame yet")
        robots = []
        for r in frame.robots:
            tick = r.tick
            robots.append({
                "method": r.method,
                "t": r.t,
                "step_index": r.step_index,
                "step_length": r.step_length,
                "fell": r.fell,
                "fall_reason": r.fall_reason,
                "success": r.last_walk_success,
                "walks_completed": r.walks_completed,
                "falls": r.falls,
                "waist_angle_deg": math.degrees(r.waist_angle),
                "kappa": tick.kappa if tick else None,
                "yaw_momentum": r.yaw_momentum,
                "reach": list(tick.reach) if tick else None,
                "zmp_ref": list(tick.zmp_ref) if tick else None,
                "zmp_measured": list(r.cop) if r.cop is not None else None,
                "solver_failures": r.solver_failures,
                "params": dict(vars(r.params.walk)),
            })
        return _finite({
            "seq": frame.seq,
            "clock": frame.clock,
            "paused": frame.paused,
            "speed": frame.speed,
            "realtime_factor": frame.realtime_factor,
            "compute_realtime_factor": frame.compute_realtime_factor,
            "robots": robots,
        })

    @runs_router.post("", response_model=RunStatus, status_code=202)
    def post_run(body: RunRequest) -> dict[str, Any]:  # type: ignore[valid-type]
        """Start a headless closed-loop run; poll ``GET /api/runs/{id}`` for its summary."""
        try:
            params = ControllerParams().replace(method=body.method, **_updates(body))  # type: ignore[attr-defined]
        except (ValueError, TypeError) as exc:
            raise _unprocessable(str(exc)) from None
        try:
            run_id = runs.submit(params, body.seed)  # type: ignore[attr-defined]
        except RunBusy as exc:
            raise HTTPException(429, detail=str(exc)) from None
        return runs.get(run_id) or {}

    @runs_router.get("/{run_id}", response_model=RunStatus)
    def get_run(run_id: str) -> dict[str, Any]:
        rec = runs.get(run_id)
        if rec is None:
            raise HTTPException(404, detail=f"no run with id {run_id!r}")
        return rec

    @pages.get("/", response_class=HTMLResponse, include_in_schema=False)
    def index(request: Request) -> HTMLResponse:
        host = request.url.hostname or "127.0.0.1"
        if ":" in host:  # IPv6 literal
            host = f"[{host}]"
        page = (STATIC_DIR / "index.html").read_text(encoding="utf-8")
        page = page.replace("{{VISER_URL}}", f"http://{host}:{viser_port}/")
        return HTMLResponse(page)

    @pages.get("/report", response_class=HTMLResponse, include_in_schema=False)
    def report() -> HTMLResponse:
        return HTMLResponse(render_report_page(ROOT / "report"))

    @pages.get("/report/{path:path}", include_in_schema=False)
    def report_file(path: str) -> FileResponse:
        base = (ROOT / "report").resolve()
        target = (base / path).resolve()
        if base not in target.parents or not target.is_file():
            raise HTTPException(404, detail="not found")
        return FileResponse(target)

    @pages.get("/static/{path:path}", include_in_schema=False)
    def static_file(path: str) -> FileResponse:
        target = (STATIC_DIR / path).resolve()
        if STATIC_DIR.resolve() not in target.parents or not target.is_file():
            raise HTTPException(404, detail="not found")
        return FileResponse(target)

    for router in (health, params_router, sim, state, runs_router, pages):
        app.include_router(router)
    return app
