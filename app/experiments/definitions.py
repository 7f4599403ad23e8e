"""The study, as data: which runs each section needs.

A run is a :class:`~pelvic_walk.core.run_spec.RunSpec`: method, step length, steps, arm swing,
seed, and
any other parameter of ``controller/params.py`` as ``("group.name", value)`` overrides.
Sections ask for runs with the *extracts* they need from each (a summary always; ``"step"``:
one mid-walk step at full rate; ``"walk"``: the walking phase down-sampled; ``"zmp"``: ZMP and
CoM paths with the footholds). The runner merges the requests, so a run shared between
sections runs once and carries the union of the extracts.

The sweep of the longest clean step (section 2) is adaptive: a coarse grid first
(:attr:`Study.sweep_grid`), then :func:`refinement_runs` fills the gap between each method's
last clean and first failed length at :attr:`Study.sweep_resolution`. The sensitivity
section (:class:`Sensitivity`) runs the core's limit search (``pelvic_walk.core.measure``) over a
grid of two parameters
and a few more cells; the robustness section reads Table 1's seeded repeats and adds seeded
walks under larger pushes (:class:`Falls`) and the largest sideways push each method survives
in both directions (:class:`Pushes`, ``pelvic-walk push-study``), also in the sensitivity cells
whose gain the report states.

The paper's numbers are in :mod:`app.experiments.paper`; the lengths the paper's figures and
Table 1 use come from there.
"""

from __future__ import annotations

import functools
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from app.experiments import paper
from controller import strategy
from controller.params import GROUPS, LATERAL_MODES, ControllerParams
from controller.strategy import FIXED, MPC, REDUNDANCY
from pelvic_walk.core.run_spec import (
    DISTURBANCE,
    DISTURBANCE_PERIOD,
    SEED_PERTURBATION,
    Override,
    RunSpec,
    length,
)

__all__ = [  # the run's own names, for the modules and tests that read them here
    "DISTURBANCE",
    "DISTURBANCE_PERIOD",
    "SEED_PERTURBATION",
    "RunSpec",
    "length",
]

ROTATING = (REDUNDANCY, MPC)
EXTRACTS = ("step", "walk", "zmp")
LATERAL = "pelvis.lateral_distance"
REFERENCE = "pelvis.reference"  # what the reference angle is computed from (an ablation)
_DEFAULT_MODE = ControllerParams().pelvis.lateral_distance
# The authors' public implementation: 0.18 s on both feet at each end of a 1.2 s step, so a
# share of 0.36 / 1.2 = 0.30 of the step split half before the lift-off and half after the
# touch-down (walk.dsp_split = both_ends), and half a step width of 0.1278 m. Its 0.06 s rest
# in the step has no counterpart in our plan.
AUTHORS_DSP = 0.30  # share of the step on both feet
AUTHORS_WIDTH = 0.2556  # [m] step width
AUTHORS = (
    ("walk.dsp_ratio", AUTHORS_DSP),
    ("walk.dsp_split", "both_ends"),
    ("walk.step_width", AUTHORS_WIDTH),
)
AUTHORS_REST = 0.06  # [s] their rest within the step
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"  # the checkout's example strategies


@dataclass(frozen=True)
class SensitivityCell:
    """One cell of the sensitivity section beside the grid: parameters off their defaults."""

    name: str  # in words
    overrides: tuple[Override, ...]
    methods: tuple[str, ...] = (FIXED, MPC)


@dataclass(frozen=True)
class Sensitivity:
    """The sensitivity section: the longest step that walks and the longest clean one (at the
    default thresholds and at each of ``landings`` and ``kappas``) over a grid of two
    parameters (``rows`` x ``columns``) and the extra ``cells``, for ``methods``."""

    rows: tuple[str, tuple[Any, ...]]  # parameter, values
    columns: tuple[str, tuple[Any, ...]]
    cells: tuple[SensitivityCell, ...] = ()
    methods: tuple[str, ...] = (FIXED, MPC)
    steps: int = 6  # steps of each walk of the limit search
    search: tuple[float, float, float] = (0.25, 0.55, 0.01)  # lo, hi, resolution [m]
    first: float = 0.40  # [m] tried first: the length the heatmap reads the waist at
    landings: tuple[float, ...] = (0.01, 0.02, 0.03, 0.04)  # [m] landing-error thresholds
    kappas: tuple[float, ...] = (300.0, 1000.0, 3000.0)  # kappa(legs) bounds


