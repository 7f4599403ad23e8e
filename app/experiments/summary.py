"""The report's summary at the top: a plain paragraph for a reader who has not read the
glossary, then the headline numbers, what holds, what does not and why, one line per topic,
written from the analysed results (a line whose numbers are missing is left out).

Every gain the summary states carries its trade beside it (:func:`trade_words`: k_pel, the
MPC's waist amplitude, the push margin against the fixed pelvis); every paper number comes
from :mod:`app.experiments.paper`, every measured one from the results.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

import numpy as np

from app.experiments import paper
from app.experiments.ablation import buys, push_n
from app.experiments.definitions import AUTHORS, Study
from app.experiments.energy import MIN_EFFECT_MEAN
from app.experiments.outcomes import case_key, length_key
from app.experiments.results import ClaimResult, StudyResults
from app.experiments.robustness import (
    PushCell,
    RobustnessSection,
    TradeRow,
    falls_p,
    stability,
)
from app.experiments.verdicts import DEPENDS, FAILS, HOLDS, INCONCLUSIVE, NOT_MEASURED, PARTLY
from controller import strategy
from controller.strategy import FIXED, MPC, REDUNDANCY
from pelvic_walk.core.metrics import KAPPA_SINGULAR, LANDING_ERROR_CLEAN
from pelvic_walk.core.run_spec import DISTURBANCE

GAIN = paper.MAX_STEP[MPC] - paper.MAX_STEP[FIXED]  # [m] the paper's gain
_CHEAP = paper.ENERGY_ROTATION_CHEAPER_UP_TO
_DEAR = [x for x in paper.TABLE1_LENGTHS if _CHEAP < x <= paper.MAX_STEP[FIXED] + 1e-9]
ENERGY_CLAIMS = {  # id -> in a few words
    "energy_std": "the MPC's smaller std",
    "energy_std_gap_grows": "the std gap growing with the length",
    "energy_mpc_below_redundancy": "the MPC below redundancy",
    "energy_short": f"rotation cheaper up to {_CHEAP:.2f} m",
    "energy_mid": f"rotation dearer at {_DEAR[0]:.2f}-{_DEAR[-1]:.2f} m",
    "energy_least": "the MPC the least",
}


def _claim(r: StudyResults, cid: str) -> ClaimResult | None:
    return next((c for c in r.claims if c.id == cid), None)


def _v(r: StudyResults, cid: str) -> str:
    c = _claim(r, cid)
    return c.verdict if c else NOT_MEASURED


def _m(v: float | None, spec: str = ".2f") -> str:
    return "-" if v is None else format(v, spec)


def _survived(p: PushCell | None) -> float | None:
    return None if p is None else p.survived


def trade_words(t: TradeRow) -> str:
    """What a gain costs, in words: k_pel, the MPC's waist amplitude against the paper's, and
    the largest push the MPC survives against the fixed pelvis's, each direction."""
    text = f"k_pel = {t.k_pel:g}"
    if t.waist_deg is not None:
        text += (
            f", the MPC's waist peaks at {t.waist_deg:.1f} deg over a walk of "
            f"{t.waist_length:.2f} m steps (the paper's {paper.WAIST_PEAK_DEG:.0f} deg)"
        )
    pushes = []
    for d, by in t.pushes.items():
        m, f = _survived(by.get(MPC)), _survived(by.get(FIXED))
        if m is not None and f is not None:
            pushes.append(f"{m:.0f} against {f:.0f} N to the {d} ({m - f:+.0f} N)")
    if pushes:
        text += (
            f", and the largest push it survives at {t.push_length:.2f} m is "
            + ", ".join(pushes)
            + " of the fixed pelvis's"
        )
    return text


def _trade_of(r: StudyResults, name: str) -> TradeRow | None:
    rob = r.robustness
    return next((t for t in rob.trade if t.name == name), None) if rob else None


def _push_tally(rob: RobustnessSection, other: str) -> tuple[int, int, int]:
    """(pushes where the MPC survives more, less, of all) against ``other``."""
    pushes = [c for c in stability(rob, MPC, other) if c.what.startswith("push")]
    return (
        sum(c.order < 0 for c in pushes),
        sum(c.order > 0 for c in pushes),
        len(pushes),
    )


def _heavy_falls(rob: RobustnessSection) -> tuple[str, dict[str, Any]] | None:
    """The largest push size's falls (its key and cells), when it is larger than the study's."""
    sizes = [k for k in rob.falls if rob.falls[k] and k != f"{DISTURBANCE:g} N"]
    return (sizes[-1], rob.falls[sizes[-1]]) if sizes else None


