"""The live plots of a recording's window as one PNG (matplotlib; viser recordings drop GUI
plots): the quantities of :data:`app.web.plots.PLOTS`, one line per robot in its method's
colour, double-support phases shaded grey, x in seconds of the recording (as the scene's
playback bar)."""

from __future__ import annotations

import io
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

from app.live.history import COL
from app.web.overlays import DANGER
from app.web.plots import LOG_PLOTS, PLOTS
from app.web.record_page import robot_title
from pelvic_walk.core.methods import METHOD_INFO
from pelvic_walk.core.metrics import KAPPA_SINGULAR

if TYPE_CHECKING:
    from app.web.record_data import Recording

DSP_GREY = (0.47, 0.47, 0.47, 0.18)  # as the live plots' DSP_FILL


def dsp_spans(t: np.ndarray, in_dsp: np.ndarray) -> list[tuple[float, float]]:
    """(start, end) of each run of double support (in_dsp == 1) in samples at times ``t``."""
    on = np.concatenate([[False], in_dsp == 1.0, [False]])
    edges = np.flatnonzero(np.diff(on.astype(int)))
    return [
        (float(t[a]), float(t[min(b, len(t) - 1)]))
        for a, b in zip(edges[::2], edges[1::2], strict=True)
    ]


# the line styles of a second, third... robot of one strategy (its colour kept)
REPEAT_STYLES: tuple[tuple[object, str], ...] = ((":", "x"), ("-.", "+"), ((0, (1, 1, 6, 1)), "1"))


def robot_styles(strategies: dict[str, str]) -> dict[str, dict[str, object]]:
    """Robot label -> matplotlib keywords: its strategy's style; a second robot of the same
    strategy keeps the colour with other dashes and markers (told apart without colour)."""
    out: dict[str, dict[str, object]] = {}
    seen: dict[str, int] = {}
    for label, name in strategies.items():
        info = METHOD_INFO.get(name)
        style: dict[str, object] = dict(info.mpl_style()) if info else {"color": "#000000"}
        k = seen.get(name, 0)
        seen[name] = k + 1
        if k:
            ls, marker = REPEAT_STYLES[(k - 1) % len(REPEAT_STYLES)]
            style.update(linestyle=ls, marker=marker)
        out[label] = style
    return out


def plots_png(rec: Recording, dpi: int = 100) -> bytes:
    """Five stacked plots over the recording's window (Figure, not pyplot: thread-safe)."""
    fig = Figure(figsize=(10, 11), dpi=dpi, layout="constrained")
    axes = fig.subplots(len(PLOTS), 1, sharex=True)
    ref = rec.methods[0] if rec.methods else None
    styles = robot_styles(rec.strategies)
    for ax, (col, title, span) in zip(axes, PLOTS, strict=True):
        for method in rec.methods:
            rows = rec.rows.get(method)
            if rows is None or not len(rows):
                continue
            x = rows[:, COL["clock"]] - rec.start
            # its colour, line style and marker (as the live plots: not colour alone)
            ax.plot(
                x,
                rows[:, COL[col]],
                lw=1.6,
                markersize=4,
                markevery=max(1, len(x) // 10),
                label=robot_title(method, rec.strategies[method]),
                **styles[method],
            )
        rows = rec.rows.get(ref) if ref else None
        if rows is not None and len(rows):
            for a, b in dsp_spans(rows[:, COL["clock"]] - rec.start, rows[:, COL["in_dsp"]]):
                ax.axvspan(a, b, color=DSP_GREY, lw=0)
        if col in LOG_PLOTS:  # as the live plot: a straight knee's 1e8 beside a clean 30
            ax.set_yscale("log")
            ax.axhline(
                KAPPA_SINGULAR,
                color=tuple(c / 255 for c in DANGER),
                ls="--",
                lw=1.2,
                label=f"knee nearly straight ({KAPPA_SINGULAR:g})",
            )
            ax.legend(loc="upper right", fontsize=8)
        lo, hi = ax.get_ylim()
        ax.set_ylim(min(lo, span[0]), max(hi, span[1]))
        ax.set_title(title, fontsize=10, loc="left")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=9, ncol=len(rec.methods) or 1)
    axes[-1].set_xlabel("time in the recording [s] (grey: double support)")
    axes[-1].set_xlim(0.0, max(rec.duration, 1e-3))
    fig.suptitle(
        f"pelvic-walk: {rec.source}, session clock {rec.start:.1f} to "
        f"{rec.start + rec.duration:.1f} s",
        fontsize=11,
    )
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()
