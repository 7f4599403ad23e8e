"""The report's summary at the top: the headline numbers, what holds, what does not and why,
one line per topic, written from the analysed results (a line whose numbers are missing is
left out)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from app.experiments import paper
from app.experiments.definitions import AUTHORS, Study
from app.experiments.results import ClaimResult, StudyResults
from app.experiments.runs import case_key
from app.experiments.verdicts import FAILS, HOLDS, NOT_MEASURED, PARTLY
from app.sim.metrics import KAPPA_SINGULAR, LANDING_ERROR_CLEAN

GAIN = paper.MAX_STEP["mpc"] - paper.MAX_STEP["fixed"]  # [m] the paper's gain
ENERGY_CLAIMS = {  # id -> in a few words
    "energy_std": "the MPC's smaller std",
    "energy_std_gap_grows": "the std gap growing with the length",
    "energy_mpc_below_redundancy": "the MPC below redundancy",
    "energy_short": "rotation cheaper up to 0.20 m",
    "energy_mid": "rotation dearer at 0.25-0.30 m",
    "energy_least": "the MPC the least",
}


def _claim(r: StudyResults, cid: str) -> ClaimResult | None:
    return next((c for c in r.claims if c.id == cid), None)


def _v(r: StudyResults, cid: str) -> str:
    c = _claim(r, cid)
    return c.verdict if c else NOT_MEASURED


def _m(v: float | None, spec: str = ".2f") -> str:
    return "-" if v is None else format(v, spec)


def _limits(study: Study, r: StudyResults) -> str | None:
    ms = r.max_step
    f, red, m = (ms[k].longest_clean for k in ("fixed", "redundancy", "mpc"))
    if f is None or m is None:
        return None
    text = (
        f"**Longest step (Sec. VI-B): {_v(r, 'max_step')}.** Clean on our model: fixed "
        f"{_m(f)}, redundancy {_m(red)}, MPC {_m(m)} m, the MPC {m - f:+.2f} m over the fixed "
        f"pelvis ({100 * (m / f - 1):+.0f} %); the paper: "
        + " / ".join(f"{paper.MAX_STEP[k]:.2f}" for k in ("fixed", "redundancy", "mpc"))
        + f" m (+{GAIN:.2f} m)."
    )
    if f > paper.MAX_STEP["fixed"] + 1e-9 and m - f < GAIN - 1e-9:
        text += " Our fixed pelvis reaches farther than the paper's, so the gain is smaller."
    s = r.sensitivity
    best = s.best_gain() if s else None
    if s and best:
        hits = s.cells_with_gain(GAIN)
        text += f" Over the sensitivity grid the gain reaches {best[0]:+.2f} m ({best[1]})"
        text += (
            f"; +{GAIN:.2f} m or more in {len(hits)} of {len(s.all_cells())} cells"
            if hits
            else f"; no cell reaches +{GAIN:.2f} m"
        )
        authors = s.gain([list(a) for a in AUTHORS])
        if authors is not None:
            text += f"; with the authors' DSP and step width {authors:+.2f} m"
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
    text = (
        f"**Robustness (section 8).** Table 1's seeded repeats ({rob.repeats} per method and "
        f"length, {rob.lengths[0]:.2f}-{rob.lengths[-1]:.2f} m, a 5 N random push on the "
        f"torso throughout): runs that fell: {', '.join(parts)}; that did not fall but landed a "
        f"foot more than {LANDING_ERROR_CLEAN * 100:.0f} cm off: {', '.join(off)}"
        + (f" (worst {max(worst):.1f} cm)." if worst else ".")
    )
    pushes = [p for p in rob.pushes.values() if p is not None]
    if pushes:
        x = sorted({p.step_length for p in pushes})[len({p.step_length for p in pushes}) // 2]
        at = {p.method: p for p in pushes if abs(p.step_length - x) < 1e-9}
        words = [
            f"{m} {'falls unpushed' if p.survived is None else f'{p.survived:.0f} N'}"
            for m in study.methods
            if (p := at.get(m)) is not None
        ]
        text += f" Largest sideways push survived at {x:.2f} m: {', '.join(words)}."
    return text


def _waist(study: Study, r: StudyResults) -> str | None:
    c = _claim(r, "waist_turns_early")
    if c is None or not c.measured:
        return None
    d = c.measured
    amp = _claim(r, "waist_amplitude")

    def when(lead: float) -> str:
        if abs(lead) < 0.005 + 1e-9:
            return "at the lift-off"
        return f"{abs(lead):.2f} s {'before' if lead > 0 else 'after'} the lift-off"

    text = (
        f"**Waist (Fig. 8-9): the early turn {c.verdict}.** The MPC's turn toward the coming "
        f"swing starts {when(d['mpc_lead'])}, redundancy's {when(d['red_lead'])} (rate at "
        f"lift-off {d['mpc_rate']:+.0f} vs {d['red_rate']:+.0f} deg/s toward the swing). "
        f"Its size: the MPC's waist moves {d['mpc_share']:.1f} % of its range in the DSP, "
        f"{d['mpc_of_sine']:.0%} of what a sine over the step moves."
    )
    if amp and amp.measured:
        text += (
            f" Amplitude {amp.measured['peak']:.1f} deg at {paper.WAIST_PEAK_LENGTH:.2f} m "
            f"(paper {paper.WAIST_PEAK_DEG:.0f}): {amp.verdict}."
        )
    return text


def _energy(study: Study, r: StudyResults) -> str | None:
    claims = [c for cid in ENERGY_CLAIMS if (c := _claim(r, cid)) and c.verdict != NOT_MEASURED]
    if not claims:
        return None
    counts = {v: sum(c.verdict == v for c in claims) for v in (HOLDS, PARTLY, FAILS)}
    ties = sum(c.measured.get("ties", 0) for c in claims)
    comparisons = sum(c.measured.get("n", 0) for c in claims if "ties" in c.measured)
    changed = [
        f"{ENERGY_CLAIMS[c.id]} ({c.verdict} -> {c.variants['1 ms']})"
        for c in claims
        if c.variants and c.variants.get("1 ms") != c.verdict
    ]
    means = [c.mean for row in r.energy.table.values() for c in row.values() if c.mean]
    text = (
        f"**Energy (Table 1):** of {len(claims)} energy claims {counts[HOLDS]} hold, "
        f"{counts[PARTLY]} partly, {counts[FAILS]} do not. {ties} of {comparisons} orderings "
        "are ties: our methods' means differ by less than the repeats' spread, most at the "
        "short lengths"
    )
    if means:
        text += f"; our windows cost {min(means):.0f}-{max(means):.0f} J (the paper's 10-941 J)"
    text += (
        f". On the energy at 1 ms instead of 200 Hz the verdict changes for {'; '.join(changed)}."
        if changed
        else ". The verdicts are the same on the energy at 1 ms."
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
            f"{own.verdict}"
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
    if not r.claims:
        return None
    count = {v: sum(c.verdict == v for c in r.claims) for v in (HOLDS, PARTLY, FAILS, NOT_MEASURED)}
    fails = [c.claim for c in r.claims if c.verdict == FAILS]
    text = (
        f"**All {len(r.claims)} claims:** {count[HOLDS]} hold, {count[PARTLY]} partly, "
        f"{count[FAILS]} do not hold"
        + (f", {count[NOT_MEASURED]} not measured" if count[NOT_MEASURED] else "")
        + "."
    )
    if fails:
        text += " Not holding: " + "; ".join(fails) + "."
    return text


LINES: tuple[Callable[[Study, StudyResults], str | None], ...] = (
    _verdicts,
    _limits,
    _robustness,
    _waist,
    _energy,
    _kappa,
    _zmp,
)


def summary_lines(study: Study, r: StudyResults) -> list[str]:
    """The summary's lines (those whose numbers are there)."""
    out: list[Any] = [line(study, r) for line in LINES]
    return [x for x in out if x]
