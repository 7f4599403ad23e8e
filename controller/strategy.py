"""How the pelvis turns: the strategy contract, the three methods of the paper, one registry.

The paper's question is *how* the waist yaw joint should turn while the legs reach the
footholds. A **pelvis strategy** answers it once per control tick: from the tick's inputs
(:class:`StrategyInputs`, read-only) it returns the waist yaw rate [rad/s] that the QP
inverse kinematics of eq. (39) pins, or ``None`` to leave the waist free to the IK. The three
methods the paper compares are three strategies on this same contract:

- ``fixed`` (:class:`FixedPelvis`): rate 0, no pelvic rotation;
- ``redundancy`` (:class:`RedundancyPelvis`, the authors' earlier method, ref. [21]): ``None``,
  the waist is a free variable of the IK, pulled toward 0 by ``ik.redundancy_weight``;
- ``mpc`` (:class:`PelvisMpcStrategy`, the paper's method): the rate theta_dot_{i+1} of the
  pelvic-rotation MPC (eq. 34-38) tracking the reference theta_ref of eq. (27)-(33).

A user's strategy is a subclass of :class:`PelvisStrategy` in a Python file of their own
(docs/STRATEGIES.md), loaded once by :func:`load_file` (``--strategy FILE.py[:Class]``) and
registered beside the built-ins. Everything that names a robot (the walker, the live tool,
the API, the lessons, the study, the sweep) asks this registry (:func:`get`, :func:`names`,
:func:`info`): a strategy's ``name`` is its robot's key and label.

A strategy's mistakes stay its own: an exception, a NaN or a wrong type from ``waist_rate``
becomes a :class:`StrategyError` naming the user's file and line (:meth:`Runner.waist_rate`);
the walker raises it, and the caller (a headless run, the live loop) stops that robot only.

Paper symbols -> names (:class:`StrategyInputs`):
    theta_pel -> ``theta``, theta_dot -> ``theta_dot``, Theta_pel^ref (eq. 33) -> ``theta_ref``,
    t + k T_p -> ``t + horizon_t``, X_c (eq. 25-26) -> ``com``, X_c^d -> ``com_now``,
    P^f (eq. 20-21) -> ``left_sole``, ``right_sole``, Delta t -> ``dt``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.util
import inspect
import math
import os
import re
import sys
import traceback
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np

from controller.params import (
    ALIASES,
    GROUPS,
    OWN_PARAMS,
    ControllerParams,
    check_value,
    horizon_samples,
    spec,
)
from controller.pelvis_mpc import PelvisMpc, PelvisPlan

FIXED, REDUNDANCY, MPC = "fixed", "redundancy", "mpc"  # the paper's three methods
# names a strategy may not take: its own parameters are named NAME.FIELD beside the paper's
# groups, and the API's parameter requests hold these fields beside the groups
RESERVED_NAMES = frozenset(
    (*GROUPS, "method", "methods", "robot", "robots", "own", "control_dt", "params", "strategy")
)
NAME_PATTERN = re.compile(r"^[A-Za-z][A-Za-z0-9_.-]{0,39}$")  # a robot key: URLs, CLI lists


class StrategyInputs(NamedTuple):
    """What a strategy may read at one control tick (read-only: arrays cannot be written).

    World frame: x forward, y to the left, z up; angles about +z. The horizon has N samples
    (N = ``params.com.horizon / params.com.sample_time``), the CoM MPC's, at ``t + horizon_t``.
    """

    t: float  # [s] this tick's time since the walk started
    dt: float  # [s] the control period Delta t (0.005: 200 Hz)
    theta: float  # [rad] waist yaw theta_pel now (commanded), + turns the left hip back
    theta_dot: float  # [rad/s] waist yaw rate commanded at the last tick
    theta_ref: np.ndarray  # (N,) [rad] reference pelvic angle of eq. (27)-(33) at horizon_t
    horizon_t: np.ndarray  # (N,) [s] the horizon's sample times from now: T_p, 2 T_p, ... H
    com: np.ndarray  # (N, 2) [m] CoM x, y predicted by the CoM MPC (eq. 25-26) at horizon_t
    com_now: np.ndarray  # (2,) [m] the CoM MPC's desired CoM x, y now (X_c^d of eq. 19)
    left_sole: np.ndarray  # (N, 3) [m] planned left sole centre at horizon_t (eq. 20-21)
    right_sole: np.ndarray  # (N, 3) [m] planned right sole centre at horizon_t
    left_sole_now: np.ndarray  # (3,) [m] planned left sole centre now
    right_sole_now: np.ndarray  # (3,) [m] planned right sole centre now
    support: str  # "left" or "right" (single support: the other foot swings) or "both"
    swing: str | None  # the foot that swings in the step in progress, "left" or "right" (on
    # the ground still in the step's double support); None while standing
    step: int  # the step in progress: -1 before the first, then 0, 1, ...
    phase: float  # progress through the single support, 0 at lift-off to 1 at touch-down (0
    # in the double support and before walking, 1 after the last step)
    params: ControllerParams  # every parameter in force (params.walk.step_time, ...)


class PelvisStrategy:
    """Base class of a pelvis strategy: subclass it, set ``name``, write :meth:`waist_rate`.

    One instance drives one robot; it is created with no arguments, and :meth:`reset` is
    called at the start of each walk (the robot's restarts included).

    Attributes:
        name: the robot's key (letters, digits, ``_ . -``; starts with a letter), as
            ``--method``, ``/api/...?method=`` and the study's tables know it.
        label: a few words on the robot's tag and in legends (default: ``name``).
        color: RGB 0-255 of the robot in the scene and plots (default: one from a palette).
        plan: a :class:`~controller.pelvis_mpc.PelvisPlan` a strategy that optimises over
            the horizon may set each tick; it is drawn as the optimised pelvic angle (the
            built-in MPC does). Leave it ``None`` otherwise.
    """

    name: ClassVar[str] = ""
    # its own parameters (optional): a dataclass whose fields are made by
    # ``pelvic_walk.param(...)``; the instance reads the values in force as ``self.params``
    # (set before :meth:`reset` and whenever they change, acting on the next tick)
    Params: ClassVar[type | None] = None
    # the paper's parameters this strategy alone reads, under its own name: field -> the
    # paper's ``group.name`` (the built-in MPC's weights); ``NAME.FIELD`` then names them too
    owns: ClassVar[dict[str, str]] = {}
    params: Any = None
    label: ClassVar[str] = ""
    paper_label: ClassVar[str] = ""  # the built-ins: how the paper names them (figures)
    color: ClassVar[tuple[int, int, int] | None] = None
    plan: PelvisPlan | None = None

    def reset(self, s: StrategyInputs) -> None:
        """Called at the start of each walk, with its first tick's inputs (before
        :meth:`waist_rate`). Clear what you keep from one tick to the next here."""

    def waist_rate(self, s: StrategyInputs) -> float | None:
        """The waist yaw rate [rad/s] the IK pins this tick, or ``None`` to leave it free.

        The IK clips a pinned rate into the waist's joint-angle and speed limits (+-10 rad/s
        by default, ``params.ik.joint_speed_limit``); a free waist is pulled toward 0 with the
        weight ``params.ik.redundancy_weight``.
        """
        raise NotImplementedError


# -- the paper's three methods -------------------------------------------------------------
class FixedPelvis(PelvisStrategy):
    """No pelvic rotation: the waist rate is pinned to 0 and the legs alone reach."""

    name = FIXED
    label = "fixed pelvis"
    paper_label = "fixed pelvis (W/O rotation)"
    color = (0, 114, 178)  # Okabe-Ito blue (pelvic_walk.core.methods says why these)

    def waist_rate(self, s: StrategyInputs) -> float:
        return 0.0


class RedundancyPelvis(PelvisStrategy):
    """Rotation by redundancy (ref. [21]): the waist is a free variable of the IK, no
    prediction; the damping spreads motion onto it in the swing, a small pull brings it back."""

    name = REDUNDANCY
    owns: ClassVar[dict[str, str]] = {"weight": "ik.redundancy_weight"}
    label = "redundancy"
    paper_label = "rotation by redundancy [21]"
    color = (100, 40, 85)  # plum, dark

    def waist_rate(self, s: StrategyInputs) -> None:
        return None


class PelvisMpcStrategy(PelvisStrategy):
    """Rotation by MPC (the paper's method, eq. 34-38): the pelvic-rotation MPC tracks the
    reference over the predicted horizon; the IK pins the rate after one control period.

    The MPC integrates its own rate (eq. 38), starting from the rate commanded when the walk
    (or this strategy) starts; the rate the IK commands can differ from it only when the IK
    clips it into the waist's limits or fails.
    """

    name = MPC
    owns: ClassVar[dict[str, str]] = {
        "alpha": "pelvis.alpha",
        "beta": "pelvis.beta",
        "angle_limit_deg": "pelvis.angle_limit_deg",
        "acc_limit": "pelvis.acc_limit",
    }
    label = "pelvic MPC"
    paper_label = "rotation by MPC (proposed)"
    color = (230, 140, 0)  # orange (Okabe-Ito's, a shade deeper: apart from yellow as lit)

    def __init__(self, backend: str = "daqp"):
        self.backend = backend
        self.mpc: PelvisMpc | None = None
        self.rate = 0.0  # [rad/s] the MPC's integrated rate theta_dot (eq. 38)
        self._params: ControllerParams | None = None

    def reset(self, s: StrategyInputs) -> None:
        self.rate = s.theta_dot
        self.plan = None

    def waist_rate(self, s: StrategyInputs) -> float:
        p = s.params
        if p is not self._params:  # new parameters: rebuild what changed (eq. 35's matrices)
            self._configure(p)
        assert self.mpc is not None
        plan = self.mpc.solve(s.theta, self.rate, s.theta_ref)
        self.plan = plan
        self.rate = plan.next_rate
        return plan.next_rate

    def _configure(self, p: ControllerParams) -> None:
        n = horizon_samples(p.com)
        old = self._params
        if self.mpc is None:
            self.mpc = PelvisMpc(p.pelvis, p.com.sample_time, n, p.control_dt, self.backend)
        elif old is None or (p.pelvis, p.com.sample_time, n) != (
            old.pelvis,
            old.com.sample_time,
            horizon_samples(old.com),
        ):
            self.mpc.set_params(p.pelvis, p.com.sample_time, n)
        self._params = p


# -- the registry ------------------------------------------------------------------------
class StrategyError(RuntimeError):
    """A strategy failed at a tick (raised, or returned something that is not a rate).

    ``str(error)`` is one line: the message and where, e.g.
    ``"ZeroDivisionError: float division by zero (my_pelvis.py:14)"``. ``step``: the
    ``s.step`` of the failing tick (the step in progress, counted from 0 as
    :attr:`StrategyInputs.step`; -1 before the first), the one every report of the stop names.
    """

    def __init__(self, strategy: str, message: str, where: str, step: int = -1):
        self.strategy, self.message, self.where, self.step = strategy, message, where, step
        super().__init__(f"{message} ({where})" if where else message)


class StrategyLoadError(ValueError):
    """A strategy file that cannot be used: missing, does not import, no or a bad strategy.
    One line, with the file (and line where there is one)."""


# A palette for strategies without a colour of their own (pelvic_walk.core.methods says how these
# were
# chosen): black and yellow (Okabe-Ito) stay apart from the built-ins' blue, plum and orange
# and from each other for the common colour-vision deficiencies and in grayscale
# (tests/test_colours.py); a third own strategy wears black again, told apart by its marker.
PALETTE: tuple[tuple[int, int, int], ...] = (
    (0, 0, 0),  # black
    (240, 228, 66),  # yellow
)


@dataclass(frozen=True)
class StrategyInfo:
    """A registered strategy as the rest of the tool sees it."""

    name: str
    label: str  # a few words: the robot's tag, legends
    paper_label: str  # how the paper names it (the study's figures); the label for others
    color: tuple[int, int, int]  # RGB 0-255
    description: str  # the class docstring's first paragraph
    builtin: bool
    # "FILE.py:Class" of a user's strategy; None for the built-ins and for a user's class
    # defined in this process (register(cls, builtin=False): a notebook cell)
    source: str | None
    cls: type[PelvisStrategy]

    @property
    def file(self) -> str | None:
        return self.source.rpartition(":")[0] if self.source else None


_REGISTRY: dict[str, StrategyInfo] = {}
_LOADED: dict[tuple[str, str | None], tuple[float, tuple[str, ...]]] = {}  # file -> names


def _description(cls: type) -> str:
    """The first paragraph of the class's own docstring; "" without one (never a base
    class's: ``inspect.getdoc`` would inherit :class:`PelvisStrategy`'s)."""
    own = cls.__dict__.get("__doc__")
    doc = inspect.cleandoc(own) if isinstance(own, str) else ""
    return " ".join(doc.split("\n\n")[0].split())


def register(
    cls: type[PelvisStrategy],
    source: str | None = None,
    replace: bool = False,
    builtin: bool | None = None,
) -> StrategyInfo:
    """Add a strategy class under its ``name``; ValueError (one line) if the name is taken by
    another class (``replace`` lets a file loaded again take its own names back).

    ``source`` is the user's ``FILE.py:Class``; without one the class is a built-in, unless
    ``builtin=False``: a user's class defined in this process (a notebook cell, a script),
    which no other process can load. Such a class may take back the name of an earlier one
    of its kind (the cell run again), never a built-in's or a file's."""
    builtin = source is None if builtin is None else builtin
    if not (isinstance(cls, type) and issubclass(cls, PelvisStrategy)):
        raise ValueError(f"{cls!r} is not a PelvisStrategy subclass")
    name = cls.__dict__.get("name", getattr(cls, "name", ""))
    where = source or cls.__qualname__
    if not isinstance(name, str) or not NAME_PATTERN.match(name):
        raise ValueError(
            f"{where}: name must be 1-40 letters, digits, '_', '.' or '-', starting with a "
            f"letter, got {name!r}"
        )
    if name in RESERVED_NAMES:
        raise ValueError(
            f"{where}: the name {name!r} is a parameter group's or a request field's; choose "
            "another (it names the strategy's own parameters NAME.FIELD)"
        )
    if cls.waist_rate is PelvisStrategy.waist_rate:
        raise ValueError(f"{where}: {cls.__name__} does not define waist_rate(self, s)")
    old = _REGISTRY.get(name)
    if old is not None and old.cls is not cls:
        same_file = (
            old.source is not None and source is not None and old.file == source.rpartition(":")[0]
        )
        in_process_again = not builtin and source is None and not old.builtin and old.source is None
        if not ((replace and same_file) or in_process_again):
            taken = (
                "a built-in strategy"
                if old.builtin
                else old.source or f"the class {old.cls.__qualname__} defined in this process"
            )
            raise ValueError(f"{where}: the name {name!r} is taken by {taken}")
    color = cls.color
    if color is not None:
        if not (
            isinstance(color, tuple)
            and len(color) == 3
            and all(isinstance(c, int) and 0 <= c <= 255 for c in color)
        ):
            raise ValueError(f"{where}: color must be three integers 0-255, got {color!r}")
    else:  # the first colour of the palette no other strategy wears
        worn = {i.color for i in _REGISTRY.values() if i.name != name}
        free = [c for c in PALETTE if c not in worn]
        color = free[0] if free else PALETTE[len(_REGISTRY) % len(PALETTE)]
    own = _check_params(cls, where)
    owns = _check_owns(cls, where)
    label = cls.label if isinstance(cls.label, str) and cls.label.strip() else name
    paper_label = cls.paper_label if isinstance(cls.paper_label, str) and cls.paper_label else label
    info = StrategyInfo(name, label, paper_label, color, _description(cls), builtin, source, cls)
    _REGISTRY[name] = info
    _forget_params(name)
    if own is not None:
        OWN_PARAMS[name] = own
    ALIASES.update({f"{name}.{k}": v for k, v in owns.items()})
    return info


def _check_params(cls: type[PelvisStrategy], where: str) -> type | None:
    """The class's ``Params``, checked: a dataclass whose every field has its metadata
    (made by ``pelvic_walk.param``) and a default in its range."""
    own = cls.__dict__.get("Params", None)
    if own is None:
        return None
    if not dataclasses.is_dataclass(own) or not isinstance(own, type):
        raise ValueError(f"{where}: Params must be a dataclass (@dataclass(frozen=True))")
    for f in dataclasses.fields(own):
        if "label" not in f.metadata:
            raise ValueError(
                f"{where}: Params.{f.name} must be made by pelvic_walk.param(default, min=, max=)"
            )
    try:
        instance = own()
        for fname, meta in spec(own).items():
            check_value(cls.name, fname, getattr(instance, fname), meta)
        hash(instance)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: Params: {exc}") from None
    return own


def _check_owns(cls: type[PelvisStrategy], where: str) -> dict[str, str]:
    owns = cls.__dict__.get("owns", {})
    if not isinstance(owns, dict):
        raise ValueError(f"{where}: owns must map field names to the paper's GROUP.NAME")
    defaults = ControllerParams()
    for k, dotted in owns.items():
        group, _, fname = str(dotted).partition(".")
        if group not in GROUPS or not hasattr(getattr(defaults, group), fname):
            raise ValueError(f"{where}: owns[{k!r}] = {dotted!r} is not a paper parameter")
    return dict(owns)


def _forget_params(name: str) -> None:
    OWN_PARAMS.pop(name, None)
    for alias in [a for a in ALIASES if a.startswith(f"{name}.")]:
        del ALIASES[alias]


def own_fields(name: str) -> dict[str, str]:
    """The parameters strategy ``name`` owns, ``NAME.FIELD`` -> the stored name (itself for
    a field of its ``Params``, the paper's ``group.name`` for one it owns of the paper's)."""
    out = {a: v for a, v in ALIASES.items() if a.startswith(f"{name}.")}
    cls = OWN_PARAMS.get(name)
    if cls is not None:
        out.update({f"{name}.{f}": f"{name}.{f}" for f in spec(cls)})
    return out


for _builtin in (FixedPelvis, RedundancyPelvis, PelvisMpcStrategy):
    register(_builtin)
BUILTINS: tuple[str, ...] = (FIXED, REDUNDANCY, MPC)  # in the paper's order


def names() -> tuple[str, ...]:
    """Every registered strategy: the built-ins in the paper's order, then the users' in the
    order they were loaded."""
    return tuple(_REGISTRY)


def info(name: str) -> StrategyInfo:
    """The registered strategy ``name``; ValueError with the choices otherwise."""
    entry = _REGISTRY.get(name)
    if entry is None:
        raise ValueError(f"unknown method {name!r}: choose from {', '.join(_REGISTRY)}")
    return entry


def is_registered(name: object) -> bool:
    return isinstance(name, str) and name in _REGISTRY


def ordered(chosen: Any) -> tuple[str, ...]:
    """``chosen`` names validated (ValueError for an unknown one), de-duplicated, in the
    registry's order (the built-ins first)."""
    chosen = tuple(chosen)
    for name in chosen:
        info(name)
    return tuple(n for n in _REGISTRY if n in chosen)


