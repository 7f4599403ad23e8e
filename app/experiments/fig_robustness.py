"""The robustness section's figure: falls and missed footholds over Table 1's seeded repeats,
the walks that fell under larger random pushes, and the largest sideways push each method
survives in each direction."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.patches import Patch

from app.experiments.definitions import Study
from app.experiments.fig_style import finish, label, plt
from app.experiments.outcomes import Results, case_key
from app.experiments.results import StudyResults
from pelvic_walk.core.methods import method_hex
from pelvic_walk.core.metrics import LANDING_ERROR_CLEAN
from pelvic_walk.core.run_spec import DISTURBANCE


def fig_robustness(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    rob = r.robustness
    if rob is None or not any(rob.cells.values()):
        return None
    has_push = any(rob.pushes.values())
    panels = 1 + bool(rob.falls) + has_push
    fig, axes = plt.subplots(1, panels, figsize=(6.5 * panels, 4.2), squeeze=False)
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
    ax.set_title(f"seeded repeats, pushes N(0, {DISTURBANCE:g} N):\nruns that fell + landed off")
    ax.legend(handles=handles, fontsize=7, loc="upper left")
    k = 1
    if rob.falls:
        ax = axes[0, k]
        k += 1
        sizes = list(rob.falls)
        fx = np.arange(len(sizes))
        for i, m in enumerate(study.methods):
            pos = fx + (i - (n_m - 1) / 2) * width
            for p, size in zip(pos, sizes, strict=True):
                fc = rob.falls[size].get(m)
                if fc is None:
                    continue
                share = 100.0 * fc.fell / fc.runs
                ax.bar(
                    p, share, width, color=method_hex(m), label=label(m) if p == pos[0] else None
                )
                ax.annotate(
                    f"{fc.fell}/{fc.runs}", (p, share), ha="center", va="bottom", fontsize=7
                )
        where = [
            f"{s}: " + (f"{fc.lengths[0]:.2f} m" if len(fc.lengths) == 1 else "all lengths")
            for s, by in rob.falls.items()
            if (fc := next(iter(by.values()), None))
        ]
        ax.set_xticks(fx, [f"N(0, {s})" for s in sizes])
        ax.set_ylabel("walks that fell [%]")
        ax.set_ylim(0, 105)
        ax.set_title("seeded walks that fell, by push size\n(" + "; ".join(where) + ")")
        ax.legend(fontsize=8, loc="upper left")
    if has_push:
        ax = axes[0, k]
        plengths = rob.push_lengths
        dirs = rob.directions
        groups = [(x, d) for x in plengths for d in dirs]
        px = np.arange(len(groups))
        for i, m in enumerate(study.methods):
            pos = px + (i - (n_m - 1) / 2) * width
            for p, (x, d) in zip(pos, groups, strict=True):
                pc = rob.push(m, x, d)
                if pc is None or pc.survived is None:
                    continue
                ax.bar(
                    p,
                    pc.survived,
                    width,
                    color=method_hex(m),
                    hatch="//" if d != dirs[0] else None,
                    edgecolor="k",
                    label=label(m) if (x, d) == groups[0] else None,
                )
                if pc.failed is not None:
                    ax.plot([p, p], [pc.survived, pc.failed], color="k", lw=2)
        setup = rob.push_setup
        what = f"{setup.duration:.1f} s, bracket {setup.resolution:g} N" if setup else ""
        ax.set_xticks(px, [f"{x:.2f}\n{d}" for x, d in groups], fontsize=8)
        ax.set_xlabel("step length [m], direction")
        ax.set_ylabel("largest push survived [N]")
        ax.set_title(
            f"push on the torso at mid single support ({what});\n"
            "line: up to the first push that topples it"
        )
        top = max((pc.failed or pc.survived or 0.0) for pc in rob.pushes.values() if pc)
        ax.set_ylim(0, 1.3 * top)
        ax.legend(fontsize=7, loc="upper center", ncol=3)
    return finish(
        fig, True, path, "Robustness: random pushes, larger random pushes, one push", y=1.02
    )
