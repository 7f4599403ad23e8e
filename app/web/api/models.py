"""Request and response models. The parameters' models are generated from
:func:`controller.params.spec`, so every range lives in ``controller/params.py``; requests are
converted to :class:`~controller.params.ControllerParams` at the edge (cross-field checks such
as "horizon >= one MPC sample" come from its ``validated()``)."""

from __future__ import annotations

from typing import Annotated, Any, Literal, cast

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, create_model

from app.live.intent import PUSH_DURATION_MAX, PUSH_FORCE_MAX, SPEED_MAX, SPEED_MIN, STEP_UNTIL
from controller import strategy
from controller.params import GROUPS, ControllerParams, spec


def _registered(name: str) -> str:
    """A registered strategy's name (read at each request: the server's --strategy files
    add to the built-ins); ValueError, hence 422 with the choices, otherwise."""
    strategy.info(name)
    return name


# a robot: one of the paper's three methods or a strategy the server loaded (GET /api/strategies)
MethodName = Annotated[str, AfterValidator(_registered)]
METHODS_MAX = 16  # robots a request may name
STRICT = ConfigDict(extra="forbid")
# create_model(**fields): the values of a **dict must also fit its __config__, __base__... keywords
Fields = dict[str, Any]


def _field(meta: dict[str, Any], required: bool) -> tuple[Any, Any]:
    """A pydantic (type, Field) pair from one field's metadata (strict, finite, ranged)."""
    default = ... if required else None
    desc = meta.get("label", "")
    if meta.get("unit"):
        desc += f" [{meta['unit']}]"
    if meta.get("applies") == "step":
        desc += " (takes effect from the next step)"
    if meta.get("choices"):
        typ: Any = Literal[tuple(meta["choices"])]
        return (typ if required else typ | None, Field(default, description=desc))
    if meta["type"] == "bool":
        return (bool if required else bool | None, Field(default, strict=True, description=desc))
    typ = int if meta["type"] == "int" else float
    return (
        typ if required else typ | None,
        Field(
            default,
            ge=meta.get("min"),
            le=meta.get("max"),
            strict=True,
            allow_inf_nan=False,
            description=desc,
        ),
    )


def _group_models() -> tuple[dict[str, type[BaseModel]], dict[str, type[BaseModel]]]:
    """(full models, partial-update models) per parameter group."""
    full, partial = {}, {}
    defaults = ControllerParams()
    for group in GROUPS:
        meta = spec(getattr(defaults, group))
        cls_name = type(getattr(defaults, group)).__name__
        full[group] = create_model(
            f"{cls_name}Model",
            __config__=STRICT,
            **cast(Fields, {k: _field(m, required=True) for k, m in meta.items()}),
        )
        partial[group] = create_model(
            f"{cls_name}Update",
            __config__=STRICT,
            **cast(Fields, {k: _field(m, required=False) for k, m in meta.items()}),
        )
    return full, partial


GROUP_MODELS, GROUP_UPDATES = _group_models()
ParamsModel = create_model(
    "ParamsModel",
    __config__=STRICT,
    **cast(Fields, {g: (GROUP_MODELS[g], ...) for g in GROUPS}),
    methods=(list[MethodName], Field(..., description="robots shown live, one per method")),
    control_dt=(float, Field(..., description="control period [s] (fixed)")),
)
ParamsUpdate = create_model(
    "ParamsUpdate",
    __config__=STRICT,
    **cast(Fields, {g: (GROUP_UPDATES[g] | None, None) for g in GROUPS}),
    methods=(
        cast(Any, list[MethodName] | None),  # a UnionType is not a type[Any] to mypy
        Field(
            None,
            min_length=1,
            max_length=METHODS_MAX,
            description="methods to show live: fixed, redundancy, mpc and the strategies the "
            "server loaded (GET /api/strategies)",
        ),
    ),
)
RunRequest = create_model(
    "RunRequest",
    __config__=STRICT,
    method=(
        MethodName,
        Field(
            strategy.MPC,
            description="how the pelvis turns: fixed, redundancy, mpc or a strategy the server "
            "loaded (GET /api/strategies)",
        ),
    ),
    seed=(
        cast(Any, int | None),
        Field(None, strict=True, description="seed of a small perturbation"),
    ),
    **cast(Fields, {g: (GROUP_UPDATES[g] | None, None) for g in GROUPS}),
)


