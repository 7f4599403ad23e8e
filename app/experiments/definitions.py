"""The study, as data: which runs each section needs, and the paper's numbers beside ours.

A run is a :class:`RunSpec` (method, step length, steps, arm swing, seed). Sections ask for
runs with the *extracts* they need from each (a summary always; ``"step"``: one mid-walk step
at full rate; ``"walk"``: the walking phase down-sampled; ``"zmp"``: ZMP and CoM paths with the
footholds). The runner merges the requests, so a run shared between sections runs once and
carries the union of the extracts.

The sweep of the longest clean step (section 2) is adaptive: a coarse grid first
(:attr:`Study.sweep_grid`), then :func:`refinement_runs` fills the gap between each method's
last clean and first failed length at :attr:`Study.sweep_resolution`.

Paper numbers are copied from Park & Park (IEEE Access 2022), :data:`PAPER_CITATION`; the
section, table or figure they come from is named beside each.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from controller.params import METHODS

PAPER_CITATION = (
    'B. Park and J. Park, "Optimization of Pelvic Rotation Walking Pattern Considering Future '
    'States Using Model Predictive Control to Increase the Step Length", IEEE Access, 2022, '
    "doi:10.1109/ACCESS.2022.3169886"
)
METHOD_LABELS = {
    "fixed": "fixed pelvis (W/O rotation)",
    "redundancy": "rotation by redundancy [21]",
    "mpc": "rotation by MPC (proposed)",
}
ROTATING = ("redundancy", "mpc")

# -- the paper's numbers ----------------------------------------------------------------------
# Sec. II, eq. (1)-(5): l_leg 0.75, z0 0.68, l_pel 0.21, w_step 0.243, theta 45 deg.
PAPER_ROBOT = {"l_leg": 0.75, "z0": 0.68, "l_pel": 0.21, "w_step": 0.243, "theta_pel_deg": 45.0}
PAPER_KINEMATICS = {"step_max_fixed": 0.31, "step_max_rotation": 0.42, "increase_percent": 35.0}
# Sec. VI-B: longest step walked in simulation [m].
PAPER_MAX_STEP = {"fixed": 0.30, "redundancy": 0.40, "mpc": 0.40}
# Sec. VI-C, Fig. 9(a): MPC waist angle from -22 to +22 deg over a 0.4 m step.
PAPER_WAIST_PEAK_DEG_040 = 22.0
# Sec. VI-F, Fig. 16 (experiment): arm swing cuts the yaw angular momentum by up to 60 %.
PAPER_ARM_REDUCTION_PERCENT = 60.0
# Sec. VI-E, Fig. 13: at 0.30 m kappa(J) of the fixed pelvis at landing is about twice the
# rotating methods'; at 0.35 m it diverges for the fixed pelvis.
PAPER_KAPPA_RATIO_030 = 2.0

# Table 1: energy during two steps [J] (the paper's header says "Mean (W)"; eq. (44) is an
# energy), mean and standard deviation over 100 windows (10 runs x 20 steps); None = "—"
# (the method could not walk that step length).
TABLE1_LENGTHS = (0.15, 0.20, 0.25, 0.30, 0.35, 0.40)
PAPER_TABLE1: dict[str, dict[float, tuple[float, float] | None]] = {
    "fixed": {
        0.15: (14.78, 2.89),
        0.20: (19.11, 5.55),
        0.25: (19.76, 10.23),
        0.30: (50.16, 22.32),
        0.35: None,
        0.40: None,
    },
    "redundancy": {
        0.15: (12.79, 3.04),
        0.20: (18.17, 6.12),
        0.25: (27.14, 9.16),
        0.30: (60.49, 28.55),
        0.35: (411.25, 208.41),
        0.40: (941.32, 597.6),
    },
    "mpc": {
        0.15: (10.06, 0.87),
        0.20: (16.92, 3.31),
        0.25: (26.53, 2.57),
        0.30: (157.92, 9.73),
        0.35: (309.64, 32.51),
        0.40: (412.34, 34.15),
    },
}

# -- runs ---------------------------------------------------------------------------------------
EXTRACTS = ("step", "walk", "zmp")


@dataclass(frozen=True, order=True)
class RunSpec:
    """One closed-loop run; repeats differ by ``seed`` (perturbation 0.01 when seeded)."""

    method: str
    step_length: float  # [m]
    n_steps: int
    arms: bool = True
    seed: int | None = None

    @property
    def perturbation(self) -> float:
        return 0.01 if self.seed is not None else 0.0

    @property
    def key(self) -> str:
        arms = "arms" if self.arms else "noarms"
        seed = "-" if self.seed is None else str(self.seed)
        return f"{self.method}_L{self.step_length:.3f}_n{self.n_steps}_{arms}_s{seed}"


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
    figure_lengths: tuple[float, ...]  # waist (Fig. 8-9) and yaw momentum (Fig. 12)
    kappa_lengths: tuple[float, ...]  # Fig. 13
    zmp_length: float  # Fig. 15
    energy_lengths: tuple[float, ...]  # Table 1
    energy_repeats: int
    energy_steps: int
    methods: tuple[str, ...] = field(default=METHODS)

    def figure_run(self, method: str, step_length: float, arms: bool = True) -> RunSpec:
        """The unseeded run every figure section shares at one (method, length)."""
        return RunSpec(method, length(step_length), self.n_steps, arms)

    def energy_runs(self, method: str, step_length: float) -> list[RunSpec]:
        return [
            RunSpec(method, length(step_length), self.energy_steps, True, seed)
            for seed in range(self.energy_repeats)
        ]


FULL = Study(
    name="full",
    n_steps=10,
    mid_step=4,
    sweep_grid=tuple(length(0.10 + 0.05 * i) for i in range(11)),  # 0.10 .. 0.60
    sweep_resolution=0.01,
    figure_lengths=(0.30, 0.40),
    kappa_lengths=(0.30, 0.35, 0.40),
    zmp_length=0.30,
    energy_lengths=TABLE1_LENGTHS,
    energy_repeats=10,
    energy_steps=20,
)
QUICK = Study(
    name="quick",
    n_steps=6,
    mid_step=2,
    sweep_grid=(0.30, 0.40, 0.50),
    sweep_resolution=0.05,
    figure_lengths=(0.30, 0.40),
    kappa_lengths=(0.30, 0.35, 0.40),
    zmp_length=0.30,
    energy_lengths=(0.15, 0.30, 0.40),
    energy_repeats=2,
    energy_steps=6,
)

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
    for x in study.energy_lengths:  # section 5: Table 1
        for m in study.methods:
            for spec in study.energy_runs(m, x):
                _add(req, spec)
    return req


def sweep_bracket(study: Study, clean: dict[float, bool]) -> tuple[float | None, float | None]:
    """(last clean, first failed) coarse lengths of one method; None where there is none.

    ``clean`` maps each coarse length to the run's ``clean`` flag. The first failure is the
    shortest length that is not clean; the last clean is the longest clean length below it.
    """
    grid = sorted(clean)
    failed = [x for x in grid if not clean[x]]
    first_failed = failed[0] if failed else None
    below = [x for x in grid if clean[x] and (first_failed is None or x < first_failed)]
    return (below[-1] if below else None), first_failed


def refinement_lengths(study: Study, clean: dict[float, bool]) -> list[float]:
    """Lengths strictly between one method's last clean and first failed coarse length."""
    lo, hi = sweep_bracket(study, clean)
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