def _row(a: Any, m: str) -> Any:
    return next((w for w in a.rows if w.method == m), None) if a else None


def _push_pair(p: dict[str, PushCell | None], directions: list[str]) -> str:
    vals = [_survived(p.get(d)) for d in directions]
    return " / ".join("-" if v is None else f"{v:.0f}" for v in vals)


def answer(study: Study, r: StudyResults) -> str | None:
    """The first page's answer: does turning the pelvis lengthen the step (every method's
    longest clean step side by side), does the MPC's plan add to it over the simpler ways to
    turn, and what each costs (waist, push margin, energy), with the resolution of each."""
    ms, a = r.max_step, r.ablation
    f, m = ms[FIXED].longest_clean, ms[MPC].longest_clean
    if f is None or m is None:
        return None
    res = study.sweep_resolution
    methods = [FIXED, REDUNDANCY, MPC] + [w.method for w in (a.rows if a else [])]
    methods = list(dict.fromkeys(x for x in methods if x in ms or _row(a, x)))

    def limit(x: str) -> float | None:
        return ms[x].longest_clean if x in ms else _row(a, x).longest_clean

    def label(x: str) -> str:
        w = _row(a, x)
        return {FIXED: "pelvis held straight", REDUNDANCY: "redundancy", MPC: "MPC"}.get(
            x, f"{w.label.lower()} (`{x}`)" if w else x
        )

    lims = {x: limit(x) for x in methods}
    turning = [x for x in methods if x != FIXED and lims[x] is not None]
    gains = [cast(float, lims[x]) - f for x in turning]
    lengthens = bool(gains) and max(gains) > res / 2
    text = (
        "**The answer.** "
        + (
            "Turning the pelvis lengthens the longest step our robot walks without a fault"
            + (", whichever way it is turned" if gains and min(gains) > res / 2 else "")
            if lengthens
            else "Turning the pelvis does not lengthen the longest step our robot walks "
            "without a fault"
        )
        + ": "
        + ", ".join(f"{label(x)} {_m(lims[x])} m" for x in methods)
        + f" (each found on a {res:g} m grid, so +/- {res:g} m; the paper: "
        + " / ".join(f"{paper.MAX_STEP[k]:.2f}" for k in (FIXED, REDUNDANCY, MPC))
        + " m for the first three)."
    )
    if gains:
        text += (
            f" Rotation earns {min(gains):+.2f} to {max(gains):+.2f} m "
            f"({100 * min(gains) / f:+.0f} to {100 * max(gains) / f:+.0f} %)"
        )
        if f > paper.MAX_STEP[FIXED] + 1e-9 and m - f < GAIN - 1e-9:
            text += (
                f"; the paper's +{GAIN:.2f} m is not reproduced because our fixed pelvis "
                f"already walks {f:.2f} m (section 2 measures why)"
            )
        text += "."
        others = [x for x in turning if x != MPC]
        best_other = max((cast(float, lims[x]) for x in others), default=None)
        if best_other is not None:
            extra = m - best_other
            text += (
                f" The MPC's plan adds {extra:+.2f} m over the best of the simpler ways to turn"
                + (" (within one step of the grid)" if abs(extra) <= res + 1e-9 else "")
                + ": "
                + ", ".join(f"{label(x)} {m - cast(float, lims[x]):+.2f} m" for x in others)
                + "."
            )
            if lengthens and extra <= res + 1e-9:
                text += (
                    " So on this robot the rotation earns the longer step; the MPC's "
                    f"prediction buys at most one grid step ({res:g} m) of it."
                )
        if _row(a, "sine"):
            text += " The sine is essentially the prior art the paper cites (its ref. [2])."
    if a is not None:
        x = length_key(a.turn_length)
        dirs = list(study.pushes.directions) if study.pushes else []
        rows = [w for w in (_row(a, y) for y in methods) if w]
        waist = ", ".join(f"{label(w.method)} {_m(w.waist_peak_deg.get(x), '.0f')}" for w in rows)
        push = ", ".join(f"{label(w.method)} {_push_pair(w.pushes, dirs)}" for w in rows)
        energy = ", ".join(
            f"{label(w.method)} {_m(w.energy_substep.get(x), '.0f')} +/- "
            f"{_m(w.energy_std_substep.get(x), '.0f')}"
            for w in rows
        )
        text += (
            f" **What each costs**, on the same unseeded walks: the waist's peak at "
            f"{a.turn_length:.2f} m: {waist} deg; the largest sideways shove survived at "
            f"{a.push_length:.2f} m ({' / '.join(dirs)}, each bracketed to "
            f"{a.push_resolution:g} N, one push phase): {push} N; energy per two steps at "
            f"{a.turn_length:.2f} m (1 ms, mean +/- std over one walk's windows): {energy} J."
        )
        fixed_row = _row(a, FIXED)
        spread = []
        for w in rows:
            for d in dirs:
                pw = push_n(w.pushes.get(d))
                pf = push_n(fixed_row.pushes.get(d)) if fixed_row else None
                if pw is not None and pf is not None:
                    spread.append(abs(pw - pf))
        if spread:
            text += (
                f" The shoves differ from the straight pelvis's by at most {max(spread):.0f} N "
                "in this one phase of the step."
            )
    rob = r.robustness
    heavy = _heavy_falls(rob) if rob else None
    if heavy and MPC in heavy[1] and FIXED in heavy[1]:
        by = heavy[1]
        cm, cf = by[MPC], by[FIXED]
        p = falls_p(cm, cf)
        text += (
            f" Under random shoves {heavy[0]} strong the MPC falls in {cm.fell} of {cm.runs} "
            f"walks against {cf.fell} of {cf.runs} with the straight pelvis"
            + (f" and {by[REDUNDANCY].fell} with redundancy" if REDUNDANCY in by else "")
            + (f" (p = {p:.2g}: not a significant difference)" if p >= 0.05 else f" (p = {p:.2g})")
            + "."
        )
    st = _claim(r, "stability")
    if st and st.measured.get("reading_rows"):
        text += (
            f" Is the MPC's rotation 'more stable' than redundancy's (Sec. VII): {st.verdict}; "
            + "; ".join(f"{k}: {says}" for k, says, _ in st.measured["reading_rows"])
            + " (section 8)."
        )
    return text


