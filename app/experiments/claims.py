"""Every claim of the paper in one table (:data:`CLAIMS`), judged on our numbers.

A :class:`~app.experiments.verdicts.Claim` is one row: its id, the report section, the claim
in words and the paper's value (both formatted from :mod:`app.experiments.paper`, where every
paper number is typed once), the function of :mod:`app.experiments.measures` that measures our
numbers, how our numbers read (a format string over them), and the verdict
:class:`~app.experiments.verdicts.Rule` with its thresholds. :func:`evaluate` judges every
claim with the one helper :func:`~app.experiments.verdicts.verdict`.

The rules compare the *shape and ordering* the paper reports (SPEC.md section 6); exact
numbers differ with our model, and nothing here is tuned to match a number. Energy comparisons
mark "(n.s.)" where two means differ by less than twice the standard error of their difference
(std / sqrt(windows)); the verdicts still count the raw ordering, as the paper does.
"""

from __future__ import annotations

from typing import cast

from app.experiments import measures, paper
from app.experiments.definitions import Study
from app.experiments.paper import MeanStd
from app.experiments.results import ClaimResult, StudyResults
from app.experiments.verdicts import Claim, Rule, above, at_least, at_most, below, is_
from controller.params import ControllerParams


def evaluate(study: Study, r: StudyResults) -> list[ClaimResult]:
    """Every applicable claim of :data:`CLAIMS` judged on ``r``, in the table's order."""
    judged = [c.judge(study, r) for c in CLAIMS if c.applies(study, r)]
    return sorted(judged, key=lambda c: c.section)  # stable: the table's order within a section


# -- the paper's side, from paper.py ----------------------------------------------------------
_K, _T = paper.KINEMATICS, paper.TABLE1
_FIXED, _ROT = paper.MAX_STEP["fixed"], paper.MAX_STEP["mpc"]
_CHEAP, _DEAR = (
    (0.0, paper.ENERGY_ROTATION_CHEAPER_UP_TO),
    (paper.ENERGY_ROTATION_CHEAPER_UP_TO, _FIXED),
)


def _t1(lo: float, hi: float) -> list[float]:
    return [x for x in paper.TABLE1_LENGTHS if lo + 1e-9 < x <= hi + 1e-9]


def _t1_vs_fixed(lo: float, hi: float) -> str:
    # Table 1 has all three up to the fixed pelvis's limit
    means = {
        x: [cast(MeanStd, _T[m][x]).mean for m in ("redundancy", "mpc", "fixed")]
        for x in _t1(lo, hi)
    }
    return "; ".join(f"{x:.2f}: {r:.1f} / {m:.1f} vs {f:.1f} J" for x, (r, m, f) in means.items())


_T1_BOTH = [x for x in paper.TABLE1_LENGTHS if _T["mpc"][x] and _T["redundancy"][x]]
_T1_STD_WINS = sum(
    cast(MeanStd, _T["mpc"][x]).std < cast(MeanStd, _T["redundancy"][x]).std for x in _T1_BOTH
)
_T1_GAPS = [
    cast(MeanStd, _T["redundancy"][x]).std - cast(MeanStd, _T["mpc"][x]).std for x in _T1_BOTH
]
_SHARE = "share of the comparisons that agree"


def _count(wins: int, n: int) -> str:
    return f"all {n}" if wins == n else f"{wins}/{n}"


# "the least energy except at a specific step length" on the paper's own Table 1
_LEAST = [x for x in paper.TABLE1_LENGTHS if sum(_T[m][x] is not None for m in paper.TABLE1) >= 2]
_LEAST_WINS = sum(
    min((m for m in paper.TABLE1 if _T[m][x]), key=lambda m: cast(MeanStd, _T[m][x]).mean) == "mpc"
    for x in _LEAST
)
_LEAST_MISSES = ", ".join(
    f"{x:.2f} m"
    for x in _LEAST
    if min((m for m in paper.TABLE1 if _T[m][x]), key=lambda m: cast(MeanStd, _T[m][x]).mean)
    != "mpc"
)
ZMP_MARGIN_HOLDS_MM = 10.0
ZMP_MARGIN_PARTLY_MM = 2.0

