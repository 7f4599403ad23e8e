"""Section 8's figures: over the k_pel x DSP-share grid, the MPC - fixed gain in the longest
clean step and the MPC's waist amplitude (heatmaps), and the gain at other clean thresholds."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from app.experiments import paper
from app.experiments.definitions import Study
from app.experiments.fig_style import finish, plt
from app.experiments.outcomes import Results
from app.experiments.results import StudyResults
from app.experiments.sensitivity import SensitivitySection
from controller.strategy import FIXED, MPC

PAPER_GAIN = paper.MAX_STEP[MPC] - paper.MAX_STEP[FIXED]  # [m]


def _grid(s: SensitivitySection, value: Any) -> np.ndarray:
    """(rows, columns) of ``value(overrides)`` over the grid (NaN where None)."""
    (_, rv), (_, cv) = s.rows_axis, s.columns_axis
    z = np.full((len(rv), len(cv)), np.nan)
    for i, r in enumerate(rv):
        for j, c in enumerate(cv):
            v = value([[s.rows_axis[0], r], [s.columns_axis[0], c]])
            z[i, j] = np.nan if v is None else v
    return z


def _axes(ax: Any, s: SensitivitySection, ylabel: bool = True) -> None:
    (rn, rv), (cn, cv) = s.rows_axis, s.columns_axis
    ax.set_xticks(range(len(cv)), [f"{v:g}" for v in cv])
    ax.set_yticks(range(len(rv)), [f"{v:g}" for v in rv])
    ax.set_xlabel(cn)
    if ylabel:
        ax.set_ylabel(rn)
    ax.grid(False)


def _heat(ax: Any, z: np.ndarray, text: list[list[str]], cmap: str, lo: float, hi: float) -> Any:
    cm = plt.get_cmap(cmap).with_extremes(bad="#d9d9d9")
    im = ax.imshow(np.ma.masked_invalid(z), origin="lower", cmap=cm, vmin=lo, vmax=hi)
    for i in range(z.shape[0]):
        for j in range(z.shape[1]):
            ax.text(j, i, text[i][j], ha="center", va="center", fontsize=8)
    return im


def fig_sensitivity(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    """The MPC - fixed gain in the longest clean step, and the MPC's waist amplitude at the
    search's first length, over the grid."""
    s = r.sensitivity
    if s is None or not s.rows:
        return None
    gain = _grid(s, s.gain)
    mpc = _grid(s, lambda ov: s.limit(MPC, ov))
    fixed = _grid(s, lambda ov: s.limit(FIXED, ov))
    waist = _grid(s, lambda ov: (row := s.row(MPC, ov)) and row.waist_at_first_deg)
    fig, (ax_g, ax_w) = plt.subplots(1, 2, figsize=(12.5, 4.6))
    span = max(PAPER_GAIN * 1.5, float(np.nanmax(np.abs(gain))) if np.isfinite(gain).any() else 0)
    text = [
        [
            "-"
            if math.isnan(gain[i, j])
            else f"{gain[i, j]:+.2f}\n{mpc[i, j]:.2f} / {fixed[i, j]:.2f}"
            + (" *" if gain[i, j] >= PAPER_GAIN - 1e-9 else "")
            for j in range(gain.shape[1])
        ]
        for i in range(gain.shape[0])
    ]
    im = _heat(ax_g, gain, text, "RdBu", -span, span)
    _axes(ax_g, s)
    fig.colorbar(im, ax=ax_g, label="MPC - fixed, longest clean step [m]")
    ax_g.set_title(
        f"gain in the longest clean step (MPC / fixed [m]);\n* = at least the paper's "
        f"+{PAPER_GAIN:.2f} m"
    )
    wtext = [["-" if math.isnan(v) else f"{v:.0f}" for v in row_] for row_ in waist.tolist()]
    finite = waist[np.isfinite(waist)]
    hi = max(float(finite.max()) if len(finite) else 1.0, paper.WAIST_PEAK_DEG)
    im = _heat(ax_w, waist, wtext, "viridis", 0.0, hi)
    _axes(ax_w, s)
    fig.colorbar(im, ax=ax_w, label="peak |waist angle| [deg]")
    ax_w.set_title(
        f"MPC's waist amplitude at {s.first:.2f} m\n(paper: {paper.WAIST_PEAK_DEG:.0f} deg at "
        f"{paper.WAIST_PEAK_LENGTH:.2f} m)"
    )
    return finish(
        fig, True, path, f"Where the paper's +{PAPER_GAIN:.2f} m appears ({s.n_steps}-step walks)"
    )


def fig_thresholds(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    """The MPC - fixed gain over the grid at each clean threshold (one panel each)."""
    s = r.sensitivity
    if s is None or not s.rows:
        return None
    names = s.clean_criteria
    n = len(names)
    cols = min(n, 4)
    rows_ = math.ceil(n / cols)
    fig, axes = plt.subplots(
        rows_, cols, figsize=(3.4 * cols + 1.0, 3.3 * rows_), squeeze=False, layout="constrained"
    )
    gains = {c: _grid(s, lambda ov, c=c: s.gain(ov, c)) for c in names}
    finite = np.concatenate([g[np.isfinite(g)] for g in gains.values()] or [np.zeros(1)])
    span = max(PAPER_GAIN * 1.5, float(np.max(np.abs(finite))) if len(finite) else 0.0)
    im = None
    for k, c in enumerate(names):
        ax = axes[k // cols, k % cols]
        g = gains[c]
        text = [["-" if math.isnan(v) else f"{v:+.2f}" for v in row_] for row_ in g.tolist()]
        im = _heat(ax, g, text, "RdBu", -span, span)
        _axes(ax, s, ylabel=k % cols == 0)
        ax.set_title(_criterion_words(c), fontsize=9)
    for k in range(n, rows_ * cols):
        axes[k // cols, k % cols].axis("off")
    if im is not None:
        fig.colorbar(im, ax=axes, label="MPC - fixed, longest clean step [m]", shrink=0.8)
    fig.suptitle("The gain at other clean thresholds (same runs)")
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path.name


def _criterion_words(c: str) -> str:
    from pelvic_walk.core.measure import threshold_of

    landing, kappa = threshold_of(c)
    return f"clean: landing < {landing * 100:g} cm,\nkappa(legs) < {kappa:g}"
