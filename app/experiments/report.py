"""The markdown report: ``templates/report.md.j2`` and one template per section, rendered from
the typed :class:`StudyResults` (numbers) and :mod:`app.experiments.paper` (the paper's).

Each section's text is in its template (``templates/<n>_<name>.md.j2``); numbers are
formatted by the small filters below. Every table cell the report writes goes through
:func:`escape_cell` (via :func:`row` and :func:`header`), so a ``|`` in a cell cannot split
its row.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import jinja2
import numpy as np

from app.experiments import paper
from app.experiments.ablation import AblationRow
from app.experiments.ablation import buys as ablation_buys
from app.experiments.ablation import reading as ablation_reading
from app.experiments.definitions import (
    AUTHORS,
    AUTHORS_DSP,
    AUTHORS_REST,
    AUTHORS_WIDTH,
    ROTATING,
    Pushes,
    Study,
)
from app.experiments.deviations import DEVIATIONS, paper_value_words
from app.experiments.energy import (
    BOOTSTRAP,
    MIN_EFFECT_MEAN,
    MIN_EFFECT_STD,
    SIGNIFICANCE,
    joint_groups,
    std_gap_p,
)
from app.experiments.kappa import NEAR_BELOW
from app.experiments.outcomes import case_key, length_key
from app.experiments.reach import QUANTITIES
from app.experiments.results import ClaimResult, StudyResults
from app.experiments.robustness import PushCell, RobustnessSection, falls_p, stability
from app.experiments.sensitivity import SensitivitySection
from app.experiments.summary import plain, summary_lines, trade_words
from app.experiments.verdicts import DEPENDS, FAILS, HOLDS, INCONCLUSIVE, NOT_MEASURED, PARTLY
from app.experiments.waist import ANTICIPATION_MIN, EARLY_TURN_MIN, sine_share
from app.experiments.worker import LANDING_WINDOW
from controller.params import LATERAL_MODES, ControllerParams
from models.dyros_jet import TOTAL_MASS
from pelvic_walk.core.measure import threshold_of
from pelvic_walk.core.methods import METHOD_INFO
from pelvic_walk.core.metrics import KAPPA_SINGULAR, LANDING_ERROR_CLEAN
from pelvic_walk.core.run_spec import DISTURBANCE, DISTURBANCE_PERIOD, SEED_PERTURBATION
from pelvic_walk.core.session import GRAVITY

_P = ControllerParams()


VERDICT_MARK = {
    HOLDS: "**holds**",
    PARTLY: "**partly**",
    FAILS: "**does not hold**",
    INCONCLUSIVE: "**inconclusive**",
    DEPENDS: "**depends on the reading**",
    NOT_MEASURED: "not measured",
}
DASH = "—"


def escape_cell(text: Any) -> str:
    """One markdown table cell: ``|`` escaped, line breaks as spaces."""
    return str(text).replace("|", "\\|").replace("\n", " ")


def row(*cells: Any) -> str:
    """A markdown table row."""
    return "| " + " | ".join(escape_cell(c) for c in cells) + " |"


def header(*names: Any) -> str:
    """A markdown table's header and separator rows."""
    return row(*names) + "\n|" + "---|" * len(names)


def fmt(v: Any, spec: str = ".2f", none: str = DASH) -> str:
    """``v`` formatted by ``spec``; ``none`` for None."""
    return none if v is None else format(v, spec)


def percent(v: float | None, spec: str = ".1f") -> str:
    """A share in [0, 1] as percent (no sign)."""
    return fmt(None if v is None else v * 100, spec)


def kappa(v: float | None) -> str:
    """A condition number for a table: singular (>= 1e6) in words, large in powers of ten."""
    if v is None:
        return DASH
    if v >= 1e6:
        return f"singular ({v:.0e})"
    return f"{v:.1f}" if v < 1e3 else f"{v:.2g}"


def lengths(xs: Any, spec: str = ".2f", sep: str = ", ") -> str:
    """Step lengths joined, e.g. ``0.30, 0.40``."""
    return sep.join(format(x, spec) for x in xs)


def stdev(values: list[float]) -> float | None:
    """Population std of a list (None when empty)."""
    return float(np.std(values)) if values else None