@dataclass(frozen=True)
class Pushes:
    """The largest sideways push each method survives
    (``pelvic_walk.core.pushes.largest_survived``), in
    both directions, bracketed to ``resolution``; and the same at ``trade_length`` in the
    sensitivity cells whose gain the report states (the push margin beside the gain)."""

    lengths: tuple[float, ...] = (0.20, 0.30, 0.40)  # [m]
    directions: tuple[str, ...] = ("left", "right")
    duration: float = 0.1  # [s]
    resolution: float = 2.0  # [N] largest bracket (survived .. toppled)
    f_high: float = 256.0  # [N] top of the bisection (a power of two times the resolution)
    trade_length: float = 0.30  # [m] where the sensitivity cells' push margin is measured
    # the stability claim's pushes beyond mid single support of the third step: at
    # ``grid_length``, each (pushed step, phase of its single support) below, both directions
    grid_length: float = 0.30  # [m]
    grid: tuple[tuple[int, float], ...] = ((2, 0.25), (2, 0.75), (3, 0.25), (3, 0.5), (3, 0.75))


@dataclass(frozen=True)
class Falls:
    """Seeded walks under random pushes larger than the study's (Table 1's repeats are the
    study's own size): the same pushes as a repeat's, each axis N(0, ``force``)."""

    force: float = 15.0  # [N] std of each axis (three times DISTURBANCE)
    step_length: float = 0.30  # [m]
    walks: int = 20  # seeds 0 .. walks - 1
    steps: int = 10  # the figure runs' walk (Table 1's 20 would double the study's cost)


@dataclass(frozen=True)
class Ablations:
    """Section 10: strategies beside the paper's MPC on the same measures (longest clean step,
    waist, energy, kappa, push survival at ``push_length``). ``files`` are pelvis strategies
    (``FILE.py[:Class]``, relative to the checkout's ``examples/`` folder unless absolute); a
    user's ``--strategy`` files join them (:attr:`Study.strategies`)."""

    files: tuple[str, ...] = ("track_reference.py", "feedforward_sine.py")
    push_length: float = 0.30  # [m]


@functools.cache
def _skipped(why: str) -> None:
    """Say once (on stderr) why an example is left out of section 10."""
    print(f"note: {why}", file=sys.stderr)


def _example(source: str) -> str:
    file, cls = strategy.parse_source(source)
    if not os.path.isabs(file):
        file = str(EXAMPLES / file)
    return f"{file}:{cls}" if cls else file


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
    methods: tuple[str, ...] = field(default=strategy.BUILTINS)
    overrides: tuple[Override, ...] = ()  # applied to every run (a sweep's cell)
    sensitivity: Sensitivity | None = None  # section 8 (None: not run)
    pushes: Pushes | None = None  # the robustness section's push survival (None: not run)
    falls: Falls | None = None  # the robustness section's walks under larger pushes
    ablations: Ablations | None = None  # section 10 (None: not run)
    strategies: tuple[str, ...] = ()  # the user's --strategy files: rows of section 10

    def ablation_methods(self) -> tuple[str, ...]:
        """The strategies of section 10 beside the paper's (loaded here, in order; a missing
        example file is skipped: an installed package has no ``examples/``)."""
        if self.ablations is None and not self.strategies:
            return ()
        yours = strategy.load_files(self.strategies)  # loaded first: a name is theirs
        examples: list[str] = []
        for source in self.ablations.files if self.ablations else ():
            path = _example(source)
            if not os.path.isfile(strategy.parse_source(path)[0]):
                continue
            try:
                examples += strategy.load_file(path)
            except strategy.StrategyLoadError as exc:  # e.g. a copy of it under its name
                _skipped(f"section 10 leaves out the example {source}: {exc}")
        names = dict.fromkeys([*examples, *yours])  # in order, once each
        return tuple(m for m in names if m not in self.methods)

    def overrides_for(self, method: str) -> tuple[Override, ...]:
        """The study's overrides a method's runs take: the paper's parameters, and a
        strategy's own ones only for that strategy (``experiments --set gain.k=12`` changes
        the runs of ``gain``, not the MPC's)."""
        return tuple(
            (name, value)
            for name, value in self.overrides
            if name.partition(".")[0] in GROUPS or name.partition(".")[0] == method
        )

    def figure_run(self, method: str, step_length: float, arms: bool = True) -> RunSpec:
        """The unseeded run every figure section shares at one (method, length)."""
        return RunSpec(
            method, length(step_length), self.n_steps, arms, None, self.overrides_for(method)
        )

    def energy_runs(self, method: str, step_length: float) -> list[RunSpec]:
        return [
            RunSpec(
                method,
                length(step_length),
                self.energy_steps,
                True,
                seed,
                self.overrides_for(method),
            )
            for seed in range(self.energy_repeats)
        ]

    def falls_runs(self, method: str) -> list[RunSpec]:
        """The seeded walks of :attr:`falls` (none when it is not run)."""
        f = self.falls
        if f is None:
            return []
        x = length(f.step_length)
        return [
            RunSpec(method, x, f.steps, True, seed, self.overrides_for(method), push_std=f.force)
            for seed in range(f.walks)
        ]

    def ablation_run(self, step_length: float) -> RunSpec:
        """MPC at one figure length with the reference angle computed from the state now,
        held over the horizon (no prediction; ``pelvis.reference``)."""
        extra = ((REFERENCE, "now"),)
        return RunSpec(
            MPC, length(step_length), self.n_steps, True, None, self.overrides_for(MPC) + extra
        )

    def lateral_run(self, mode: str, step_length: float) -> RunSpec:
        """MPC at one figure length with one reading of the lateral distance (the default
        mode's run is the figure run)."""
        extra = () if mode == _DEFAULT_MODE else ((LATERAL, mode),)
        return RunSpec(
            MPC, length(step_length), self.n_steps, True, None, self.overrides_for(MPC) + extra
        )

    def is_figure_run(self, spec: RunSpec) -> bool:
        """Whether ``spec`` is the figure run of its (method, length), arms on."""
        return spec == self.figure_run(spec.method, spec.step_length)


