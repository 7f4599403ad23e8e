"""Figures of the sections added for a fair reading (issue 13): the energy per joint group and
the sensitivity of the longest step. Same conventions as :mod:`app.experiments.figures`
(whose :func:`~app.experiments.figures.make_all` draws these too)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from app.experiments.definitions import Study
from app.experiments.figures import _finish, _label, plt
from app.experiments.report import JOINT_GROUPS, joint_groups
from app.experiments.results import Results, StudyResults, length_key
from controller.params import method_hex


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
            ax.set_title(f"{_label(m)}: no run")
            continue
        drawn = True
        data = np.array(stacks)  # (lengths, groups)
        bottom = np.zeros(len(xs))
        labels = [f"{x:.2f}" for x in xs]
        for g, (name, col) in enumerate(zip(JOINT_GROUPS, colors, strict=True)):
            ax.bar(labels, data[:, g], bottom=bottom, color=col, label=name)
            bottom += data[:, g]
        ax.set_title(_label(m))
        ax.set_xlabel("step length [m]")
    np.atleast_1d(axes)[0].set_ylabel("energy per two steps, 200 Hz [J]")
    np.atleast_1d(axes)[-1].legend(loc="upper left", fontsize=8)
    return _finish(fig, drawn, path, "Where the energy goes: eq. (44) per joint group (both legs)")


def fig_sensitivity(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    """Longest clean (filled) and walking (open) step per sensitivity cell, fixed vs MPC."""
    s = r.sensitivity
    if s is None or not s.rows:
        return None
    cells: list[tuple[str, object]] = []
    for row in s.rows:
        if (row.parameter, row.value) not in cells:
            cells.append((row.parameter, row.value))
    fig, ax = plt.subplots(figsize=(11, 4.4))
    methods = [m for m in study.methods if any(row.method == m for row in s.rows)]
    width = 0.8 / max(len(methods), 1)
    drawn = False
    for i, m in enumerate(methods):
        for j, (name, value) in enumerate(cells):
            pos = j + (i - (len(methods) - 1) / 2) * width
            clean = s.limit(name, value, m, "clean_limit")
            walks = s.limit(name, value, m, "walks_limit")
            if clean is not None:
                ax.bar(pos, clean, width, color=method_hex(m), label=_label(m) if j == 0 else None)
                drawn = True
            if walks is not None:
                ax.plot(pos, walks, marker="_", ms=14, mew=2.5, color="k")
                drawn = True
    ax.plot([], [], marker="_", ls="none", ms=14, mew=2.5, color="k", label="longest that walks")
    ax.set_xticks(range(len(cells)))
    ax.set_xticklabels(
        [f"{n.split('.')[-1]}={v}" if n else "defaults" for n, v in cells], rotation=20
    )
    ax.set_ylabel("longest clean step [m]")
    ax.set_ylim(0.0, max(s.search[1], 0.1))
    ax.legend(loc="upper right")
    return _finish(
        fig, drawn, path, f"Sensitivity: longest clean step (bars), {s.n_steps}-step walks"
    )
