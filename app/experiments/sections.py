"""The study's numbers, section by section, from the finished runs.

Every function takes the :class:`Study` and the run results (:data:`results.Results`) and
returns that section's dataclass (:mod:`app.experiments.results`). The claims and their
verdicts are in :mod:`app.experiments.claims`, the text in ``templates/``. Nothing here is
tuned to match a number of the paper.

Definitions used below:
- *clean* run: ``summary.clean`` (completed, no QP failure, no servo saturation, no
  speed-limited IK tick, every step within 2 cm of its planned foothold, kappa(J) bounded).
- *longest clean step*: the longest length below the method's shortest failing length.
- *kappa at landing*: the largest kappa(J) within +/- 50 ms of the planned touch-down of a
  step (``worker.LANDING_WINDOW``); the per-run value is the median over the walking steps
  after the first (the first step starts from standing).
- *peak yaw momentum*: ``summary.yaw_momentum_peak`` (walking phase, measured).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any, cast

import numpy as np

from app.experiments import paper
from app.experiments.definitions import ROTATING, RunSpec, Study, length, sweep_bracket
from app.experiments.results import (
    EnergyCell,
    EnergySection,
    EquivalentLengths,
    EquivalentRow,
    KappaCase,
    KappaSection,
    KinematicsSection,
    MaxStep,
    Results,
    RunSummary,
    ShareOfLimit,
    StepExtract,
    SweepPoint,
    WaistCase,
    WaistSection,
    WalkExtract,
    YawCase,
    YawRun,
    YawSection,
    ZmpExtract,
    ZmpSection,
    array,
    case_key,
    length_key,
)
from app.sim.metrics import KAPPA_SINGULAR, LANDING_ERROR_CLEAN
from app.sweep.measure import walks
from controller.params import CONTROL_DT

DEG = 180.0 / math.pi


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
    """What made a run not clean, in words (empty for a clean run); see app.runs' criterion."""
    if s is None:
        return ["the run crashed"]
    out = []
    if s.fell:
        out.append(f"fell at {s.fall_time:.2f} s ({s.fall_reason})")
    elif not s.success:
        out.append(f"did not complete ({s.steps_completed}/{s.steps_planned} steps)")
    le = s.landing_error_max
    if le is not None and le >= LANDING_ERROR_CLEAN:
        out.append(f"landing error {le * 100:.1f} cm (limit {LANDING_ERROR_CLEAN * 100:.0f} cm)")
    legs = s.condition_number_legs_max  # the clean criterion's matrix (app.sim.summary)
    if legs is not None and legs >= KAPPA_SINGULAR:
        out.append(
            f"a knee nearly straight: kappa of the leg columns up to {legs:.3g} "
            f"(limit {KAPPA_SINGULAR:.0f})"
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


def _median(values: Sequence[float | None]) -> float | None:
    a = array(list(values))
    return float(np.nanmedian(a)) if np.any(np.isfinite(a)) else None


def _max(values: Sequence[float | None]) -> float | None:
    a = array(list(values))
    return float(np.nanmax(a)) if np.any(np.isfinite(a)) else None


# -- section 1 --------------------------------------------------------------------------------
def kinematics() -> KinematicsSection:
    """Eq. (1)-(5) with the paper's numbers and with our model's (same theta)."""
    from controller.analysis import kinematic_analysis
    from models.dyros_jet import HIP_HEIGHT_Z0, HIP_OFFSET, LEG_LENGTH, W_STEP

    theirs = vars(paper.ROBOT)
    ours: dict[str, Any] = dict(
        l_leg=LEG_LENGTH,
        z0=HIP_HEIGHT_Z0,
        l_pel=2 * HIP_OFFSET[1],
        w_step=W_STEP,
        theta_pel_deg=paper.ROBOT.theta_pel_deg,
    )
    return KinematicsSection(
        paper_reported=paper.KINEMATICS,
        paper_inputs=kinematic_analysis(**theirs),
        paper_inputs_literal=kinematic_analysis(**theirs, rule="literal"),
        ours=kinematic_analysis(**ours),
        ours_literal=kinematic_analysis(**ours, rule="literal"),
    )


# -- section 2 --------------------------------------------------------------------------------
def _point(x: float, s: RunSummary | None) -> SweepPoint:
    return SweepPoint(
        step_length=x,
        clean=bool(s and s.clean),
        fell=s.fell if s else None,
        fall_reason=s.fall_reason if s else None,
        steps_completed=s.steps_completed if s else None,
        steps_planned=s.steps_planned if s else None,
        landing_error_max=s.landing_error_max if s else None,
        speed_limited_ticks=s.speed_limited_ticks if s else None,
        servo_saturation_substeps=s.servo_saturation_substeps if s else None,
        solver_failures=s.solver_failures if s else None,
        condition_number_max=s.condition_number_max if s else None,
        waist_yaw_max_deg=s.waist_yaw_max_deg if s else None,
        reasons=failure_reasons(s),
    )


def figure_lengths_run(study: Study, results: Results, method: str) -> list[float]:
    """Every length of ``method``'s figure runs (sweep, refinement, figures), sorted."""
    return sorted({s.step_length for s in results if s.method == method and study.is_figure_run(s)})


def max_step(study: Study, results: Results) -> dict[str, MaxStep]:
    """Longest clean step per method from every unseeded arms-on run of ``n_steps`` steps."""
    out = {}
    for m in study.methods:
        points = [
            _point(x, summary_of(results, study.figure_run(m, x)))
            for x in figure_lengths_run(study, results, m)
        ]
        longest, first_failed = sweep_bracket({p.step_length: p.clean for p in points})
        sums = {
            x: summary_of(results, study.figure_run(m, x))
            for x in figure_lengths_run(study, results, m)
        }
        walks_limit, walks_failed = sweep_bracket(
            {x: bool(s and walks(s.as_dict())) for x, s in sums.items()}
        )
        out[m] = MaxStep(
            paper=paper.MAX_STEP[m],
            longest_clean=longest,
            first_failed=first_failed,
            resolution=(
                study.sweep_resolution
                if longest is not None
                and first_failed is not None
                and first_failed - longest <= study.sweep_resolution + 1e-9
                else None
            ),
            clean_again_above_first_failure=[
                p.step_length
                for p in points
                if p.clean and first_failed is not None and p.step_length > first_failed
            ],
            binding_at_first_failure=next(
                (p for p in points if p.step_length == first_failed), None
            ),
            points=points,
            walks_limit=walks_limit,
            walks_first_failed=walks_failed,
        )
    return out


def equivalent_lengths(study: Study, ms: dict[str, MaxStep]) -> EquivalentLengths:
    """The paper's lengths as a share of each method's paper limit, and ours at that share."""
    rows = []
    for x in paper.TABLE1_LENGTHS:
        methods = {}
        for m in study.methods:
            share = x / paper.MAX_STEP[m]
            ours = ms[m].longest_clean
            methods[m] = ShareOfLimit(share, length(share * ours) if ours is not None else None)
        rows.append(EquivalentRow(x, methods))
    return EquivalentLengths(
        paper_limits=dict(paper.MAX_STEP),
        our_limits={m: ms[m].longest_clean for m in study.methods},
        rows=rows,
    )


# -- section 3 --------------------------------------------------------------------------------
def waist_case(m: str, x: float, ex: StepExtract) -> WaistCase:
    """Waist angle and rate over one step: turning in the DSP, sharpness of the rate."""
    t = array(ex.t)
    ang = array(ex.waist_angle_cmd) * DEG
    rate = array(ex.waist_rate) * DEG
    i_dsp = int(np.argmin(np.abs(t - ex.dsp)))
    swing = float(np.nanmax(ang) - np.nanmin(ang))
    dsp_change = float(ang[i_dsp] - ang[0])
    acc = np.diff(rate) / CONTROL_DT
    # "Turns before the swing": the rate already points the way the step will turn by
    # lift-off (end of the DSP), and when it reversed into that direction.
    turn_dir = float(np.sign(ang[-1] - ang[0])) or 1.0
    toward = rate * turn_dir
    rising = np.nonzero((toward[:-1] <= 0) & (toward[1:] > 0))[0]
    reversal = float(t[rising[0] + 1] - t[i_dsp]) if len(rising) else float("nan")
    return WaistCase(
        method=m,
        step_length=x,
        complete=ex.complete,
        angle_start_deg=float(ang[0]),
        angle_dsp_end_deg=float(ang[i_dsp]),
        angle_end_deg=float(ang[-1]),
        angle_min_deg=float(np.nanmin(ang)),
        angle_max_deg=float(np.nanmax(ang)),
        peak_abs_angle_deg=float(np.nanmax(np.abs(ang))),
        dsp_change_deg=dsp_change,
        range_deg=swing,
        dsp_share_of_range=abs(dsp_change) / swing if swing > 1e-9 else 0.0,
        peak_abs_rate_deg_s=float(np.nanmax(np.abs(rate))),
        peak_abs_rate_change_deg_s2=float(np.nanmax(np.abs(acc))),
        rate_at_liftoff_toward_swing_deg_s=float(toward[i_dsp]),
        reversal_before_liftoff_s=-reversal,
        dsp_time=ex.dsp,
        step_time=ex.duration,
        step_index=ex.step_index,
    )


def waist(study: Study, results: Results) -> WaistSection:
    cases: dict[str, WaistCase | None] = {}
    for x in study.figure_lengths:
        for m in ROTATING:
            ex = step_of(results, study.figure_run(m, x))
            ok = ex is not None and len(ex.t) >= 3
            cases[case_key(m, x)] = waist_case(m, x, cast(StepExtract, ex)) if ok else None
    return WaistSection(cases)


# -- section 4 --------------------------------------------------------------------------------
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


# -- section 5 --------------------------------------------------------------------------------
def energy(study: Study, results: Results) -> EnergySection:
    """Table 1: energy per two-step window over the repeats that did not fall."""
    table: dict[str, dict[str, EnergyCell]] = {}
    for m in study.methods:
        table[m] = {}
        for x in study.energy_lengths:
            sums = [summary_of(results, s) for s in study.energy_runs(m, x)]
            ok = [s for s in sums if s and not s.fell]
            windows = [w for s in ok for w in s.energy_two_step_windows]
            substep = [w for s in ok for w in s.other.get("energy_two_step_windows_substep", [])]
            joints = [
                s.other["energy_two_step_per_joint_mean"]
                for s in ok
                if s.other.get("energy_two_step_per_joint_mean")
            ]
            theirs = paper.TABLE1.get(m, {}).get(x)
            table[m][length_key(x)] = EnergyCell(
                mean=float(np.mean(windows)) if windows else None,
                std=float(np.std(windows)) if windows else None,
                n_windows=len(windows),
                n_runs=len(sums),
                n_not_fallen=len(ok),
                n_clean=sum(1 for s in sums if s and s.clean),
                paper_mean=theirs.mean if theirs else None,
                paper_std=theirs.std if theirs else None,
                paper_dash=theirs is None,
                run_means=[
                    float(np.mean(s.energy_two_step_windows))
                    for s in ok
                    if s.energy_two_step_windows
                ],
                mean_substep=float(np.mean(substep)) if substep else None,
                std_substep=float(np.std(substep)) if substep else None,
                per_joint_mean=np.mean(joints, axis=0).tolist() if joints else [],
            )
    p_values = {}
    for x in study.energy_lengths:
        cells = {m: table[m][length_key(x)] for m in study.methods}
        for i, a in enumerate(study.methods):
            for b in study.methods[i + 1 :]:
                p = welch_p(cells[a].run_means, cells[b].run_means)
                if p is not None:
                    p_values[f"{length_key(x)}:{a}-{b}"] = p
    from app.sim.world import JOINTS

    return EnergySection(
        table,
        list(study.energy_lengths),
        study.energy_repeats,
        study.energy_steps,
        p_values=p_values,
        joints=list(JOINTS),
    )


SIGNIFICANCE = 0.05  # two means differ when Welch's t-test over the repeats gives p below this


def welch_p(a: Sequence[float], b: Sequence[float]) -> float | None:
    """Welch's t-test p-value of two samples of repeat means (None: fewer than 2 each, or
    both without spread)."""
    from scipy import stats

    if len(a) < 2 or len(b) < 2:
        return None
    if np.std(a) == 0 and np.std(b) == 0:
        return 0.0 if np.mean(a) != np.mean(b) else 1.0
    return float(stats.ttest_ind(a, b, equal_var=False).pvalue)


def significant(a: EnergyCell, b: EnergyCell) -> bool:
    """The repeats' means differ (Welch's t-test, p < SIGNIFICANCE); with fewer than two
    repeats, by at least twice the standard error of the windows' means."""
    p = welch_p(a.run_means, b.run_means)
    if p is not None:
        return p < SIGNIFICANCE
    assert a.mean is not None and a.std is not None  # cells of EnergySection.cell()
    assert b.mean is not None and b.std is not None
    se = math.sqrt(a.std**2 / max(a.n_windows, 1) + b.std**2 / max(b.n_windows, 1))
    return abs(a.mean - b.mean) >= 2 * se


# -- section 6 --------------------------------------------------------------------------------
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
        kappa_legs_run_max=s.other.get("condition_number_legs_max"),
        kappa_legs_landing_median=_median(s.kappa_legs_landing[1:]),
        kappa_legs_liftoff_median=_median(s.kappa_legs_liftoff[1:]),
    )


