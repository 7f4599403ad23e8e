"""Our side of each claim: the numbers a claim's rule reads, measured from the typed results.

Each function takes the :class:`Study` and the :class:`StudyResults` (sections 1-7, claims not
yet judged) and returns the measured numbers as a dict, or None when the runs the claim needs
are missing ("not measured"). :data:`app.experiments.claims.CLAIMS` names the function of each
claim; NaN or None in a number fails any bound on it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

import numpy as np

from app.experiments import paper
from app.experiments.definitions import ROTATING, Study
from app.experiments.results import EnergyCell, StudyResults, case_key, length_key
from app.experiments.sections import significant

Measured = dict[str, Any] | None  # None: the runs a claim needs are missing
LONG = max(paper.FIGURE_LENGTHS)  # [m] the long step of Fig. 8-9 and 12


def kinematics(study: Study, r: StudyResults) -> Measured:
    p, o, k = r.kinematics.paper_inputs, r.kinematics.ours, paper.KINEMATICS
    return dict(
        error=max(
            abs(p["step_max_fixed_static"] - k.step_max_fixed),
            abs(p["step_max_rotation_static"] - k.step_max_rotation),
        ),
        **{
            f"{who}_{key}": d[f"step_max_{key}_static"]
            for who, d in (("p", p), ("o", o))
            for key in ("fixed", "rotation")
        },
        p_inc=p["increase_percent"],
        o_inc=o["increase_percent"],
    )


def max_step(study: Study, r: StudyResults) -> Measured:
    f, red, m = (r.max_step[k].longest_clean for k in ("fixed", "redundancy", "mpc"))
    if f is None or m is None:
        return None
    red_text = "None" if red is None else format(red, ".2f")
    walks = " / ".join(
        "-" if (w := r.max_step[k].walks_limit) is None else f"{w:.2f}"
        for k in ("fixed", "redundancy", "mpc")
    )
    return dict(
        fixed=f, redundancy=red_text, mpc=m, increase=100.0 * (m / f - 1.0), walks=walks + " m"
    )


def _waist_pair(r: StudyResults) -> tuple[Any, Any]:
    cases = r.waist.cases
    return cases.get(case_key("mpc", LONG)), cases.get(case_key("redundancy", LONG))


def waist_amplitude(study: Study, r: StudyResults) -> Measured:
    c = r.waist.cases.get(case_key("mpc", paper.WAIST_PEAK_LENGTH))
    if not c:
        return None
    return dict(
        peak=c.peak_abs_angle_deg,
        error=abs(c.peak_abs_angle_deg - paper.WAIST_PEAK_DEG),
        angle_min=c.angle_min_deg,
        angle_max=c.angle_max_deg,
    )


def _toward_share(c: Any) -> float:
    """The DSP's share of the step's waist range, signed: > 0 toward the coming swing."""
    turn = 1.0 if c.angle_end_deg >= c.angle_start_deg else -1.0
    return c.dsp_share_of_range * (1.0 if c.dsp_change_deg * turn > 0 else -1.0)


def waist_turns(study: Study, r: StudyResults) -> Measured:
    """How far each method's waist turns toward the coming swing in the DSP, against a sine
    over the step (the share a sine moves in the same DSP)."""
    from app.experiments.sections_more import sine_share

    mpc, red = _waist_pair(r)
    if not (mpc and red):
        return None
    sine = sine_share(mpc.dsp_time / mpc.step_time)
    m, d = _toward_share(mpc), _toward_share(red)
    return dict(
        length=LONG,
        sine=100 * sine,
        mpc_share=100 * m,
        red_share=100 * d,
        mpc_ratio=m / sine,
        red_ratio=d / sine,
        mpc_minus_red=(m - d) / sine,
        mpc_dsp=mpc.dsp_change_deg,
        red_dsp=red.dsp_change_deg,
        mpc_range=mpc.range_deg,
        mpc_rate=mpc.rate_at_liftoff_toward_swing_deg_s,
    )


def waist_sharp(study: Study, r: StudyResults) -> Measured:
    mpc, red = _waist_pair(r)
    if not (mpc and red):
        return None
    return dict(
        length=LONG,
        red_acc=red.peak_abs_rate_change_deg_s2,
        mpc_acc=mpc.peak_abs_rate_change_deg_s2,
        ratio=red.peak_abs_rate_change_deg_s2 / max(mpc.peak_abs_rate_change_deg_s2, 1e-9),
        red_rate=red.peak_abs_rate_deg_s,
        mpc_rate=mpc.peak_abs_rate_deg_s,
    )


def arm_swing(study: Study, r: StudyResults) -> Measured:
    ok = [
        c
        for c in r.yaw_momentum.cases.values()
        if c.peak_reduction_percent is not None and not c.arms.fell and not c.no_arms.fell
    ]
    if not ok:
        return None
    best = max(ok, key=lambda c: cast(float, c.peak_reduction_percent))  # not None in ok
    worst = min(ok, key=lambda c: cast(float, c.peak_reduction_percent))
    return dict(
        best=best.peak_reduction_percent,
        best_case=f"{best.method}, {best.step_length} m",
        worst=worst.peak_reduction_percent,
        worst_case=f"{worst.method}, {worst.step_length} m",
    )


def yaw_redundancy_higher(study: Study, r: StudyResults) -> Measured:
    red = r.yaw_momentum.cases.get(case_key("redundancy", LONG))
    mpc = r.yaw_momentum.cases.get(case_key("mpc", LONG))
    if not (red and mpc and red.no_arms.peak and mpc.no_arms.peak):
        return None
    return dict(
        red=red.no_arms.peak, mpc=mpc.no_arms.peak, excess=red.no_arms.peak - mpc.no_arms.peak
    )


def _vs(a: EnergyCell, b: EnergyCell) -> str:
    """ "a vs b J", with "(n.s.)" when the means differ by less than twice their standard error."""
    return f"{a.mean:.1f} vs {b.mean:.1f} J" + ("" if significant(a, b) else " (n.s.)")


def _wins(wins: int, n: int, details: str) -> dict[str, Any]:
    return dict(wins=wins, n=n, share=wins / n, details=details)


def _mpc_redundancy(
    r: StudyResults, lengths: list[float]
) -> list[tuple[float, EnergyCell, EnergyCell]]:
    pairs = [(x, r.energy.cell("mpc", x), r.energy.cell("redundancy", x)) for x in lengths]
    return [(x, a, b) for x, a, b in pairs if a and b]


def energy_std(study: Study, r: StudyResults) -> Measured:
    pairs = _mpc_redundancy(r, r.energy.lengths)
    if not pairs:
        return None
    details = ", ".join(f"{x:.2f}: {a.std:.1f} vs {b.std:.1f} J" for x, a, b in pairs)
    # the cells of EnergySection.cell() have a mean and a std (here and below)
    wins = sum(cast(float, a.std) < cast(float, b.std) for _, a, b in pairs)
    return _wins(wins, len(pairs), details)


def energy_std_gap(study: Study, r: StudyResults) -> Measured:
    pairs = _mpc_redundancy(r, r.energy.lengths)
    gaps = [cast(float, b.std) - cast(float, a.std) for _, a, b in pairs]
    if len(gaps) < 3:
        return None
    rho = float(np.corrcoef(np.argsort(np.argsort(gaps)), np.arange(len(gaps)))[0, 1])
    details = ", ".join(f"{x:.2f}: {g:+.1f} J" for (x, _, _), g in zip(pairs, gaps, strict=True))
    return dict(rho=rho, change=gaps[-1] - gaps[0], details=details)


def energy_mean_long(study: Study, r: StudyResults) -> Measured:
    lengths = [x for x in paper.ENERGY_MPC_BELOW_REDUNDANCY if x in r.energy.lengths]
    pairs = _mpc_redundancy(r, lengths)
    if not pairs:
        return None
    details = ", ".join(f"{x:.2f}: {_vs(a, b)}" for x, a, b in pairs)
    wins = sum(cast(float, a.mean) < cast(float, b.mean) for _, a, b in pairs)
    return _wins(wins, len(pairs), details)


def energy_vs_fixed(
    lo: float, hi: float, cheaper: bool
) -> Callable[[Study, StudyResults], Measured]:
    """Rotating methods' means against the fixed pelvis's at lengths in (lo, hi]."""

    def measure(study: Study, r: StudyResults) -> Measured:
        checks = []
        for x in (x for x in r.energy.lengths if lo + 1e-9 < x <= hi + 1e-9):
            f = r.energy.cell("fixed", x)
            for m in ROTATING:
                c = r.energy.cell(m, x)
                if f and c:
                    checks.append((x, m, c, f))
        if not checks:
            return None
        details = "; ".join(f"{x:.2f} {m}: {_vs(c, f)}" for x, m, c, f in checks)
        return _wins(
            sum((cast(float, c.mean) < cast(float, f.mean)) == cheaper for _, _, c, f in checks),
            len(checks),
            details,
        )

    return measure


def _kappa_ratio_at(r: StudyResults, x: float | None) -> Measured:
    row = r.kappa.landing_ratio_fixed_over.get(length_key(x), {}) if x is not None else {}
    if not row.get("mpc"):
        return None
    return dict(length=x, ratio=row["mpc"], ratio_redundancy=row.get("redundancy", float("nan")))


def own_limit_differs(study: Study, r: StudyResults) -> bool:
    lc = r.max_step["fixed"].longest_clean
    return lc is not None and abs(lc - paper.MAX_STEP["fixed"]) > 1e-9


def energy_least(study: Study, r: StudyResults) -> Measured:
    """At each length where at least two methods walked: is the MPC's mean the least?"""
    wins, n, exceptions, details = 0, 0, [], []
    for x in r.energy.lengths:
        cells = {m: c for m in study.methods if (c := r.energy.cell(m, x))}
        if "mpc" not in cells or len(cells) < 2:
            continue
        n += 1
        least = min(cells, key=lambda m: cast(float, cells[m].mean))
        if least == "mpc":
            wins += 1
        else:
            exceptions.append(f"{x:.2f}")
            details.append(f"{x:.2f}: {least} {_vs(cells[least], cells['mpc'])} (MPC)")
    if not n:
        return None
    return dict(
        wins=wins,
        n=n,
        share=wins / n,
        misses=n - wins,
        exceptions=", ".join(exceptions) or "none",
        details="; ".join(details) or "-",
    )


