"""The study's figures (matplotlib, Agg): one function per figure, one colour per method.

Each ``fig_*`` takes the study, the run results (:data:`results.Results`) and the analysed
:class:`StudyResults` and writes one PNG; :func:`make_all` writes them all and returns the file
names. A figure whose runs are missing is skipped (and the report says so) rather than drawn
empty. Method labels and colours are ``controller.params``'s, the paper's numbers
:mod:`app.experiments.paper`'s.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, cast

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

from app.experiments import paper  # noqa: E402
from app.experiments.definitions import ROTATING, Study  # noqa: E402
from app.experiments.results import Results, StudyResults, array, case_key  # noqa: E402
from app.experiments.sections import step_of, walk_of, zmp_of  # noqa: E402
from app.sim.metrics import KAPPA_SINGULAR  # noqa: E402
from controller.kinematics import KAPPA_CAP  # noqa: E402
from controller.params import METHOD_INFO, method_hex  # noqa: E402
from models.dyros_jet import FOOT_SIZE  # noqa: E402

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


def _label(m: str) -> str:
    return METHOD_INFO[m].label


def _save(fig: Any, path: Path) -> str:
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    return path.name


def _finish(fig: Any, drawn: bool, path: Path, title: str, **title_kw: Any) -> str | None:
    """Title, lay out and save a figure; None (and no file) when nothing was drawn."""
    if not drawn:
        plt.close(fig)
        return None
    fig.suptitle(title, **title_kw)
    fig.tight_layout()
    return _save(fig, path)


def _shade_dsp(ax: Any, dsp: float) -> None:
    ax.axvspan(0.0, dsp, color="#c8d8c8", alpha=0.5, lw=0)


# -- section 2 --------------------------------------------------------------------------------
def fig_max_step(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    fig, ax = plt.subplots(figsize=(9.5, 3.6))
    for row, m in enumerate(study.methods):
        pts = r.max_step[m].points
        y = len(study.methods) - 1 - row
        for kind, marker, color, label in (
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
                label=label if row == 0 else None,
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
    ax.set_yticklabels([_label(m) for m in reversed(study.methods)])
    ax.set_ylim(-0.6, len(study.methods) - 0.4)
    ax.set_xlabel("step length [m]")
    ax.set_title(f"Longest clean step ({study.n_steps} steps of 1.2 s, arm swing on)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=5, frameon=False)
    return _save(fig, path)


# -- section 3 --------------------------------------------------------------------------------
def fig_waist(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    lengths = study.figure_lengths
    fig, axes = plt.subplots(2, len(lengths), figsize=(5.2 * len(lengths), 6.4), squeeze=False)
    drawn = False
    for j, x in enumerate(lengths):
        ax_a, ax_r = axes[0, j], axes[1, j]
        dsp = None
        for m in ROTATING:
            ex = step_of(results, study.figure_run(m, x))
            if not ex or not ex.t:
                continue
            drawn = True
            t = array(ex.t)
            dsp = ex.dsp
            style = dict(color=method_hex(m), lw=2, label=_label(m))
            ax_a.plot(t, array(ex.waist_angle_cmd) * DEG, **style)
            ax_r.plot(t, array(ex.waist_rate) * DEG, **style)
            if m == "mpc":
                t_ref = t + ex.theta_ref_lead
                keep = t_ref <= ex.duration + 1e-9
                ax_a.plot(
                    t_ref[keep],
                    array(ex.theta_ref)[keep] * DEG,
                    color="k",
                    lw=1.2,
                    ls=":",
                    zorder=5,
                    label="MPC's reference angle (eq. 33)",
                )
        for ax in (ax_a, ax_r):
            if dsp is not None:
                _shade_dsp(ax, dsp)
                ax.axvline(dsp, color="#3a7a3a", lw=1)
            ax.set_xlabel(f"time in step {study.mid_step + 1} [s]  (shaded: DSP, then swing)")
        if abs(x - paper.WAIST_PEAK_LENGTH) < 1e-9:
            for sgn in (-1, 1):
                ax_a.axhline(
                    sgn * paper.WAIST_PEAK_DEG,
                    color="k",
                    ls="--",
                    lw=1,
                    label=f"paper: +/-{paper.WAIST_PEAK_DEG:.0f} deg" if sgn > 0 else None,
                )
        ax_a.set_title(f"waist yaw angle, step {x:.2f} m")
        ax_r.set_title(f"waist yaw rate, step {x:.2f} m")
        ax_a.set_ylabel("commanded waist yaw [deg]")
        ax_r.set_ylabel("waist yaw rate [deg/s]")
        ax_a.legend(loc="best")
    return _finish(fig, drawn, path, "Waist yaw over one mid-walk step (paper Fig. 8-9)")


# -- section 4 --------------------------------------------------------------------------------
def _yaw_note(r: StudyResults, m: str, x: float) -> str:
    case = r.yaw_momentum.cases.get(case_key(m, x))
    if not case:
        return ""
    note = ""
    if case.peak_reduction_percent is not None:
        note = f"peak -{case.peak_reduction_percent:.0f} %"
    if case.arms.fell or case.no_arms.fell:
        note += " (fell)"
    elif not (case.arms.clean and case.no_arms.clean):
        note += " (not clean)"
    return note


def fig_yaw_momentum(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    lengths, methods = study.figure_lengths, study.methods
    fig, axes = plt.subplots(
        len(lengths),
        len(methods),
        figsize=(4.6 * len(methods), 3.2 * len(lengths)),
        squeeze=False,
        sharey="row",
    )
    drawn = False
    k0, k1 = max(study.mid_step - 2, 0), study.mid_step + 2  # steps shown: k0 .. k1 - 1
    for i, x in enumerate(lengths):
        for j, m in enumerate(methods):
            ax = axes[i, j]
            starts = None
            for arms, lw in ((False, 1.2), (True, 2.0)):
                ex = walk_of(results, study.figure_run(m, x, arms))
                if not ex:
                    continue
                drawn = True
                t, h = array(ex.t), array(ex.yaw_momentum)
                starts = array(ex.step_start)
                sel = (t >= starts[k0]) & (t <= starts[min(k1, len(starts) - 1)])
                ax.plot(
                    t[sel] - starts[k0],
                    h[sel],
                    lw=lw,
                    color=method_hex(m) if arms else NO_ARMS_GREY,
                    label="with arm swing" if arms else "without arm swing",
                )
            if starts is not None:
                for k in range(k0, min(k1, len(starts) - 1) + 1):
                    ax.axvline(starts[k] - starts[k0], color="k", lw=0.6, alpha=0.5)
                    ax.annotate(
                        f"T{k + 1}",
                        (starts[k] - starts[k0], 1.0),
                        xycoords=("data", "axes fraction"),
                        ha="center",
                        va="bottom",
                        fontsize=8,
                    )
            ax.set_title(f"{_label(m)}, {x:.2f} m\n{_yaw_note(r, m, x)}", pad=14)
            ax.set_xlabel("time from the start of the step shown first [s]")
            if j == 0:
                ax.set_ylabel("yaw momentum about CoM [kg m^2/s]")
            ax.legend(loc="lower left", fontsize=8)
    return _finish(
        fig,
        drawn,
        path,
        "Measured yaw angular momentum with and without arm swing (paper Fig. 12); "
        "T_k: start of step k",
        y=1.01,
    )


# -- section 5 --------------------------------------------------------------------------------
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
                label=_label(m),
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
            label=_label(m),
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
    return _finish(fig, drawn, path, "Energy per two-step window: mean +/- std (paper Table 1)")


# -- section 6 --------------------------------------------------------------------------------
def _limit_tag(r: StudyResults, x: float) -> str:
    """Where ``x`` stands against the fixed pelvis's own limit."""
    lc, ff = r.max_step["fixed"].longest_clean, r.max_step["fixed"].first_failed
    if lc is not None and abs(x - lc) < 1e-9:
        return " (fixed: longest clean)"
    if ff is not None and abs(x - ff) < 1e-9:
        return " (fixed: first failure)"
    if ff is not None and x > ff:
        return " (fixed: past its limit)"
    return ""


