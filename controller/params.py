"""Every tunable of the controller: frozen dataclasses with units, defaults and ranges.

This module is the single source of truth for parameters. The CLI's options (``simulate``,
``sweep``), the HTTP API's Pydantic models, the GUI's folders and sliders and the study's run
specs all read the metadata attached to each field with :func:`spec`, so a new gain added
here appears everywhere. Metadata keys: ``min``, ``max``, ``step``, ``unit``, ``label``
(always); ``lo_open`` (the minimum itself is excluded); ``log`` (a weight spanning decades:
log-scale slider from ``log_min``); ``paper`` (the paper's value, marked on the slider);
``applies`` ("tick": the next control tick, the default; "step": from the next step, as the
footstep plan is re-planned); ``cli`` (the command-line option, without ``--``; default
``group-name``); ``choices`` (a text parameter's values); ``help`` (one line of explanation).

Paper symbols -> names (Park & Park 2022):
    l_step -> WalkParams.step_length, w_step -> WalkParams.step_width,
    T_p (MPC sample) -> ComMpcParams.sample_time, H -> ComMpcParams.horizon,
    alpha/beta/gamma (eq. 18) -> ComMpcParams.alpha/beta/gamma,
    K_p (eq. 19) -> ComMpcParams.pelvis_gain,
    k_pel (eq. 31-32) -> PelvisMpcParams.k_pel,
    alpha_pel/beta_pel (eq. 37) -> PelvisMpcParams.alpha/beta,
    omega_1..3 (eq. 43) -> ArmParams.omega1..omega3.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

# Readings of the lateral distance Delta d_{FP,i,y} of eq. (31)-(32): controller/pelvis_reference.py
LATERAL_MODES: tuple[str, ...] = ("current", "nominal", "predicted")
# What the reference pelvic angle of eq. (27)-(33) is computed from over the MPC's horizon:
# the predicted CoM and the planned feet (the paper), or the state now held (an ablation)
REFERENCE_SOURCES: tuple[str, ...] = ("predicted", "now")
# Where a step's double support lies: all at its start (our plan) or half at each end (the
# authors' public implementation): controller/footsteps.py, docs/DESIGN.md
DSP_SPLITS: tuple[str, ...] = ("start", "both_ends")
CONTROL_DT = 0.005  # [s] the paper's 200 Hz control period (every layer, every QP)


def _f(default: float, lo: float, hi: float, step: float, unit: str, label: str, **kw: Any) -> Any:
    """A float field with its range, slider step, unit and label as metadata."""
    meta = {"min": lo, "max": hi, "step": step, "unit": unit, "label": label, **kw}
    return field(default=default, metadata=meta)


def _choice(default: str, choices: tuple[str, ...], label: str, **kw: Any) -> Any:
    """A text field taking one of ``choices``."""
    return field(default=default, metadata={"choices": choices, "label": label, **kw})


def _w(default: float, lo: float, hi: float, label: str, log_min: float, **kw: Any) -> Any:
    """A QP weight: a float spanning decades, shown on a log-scale slider from ``log_min``."""
    return _f(default, lo, hi, log_min, "", label, log=True, log_min=log_min, **kw)


def param(
    default: Any,
    *,
    min: float | None = None,  # noqa: A002 - the names a strategy's author writes
    max: float | None = None,  # noqa: A002
    step: float | None = None,
    unit: str = "",
    label: str = "",
    help: str = "",  # noqa: A002
    choices: tuple[str, ...] | None = None,
    log: bool = False,
    log_min: float | None = None,
) -> Any:
    """A field of a strategy's own ``Params`` dataclass (docs/STRATEGIES.md), with the same
    metadata as the paper's parameters below: it then has a slider, ``--set NAME.FIELD=V``,
    an API entry and a sweep grid, and its range is checked everywhere.

    A number needs ``min`` and ``max``; a text field ``choices``; a bool neither.
    """
    meta: dict[str, Any] = {"label": label or "", "unit": unit}
    if help:
        meta["help"] = help
    if isinstance(default, bool):
        pass
    elif isinstance(default, str):
        if not choices or default not in choices:
            raise ValueError(f"param({default!r}): a text parameter needs choices holding it")
        meta["choices"] = tuple(choices)
    elif isinstance(default, (int, float)):
        if min is None or max is None or not (min <= default <= max):
            raise ValueError(f"param({default!r}): a number needs min <= default <= max")
        span = float(max) - float(min)
        if step is None:
            step = 1 if isinstance(default, int) else float(f"{span / 100:.1g}") or span / 100
        meta.update(min=min, max=max, step=step)
        if log:
            meta.update(log=True, log_min=log_min if log_min is not None else step)
    else:
        raise ValueError(f"param({default!r}): a number, a bool or a text with choices")
    return field(default=default, metadata=meta)


# A strategy's own parameters (its nested ``Params`` dataclass), by strategy name; and the
# names under a strategy for parameters of the paper it alone reads (``mpc.k_pel`` ->
# ``pelvis.k_pel``). Filled by controller/strategy.py's registry; read by :func:`validate`
# and :meth:`ControllerParams.replace`. Their values ride in ``ControllerParams.own``.
OWN_PARAMS: dict[str, type] = {}
ALIASES: dict[str, str] = {}


def resolve(dotted: str) -> str:
    """A parameter's stored name: an alias (``mpc.alpha``) gives the paper's (``pelvis.alpha``)."""
    return ALIASES.get(dotted, dotted)


@dataclass(frozen=True)
class WalkParams:
    """Footstep plan and swing-foot shape (layer 1, eq. 20-21)."""

    step_length: float = _f(
        0.2, 0.01, 0.6, 0.01, "m", "Step length", lo_open=True, applies="step", cli="step-length"
    )
    step_time: float = _f(
        1.2, 0.6, 2.0, 0.05, "s", "Step time", applies="step", cli="step-time", paper=1.2
    )
    dsp_ratio: float = _f(
        0.2, 0.05, 0.5, 0.01, "", "Double-support share", applies="step", cli="dsp-ratio"
    )
    dsp_split: str = _choice(
        "start",
        DSP_SPLITS,
        "Where the DSP lies in a step",
        applies="step",
        help="start: all before the lift-off; both_ends: half before the lift-off, half after "
        "the touch-down (the authors' implementation)",
    )
    foot_height: float = _f(
        0.06, 0.0, 0.15, 0.005, "m", "Foot lift height", applies="step", cli="foot-height"
    )
    step_width: float = _f(
        0.243,
        0.18,
        0.35,
        0.001,
        "m",
        "Step width (feet lateral distance)",
        applies="step",
        cli="step-width",
        paper=0.243,
    )
    n_steps: int = field(
        default=10,
        metadata={
            "min": 1,
            "max": 200,
            "step": 1,
            "unit": "",
            "label": "Steps",
            "applies": "step",
            "cli": "steps",
            "gui": False,
        },
    )


@dataclass(frozen=True)
class ComMpcParams:
    """CoM MPC of eq. (10)-(18) and the pelvis tracking of eq. (19)."""

    horizon: float = _f(
        1.6,
        0.2,
        3.0,
        0.1,
        "s",
        "Horizon H",
        cli="horizon",
        paper=1.6,
        help="both MPCs look this far ahead; shorter than a step, they cannot "
        "see the next support foot",
    )
    sample_time: float = _f(0.1, 0.02, 0.2, 0.01, "s", "MPC sample T_p")
    alpha: float = _w(1.0, 0.0, 100.0, "alpha (ZMP tracking)", 1e-3, paper=1.0)
    beta: float = _w(1e-3, 0.0, 10.0, "beta (CoM velocity fluctuation)", 1e-6)
    gamma: float = _w(1e-6, 1e-9, 1.0, "gamma (jerk)", 1e-9)
    zmp_margin: float = _f(0.02, 0.0, 0.06, 0.005, "m", "ZMP margin inside the foot")
    # K_p per 5 ms tick: 0.1 removes an offset with a time constant of about 50 ms. At 0.3
    # (15 ms) the MPC robot fell in 6 of 19 seeded walks under 10 N random pushes, at 0.1 in
    # none, the unpushed walks unchanged (docs/DESIGN.md, "Pelvis feed-forward").
    pelvis_gain: float = _f(0.1, 0.0, 1.0, 0.01, "", "K_p (eq. 19)")


@dataclass(frozen=True)
class PelvisMpcParams:
    """Reference pelvic angle (eq. 27-33) and pelvic-rotation MPC (eq. 34-38)."""

    k_pel: float = _f(
        0.25,
        0.0,
        1.0,
        0.01,
        "",
        "k_pel (eq. 31-32)",
        help="share of the step made by turning the pelvis",
    )
    alpha: float = _w(1.0, 0.0, 100.0, "alpha_pel (tracking)", 1e-3, paper=1.0)
    beta: float = _w(1e-6, 1e-10, 1.0, "beta_pel (yaw acceleration)", 1e-10, paper=1e-10)
    lateral_distance: str = _choice(
        "current",
        LATERAL_MODES,
        "Lateral distance (eq. 31-32)",
        help="current: pelvis (the CoM MPC's state) to foot now, held over the horizon (the "
        "paper's Delta d_{FP,i,y}); predicted: per horizon sample; nominal: half the step width",
    )
    reference: str = _choice(
        "predicted",
        REFERENCE_SOURCES,
        "Reference angle from",
        help="predicted: eq. (27)-(33) at every horizon sample, from the predicted CoM and the "
        "planned feet (the paper); now: from the CoM MPC's state and the feet now, held over "
        "the horizon (an ablation: the MPC without its prediction)",
    )
    lateral_floor: float = _f(
        0.03,
        0.005,
        0.1,
        0.005,
        "m",
        "Lateral distance floor",
        help="smallest pelvis-to-foot lateral distance in eq. (31)-(32) (current, predicted)",
    )
    angle_limit_deg: float = _f(45.0, 0.0, 50.0, 1.0, "deg", "Pelvic angle limit")
    acc_limit: float = _f(30.0, 1.0, 100.0, 1.0, "rad/s^2", "Yaw acceleration limit")


@dataclass(frozen=True)
class IkParams:
    """QP inverse kinematics, eq. (39)-(40)."""

    foot_gain: float = _f(20.0, 0.0, 200.0, 1.0, "1/s", "Foot pose error gain")
    damping: float = _w(1e-4, 0.0, 1.0, "Joint-velocity damping", 1e-8)
    joint_speed_limit: float = _f(10.0, 1.0, 30.0, 0.5, "rad/s", "Joint speed limit")
    redundancy_weight: float = _f(0.05, 0.0, 10.0, 0.01, "", "Redundancy: waist-yaw pull to 0")


@dataclass(frozen=True)
class ArmParams:
    """Arm swing QP on the centroidal momentum matrix, eq. (41)-(43)."""

    enabled: bool = field(default=True, metadata={"label": "Arm swing", "cli": "arms"})
    omega1: float = _w(1.0, 0.0, 100.0, "omega1 (yaw momentum)", 1e-3, paper=1.0)
    omega2: float = _w(1e-2, 0.0, 10.0, "omega2 (initial pose)", 1e-5, paper=1e-2)
    omega3: float = _w(1e-4, 0.0, 1.0, "omega3 (joint rate)", 1e-7, paper=1e-4)


@dataclass(frozen=True)
class ControllerParams:
    """All the controller's parameters for one robot."""

    # how the pelvis turns: the name of a registered strategy (controller/strategy.py: the
    # paper's three methods and any a user loaded); the walker rejects an unknown one
    method: str = "mpc"
    walk: WalkParams = field(default_factory=WalkParams)
    com: ComMpcParams = field(default_factory=ComMpcParams)
    pelvis: PelvisMpcParams = field(default_factory=PelvisMpcParams)
    ik: IkParams = field(default_factory=IkParams)
    arms: ArmParams = field(default_factory=ArmParams)
    control_dt: float = CONTROL_DT  # [s] 200 Hz, fixed by the paper
    # strategies' own parameters set away from their defaults: ("NAME.FIELD", value), sorted
    # (a strategy reads its own as ``self.params``: :meth:`own_params`)
    own: tuple[tuple[str, Any], ...] = ()

    def validated(self) -> ControllerParams:
        """Return self after checking every field against its range; raise ValueError."""
        validate(self)
        return self

    def replace(self, **groups: Any) -> ControllerParams:
        """Copy with some groups replaced, e.g. ``p.replace(walk=dict(step_length=0.3))``.

        A strategy's name is a group too: ``p.replace(gain={"k": 12})`` sets its own
        parameter ``gain.k``; a name under a strategy for a paper parameter it owns
        (``mpc={"alpha": 2}``) sets the paper's (``pelvis.alpha``)."""
        changes: dict[str, Any] = {}
        values: dict[str, Any] = {}
        for name, value in groups.items():
            if isinstance(value, dict):  # a group of the paper's, or a strategy's own
                values.update({f"{name}.{k}": v for k, v in value.items()})
            else:
                changes[name] = value
        own = dict(changes.pop("own", self.own))
        grouped: dict[str, dict[str, Any]] = {}
        for dotted, value in values.items():
            group, _, fname = resolve(dotted).partition(".")
            if group in GROUPS:
                grouped.setdefault(group, {})[fname] = value
            else:
                if group not in OWN_PARAMS:
                    known = ", ".join((*GROUPS, *OWN_PARAMS))
                    raise ValueError(f"unknown parameter group {group!r} (one of: {known})")
                own[f"{group}.{fname}"] = value
        for group, value in grouped.items():
            base = changes.get(group, getattr(self, group))
            try:
                changes[group] = dataclasses.replace(base, **value)
            except TypeError:
                bad = next(k for k in value if k not in {f.name for f in dataclasses.fields(base)})
                raise ValueError(f"unknown parameter {group}.{bad}") from None
        changes["own"] = _own_tuple(own)
        return dataclasses.replace(self, **changes).validated()

    def value(self, dotted: str) -> Any:
        """One parameter's value by name (``walk.step_length``, ``gain.k``, ``mpc.alpha``)."""
        group, _, fname = resolve(dotted).partition(".")
        if group in GROUPS:
            if fname not in spec(getattr(self, group)):
                raise ValueError(f"unknown parameter {dotted!r}")
            return getattr(getattr(self, group), fname)
        own = dict(self.own)
        if f"{group}.{fname}" in own:
            return own[f"{group}.{fname}"]
        cls = OWN_PARAMS.get(group)
        if cls is None or fname not in spec(cls):
            raise ValueError(f"unknown parameter {dotted!r}")
        return spec(cls)[fname]["default"]

    def own_params(self, strategy: str) -> Any:
        """A strategy's ``Params`` instance with the values in force (None without one)."""
        cls = OWN_PARAMS.get(strategy)
        if cls is None:
            return None
        prefix = f"{strategy}."
        return cls(**{k[len(prefix) :]: v for k, v in self.own if k.startswith(prefix)})


