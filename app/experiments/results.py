"""Typed results: what a run sends back, what each section measures, what the report shows.

- :class:`RunResult` (one run: spec, summary, extracts), built by :mod:`app.experiments.worker`;
- one dataclass per section (:class:`MaxStep`, :class:`WaistCase`, ...), built by
  :mod:`app.experiments.sections`;
- :class:`StudyResults`, everything ``results.json`` and ``report.md`` show; :func:`to_json`
  writes it (``dataclasses.asdict``, NaN / inf as null).

Cases of a section are keyed ``"<method>@<length>"`` (:func:`case_key`), energy cells by
``"<length>"`` (:func:`length_key`), both with two decimals.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from app.experiments.definitions import RunSpec
from app.experiments.paper import KinematicLimits

if TYPE_CHECKING:
    from app.experiments.results_more import BalanceSection, LateralSection, SensitivitySection

Samples = list[float | None]  # a series as JSON-safe floats (None = NaN / inf)


def length_key(x: float) -> str:
    return f"{x:.2f}"


def case_key(method: str, x: float) -> str:
    return f"{method}@{x:.2f}"


def samples(values: Any) -> Samples:
    """A float array as a JSON-safe list (NaN / inf -> None)."""
    return [float(v) if math.isfinite(v) else None for v in np.asarray(values, dtype=float)]


def array(values: Samples) -> np.ndarray:
    """The inverse of :func:`samples` (None -> NaN)."""
    return np.array([np.nan if v is None else v for v in values], dtype=float)


# -- one run --------------------------------------------------------------------------------
@dataclass(frozen=True)
class RunSummary:
    """The summary keys of a run (``app.runs``) the study reads, plus kappa at the step events.

    ``other`` keeps every further key of the run's summary, so ``results.json`` shows them all.
    """

    method: str
    arms: bool
    step_length: float  # [m]
    steps_planned: int
    steps_completed: int
    success: bool
    fell: bool
    fall_time: float | None  # [s]
    fall_reason: str | None
    clean: bool  # app.runs' criterion: see sections.failure_reasons
    landing_error_max: float | None  # [m]
    condition_number_max: float  # kappa(J) of J_low, walking phase
    speed_limited_ticks: int
    servo_saturation_substeps: int
    solver_failures: int
    solver_failures_by_layer: dict[str, int]
    waist_yaw_max_deg: float
    yaw_momentum_peak: float  # [kg m^2/s]
    zmp_in_support_ratio: float
    energy_two_step_windows: list[float]  # [J] eq. (44), one per two-step window
    sim_time: float  # [s]
    kappa_liftoff: Samples  # max kappa(J) within +/- 50 ms of each walking step's lift-off
    kappa_landing: Samples  # ... and of each landing
    kappa_legs_liftoff: Samples = field(default_factory=list)  # the same, leg columns
    kappa_legs_landing: Samples = field(default_factory=list)
    # kappa of J_low's 12 leg columns, walking phase: what the clean criterion reads
    condition_number_legs_max: float | None = None
    other: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def from_run(cls, summary: dict[str, Any], **extra: Any) -> RunSummary:
        """From ``Session.summary()`` (every key kept) and the worker's ``extra`` keys."""
        names = {f.name for f in dataclasses.fields(cls)} - {"other"}
        merged = {**summary, **extra}
        return cls(
            **{k: v for k, v in merged.items() if k in names},
            other={k: v for k, v in merged.items() if k not in names},
        )

    def as_dict(self) -> dict[str, Any]:
        """Every key of the run's summary, flat, as the run returned it."""
        d = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "other"}
        return {**d, **self.other}


@dataclass(frozen=True)
class StepExtract:
    """One mid-walk step at 200 Hz; times from the step's start [s]."""

    t: Samples
    waist_angle_cmd: Samples  # [rad]
    waist_angle: Samples  # [rad]
    waist_rate: Samples  # [rad/s]
    theta_ref: Samples  # [rad] the MPC's reference angle, first horizon sample
    kappa: Samples  # kappa(J), capped
    step_index: int
    step_start: float  # [s]
    duration: float  # [s]
    dsp: float  # [s]
    theta_ref_lead: float  # [s] theta_ref refers to this long after the row's time
    swing_side: int
    complete: bool  # the step ended before any fall


@dataclass(frozen=True)
class WalkExtract:
    """The walking phase at 100 Hz."""

    t: Samples
    yaw_momentum: Samples  # [kg m^2/s] whole body about the CoM
    h_low: Samples
    h_up: Samples
    step_start: Samples  # [s] every step's start


@dataclass(frozen=True)
class ZmpExtract:
    """ZMP and CoM paths of the walking phase at 100 Hz, the footholds, shares inside."""

    t: Samples
    cop_x: Samples
    cop_y: Samples
    lipm_zmp_x: Samples
    lipm_zmp_y: Samples
    com_x: Samples
    com_y: Samples
    com_des_x: Samples
    com_des_y: Samples
    zmp_ref_x: Samples
    zmp_ref_y: Samples
    zmp_in_support: Samples
    footholds: list[list[float]]  # (n + 2, 2) [m]
    lipm_in_planned_support: float
    cop_in_planned_support: float
    cop_in_measured_support: float