def create(name: str, backend: str = "daqp") -> Runner:
    """A new instance of strategy ``name``, wrapped to contain its faults (:class:`Runner`)."""
    entry = info(name)
    try:
        # the built-in MPC solves its QP on the walker's back-end; a user's class takes nothing
        strategy = entry.cls(backend) if entry.cls is PelvisMpcStrategy else entry.cls()
    except Exception as exc:  # noqa: BLE001 - the user's constructor: report it as theirs
        raise StrategyError(name, _exc_line(exc), _where(exc, entry)) from exc
    return Runner(strategy, entry)


# -- containing a strategy's faults ----------------------------------------------------------
def _where(exc: BaseException, entry: StrategyInfo) -> str:
    """``file.py:line`` of the innermost frame of ``exc`` in the strategy's own file (else
    the innermost frame)."""
    frames = traceback.extract_tb(exc.__traceback__)
    if not frames:
        return ""
    file = entry.file
    own = [f for f in frames if file and _same_file(f.filename, file)]
    f = (own or frames)[-1]
    return f"{os.path.basename(f.filename)}:{f.lineno}"


def _same_file(a: str, b: str) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _exc_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


class Runner:
    """One robot's strategy instance, called through a guard: its exceptions and bad return
    values become :class:`StrategyError` with the user's file and line."""

    __slots__ = ("strategy", "info", "_started", "_def_line", "_params")

    def __init__(self, strategy: PelvisStrategy, entry: StrategyInfo):
        self.strategy = strategy
        self.info = entry
        self._started = False
        self._def_line: str | None = None
        self._params: ControllerParams | None = None

    @property
    def plan(self) -> PelvisPlan | None:
        plan = self.strategy.plan
        return plan if isinstance(plan, PelvisPlan) else None

    def restart(self) -> None:
        """Call :meth:`PelvisStrategy.reset` again before the next tick (a new walk)."""
        self._started = False

    def waist_rate(self, s: StrategyInputs) -> float | None:
        """The strategy's rate for this tick, checked: None or a finite float."""
        strategy = self.strategy
        if s.params is not self._params:  # new parameters: the strategy's own, in force now
            self._params = s.params
            if self.info.name in OWN_PARAMS:
                strategy.params = s.params.own_params(self.info.name)
        try:
            if not self._started:
                strategy.reset(s)
                self._started = True
            rate = strategy.waist_rate(s)
        except Exception as exc:  # noqa: BLE001 - the user's code: contained, reported as theirs
            raise StrategyError(
                self.info.name, _exc_line(exc), _where(exc, self.info), s.step
            ) from exc
        if rate is None:
            return None
        if isinstance(rate, bool) or not isinstance(rate, (int, float, np.floating, np.integer)):
            raise StrategyError(
                self.info.name,
                f"waist_rate returned {type(rate).__name__} {_short(rate)}, not a number "
                "[rad/s] or None",
                self._definition(),
                s.step,
            )
        rate = float(rate)
        if not math.isfinite(rate):
            raise StrategyError(
                self.info.name,
                f"waist_rate returned {rate}, not a finite number [rad/s] or None",
                self._definition(),
                s.step,
            )
        return rate

    def _definition(self) -> str:
        """``file.py:line`` of the strategy's ``waist_rate`` definition."""
        if self._def_line is None:
            fn = type(self.strategy).waist_rate
            try:
                line = inspect.getsourcelines(fn)[1]
                file = inspect.getsourcefile(fn) or "?"
                self._def_line = f"{os.path.basename(file)}:{line}"
            except (OSError, TypeError):
                self._def_line = ""
        return self._def_line