def energy_note(r: StudyResults) -> str:
    """Net work against eq. (44) at 1 ms and at 200 Hz over the seeded runs that did not fall:
    how much of either figure does no net work."""
    rows = [
        rec.summary
        for rec in r.runs.values()
        if rec.summary
        and rec.spec.seed is not None
        and not rec.summary.get("fell")
        and rec.summary.get("work_net_total") is not None
        and rec.summary.get("energy_total")
    ]
    if not rows:
        return "no net-work figure recorded"
    net_sub = np.median([s["work_net_total"] / s["energy_total_substep"] for s in rows])
    ratio = np.median([s["energy_total_substep"] / s["energy_total"] for s in rows])
    sampled = [s.get("work_net_total_ctrl") for s in rows]
    net_ctrl = np.median([w / s["work_net_total"] for w, s in zip(sampled, rows, strict=True)])
    return (
        f"over the {len(rows)} seeded runs that did not fall, medians: the 1 ms sum of the "
        f"positive parts is x{ratio:.2f} the 200 Hz one; the net work (torque x speed summed "
        f"with its sign every 1 ms) is {100 * net_sub:.0f} % of the 1 ms figure; the same net "
        f"work from the 200 Hz samples comes out at {net_ctrl:+.1f} times the true one"
    )


def lateral_words() -> dict[str, str]:
    """Each reading of the lateral distance in words, from its parameter's help text
    (``controller/params.py``: "mode: words; mode: words")."""
    from controller.params import PelvisMpcParams, spec

    text = spec(PelvisMpcParams())["lateral_distance"].get("help", "")
    out = {}
    for part in text.split("; "):
        mode, sep, words = part.partition(": ")
        if sep and mode.strip() in LATERAL_MODES:
            out[mode.strip()] = words.strip()
    return out


def verdict_cell(c: ClaimResult) -> str:
    """A claim's verdict; where it depends on the reading, each reading's (e.g. "partly at
    200 Hz, does not hold at 1 ms")."""
    out = VERDICT_MARK.get(c.verdict, c.verdict)
    if c.verdict == DEPENDS:
        return out + " (" + ", ".join(f"{v} at {k}" for k, v in c.variants.items()) + ")"
    others = {k: v for k, v in c.variants.items() if k != c.reading}
    if others:  # a primary reading decided; the others beside it
        return (
            out + f" (at {c.reading}; " + ", ".join(f"{v} at {k}" for k, v in others.items()) + ")"
        )
    return out


def robustness_totals(rob: RobustnessSection, methods: Sequence[str]) -> dict[str, dict]:
    """Per method, the repeats' counts summed over the lengths."""
    out = {}
    for m in methods:
        cells = [c for c in (rob.cells.get(case_key(m, x)) for x in rob.lengths) if c]
        out[m] = {
            "runs": sum(c.runs for c in cells),
            "fell": sum(c.fell for c in cells),
            "off": sum(c.off_foothold for c in cells),
            "landings": sum(c.landings for c in cells),
            "landings_off": sum(c.landings_off for c in cells),
        }
    return out


def push_words(p: PushCell | None) -> str:
    """One push survival in a table cell: "94 / 96" (survives / topples at, N)."""
    if p is None:
        return DASH
    if p.survived is None:
        return "falls unpushed"
    if p.failed is None:
        return f">= {p.survived:.0f} / —"
    return f"{p.survived:.0f} / {p.failed:.0f}"


ORDER_WORDS = {-1: "more", 0: "tie", 1: "less"}  # the MPC against another method


def criterion_words(name: str) -> str:
    """A clean criterion of the sensitivity section in words."""
    landing, bound = threshold_of(name)
    return f"landing < {landing * 100:g} cm, kappa(legs) < {bound:g}"


def threshold_words(s: SensitivitySection) -> str:
    """The thresholds the sensitivity section varies, in words."""
    landings = sorted({threshold_of(c)[0] for c in s.criteria if c != "walks"})
    bounds = sorted({threshold_of(c)[1] for c in s.criteria if c != "walks"})
    return (
        ", ".join(f"{x * 100:g}" for x in landings)
        + " cm and a kappa(legs) bound of "
        + ", ".join(f"{x:g}" for x in bounds)
    )