GROUPS: tuple[str, ...] = ("walk", "com", "pelvis", "ik", "arms")
GROUP_TITLES = {
    "walk": "Walk",
    "com": "CoM MPC",
    "pelvis": "Pelvic MPC",
    "ik": "QP IK",
    "arms": "Arm swing",
}


def spec(cls_or_obj: Any) -> dict[str, dict[str, Any]]:
    """Field name -> metadata (min, max, step, unit, label, default) of a params dataclass."""
    out = {}
    for f in dataclasses.fields(cls_or_obj):
        meta = dict(f.metadata)
        default = f.default if f.default is not dataclasses.MISSING else None
        meta["default"] = default
        meta["type"] = type(default).__name__
        out[f.name] = meta
    return out


def check_value(group: str, name: str, value: Any, meta: dict[str, Any]) -> None:
    """Raise ValueError with a one-line message if ``value`` is outside its range."""
    where = f"{group}.{name}" if group else name
    if meta.get("choices"):
        if value not in meta["choices"]:
            raise ValueError(f"{where} must be one of {', '.join(meta['choices'])}, got {value!r}")
        return
    if meta.get("type") == "bool":
        if not isinstance(value, bool):
            raise ValueError(f"{where} must be true or false, got {value!r}")
        return
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{where} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{where} must be finite, got {value!r}")
    lo, hi = meta.get("min"), meta.get("max")
    unit = f" {meta['unit']}" if meta.get("unit") else ""
    if lo is not None and (value < lo or (meta.get("lo_open") and value <= 0)):
        raise ValueError(f"{where} = {value} is below the minimum {lo}{unit}")
    if hi is not None and value > hi:
        raise ValueError(f"{where} = {value} is above the maximum {hi}{unit}")
    if meta.get("type") == "int" and int(value) != value:
        raise ValueError(f"{where} must be an integer, got {value!r}")


