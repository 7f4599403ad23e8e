"""The usual plots of runs against time (matplotlib), one line per run in its method's colour.

A :class:`matplotlib.figure.Figure` is made directly (not through pyplot): a notebook shows it
once, as the cell's value, and nothing is left open in pyplot's list of figures.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from controller.params import GROUPS, ControllerParams
from pelvic_walk.core.methods import METHOD_INFO, method_hex
from pelvic_walk.core.metrics import KAPPA_SINGULAR

if TYPE_CHECKING:
    from matplotlib.figure import Figure

DEG = 180.0 / np.pi
# name -> (series column, scale, title with unit, log axis)
PANELS: dict[str, tuple[str, float, str, bool]] = {
    "waist": ("waist_angle", DEG, "waist yaw theta [deg] (measured)", False),
    "waist_rate": ("waist_rate", DEG, "waist yaw rate [deg/s] (commanded)", False),
    "yaw_momentum": ("yaw_momentum", 1.0, "yaw momentum about the CoM [kg m^2/s]", False),
    "kappa": ("kappa_legs", 1.0, "kappa(J) of the leg columns (eq. 45), log", True),
    "energy": ("energy", 1.0, "positive joint work since the start (eq. 44) [J]", False),
    "theta_ref": ("theta_ref", DEG, "reference pelvic angle theta_ref (eq. 33) [deg]", False),
    "com_y": ("com_y", 1.0, "CoM y, measured [m]", False),
    "zmp_y": ("cop_y", 1.0, "ZMP y (centre of pressure), measured [m]", False),
    "reach": ("reach_left", 1.0, "left hip-to-ankle / leg length (1 = straight)", False),
    "active_ik": ("active_ik", 1.0, "active constraints of the IK (Run.qp names them)", False),
    "active_pelvis_mpc": ("active_pelvis_mpc", 1.0, "active constraints of the pelvic MPC", False),
    "active_com_mpc": ("active_com_mpc", 1.0, "active ZMP bounds of the CoM MPC", False),
}
DEFAULT_PANELS = ("waist", "waist_rate", "yaw_momentum", "kappa", "energy")
STYLES = ("-", "--", ":", "-.")  # runs of the same method, told apart
DSP_GREY = (0.47, 0.47, 0.47, 0.15)


def _dsp_spans(t: np.ndarray, step: np.ndarray, in_ssp: np.ndarray) -> list[tuple[float, float]]:
    """(start, end) of each double support while walking."""
    dsp = (step >= 0) & (in_ssp == 0)
    on = np.concatenate([[False], dsp, [False]])
    edges = np.flatnonzero(np.diff(on.astype(int)))
    return [
        (float(t[a]), float(t[min(b, len(t) - 1)]))
        for a, b in zip(edges[::2], edges[1::2], strict=True)
    ]


def plot(runs: Sequence[Any], *panels: str) -> Figure:
    """Stacked panels against time [s], a line per run (a method's runs in its colour, told
    apart by the line style); grey: double support of the first run. ``panels``: names of
    :data:`PANELS` (default: waist, waist_rate, yaw_momentum, kappa, energy)."""
    from matplotlib.figure import Figure

    runs = list(runs)
    if not runs or not all(hasattr(r, "column") and hasattr(r, "params") for r in runs):
        raise ValueError("plot() takes runs made by pelvic_walk.simulate")
    chosen = panels or DEFAULT_PANELS
    for p in chosen:
        if p not in PANELS:
            raise ValueError(f"unknown panel {p!r} (one of: {', '.join(PANELS)})")
    fig = Figure(figsize=(9, 1.9 * len(chosen) + 0.6), layout="constrained")
    axes = fig.subplots(len(chosen), 1, sharex=True, squeeze=False)[:, 0]
    names = labels(runs, titles=True)
    per_method: dict[str, int] = {}
    styles = []
    for r in runs:
        styles.append(STYLES[per_method.get(r.method, 0) % len(STYLES)])
        per_method[r.method] = per_method.get(r.method, 0) + 1
    first = runs[0]
    t0 = first.column("t")
    spans = _dsp_spans(t0, first.column("step_index"), first.column("in_ssp"))
    for ax, name in zip(axes, chosen, strict=True):
        col, scale, title, log = PANELS[name]
        for r, label, ls in zip(runs, names, styles, strict=True):
            ax.plot(
                r.column("t"),
                r.column(col) * scale,
                color=method_hex(r.method),
                ls=ls,
                lw=1.5,
                label=label,
            )
        for a, b in spans:
            ax.axvspan(a, b, color=DSP_GREY, lw=0)
        if log:
            ax.set_yscale("log")
            ax.axhline(KAPPA_SINGULAR, color="red", ls="--", lw=1, label="knee nearly straight")
        ax.set_title(title, fontsize=10, loc="left")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8, ncol=min(len(runs), 4))
    axes[-1].set_xlabel("time since the start [s] (grey: double support)")
    _show_figures_in_notebook()
    return fig


def _show_figures_in_notebook() -> None:
    """In a notebook, make a Figure show as a picture when it is a cell's value. IPython does
    so once pyplot is imported; a notebook that never imports it would print
    ``<Figure size ...>``."""
    try:
        from IPython import get_ipython
    except ImportError:
        return
    shell = get_ipython()
    if shell is None:
        return
    from matplotlib.figure import Figure

    png = shell.display_formatter.formatters["image/png"]
    if Figure not in png.type_printers:
        from IPython.core.pylabtools import select_figure_formats

        select_figure_formats(shell, {"png"}, bbox_inches="tight")


def differing_params(runs: Sequence[Any]) -> list[str]:
    """Dotted names of the parameters (and ``seed``) that differ between the runs: the
    paper's, then strategies' own (``gain.k``: a run of another strategy has none)."""
    names: list[str] = []
    for group in GROUPS:
        for f in dataclasses.fields(getattr(ControllerParams(), group)):
            values = {repr(getattr(getattr(r.params, group), f.name)) for r in runs}
            if len(values) > 1:
                names.append(f"{group}.{f.name}")
    own = sorted({n for r in runs for n, _ in r.params.own})
    names += [n for n in own if len({repr(param_value(r, n)) for r in runs}) > 1]
    if len({r.seed for r in runs}) > 1:
        names.append("seed")
    return names


def param_value(run: Any, dotted: str) -> Any:
    """A run's value of a parameter (``seed``, ``group.name``, a strategy's ``NAME.FIELD``;
    None for another strategy's own parameter, which the run does not have)."""
    if dotted == "seed":
        return run.seed
    group, _, name = dotted.partition(".")
    if group in GROUPS:
        return getattr(getattr(run.params, group), name)
    return run.params.value(dotted) if group == run.params.method else None


def labels(runs: Sequence[Any], titles: bool = False) -> list[str]:
    """A name per run: its method (``titles``: the strategy's label, as the legends of the
    live tool show it), with the parameters that tell it from the others' (dotted names)."""
    differing = differing_params(runs)
    out = []
    for r in runs:
        same = [o for o in runs if o.method == r.method]
        name = METHOD_INFO[r.method].title if titles else r.method
        extra = [f"{d}={param_value(r, d)}" for d in differing]
        out.append(f"{name} ({', '.join(extra)})" if extra and len(same) > 1 else name)
    seen: dict[str, int] = {}
    unique = []
    for label in out:
        seen[label] = seen.get(label, 0) + 1
        unique.append(label if seen[label] == 1 else f"{label} #{seen[label]}")
    return unique
