"""The robustness section's figure: falls and missed footholds over Table 1's seeded repeats,
and the largest sideways push each method survives."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.patches import Patch

from app.experiments.definitions import Study
from app.experiments.fig_style import finish, label, plt
from app.experiments.results import StudyResults
from app.experiments.runs import Results, case_key
from app.methods import method_hex
from app.sim.metrics import LANDING_ERROR_CLEAN


def fig_robustness(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    rob = r.robustness
    if rob is None or not any(rob.cells.values()):
        return None
    has_push = any(rob.pushes.values())
    fig, axes = plt.subplots(
        1, 2 if has_push else 1, figsize=(13 if has_push else 8, 4.2), squeeze=False
    )
    ax = axes[0, 0]
    n_m = len(study.methods)
    width = 0.8 / n_m
    xs = np.arange(len(rob.lengths))
    for i, m in enumerate(study.methods):
        pos = xs + (i - (n_m - 1) / 2) * width
        cells = [rob.cells.get(case_key(m, x)) for x in rob.lengths]
        fell = np.array([c.fell if c else 0 for c in cells])
        off = np.array([c.off_foothold if c else 0 for c in cells])
        ax.bar(pos, fell, width, color=method_hex(m), edgecolor="k", label=label(m))
        ax.bar(
            pos, off, width, bottom=fell, color=method_hex(m), alpha=0.35, edgecolor="k", hatch="//"
        )
        for p, f, o, c in zip(pos, fell, off, cells, strict=True):
            if c is not None:
                ax.annotate(f"{f}+{o}", (p, f + o), ha="center", va="bottom", fontsize=7)
    handles, _ = ax.get_legend_handles_labels()
    handles += [
        Patch(facecolor="white", edgecolor="k", label="solid: fell"),
        Patch(
            facecolor="white",
            edgecolor="k",
            hatch="//",
            label=f"hatched: > {LANDING_ERROR_CLEAN * 100:.0f} cm off",
        ),
    ]
    ax.set_xticks(xs, [f"{x:.2f}" for x in rob.lengths])
    ax.set_xlabel("step length [m]")
    ax.set_ylabel(f"runs of {rob.repeats} ({rob.steps} steps each)")
    ax.set_ylim(0, rob.repeats + 0.5)
    ax.set_title("seeded repeats: runs that fell + that landed a foot off")
    ax.legend(handles=handles, fontsize=7, loc="upper left")
    if has_push:
        ax = axes[0, 1]
        plengths = sorted({c.step_length for c in rob.pushes.values() if c})
        px = np.arange(len(plengths))
        for i, m in enumerate(study.methods):
            pos = px + (i - (n_m - 1) / 2) * width
            for p, x in zip(pos, plengths, strict=True):
                pc = rob.pushes.get(case_key(m, x))
                if pc is None or pc.survived is None:
                    continue
                ax.bar(
                    p,
                    pc.survived,
                    width,
                    color=method_hex(m),
                    label=label(m) if x == plengths[0] else None,
                )
                if pc.failed is not None:
                    ax.plot([p, p], [pc.survived, pc.failed], color="k", lw=2)
        setup = rob.push_setup
        what = f"{setup.direction}, {setup.duration:.1f} s" if setup else ""
        ax.set_xticks(px, [f"{x:.2f}" for x in plengths])
        ax.set_xlabel("step length [m]")
        ax.set_ylabel("largest push survived [N]")
        ax.set_title(
            f"push on the torso at mid single support ({what});\n"
            "line: up to the first push that topples it"
        )
        ax.legend(fontsize=8, loc="upper right")
    return finish(
        fig, True, path, "Robustness: the study's small disturbance, and one push", y=1.02
    )