@dataclass(frozen=True)
class Extracts:
    """The extracts a run's sections asked for (the names of ``definitions.EXTRACTS``)."""

    step: StepExtract | None = None
    walk: WalkExtract | None = None
    zmp: ZmpExtract | None = None


@dataclass(frozen=True)
class RunResult:
    """What a worker sends back: ``summary`` None (and ``error`` set) when the run crashed."""

    spec: RunSpec
    summary: RunSummary | None
    extracts: Extracts = field(default_factory=Extracts)
    error: str | None = None
    wall_s: float = 0.0

    @property
    def clean(self) -> bool:
        return self.summary is not None and self.summary.clean


Results = dict[RunSpec, RunResult]


# -- sections -------------------------------------------------------------------------------
@dataclass(frozen=True)
class KinematicsSection:
    """Section 1: eq. (1)-(5) (``controller.analysis.kinematic_analysis``'s keys)."""

    paper_reported: KinematicLimits
    paper_inputs: dict[str, float]
    paper_inputs_literal: dict[str, float]
    ours: dict[str, float]
    ours_literal: dict[str, float]


@dataclass(frozen=True)
class SweepPoint:
    """Section 2: one run of the sweep (None where the run crashed)."""

    step_length: float
    clean: bool
    fell: bool | None
    fall_reason: str | None
    steps_completed: int | None
    steps_planned: int | None
    landing_error_max: float | None
    speed_limited_ticks: int | None
    servo_saturation_substeps: int | None
    solver_failures: int | None
    condition_number_max: float | None
    waist_yaw_max_deg: float | None
    reasons: list[str]


@dataclass(frozen=True)
class MaxStep:
    """Section 2: one method's longest clean step."""

    paper: float
    longest_clean: float | None
    first_failed: float | None
    resolution: float | None  # the sweep's resolution where the bracket was refined to it
    clean_again_above_first_failure: list[float]
    binding_at_first_failure: SweepPoint | None
    points: list[SweepPoint]
    # the longest step that *walks* (no fall, every landing within 2 cm) and the first that
    # does not, from the same runs
    walks_limit: float | None = None
    walks_first_failed: float | None = None


@dataclass(frozen=True)
class ShareOfLimit:
    share_of_limit: float
    ours: float | None  # [m]


@dataclass(frozen=True)
class EquivalentRow:
    paper_length: float
    methods: dict[str, ShareOfLimit]


@dataclass(frozen=True)
class EquivalentLengths:
    """The paper's lengths as a share of each method's paper limit, and ours at that share."""

    paper_limits: dict[str, float]
    our_limits: dict[str, float | None]
    rows: list[EquivalentRow]


@dataclass(frozen=True)
class WaistCase:
    """Section 3: waist angle and rate over one mid-walk step."""

    method: str
    step_length: float
    complete: bool
    angle_start_deg: float
    angle_dsp_end_deg: float
    angle_end_deg: float
    angle_min_deg: float
    angle_max_deg: float
    peak_abs_angle_deg: float
    dsp_change_deg: float
    range_deg: float
    dsp_share_of_range: float
    peak_abs_rate_deg_s: float
    peak_abs_rate_change_deg_s2: float
    rate_at_liftoff_toward_swing_deg_s: float
    reversal_before_liftoff_s: float  # NaN: the rate never turned toward the swing
    dsp_time: float
    step_time: float
    step_index: int


@dataclass(frozen=True)
class WaistSection:
    cases: dict[str, WaistCase | None]


@dataclass(frozen=True)
class YawRun:
    """Section 4: one run's measured yaw momentum."""

    peak: float | None  # [kg m^2/s]
    rms: float | None
    clean: bool
    fell: bool
    reasons: list[str]


@dataclass(frozen=True)
class YawCase:
    method: str
    step_length: float
    arms: YawRun
    no_arms: YawRun
    peak_reduction_percent: float | None
    rms_reduction_percent: float | None


@dataclass(frozen=True)
class YawSection:
    cases: dict[str, YawCase]
    paper_reduction_percent: float


@dataclass(frozen=True)
class EnergyCell:
    """Section 5: one cell of Table 1, ours (over the runs that did not fall) and the paper's."""

    mean: float | None  # [J]
    std: float | None
    n_windows: int
    n_runs: int
    n_not_fallen: int
    n_clean: int
    paper_mean: float | None
    paper_std: float | None
    paper_dash: bool  # the paper has "—" (the method could not walk the length)
    run_means: list[float] = field(default_factory=list)  # [J] each repeat's mean window
    mean_substep: float | None = None  # [J] the same windows from every 1 ms substep
    std_substep: float | None = None
    per_joint_mean: list[float] = field(default_factory=list)  # [J] mean window, per joint


