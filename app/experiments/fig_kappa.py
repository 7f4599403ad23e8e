"""Section 6's figures: kappa over one step at the paper's lengths (paper Fig. 13) and where
the fixed pelvis nears and passes its own limit."""

from __future__ import annotations

from pathlib import Path

from app.experiments.definitions import Study
from app.experiments.fig_style import finish, label, plt, shade_dsp
from app.experiments.outcomes import Results, array, step_of
from app.experiments.results import StudyResults
from controller.kinematics import KAPPA_CAP
from controller.strategy import FIXED
from pelvic_walk.core.methods import method_hex
from pelvic_walk.core.metrics import KAPPA_SINGULAR


def _limit_tag(r: StudyResults, x: float) -> str:
    """Where ``x`` stands against the fixed pelvis's own limit."""
    lc, ff = r.max_step[FIXED].longest_clean, r.max_step[FIXED].first_failed
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
            t = array(ex.t)
            if ex.kappa_legs:
                ax.semilogy(t, array(ex.kappa_legs), color=method_hex(m), lw=1.8, label=label(m))
            ax.semilogy(t, array(ex.kappa), color=method_hex(m), lw=1.0, ls="--")
        if dsp is not None:
            shade_dsp(ax, dsp)
            ax.axvline(dur, color="k", lw=0.8, ls=":")
            ax.plot([], [], color="k", lw=1.0, ls="--", label="kappa(J_low), dashed")
            ax.axhline(
                KAPPA_SINGULAR,
                color="#c0392b",
                lw=0.8,
                ls="--",
                label=f"kappa(legs) bound of a clean run ({KAPPA_SINGULAR:.0f})"
                if j == 0
                else None,
            )
            ax.annotate(
                "landing", (dur, 0.02), xycoords=("data", "axes fraction"), ha="right", fontsize=8
            )
        ax.set_title(f"step {x:.2f} m{_limit_tag(r, x) if near else ''}")
        ax.set_xlabel(f"time in step {study.mid_step + 1} [s] (shaded: DSP)")
        if j == 0:
            ax.set_ylabel(f"kappa(legs), solid; eq. (45) (singular: {KAPPA_CAP:.0e})")
            ax.legend(loc="upper left", fontsize=8)
    return finish(fig, drawn, path, title)


def fig_kappa(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    return _kappa_panels(
        study,
        results,
        r,
        list(study.kappa_lengths),
        "kappa(legs) and kappa(J_low) over one step at the paper's lengths (paper Fig. 13)",
        path,
        near=False,
    )


def fig_kappa_limit(study: Study, results: Results, r: StudyResults, path: Path) -> str | None:
    return _kappa_panels(
        study,
        results,
        r,
        r.kappa.near_limit_lengths,
        "kappa(legs) and kappa(J_low) where our fixed pelvis nears and passes its own limit",
        path,
        near=True,
    )
