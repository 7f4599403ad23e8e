"""Every figure of the report: :data:`FIGURES` (name -> function, one module per topic) and
:func:`make_all`. The style and shared helpers are in :mod:`app.experiments.fig_style`."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from app.experiments.definitions import Study
from app.experiments.fig_balance import fig_zmp
from app.experiments.fig_energy import fig_energy, fig_energy_joints
from app.experiments.fig_kappa import fig_kappa, fig_kappa_limit
from app.experiments.fig_limits import fig_max_step
from app.experiments.fig_robustness import fig_robustness
from app.experiments.fig_sensitivity import fig_sensitivity, fig_thresholds
from app.experiments.fig_waist import fig_waist
from app.experiments.fig_yaw import fig_yaw_momentum
from app.experiments.outcomes import Results
from app.experiments.results import StudyResults

Figure = Callable[[Study, Results, StudyResults, Path], str | None]
FIGURES: dict[str, Figure] = {
    "max_step": fig_max_step,
    "waist": fig_waist,
    "yaw_momentum": fig_yaw_momentum,
    "energy": fig_energy,
    "energy_joints": fig_energy_joints,
    "robustness": fig_robustness,
    "kappa": fig_kappa,
    "kappa_limit": fig_kappa_limit,
    "zmp": fig_zmp,
    "sensitivity": fig_sensitivity,
    "thresholds": fig_thresholds,
}


def make_all(study: Study, results: Results, r: StudyResults, folder: Path) -> dict[str, str]:
    """Write every figure into ``folder``; returns name -> file name (drawn figures only)."""
    folder.mkdir(parents=True, exist_ok=True)
    out = {}
    for name, fn in FIGURES.items():
        file = fn(study, results, r, folder / f"{name}.png")
        if file:
            out[name] = file
    return out