def updates(body: BaseModel) -> dict[str, dict[str, Any]]:
    """The parameter groups a request changes (fields it leaves out keep their value)."""
    return {
        g: getattr(body, g).model_dump(exclude_none=True)
        for g in GROUPS
        if getattr(body, g) is not None
    }


def params_dict(params: ControllerParams, methods: tuple[str, ...]) -> dict[str, Any]:
    out: dict[str, Any] = {g: dict(vars(getattr(params, g))) for g in GROUPS}
    out["methods"] = list(methods)
    out["control_dt"] = params.control_dt
    return out


class SpeedRequest(BaseModel):
    model_config = STRICT
    speed: float = Field(
        ...,
        ge=SPEED_MIN,
        le=SPEED_MAX,
        strict=True,
        allow_inf_nan=False,
        description="playback speed [x real time]",
    )


class StepRequest(BaseModel):
    model_config = STRICT
    until: Literal[STEP_UNTIL] = Field(  # type: ignore[valid-type]
        "tick", description="advance one 5 ms tick, or to the next lift-off or landing"
    )


class SeekRequest(BaseModel):
    model_config = STRICT
    t: float = Field(
        ...,
        strict=True,
        allow_inf_nan=False,
        description="session clock [s] to show (the nearest kept instant)",
    )


class PushRequest(BaseModel):
    model_config = STRICT
    method: MethodName = Field(..., description="the robot to push")
    force: tuple[float, float] = Field(
        ..., description=f"[Fx, Fy] horizontal force on the torso [N], |F| <= {PUSH_FORCE_MAX:.0f}"
    )
    duration: float = Field(
        0.1, gt=0.0, le=PUSH_DURATION_MAX, strict=True, allow_inf_nan=False, description="[s]"
    )


class RobotState(BaseModel):
    method: str
    t: float = Field(description="the robot's time since its (re)start [s]")
    step_index: int
    in_dsp: bool = Field(description="both feet down inside a step (double support)")
    step_length: float = Field(description="length of the step in progress [m]")
    status: str = Field(
        description="clean / knee nearly straight / IK at the speed limit / fell / stopped"
    )
    fell: bool
    fall_reason: str | None
    error: str | None = Field(
        description="its pelvis strategy failed (the message, with the file and line of the "
        "strategy's code): this robot stopped, the others walk on"
    )
    strategy_ms: float = Field(
        description="[ms] its strategy's waist_rate call, the median over the last second "
        "(above the 5 ms control period it cannot keep real time)"
    )
    fell_at: float | None = Field(
        description="session clock of the fall [s]: the robot lies where it fell until the "
        "session restarts every robot, a few seconds later"
    )
    finished: bool = Field(description="walked its whole plan (all robots restart then)")
    waiting: bool = Field(description="built late, standing by to start in phase")
    success: bool | None = Field(description="outcome of the last finished (or failed) walk")
    walks_completed: int
    falls: int
    waist_angle_deg: float
    kappa: float | None = Field(description="kappa(J) of eq. (45)")
    yaw_momentum: float
    reach: list[float | None] | None = Field(
        description="hip-to-ankle / leg length, left and right"
    )
    zmp_ref: list[float] | None
    zmp_measured: list[float] | None = Field(description="centre of pressure [m]")
    pushing: bool
    solver_failures: int
    params: dict[str, Any] = Field(description="walking parameters in force in this robot")


class KeptRange(BaseModel):
    start: float | None = Field(description="oldest session clock kept [s]")
    end: float | None = Field(description="newest session clock kept [s]")
    frames: int
    megabytes: float = Field(description="memory of the kept frames' arrays")