_RATIO = {"ratio": "fixed / MPC median kappa(J) at landing"}
KAPPA_RATIO_RULE = Rule((at_least("ratio", 1.5),), (above("ratio", 1.1),))
# partly: at least half of the comparisons agree (one of four is not "partly")
ALL_AGREE = Rule((at_least("share", 1.0),), (at_least("share", 0.5),))


def _energy_vs_fixed(cid: str, lo: float, hi: float, cheaper: bool) -> Claim:
    """Pelvic rotation costs less (``cheaper``) or more than the fixed pelvis in (lo, hi]."""
    where = f"up to {hi:.2f} m" if lo <= 0 else f"from {_t1(lo, hi)[0]:.2f} to {hi:.2f} m"
    sign = "<" if cheaper else ">"
    claim = (
        f"{where} walking with pelvic rotation costs less than with the fixed pelvis"
        if cheaper
        else f"{where} pelvic rotation costs more than the fixed pelvis"
    )
    return Claim(
        id=cid,
        section="5",
        claim=claim,
        paper=_t1_vs_fixed(lo, hi),
        measure=measures.energy_vs_fixed(lo, hi, cheaper),
        ours="{details}",
        rule=ALL_AGREE,
        names={"share": f"{_SHARE} (a rotating method's mean {sign} the fixed pelvis's)"},
    )