def _short(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


# -- loading a user's file -------------------------------------------------------------------
def parse_source(source: str) -> tuple[str, str | None]:
    """``"FILE.py[:Class]"`` -> (file, class or None)."""
    file, sep, cls = source.rpartition(":")
    if not sep or not cls.isidentifier() or not file.endswith(".py"):
        return source, None
    return file, cls


def load_file(source: str) -> tuple[str, ...]:
    """Import ``FILE.py[:Class]`` and register its strategy classes (only ``Class`` if given);
    returns their names. Loading a file again is free unless it changed since (then its
    strategies are loaded anew and replace their earlier selves).

    Raises:
        StrategyLoadError: one line: a missing file, an import error (with the file and line),
            no strategy in the file, a bad name or colour, a name another strategy has.
    """
    file, cls_name = parse_source(source)
    path = os.path.abspath(os.path.expanduser(file))
    shown = file
    if not path.endswith(".py"):
        raise StrategyLoadError(f"{shown}: a strategy file must be a Python file (.py)")
    if not os.path.isfile(path):
        raise StrategyLoadError(f"{shown}: no such file")
    mtime = os.path.getmtime(path)
    key = (path, cls_name)
    seen = _LOADED.get(key)
    if seen is not None and seen[0] == mtime and all(n in _REGISTRY for n in seen[1]):
        return seen[1]
    module = _import(path, shown)
    found = [
        c
        for c in vars(module).values()
        if isinstance(c, type)
        and issubclass(c, PelvisStrategy)
        and c.__module__ == module.__name__
        and c.waist_rate is not PelvisStrategy.waist_rate
    ]
    if cls_name is not None:
        chosen = [c for c in found if c.__name__ == cls_name]
        if not chosen:
            have = ", ".join(c.__name__ for c in found) or "none"
            raise StrategyLoadError(
                f"{shown}: no PelvisStrategy subclass named {cls_name} (strategies in it: {have})"
            )
        found = chosen
    if not found:
        raise StrategyLoadError(
            f"{shown}: defines no strategy (a subclass of pelvic_walk.PelvisStrategy with "
            "a waist_rate method)"
        )
    infos = []
    for c in found:
        try:
            infos.append(register(c, f"{path}:{c.__name__}", replace=True))
        except ValueError as exc:
            raise StrategyLoadError(str(exc).replace(path, shown)) from None
    names_ = tuple(i.name for i in infos)
    if len(set(names_)) != len(names_):
        raise StrategyLoadError(f"{shown}: two strategies share a name: {', '.join(names_)}")
    for i in infos:  # each can be made (its constructor takes no arguments)
        try:
            create(i.name)
        except StrategyError as exc:
            del _REGISTRY[i.name]
            raise StrategyLoadError(f"{shown}: {i.cls.__name__}() failed: {exc}") from None
    _LOADED[key] = (mtime, names_)
    return names_


def _import(path: str, shown: str) -> Any:
    """The module of the file at ``path``, under a name of its own (its errors: one line).
    Its folder joins ``sys.path`` (as for a script run from there), so the file may import a
    module of its own that lies beside it."""
    digest = hashlib.sha1(path.encode()).hexdigest()[:12]
    name = f"pelvic_walk_user_{re.sub(r'[^0-9A-Za-z_]', '_', os.path.basename(path)[:-3])}_{digest}"
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise StrategyLoadError(f"{shown}: cannot be imported")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and pickling look classes up by their module
    folder = os.path.dirname(path)
    if folder not in sys.path:
        sys.path.append(folder)  # after the tool's own: a student's file cannot shadow them
    try:
        spec.loader.exec_module(module)
    except SyntaxError as exc:
        del sys.modules[name]
        raise StrategyLoadError(f"{shown}:{exc.lineno}: SyntaxError: {exc.msg}") from None
    except Exception as exc:  # noqa: BLE001 - the user's module: one line with its place
        del sys.modules[name]
        frames = [
            f for f in traceback.extract_tb(exc.__traceback__) if _same_file(f.filename, path)
        ]
        line = f":{frames[-1].lineno}" if frames else ""
        raise StrategyLoadError(f"{shown}{line}: {_exc_line(exc)}") from None
    return module


def load_files(sources: Any) -> tuple[str, ...]:
    """:func:`load_file` of each source, in order; the names of all their strategies."""
    out: list[str] = []
    for source in sources:
        out += [n for n in load_file(source) if n not in out]
    return tuple(out)


def user_sources() -> tuple[str, ...]:
    """``FILE.py:Class`` of every user strategy registered in this process (what a worker
    process must load to know the same names)."""
    return tuple(i.source for i in _REGISTRY.values() if i.source is not None)


def unregister(name: str) -> None:
    """Remove a user's strategy (tests, a notebook starting over); built-ins stay."""
    entry = _REGISTRY.get(name)
    if entry is not None and not entry.builtin:
        del _REGISTRY[name]
        _forget_params(name)
        for key, (_, loaded) in list(_LOADED.items()):
            if name in loaded:
                del _LOADED[key]
