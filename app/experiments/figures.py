"""The study's figures (matplotlib, Agg): one function per figure, one colour per method.

Each ``fig_*`` takes the study, the run results and the analysed data (``sections.analyse``)
and writes one PNG; :func:`make_all` writes them all and returns the file names. A figure
whose runs are missing is skipped (and the report says so) rather than drawn empty.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

from app.experiments.definitions import (  # noqa: E402
    METHOD_LABELS,
    PAPER_MAX_STEP,
    PAPER_TABLE1,
    PAPER_WAIST_PEAK_DEG_040,
    ROTATING,
    RunSpec,
    Study,
)
from app.runs import KAPPA_SINGULAR  # noqa: E402

COLORS = {"fixed": "#555555", "redundancy": "#e07b00", "mpc": "#1f5fbf"}
DEG = 180.0 / np.pi
DPI = 110
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


def _arr(values: list[float | None] | None) -> np.ndarray:
    if values is None:
        return np.zeros(0)
    return np.array([np.nan if v is None else v for v in values], dtype=float)


def _extract(results: dict[RunSpec, Any], spec: RunSpec, name: str) -> dict[str, Any] | None:
    r = results.get(spec)
    return r["extracts"].get(name) if r and r["summary"] else None


def _save(fig: Any, path: Path) -> str:
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    return path.name


def _shade_dsp(ax: Any, dsp: float) -> None:
    ax.axvspan(0.0, dsp, color="#c8d8c8", alpha=0.5, lw=0)


# -- section 2 --------------------------------------------------------------------------------
def fig_max_step(study: Study, results: Any, data: dict[str, Any], path: Path) -> str | None:
    ms = data["max_step"]
    fig, ax = plt.subplots(figsize=(9.5, 3.6))
    for row, m in enumerate(study.methods):
        pts = ms[m]["points"]
        y = len(study.methods) - 1 - row
        for kind, marker, color, label in (
            ("clean", "o", "#2a9d3a", "clean"),
            ("unclean", "^", "#e0a000", "walked, not clean"),
            ("fell", "x", "#c0392b", "fell"),
        ):
            xs = [
                p["step_length"]
                for p in pts
                if (
                    p["clean"]
                    if kind == "clean"
                    else (p["fell"] if kind == "fell" else not p["clean"] and not p["fell"])
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
        paper = PAPER_MAX_STEP[m]
        ax.plot(
            [paper, paper],
            [y - 0.4, y - 0.08],
            ls="--",
            color="k",
            lw=1.5,
            label="paper's limit (below the dots)" if row == 0 else None,
        )
        ours = ms[m]["longest_clean"]
        if ours is not None:
            ax.plot(
                [ours, ours],
                [y + 0.08, y + 0.4],
                color=COLORS[m],
                lw=3,
                label="our longest clean step (above)" if row == 0 else None,
            )
            ax.annotate(
                f"{ours:.2f} m",
                (ours + 0.004, y + 0.22),
                ha="left",
                va="center",
                fontsize=9,
                color=COLORS[m],
            )
    ax.set_yticks(range(len(study.methods)))
    ax.set_yticklabels([METHOD_LABELS[m] for m in reversed(study.methods)])
    ax.set_ylim(-0.6, len(study.methods) - 0.4)
    ax.set_xlabel("step length [m]")
    ax.set_title(f"Longest clean step ({study.n_steps} steps of 1.2 s, arm swing on)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=5, frameon=False)
    return _save(fig, path)


# -- section 3 --------------------------------------------------------------------------------
def fig_waist(study: Study, results: Any, data: dict[str, Any], path: Path) -> str | None:
    lengths = study.figure_lengths
    fig, axes = plt.subplots(2, len(lengths), figsize=(5.2 * len(lengths), 6.4), squeeze=False)
    drawn = False
    for j, x in enumerate(lengths):
        ax_a, ax_r = axes[0, j], axes[1, j]
        dsp = None
        for m in ROTATING:
            ex = _extract(results, study.figure_run(m, x), "step")
            if not ex or not ex["t"]:
                continue
            drawn = True
            t = _arr(ex["t"])
            dsp = ex["dsp"]
            ax_a.plot(
                t, _arr(ex["waist_angle_cmd"]) * DEG, color=COLORS[m], lw=2, label=METHOD_LABELS[m]
            )
            ax_r.plot(
                t, _arr(ex["waist_rate"]) * DEG, color=COLORS[m], lw=2, label=METHOD_LABELS[m]
            )
            if m == "mpc":
                t_ref = t + ex.get("theta_ref_lead", 0.0)
                keep = t_ref <= ex["duration"] + 1e-9
                ax_a.plot(
                    t_ref[keep],
                    _arr(ex["theta_ref"])[keep] * DEG,
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
        if abs(x - 0.40) < 1e-9:
            for sgn in (-1, 1):
                ax_a.axhline(
                    sgn * PAPER_WAIST_PEAK_DEG_040,
                    color="k",
                    ls="--",
                    lw=1,
                    label="paper: +/-22 deg" if sgn > 0 else None,
                )
        ax_a.set_title(f"waist yaw angle, step {x:.2f} m")
        ax_r.set_title(f"waist yaw rate, step {x:.2f} m")
        ax_a.set_ylabel("commanded waist yaw [deg]")
        ax_r.set_ylabel("waist yaw rate [deg/s]")
        ax_a.legend(loc="best")
    if not drawn:
        plt.close(fig)
        return None
    fig.suptitle("Waist yaw over one mid-walk step (paper Fig. 8-9)")
    fig.tight_layout()
    return _save(fig, path)


# -- section 4 --------------------------------------------------------------------------------
def fig_yaw_momentum(study: Study, results: Any, data: dict[str, Any], path: Path) -> str | None:
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
            for arms, ls, lw in ((False, "-", 1.2), (True, "-", 2.0)):
                ex = _extract(results, study.figure_run(m, x, arms), "walk")
                if not ex:
                    continue
                drawn = True
                t, h = _arr(ex["t"]), _arr(ex["yaw_momentum"])
                starts = _arr(ex["step_start"])
                sel = (t >= starts[k0]) & (t <= starts[min(k1, len(starts) - 1)])
                ax.plot(
                    t[sel] - starts[k0],
                    h[sel],
                    ls=ls,
                    lw=lw,
                    color=COLORS[m] if arms else "#b0b0b0",
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
            case = data["yaw_momentum"]["cases"].get(f"{m}@{x:.2f}")
            note = ""
            if case and case["peak_reduction_percent"] is not None:
                note = f"peak -{case['peak_reduction_percent']:.0f} %"
            if case and (case["fell_arms"] or case["fell_no_arms"]):
                note += " (fell)"
            elif case and not (case["clean_arms"] and case["clean_no_arms"]):
                note += " (not clean)"
            ax.set_title(f"{METHOD_LABELS[m]}, {x:.2f} m\n{note}", pad=14)
            ax.set_xlabel("time from the start of the step shown first [s]")
            if j == 0:
                ax.set_ylabel("yaw momentum about CoM [kg m^2/s]")
            ax.legend(loc="lower left", fontsize=8)
    if not drawn:
        plt.close(fig)
        return None
    fig.suptitle(
        "Measured yaw angular momentum with and without arm swing (paper Fig. 12); "
        "T_k: start of step k",
        y=1.01,
    )
    fig.tight_layout()
    return _save(fig, path)


# -- section 5 --------------------------------------------------------------------------------
def fig_energy(study: Study, results: Any, data: dict[str, Any], path: Path) -> str | None:
    e = data["energy"]
    fig, (ax_o, ax_p) = plt.subplots(1, 2, figsize=(11, 4.2))
    off = {"fixed": -0.004, "redundancy": 0.0, "mpc": 0.004}
    drawn = False
    for m in study.methods:
        xs, mean, std, unclean = [], [], [], []
        for x in e["lengths"]:
            c = e["table"][m][f"{x:.2f}"]
            if c["mean"] is not None:
                xs.append(x + off[m])
                mean.append(c["mean"])
                std.append(c["std"])
                unclean.append(c["n_clean"] < c["n_runs"])
        if xs:
            drawn = True
            ax_o.errorbar(
                xs,
                mean,
                yerr=std,
                color=COLORS[m],
                marker="o",
                capsize=3,
                lw=1.8,
                label=METHOD_LABELS[m],
            )
            bad = [i for i, u in enumerate(unclean) if u]
            ax_o.plot(
                [xs[i] for i in bad],
                [mean[i] for i in bad],
                ls="none",
                marker="o",
                ms=9,
                mfc="white",
                mec=COLORS[m],
                mew=2,
                label=f"{m}: runs not all clean" if bad else None,
            )
        px = [x for x, v in PAPER_TABLE1[m].items() if v is not None]
        ax_p.errorbar(
            [x + off[m] for x in px],
            [PAPER_TABLE1[m][x][0] for x in px],
            yerr=[PAPER_TABLE1[m][x][1] for x in px],
            color=COLORS[m],
            marker="s",
            capsize=3,
            lw=1.8,
            ls="--",
            label=METHOD_LABELS[m],
        )
    if not drawn:
        plt.close(fig)
        return None
    ax_o.set_title(
        f"ours: {e['repeats']} runs x {e['steps']} steps per point "
        "(runs that did not fall)\nopen marker: not every run clean"
    )
    ax_p.set_title("paper, Table 1 (10 runs x 20 steps)")
    for ax in (ax_o, ax_p):
        ax.set_xlabel("step length [m]")
        ax.set_ylabel("energy per two steps, eq. (44) [J]")
        ax.legend(loc="upper left")
    fig.suptitle("Energy per two-step window: mean +/- std (paper Table 1)")
    fig.tight_layout()
    return _save(fig, path)


# -- section 6 --------------------------------------------------------------------------------
def _kappa_panels(
    study: Study,
    results: Any,
    lengths: list[float],
    title: str,
    path: Path,
    data: dict[str, Any],
    near: bool,
) -> str | None:
    if not lengths:
        return None
    fig, axes = plt.subplots(
        1, len(lengths), figsize=(4.4 * len(lengths), 3.8), squeeze=False, sharey=True
    )
    drawn = False
    ms = data["max_step"]
    for j, x in enumerate(lengths):
        ax = axes[0, j]
        dsp = dur = None
        for m in study.methods:
            ex = _extract(results, study.figure_run(m, x), "step")
            if not ex or not ex["t"]:
                continue
            drawn = True
            dsp, dur = ex["dsp"], ex["duration"]
            k = _arr(ex["kappa"])
            ax.semilogy(_arr(ex["t"]), k, color=COLORS[m], lw=1.8, label=METHOD_LABELS[m])
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
        tag = ""
        if near:
            lc, ff = ms["fixed"]["longest_clean"], ms["fixed"]["first_failed"]
            tag = (
                " (fixed: longest clean)"
                if lc is not None and abs(x - lc) < 1e-9
                else " (fixed: first failure)"
                if ff is not None and abs(x - ff) < 1e-9
                else " (fixed: past its limit)"
                if ff is not None and x > ff
                else ""
            )
        ax.set_title(f"step {x:.2f} m{tag}")
        ax.set_xlabel(f"time in step {study.mid_step + 1} [s] (shaded: DSP)")
        if j == 0:
            ax.set_ylabel("kappa(J), eq. (45) (singular: 1e8)")
            ax.legend(loc="upper left", fontsize=8)
    if not drawn:
        plt.close(fig)
        return None
    fig.suptitle(title)
    fig.tight_layout()
    return _save(fig, path)


def fig_kappa(study: Study, results: Any, data: dict[str, Any], path: Path) -> str | None:
    return _kappa_panels(
        study,
        results,
        list(study.kappa_lengths),
        "kappa(J) over one step at the paper's lengths (paper Fig. 13)",
        path,
        data,
        near=False,
    )


def fig_kappa_limit(study: Study, results: Any, data: dict[str, Any], path: Path) -> str | None:
    return _kappa_panels(
        study,
        results,
        data["kappa"]["near_limit_lengths"],
        "kappa(J) where our fixed pelvis nears and passes its own limit",
        path,
        data,
        near=True,
    )


# -- section 7 --------------------------------------------------------------------------------
def fig_zmp(study: Study, results: Any, data: dict[str, Any], path: Path) -> str | None:
    ex = _extract(results, study.figure_run("mpc", study.zmp_length), "zmp")
    if not ex:
        return None
    feet = np.array(ex["footholds"])
    fig, (ax, ax_z) = plt.subplots(
        2, 1, figsize=(13, 8.2), gridspec_kw={"height_ratios": [1.0, 1.5]}
    )
    lx, ly = _arr(ex["lipm_zmp_x"]), _arr(ex["lipm_zmp_y"])
    cx, cy = _arr(ex["cop_x"]), _arr(ex["cop_y"])
    mid = len(feet) // 2
    zoom = feet[max(mid - 1, 0) : mid + 2]
    for a in (ax, ax_z):
        for i, (fx, fy) in enumerate(feet):
            a.add_patch(
                Rectangle(
                    (fx - 0.15, fy - 0.085),
                    0.30,
                    0.17,
                    fill=False,
                    lw=1.2,
                    ec="k",
                    label="footholds (0.30 x 0.17 m)" if i == 0 else None,
                )
            )
        a.plot(lx, ly, color="#c0392b", lw=0.8, alpha=0.8, label="LIPM ZMP (measured CoM)")
        a.plot(
            cx,
            cy,
            ls="none",
            marker=".",
            ms=2.5,
            color=COLORS["mpc"],
            label="measured ZMP (centre of pressure), 100 Hz",
        )
        a.plot(
            _arr(ex["com_des_x"]),
            _arr(ex["com_des_y"]),
            color="#2a9d3a",
            lw=1.5,
            ls="--",
            label="desired CoM",
        )
        a.plot(_arr(ex["com_x"]), _arr(ex["com_y"]), color="#2a9d3a", lw=1.5, label="measured CoM")
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
    z = data["zmp"]
    if z.get("available"):
        title += (
            f"\nwalking ticks with the CoP inside the measured support polygon: "
            f"{z['cop_in_measured_support_walking'] * 100:.1f} %; LIPM ZMP inside the "
            f"planned support: {z['lipm_in_planned_support_walking'] * 100:.1f} %"
        )
    ax_z.set_title(title)
    fig.suptitle("ZMP in the footholds (paper Fig. 15)")
    fig.tight_layout()
    return _save(fig, path)


FIGURES = {
    "max_step": fig_max_step,
    "waist": fig_waist,
    "yaw_momentum": fig_yaw_momentum,
    "energy": fig_energy,
    "kappa": fig_kappa,
    "kappa_limit": fig_kappa_limit,
    "zmp": fig_zmp,
}


def make_all(study: Study, results: Any, data: dict[str, Any], folder: Path) -> dict[str, str]:
    """Write every figure into ``folder``; returns name -> file name (drawn figures only)."""
    folder.mkdir(parents=True, exist_ok=True)
    out = {}
    for name, fn in FIGURES.items():
        file = fn(study, results, data, folder / f"{name}.png")
        if file:
            out[name] = file
    return out