AUTHORS_CELL = "the authors' DSP and step width"
BETA_CELL = "the paper's beta_pel (1e-10)"
NO_ACC_BOUND_CELL = "no yaw-acceleration bound (pelvis.acc_limit = 100)"
# the paper's values of parameters where ours differ (app.experiments.deviations)
_PAPER_CELLS = (
    SensitivityCell(BETA_CELL, (("pelvis.beta", 1e-10),), (MPC,)),
    SensitivityCell(NO_ACC_BOUND_CELL, (("pelvis.acc_limit", 100.0),), (MPC,)),
)
_LATERAL_CELLS = tuple(
    SensitivityCell(f"lateral distance: {m}", ((LATERAL, m),), (MPC,))
    for m in LATERAL_MODES
    if m != _DEFAULT_MODE
)
FULL = Study(
    name="full",
    n_steps=10,
    mid_step=4,
    sweep_grid=tuple(length(0.10 + 0.05 * i) for i in range(11)),  # 0.10 .. 0.60
    sweep_resolution=0.01,
    energy_lengths=paper.TABLE1_LENGTHS,
    energy_repeats=paper.TABLE1_RUNS,
    energy_steps=paper.TABLE1_STEPS,
    sensitivity=Sensitivity(
        rows=("pelvis.k_pel", (0.15, 0.25, 0.35, 0.45)),
        columns=("walk.dsp_ratio", (0.1, 0.2, 0.3)),
        cells=(
            SensitivityCell(AUTHORS_CELL, AUTHORS),
            *_LATERAL_CELLS,
            *_PAPER_CELLS,
        ),
    ),
    pushes=Pushes(),
    falls=Falls(),
    ablations=Ablations(),
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
    sensitivity=Sensitivity(
        rows=("pelvis.k_pel", (0.25, 0.45)),
        columns=("walk.dsp_ratio", (0.2, 0.3)),
        cells=(SensitivityCell(AUTHORS_CELL, AUTHORS),),
        steps=4,
        search=(0.30, 0.50, 0.05),
        landings=(0.01, 0.02, 0.03),
        kappas=(300.0, 1000.0),
    ),
    pushes=Pushes(lengths=(0.30,), resolution=64.0, grid=((3, 0.5),)),  # one extra condition
    falls=Falls(walks=3, steps=6),
    ablations=Ablations(),
)

STUDIES: dict[str, Study] = {"full": FULL, "quick": QUICK}
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
    _add(req, study.figure_run(MPC, study.zmp_length), "zmp")  # section 7
    for x in study.figure_lengths:  # section 3: the lateral distance's readings, the ablation
        for mode in LATERAL_MODES:
            _add(req, study.lateral_run(mode, x), "step")
        _add(req, study.ablation_run(x), "step")
    for m in study.methods:  # section 8: walks under larger pushes
        for spec in study.falls_runs(m):
            _add(req, spec)
    for x in study.energy_lengths:  # section 5: Table 1
        for m in study.methods:
            for spec in study.energy_runs(m, x):
                _add(req, spec)
    for m in study.ablation_methods():  # section 10: the sweep and the figure lengths
        for x in sorted({*study.sweep_grid, *study.figure_lengths}):
            _add(req, study.figure_run(m, x), "step")
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
    kappa of all methods where the fixed pelvis nears and passes its own limit.
    """
    req: Requests = {}
    for m, clean in clean_by_method.items():
        for x in refinement_lengths(study, clean):
            _add(req, study.figure_run(m, x), "step")
    for x in refinement_lengths(study, clean_by_method.get(FIXED, {})):
        for m in study.methods:
            _add(req, study.figure_run(m, x), "step")
    return req
