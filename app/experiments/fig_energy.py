"""Section 5's figures: energy per two-step window against Table 1, and per joint group."""

from __future__ import annotations

from pathlib import Path
from typing import cast

import numpy as np

from app.experiments import paper
from app.experiments.definitions import Study
from app.experiments.energy import JOINT_GROUPS, joint_groups
from app.experiments.fig_style import finish, label, plt
from app.experiments.outcomes import Results, length_key
from app.experiments.results import StudyResults
from pelvic_walk.core.methods import method_hex


def fig_energy(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    e = r.energy
    fig, (ax_o, ax_p) = plt.subplots(1, 2, figsize=(11, 4.2))
    off = {m: 0.004 * (i - (len(study.methods) - 1) / 2) for i, m in enumerate(study.methods)}
    drawn = False
    for m in study.methods:
        found = [(x, e.cell(m, x)) for x in e.lengths]
        cells = [(x + off[m], c) for x, c in found if c]
        if cells:
            drawn = True
            xs = [x for x, _ in cells]
            mean = [c.mean for _, c in cells]
            ax_o.errorbar(
                xs,
                mean,
                yerr=[c.std for _, c in cells],
                color=method_hex(m),
                marker="o",
                capsize=3,
                lw=1.8,
                label=label(m),
            )
            bad = [i for i, (_, c) in enumerate(cells) if c.n_clean < c.n_runs]
            ax_o.plot(
                [xs[i] for i in bad],
                [mean[i] for i in bad],
                ls="none",
                marker="o",
                ms=9,
                mfc="white",
                mec=method_hex(m),
                mew=2,
                label=f"{m}: runs not all clean" if bad else None,
            )
        px = paper.table1_lengths(m)
        ax_p.errorbar(
            [x + off[m] for x in px],
            [cast(paper.MeanStd, paper.TABLE1[m][x]).mean for x in px],  # px: no dashes
            yerr=[cast(paper.MeanStd, paper.TABLE1[m][x]).std for x in px],
            color=method_hex(m),
            marker="s",
            capsize=3,
            lw=1.8,
            ls="--",
            label=label(m),
        )
    ax_o.set_title(
        f"ours: {e.repeats} runs x {e.steps} steps per point "
        "(runs that did not fall)\nopen marker: not every run clean"
    )
    ax_p.set_title(f"paper, Table 1 ({paper.TABLE1_RUNS} runs x {paper.TABLE1_STEPS} steps)")
    for ax in (ax_o, ax_p):
        ax.set_xlabel("step length [m]")
        ax.set_ylabel("energy per two steps, eq. (44) [J]")
        ax.legend(loc="upper left")
    return finish(fig, drawn, path, "Energy per two-step window: mean +/- std (paper Table 1)")


def fig_energy_joints(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    """Mean two-step window (200 Hz) per joint group, stacked, per method and length."""
    e = r.energy
    fig, axes = plt.subplots(1, len(study.methods), figsize=(12, 4.2), sharey=True)
    colors = plt.get_cmap("tab10")(np.arange(len(JOINT_GROUPS)))
    drawn = False
    for ax, m in zip(np.atleast_1d(axes), study.methods, strict=True):
        xs, stacks = [], []
        for x in e.lengths:
            c = e.table[m].get(length_key(x))
            if c and c.per_joint_mean:
                xs.append(x)
                stacks.append(list(joint_groups(c.per_joint_mean, e.joints).values()))
        if not xs:
            ax.set_title(f"{label(m)}: no run")
            continue
        drawn = True
        data = np.array(stacks)  # (lengths, groups)
        bottom = np.zeros(len(xs))
        labels = [f"{x:.2f}" for x in xs]
        for g, (name, col) in enumerate(zip(JOINT_GROUPS, colors, strict=True)):
            ax.bar(labels, data[:, g], bottom=bottom, color=col, label=name)
            bottom += data[:, g]
        ax.set_title(label(m))
        ax.set_xlabel("step length [m]")
    np.atleast_1d(axes)[0].set_ylabel("energy per two steps, 200 Hz [J]")
    np.atleast_1d(axes)[-1].legend(loc="upper left", fontsize=8)
    return finish(fig, drawn, path, "Where the energy goes: eq. (44) per joint group (both legs)")
