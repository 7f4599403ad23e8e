"""The viser control panel: parameters, comparison, playback, layers, presets, plots, lessons.

Every control only writes intent into :class:`~app.live.LiveSim` (never the simulation).
Slider ranges, steps, defaults and labels come from :func:`controller.params.spec`, the single
source of truth; gains whose range spans many orders of magnitude (e.g. gamma 1e-9..1) get a
number box instead of a slider, which would be unusable at that step.

The panel also *reflects* the intent (a ``PUT /api/params`` moves the sliders): assigning a
value from Python fires the control's callback synchronously in viser, so :meth:`reflect`
marks its own thread as reflecting and the callbacks ignore what they receive there; a
callback that receives the value already in force does nothing either, so nothing can loop.
"""

from __future__ import annotations

import html
import math
import threading
from typing import Any

import numpy as np
import viser
import viser.uplot

from app.live import SPEED_MAX, SPEED_MIN, LiveFrame, LiveSim, live_params
from app.web.scene import LAYERS, SceneView
from controller.params import METHOD_INFO, METHODS, ControllerParams, spec

MAX_SLIDER_POSITIONS = 2000  # above this many steps a number box replaces the slider
PLOT_WINDOW_S = 12.0  # [s] of history the live plots show

# The GUI folders of parameters: folder -> (group, field) in controller.params.
PARAM_FOLDERS: dict[str, tuple[tuple[str, str], ...]] = {
    "Walk": (("walk", "step_length"), ("walk", "step_time"), ("walk", "dsp_ratio"),
             ("walk", "foot_height")),
    "CoM MPC": (("com", "horizon"), ("com", "alpha"), ("com", "beta"), ("com", "gamma")),
    "Pelvic MPC": (("pelvis", "alpha"), ("pelvis", "beta"), ("pelvis", "k_pel"),
                   ("pelvis", "angle_limit_deg")),
    "Arm swing": (("arms", "enabled"), ("arms", "omega1"), ("arms", "omega2"),
                  ("arms", "omega3")),
}

# The paper's scenarios, in one place: parameter groups to change (others keep their value)
# and optionally the methods to compare.
PRESETS: dict[str, dict[str, Any]] = {
    "Paper: 0.30 m steps": {"walk": {"step_length": 0.30, "step_time": 1.2}},
    "Paper: 0.40 m steps": {"walk": {"step_length": 0.40, "step_time": 1.2},
                            "methods": ["fixed", "mpc"]},
    # Our fixed pelvis walks cleanly to 0.37 m; at 0.38-0.39 m its swing knee straightens
    # (kappa > 1000) and the IK hits the joint-speed limit (report section 2). Paper: 0.35 m.
    "Where our fixed pelvis fails: 0.39 m (paper: 0.35 m)": {
        "walk": {"step_length": 0.39, "step_time": 1.2}, "methods": ["fixed", "mpc"]},
    "All three methods, 0.30 m": {"walk": {"step_length": 0.30, "step_time": 1.2},
                                  "methods": ["fixed", "redundancy", "mpc"]},
    "Defaults": {"walk": {"step_length": 0.2, "step_time": 1.2}, "reset_groups": True},
}

