"""Section 7's figure: the ZMP and CoM paths in the footholds (paper Fig. 15)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.patches import Rectangle

from app.experiments.balance import EDGE_MARGIN
from app.experiments.definitions import Study
from app.experiments.fig_style import finish, plt
from app.experiments.outcomes import Results, array, zmp_of
from app.experiments.results import StudyResults
from controller.strategy import MPC
from models.dyros_jet import FOOT_SIZE
from pelvic_walk.core.methods import method_hex


def fig_zmp(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    ex = zmp_of(results, study.figure_run(MPC, study.zmp_length))
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
            color=method_hex(MPC),
            label="measured ZMP (centre of pressure), 100 Hz",
        )
        if ex.balance_margin:
            edge = np.abs(array(ex.balance_margin)) < EDGE_MARGIN
            a.plot(
                array(ex.cop_x)[edge],
                array(ex.cop_y)[edge],
                ls="none",
                marker="x",
                ms=3.5,
                mew=0.8,
                color="k",
                label=f"CoP on a sole's edge (margin < {EDGE_MARGIN * 1000:.1f} mm)",
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
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.22), ncol=3, frameon=False)
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
    return finish(fig, True, path, "ZMP in the footholds (paper Fig. 15)")