def yaw_similar(study: Study, r: StudyResults) -> Measured:
    """Spread of the methods' peak yaw momentum at the short figure length, arms on and off."""
    x = min(paper.FIGURE_LENGTHS)
    cases = [r.yaw_momentum.cases.get(case_key(m, x)) for m in study.methods]
    if not all(cases):
        return None
    out: dict[str, Any] = dict(length=x)
    for key in ("arms", "no_arms"):
        peaks = [getattr(c, key).peak for c in cases]
        if any(p is None or getattr(c, key).fell for p, c in zip(peaks, cases, strict=True)):
            return None
        out[f"spread_{key}"] = (max(peaks) - min(peaks)) / max(peaks)
        out[f"peaks_{key}"] = " / ".join(f"{p:.2f}" for p in peaks)
    out["spread"] = max(out["spread_arms"], out["spread_no_arms"])
    out["spread_percent"] = 100 * out["spread"]
    return out


def kappa_events(study: Study, r: StudyResults) -> Measured:
    """At the long length: MPC's kappa at lift-off above redundancy's, redundancy's at
    landing above MPC's (median over the steps; J_low and its leg columns)."""
    mpc, red = r.kappa.case("mpc", LONG), r.kappa.case("redundancy", LONG)
    if not (mpc and red and mpc.kappa_liftoff_median and red.kappa_liftoff_median):
        return None
    if not (mpc.kappa_landing_median and red.kappa_landing_median):
        return None
    lift = mpc.kappa_liftoff_median > red.kappa_liftoff_median
    land = red.kappa_landing_median > mpc.kappa_landing_median
    nan = float("nan")
    return dict(
        length=LONG,
        liftoff_mpc_higher=lift,
        landing_red_higher=land,
        n_agree=int(lift) + int(land),
        mpc_lift=mpc.kappa_liftoff_median,
        red_lift=red.kappa_liftoff_median,
        mpc_land=mpc.kappa_landing_median,
        red_land=red.kappa_landing_median,
        mpc_lift_legs=mpc.kappa_legs_liftoff_median or nan,
        red_lift_legs=red.kappa_legs_liftoff_median or nan,
        mpc_land_legs=mpc.kappa_legs_landing_median or nan,
        red_land_legs=red.kappa_legs_landing_median or nan,
    )