def plain(study: Study, r: StudyResults) -> str | None:
    """The first paragraph: what the paper says, our answer, and the tally."""
    ms = r.max_step
    f, m = ms[FIXED].longest_clean, ms[MPC].longest_clean
    if f is None or m is None:
        return None
    text = (
        "The paper proposes that a humanoid robot turn its pelvis (its hips, about the "
        "vertical) while it walks, planned a moment ahead by a model-predictive controller "
        "(*MPC*: at every instant it predicts where the body and feet will be over the next "
        "second or so and chooses the turn that fits them), so that each leg reaches "
        "further and the robot can take longer steps. It compares this with the pelvis held "
        "straight (*fixed*) and with the authors' earlier method, which turns the pelvis only "
        "as far as the feet need at each instant (*redundancy*)."
    )
    if r.ablation is not None and any(w.role != "paper" for w in r.ablation.rows):
        text += (
            " Beside them we run simpler ways to turn: "
            + ", ".join(
                f"{w.label.lower()} (`{w.method}`)" for w in r.ablation.rows if w.role != "paper"
            )
            + " (section 10)."
        )
    ans = answer(study, r)
    if ans:
        text += "\n\n" + ans
    count = {
        v: sum(c.verdict == v for c in r.tallied)
        for v in (HOLDS, PARTLY, INCONCLUSIVE, FAILS, DEPENDS)
    }
    text += (
        f"\n\nOf the paper's {len(r.tallied)} claims we test, {count[HOLDS]} hold, "
        f"{count[PARTLY]} hold in part, "
        + (
            f"{count[INCONCLUSIVE]} are inconclusive (our evidence cannot tell) "
            if count[INCONCLUSIVE]
            else "none is inconclusive "
        )
        + f"and {count[FAILS]} do not hold"
        + (f"; {count[DEPENDS]} depend on the reading" if count[DEPENDS] else "")
        + "."
    )
    if r.checks:
        text += (
            f" {len(r.checks)} more rows are listed apart, not counted: their inputs were chosen "
            "to match the paper (or they follow from another rule), so they only check the "
            "set-up."
        )
    return text