# Short lessons, one per layer, with the paper's equation numbers.
EXPLAIN: dict[str, str] = {
    "Overview": (
        "Each robot runs the same controller with the same parameters; only the **waist yaw** "
        "(the pelvic rotation) differs: **fixed** keeps it at 0, **redundancy** (ref. [21]) "
        "lets the IK use it with no preview, the **pelvic-rotation MPC** plans it over the "
        "horizon. Raise the step length and watch the **reach gauges**: the fixed pelvis "
        "straightens its swing leg (red) first."
    ),
    "CoM MPC (eq. 10-18)": (
        "A linear inverted pendulum at constant height, state [p, v, a] per axis, input = jerk "
        "(eq. 10-12). Over the horizon H it trades **alpha** x ZMP tracking, **beta** x CoM "
        "velocity changes and **gamma** x jerk (eq. 18), keeping the ZMP inside the support "
        "area. The **cyan** points are its predicted CoM (eq. 25-26)."
    ),
    "Pelvis position (eq. 19)": (
        "The pelvis follows the desired CoM and corrects the offset to the CoM measured from "
        "the joint angles with gain K_p (eq. 19). Its orientation stays 0: the torso faces "
        "forward while the waist joint turns the hips."
    ),
    "Feet (eq. 20-21)": (
        "The support foot stays on its foothold; the swing foot follows a cubic from the old "
        "to the new foothold with zero velocity at both ends, plus a smooth lift (eq. 20-21). "
        "The **white/coloured curve** is the path of the swing in progress; the rectangles are "
        "the planned footholds (0.30 x 0.17 m feet)."
    ),
    "Reference pelvic angle (eq. 27-33)": (
        "At each predicted sample the pelvis is put at the predicted CoM (eq. 27) and the angle "
        "is the mean over both feet of atan(k_pel dx / dy) (eq. 28-33), signed so each hip "
        "turns **toward its own foot**. The **yellow hip lines** show it over the horizon."
    ),
    "Pelvic-rotation MPC (eq. 34-38)": (
        "A double integrator theta'' = u tracks the reference with weight **alpha_pel** and "
        "penalises u with **beta_pel**, with |theta| under the angle limit (eq. 34-38). The "
        "**orange hip lines** are its optimised angles: it starts turning *before* the swing."
    ),
    "QP inverse kinematics (eq. 39-40)": (
        "13 joint velocities (waist yaw + two legs) make the feet follow their paths: "
        "min ||J q' - x'_feet||^2 with joint and speed limits (eq. 39-40). The waist rate is "
        "pinned to 0 (fixed), free (redundancy) or the MPC's rate (mpc). The **leg colours** "
        "show the reach: hip-to-ankle distance / leg length, red near 1 (straight knee)."
    ),
    "Arm swing (eq. 41-43)": (
        "The arms cancel the legs' yaw momentum: min omega1 (h_low + h_up)^2 + omega2 "
        "||q_up0 - q_up||^2 + omega3 ||q'_up||^2 on the centroidal momentum matrix "
        "(eq. 41-43). The **arrow** at the CoM is the whole-body yaw momentum."
    ),
    "Energy and kappa (eq. 44-45)": (
        "Energy = sum of the positive joint work per two-step window (eq. 44). kappa(J) is the "
        "condition number of the leg Jacobian (eq. 45): it shoots up as a knee straightens."
    ),
    "Kinematic analysis (eq. 1-5)": (
        "Static step limit of a stretched leg: sqrt(l_leg^2 - z0^2) (eq. 4, 0.31 m); turning "
        "the pelvis moves the forward hip ahead by up to l_pel/2 (eq. 2, 5): 0.42 m, +35 %. "
        "Use the slider below the lesson to turn the pelvis."
    ),
}

PLOTS = (  # (plot row column, title)
    ("waist_deg", "Waist yaw [deg]"),
    ("waist_rate_deg_s", "Waist yaw rate [deg/s]"),
    ("yaw_momentum", "Yaw momentum [kg m^2/s]"),
    ("kappa", "kappa(J) (eq. 45)"),
    ("energy_two_step", "Energy, last two steps [J] (eq. 44)"),
)


def _label(meta: dict[str, Any]) -> str:
    unit = meta.get("unit")
    return f"{meta['label']} [{unit}]" if unit else str(meta["label"])


def _css(rgb: tuple[int, int, int]) -> str:
    return f"rgb({rgb[0]}, {rgb[1]}, {rgb[2]})"


