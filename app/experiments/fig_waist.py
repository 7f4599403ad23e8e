"""Section 3's figure: the waist angle and rate over one mid-walk step (paper Fig. 8-9)."""

from __future__ import annotations

from pathlib import Path

from app.experiments import paper
from app.experiments.definitions import ROTATING, Study
from app.experiments.fig_style import DEG, finish, label, plt, shade_dsp
from app.experiments.outcomes import Results, array, step_of
from app.experiments.results import StudyResults
from controller.strategy import MPC
from pelvic_walk.core.methods import method_hex


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
            style = dict(color=method_hex(m), lw=2, label=label(m))
            ax_a.plot(t, array(ex.waist_angle_cmd) * DEG, **style)
            ax_r.plot(t, array(ex.waist_rate) * DEG, **style)
            if m == MPC:
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
                shade_dsp(ax, dsp)
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
    return finish(fig, drawn, path, "Waist yaw over one mid-walk step (paper Fig. 8-9)")
