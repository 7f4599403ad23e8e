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
from app.experiments.results import StudyResults
from app.experiments.runs import case_key, length_key
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


def waist_turns_early(study: Study, r: StudyResults) -> Measured:
    """When each method's turn toward the coming swing starts (``waist.turn_onset``), the
    rate's sign at the lift-off and the turn's size before it, against a sine's; the DSP share
    beside it."""
    mpc, red = _waist_pair(r)
    if not (mpc and red):
        return None
    sine = sine_share(mpc.dsp_time / mpc.step_time)
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
    )


def waist_from_prediction(study: Study, r: StudyResults) -> Measured:
    """The MPC's early turn with its reference from the prediction (the default) and from the
    state now held over the horizon (the ablation), at the long length."""
    mpc, _ = _waist_pair(r)
    lat = r.lateral
    abl = lat.ablation.get(case_key(lat.default_mode, LONG)) if lat else None
    if not (mpc and abl):
        return None
    sine = sine_share(mpc.dsp_time / mpc.step_time)
    ratio = abl.early_turn_share / mpc.early_turn_share if mpc.early_turn_share > 0 else math.nan
    return dict(
        length=LONG,
        mpc_anticipates=mpc.anticipates,
        abl_anticipates=abl.anticipates,
        mpc_early=100 * mpc.early_turn_share,
        abl_early=100 * abl.early_turn_share,
        abl_rate=abl.rate_at_liftoff_toward_swing_deg_s,
        mpc_rate=mpc.rate_at_liftoff_toward_swing_deg_s,
        sine=100 * sine,
        abl_of_mpc=ratio,
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
    red = r.yaw_momentum.cases.get(case_key(REDUNDANCY, LONG))
    mpc = r.yaw_momentum.cases.get(case_key(MPC, LONG))
    if not (red and mpc and red.no_arms.peak and mpc.no_arms.peak):
        return None
    return dict(
        red=red.no_arms.peak, mpc=mpc.no_arms.peak, excess=red.no_arms.peak - mpc.no_arms.peak
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
    ours_not = [x for x in sorted(status) if status[x] != "least"]
    return dict(
        agree=agree,
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


def stability(study: Study, r: StudyResults) -> Measured:
    """The MPC against redundancy on every stability measure of section 8 (the largest push
    survived at each length and direction, the falls at each push size); the fixed pelvis
    beside it (what turning the pelvis costs)."""
    from app.experiments.robustness import stability as compare

    rob = r.robustness
    if rob is None:
        return None
    comps = compare(rob, MPC, REDUNDANCY)
    if not comps:
        return None
    t = _tally(comps)
    fixed = _tally(compare(rob, MPC, FIXED))
    return dict(
        **t,
        share=t["wins"] / t["n"],
        net=t["wins"] - t["losses"],
        details="; ".join(f"{c.what}: {c.a} vs {c.b}" for c in comps),
        fixed_wins=fixed["wins"],
        fixed_losses=fixed["losses"],
        fixed_n=fixed["n"],
    )