def _kappa_panels(
    study: Study,
    results: Results,
    r: StudyResults,
    lengths: list[float],
    title: str,
    path: Path,
    near: bool,
) -> str | None:
    if not lengths:
        return None
    fig, axes = plt.subplots(
        1, len(lengths), figsize=(4.4 * len(lengths), 3.8), squeeze=False, sharey=True
    )
    drawn = False
    for j, x in enumerate(lengths):
        ax = axes[0, j]
        dsp = dur = None
        for m in study.methods:
            ex = step_of(results, study.figure_run(m, x))
            if not ex or not ex.t:
                continue
            drawn = True
            dsp, dur = ex.dsp, ex.duration
            ax.semilogy(array(ex.t), array(ex.kappa), color=method_hex(m), lw=1.8, label=_label(m))
        if dsp is not None:
            _shade_dsp(ax, dsp)
            ax.axvline(dur, color="k", lw=0.8, ls=":")
            ax.axhline(
                KAPPA_SINGULAR,
                color="#c0392b",
                lw=0.8,
                ls="--",
                label="bound of a clean run" if j == 0 else None,
            )
            ax.annotate(
                "landing", (dur, 0.02), xycoords=("data", "axes fraction"), ha="right", fontsize=8
            )
        ax.set_title(f"step {x:.2f} m{_limit_tag(r, x) if near else ''}")
        ax.set_xlabel(f"time in step {study.mid_step + 1} [s] (shaded: DSP)")
        if j == 0:
            ax.set_ylabel(f"kappa(J), eq. (45) (singular: {KAPPA_CAP:.0e})")
            ax.legend(loc="upper left", fontsize=8)
    return _finish(fig, drawn, path, title)


