"""Section 4: the whole body's yaw angular momentum with and without arm swing (paper Fig. 12):
*peak yaw momentum* = ``summary.yaw_momentum_peak`` (walking phase, measured in MuJoCo about the
CoM), and its RMS over the walking phase.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.experiments import paper
from app.experiments.definitions import Study
from app.experiments.runs import Results, array, case_key, failure_reasons, summary_of, walk_of


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


def _yaw_run(study: Study, results: Results, m: str, x: float, arms: bool) -> YawRun:
    spec = study.figure_run(m, x, arms)
    s, ex = summary_of(results, spec), walk_of(results, spec)
    return YawRun(
        peak=s.yaw_momentum_peak if s else None,
        rms=float(np.sqrt(np.nanmean(array(ex.yaw_momentum) ** 2))) if ex else None,
        clean=bool(s and s.clean),
        fell=bool(s and s.fell),
        reasons=failure_reasons(s),
    )


def _reduction(with_arms: float | None, without: float | None) -> float | None:
    return 100.0 * (1.0 - with_arms / without) if with_arms is not None and without else None


def yaw_momentum(study: Study, results: Results) -> YawSection:
    """Peak (and RMS) measured yaw momentum with and without arm swing; reduction in %."""
    cases = {}
    for x in study.figure_lengths:
        for m in study.methods:
            on, off = _yaw_run(study, results, m, x, True), _yaw_run(study, results, m, x, False)
            cases[case_key(m, x)] = YawCase(
                method=m,
                step_length=x,
                arms=on,
                no_arms=off,
                peak_reduction_percent=_reduction(on.peak, off.peak),
                rms_reduction_percent=_reduction(on.rms, off.rms),
            )
    return YawSection(cases, paper.ARM_REDUCTION_PERCENT)