def authors_words() -> str:
    """The authors' DSP and step width (:data:`~app.experiments.definitions.AUTHORS`) in words."""
    end = AUTHORS_DSP * _P.walk.step_time / 2
    split = dict(AUTHORS)["walk.dsp_split"]
    return (
        f"{end:g} s on both feet at each end of a {_P.walk.step_time:g} s step, i.e. "
        f"`walk.dsp_ratio` = {AUTHORS_DSP:.2f} with `walk.dsp_split` = {split}, and half a step "
        f"width of {AUTHORS_WIDTH / 2:g} m (`walk.step_width` = {AUTHORS_WIDTH:g}); their "
        f"{AUTHORS_REST:g} s rest within the step has no counterpart in our plan"
    )


def energy_word(k: str, w: AblationRow) -> str:
    """A section 10 row's energy at one length: 200 Hz (1 ms substeps)."""
    e, es = w.energy.get(k), w.energy_substep.get(k)
    return DASH if e is None else f"{e:.1f}" + (f" ({es:.1f})" if es is not None else "")


def _environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("app.experiments", "templates"),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,  # markdown, not HTML
        extensions=["jinja2.ext.do"],
    )
    env.filters.update(
        f=fmt,
        percent=percent,
        kappa=kappa,
        lengths=lengths,
        mark=VERDICT_MARK.get,
        stdev=stdev,
        length_key=length_key,
        clean_word=lambda k, w: "yes" if w.clean.get(k) else "no",
        energy_word=energy_word,
    )
    env.globals.update(
        row=row,
        header=header,
        label=lambda m: METHOD_INFO[m].label,
        case_key=case_key,
        length_key=length_key,
        paper=paper,
        ROTATING=ROTATING,
        SEED_PERTURBATION=SEED_PERTURBATION,
        KAPPA_SINGULAR=KAPPA_SINGULAR,
        LANDING_ERROR_CLEAN=LANDING_ERROR_CLEAN,
        DISTURBANCE=DISTURBANCE,
        DISTURBANCE_PERIOD=DISTURBANCE_PERIOD,
        SIGNIFICANCE=SIGNIFICANCE,
        MIN_EFFECT_MEAN=MIN_EFFECT_MEAN,
        MIN_EFFECT_STD=MIN_EFFECT_STD,
        push_resolution=Pushes().resolution,
        deviations=DEVIATIONS,
        paper_value_words=paper_value_words,
        reach_words=QUANTITIES,
        zmp_margin=_P.com.zmp_margin,
        lateral_floor=_P.pelvis.lateral_floor,
        step_width=_P.walk.step_width,
        joint_groups=joint_groups,
        verdict_cell=verdict_cell,
        DEPENDS=DEPENDS,
        robustness_totals=robustness_totals,
        push_words=push_words,
        falls_p=falls_p,
        stability=stability,
        order_words=ORDER_WORDS,
        trade_words=trade_words,
        criterion_words=criterion_words,
        threshold_words=threshold_words,
        std_p=std_gap_p,
        BOOTSTRAP=BOOTSTRAP,
        authors=[list(a) for a in AUTHORS],
        authors_words=authors_words(),
        authors_end_s=AUTHORS_DSP * _P.walk.step_time / 2,
        authors_dsp=AUTHORS_DSP,
        push_share=DISTURBANCE / (TOTAL_MASS * GRAVITY),
        landing_window=LANDING_WINDOW,
        near_below=NEAR_BELOW,
        anticipation_min=ANTICIPATION_MIN,
        early_turn_min=EARLY_TURN_MIN,
        lateral_modes=LATERAL_MODES,
        lateral_words=lateral_words(),
        horizon=_P.com.horizon,
        step_time=_P.walk.step_time,
        dsp_ratio=_P.walk.dsp_ratio,
        k_pel=_P.pelvis.k_pel,
        sine=sine_share(_P.walk.dsp_ratio),
        ablation_reading=ablation_reading,
        ablation_buys=ablation_buys,
    )
    return env


def render(study: Study, results: StudyResults) -> str:
    """The whole report as markdown."""
    return (
        _environment()
        .get_template("report.md.j2")
        .render(
            study=study,
            r=results,
            energy_note=energy_note(results),
            summary=summary_lines(study, results),
            plain=plain(study, results),
        )
    )