class ControlPanel:
    """All the viser GUI of the live tool; writes intent into ``live``."""

    def __init__(self, server: viser.ViserServer, live: LiveSim, scene: SceneView):
        self.server = server
        self.live = live
        self.scene = scene
        self._local = threading.local()  # .reflecting: True inside reflect() on that thread
        self._reflected_version = -1
        self.controls: dict[tuple[str, str], Any] = {}
        self.method_boxes: dict[str, Any] = {}
        self.plots: dict[str, Any] = {}
        self._plot_methods: tuple[str, ...] = ()
        self._plot_clock = -1.0
        gui = server.gui
        gui.configure_theme(control_layout="fixed", control_width="large", dark_mode=False,
                            show_logo=False, show_share_button=False)
        gui.add_markdown(
            "**Pelvic rotation with MPC** (Park & Park 2022): robots walking side by side, "
            "same parameters, different pelvis strategies."
        )
        tabs = gui.add_tab_group()
        with tabs.add_tab("Controls"):
            self._build_controls()
        with tabs.add_tab("Plots"):
            self.plot_folder = gui.add_folder("Live plots (one line per method)")
        with tabs.add_tab("Learn"):
            self._build_learn()

    # -- building ------------------------------------------------------------------------
    def _guarded(self) -> bool:
        return getattr(self._local, "reflecting", False)

    def _build_controls(self) -> None:
        gui = self.server.gui
        intent = self.live.intent
        with gui.add_folder("Presets"):
            for name in PRESETS:
                button = gui.add_button(name)
                button.on_click(lambda _e, name=name: self.apply_preset(name))
        for folder, fields in PARAM_FOLDERS.items():
            with gui.add_folder(folder, expand_by_default=folder == "Walk"):
                for group, name in fields:
                    self._add_param(group, name, getattr(getattr(intent.params, group), name))
        with gui.add_folder("Compare"):
            for method in METHODS:
                box = gui.add_checkbox(METHOD_INFO[method].title, method in intent.methods)
                box.on_update(lambda _e: self._methods_changed())
                self.method_boxes[method] = box
        with gui.add_folder("Playback"):
            self.pause_button = gui.add_button("Pause", icon=viser.Icon.PLAYER_PAUSE)
            self.pause_button.on_click(lambda _e: self._toggle_pause())
            step = gui.add_button("Step one tick (5 ms)", icon=viser.Icon.PLAYER_TRACK_NEXT)
            step.on_click(lambda _e: self.live.step())
            self.speed = gui.add_slider("Speed [x real time]", SPEED_MIN, SPEED_MAX, 0.1,
                                        intent.speed)
            self.speed.on_update(lambda _e: self._speed_changed())
            reset = gui.add_button("Reset robots", icon=viser.Icon.REFRESH)
            reset.on_click(lambda _e: self.live.reset())
            self.status = gui.add_markdown("starting...")
        with gui.add_folder("Layers", expand_by_default=False):
            self.layer_boxes = {}
            for key, label in LAYERS.items():
                box = gui.add_checkbox(label, True)
                box.on_update(lambda _e, key=key: self._layer_changed(key))
                self.layer_boxes[key] = box
            follow = gui.add_checkbox("Follow the robots", True)
            follow.on_update(lambda _e: setattr(self.scene, "follow", follow.value))

    def _add_param(self, group: str, name: str, value: Any) -> None:
        gui = self.server.gui
        meta = spec(type(getattr(live_params(), group)))[name]
        label = _label(meta)
        if meta["type"] == "bool":
            handle = gui.add_checkbox(label, bool(value))
        else:
            lo, hi, step = meta["min"], meta["max"], meta["step"]
            if (hi - lo) / step <= MAX_SLIDER_POSITIONS:
                handle = gui.add_slider(label, lo, hi, step, value)
            else:
                handle = gui.add_number(label, value, min=lo, max=hi, step=step,
                                        hint=f"{lo:g} .. {hi:g}")
        handle.on_update(lambda _e, g=group, n=name, h=handle: self._param_changed(g, n, h))
        self.controls[(group, name)] = handle

    def _build_learn(self) -> None:
        gui = self.server.gui
        with gui.add_folder("Explain"):
            self.lesson_choice = gui.add_dropdown("Layer", tuple(EXPLAIN), initial_value="Overview")
            self.lesson = gui.add_markdown(EXPLAIN["Overview"])
            self.lesson_choice.on_update(
                lambda _e: setattr(self.lesson, "content", EXPLAIN[self.lesson_choice.value])
            )
        with gui.add_folder("Kinematic analysis (Fig. 1-2, eq. 1-5)"):
            self.theta_slider = gui.add_slider("Pelvic angle [deg]", 0.0, 45.0, 1.0, 0.0)
            self.analysis_view = gui.add_html(analysis_svg(0.0))
            self.theta_slider.on_update(
                lambda _e: setattr(self.analysis_view, "content",
                                   analysis_svg(self.theta_slider.value))
            )

    # -- callbacks (write intent only) -----------------------------------------------------
    def _param_changed(self, group: str, name: str, handle: Any) -> None:
        if self._guarded():
            return
        value = handle.value
        if getattr(getattr(self.live.intent.params, group), name) == value:
            return
        try:
            self.live.update_params(**{group: {name: value}})
        except ValueError as exc:
            self.status.content = f"**Not applied:** {html.escape(str(exc))}"
            self._reflected_version = -1  # put the control back at the value in force

    def _methods_changed(self) -> None:
        if self._guarded():
            return
        chosen = [m for m, box in self.method_boxes.items() if box.value]
        if not chosen:
            self.status.content = "**Choose at least one method.**"
            self._reflected_version = -1
            return
        self.live.set_methods(chosen)

    def _speed_changed(self) -> None:
        if self._guarded() or self.speed.value == self.live.intent.speed:
            return
        self.live.set_speed(self.speed.value)

    def _toggle_pause(self) -> None:
        if self.live.intent.paused:
            self.live.resume()
        else:
            self.live.pause()

    def _layer_changed(self, key: str) -> None:
        self.scene.layers[key] = self.layer_boxes[key].value
        self.scene.apply_layers()

    def apply_preset(self, name: str) -> None:
        """Apply one of :data:`PRESETS` (parameters, and methods if it names them)."""
        preset = PRESETS[name]
        groups = {k: v for k, v in preset.items() if k not in ("methods", "reset_groups")}
        if preset.get("reset_groups"):
            self.live.set_params(live_params().replace(**groups))
        else:
            self.live.update_params(**groups)
        if "methods" in preset:
            self.live.set_methods(preset["methods"])

    # -- reflecting the intent and the frames (display thread) ---------------------------
    def reflect(self, frame: LiveFrame | None) -> None:
        """Move the controls to the intent in force (e.g. after ``PUT /api/params``)."""
        intent = self.live.intent
        if intent.version != self._reflected_version:
            self._local.reflecting = True
            try:
                self._reflect_params(intent.params)
                for method, box in self.method_boxes.items():
                    box.value = method in intent.methods
                self.speed.value = intent.speed
                self.pause_button.label = "Resume" if intent.paused else "Pause"
                self.pause_button.icon = (
                    viser.Icon.PLAYER_PLAY if intent.paused else viser.Icon.PLAYER_PAUSE
                )
            finally:
                self._local.reflecting = False
            self._reflected_version = intent.version
        if frame is not None:
            self._update_status(frame)
            self._update_plots(frame)

    def _reflect_params(self, params: ControllerParams) -> None:
        for (group, name), handle in self.controls.items():
            value = getattr(getattr(params, group), name)
            if handle.value != value:
                handle.value = value

    def _update_status(self, frame: LiveFrame) -> None:
        rtf = frame.realtime_factor
        lines = [
            "**Paused**" if frame.paused else f"Running at {frame.speed:g}x",
            f"real-time factor {rtf:.2f}" if rtf is not None else "real-time factor -",
        ]
        for r in frame.robots:
            state = "fallen" if r.fell else f"step {max(r.step_index, 0)}"
            lines.append(f"{r.method}: t {r.t:.1f} s, {state}, {r.step_length:.2f} m, "
                         f"falls {r.falls}, walks {r.walks_completed}")
        text = "  \n".join(lines)
        if self.status.content != text and not self.status.content.startswith("**Not"):
            self.status.content = text

    def _update_plots(self, frame: LiveFrame) -> None:
        methods = tuple(r.method for r in frame.robots)
        if methods != self._plot_methods:
            self._build_plots(methods)
        if abs(frame.clock - self._plot_clock) < 0.2 and not frame.paused:  # ~5 Hz
            return
        self._plot_clock = frame.clock
        window = self.live.history.window(PLOT_WINDOW_S, until=frame.clock)
        clock = window.column(methods[0], "clock") if methods else np.zeros(0)
        if len(clock) < 2:
            return
        x = clock - frame.clock
        for col, handle in self.plots.items():
            ys = []
            for m in methods:
                y = window.column(m, col)
                ys.append(y if len(y) == len(x) else np.full(len(x), np.nan))
            handle.data = (x, *ys)

    def _build_plots(self, methods: tuple[str, ...]) -> None:
        for handle in self.plots.values():
            handle.remove()
        self.plots = {}
        series = (
            viser.uplot.Series(label="t - now [s]"),
            *(viser.uplot.Series(label=m, stroke=_css(METHOD_INFO[m].color), width=2)
              for m in methods),
        )
        empty = tuple(np.zeros(2) for _ in range(len(methods) + 1))
        with self.plot_folder:
            for col, title in PLOTS:
                self.plots[col] = self.server.gui.add_uplot(
                    data=empty, series=series, title=title, aspect=1.8,
                    scales={"x": viser.uplot.Scale(time=False, range=(-PLOT_WINDOW_S, 0.0))},
                )
        self._plot_methods = methods


