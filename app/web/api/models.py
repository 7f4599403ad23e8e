"""Request and response models. The parameters' models are generated from
:func:`controller.params.spec`, so every range lives in ``controller/params.py``; requests are
converted to :class:`~controller.params.ControllerParams` at the edge (cross-field checks such
as "horizon >= one MPC sample" come from its ``validated()``)."""

from __future__ import annotations

from typing import Annotated, Any, Literal, cast

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    StrictBool,
    StrictFloat,
    StrictInt,
    StrictStr,
    create_model,
)

from app.live.intent import PUSH_DURATION_MAX, PUSH_FORCE_MAX, SPEED_MAX, SPEED_MIN, STEP_UNTIL
from controller import strategy
from controller.params import GROUPS, ControllerParams, spec
from pelvic_walk.core import robots as robots_
from pelvic_walk.core.robots import MAX_ROBOTS, Robot


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

# A value of a strategy's own parameter (its range is checked where the parameters are built)
OwnValue = StrictFloat | StrictInt | StrictBool | StrictStr
STRATEGY_GROUPS = (
    "More keys: a strategy's own parameters, as a group named by the strategy "
    '(`"gain": {"k": 12}`, the server\'s strategies with a `Params`: GET /api/params/spec), '
    'or a paper parameter under the strategy that owns it (`"mpc": {"alpha": 2}` is '
    "pelvis.alpha)"
)


class _StrategyGroups(BaseModel):
    """A model whose further keys are strategies' own parameter groups (their names and
    fields are the server's registered strategies', read at each request)."""

    model_config = ConfigDict(extra="allow", json_schema_extra={"description": STRATEGY_GROUPS})
    __pydantic_extra__: dict[str, dict[str, OwnValue]] = Field(init=False)


class RobotSpec(BaseModel):
    """A robot: a strategy, its own settings over the session's parameters, a label."""

    model_config = STRICT
    strategy: MethodName = Field(..., description="a registered strategy (GET /api/strategies)")
    settings: dict[str, OwnValue] = Field(
        default_factory=dict,
        description='its own parameter values, by dotted name: {"com.horizon": 0.8, "gain.k": 12}',
    )
    label: str = Field(
        "", max_length=40, description="its name in the session (default: made from the above)"
    )


class RobotInfo(BaseModel):
    label: str = Field(description="its key in the session (state, horizon, push, plots)")
    strategy: str
    settings: dict[str, Any] = Field(description="its own settings over the shared parameters")
    text: str = Field(description="its form NAME[,KEY=VALUE...][@LABEL] (serve --robot)")


ROBOTS_DESCRIPTION = (
    "replace the session's robots (all restart together): each a form "
    "NAME[,KEY=VALUE...][@LABEL] (`mpc,com.horizon=0.8@short`) or an object {strategy, "
    f"settings, label}}; 1 to {MAX_ROBOTS}, labels unique"
)