class StateResponse(BaseModel):
    session: str
    seq: int
    clock: float = Field(description="simulated time since the live session started [s]")
    shown_t: float | None = Field(
        description="session clock of the instant shown while paused and sought (POST "
        "/api/sim/seek); null when showing the present"
    )
    present: float | None = Field(description="session clock of the newest frame [s]")
    kept: KeptRange = Field(description="what is kept: the timeline's range")
    paused: bool = Field(description="as asked (the panel and GET /api/sessions say the same)")
    speed: float
    realtime_factor: float | None = Field(description="simulated / wall time, last seconds")
    compute_realtime_factor: float | None = Field(
        description="simulated / compute time: how fast the loop could run unpaced"
    )
    robots: list[RobotState]


class HorizonResponse(BaseModel):
    """The plan of one robot over the horizon at the shown instant (paper Fig. 5-7)."""

    session: str
    method: str
    clock: float = Field(description="session clock of the instant [s]")
    t: list[float] = Field(description="[s] from the instant")
    com_x: list[float]
    com_y: list[float]
    zmp_x: list[float]
    zmp_y: list[float]
    zmp_ref_x: list[float]
    zmp_ref_y: list[float]
    zmp_min_x: list[float]
    zmp_max_x: list[float]
    zmp_min_y: list[float]
    zmp_max_y: list[float]
    left_foot_x: list[float]
    left_foot_y: list[float]
    right_foot_x: list[float]
    right_foot_y: list[float]
    theta_ref_deg: list[float]
    theta_deg: list[float]


class QpConstraint(BaseModel):
    """One active constraint of a layer's QP at its solution (controller.explain)."""

    name: str = Field(description='what it is, in words: "left knee at its straight limit (0 deg)"')
    kind: str = Field(description='"joint limit", "speed limit", "pinned", "ZMP bound", ...')
    side: Literal["upper", "lower", "pinned"]
    multiplier: float | None = Field(
        description="|lambda|: how much the cost would fall per unit the bound were relaxed"
    )
    lam: float | None = Field(description="the Lagrange multiplier (> 0 upper, < 0 lower)")
    bound: float | None = Field(description="the bound's value, in the row's unit")
    row: int = Field(description="the row of the layer's QP")
    joint: str | None = Field(description="the joint it holds (models.dyros_jet name), if any")
    ahead_s: float | None = Field(description="[s] how far ahead in the horizon (MPC rows)")
    axis: str | None = Field(description='"x" or "y" (the CoM MPC\'s ZMP rows)')


class QpLayer(BaseModel):
    """What one layer's optimisation did at the instant."""

    layer: Literal["com_mpc", "pelvis_mpc", "ik", "arm_swing"]
    title: str
    ran: bool = Field(description="the layer solved a QP at this tick")
    ok: bool = Field(description="solved (false: it failed and the fallback was used)")
    status: str
    iterations: int = Field(description="the solver's iterations (-1 unknown)")
    solve_ms: float | None = Field(description="[ms] the solver's time")
    objective: float | None = Field(description="the cost at the solution: the terms' sum")
    qp_objective: float | None = Field(description="1/2 x'Px + q'x (the constants left out)")
    terms: dict[str, float | None] = Field(description="the cost split into its named terms")
    active: list[QpConstraint] = Field(description="the active constraints, largest first")
    fallback: str = Field(description="what the layer did instead when the solve failed")
    n_variables: int
    n_constraints: int
    note: str


class QpResponse(BaseModel):
    """The four layers' optimisations of one robot at the shown instant (the QP inspector)."""

    session: str
    method: str
    clock: float = Field(description="session clock of the instant [s]")
    t: float = Field(description="[s] the robot's time of the tick explained")
    meaning: str = Field(description="what the active set means, in a sentence")
    layers: list[QpLayer] = Field(description="CoM MPC, pelvic MPC, IK, arm swing")


class RunStatus(BaseModel):
    id: str
    status: Literal["queued", "running", "done", "error"]
    summary: dict[str, Any] | None = None
    error: str | None = None
