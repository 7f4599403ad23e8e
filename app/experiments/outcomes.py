"""A run's results as the study keeps them: what a worker sends back (:class:`RunResult`:
its :class:`RunSummary` and the small extracts its sections asked for) and how a section reads
them (:func:`summary_of`, :func:`step_of`, ... and :func:`failure_reasons`).

Cases of a section are keyed ``"<method>@<length>"`` (:func:`case_key`), energy cells by
``"<length>"`` (:func:`length_key`), both with two decimals. A series crosses processes and
``results.json`` as JSON-safe floats (:func:`samples`; :func:`array` reads it back).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pelvic_walk.core.metrics import KAPPA_SINGULAR, LANDING_ERROR_CLEAN
from pelvic_walk.core.run_spec import RunSpec
from pelvic_walk.core.summary import INCOMPLETE

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
    """The summary keys of a run (``pelvic_walk.core.summary``) the study reads, plus kappa at the
    step
    events and where the centre of pressure sat on a sole's edge.

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
    clean: bool  # pelvic_walk.core.summary's criterion, in words: failure_reasons
    landing_error_max: float | None  # [m]
    condition_number_max: float  # kappa(J_low), walking phase
    speed_limited_ticks: int
    servo_saturation_substeps: int
    solver_failures: int
    solver_failures_by_layer: dict[str, int]
    waist_yaw_max_deg: float
    yaw_momentum_peak: float  # [kg m^2/s]
    zmp_in_support_ratio: float
    energy_two_step_windows: list[float]  # [J] eq. (44), one per two-step window
    sim_time: float  # [s]
    kappa_liftoff: Samples  # max kappa(J_low) within +/- 50 ms of each walking step's lift-off
    kappa_landing: Samples  # ... and of each landing
    kappa_legs_liftoff: Samples = field(default_factory=list)  # the same, kappa(legs)
    kappa_legs_landing: Samples = field(default_factory=list)
    # kappa(legs): J_low's 12 leg columns, walking phase: what the clean criterion reads
    condition_number_legs_max: float | None = None
    landing_errors: list[float] = field(default_factory=list)  # [m] every landing, in order
    energy_two_step_windows_substep: list[float] = field(default_factory=list)  # [J] at 1 ms
    # walking ticks with the CoP on a sole's edge, by edge (outer, inner, toe, heel), and all
    cop_edge_ticks: dict[str, int] = field(default_factory=dict)
    other: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def from_run(cls, summary: dict[str, Any], **extra: Any) -> RunSummary:
        """From ``pelvic_walk.core.summary.summarize`` (every key kept) and the worker's ``extra``
        keys."""
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
    kappa: Samples  # kappa(J_low), capped
    step_index: int
    step_start: float  # [s]
    duration: float  # [s]
    dsp: float  # [s]
    theta_ref_lead: float  # [s] theta_ref refers to this long after the row's time
    swing_side: int
    complete: bool  # the step ended before any fall
    kappa_legs: Samples = field(default_factory=list)  # kappa(legs), capped


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
    lipm_outside_max_mm: float | None = None  # farthest the LIPM ZMP left the planned support
    balance_margin: Samples = field(default_factory=list)  # [m] CoP to the polygon's edge


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


# -- reading a run ---------------------------------------------------------------------------
def summary_of(results: Results, spec: RunSpec) -> RunSummary | None:
    r = results.get(spec)
    return r.summary if r else None


def extract_of(results: Results, spec: RunSpec, name: str) -> Any:
    """The run's extract ``name`` ("step", "walk", "zmp"), None if missing or crashed."""
    r = results.get(spec)
    return getattr(r.extracts, name) if r and r.summary else None


def step_of(results: Results, spec: RunSpec) -> StepExtract | None:
    return extract_of(results, spec, "step")


def walk_of(results: Results, spec: RunSpec) -> WalkExtract | None:
    return extract_of(results, spec, "walk")


def zmp_of(results: Results, spec: RunSpec) -> ZmpExtract | None:
    return extract_of(results, spec, "zmp")


def failure_reasons(s: RunSummary | None) -> list[str]:
    """What made a run not clean, in words (empty for a clean run); see
    ``pelvic_walk.core.summary``'s
    criterion."""
    if s is None:
        return ["the run crashed"]
    out = []
    if s.fell:
        out.append(f"fell at {s.fall_time:.2f} s ({s.fall_reason})")
    elif INCOMPLETE in s.other.get("unsuccessful", () if s.success else (INCOMPLETE,)):
        out.append(f"did not complete ({s.steps_completed}/{s.steps_planned} steps)")
    le = s.landing_error_max
    if le is not None and le >= LANDING_ERROR_CLEAN:
        out.append(f"landing error {le * 100:.1f} cm (limit {LANDING_ERROR_CLEAN * 100:.0f} cm)")
    legs = s.condition_number_legs_max  # the clean criterion's matrix (pelvic_walk.core.summary)
    if legs is not None and legs >= KAPPA_SINGULAR:
        out.append(
            f"a knee nearly straight: kappa(legs) up to {legs:.3g} (limit {KAPPA_SINGULAR:.0f})"
        )
    if s.speed_limited_ticks:
        out.append(f"{s.speed_limited_ticks} IK ticks at the joint-speed limit")
    if s.servo_saturation_substeps:
        out.append(f"{s.servo_saturation_substeps} servo-saturated sim steps")
    if s.solver_failures:
        layers = ", ".join(f"{k} {v}" for k, v in s.solver_failures_by_layer.items() if v)
        out.append(f"{s.solver_failures} QP failures ({layers})")
    if not out and not s.clean:
        out.append("not clean")
    return out