def kappa_diverges(study: Study, r: StudyResults) -> Measured:
    f = r.kappa.cases.get(case_key("fixed", paper.KAPPA_DIVERGES_LENGTH))
    m = r.kappa.cases.get(case_key("mpc", paper.KAPPA_DIVERGES_LENGTH))
    if not (f and m):
        return None
    return dict(
        fixed_max=f.kappa_run_max,
        mpc_max=m.kappa_run_max,
        fixed_clean=f.clean,
        ratio=f.kappa_run_max / m.kappa_run_max,
        status="clean" if f.clean else "not clean: " + "; ".join(f.reasons),
    )


def kappa_own_limit(study: Study, r: StudyResults) -> Measured:
    lc, ff = r.max_step["fixed"].longest_clean, r.max_step["fixed"].first_failed
    if lc is None or ff is None:
        return None
    near = r.kappa.near_limit_cases
    a, b = near.get(case_key("fixed", lc)), near.get(case_key("fixed", ff))
    c = near.get(case_key("mpc", ff))
    if not (a and b and c):
        return None
    return dict(
        lc=lc,
        ff=ff,
        fixed_at_limit=a.kappa_run_max,
        fixed_past=b.kappa_run_max,
        mpc_past=c.kappa_run_max,
        growth=b.kappa_run_max / a.kappa_run_max,
        mpc_over_fixed=c.kappa_run_max / b.kappa_run_max,
    )


def zmp(study: Study, r: StudyResults) -> Measured:
    z = r.zmp
    b = r.balance.cases.get(case_key("mpc", study.zmp_length)) if r.balance else None
    if not z.available or b is None or b.margin_p5_mm is None:
        return None
    cop, lipm = z.cop_in_measured_support_walking, z.lipm_in_planned_support_walking
    assert cop is not None and lipm is not None  # set when available
    return dict(
        cop=cop,
        lipm=lipm,
        cop_percent=cop * 100,
        lipm_percent=lipm * 100,
        p5=b.margin_p5_mm,
        min=b.margin_min_mm,
        tilt=b.tilt_max_deg,
    )


def kappa_ratio_paper_length(study: Study, r: StudyResults) -> Measured:
    """Fixed / rotating kappa(J) at landing at the paper's length."""
    return _kappa_ratio_at(r, paper.KAPPA_RATIO_LENGTH)


def kappa_ratio_own_limit(study: Study, r: StudyResults) -> Measured:
    """Fixed / rotating kappa(J) at landing at our fixed pelvis's longest clean step."""
    return _kappa_ratio_at(r, r.max_step["fixed"].longest_clean)
