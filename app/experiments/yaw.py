"""Section 4: the whole body's yaw angular momentum with and without arm swing (paper Fig. 12):
*peak yaw momentum* = ``summary.yaw_momentum_peak`` (walking phase, measured in MuJoCo about the
CoM), and its RMS over the walking phase.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.experiments import paper
from app.experiments.definitions import Study
from app.experiments.outcomes import Results, array, case_key, failure_reasons, summary_of, walk_of


@dataclass(frozen=True)
class YawRun:
    """Section 4: one run's measured yaw momentum."""

    peak: float | None  # [kg m^2/s]
    rms: float | None
    clean: bool
    fell: bool
    reasons: list[str]
    # [kg m^2/s^2] peak |d momentum/dt| within LANDING_WINDOW of a touch-down, and elsewhere
    landing_rate_peak: float | None = None
    other_rate_peak: float | None = None


LANDING_WINDOW = 0.1  # [s] either side of a planned touch-down


def rate_near_landing(
    t: np.ndarray, h: np.ndarray, landings: np.ndarray
) -> tuple[float | None, float | None]:
    """Peak |dh/dt| within :data:`LANDING_WINDOW` of a landing, and the peak elsewhere (None
    without samples there)."""
    if len(t) < 3 or not len(landings):
        return None, None
    dh = np.abs(np.diff(h) / np.diff(t))
    mid = 0.5 * (t[1:] + t[:-1])
    near = np.min(np.abs(mid[:, None] - landings[None, :]), axis=1) <= LANDING_WINDOW
    ok = np.isfinite(dh)
    at = dh[near & ok]
    rest = dh[~near & ok]
    return (float(at.max()) if at.size else None, float(rest.max()) if rest.size else None)


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
    at, rest = (None, None)
    if ex is not None:
        # a step ends with its touch-down: every step's start after the first is a landing
        at, rest = rate_near_landing(array(ex.t), array(ex.yaw_momentum), array(ex.step_start)[1:])
    return YawRun(
        peak=s.yaw_momentum_peak if s else None,
        rms=float(np.sqrt(np.nanmean(array(ex.yaw_momentum) ** 2))) if ex else None,
        clean=bool(s and s.clean),
        fell=bool(s and s.fell),
        reasons=failure_reasons(s),
        landing_rate_peak=at,
        other_rate_peak=rest,
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
