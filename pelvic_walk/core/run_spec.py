"""One closed-loop run as plain data: :class:`RunSpec` (what the study and a sweep run).

A spec is method, step length, steps, arm swing, seed, and any other parameter of
``controller/params.py`` as ``("group.name", value)`` overrides, or one of the strategy's own
(``("gain.k", 4.0)``: its ``Params``); a name under a strategy for a paper parameter
(``mpc.alpha``) is stored by the paper's name (``pelvis.alpha``). It crosses process and Ray
boundaries as it is (no MuJoCo or Pinocchio object): a worker builds its own run from
:meth:`RunSpec.config`. The method is a registered pelvis strategy (``controller.strategy``);
a user's strategy travels as its file (``strategy_file``: the path and class), which a worker
that does not know the name yet loads (before it reads the overrides: its own parameters are
known once it is loaded).

A *seeded* spec is one of the study's repeats: a 0.01 rad perturbation of the initial state and
a horizontal force on the torso through the whole run, each axis N(0, :data:`DISTURBANCE`)
renewed every :data:`DISTURBANCE_PERIOD` (``pelvic_walk.core.session.RunConfig``). 5 N is 1 % of the
robot's weight (~0.1 m/s^2 on the CoM): unmodelled pulls such as a tether or a hand on a safety
rope. Repeats then differ for the whole run, not only by a start-up transient that dies out.
A spec may ask for pushes of another size (``push_std``, e.g. the robustness section's 15 N).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from controller import strategy
from controller.params import GROUPS, ControllerParams, check_value
from pelvic_walk.core.params import meta_of

if TYPE_CHECKING:
    from pelvic_walk.core.session import RunConfig

SEED_PERTURBATION = 0.01  # [rad] std of the seeded initial perturbation of a repeat
DISTURBANCE = 5.0  # [N] std of each axis of the seeded pushes
DISTURBANCE_PERIOD = 0.1  # [s] a push is held this long, then drawn again
# Parameters a RunSpec sets through its own fields; an override may not set them again.
OWN_FIELDS = ("walk.step_length", "walk.n_steps", "arms.enabled")

Override = tuple[str, Any]  # ("group.name", value), e.g. ("pelvis.k_pel", 0.3)


def _shown(source: str) -> str:
    """A strategy's ``FILE.py:Class`` as a command shows it: relative to the working folder
    when it lies inside it (a report's commands then hold in any clone)."""
    file, cls = strategy.parse_source(source)
    rel = os.path.relpath(file)
    shown = file if rel.startswith("..") else rel
    return f"{shown}:{cls}" if cls else shown


def length(x: float) -> float:
    """Step lengths on a millimetre grid, so equal lengths compare equal."""
    return round(float(x), 3)


def _check_override(name: str, value: Any, method: str) -> str:
    """The stored name of an override of a run of ``method``, checked: a known parameter (the
    paper's ``group.name``, a name under a strategy such as ``mpc.alpha``, or ``method``'s own
    ``NAME.FIELD``), not one of the spec's own fields, a single value in its range."""
    try:
        group, fname, meta = meta_of(name)
    except ValueError:
        mine = ", ".join(strategy.own_fields(method)) or "none"
        raise ValueError(
            f"override {name!r}: no such parameter (GROUP.NAME of controller/params.py, or "
            f"NAME.FIELD of a strategy's own; {method}'s: {mine})"
        ) from None
    stored = f"{group}.{fname}"
    if group not in GROUPS and group != method:
        raise ValueError(
            f"override {name!r}: a parameter of the strategy {group!r}, not of this run's "
            f"{method!r}"
        )
    if stored in OWN_FIELDS:
        raise ValueError(f"override {name!r}: set it with the RunSpec's own field")
    try:
        hash(value)  # the spec is a dict key
    except TypeError:
        raise ValueError(f"override {name!r}: {value!r} is not a single value") from None
    check_value(group, fname, value, meta)
    return stored


@dataclass(frozen=True)
class RunSpec:
    """One closed-loop run; repeats differ by ``seed`` (see the module docstring).

    ``overrides`` sets any other parameter of :class:`ControllerParams`, as ``("group.name",
    value)`` pairs, or the strategy's own (``("gain.k", 4.0)``), kept by their stored names and
    sorted (equal specs compare and hash equal).
    """

    method: str  # a registered strategy's name
    step_length: float  # [m]
    n_steps: int
    arms: bool = True
    seed: int | None = None
    overrides: tuple[Override, ...] = ()
    push_std: float | None = None  # [N] the seeded pushes' size (None: DISTURBANCE)
    # "FILE.py:Class" of a user's strategy (filled in from the registry; None: a built-in)
    strategy_file: str | None = None

    def __post_init__(self) -> None:
        if self.push_std is not None and (self.seed is None or not self.push_std >= 0.0):
            raise ValueError(f"push_std needs a seed and must be >= 0 N, got {self.push_std!r}")
        if self.strategy_file is not None:
            try:
                loaded = strategy.load_file(self.strategy_file)
            except strategy.StrategyLoadError as exc:
                raise ValueError(str(exc)) from None
            if self.method not in loaded:
                raise ValueError(f"{self.strategy_file} defines no strategy {self.method!r}")
        else:
            object.__setattr__(self, "strategy_file", strategy.info(self.method).source)
        checked = [(_check_override(n, v, self.method), v) for n, v in self.overrides]
        names = [name for name, _ in checked]
        if len(set(names)) != len(names):
            raise ValueError(f"an override is given twice: {names}")
        object.__setattr__(self, "overrides", tuple(sorted(checked, key=lambda o: o[0])))

    @property
    def perturbation(self) -> float:
        """[rad] std of the seeded initial perturbation (0 without a seed)."""
        return SEED_PERTURBATION if self.seed is not None else 0.0

    @property
    def disturbance(self) -> float:
        """[N] std of the seeded pushes (0 without a seed)."""
        if self.seed is None:
            return 0.0
        return DISTURBANCE if self.push_std is None else self.push_std

    @property
    def key(self) -> str:
        """A readable, stable name: ``mpc_L0.300_n10_arms_s-`` (+ ``_pelvis.k_pel=0.3`` ...,
        ``_push15N`` for pushes of another size than the study's)."""
        arms = "arms" if self.arms else "noarms"
        seed = "-" if self.seed is None else str(self.seed)
        extra = "".join(f"_{name}={value}" for name, value in self.overrides)
        if self.push_std is not None and self.push_std != DISTURBANCE:
            extra += f"_push{self.push_std:g}N"
        return f"{self.method}_L{self.step_length:.3f}_n{self.n_steps}_{arms}_s{seed}{extra}"

    def params(self) -> ControllerParams:
        """The controller's parameters of this run (defaults, the fields, then the overrides)."""
        groups: dict[str, dict[str, Any]] = {
            "walk": {"step_length": self.step_length, "n_steps": self.n_steps},
            "arms": {"enabled": self.arms},
        }
        for name, value in self.overrides:
            group, _, fname = name.partition(".")
            groups.setdefault(group, {})[fname] = value
        self.load_strategy()
        return ControllerParams().replace(method=self.method, **groups)

    def load_strategy(self) -> None:
        """Register the spec's strategy in this process if it is a user's not known here (a
        worker process or a Ray task: the spec crossed without running ``__init__``)."""
        if self.strategy_file is not None and not strategy.is_registered(self.method):
            strategy.load_file(self.strategy_file)

    def config(self) -> RunConfig:
        """The headless run of this spec (``pelvic_walk.core.run.run`` takes it)."""
        from pelvic_walk.core.session import RunConfig

        return RunConfig(
            params=self.params(),
            seed=self.seed,
            perturbation=self.perturbation,
            disturbance=self.disturbance,
            disturbance_period=DISTURBANCE_PERIOD,
        )

    def command(self) -> str:
        """The ``pelvic-walk simulate`` command line that reruns this spec."""
        parts = [
            "pelvic-walk simulate",
            f"--strategy {_shown(self.strategy_file)}"
            if self.strategy_file
            else f"--method {self.method}",
            f"--step-length {self.step_length:g}",
            f"--steps {self.n_steps}",
        ]
        if not self.arms:
            parts.append("--no-arms")
        if self.seed is not None:
            parts.append(f"--seed {self.seed}")
        if self.push_std is not None and self.push_std != DISTURBANCE:
            parts.append(f"--disturbance {self.push_std:g}")
        parts += [f"--set {name}={value}" for name, value in self.overrides]
        known = strategy.info(self.method) if strategy.is_registered(self.method) else None
        if known is not None and not known.builtin and self.strategy_file is None:
            # a class defined in this process (a notebook): no file the command could load
            parts.append(f"  # {self.method} is defined in your session: save it in a file and "
                         "run it with --strategy FILE.py")  # fmt: skip
        return " ".join(parts)