def _limits(study: Study, r: StudyResults) -> str | None:
    ms = r.max_step
    f, red, m = (ms[k].longest_clean for k in (FIXED, REDUNDANCY, MPC))
    if f is None or m is None:
        return None
    text = (
        f"**Longest step (Sec. VI-B): {_v(r, 'max_step')}.** Clean on our model: fixed "
        f"{_m(f)}, redundancy {_m(red)}, MPC {_m(m)} m, the MPC {m - f:+.2f} m over the fixed "
        f"pelvis ({100 * (m / f - 1):+.0f} %); the paper: "
        + " / ".join(f"{paper.MAX_STEP[k]:.2f}" for k in (FIXED, REDUNDANCY, MPC))
        + f" m (+{GAIN:.2f} m)."
    )
    if f > paper.MAX_STEP[FIXED] + 1e-9 and m - f < GAIN - 1e-9:
        text += " Our fixed pelvis reaches farther than the paper's, so the gain is smaller."
    default = _trade_of(r, "the defaults")
    if default:
        text += f" The cost of that gain: {trade_words(default)} (section 8)."
    s = r.sensitivity
    best = s.best_gain() if s else None
    if s and best:
        hits = s.cells_with_gain(GAIN)
        text += f" Over the sensitivity grid the gain reaches {best[0]:+.2f} m ({best[1]})"
        t = _trade_of(r, best[1])
        if t:
            text += f", where {trade_words(t)}"
        text += (
            f"; +{GAIN:.2f} m or more in {len(hits)} of {len(s.all_cells())} cells"
            if hits
            else f"; no cell reaches +{GAIN:.2f} m"
        )
        authors = s.gain([list(a) for a in AUTHORS])
        if authors is not None:
            text += f". With the authors' DSP and step width the gain is {authors:+.2f} m"
            t = next(
                (
                    t
                    for t in (r.robustness.trade if r.robustness else [])
                    if sorted(map(tuple, t.overrides)) == sorted(AUTHORS)
                ),
                None,
            )
            if t:
                text += f" ({trade_words(t)})"
        text += " (section 9)."
    return text


def _robustness(study: Study, r: StudyResults) -> str | None:
    rob = r.robustness
    if rob is None or not any(rob.cells.values()):
        return None
    parts, off = [], []
    for m in study.methods:
        cells = [c for c in (rob.cells.get(case_key(m, x)) for x in rob.lengths) if c]
        parts.append(f"{m} {sum(c.fell for c in cells)}/{sum(c.runs for c in cells)}")
        off.append(f"{m} {sum(c.off_foothold for c in cells)}")
    worst = [c.worst_landing_cm for c in rob.cells.values() if c and c.worst_landing_cm]
    c = _claim(r, "stability")
    text = "**Stability (Sec. VII, section 8): " + (
        f"the MPC more stable than redundancy: {c.verdict}.** " if c else "** "
    )
    if c and c.measured.get("reading_rows"):
        text += (
            "Reading by reading: "
            + "; ".join(f"{k}: {says}" for k, says, _ in c.measured["reading_rows"])
            + ". "
        )
    text += (
        f"Table 1's seeded repeats ({rob.repeats} per method and length, "
        f"{rob.lengths[0]:.2f}-{rob.lengths[-1]:.2f} m, a {DISTURBANCE:g} N random push on the "
        f"torso throughout): runs that fell: {', '.join(parts)}; that did not fall but landed a "
        f"foot more than {LANDING_ERROR_CLEAN * 100:.0f} cm off: {', '.join(off)}"
        + (f" (worst {max(worst):.1f} cm)." if worst else ".")
    )
    heavy = _heavy_falls(rob)
    if heavy:
        size, by = heavy
        text += (
            f" Under pushes of {size}: fell "
            + ", ".join(f"{m} {by[m].fell}/{by[m].runs}" for m in study.methods if m in by)
            + "."
        )
    if rob.pushes:
        for other in (REDUNDANCY, FIXED):
            more, less, n = _push_tally(rob, other)
            if n:
                text += (
                    f" Largest sideways push survived, the MPC against {other}: more in {more}, "
                    f"less in {less}, within the bisection's resolution in {n - more - less} of "
                    f"{n} (lengths and directions)."
                )
    return text