@dataclass(frozen=True)
class EnergySection:
    table: dict[str, dict[str, EnergyCell]]  # method -> length_key -> cell
    lengths: list[float]
    repeats: int
    steps: int
    # Welch's t-test over the repeats' means: "<length>:<a>-<b>" -> p-value
    p_values: dict[str, float] = field(default_factory=dict)
    joints: list[str] = field(default_factory=list)  # per_joint_mean's order

    def p_value(self, x: float, a: str, b: str) -> float | None:
        return self.p_values.get(
            f"{length_key(x)}:{a}-{b}", self.p_values.get(f"{length_key(x)}:{b}-{a}")
        )

    def cell(self, method: str, x: float) -> EnergyCell | None:
        """The cell where we measured a mean, else None."""
        c = self.table.get(method, {}).get(length_key(x))
        return c if c and c.mean is not None else None


@dataclass(frozen=True)
class KappaCase:
    """Section 6: kappa(J) of one run."""

    method: str
    step_length: float
    clean: bool
    fell: bool
    reasons: list[str]
    kappa_landing_median: float | None
    kappa_landing_max: float | None
    kappa_liftoff_median: float | None
    kappa_landing_mid_step: float | None
    kappa_step_peak: float | None
    kappa_run_max: float
    # the same on the 12 leg columns (the clean criterion's figure)
    kappa_legs_run_max: float | None = None
    kappa_legs_landing_median: float | None = None
    kappa_legs_liftoff_median: float | None = None


@dataclass(frozen=True)
class KappaSection:
    paper_lengths: list[float]
    near_limit_lengths: list[float]
    cases: dict[str, KappaCase | None]
    near_limit_cases: dict[str, KappaCase | None]
    landing_ratio_fixed_over: dict[str, dict[str, float]]  # length_key -> method -> ratio

    def case(self, method: str, x: float) -> KappaCase | None:
        key = case_key(method, x)
        return self.cases.get(key) or self.near_limit_cases.get(key)

    def all_cases(self, methods: tuple[str, ...]) -> list[KappaCase]:
        """The paper's and the near-limit cases, once each, by length then method."""
        unique = {
            (length_key(c.step_length), c.method): c
            for c in reversed([*self.cases.values(), *self.near_limit_cases.values()])
            if c is not None
        }
        return sorted(unique.values(), key=lambda c: (c.step_length, methods.index(c.method)))


@dataclass(frozen=True)
class ZmpSection:
    """Section 7 (the shares are None when the run is missing)."""

    step_length: float
    available: bool
    clean: bool | None = None
    cop_in_support_ratio_run: float | None = None
    cop_in_measured_support_walking: float | None = None
    cop_in_planned_support_walking: float | None = None
    lipm_in_planned_support_walking: float | None = None


@dataclass(frozen=True)
class ClaimResult:
    """One claim of the paper judged on our numbers (see :mod:`app.experiments.claims`)."""

    id: str
    section: str
    claim: str
    paper: str
    ours: str
    verdict: str  # "holds", "partly", "does not hold" or "not measured"
    rule: str
    measured: dict[str, Any]  # the numbers the rule read


@dataclass(frozen=True)
class Meta:
    command: str
    study: str
    date_utc: str
    duration_s: float
    run_seconds_total: float
    n_runs: int
    jobs: int
    cpu_count: int | None
    machine: str
    errors: dict[str, str]
    full_estimate_s: float | None = None
    study_s: float | None = None  # [s] the study's runs alone (before the sensitivity section)
    load_average: float | None = None  # the machine's 1-minute load average at the end
    load_average_start: float | None = None  # ... and when the runs started


@dataclass(frozen=True)
class RunRecord:
    """A run as ``results.json`` lists it: the summary with every key, no extracts."""

    spec: RunSpec
    wall_s: float
    error: str | None
    summary: dict[str, Any] | None


@dataclass(frozen=True)
class StudyResults:
    """Everything the report and ``results.json`` show."""

    meta: Meta
    kinematics: KinematicsSection
    max_step: dict[str, MaxStep]
    equivalent_lengths: EquivalentLengths
    waist: WaistSection
    yaw_momentum: YawSection
    energy: EnergySection
    kappa: KappaSection
    zmp: ZmpSection
    lateral: LateralSection | None = None
    balance: BalanceSection | None = None
    sensitivity: SensitivitySection | None = None
    claims: list[ClaimResult] = field(default_factory=list)
    runs: dict[str, RunRecord] = field(default_factory=dict)
    figures: dict[str, str] = field(default_factory=dict)  # name -> file in figures/

    def claims_of(self, section: str) -> list[ClaimResult]:
        return [c for c in self.claims if c.section == section]


def _json_safe(obj: Any) -> Any:
    """Replace NaN / inf by None and numpy scalars by Python numbers, recursively."""
    if isinstance(obj, dict):
        return {str(k): _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def to_json(results: StudyResults) -> str:
    """``results.json``: the study's results as JSON (NaN / inf as null)."""
    return json.dumps(_json_safe(dataclasses.asdict(results)), indent=1, allow_nan=False)
