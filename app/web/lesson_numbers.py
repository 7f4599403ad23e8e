"""The numbers the Learn tab quotes, read from the reference report: the committed output of
``pelvic-walk experiments`` packaged as ``app.reference_report`` (its ``results.json``).

Our measured figures (the longest clean steps, the MPC's waist amplitude and kappa at a length)
are the study's, and the paper's numbers are those the study typed once
(``app/experiments/paper.py``, written into ``results.json`` under ``paper``): a lesson never
types a number the study measures or copies, and regenerating the reference report updates
the lessons. The web tool cannot import the study (``docs/ARCHITECTURE.md``), so it reads the
file.
"""

from __future__ import annotations

import json
from functools import cache
from typing import Any

from pelvic_walk.core.report_dir import reference_report_dir


@cache
def reference() -> dict[str, Any]:
    """The reference report's ``results.json`` (read once)."""
    return json.loads((reference_report_dir() / "results.json").read_text())


def clean_limits() -> dict[str, float]:
    """Each method's longest clean step on our model [m] (the report's section 2)."""
    return {m: float(d["longest_clean"]) for m, d in reference()["max_step"].items()}


def paper() -> dict[str, Any]:
    """The paper's numbers as the study typed them (``app/experiments/paper.py``)."""
    return reference()["paper"]


def paper_limits() -> dict[str, float]:
    """The paper's longest step per method [m] (Sec. VI-B)."""
    return {m: float(x) for m, x in paper()["max_step"].items()}


def mpc_waist_deg(step_length: float) -> float:
    """The MPC's peak |waist angle| over a mid-walk step at ``step_length`` [deg] (section 3)."""
    return float(reference()["waist"]["cases"][f"mpc@{step_length:.2f}"]["peak_abs_angle_deg"])


def kappa_legs_at_landing(method: str, step_length: float) -> float:
    """A method's median kappa(legs) at landing at ``step_length`` (section 6)."""
    case = reference()["kappa"]["cases"][f"{method}@{step_length:.2f}"]
    return float(case["kappa_legs_landing_median"])
