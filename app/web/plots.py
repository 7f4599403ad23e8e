"""The GUI's plots: live metrics per method (Plots tab) and the horizon inspector (Inspect tab).

Both draw published data only: the session's plot rows (:class:`~app.live.history.PlotHistory`)
and the shown frame's :class:`~pelvic_walk.core.frames.Horizon`. They are updated at a few hertz (a
plot message carries its whole window, so updating at the display rate would dominate what
a viewer is sent) and, while paused, whenever the shown instant changes.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import viser
import viser.uplot

from app.live.session import SessionView
from app.web.looks import looks
from app.web.overlays import DANGER, MEASURED, PLAN, PREDICTED, REFERENCE
from controller import strategy
from pelvic_walk.core.frames import LiveFrame
from pelvic_walk.core.methods import METHOD_INFO
from pelvic_walk.core.metrics import KAPPA_SINGULAR

PLOT_HZ = 1.0  # live plot updates per second while running (each carries its whole window)
INSPECTOR_HZ = 4.0  # horizon inspector updates per second while running
WINDOWS_S = (12.0, 30.0, 60.0)  # [s] the live plots' x range, chosen in the GUI
MAX_POINTS = 150  # plot rows sent per series (a longer window is decimated)
DSP_FILL = "rgba(120, 120, 120, 0.18)"  # shading of the double-support phases
PLOTS: tuple[tuple[str, str, tuple[float, float]], ...] = (  # (row column, title, min y-span)
    ("waist_deg", "Waist yaw [deg]", (-30.0, 30.0)),
    ("waist_rate_deg_s", "Waist yaw rate [deg/s]", (-60.0, 60.0)),
    ("yaw_momentum", "Yaw momentum [kg m^2/s]", (-0.5, 0.5)),
    # (short: a title wider than the panel runs under the plot's expand button; the legend
    # names the dashed line)
    ("kappa_legs", "kappa(J) of the legs, log (eq. 45)", (1.0, 10 * KAPPA_SINGULAR)),
    ("energy_two_step", "Energy per two steps [J] (eq. 44, as Table 1)", (0.0, 100.0)),
)
LOG_PLOTS = {"kappa_legs"}  # drawn on a log10 axis: a straight knee's 1e8 beside a clean 30
LOG_MAX = 1e12  # the log axis's top at most (kappa is finite but unbounded at a straight knee)
# the legends name the lines only: uPlot's live values ("--" until the pointer is on the
# plot) left gaps after every name in a narrow panel
LEGEND = viser.uplot.Legend(show=True, live=False)
LIVE_X = viser.uplot.Axis(label="t - now [s]")  # the x axes say what they count
HORIZON_X = viser.uplot.Axis(label="t from now [s]")


def css(rgb: tuple[int, int, int], alpha: float = 1.0) -> str:
    return f"rgba({rgb[0]}, {rgb[1]}, {rgb[2]}, {alpha})"


def log_span(values: list[np.ndarray], minimum: tuple[float, float]) -> tuple[float, float]:
    """Whole decades holding the data and at least ``minimum`` (a log axis)."""
    finite = (
        np.concatenate([v[np.isfinite(v) & (v > 0)] for v in values]) if values else np.zeros(0)
    )
    lo, hi = minimum
    if len(finite):
        lo = min(lo, float(np.min(finite)))
        hi = max(hi, float(np.max(finite)))
    hi = min(hi, LOG_MAX)
    return 10.0 ** math.floor(math.log10(lo)), 10.0 ** math.ceil(math.log10(hi))


def log_axis(lo: float, hi: float) -> viser.uplot.Axis:
    """A y axis with a tick at whole decades, labelled 1, 10, 100, 1e3, ... (uPlot's default
    labels of a log axis are numbers with thousands separators, cut off in a narrow panel);
    every other decade when there are many."""
    d0, d1 = round(math.log10(lo)), round(math.log10(hi))
    every = 1 if d1 - d0 <= 6 else 2
    decades = list(range(d0, d1 + 1, every))
    # the top decade's line is the plot's top edge: a label there is cut in half (uPlot snaps
    # a log range to whole decades, so no head room can be given), so it is left unlabelled
    return viser.uplot.Axis(
        splits=tuple(10.0**d for d in decades),
        values=tuple(
            "" if d == d1 and d > d0 else f"{10**d:g}" if d < 3 else f"1e{d}" for d in decades
        ),
        size=44,
    )


def _on(x: np.ndarray, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """``fp`` sampled at ``xp``, read at ``x`` (NaN outside ``xp``)."""
    if len(xp) < 2:
        return np.full(len(x), np.nan)
    return np.interp(x, xp, fp, left=np.nan, right=np.nan)


def _span(values: list[np.ndarray], minimum: tuple[float, float]) -> tuple[float, float]:
    """A y range holding the data and at least ``minimum``, with some head room."""
    finite = np.concatenate([v[np.isfinite(v)] for v in values]) if values else np.zeros(0)
    lo, hi = minimum
    if len(finite):
        lo, hi = min(lo, float(finite.min())), max(hi, float(finite.max()))
    pad = 0.05 * (hi - lo or 1.0)
    return lo - pad, hi + pad


class LivePlots:
    """Waist angle and rate, yaw momentum, kappa and energy per method, against time."""

    def __init__(self, gui: Any, session: SessionView):
        self.gui = gui
        self.session = session
        self.window = gui.add_dropdown(
            "Window [s]", tuple(f"{w:g}" for w in WINDOWS_S), initial_value=f"{WINDOWS_S[0]:g}"
        )
        self.window.on_update(lambda _e: self._invalidate())
        self.note = gui.add_markdown(
            "Grey bands: double support, both feet down (a band starts at a landing and ends "
            "at the next lift-off). x: seconds before the instant shown (while paused and "
            "sought, the plots end there)."
        )
        self.folder = gui.add_folder("Plots", expand_by_default=True)
        self.handles: dict[str, Any] = {}  # the plots shown: column -> handle
        # every set of plots made, by robots shown: a change of robots hides one set and shows
        # (or makes) another, and never removes one. (viser's client applies a batch's
        # property updates after its removals: an update sent just before a removal fails on
        # the page as "Tried to update non-existent component", a starved page's batch holding
        # several of them.)
        self._sets: dict[tuple[tuple[str, str], ...], dict[str, Any]] = {}
        self._scales: dict[str, tuple] = {}
        self._methods: tuple[tuple[str, str], ...] = ()  # the robots': (key, strategy)
        self._last: tuple[float, float] | None = None  # (frame clock, wall time of update)

    def _invalidate(self) -> None:
        self._last = None

    def update(self, frame: LiveFrame, now: float) -> None:
        shown = tuple((r.method, r.strategy) for r in frame.robots)
        methods = tuple(r.method for r in frame.robots)
        if shown != self._methods:
            self._build(shown)
        if self._last is not None and (
            (not frame.paused and now - self._last[1] < 1.0 / PLOT_HZ)
            or (frame.paused and frame.clock == self._last[0])
        ):
            return
        self._last = (frame.clock, now)
        seconds = float(self.window.value)
        window = self.session.history.window(seconds, until=frame.clock)
        if not methods:
            return
        ref = methods[0]
        clock = window.column(ref, "clock")
        if len(clock) < 2:
            return
        step = max(1, int(math.ceil(len(clock) / MAX_POINTS)))
        clock = clock[::step]
        x = clock - frame.clock
        dsp = window.column(ref, "in_dsp")[::step] == 1.0
        for col, handle in self.handles.items():
            # each robot's rows on the first robot's clock (robots of a session split across
            # worker processes arrive in different batches)
            ys = [_on(clock, window.column(m, "clock"), window.column(m, col)) for m in methods]
            spec = next(p for p in PLOTS if p[0] == col)
            log = col in LOG_PLOTS
            lo, hi = log_span(ys, spec[2]) if log else _span(ys, spec[2])
            band = np.where(dsp, hi, lo)  # filled down from the line: shaded in the DSP only
            extra = (np.full(len(x), KAPPA_SINGULAR),) if col == "kappa_legs" else ()
            handle.data = (
                x.astype(np.float32),
                *(y.astype(np.float32) for y in ys),
                *(e.astype(np.float32) for e in extra),
                band.astype(np.float32),
            )
            scales = (seconds, round(lo, 2), round(hi, 2))
            if self._scales.get(col) != scales:  # sent only when the ranges change
                self._scales[col] = scales
                y_scale = (
                    viser.uplot.Scale(range=(lo, hi), distr=3, log=10)
                    if log
                    else viser.uplot.Scale(range=(scales[1], scales[2]))
                )
                handle.scales = {
                    "x": viser.uplot.Scale(time=False, range=(-seconds, 0.0)),
                    "y": y_scale,
                }
                if log:
                    handle.axes = (LIVE_X, log_axis(lo, hi))

    def _build(self, methods: tuple[tuple[str, str], ...]) -> None:
        """Show the plots of these robots (made the first time), hide the others."""
        for shown, handles in self._sets.items():
            if shown != methods:
                for handle in handles.values():
                    if handle.visible:
                        handle.visible = False
        if methods in self._sets:
            self.handles = self._sets[methods]
            for handle in self.handles.values():
                handle.visible = True
        else:
            self.handles = self._sets[methods] = self._make(methods)
        self._methods = methods
        self._scales = {}
        self._last = None

    def _make(self, methods: tuple[tuple[str, str] | str, ...]) -> dict[str, Any]:
        handles: dict[str, Any] = {}
        # each robot's line in its colour and its own dash pattern, its legend entry with its
        # marker and label: told apart without colour too (app.web.looks)
        look = looks(methods)
        robots = tuple(
            viser.uplot.Series(
                label=look[m].tag,
                stroke=css(look[m].color),
                width=2,
                **({"dash": look[m].dash} if look[m].dash else {}),
            )
            for m in (x if isinstance(x, str) else x[0] for x in methods)
        )
        x_axis = viser.uplot.Series(label="t - now [s]")

        def dsp(log: bool) -> viser.uplot.Series:  # filled down to the axis (> 0 on a log axis)
            return viser.uplot.Series(
                label="double support",
                stroke="rgba(0,0,0,0)",
                fill=DSP_FILL,
                fillTo=1e-9 if log else -1e9,
                width=0,
            )

        singular = viser.uplot.Series(
            label=f"knee nearly straight ({KAPPA_SINGULAR:g})",
            stroke=css(DANGER),
            width=1.5,
            dash=(6, 4),
        )
        with self.folder:
            for col, title, _span_min in PLOTS:
                kappa = col == "kappa_legs"
                series = (x_axis, *robots, *((singular,) if kappa else ()), dsp(col in LOG_PLOTS))
                empty = tuple(np.ones(2, dtype=np.float32) for _ in series)
                handles[col] = self.gui.add_uplot(
                    data=empty,
                    series=series,
                    title=title,
                    aspect=2.0,
                    scales={"x": viser.uplot.Scale(time=False, range=(-WINDOWS_S[0], 0.0))},
                    axes=(LIVE_X, viser.uplot.Axis()),
                    legend=LEGEND,
                )
        return handles


class HorizonInspector:
    """The chosen robot's plan over the horizon at the shown instant (paper Fig. 5-7), in the
    scene's colours: predicted / optimised sky blue and solid, references indigo and dashed,
    the footstep plan grey. The robot is chosen by its label (as the legends name it)."""

    def __init__(self, gui: Any):
        self.gui = gui
        mpc = METHOD_INFO[strategy.MPC].title
        self.robot = gui.add_dropdown("Robot", (mpc,), initial_value=mpc)
        self._by_title: dict[str, str] = {mpc: strategy.MPC}  # dropdown option -> method
        self._shown: tuple[LiveFrame, float] | None = None  # the last frame, for a redraw
        self.robot.on_update(lambda _e: self._reselected())
        self.caption = gui.add_markdown("")
        pred, ref, plan = css(PREDICTED), css(REFERENCE), css(PLAN)
        x_axis = viser.uplot.Series(label="t from now [s]")
        self.com = gui.add_uplot(
            data=tuple(np.zeros(2, dtype=np.float32) for _ in range(4)),
            title="Forward (x) from the CoM now [m]: predicted CoM (eq. 25-26), planned feet "
            "(eq. 20-21)",
            series=(
                x_axis,
                viser.uplot.Series(label="CoM x (predicted)", stroke=pred, width=2.5),
                viser.uplot.Series(label="left foot x (plan)", stroke=css(MEASURED), width=1.5),
                viser.uplot.Series(label="right foot x (plan)", stroke=plan, width=2, dash=(6, 4)),
            ),
            aspect=2.0,
            axes=(HORIZON_X, viser.uplot.Axis()),
            legend=LEGEND,
        )
        self.zmp = gui.add_uplot(
            data=tuple(np.zeros(2, dtype=np.float32) for _ in range(7)),
            title="Sideways (y) [m]: predicted ZMP and CoM in the ZMP bounds (eq. 16-18, 25-26)",
            series=(
                x_axis,
                viser.uplot.Series(label="ZMP y (predicted)", stroke=pred, width=2.5),
                viser.uplot.Series(label="CoM y (predicted)", stroke=css(PREDICTED, 0.45), width=2),
                viser.uplot.Series(label="ZMP reference", stroke=ref, width=1.5, dash=(6, 4)),
                viser.uplot.Series(label="min", stroke=plan, width=1),
                viser.uplot.Series(label="max", stroke=plan, width=1),
                # the CoM MPC's active ZMP bounds (the QP view names them)
                viser.uplot.Series(
                    label="bound touched (active)",
                    stroke=css(DANGER),
                    width=0,
                    points=viser.uplot.Series_Points(show=True, size=9, fill=css(DANGER)),
                ),
            ),
            aspect=2.0,
            axes=(HORIZON_X, viser.uplot.Axis()),
            legend=LEGEND,
        )
        self.theta = gui.add_uplot(
            data=tuple(np.zeros(2, dtype=np.float32) for _ in range(3)),
            title="Pelvic angle over the horizon [deg] (eq. 30-33, 35)",
            series=(
                x_axis,
                # the reference drawn last, its dashes over the MPC's line where they coincide
                viser.uplot.Series(label="theta (planned: the MPC, eq. 35)", stroke=pred, width=3),
                viser.uplot.Series(label="theta_ref (eq. 33)", stroke=ref, width=2, dash=(8, 5)),
            ),
            aspect=2.0,
            axes=(HORIZON_X, viser.uplot.Axis()),
            legend=LEGEND,
        )
        self.theta_note = gui.add_markdown("")
        self._key: tuple | None = None
        self._time = -math.inf
        self._scales: dict[str, tuple[float, float, float]] = {}

    def _invalidate(self) -> None:
        self._key = None

    def _reselected(self) -> None:
        """Another robot chosen: draw it at once from the last frame (paused, no new frame
        may come to draw it)."""
        self._invalidate()
        if self._shown is not None:
            self.update(*self._shown)

    def selected(self) -> str | None:
        """The method of the robot the dropdown names (by its label)."""
        return self._by_title.get(self.robot.value)

    def _scale(
        self,
        handle: Any,
        name: str,
        horizon: float,
        ys: list[np.ndarray],
        minimum: tuple[float, float],
    ) -> None:
        """Explicit x (seconds, not uPlot's default time axis) and y ranges, sent on change."""
        lo, hi = _span(ys, minimum)
        scales = (round(horizon, 3), round(lo, 2), round(hi, 2))
        if self._scales.get(name) != scales:
            self._scales[name] = scales
            handle.scales = {
                "x": viser.uplot.Scale(time=False, range=(0.0, scales[0])),
                "y": viser.uplot.Scale(range=(scales[1], scales[2])),
            }

    def update(self, frame: LiveFrame, now: float) -> None:
        self._shown = (frame, now)
        methods = tuple(r.method for r in frame.robots)
        look = looks(frame.robots)
        titles = tuple(look[m].title for m in methods)
        if tuple(self.robot.options) != titles and methods:
            self._by_title = dict(zip(titles, methods, strict=True))
            self.robot.options = titles
            if self.robot.value not in titles:
                mpcs = [r.method for r in frame.robots if r.strategy == strategy.MPC]
                self.robot.value = look[mpcs[0] if mpcs else methods[0]].title
        method = self._by_title.get(self.robot.value)
        r = frame.robot(method) if methods and method is not None else None
        if r is None or r.horizon is None:
            return
        key = (frame.seq, r.method)
        if key == self._key or (
            not frame.paused
            and now - self._time < 1.0 / INSPECTOR_HZ
            and self._key is not None
            and self._key[1] == r.method
        ):
            return
        self._key, self._time = key, now
        h = r.horizon
        t = h.t.astype(np.float32)
        f32 = np.float32
        x0 = float(r.com[0])  # forward positions from the measured CoM now: readable numbers
        com_x, left_x, right_x = h.com[:, 0] - x0, h.left_foot[:, 0] - x0, h.right_foot[:, 0] - x0
        self.com.data = (t, com_x.astype(f32), left_x.astype(f32), right_x.astype(f32))
        self.zmp.data = (
            t,
            h.zmp[:, 1].astype(f32),
            h.com[:, 1].astype(f32),
            h.zmp_ref[:, 1].astype(f32),
            h.zmp_lo[:, 1].astype(f32),
            h.zmp_hi[:, 1].astype(f32),
            touched_y(r, h.zmp_lo[:, 1], h.zmp_hi[:, 1]).astype(f32),
        )
        deg = 180.0 / np.pi
        theta_ref, theta = h.theta_ref * deg, h.theta * deg
        self.theta.data = (t, theta.astype(f32), theta_ref.astype(f32))
        horizon = float(h.t[-1])
        self._scale(self.com, "com", horizon, [com_x, left_x, right_x], (-0.2, 0.6))
        self._scale(
            self.zmp,
            "zmp",
            horizon,
            [h.zmp[:, 1], h.com[:, 1], h.zmp_lo[:, 1], h.zmp_hi[:, 1]],
            (-0.15, 0.15),
        )
        self._scale(self.theta, "theta", horizon, [theta_ref, theta], (-10.0, 10.0))
        self.theta_note.content = theta_note(r, theta, theta_ref)
        phase = (
            "double support"
            if r.in_dsp
            else ("single support" if r.step_index >= 0 else "standing")
        )
        stopped = (
            f" ⚠ stopped by its strategy's error at t = {r.t:.2f} s of its walk: the plan shown "
            "is its last."
            if r.error is not None
            else ""
        )
        self.caption.content = (
            f"**{look[r.method].full}** at t = {frame.clock:.2f} s ({phase}, step "
            f"{max(r.step_index, 0)}): horizon {h.t[-1]:.1f} s, {len(h.t)} samples.{stopped}"
        )


def touched_y(r: Any, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(N,) the y bound the CoM MPC's ZMP touches at each horizon sample (its active
    constraints, controller.explain), NaN where none is active: the strip's markers."""
    out = np.full(len(lo), np.nan)
    rec = getattr(r, "qp", None)
    if rec is None:
        return out
    for c in rec["com_mpc"].active:
        k = c.row - len(lo)  # the y rows follow the N x rows
        if c.axis == "y":
            if 0 <= k < len(lo):
                out[k] = hi[k] if c.side == "upper" else lo[k]
    return out


def theta_note(r: Any, theta: np.ndarray, theta_ref: np.ndarray) -> str:
    """Why theta and theta_ref coincide (or not), from the weights in force, with the largest
    difference over the horizon [deg]."""
    if r.horizon is None or not r.horizon.planned:
        return (
            "Only the MPC robot plans its pelvic angle: for this robot theta is the commanded "
            "angle now, held over the horizon."
        )
    diff = float(np.max(np.abs(theta - theta_ref))) if len(theta) else math.nan
    pel = r.params.pelvis
    head = (
        f"Largest difference theta - theta_ref over the horizon: **{diff:.2f}°**. The MPC "
        f"weighs tracking its reference by alpha_pel = {pel.alpha:g} and the yaw acceleration "
        f"by beta_pel = {pel.beta:g} (eq. 37; the paper: 1 and 1e-10)"
    )
    # Measured at 0.4 m steps (a closed-loop Session, 6 steps, ticks 300-1400: the median of
    # the largest |theta - theta_ref| over the horizon): beta_pel 1e-10: 0.0°, 1e-6: 0.4°,
    # 1e-4: 2.9°, 1e-2: 15.4°.
    if pel.beta <= 1e-5 * max(pel.alpha, 1e-12):
        return (
            f"{head}: with so small a beta_pel smoothing costs nearly nothing, so theta "
            "follows theta_ref closely and the two lines lie on each other. Raise beta_pel "
            "(Pelvic MPC folder) to see the MPC trade tracking for a smoother turn: at 0.4 m "
            "steps theta departs from theta_ref by about 3° at 1e-4 and 15° at 1e-2."
        )
    return (
        f"{head}: at this beta_pel the MPC trades tracking for a smoother turn, so theta "
        "departs from its reference (about 3° at 1e-4 and 15° at 1e-2, at 0.4 m steps)."
    )
