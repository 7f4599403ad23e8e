"""The markdown report: ``templates/report.md.j2`` and one template per section, rendered from
the typed :class:`StudyResults` (numbers) and :mod:`app.experiments.paper` (the paper's).

Each section's text is in its template (``templates/<n>_<name>.md.j2``); numbers are
formatted by the small filters below. Every table cell the report writes goes through
:func:`escape_cell` (via :func:`row` and :func:`header`), so a ``|`` in a cell cannot split
its row.
"""

from __future__ import annotations

from typing import Any

import jinja2

from app.experiments import paper
from app.experiments.definitions import ROTATING, SEED_PERTURBATION, Study
from app.experiments.results import StudyResults, case_key, length_key
from app.experiments.verdicts import FAILS, HOLDS, NOT_MEASURED, PARTLY
from app.sim.metrics import KAPPA_SINGULAR, LANDING_ERROR_CLEAN
from controller.params import METHOD_INFO

VERDICT_MARK = {
    HOLDS: "**holds**",
    PARTLY: "**partly**",
    FAILS: "**does not hold**",
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
    """kappa(J) for a table: singular values (>= 1e6) in words, large ones in powers of ten."""
    if v is None:
        return DASH
    if v >= 1e6:
        return f"singular ({v:.0e})"
    return f"{v:.1f}" if v < 1e3 else f"{v:.2g}"


def lengths(xs: Any, spec: str = ".2f", sep: str = ", ") -> str:
    """Step lengths joined, e.g. ``0.30, 0.40``."""
    return sep.join(format(x, spec) for x in xs)


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
    env.filters.update(f=fmt, percent=percent, kappa=kappa, lengths=lengths, mark=VERDICT_MARK.get)
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
    )
    return env


def render(study: Study, results: StudyResults) -> str:
    """The whole report as markdown."""
    return _environment().get_template("report.md.j2").render(study=study, r=results)