def _waist(study: Study, r: StudyResults) -> str | None:
    c = _claim(r, "waist_turns_early")
    if c is None or not c.measured:
        return None
    d = c.measured
    amp, why = _claim(r, "waist_amplitude"), _claim(r, "waist_from_prediction")

    text = (
        f"**Waist (Fig. 8-9): the early turn {c.verdict}.** Before the lift-off the MPC's waist "
        f"turns {d['mpc_early']:.1f} % of its range toward the coming swing, "
        f"{d['mpc_of_sine_percent']:.0f} % of what a sine over the step moves "
        f"({d['sine']:.1f} %; the rule's bar is 50 %), its rate at lift-off "
        f"{d['mpc_rate']:+.0f} deg/s toward the swing; redundancy's {d['red_early']:.1f} % "
        f"({d['red_rate']:+.0f} deg/s)."
    )
    if why and why.measured:
        w = why.measured
        text += (
            f" Does it come from the prediction: {why.verdict}. The prediction is necessary "
            f"(with the reference from the state now: {w['abl_early']:+.1f} % of the range) "
            f"but not sufficient (with the prediction and the other readings of eq. (31)-(32)'s "
            f"lateral distance: {w['others']})."
        )
    if amp and amp.measured:
        text += (
            f" Amplitude in the mid-walk step {amp.measured['peak']:.1f} deg at "
            f"{paper.WAIST_PEAK_LENGTH:.2f} m "
            f"(paper {paper.WAIST_PEAK_DEG:.0f}): {amp.verdict}, a check (k_pel was chosen to "
            "give it)."
        )
    return text


def _energy(study: Study, r: StudyResults) -> str | None:
    claims = [c for cid in ENERGY_CLAIMS if (c := _claim(r, cid)) and c.verdict != NOT_MEASURED]
    if not claims:
        return None
    counts = {
        v: sum(c.verdict == v for c in claims)
        for v in (HOLDS, PARTLY, INCONCLUSIVE, FAILS, DEPENDS)
    }
    ties = sum(c.measured.get("ties", 0) for c in claims)
    comparisons = sum(c.measured.get("n", 0) for c in claims if "ties" in c.measured)
    depends = [
        f"{ENERGY_CLAIMS[c.id]} (" + ", ".join(f"{v} at {k}" for k, v in c.variants.items()) + ")"
        for c in claims
        if c.verdict == DEPENDS
    ]
    e1 = r.energy.at_substep()  # the reading the claims use
    means = [c.mean for row in e1.table.values() for c in row.values() if c.mean]
    theirs = [c.mean for row in paper.TABLE1.values() for c in row.values() if c]
    text = (
        f"**Energy (Table 1, judged at 1 ms):** of {len(claims)} energy claims "
        f"{counts[HOLDS]} hold, {counts[PARTLY]} partly, {counts[INCONCLUSIVE]} inconclusive, "
        f"{counts[FAILS]} do not"
        + (
            f", {counts[DEPENDS]} "
            + ("depends" if counts[DEPENDS] == 1 else "depend")
            + " on the reading"
            if counts[DEPENDS]
            else ""
        )
        + f". {ties} of {comparisons} orderings are ties: the repeats do not separate the "
        f"means, or they differ by less than {100 * MIN_EFFECT_MEAN:.0f} % (the smallest "
        "difference that counts)"
    )
    if means:
        text += (
            f"; our windows cost {min(means):.0f}-{max(means):.0f} J at 1 ms (the paper's "
            f"{min(theirs):.0f}-{max(theirs):.0f} J)"
        )
    differ = [
        f"{ENERGY_CLAIMS[c.id]} ({c.verdict}; "
        + ", ".join(f"{v} at {k}" for k, v in c.variants.items() if k != c.reading)
        + ")"
        for c in claims
        if any(v != c.verdict for v in c.variants.values())
    ]
    text += (
        ". Depending on whether the energy is sampled at 200 Hz or every 1 ms: "
        + "; ".join(depends)
        + " (section 5 says why)."
        if depends
        else ""
    )
    text += (
        ". The 200 Hz reading (aliased, not used for the verdicts) would say otherwise for: "
        + "; ".join(differ)
        + "."
        if differ
        else ". The 200 Hz reading gives the same verdicts."
    )
    return text


def _kappa(study: Study, r: StudyResults) -> str | None:
    c, own = _claim(r, "kappa_035"), _claim(r, "kappa_own_limit")
    if c is None or not c.measured:
        return None
    d = c.measured
    text = (
        f"**kappa (Fig. 13): divergence at {paper.KAPPA_DIVERGES_LENGTH:.2f} m {c.verdict}.** "
        f"The fixed pelvis's kappa(legs) peaks at {d['fixed_legs']:.3g} there (singular from "
        f"{KAPPA_SINGULAR:.0f}), the MPC's at {d['mpc_legs']:.3g}"
    )
    if own and own.measured:
        o = own.measured
        text += (
            f"; past our fixed pelvis's own limit ({o['lc']:.2f} m) it reaches "
            f"{o['fixed_past']:.3g} at {o['ff']:.2f} m against the MPC's {o['mpc_past']:.3g}: "
            f"{own.verdict}, a check (the clean rule that sets the limit implies it)"
        )
    return text + "."


