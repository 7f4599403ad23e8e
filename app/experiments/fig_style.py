"""The report's figure style (matplotlib, Agg) and the helpers every figure module shares:
one colour and label per method (``controller.params``), titles, saving.

A figure function takes the study, the run results (:data:`runs.Results`) and the analysed
:class:`~app.experiments.results.StudyResults`, writes one PNG and returns its file name, or
None (and no file) when its runs are missing: the report then says so rather than showing an
empty plot.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from pelvic_walk.core.methods import METHOD_INFO  # noqa: E402

DEG = 180.0 / np.pi
DPI = 110
NO_ARMS_GREY = "#b0b0b0"
plt.rcParams.update(
    {
        "font.size": 10,
        "axes.titlesize": 11,
        "axes.labelsize": 10,
        "legend.fontsize": 9,
        "axes.grid": True,
        "grid.alpha": 0.3,
    }
)

__all__ = ["DEG", "DPI", "NO_ARMS_GREY", "finish", "label", "plt", "save", "shade_dsp"]


def label(m: str) -> str:
    """A method's label in figures."""
    return METHOD_INFO[m].label


def save(fig: Any, path: Path) -> str:
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    return path.name


def finish(fig: Any, drawn: bool, path: Path, title: str, **title_kw: Any) -> str | None:
    """Title, lay out and save a figure; None (and no file) when nothing was drawn."""
    if not drawn:
        plt.close(fig)
        return None
    fig.suptitle(title, **title_kw)
    fig.tight_layout()
    return save(fig, path)


def shade_dsp(ax: Any, dsp: float) -> None:
    """Shade the DSP at the start of a step (time from the step's start)."""
    ax.axvspan(0.0, dsp, color="#c8d8c8", alpha=0.5, lw=0)