def near_limit_lengths(study: Study, results: Results, fixed: MaxStep) -> list[float]:
    """The fixed pelvis's longest clean step, the length ~0.05 m below, its first failures."""
    if fixed.longest_clean is None:
        return []
    lc, ff = fixed.longest_clean, fixed.first_failed
    cands = figure_lengths_run(study, results, "fixed")
    below = [x for x in cands if x < lc - 1e-9 and x >= lc - 0.05 - 1e-9]
    near = ([below[0]] if below else []) + [lc]
    if ff is not None:
        near.append(ff)
        later = [x for x in cands if x > ff + 1e-9]
        if later:
            near.append(later[0])
    return near


def kappa(study: Study, results: Results, ms: dict[str, MaxStep]) -> KappaSection:
    """kappa(J) at the paper's lengths and where the fixed pelvis nears and passes its limit."""

    def cases(lengths: Sequence[float]) -> dict[str, KappaCase | None]:
        return {
            case_key(m, x): kappa_case(study, results, m, x) for x in lengths for m in study.methods
        }

    near = near_limit_lengths(study, results, ms["fixed"])
    section = KappaSection(
        paper_lengths=list(study.kappa_lengths),
        near_limit_lengths=near,
        cases=cases(study.kappa_lengths),
        near_limit_cases=cases(near),
        landing_ratio_fixed_over={},
    )
    ratios: dict[str, dict[str, float]] = {}
    for x in sorted(set(study.kappa_lengths) | set(near)):
        f, row = section.case("fixed", x), {}
        for m in ROTATING:
            r = section.case(m, x)
            if f and r and f.kappa_landing_median and r.kappa_landing_median:
                row[m] = f.kappa_landing_median / r.kappa_landing_median
        ratios[length_key(x)] = row
    return dataclasses.replace(section, landing_ratio_fixed_over=ratios)


# -- section 7 --------------------------------------------------------------------------------
def zmp(study: Study, results: Results) -> ZmpSection:
    spec = study.figure_run("mpc", study.zmp_length)
    s, ex = summary_of(results, spec), zmp_of(results, spec)
    if not s or not ex:
        return ZmpSection(study.zmp_length, available=False)
    return ZmpSection(
        step_length=study.zmp_length,
        available=True,
        clean=s.clean,
        cop_in_support_ratio_run=s.zmp_in_support_ratio,
        cop_in_measured_support_walking=ex.cop_in_measured_support,
        cop_in_planned_support_walking=ex.cop_in_planned_support,
        lipm_in_planned_support_walking=ex.lipm_in_planned_support,
    )