def _zmp(study: Study, r: StudyResults) -> str | None:
    c = _claim(r, "zmp")
    if c is None or not c.measured:
        return None
    text = (
        f"**ZMP (Fig. 15): {c.verdict}.** The LIPM ZMP from the measured CoM lies in the "
        f"planned support in {c.measured['lipm_percent']:.1f} % of the walking ticks."
    )
    b = r.balance
    cases = [x for x in (b.cases.values() if b else []) if x and x.edge_share is not None]
    if cases:
        edges: dict[str, int] = {}
        for x in cases:
            for k, v in x.edges.items():
                edges[k] = edges.get(k, 0) + v
        top = max(edges, key=lambda k: edges[k]) if any(edges.values()) else None
        zero = [x for x in cases if x.margin_p5_mm is not None and x.margin_p5_mm < 0.05]
        share = float(np.mean([x.edge_share for x in cases]))
        if zero:
            text += (
                f" The CoP's margin reads 0 mm in {len(zero)} of {len(cases)} runs (5th "
                "percentile) because a foot rests on one edge of its sole "
                f"({100 * share:.1f} % of walking ticks on average"
                + (f", mostly the {top} edge" if top else "")
                + "): a roll, not a measuring error."
            )
        else:
            p5 = min(x.margin_p5_mm for x in cases if x.margin_p5_mm is not None)
            text += (
                f" The CoP keeps a margin to the sole's edge: its 5th percentile is at least "
                f"{p5:.1f} mm in every run; on an edge in {100 * share:.1f} % of walking ticks."
            )
    return text


def _verdicts(study: Study, r: StudyResults) -> str | None:
    tallied = r.tallied
    if not tallied:
        return None
    count = {
        v: sum(c.verdict == v for c in tallied)
        for v in (HOLDS, PARTLY, INCONCLUSIVE, FAILS, DEPENDS, NOT_MEASURED)
    }
    fails = [c.claim for c in tallied if c.verdict == FAILS]
    unsure = [c.claim for c in tallied if c.verdict == INCONCLUSIVE]
    depends = [c.claim for c in tallied if c.verdict == DEPENDS]
    text = (
        f"**All {len(tallied)} claims:** {count[HOLDS]} hold, {count[PARTLY]} partly, "
        f"{count[INCONCLUSIVE]} inconclusive, {count[FAILS]} do not hold"
        + (
            f", {count[DEPENDS]} "
            + ("depends" if count[DEPENDS] == 1 else "depend")
            + " on the energy's reading"
            if count[DEPENDS]
            else ""
        )
        + (f", {count[NOT_MEASURED]} not measured" if count[NOT_MEASURED] else "")
        + "."
    )
    if fails:
        text += " Not holding: " + "; ".join(fails) + "."
    if unsure:
        text += " Inconclusive (our evidence cannot tell): " + "; ".join(unsure) + "."
    if depends:
        text += " Depending on the reading: " + "; ".join(depends) + "."
    if r.checks:
        text += (
            f" Besides them {len(r.checks)} consistency "
            + ("check" if len(r.checks) == 1 else "checks")
            + " (not counted): "
            + "; ".join(f"{c.claim} ({c.verdict})" for c in r.checks)
            + "."
        )
    return text


def _ablation(study: Study, r: StudyResults) -> str | None:
    a = r.ablation
    if a is None or not any(w.method == strategy.MPC for w in a.rows):
        return None
    parts = [f"over {w.label} (`{w.method}`) {buys(a, w)}" for w in a.rows if w.role != "paper"]
    return "**What the MPC's plan buys (section 10):** " + "; ".join(parts) + "."


LINES: tuple[Callable[[Study, StudyResults], str | None], ...] = (
    _verdicts,
    _limits,
    _robustness,
    _waist,
    _energy,
    _kappa,
    _zmp,
    _ablation,
)


def summary_lines(study: Study, r: StudyResults) -> list[str]:
    """The summary's lines (those whose numbers are there)."""
    out: list[Any] = [line(study, r) for line in LINES]
    return [x for x in out if x]