ParamsModel = create_model(
    "ParamsModel",
    __base__=_StrategyGroups,
    **cast(Fields, {g: (GROUP_MODELS[g], ...) for g in GROUPS}),
    methods=(
        list[str],
        Field(..., description="the robots shown live, by their labels (in their order)"),
    ),
    robots=(
        list[RobotInfo],
        Field(..., description="the robots shown: label, strategy and their own settings"),
    ),
    control_dt=(float, Field(..., description="control period [s] (fixed)")),
)
ParamsUpdate = create_model(
    "ParamsUpdate",
    __base__=_StrategyGroups,
    **cast(Fields, {g: (GROUP_UPDATES[g] | None, None) for g in GROUPS}),
    robot=(
        cast(Any, str | None),
        Field(
            None,
            description="a robot's label: the change is that robot's own setting (absent: "
            "every robot's, and no robot keeps its own value of those parameters)",
        ),
    ),
    robots=(
        cast(Any, list[str | RobotSpec] | None),
        Field(None, min_length=1, max_length=MAX_ROBOTS, description=ROBOTS_DESCRIPTION),
    ),
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
    __base__=_StrategyGroups,
    robot=(
        cast(Any, str | None),
        Field(
            None,
            description="a robot's form NAME[,KEY=VALUE...] (a live robot's `text` in GET "
            "/api/params): its strategy and its settings over the groups given (replaces "
            "`method`)",
        ),
    ),
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
    """The parameter groups a request changes (fields it leaves out keep their value): the
    paper's, then strategies' own (``{"gain": {"k": 12}}``, ``{"mpc": {"alpha": 2}}``)."""
    out = {
        g: getattr(body, g).model_dump(exclude_none=True)
        for g in GROUPS
        if getattr(body, g) is not None
    }
    for name, values in (body.model_extra or {}).items():
        if name not in strategy.names():
            groups = ", ".join((*GROUPS, *(n for n in strategy.names() if own_values(n))))
            raise ValueError(f"unknown parameter group {name!r} (one of: {groups})")
        if not own_values(name):
            raise ValueError(f"strategy {name!r} has no parameters of its own")
        out[name] = dict(values)
    return out


def own_values(name: str, params: ControllerParams | None = None) -> dict[str, Any]:
    """Strategy ``name``'s own parameters with their values in ``params`` (its ``Params``
    fields and the paper's it owns, ``alpha`` for ``mpc.alpha``), by field name."""
    params = params or ControllerParams()
    return {k.partition(".")[2]: params.value(k) for k in strategy.own_fields(name)}


def robot_of(item: str | RobotSpec) -> Robot:
    """A robot of a request: its form, or an object (ValueError, one line)."""
    if isinstance(item, str):
        return robots_.parse(item)
    return robots_.make(item.strategy, item.settings, item.label)


def robot_info(robot: Robot) -> dict[str, Any]:
    return {
        "label": robot.key,
        "strategy": robot.strategy,
        "settings": dict(robot.overrides),
        "text": robot.text(),
    }


def params_dict(params: ControllerParams, robots: tuple[Robot, ...]) -> dict[str, Any]:
    """``GET /api/params``: the shared parameters (the paper's groups, then every strategy's
    own), the robots shown and their own settings."""
    out: dict[str, Any] = {g: dict(vars(getattr(params, g))) for g in GROUPS}
    for name in strategy.names():
        own = own_values(name, params)
        if own and name not in out:
            out[name] = own
    out["methods"] = [r.key for r in robots]
    out["robots"] = [robot_info(r) for r in robots]
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
    robot: str | None = Field(None, description="the robot to push, by its label")
    method: str | None = Field(None, description="the same as robot (the name of old)")
    force: tuple[float, float] = Field(
        ..., description=f"[Fx, Fy] horizontal force on the torso [N], |F| <= {PUSH_FORCE_MAX:.0f}"
    )
    duration: float = Field(
        0.1, gt=0.0, le=PUSH_DURATION_MAX, strict=True, allow_inf_nan=False, description="[s]"
    )


class RobotState(BaseModel):
    label: str = Field(description="the robot's key in the session (its label)")
    method: str = Field(description="the same as label (the key of old)")
    strategy: str = Field(description="the pelvis strategy it runs")
    settings: dict[str, Any] = Field(
        description='its own settings that not every robot shares: {"com.horizon": 0.8}'
    )
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
    method: str = Field(description="the robot's label")
    strategy: str
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
    method: str = Field(description="the robot's label")
    strategy: str
    clock: float = Field(description="session clock of the instant [s]")
    t: float = Field(description="[s] the robot's time of the tick explained")
    meaning: str = Field(description="what the active set means, in a sentence")
    layers: list[QpLayer] = Field(description="CoM MPC, pelvic MPC, IK, arm swing")


class RunStatus(BaseModel):
    id: str
    status: Literal["queued", "running", "done", "error"]
    summary: dict[str, Any] | None = None
    error: str | None = None
