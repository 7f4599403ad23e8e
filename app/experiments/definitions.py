"""The study, as data: which runs each section needs.

A run is a :class:`RunSpec`: method, step length, steps, arm swing, seed, and any other
parameter of ``controller/params.py`` as ``("group.name", value)`` overrides (a parameter sweep
varies those). Sections ask for runs with the *extracts* they need from each (a summary always;
``"step"``: one mid-walk step at full rate; ``"walk"``: the walking phase down-sampled;
``"zmp"``: ZMP and CoM paths with the footholds). The runner merges the requests, so a run
shared between sections runs once and carries the union of the extracts.

The sweep of the longest clean step (section 2) is adaptive: a coarse grid first
(:attr:`Study.sweep_grid`), then :func:`refinement_runs` fills the gap between each method's
last clean and first failed length at :attr:`Study.sweep_resolution`.

The paper's numbers are in :mod:`app.experiments.paper`; the lengths the paper's figures and
Table 1 use come from there.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from app.experiments import paper
from controller.params import GROUPS, LATERAL_MODES, METHODS, ControllerParams

ROTATING = ("redundancy", "mpc")
EXTRACTS = ("step", "walk", "zmp")
SEED_PERTURBATION = 0.01  # [rad] std of the seeded initial perturbation of a repeat
# A seeded repeat is also pushed through the whole run (app.sim.session.RunConfig): a
# horizontal force on the torso, each axis N(0, DISTURBANCE) [N], renewed every
# DISTURBANCE_PERIOD [s]. 5 N is 1 % of the robot's weight (~0.1 m/s^2 on the CoM): unmodelled
# pulls such as a tether or a hand on a safety rope. 10 N made the MPC fall at 0.40 m within 10
# steps (seed 0); at 5 N both 20-step probes at 0.40 m walked clean. Repeats then differ for
# the whole run, not only by a start-up transient that dies out.
DISTURBANCE = 5.0  # [N]
DISTURBANCE_PERIOD = 0.1  # [s]
# Parameters a RunSpec sets through its own fields; an override may not set them again.
_OWN_FIELDS = ("walk.step_length", "walk.n_steps", "arms.enabled")

Override = tuple[str, Any]  # ("group.name", value), e.g. ("pelvis.k_pel", 0.3)
# One axis of the sensitivity section: a parameter, its values off the default, the methods.
SensitivityAxis = tuple[str, tuple[Any, ...], tuple[str, ...]]
LATERAL = "pelvis.lateral_distance"
_DEFAULT_MODE = ControllerParams().pelvis.lateral_distance


def _check_override(name: str, value: Any) -> None:
    group, _, fname = name.partition(".")
    if group not in GROUPS:
        raise ValueError(f"override {name!r}: the group must be one of {', '.join(GROUPS)}")
    names = {f.name for f in dataclasses.fields(getattr(ControllerParams(), group))}
    if fname not in names:
        raise ValueError(f"override {name!r}: {group} has no parameter {fname!r}")
    if name in _OWN_FIELDS:
        raise ValueError(f"override {name!r}: set it with the RunSpec's own field")
    try:
        hash(value)  # the spec is a dict key
    except TypeError:
        raise ValueError(f"override {name!r}: {value!r} is not a single value") from None


@dataclass(frozen=True)
class RunSpec:
    """One closed-loop run; repeats differ by ``seed`` (when seeded: a 0.01 rad start
    perturbation and random pushes through the run, :data:`DISTURBANCE`).

    ``overrides`` sets any other parameter of :class:`ControllerParams`, as ``("group.name",
    value)`` pairs (kept sorted by name, so equal specs compare and hash equal).
    """

    method: str
    step_length: float  # [m]
    n_steps: int
    arms: bool = True
    seed: int | None = None
    overrides: tuple[Override, ...] = ()

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ValueError(f"method must be one of {', '.join(METHODS)}, got {self.method!r}")
        for name, value in self.overrides:
            _check_override(name, value)
        names = [name for name, _ in self.overrides]
        if len(set(names)) != len(names):
            raise ValueError(f"an override is given twice: {names}")
        object.__setattr__(self, "overrides", tuple(sorted(self.overrides, key=lambda o: o[0])))

    @property
    def perturbation(self) -> float:
        return SEED_PERTURBATION if self.seed is not None else 0.0

    @property
    def disturbance(self) -> float:
        """[N] std of the seeded pushes (0 without a seed)."""
        return DISTURBANCE if self.seed is not None else 0.0

    @property
    def key(self) -> str:
        """A readable, stable name: ``mpc_L0.300_n10_arms_s-`` (+ ``_pelvis.k_pel=0.3`` ...)."""
        arms = "arms" if self.arms else "noarms"
        seed = "-" if self.seed is None else str(self.seed)
        extra = "".join(f"_{name}={value}" for name, value in self.overrides)
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
        return ControllerParams().replace(method=self.method, **groups)


def length(x: float) -> float:
    """Step lengths on a millimetre grid, so equal lengths compare equal."""
    return round(float(x), 3)


@dataclass(frozen=True)
class Study:
    """What the study runs. :data:`FULL` reproduces the paper; :data:`QUICK` is a smoke run."""

    name: str
    n_steps: int  # steps of the sweep and figure runs
    mid_step: int  # the step index shown in the one-step figures
    sweep_grid: tuple[float, ...]  # coarse step lengths [m]
    sweep_resolution: float  # [m]
    energy_lengths: tuple[float, ...]  # Table 1
    energy_repeats: int
    energy_steps: int
    figure_lengths: tuple[float, ...] = paper.FIGURE_LENGTHS  # waist, yaw momentum
    kappa_lengths: tuple[float, ...] = paper.KAPPA_LENGTHS  # Fig. 13
    zmp_length: float = paper.ZMP_LENGTH  # Fig. 15
    methods: tuple[str, ...] = field(default=METHODS)
    overrides: tuple[Override, ...] = ()  # applied to every run (a sweep's cell)
    # the sensitivity section (app.sweep's limit search, one parameter at a time off its
    # default, plus the baseline); its walks have sensitivity_steps steps
    sensitivity: tuple[SensitivityAxis, ...] = ()
    sensitivity_steps: int = 6
    sensitivity_search: tuple[float, float, float] = (0.10, 0.60, 0.01)  # lo, hi, step [m]

    def figure_run(self, method: str, step_length: float, arms: bool = True) -> RunSpec:
        """The unseeded run every figure section shares at one (method, length)."""
        return RunSpec(method, length(step_length), self.n_steps, arms, None, self.overrides)

    def energy_runs(self, method: str, step_length: float) -> list[RunSpec]:
        return [
            RunSpec(method, length(step_length), self.energy_steps, True, seed, self.overrides)
            for seed in range(self.energy_repeats)
        ]

    def lateral_run(self, mode: str, step_length: float) -> RunSpec:
        """MPC at one figure length with one reading of the lateral distance (the default
        mode's run is the figure run)."""
        extra = () if mode == _DEFAULT_MODE else ((LATERAL, mode),)
        return RunSpec("mpc", length(step_length), self.n_steps, True, None, self.overrides + extra)

    def is_figure_run(self, spec: RunSpec) -> bool:
        """Whether ``spec`` is the figure run of its (method, length), arms on."""
        return spec == self.figure_run(spec.method, spec.step_length)


FULL = Study(
    name="full",
    n_steps=10,
    mid_step=4,
    sweep_grid=tuple(length(0.10 + 0.05 * i) for i in range(11)),  # 0.10 .. 0.60
    sweep_resolution=0.01,
    energy_lengths=paper.TABLE1_LENGTHS,
    energy_repeats=paper.TABLE1_RUNS,
    energy_steps=paper.TABLE1_STEPS,
    sensitivity=(
        ("walk.dsp_ratio", (0.1, 0.35), ("fixed", "mpc")),
        ("walk.step_time", (0.8, 1.4), ("fixed", "mpc")),
        ("pelvis.k_pel", (0.15, 0.45), ("mpc",)),  # the fixed pelvis does not read k_pel
        ("walk.dsp_split", ("both_ends",), ("fixed", "mpc")),
        (LATERAL, tuple(m for m in LATERAL_MODES if m != _DEFAULT_MODE), ("mpc",)),
    ),
)
# The full study made lighter for a shared or slow machine: Table 1 with 3 runs of 6 steps per
# cell (2 windows each) instead of the paper's 10 x 20, the step-length sweep refined to 0.02 m,
# and the sensitivity section's limit search over 0.20-0.60 m at 0.02 m with 4-step walks.
REDUCED = dataclasses.replace(
    FULL,
    name="reduced",
    sweep_resolution=0.02,
    energy_repeats=3,
    energy_steps=6,
    sensitivity_steps=4,
    sensitivity_search=(0.20, 0.60, 0.02),
)
QUICK = Study(
    name="quick",
    n_steps=6,
    mid_step=2,
    sweep_grid=(0.30, 0.40, 0.50),
    sweep_resolution=0.05,
    energy_lengths=(0.15, 0.30, 0.40),
    energy_repeats=2,
    energy_steps=6,
    sensitivity=(("walk.dsp_split", ("both_ends",), ("mpc",)),),
    sensitivity_steps=4,
    sensitivity_search=(0.30, 0.50, 0.05),
)

STUDIES: dict[str, Study] = {"full": FULL, "reduced": REDUCED, "quick": QUICK}
Requests = dict[RunSpec, set[str]]


def _add(req: Requests, spec: RunSpec, *extracts: str) -> None:
    req.setdefault(spec, set()).update(extracts)


def planned_runs(study: Study) -> Requests:
    """Every run known before any has finished, with the extracts each section needs."""
    req: Requests = {}
    for m in study.methods:  # section 2 (sweep) and section 6 near the limit: one step each
        for x in study.sweep_grid:
            _add(req, study.figure_run(m, x), "step")
    for x in study.figure_lengths:
        for m in ROTATING:  # section 3: waist angle and rate
            _add(req, study.figure_run(m, x), "step")
        for m in study.methods:  # section 4: yaw momentum with and without arms
            for arms in (True, False):
                _add(req, study.figure_run(m, x, arms), "walk")
    for x in study.kappa_lengths:  # section 6: kappa over one step
        for m in study.methods:
            _add(req, study.figure_run(m, x), "step")
    _add(req, study.figure_run("mpc", study.zmp_length), "zmp")  # section 7
    for x in study.figure_lengths:  # section 3: the lateral distance's readings
        for mode in LATERAL_MODES:
            _add(req, study.lateral_run(mode, x), "step")
    for x in study.energy_lengths:  # section 5: Table 1
        for m in study.methods:
            for spec in study.energy_runs(m, x):
                _add(req, spec)
    return req


def sweep_bracket(clean: dict[float, bool]) -> tuple[float | None, float | None]:
    """(last clean, first failed) lengths of one method; None where there is none.

    ``clean`` maps each length to the run's ``clean`` flag. The first failure is the shortest
    length that is not clean; the last clean is the longest clean length below it.
    """
    grid = sorted(clean)
    failed = [x for x in grid if not clean[x]]
    first_failed = failed[0] if failed else None
    below = [x for x in grid if clean[x] and (first_failed is None or x < first_failed)]
    return (below[-1] if below else None), first_failed


def refinement_lengths(study: Study, clean: dict[float, bool]) -> list[float]:
    """Lengths strictly between one method's last clean and first failed coarse length."""
    lo, hi = sweep_bracket(clean)
    if lo is None or hi is None:
        return []
    n = int(round((hi - lo) / study.sweep_resolution))
    return [length(lo + i * study.sweep_resolution) for i in range(1, n)]


def refinement_runs(study: Study, clean_by_method: dict[str, dict[float, bool]]) -> Requests:
    """Runs between each method's last clean and first failed coarse length.

    The fixed pelvis's refinement lengths are run for every method too: section 6 compares
    kappa(J) of all methods where the fixed pelvis nears and passes its own limit.
    """
    req: Requests = {}
    for m, clean in clean_by_method.items():
        for x in refinement_lengths(study, clean):
            _add(req, study.figure_run(m, x), "step")
    for x in refinement_lengths(study, clean_by_method.get("fixed", {})):
        for m in study.methods:
            _add(req, study.figure_run(m, x), "step")
    return req