def fig_kappa(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    return _kappa_panels(
        study,
        results,
        r,
        list(study.kappa_lengths),
        "kappa(J) over one step at the paper's lengths (paper Fig. 13)",
        path,
        near=False,
    )


def fig_kappa_limit(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    return _kappa_panels(
        study,
        results,
        r,
        r.kappa.near_limit_lengths,
        "kappa(J) where our fixed pelvis nears and passes its own limit",
        path,
        near=True,
    )


# -- section 7 --------------------------------------------------------------------------------
def fig_zmp(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    ex = zmp_of(results, study.figure_run("mpc", study.zmp_length))
    if not ex:
        return None
    feet = np.array(ex.footholds)
    fig, (ax, ax_z) = plt.subplots(
        2, 1, figsize=(13, 8.2), gridspec_kw={"height_ratios": [1.0, 1.5]}
    )
    mid = len(feet) // 2
    zoom = feet[max(mid - 1, 0) : mid + 2]
    length, width = FOOT_SIZE
    for a in (ax, ax_z):
        for i, (fx, fy) in enumerate(feet):
            a.add_patch(
                Rectangle(
                    (fx - length / 2, fy - width / 2),
                    length,
                    width,
                    fill=False,
                    lw=1.2,
                    ec="k",
                    label=f"footholds ({length:.2f} x {width:.2f} m)" if i == 0 else None,
                )
            )
        a.plot(
            array(ex.lipm_zmp_x),
            array(ex.lipm_zmp_y),
            color="#c0392b",
            lw=0.8,
            alpha=0.8,
            label="LIPM ZMP (measured CoM)",
        )
        a.plot(
            array(ex.cop_x),
            array(ex.cop_y),
            ls="none",
            marker=".",
            ms=2.5,
            color=method_hex("mpc"),
            label="measured ZMP (centre of pressure), 100 Hz",
        )
        a.plot(
            array(ex.com_des_x),
            array(ex.com_des_y),
            color="#2a9d3a",
            lw=1.5,
            ls="--",
            label="desired CoM",
        )
        a.plot(array(ex.com_x), array(ex.com_y), color="#2a9d3a", lw=1.5, label="measured CoM")
        a.set_xlabel("x (walking direction) [m]")
        a.set_ylabel("y [m]")
    ax.set_xlim(feet[:, 0].min() - 0.25, feet[:, 0].max() + 0.25)
    ax.set_ylim(-0.3, 0.3)
    ax.set_title(f"whole walk, MPC, step {study.zmp_length:.2f} m (axes not to scale)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.22), ncol=5, frameon=False)
    ax_z.set_xlim(zoom[:, 0].min() - 0.2, zoom[:, 0].max() + 0.2)
    ax_z.set_ylim(-0.25, 0.25)
    ax_z.set_aspect("equal")
    title = "middle of the walk, to scale"
    z = r.zmp
    if z.available:
        assert z.cop_in_measured_support_walking is not None  # set when available
        assert z.lipm_in_planned_support_walking is not None
        title += (
            f"\nwalking ticks with the CoP inside the measured support polygon: "
            f"{z.cop_in_measured_support_walking * 100:.1f} %; LIPM ZMP inside the "
            f"planned support: {z.lipm_in_planned_support_walking * 100:.1f} %"
        )
    ax_z.set_title(title)
    return _finish(fig, True, path, "ZMP in the footholds (paper Fig. 15)")


FIGURES = {
    "max_step": fig_max_step,
    "waist": fig_waist,
    "yaw_momentum": fig_yaw_momentum,
    "energy": fig_energy,
    "kappa": fig_kappa,
    "kappa_limit": fig_kappa_limit,
    "zmp": fig_zmp,
}


def make_all(study: Study, results: Results, r: StudyResults, folder: Path) -> dict[str, str]:
    """Write every figure into ``folder``; returns name -> file name (drawn figures only)."""
    folder.mkdir(parents=True, exist_ok=True)
    out = {}
    from app.experiments.figures_more import fig_energy_joints, fig_sensitivity

    more = {"energy_joints": fig_energy_joints, "sensitivity": fig_sensitivity}
    for name, fn in {**FIGURES, **more}.items():
        file = fn(study, results, r, folder / f"{name}.png")
        if file:
            out[name] = file
    return out