def analysis_svg(theta_deg: float) -> str:
    """Top view of the pelvis turned by ``theta_deg`` and the static step limit (eq. 1-5)."""
    from controller.analysis import hip_points_for_angle, kinematic_analysis, reachable_step

    ka = kinematic_analysis()
    l_leg, z0, l_pel = ka["l_leg"], ka["z0"], ka["l_pel"]
    step0 = reachable_step(l_leg, z0, l_pel, 0.0)
    step = reachable_step(l_leg, z0, l_pel, theta_deg)
    hx = hip_points_for_angle(theta_deg, l_pel)  # (2,) x of left, right hip [m]
    hy = 0.5 * l_pel * math.cos(math.radians(theta_deg))
    scale, ox, oy = 300.0, 70.0, 95.0  # px per m, origin (pelvis centre) in px

    def px(x: float, y: float) -> tuple[float, float]:
        return ox + scale * x, oy - scale * y

    (lx, ly), (rx, ry) = px(hx[0], hy), px(hx[1], -hy)
    foot0, foot1 = px(step0, -0.12), px(step, -0.12)
    rear = px(0.0, -0.12)
    return f"""
<svg viewBox="0 0 320 198" width="100%" xmlns="http://www.w3.org/2000/svg"
     style="font: 11px sans-serif; background: #f6f7f9; border-radius: 6px">
  <text x="8" y="16">top view, walking to the right; pelvis turned {theta_deg:.0f} deg</text>
  <line x1="{lx:.1f}" y1="{ly:.1f}" x2="{rx:.1f}" y2="{ry:.1f}" stroke="#444" stroke-width="6"
        stroke-linecap="round"/>
  <circle cx="{lx:.1f}" cy="{ly:.1f}" r="6" fill="#4682ff"/>
  <circle cx="{rx:.1f}" cy="{ry:.1f}" r="6" fill="#ff5050"/>
  <line x1="{rear[0]:.1f}" y1="{rear[1] + 8:.1f}" x2="{foot0[0]:.1f}" y2="{foot0[1] + 8:.1f}"
        stroke="#999" stroke-width="3"/>
  <line x1="{rear[0]:.1f}" y1="{rear[1] + 22:.1f}" x2="{foot1[0]:.1f}" y2="{foot1[1] + 22:.1f}"
        stroke="#28b464" stroke-width="3"/>
  <text x="8" y="{rear[1] + 12:.1f}">eq. 4</text>
  <text x="8" y="{rear[1] + 26:.1f}">eq. 5</text>
  <text x="{foot0[0] + 4:.1f}" y="{foot0[1] + 12:.1f}">{step0:.3f} m</text>
  <text x="{foot1[0] + 4:.1f}" y="{foot1[1] + 26:.1f}">{step:.3f} m
    (+{100 * (step / step0 - 1):.0f} %)</text>
  <text x="8" y="176">hip advance {1000 * (hx[1] - hx[0]):.0f} mm (eq. 2)</text>
  <text x="8" y="191">l_leg {l_leg} m, z0 {z0} m, l_pel {l_pel} m</text>
</svg>"""
