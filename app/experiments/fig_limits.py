"""Section 2's figure: every run of the step-length sweep per method, the paper's limit and
ours."""

from __future__ import annotations

from pathlib import Path

from app.experiments import paper
from app.experiments.definitions import Study
from app.experiments.fig_style import label, plt, save
from app.experiments.outcomes import Results
from app.experiments.results import StudyResults
from pelvic_walk.core.methods import method_hex


def fig_max_step(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    fig, ax = plt.subplots(figsize=(9.5, 3.6))
    for row, m in enumerate(study.methods):
        pts = r.max_step[m].points
        y = len(study.methods) - 1 - row
        for kind, marker, color, words in (
            ("clean", "o", "#2a9d3a", "clean"),
            ("unclean", "^", "#e0a000", "walked, not clean"),
            ("fell", "x", "#c0392b", "fell"),
        ):
            xs = [
                p.step_length
                for p in pts
                if (
                    p.clean
                    if kind == "clean"
                    else (p.fell if kind == "fell" else not p.clean and not p.fell)
                )
            ]
            ax.scatter(
                xs,
                [y] * len(xs),
                marker=marker,
                color=color,
                s=45,
                zorder=3,
                label=words if row == 0 else None,
            )
        theirs = paper.MAX_STEP[m]
        ax.plot(
            [theirs, theirs],
            [y - 0.4, y - 0.08],
            ls="--",
            color="k",
            lw=1.5,
            label="paper's limit (below the dots)" if row == 0 else None,
        )
        ours = r.max_step[m].longest_clean
        if ours is not None:
            ax.plot(
                [ours, ours],
                [y + 0.08, y + 0.4],
                color=method_hex(m),
                lw=3,
                label="our longest clean step (above)" if row == 0 else None,
            )
            ax.annotate(
                f"{ours:.2f} m",
                (ours + 0.004, y + 0.22),
                ha="left",
                va="center",
                fontsize=9,
                color=method_hex(m),
            )
    ax.set_yticks(range(len(study.methods)))
    ax.set_yticklabels([label(m) for m in reversed(study.methods)])
    ax.set_ylim(-0.6, len(study.methods) - 0.4)
    ax.set_xlabel("step length [m]")
    ax.set_title(f"Longest clean step ({study.n_steps} steps of 1.2 s, arm swing on)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=5, frameon=False)
    return save(fig, path)