CLAIMS: tuple[Claim, ...] = (
    Claim(
        id="kinematics",
        section="1",
        claim=f"eq. (4)-(5): {_K.step_max_fixed:.2f} m without and {_K.step_max_rotation:.2f} m "
        f"with pelvic rotation (+{_K.increase_percent:.0f} %)",
        paper=f"{_K.step_max_fixed:.2f} / {_K.step_max_rotation:.2f} m, "
        f"+{_K.increase_percent:.0f} %",
        measure=measures.kinematics,
        ours="paper's inputs: {p_fixed:.3f} / {p_rotation:.3f} m (+{p_inc:.0f} %); our robot: "
        "{o_fixed:.3f} / {o_rotation:.3f} m (+{o_inc:.0f} %)",
        rule=Rule((below("error", 0.01),)),
        names={"error": "eq. (4)-(5) with the paper's inputs, largest gap to its numbers [m]"},
        note="Delta d*_hc read as l_pel sin(theta) cos(theta), see controller/analysis.py",
    ),
    Claim(
        id="max_step",
        section="2",
        claim=f"pelvic rotation lengthens the longest step: fixed {_FIXED:.2f} m, rotation "
        f"{_ROT:.2f} m (+{paper.max_step_increase_percent():.0f} %)",
        paper=" / ".join(f"{paper.MAX_STEP[m]:.2f}" for m in paper.MAX_STEP)
        + f" m (fixed / redundancy / MPC), +{paper.max_step_increase_percent():.0f} %",
        measure=measures.max_step,
        ours="clean: {fixed:.2f} / {redundancy} / {mpc:.2f} m, MPC vs fixed {increase:+.0f} %; "
        "walks: {walks}",
        rule=Rule((at_least("increase", 20.0),), (above("increase", 0.0),)),
        names={"increase": "gain of MPC's longest clean step over the fixed pelvis's [%]"},
    ),
    Claim(
        id="waist_amplitude",
        section="3",
        claim=f"MPC waist angle sine-like, about -{paper.WAIST_PEAK_DEG:.0f} to "
        f"+{paper.WAIST_PEAK_DEG:.0f} deg at {paper.WAIST_PEAK_LENGTH:g} m",
        paper=f"+/-{paper.WAIST_PEAK_DEG:.0f} deg",
        measure=measures.waist_amplitude,
        ours="{angle_min:+.1f} to {angle_max:+.1f} deg",
        rule=Rule((at_most("error", 5.0),)),
        names={"error": f"|peak |angle| - {paper.WAIST_PEAK_DEG:.0f} deg| [deg]"},
        note=f"k_pel = 0.25 was chosen in SPEC.md to give {paper.WAIST_PEAK_DEG:.0f} deg at "
        f"{paper.WAIST_PEAK_LENGTH:.2f} m, so this checks the chain, not a free result",
    ),
    Claim(
        id="waist_turns_in_dsp",
        section="3",
        claim="MPC turns the pelvis already in the DSP, before the swing; redundancy does not",
        paper="redundancy: no change during the DSP",
        measure=measures.waist_turns,
        ours="at {length:g} m in the DSP the waist moves toward the coming swing by "
        "{mpc_share:+.1f} % of its range with MPC ({mpc_dsp:+.1f} of {mpc_range:.1f} deg), "
        "{red_share:+.1f} % with redundancy; a sine over the step: {sine:.1f} %",
        rule=Rule(
            (at_least("mpc_ratio", 0.75), at_most("red_ratio", 0.25)),
            (at_least("mpc_ratio", 0.25), above("mpc_minus_red", 0.0)),
        ),
        names={
            "mpc_ratio": "MPC's DSP share toward the swing / a sine's",
            "red_ratio": "redundancy's / a sine's",
            "mpc_minus_red": "MPC's ratio - redundancy's",
        },
        note="the share a sine -A cos(pi t/T) moves in the DSP is the yardstick of 'smoothly "
        "from the moment the step starts'; a negative share moves away from the swing",
    ),
    Claim(
        id="waist_rate_sharp",
        section="3",
        claim="redundancy's waist rate changes sharply; MPC's rate does not",
        paper="qualitative (Fig. 8b, 9b)",
        measure=measures.waist_sharp,
        ours="peak |d rate/dt| at {length:g} m: redundancy {red_acc:.0f} deg/s^2, MPC "
        "{mpc_acc:.0f} deg/s^2 (x{ratio:.1f}); peak |rate| {red_rate:.0f} vs {mpc_rate:.0f} "
        "deg/s",
        rule=Rule((above("ratio", 1.5),), (above("ratio", 1.0),)),
        names={"ratio": "redundancy's peak |d rate/dt| / MPC's"},
    ),
    Claim(
        id="arm_swing",
        section="4",
        claim="arm swing cuts the peak yaw angular momentum by up to about "
        f"{paper.ARM_REDUCTION_PERCENT:.0f} %",
        paper=f"up to {paper.ARM_REDUCTION_PERCENT:.0f} % (experiment, Fig. 16); "
        "'significantly reduced' (simulation, Fig. 12)",
        measure=measures.arm_swing,
        ours="up to {best:.0f} % ({best_case}); least {worst:.0f} % ({worst_case})",
        rule=Rule((at_least("best", 45.0),), (above("best", 10.0),)),
        names={"best": "largest peak reduction over the runs without a fall [%]"},
    ),
    Claim(
        id="yaw_redundancy_higher",
        section="4",
        claim=f"without arm swing at {measures.LONG:g} m redundancy's yaw momentum peaks higher "
        "than MPC's (the pelvis turns fast just before landing)",
        paper="qualitative (Fig. 12b)",
        measure=measures.yaw_redundancy_higher,
        ours="peak {red:.2f} vs {mpc:.2f} kg m^2/s",
        rule=Rule((above("excess", 0.0),)),
        names={"excess": "redundancy's peak - MPC's, arms off [kg m^2/s]"},
    ),
    Claim(
        id="energy_std",
        section="5",
        claim="MPC's energy std is smaller than redundancy's at every length",
        paper=f"smaller at {_count(_T1_STD_WINS, len(_T1_BOTH))} lengths",
        measure=measures.energy_std,
        ours="smaller at {wins}/{n} lengths ({details})",
        rule=Rule((at_least("share", 1.0),), (at_least("share", 0.5),)),
        names={"share": "share of the lengths where MPC's std < redundancy's"},
    ),
    Claim(
        id="energy_std_gap_grows",
        section="5",
        claim="the std gap (redundancy - MPC) grows with the step length",
        paper=f"{_T1_GAPS[0]:.1f} -> {_T1_GAPS[-1]:.0f} J from {_T1_BOTH[0]:.2f} to "
        f"{_T1_BOTH[-1]:.2f} m",
        measure=measures.energy_std_gap,
        ours="gaps {details} (rank correlation with length {rho:+.2f})",
        rule=Rule((at_least("rho", 0.8), above("change", 0.0)), (above("rho", 0.0),)),
        names={
            "rho": "Spearman rank correlation of the gap with the length",
            "change": "gap at the longest length - at the shortest [J]",
        },
    ),
    Claim(
        id="energy_mean_long",
        section="5",
        claim="MPC's mean energy is below redundancy's at "
        + " and ".join(f"{x:.2f}" for x in paper.ENERGY_MPC_BELOW_REDUNDANCY)
        + " m",
        paper="; ".join(
            f"{cast(MeanStd, _T['mpc'][x]).mean:.1f} vs "
            f"{cast(MeanStd, _T['redundancy'][x]).mean:.1f} J"
            for x in paper.ENERGY_MPC_BELOW_REDUNDANCY
        ),
        measure=measures.energy_mean_long,
        ours="{details}",
        rule=ALL_AGREE,
        names={"share": f"{_SHARE} (MPC mean < redundancy mean)"},
    ),
    _energy_vs_fixed("energy_short", *_CHEAP, cheaper=True),
    _energy_vs_fixed("energy_mid", *_DEAR, cheaper=False),
    Claim(
        id="kappa_030",
        section="6",
        claim=f"at {paper.KAPPA_RATIO_LENGTH:.2f} m kappa(J) of the fixed pelvis at landing is "
        f"about {paper.KAPPA_RATIO:g} times the rotating methods'",
        paper=f"about x{paper.KAPPA_RATIO:.0f}",
        measure=measures.kappa_ratio_paper_length,
        ours="fixed / MPC x{ratio:.2f}, fixed / redundancy x{ratio_redundancy:.2f} "
        "(median kappa at landing)",
        rule=KAPPA_RATIO_RULE,
        names=_RATIO,
    ),
    Claim(
        id="kappa_035",
        section="6",
        claim=f"at {paper.KAPPA_DIVERGES_LENGTH:.2f} m kappa(J) diverges for the fixed pelvis "
        "(the foot cannot reach the foothold)",
        paper="diverges",
        measure=measures.kappa_diverges,
        ours="fixed max {fixed_max:.0f} vs MPC {mpc_max:.0f}; fixed {status}",
        rule=Rule((is_("fixed_clean", False), above("ratio", 5.0)), any_holds=True),
        names={
            "fixed_clean": "the fixed pelvis's run is clean",
            "ratio": "fixed / MPC max kappa(J)",
        },
    ),
    Claim(
        id="kappa_030_equivalent",
        section="6",
        claim="(at the equivalent length) at the fixed pelvis's own limit its kappa(J) at "
        f"landing is about {paper.KAPPA_RATIO:g} times the rotating methods'",
        paper=f"about x{paper.KAPPA_RATIO:.0f} at {_FIXED:.2f} m, the paper's fixed limit",
        measure=measures.kappa_ratio_own_limit,
        ours="at {length:.2f} m, our fixed limit: fixed / MPC x{ratio:.2f}, fixed / "
        "redundancy x{ratio_redundancy:.2f}",
        rule=KAPPA_RATIO_RULE,
        names=_RATIO,
        applies=measures.own_limit_differs,
    ),
    Claim(
        id="kappa_own_limit",
        section="6",
        claim="(at the equivalent length) kappa(J) of the fixed pelvis diverges just past its "
        "own limit while the rotating pelvis stays bounded",
        paper=f"diverges at {paper.KAPPA_DIVERGES_LENGTH:.2f} m "
        f"({paper.KAPPA_DIVERGES_LENGTH - _FIXED:.2f} m past its {_FIXED:.2f} m limit)",
        measure=measures.kappa_own_limit,
        ours="fixed max kappa {fixed_at_limit:.0f} at {lc:.2f} m (clean) -> {fixed_past:.0f} "
        "at {ff:.2f} m (not clean); MPC at {ff:.2f} m: {mpc_past:.0f}",
        rule=Rule(
            (above("growth", 2.0), below("mpc_over_fixed", 1.0)), (below("mpc_over_fixed", 1.0),)
        ),
        names={
            "growth": "fixed's max kappa(J) at its first failed / at its longest clean length",
            "mpc_over_fixed": "MPC's / fixed's max kappa(J) at that failed length",
        },
    ),
    Claim(
        id="zmp",
        section="7",
        claim=f"with MPC at {paper.ZMP_LENGTH:g} m the ZMP stays inside the support foot",
        paper="inside (experiment, LIPM ZMP from the measured CoM)",
        measure=measures.zmp,
        ours="CoP to the support polygon's edge: 5th percentile {p5:.1f} mm, least {min:.1f} "
        "mm; support foot tilts up to {tilt:.2f} deg; LIPM ZMP inside the planned support "
        "{lipm_percent:.1f} % (the CoP is inside by construction: {cop_percent:.1f} %)",
        rule=Rule(
            (at_least("p5", ZMP_MARGIN_HOLDS_MM), at_most("tilt", 1.0)),
            (at_least("p5", ZMP_MARGIN_PARTLY_MM),),
        ),
        names={
            "p5": "5th percentile of the CoP's distance to the support polygon's edge [mm]",
            "tilt": "largest support-foot tilt [deg]",
        },
        note=f"half the controller's ZMP margin ({ZMP_MARGIN_HOLDS_MM:.0f} mm of "
        f"{1000 * ControllerParams().com.zmp_margin:.0f} mm) in 95 % of the walking ticks, the "
        "foot flat within 1 deg",
    ),
    Claim(
        id="energy_least",
        section="5",
        claim="the proposed method consumes the least energy, except at one step length",
        paper=f"least at {_LEAST_WINS}/{len(_LEAST)} of Table 1's lengths (not at {_LEAST_MISSES})",
        measure=measures.energy_least,
        ours="least at {wins}/{n} lengths; not at {exceptions} ({details})",
        rule=Rule((at_most("misses", 1),), (at_least("share", 0.5),)),
        names={
            "misses": "lengths where another method's mean is lower",
            "share": "share of the lengths where MPC's mean is the least",
        },
        note="among the methods that walked the length (repeats that did not fall)",
    ),
    Claim(
        id="yaw_030_similar",
        section="4",
        claim=f"at {min(paper.FIGURE_LENGTHS):.1f} m the methods' yaw momentum differs little",
        paper="'the difference does not appear to be significant' (Fig. 12a)",
        measure=measures.yaw_similar,
        ours="peaks (fixed / redundancy / MPC) arms on {peaks_arms}, off {peaks_no_arms} kg "
        "m^2/s: spread up to {spread_percent:.0f} %",
        rule=Rule((at_most("spread", 0.2),), (at_most("spread", 0.35),)),
        names={"spread": "(largest - least peak) / largest, the worse of arms on and off"},
    ),
    Claim(
        id="kappa_040_events",
        section="6",
        claim=f"at {measures.LONG:g} m MPC has the larger kappa(J) at lift-off, redundancy at "
        "landing",
        paper="Sec. VI-E (Fig. 13c)",
        measure=measures.kappa_events,
        ours="lift-off MPC {mpc_lift:.0f} vs redundancy {red_lift:.0f}; landing redundancy "
        "{red_land:.0f} vs MPC {mpc_land:.0f} (J_low; leg columns: lift-off {mpc_lift_legs:.0f} "
        "vs {red_lift_legs:.0f}, landing {red_land_legs:.0f} vs {mpc_land_legs:.0f})",
        rule=Rule((at_least("n_agree", 2),), (at_least("n_agree", 1),)),
        names={"n_agree": "of the two orderings, how many we see (median over the steps)"},
    ),
)
