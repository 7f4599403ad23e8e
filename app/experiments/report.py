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
import numpy as np

from app.experiments import paper
from app.experiments.definitions import (
    DISTURBANCE,
    DISTURBANCE_PERIOD,
    ROTATING,
    SEED_PERTURBATION,
    Study,
)
from app.experiments.results import StudyResults, case_key, length_key
from app.experiments.sections import SIGNIFICANCE
from app.experiments.verdicts import FAILS, HOLDS, NOT_MEASURED, PARTLY
from app.sim.metrics import KAPPA_SINGULAR, LANDING_ERROR_CLEAN
from controller.params import METHOD_INFO, ControllerParams

_P = ControllerParams()
# joints grouped for the energy breakdown: group -> name fragments of models.dyros_jet.JOINTS
JOINT_GROUPS = {
    "hip yaw": ("hip_yaw",),
    "hip roll": ("hip_roll",),
    "hip pitch": ("hip_pitch",),
    "knee": ("knee",),
    "ankle pitch": ("ankle_pitch",),
    "ankle roll": ("ankle_roll",),
    "waist": ("waist",),
    "arms": ("shoulder", "elbow"),
}


def joint_groups(per_joint: list[float], joints: list[str]) -> dict[str, float]:
    """Per-joint figures summed into :data:`JOINT_GROUPS` (both legs together)."""
    return {
        g: sum(v for v, j in zip(per_joint, joints, strict=True) if any(f in j for f in frags))
        for g, frags in JOINT_GROUPS.items()
    }


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
        f=fmt, percent=percent, kappa=kappa, lengths=lengths, mark=VERDICT_MARK.get, stdev=stdev
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
        zmp_margin=_P.com.zmp_margin,
        lateral_floor=_P.pelvis.lateral_floor,
        step_width=_P.walk.step_width,
        joint_groups=joint_groups,
    )
    return env


def render(study: Study, results: StudyResults) -> str:
    """The whole report as markdown."""
    return (
        _environment()
        .get_template("report.md.j2")
        .render(study=study, r=results, energy_note=energy_note(results))
    )
