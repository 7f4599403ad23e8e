"""Our side of each claim: the numbers a claim's rule reads, measured from the typed results.

Each function takes the :class:`Study` and the :class:`StudyResults` (sections 1-7, claims not
yet judged) and returns the measured numbers as a dict, or None when the runs the claim needs
are missing ("not measured"). :data:`app.experiments.claims.CLAIMS` names the function of each
claim; NaN or None in a number fails any bound on it.

Orderings of energy cells count only when the repeats say the cells differ
(:func:`app.experiments.energy.order_means`, :func:`~app.experiments.energy.order_stds`);
otherwise they are ties, in every rule. :func:`at_1ms` gives any energy measure on the 1 ms
figures instead of the 200 Hz ones.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any, cast

from app.experiments import paper
from app.experiments.definitions import ROTATING, Study
from app.experiments.energy import EnergyCell, EnergySection, order_means, order_stds
from app.experiments.outcomes import case_key, length_key
from app.experiments.results import StudyResults
from app.experiments.waist import sine_share
from controller.strategy import FIXED, MPC, REDUNDANCY
from pelvic_walk.core.metrics import KAPPA_SINGULAR

Measured = dict[str, Any] | None  # None: the runs a claim needs are missing
Measure = Callable[[Study, StudyResults], Measured]
LONG = max(paper.FIGURE_LENGTHS)  # [m] the long step of Fig. 8-9 and 12
WORDS = {-1: "<", 0: "tie", 1: ">"}


def at_1ms(measure: Measure) -> Measure:
    """``measure`` on the energy from every 1 ms substep instead of the 200 Hz samples."""

    def substep(study: Study, r: StudyResults) -> Measured:
        return measure(study, dataclasses.replace(r, energy=r.energy.at_substep()))

    return substep


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
            for key in ("fixed", "rotation")  # eq. (4) and (5), not methods
        },
        p_inc=p["increase_percent"],
        o_inc=o["increase_percent"],
    )


ANALYSIS_SIMILAR = 0.03  # [m] "similar" to eq. (4)-(5): within 3 steps of the 0.01 m grid


def limits_vs_analysis(study: Study, r: StudyResults) -> Measured:
    """Our longest clean steps against eq. (4) (fixed) and eq. (5) (rotating) on our robot's
    dimensions (Sec. VI-B: "similar to the value analyzed in Section II"). The paper's own gaps
    are 0.01 and 0.02 m; "similar" is read as within :data:`ANALYSIS_SIMILAR`."""
    o = r.kinematics.ours
    f, red, m = (r.max_step[k].longest_clean for k in (FIXED, REDUNDANCY, MPC))
    if f is None or m is None:
        return None
    eq4, eq5 = o["step_max_fixed_static"], o["step_max_rotation_static"]
    gaps = {"fixed": f - eq4, "mpc": m - eq5}
    if red is not None:
        gaps["redundancy"] = red - eq5
    near = sum(abs(g) <= ANALYSIS_SIMILAR + 1e-9 for g in gaps.values())
    return dict(
        eq4=eq4,
        eq5=eq5,
        fixed=f,
        mpc=m,
        redundancy=red if red is not None else float("nan"),
        gap_fixed=gaps["fixed"],
        gap_mpc=gaps["mpc"],
        gap_redundancy=gaps.get("redundancy", float("nan")),
        near=near,
        n=len(gaps),
        share=near / len(gaps),
    )


def max_step(study: Study, r: StudyResults) -> Measured:
    f, red, m = (r.max_step[k].longest_clean for k in (FIXED, REDUNDANCY, MPC))
    if f is None or m is None:
        return None
    red_text = "None" if red is None else format(red, ".2f")
    walks = " / ".join(
        "-" if (w := r.max_step[k].walks_limit) is None else f"{w:.2f}"
        for k in (FIXED, REDUNDANCY, MPC)
    )
    return dict(
        fixed=f, redundancy=red_text, mpc=m, increase=100.0 * (m / f - 1.0), walks=walks + " m"
    )


def _waist_pair(r: StudyResults) -> tuple[Any, Any]:
    cases = r.waist.cases
    return cases.get(case_key(MPC, LONG)), cases.get(case_key(REDUNDANCY, LONG))


def waist_amplitude(study: Study, r: StudyResults) -> Measured:
    c = r.waist.cases.get(case_key(MPC, paper.WAIST_PEAK_LENGTH))
    if not c:
        return None
    return dict(
        peak=c.peak_abs_angle_deg,
        error=abs(c.peak_abs_angle_deg - paper.WAIST_PEAK_DEG),
        angle_min=c.angle_min_deg,
        angle_max=c.angle_max_deg,
    )


def _other_readings(r: StudyResults) -> list[Any]:
    """The MPC at the long length with the prediction but another reading of the lateral
    distance of eq. (31)-(32) than the default (section 3's table)."""
    lat = r.lateral
    if lat is None:
        return []
    return [
        c
        for k, c in lat.cases.items()
        if c is not None and not c.default and abs(c.step_length - LONG) < 1e-9
    ]


def _readings_words(others: list[Any]) -> str:
    if not others:
        return "not run"
    return ", ".join(
        f"{c.mode} {100 * c.early_turn_share:+.1f} % ({'an' if c.anticipates else 'no'} early turn)"
        for c in others
    )


def waist_turns_early(study: Study, r: StudyResults) -> Measured:
    """Each method's turn toward the coming swing before the lift-off: its size (against a
    sine's) and the rate's sign at the lift-off (``waist.turn_onset``); the other readings of
    the lateral distance beside it. The onset's time is not cited: it is the same (+0.24 s)
    in every variant, the ablation's included, so it tells none apart."""
    mpc, red = _waist_pair(r)
    if not (mpc and red):
        return None
    sine = sine_share(mpc.dsp_time / mpc.step_time)
    others = _other_readings(r)
    return dict(
        length=LONG,
        mpc_anticipates=mpc.anticipates,
        red_anticipates=red.anticipates,
        mpc_lead=mpc.turn_onset_before_liftoff_s,
        red_lead=red.turn_onset_before_liftoff_s,
        mpc_rate=mpc.rate_at_liftoff_toward_swing_deg_s,
        red_rate=red.rate_at_liftoff_toward_swing_deg_s,
        sine=100 * sine,
        mpc_share=100 * mpc.dsp_share_toward_swing,
        red_share=100 * red.dsp_share_toward_swing,
        mpc_early=100 * mpc.early_turn_share,
        red_early=100 * red.early_turn_share,
        mpc_of_sine=mpc.early_turn_share / sine if sine else float("nan"),
        mpc_of_sine_percent=100 * mpc.early_turn_share / sine if sine else float("nan"),
        others=_readings_words(others),
        n_others_anticipate=sum(c.anticipates for c in others),
        n_others=len(others),
    )


def waist_from_prediction(study: Study, r: StudyResults) -> Measured:
    """Is the prediction necessary for the MPC's early turn (without it, the reference from
    the state now held over the horizon, the turn is gone) and sufficient (with it, every
    reading of the lateral distance turns early)? At the long length."""
    mpc, _ = _waist_pair(r)
    lat = r.lateral
    abl = lat.ablation.get(case_key(lat.default_mode, LONG)) if lat else None
    if not (mpc and abl):
        return None
    sine = sine_share(mpc.dsp_time / mpc.step_time)
    ratio = abl.early_turn_share / mpc.early_turn_share if mpc.early_turn_share > 0 else math.nan
    others = _other_readings(r)
    return dict(
        length=LONG,
        mpc_anticipates=mpc.anticipates,
        abl_anticipates=abl.anticipates,
        necessary=bool(mpc.anticipates and not abl.anticipates),
        sufficient=bool(mpc.anticipates and all(c.anticipates for c in others)),
        mpc_early=100 * mpc.early_turn_share,
        abl_early=100 * abl.early_turn_share,
        abl_rate=abl.rate_at_liftoff_toward_swing_deg_s,
        mpc_rate=mpc.rate_at_liftoff_toward_swing_deg_s,
        sine=100 * sine,
        abl_of_mpc=ratio,
        others=_readings_words(others),
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


def rate_growth(study: Study, r: StudyResults) -> Measured:
    """Each rotating method's peak |waist rate| at the short and the long figure length and
    its growth (the introduction: redundancy's rate "increased rapidly as the step length
    increased")."""
    short, long_ = min(paper.FIGURE_LENGTHS), LONG
    c = r.waist.cases
    red0, red1 = c.get(case_key(REDUNDANCY, short)), c.get(case_key(REDUNDANCY, long_))
    mpc0, mpc1 = c.get(case_key(MPC, short)), c.get(case_key(MPC, long_))
    if not (red0 and red1 and mpc0 and mpc1):
        return None
    red_g = red1.peak_abs_rate_deg_s / max(red0.peak_abs_rate_deg_s, 1e-9)
    mpc_g = mpc1.peak_abs_rate_deg_s / max(mpc0.peak_abs_rate_deg_s, 1e-9)
    return dict(
        short=short,
        long=long_,
        red0=red0.peak_abs_rate_deg_s,
        red1=red1.peak_abs_rate_deg_s,
        mpc0=mpc0.peak_abs_rate_deg_s,
        mpc1=mpc1.peak_abs_rate_deg_s,
        red_growth=red_g,
        mpc_growth=mpc_g,
        over_mpc=red_g / max(mpc_g, 1e-9),
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
    red = r.yaw_momentum.cases.get(case_key(REDUNDANCY, LONG))
    mpc = r.yaw_momentum.cases.get(case_key(MPC, LONG))
    if not (red and mpc and red.no_arms.peak and mpc.no_arms.peak):
        return None
    return dict(
        red=red.no_arms.peak, mpc=mpc.no_arms.peak, excess=red.no_arms.peak - mpc.no_arms.peak
    )


def yaw_landing_rapid(study: Study, r: StudyResults) -> Measured:
    """Without arm swing at the long length: the peak |d momentum/dt| within 0.1 s of a
    touch-down, redundancy against the MPC (Sec. VI-C: redundancy's momentum "changes
    rapidly" at landing), and each one's peak elsewhere."""
    red = r.yaw_momentum.cases.get(case_key(REDUNDANCY, LONG))
    mpc = r.yaw_momentum.cases.get(case_key(MPC, LONG))
    if not (red and mpc and red.no_arms.landing_rate_peak and mpc.no_arms.landing_rate_peak):
        return None
    a, b = red.no_arms, mpc.no_arms
    at_a, at_b = cast(float, a.landing_rate_peak), cast(float, b.landing_rate_peak)
    nan = float("nan")
    return dict(
        length=LONG,
        red=at_a,
        mpc=at_b,
        red_rest=a.other_rate_peak if a.other_rate_peak is not None else nan,
        mpc_rest=b.other_rate_peak if b.other_rate_peak is not None else nan,
        ratio=at_a / at_b,
        # the change is at landing: redundancy's fastest change is there, not elsewhere
        at_landing=bool(a.other_rate_peak is None or at_a >= a.other_rate_peak),
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


# -- energy -----------------------------------------------------------------------------------
def _mean_vs(a: EnergyCell, b: EnergyCell) -> str:
    """ "a vs b J", with "(n.s.)" when the repeats do not separate the means."""
    return f"{a.mean:.1f} vs {b.mean:.1f} J" + ("" if order_means(a, b) else " (n.s.)")


def _std_vs(a: EnergyCell, b: EnergyCell) -> str:
    return f"{a.std:.1f} vs {b.std:.1f} J" + ("" if order_stds(a, b) else " (n.s.)")


def _orderings(orders: list[int], details: str) -> dict[str, Any]:
    """Counts of the paper's ordering (-1 in ``orders``), ties and the reverse."""
    n = len(orders)
    wins, ties = orders.count(-1), orders.count(0)
    return dict(wins=wins, ties=ties, losses=n - wins - ties, n=n, share=wins / n, details=details)


def _pair_cells(e: EnergySection, a: str, b: str, lengths: list[float]) -> list[tuple]:
    pairs = [(x, e.cell(a, x), e.cell(b, x)) for x in lengths]
    return [(x, ca, cb) for x, ca, cb in pairs if ca and cb]


def energy_std(study: Study, r: StudyResults) -> Measured:
    """MPC's std against redundancy's at every length both walked."""
    pairs = _pair_cells(r.energy, MPC, REDUNDANCY, r.energy.lengths)
    if not pairs:
        return None
    details = ", ".join(f"{x:.2f}: {_std_vs(a, b)}" for x, a, b in pairs)
    return _orderings([order_stds(a, b) for _, a, b in pairs], details)


def energy_std_gap(study: Study, r: StudyResults) -> Measured:
    """The std gap (redundancy - MPC) against the length: Spearman's rank correlation and its
    p-value, and whether the MPC's std is significantly the smaller at the longest length."""
    from scipy import stats

    pairs = _pair_cells(r.energy, MPC, REDUNDANCY, r.energy.lengths)
    if len(pairs) < 3:
        return None
    gaps = [cast(float, b.std) - cast(float, a.std) for _, a, b in pairs]
    res = stats.spearmanr([x for x, _, _ in pairs], gaps)
    rho, p = float(res.statistic), float(res.pvalue)
    _, a_last, b_last = pairs[-1]
    details = ", ".join(f"{x:.2f}: {g:+.1f} J" for (x, _, _), g in zip(pairs, gaps, strict=True))
    return dict(
        rho=rho,
        p=p,
        p_text="p < 0.001" if p < 0.001 else f"p = {p:.2g}",
        grows=bool(rho > 0 and p < 0.05),
        shrinks=bool(rho < 0 and p < 0.05),
        last_smaller=order_stds(a_last, b_last) == -1,
        last=pairs[-1][0],
        details=details,
    )


def mpc_below_redundancy_lengths() -> list[float]:
    """The lengths of the paper's "the method using redundancy consumed more energy than the
    method using MPC, except for the case of a 0.3 m step length": Table 1's lengths where
    both have a value, but the exception."""
    both = [x for x in paper.TABLE1_LENGTHS if paper.TABLE1[MPC][x] and paper.TABLE1[REDUNDANCY][x]]
    return [x for x in both if x not in paper.table1_lengths_mpc_not_below_redundancy()]


def energy_mpc_below_redundancy(study: Study, r: StudyResults) -> Measured:
    lengths = [x for x in mpc_below_redundancy_lengths() if x in r.energy.lengths]
    pairs = _pair_cells(r.energy, MPC, REDUNDANCY, lengths)
    if not pairs:
        return None
    details = ", ".join(f"{x:.2f}: {_mean_vs(a, b)}" for x, a, b in pairs)
    return _orderings([order_means(a, b) for _, a, b in pairs], details)


def energy_vs_fixed(lo: float, hi: float, cheaper: bool) -> Measure:
    """Rotating methods' means against the fixed pelvis's at lengths in (lo, hi]: the paper's
    ordering counts where the repeats separate the means."""

    def measure(study: Study, r: StudyResults) -> Measured:
        checks = []
        for x in (x for x in r.energy.lengths if lo + 1e-9 < x <= hi + 1e-9):
            f = r.energy.cell(FIXED, x)
            for m in ROTATING:
                c = r.energy.cell(m, x)
                if f and c:
                    checks.append((x, m, c, f))
        if not checks:
            return None
        details = "; ".join(f"{x:.2f} {m}: {_mean_vs(c, f)}" for x, m, c, f in checks)
        # -1: the paper's ordering (cheaper: the rotating method below the fixed pelvis)
        orders = [order_means(c, f) * (1 if cheaper else -1) for _, _, c, f in checks]
        return _orderings(orders, details)

    return measure


def paper_least_lengths() -> tuple[list[float], list[float]]:
    """Table 1's lengths (with at least two methods) where the MPC's mean is the least, and
    those where it is not (the paper's exceptions: 0.25 and 0.30 m)."""
    least: list[float] = []
    not_least: list[float] = []
    for x in paper.TABLE1_LENGTHS:
        cells = {m: c for m in paper.TABLE1 if (c := paper.TABLE1[m][x])}
        if len(cells) >= 2:
            mine = min(cells, key=lambda m: cells[m].mean) == MPC
            (least if mine else not_least).append(x)
    return least, not_least


def energy_least(study: Study, r: StudyResults) -> Measured:
    """Where the MPC's mean is the least, against where the paper's is. At each length where
    at least two methods walked, the MPC is *least* when its mean is significantly below every
    other's, *missed* when another's is significantly below it, else tied; the rule reads the
    lengths where the paper's MPC is the least (its exceptions elsewhere are the paper's)."""
    theirs, _ = paper_least_lengths()
    status: dict[float, str] = {}
    for x in r.energy.lengths:
        cells = {m: c for m in study.methods if (c := r.energy.cell(m, x))}
        if MPC not in cells or len(cells) < 2:
            continue
        orders = {m: order_means(cells[MPC], cells[m]) for m in cells if m != MPC}
        if all(o == -1 for o in orders.values()):
            status[x] = "least"
        elif any(o == 1 for o in orders.values()):
            status[x] = "below: " + ", ".join(m for m, o in orders.items() if o == 1)
        else:
            status[x] = "tied"
    judged = [x for x in theirs if any(abs(x - y) < 1e-9 for y in status)]
    if not judged:
        return None
    at = {round(x, 3): v for x, v in status.items()}
    agree = sum(at[round(x, 3)] == "least" for x in judged)
    missed = sum(at[round(x, 3)].startswith("below") for x in judged)
    ours_not = [x for x in sorted(status) if status[x] != "least"]
    return dict(
        agree=agree,
        missed=missed,
        n=len(judged),
        share=agree / len(judged),
        least=", ".join(f"{x:.2f}" for x in sorted(status) if status[x] == "least") or "none",
        exceptions="; ".join(f"{x:.2f} ({status[x]})" for x in ours_not) or "none",
        judged=", ".join(f"{x:.2f}" for x in judged),
    )


# -- kappa ------------------------------------------------------------------------------------
def _kappa_ratio_at(r: StudyResults, x: float | None) -> Measured:
    if x is None:
        return None
    row = r.kappa.landing_ratio_fixed_over.get(length_key(x), {})
    legs = r.kappa.landing_ratio_fixed_over_legs.get(length_key(x), {})
    if not row.get(MPC):
        return None
    nan = float("nan")
    return dict(
        length=x,
        ratio=row[MPC],
        ratio_redundancy=row.get(REDUNDANCY, nan),
        ratio_legs=legs.get(MPC, nan),
        ratio_legs_redundancy=legs.get(REDUNDANCY, nan),
    )


def kappa_ratio_paper_length(study: Study, r: StudyResults) -> Measured:
    """Fixed / rotating kappa(J_low) at landing at the paper's length."""
    return _kappa_ratio_at(r, paper.KAPPA_RATIO_LENGTH)


def kappa_ratio_diverging_length(study: Study, r: StudyResults) -> Measured:
    """Fixed / rotating kappa(J_low) at landing at the paper's 0.35 m, the lesser of the two
    rotating methods' ratios (the paper: "close to twice that of walking with pelvic
    rotation")."""
    m = _kappa_ratio_at(r, paper.KAPPA_DIVERGES_LENGTH)
    if m is None:
        return None
    return m | {"least": min(m["ratio"], m["ratio_redundancy"])}


def kappa_ratio_own_limit(study: Study, r: StudyResults) -> Measured:
    """Fixed / rotating kappa(J_low) at landing at our fixed pelvis's longest clean step."""
    return _kappa_ratio_at(r, r.max_step[FIXED].longest_clean)


def own_limit_differs(study: Study, r: StudyResults) -> bool:
    lc = r.max_step[FIXED].longest_clean
    return lc is not None and abs(lc - paper.MAX_STEP[FIXED]) > 1e-9


def _status(c: Any) -> str:
    return "clean" if c.clean else "not clean: " + "; ".join(c.reasons)


def kappa_diverges(study: Study, r: StudyResults) -> Measured:
    """kappa(legs) over the run at the paper's length, fixed pelvis against the MPC."""
    f = r.kappa.cases.get(case_key(FIXED, paper.KAPPA_DIVERGES_LENGTH))
    m = r.kappa.cases.get(case_key(MPC, paper.KAPPA_DIVERGES_LENGTH))
    if not (f and m and f.kappa_legs_run_max and m.kappa_legs_run_max):
        return None
    return dict(
        fixed_legs=f.kappa_legs_run_max,
        mpc_legs=m.kappa_legs_run_max,
        fixed_diverges=f.kappa_legs_run_max >= KAPPA_SINGULAR,
        mpc_bounded=m.kappa_legs_run_max < KAPPA_SINGULAR,
        ratio_legs=f.kappa_legs_run_max / m.kappa_legs_run_max,
        fixed_low=f.kappa_run_max,
        mpc_low=m.kappa_run_max,
        status=_status(f),
    )


def kappa_own_limit(study: Study, r: StudyResults) -> Measured:
    """kappa(legs) of the fixed pelvis at its longest clean and first failed length, and the
    MPC's at that failed length."""
    lc, ff = r.max_step[FIXED].longest_clean, r.max_step[FIXED].first_failed
    if lc is None or ff is None:
        return None
    a, b, c = (r.kappa.case(m, x) for m, x in ((FIXED, lc), (FIXED, ff), (MPC, ff)))
    if not (a and b and c and a.kappa_legs_run_max and b.kappa_legs_run_max):
        return None
    if not c.kappa_legs_run_max:
        return None
    return dict(
        lc=lc,
        ff=ff,
        fixed_at_limit=a.kappa_legs_run_max,
        fixed_past=b.kappa_legs_run_max,
        mpc_past=c.kappa_legs_run_max,
        fixed_diverges=b.kappa_legs_run_max >= KAPPA_SINGULAR,
        mpc_bounded=c.kappa_legs_run_max < KAPPA_SINGULAR,
        mpc_over_fixed=c.kappa_legs_run_max / b.kappa_legs_run_max,
        fixed_low_past=b.kappa_run_max,
        mpc_low_past=c.kappa_run_max,
    )


def kappa_events(study: Study, r: StudyResults) -> Measured:
    """At the long length: MPC's kappa(J_low) at lift-off above redundancy's, redundancy's at
    landing above MPC's (median over the steps; kappa(legs) beside)."""
    mpc, red = r.kappa.case(MPC, LONG), r.kappa.case(REDUNDANCY, LONG)
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


# -- ZMP --------------------------------------------------------------------------------------
def zmp(study: Study, r: StudyResults) -> Measured:
    """The LIPM ZMP from the measured CoM in the planned support (the paper's Fig. 15)."""
    z = r.zmp
    if not z.available or z.lipm_in_planned_support_walking is None:
        return None
    out = z.lipm_outside_max_mm
    return dict(
        lipm=z.lipm_in_planned_support_walking,
        lipm_percent=100 * z.lipm_in_planned_support_walking,
        outside="never" if out is None else f"{out:.0f} mm at most",
    )


# -- stability --------------------------------------------------------------------------------
def _tally(comps: list[Any]) -> dict[str, int]:
    wins, losses = sum(c.order < 0 for c in comps), sum(c.order > 0 for c in comps)
    return dict(wins=wins, losses=losses, ties=len(comps) - wins - losses, n=len(comps))


SMOOTHER = 1.5  # redundancy's peak |d rate/dt| over the MPC's that reads "smoother"
READ_WORDS = {-1: "the MPC more stable", 0: "cannot tell", 1: "redundancy more stable"}


def _readings(study: Study, r: StudyResults, comps: list[Any]) -> dict[str, tuple[int, str]]:
    """Each reading of "more stable", MPC against redundancy: -1 the MPC, +1 redundancy, 0
    the evidence cannot tell; with its numbers in words."""
    from app.experiments.robustness import sign_p

    out: dict[str, tuple[int, str]] = {}
    pushes = [c for c in comps if c.what.startswith("push")]
    if pushes:
        t = _tally(pushes)
        p = sign_p(t["wins"], t["losses"])
        order = 0 if p >= 0.05 else (-1 if t["wins"] > t["losses"] else 1)
        out["pushes"] = (
            order,
            f"largest push survived in {t['n']} conditions: the MPC more in {t['wins']}, less "
            f"in {t['losses']}, within the bisection's resolution in {t['ties']} (sign test p = "
            f"{p:.2g})",
        )
    falls = [c for c in comps if c.what.startswith("falls")]
    if falls:
        sig = [c.order for c in falls if c.order]
        order = 0 if not sig or len(set(sig)) > 1 else sig[0]
        out["falls"] = (order, "; ".join(f"{c.what}: {c.a} vs {c.b}" for c in falls))
    sharp = waist_sharp(study, r)
    if sharp:
        ratio = sharp["ratio"]
        order = -1 if ratio > SMOOTHER else (1 if ratio < 1 / SMOOTHER else 0)
        out["rate smoothness"] = (
            order,
            f"peak |d rate/dt| at {sharp['length']:g} m redundancy / MPC x{ratio:.1f} "
            f"(smoother beyond x{SMOOTHER:g})",
        )
    from app.experiments.energy import order_stds

    e = r.energy.at_substep()
    pairs = _pair_cells(e, MPC, REDUNDANCY, e.lengths)
    if pairs:
        orders = [order_stds(a, b) for _, a, b in pairs]
        wins, losses = orders.count(-1), orders.count(1)
        order = -1 if wins * 2 >= len(orders) and not losses else (1 if losses > wins else 0)
        out["trajectory consistency"] = (
            order,
            f"the energy's std over the repeats (1 ms; the paper's own basis, Sec. VI-D): the "
            f"MPC's smaller at {wins}, larger at {losses} of {len(orders)} lengths",
        )
    return out


def stability(study: Study, r: StudyResults) -> Measured:
    """The MPC against redundancy, reading by reading: our pushes (the largest push survived
    at each length and direction; a difference counts beyond the bisection's resolution, and
    the conditions' direction must pass a sign test), our falls at each push size (Fisher's
    exact test), and the paper's own basis for its sentence: the waist rate's smoothness
    (Sec. V-C) and the trajectory's consistency over repeats (the energy's std, Sec. VI-D).
    Each reading says the MPC, redundancy, or cannot tell; the fixed pelvis beside it."""
    from app.experiments.robustness import stability as compare

    rob = r.robustness
    if rob is None:
        return None
    comps = compare(rob, MPC, REDUNDANCY)
    if not comps:
        return None
    readings = _readings(study, r, comps)
    favor = sum(o < 0 for o, _ in readings.values())
    against = sum(o > 0 for o, _ in readings.values())
    t = _tally(comps)
    fixed = _tally([c for c in compare(rob, MPC, FIXED) if c.what.startswith("push")])
    return dict(
        **t,
        favor=favor,
        against=against,
        n_readings=len(readings),
        favor_share=favor / len(readings),
        net_readings=favor - against,
        readings={k: READ_WORDS[o] for k, (o, _) in readings.items()},
        reading_rows=[[k, READ_WORDS[o], w] for k, (o, w) in readings.items()],
        n_push=sum(c.what.startswith("push") for c in comps),
        reading_words="; ".join(f"{k}: {READ_WORDS[o]} ({w})" for k, (o, w) in readings.items()),
        details="; ".join(f"{c.what}: {c.a} vs {c.b}" for c in comps),
        fixed_wins=fixed["wins"],
        fixed_losses=fixed["losses"],
        fixed_n=fixed["n"],
    )
