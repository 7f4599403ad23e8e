"""Section 6: the condition number kappa of eq. (45) over one step (paper Fig. 13), on two
matrices, the same for every method:

- *kappa(J_low)*: J_low of eq. (9), 12 x 13 (the legs and the waist column);
- *kappa(legs)*: J_low's 12 leg columns. A straight knee makes the leg columns singular while
  the waist column keeps J_low's rank, so "kappa diverges" (the foot cannot reach the
  foothold) is read on kappa(legs), with kappa(J_low) beside it; the clean criterion reads
  kappa(legs) too.

*kappa at landing* = the largest value within +/- 50 ms of a planned touch-down
(``worker.LANDING_WINDOW``), median over the walking steps after the first (the first starts
from standing); *at lift-off* likewise.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from app.experiments.definitions import ROTATING, Study
from app.experiments.limits import MaxStep, figure_lengths_run
from app.experiments.outcomes import (
    Results,
    array,
    case_key,
    failure_reasons,
    length_key,
    step_of,
    summary_of,
)
from controller.strategy import FIXED


@dataclass(frozen=True)
class KappaCase:
    """kappa(J_low) and kappa(legs) of one run (the figure run of a method and length)."""

    method: str
    step_length: float
    clean: bool
    fell: bool
    reasons: list[str]
    # kappa(J_low)
    kappa_landing_median: float | None
    kappa_landing_max: float | None
    kappa_liftoff_median: float | None
    kappa_landing_mid_step: float | None
    kappa_step_peak: float | None
    kappa_run_max: float
    # kappa(legs) (the clean criterion's figure)
    kappa_legs_run_max: float | None = None
    kappa_legs_landing_median: float | None = None
    kappa_legs_liftoff_median: float | None = None
    kappa_legs_step_peak: float | None = None


@dataclass(frozen=True)
class KappaSection:
    paper_lengths: list[float]
    near_limit_lengths: list[float]
    cases: dict[str, KappaCase | None]
    near_limit_cases: dict[str, KappaCase | None]
    # fixed / rotating median kappa at landing: length_key -> method -> ratio
    landing_ratio_fixed_over: dict[str, dict[str, float]]  # kappa(J_low)
    landing_ratio_fixed_over_legs: dict[str, dict[str, float]] = dataclasses.field(
        default_factory=dict
    )  # kappa(legs)
    # kappa(J_low) and kappa(legs) with the left knee straight (:func:`straight_knee`)
    straight_knee: dict[str, float] = dataclasses.field(default_factory=dict)

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


def _median(values: Sequence[float | None]) -> float | None:
    a = array(list(values))
    return float(np.nanmedian(a)) if np.any(np.isfinite(a)) else None


def _max(values: Sequence[float | None]) -> float | None:
    a = array(list(values))
    return float(np.nanmax(a)) if np.any(np.isfinite(a)) else None


def kappa_case(study: Study, results: Results, m: str, x: float) -> KappaCase | None:
    spec = study.figure_run(m, x)
    s, ex = summary_of(results, spec), step_of(results, spec)
    if s is None:
        return None
    land, lift = s.kappa_landing[1:], s.kappa_liftoff[1:]
    mid = s.kappa_landing[study.mid_step] if len(s.kappa_landing) > study.mid_step else None
    return KappaCase(
        method=m,
        step_length=x,
        clean=s.clean,
        fell=s.fell,
        reasons=failure_reasons(s),
        kappa_landing_median=_median(land),
        kappa_landing_max=_max(land),
        kappa_liftoff_median=_median(lift),
        kappa_landing_mid_step=mid,
        kappa_step_peak=float(np.nanmax(array(ex.kappa))) if ex and ex.kappa else None,
        kappa_run_max=s.condition_number_max,
        kappa_legs_run_max=s.condition_number_legs_max,
        kappa_legs_landing_median=_median(s.kappa_legs_landing[1:]),
        kappa_legs_liftoff_median=_median(s.kappa_legs_liftoff[1:]),
        kappa_legs_step_peak=(
            float(np.nanmax(array(ex.kappa_legs))) if ex and ex.kappa_legs else None
        ),
    )


NEAR_BELOW = 0.05  # [m] the near-limit lengths start this far below the fixed pelvis's limit


def near_limit_lengths(study: Study, results: Results, fixed: MaxStep) -> list[float]:
    """The fixed pelvis's longest clean step, the length ~NEAR_BELOW below, its first
    failures."""
    if fixed.longest_clean is None:
        return []
    lc, ff = fixed.longest_clean, fixed.first_failed
    cands = figure_lengths_run(study, results, FIXED)
    below = [x for x in cands if x < lc - 1e-9 and x >= lc - NEAR_BELOW - 1e-9]
    near = ([below[0]] if below else []) + [lc]
    if ff is not None:
        near.append(ff)
        later = [x for x in cands if x > ff + 1e-9]
        if later:
            near.append(later[0])
    return near


def straight_knee() -> dict[str, float]:
    """kappa(J_low) and kappa(legs) in the walk-ready pose with the left knee straight (the
    leg tilted as in a step): why "diverges" is read on the leg columns."""
    from controller.kinematics import RobotKinematics, jacobian_conditions
    from models.dyros_jet import JOINTS, walk_ready_joint_angles

    q = walk_ready_joint_angles()
    q[JOINTS.index("L_knee")] = 0.0
    low, legs = jacobian_conditions(RobotKinematics().compute(q).J_low)
    return {"kappa_low": float(low), "kappa_legs": float(legs)}


def kappa(study: Study, results: Results, ms: dict[str, MaxStep]) -> KappaSection:
    """kappa at the paper's lengths and where the fixed pelvis nears and passes its limit."""

    def cases(lengths: Sequence[float]) -> dict[str, KappaCase | None]:
        return {
            case_key(m, x): kappa_case(study, results, m, x) for x in lengths for m in study.methods
        }

    near = near_limit_lengths(study, results, ms[FIXED])
    section = KappaSection(
        paper_lengths=list(study.kappa_lengths),
        near_limit_lengths=near,
        cases=cases(study.kappa_lengths),
        near_limit_cases=cases(near),
        landing_ratio_fixed_over={},
        straight_knee=straight_knee(),
    )
    ratios: dict[str, dict[str, dict[str, float]]] = {"J_low": {}, "legs": {}}
    for x in sorted(set(study.kappa_lengths) | set(near)):
        f = section.case(FIXED, x)
        for name, attr in (
            ("J_low", "kappa_landing_median"),
            ("legs", "kappa_legs_landing_median"),
        ):
            row = {}
            for m in ROTATING:
                r = section.case(m, x)
                a, b = getattr(f, attr, None), getattr(r, attr, None)
                if a and b:
                    row[m] = a / b
            ratios[name][length_key(x)] = row
    return dataclasses.replace(
        section,
        landing_ratio_fixed_over=ratios["J_low"],
        landing_ratio_fixed_over_legs=ratios["legs"],
    )