def _own_tuple(own: dict[str, Any]) -> tuple[tuple[str, Any], ...]:
    """Strategies' own values, sorted, defaults left out (equal settings compare equal)."""
    out = []
    for dotted, value in sorted(own.items()):
        group, _, fname = dotted.partition(".")
        cls = OWN_PARAMS.get(group)
        meta = spec(cls).get(fname) if cls is not None else None
        if meta is not None and isinstance(meta["default"], float) and type(value) is int:
            value = float(value)  # 12 for a float field: 12.0, as the paper's fields keep it
        if meta is not None and value == meta["default"] and type(value) is type(meta["default"]):
            continue
        out.append((dotted, value))
    return tuple(out)


def validate(p: ControllerParams) -> None:
    """Check every field of every group against its range; raise ValueError on the first bad."""
    if not isinstance(p.method, str) or not p.method:
        raise ValueError(f"method must be a strategy's name, got {p.method!r}")
    for group in GROUPS:
        obj = getattr(p, group)
        for name, meta in spec(obj).items():
            check_value(group, name, getattr(obj, name), meta)
    if not isinstance(p.own, tuple):
        raise ValueError(f"own must be a tuple of (NAME.FIELD, value), got {p.own!r}")
    for item in p.own:
        if not (isinstance(item, tuple) and len(item) == 2 and isinstance(item[0], str)):
            raise ValueError(f"own must be a tuple of (NAME.FIELD, value), got {item!r}")
        group, _, fname = item[0].partition(".")
        cls = OWN_PARAMS.get(group)
        if cls is None:
            raise ValueError(f"unknown parameter {item[0]!r}: no strategy {group!r} has parameters")
        fields_ = spec(cls)
        if fname not in fields_:
            raise ValueError(
                f"unknown parameter {item[0]!r} (one of: "
                f"{', '.join(f'{group}.{n}' for n in fields_)})"
            )
        check_value(group, fname, item[1], fields_[fname])
    if p.com.horizon < p.com.sample_time:
        raise ValueError(
            f"com.horizon = {p.com.horizon} s is shorter than one MPC sample "
            f"({p.com.sample_time} s)"
        )


def horizon_samples(com: ComMpcParams) -> int:
    """N = H / T_p, the number of MPC samples (at least 1)."""
    return max(1, int(round(com.horizon / com.sample_time)))
