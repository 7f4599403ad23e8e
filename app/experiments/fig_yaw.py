"""Section 4's figure: the yaw angular momentum with and without arm swing (paper Fig. 12)."""

from __future__ import annotations

from pathlib import Path

from app.experiments.definitions import Study
from app.experiments.fig_style import NO_ARMS_GREY, finish, label, plt
from app.experiments.outcomes import Results, array, case_key, walk_of
from app.experiments.results import StudyResults
from pelvic_walk.core.methods import method_hex


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
            ax.set_title(f"{label(m)}, {x:.2f} m\n{_yaw_note(r, m, x)}", pad=14)
            ax.set_xlabel("time from the start of the step shown first [s]")
            if j == 0:
                ax.set_ylabel("yaw momentum about CoM [kg m^2/s]")
            ax.legend(loc="lower left", fontsize=8)
    return finish(
        fig,
        drawn,
        path,
        "Measured yaw angular momentum with and without arm swing (paper Fig. 12); "
        "T_k: start of step k",
        y=1.01,
    )
