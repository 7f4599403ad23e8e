"""The viser control panel of one view: playback and timeline, views, comparison, presets,
parameters, push, layers; and the Inspect, Plots and Learn tabs.

The Compare folder shows the session's robots (a strategy, its own settings, a label: two may
run one strategy) and adds, removes and relabels them; a refusal (a bad setting, a label taken,
more than six robots, no room in the workers) is said there in one line and the session keeps
its robots. "Sliders act on" chooses what the parameter sliders show and set: the value every
robot shares (``update_params``), or one robot's own settings (``update_params(target=KEY)``).
A strategy's own parameters (its ``Params``) get a folder of sliders each, shown while a robot
of that strategy is; the paper's parameters a built-in strategy owns stay in the paper's
folders.

Every control only writes intent into the view's session (never the simulation). The
parameter folders are generated from :func:`controller.params.spec` (a new gain in
controller/params.py appears here): weights spanning decades get a log-scale slider with the
paper's value marked, every control says whether it acts on the next tick or from the next
step, and settings known to break walking are explained when chosen (:func:`warnings_for`).

The panel also *reflects* the intent (a ``PUT /api/params`` moves the sliders): assigning a
value from Python fires the control's callback synchronously in viser, so :meth:`reflect`
marks its own thread as reflecting and the callbacks ignore what they receive there; a
callback that receives the value already in force does nothing either, so nothing can loop.
The status line and the timeline read the session's one account of its playback
(:meth:`~app.live.session.SessionView.playback`), as ``GET /api/state`` does.

A *read-only* panel (a student's, when an instructor drives the shared demo) disables every
control that would change the session; what is the viewer's own (camera, layers, plots,
inspector, recording, the Learn tab's explanations) stays enabled.
"""

from __future__ import annotations

import html
import math
import re
import threading
import time
from typing import TYPE_CHECKING, Any

import viser

from app.live import FALL_HOLD_S, SPEED_MAX, SPEED_MIN, LiveFrame, Playback, live_params
from app.live.intent import PUSH_DURATION_MAX, PUSH_FORCE_MAX
from app.live.pool import PoolFull
from app.web.camera import CAMERA_VIEWS
from app.web.learn_gui import LearnTab
from app.web.lessons import PRESETS, warnings_for
from app.web.looks import looks, value_text
from app.web.overlays import COLOUR_NAMES, DANGER, legend_html
from app.web.plots import HorizonInspector, LivePlots
from app.web.qp_view import QpView
from app.web.record_gui import RecordFolder
from app.web.scene import LAYERS, SLOW_STRATEGY_MS, fall_note
from controller import strategy
from controller.params import GROUP_TITLES, GROUPS, OWN_PARAMS, ControllerParams, spec
from pelvic_walk.core import robots as robots_
from pelvic_walk.core.methods import METHOD_INFO
from pelvic_walk.core.robots import Robot

if TYPE_CHECKING:
    from app.web.host import ViewHost

STATUS_HZ = 2.0  # status text refreshes per second while running
MESSAGE_S = 10.0  # [s] a one-off message (a refusal, a push done) stays in the status area
READ_ONLY_NOTE = (
    "**The instructor drives this demo.** The controls that change the robots are off "
    "here; the camera, layers, plots, inspector and recording are yours."
)
REFUSED = "**Not applied:** the instructor drives this demo (your controls are read-only)."
DISABLED_SLIDER_STYLE = (  # (Mantine marks a disabled slider's track, not its root)
    "<style>.mantine-Slider-root:has(.mantine-Slider-trackContainer[data-disabled])"
    " ~ .mantine-NumberInput-root{opacity:.45;pointer-events:none}</style>"
)
# Named and seen by everyone (docs/TEACHING.md, "Accessibility"): viser's default blue
# (#228be6) under white button text, as outline buttons' text, and Mantine's grey "dimmed"
# labels (#868e96) are below 4.5:1 on white. A darker brand colour (its buttons' shade
# #1c63d5: 5.5:1) and darker dimmed text (#495057: 8.2:1) through the theme's CSS variables;
# a focus ring a keyboard user sees on every control.
BRAND_COLOR = (20, 70, 150)
THEME: dict[str, Any] = {
    "control_width": "large",
    "dark_mode": False,
    "show_logo": False,
    "show_share_button": False,
    "brand_color": BRAND_COLOR,
}
A11Y_STYLE = (
    "<style>:root[data-mantine-color-scheme],:root{--mantine-color-dimmed:#495057}"
    ".mantine-focus-auto:focus-visible,[role=slider]:focus-visible,[role=tab]:focus-visible"
    "{outline:3px solid #1c63d5 !important;outline-offset:2px}</style>"
)
MAX_SLIDER_POSITIONS = 2000  # above this many steps a number box replaces a linear slider
ALL_ROBOTS = "all robots"  # the sliders' target: the shared value of every robot
SETTINGS_EXAMPLE = "com.horizon=0.8, pelvis.k_pel=0.45"
SETTINGS_HINT = (
    f"Its own settings, e.g. {SETTINGS_EXAMPLE}: NAME=VALUE, comma-separated. A NAME is "
    "GROUP.NAME as in the Controls' folders ("
    + ", ".join(f"{g}: {t}" for g, t in GROUP_TITLES.items())
    + "), or the name alone when one group has it (k_pel). Empty: the shared values."
)
PUSH_DIRECTIONS = {
    "left (+y)": (0.0, 1.0),
    "right (-y)": (0.0, -1.0),
    "forward (+x)": (1.0, 0.0),
    "backward (-x)": (-1.0, 0.0),
}


def _label(meta: dict[str, Any]) -> str:
    unit = meta.get("unit")
    return f"{meta['label']} [{unit}]" if unit else str(meta["label"])


def _hint(meta: dict[str, Any]) -> str:
    when = (
        "from the next step (the footsteps are re-planned)"
        if meta.get("applies") == "step"
        else "on the next tick"
    )
    extra = f"; {meta['help']}" if meta.get("help") else ""
    paper = f"; paper: {meta['paper']:g}" if meta.get("paper") is not None else ""
    return f"Acts {when}{paper}{extra}."


def target_note(target: str, why: str = "") -> str:
    """What the sliders act on, in words (under the "Sliders act on" dropdown), after ``why``
    they changed if they did not change by hand ("k_pel 0.45 was removed")."""
    said = f"{_md(why)}. " if why else ""
    if target == ALL_ROBOTS:
        return (
            f"{said}The sliders show and set the value **every robot** shares (a robot's own "
            "setting of a slider you move is dropped)."
        )
    return (
        f"{said}The sliders show and set **{_md(target)}**'s own values only; the other "
        "robots keep theirs."
    )


def _md(text: str) -> str:
    """Text as it comes, safe in a markdown element (no HTML; quotes kept as they are)."""
    return html.escape(str(text), quote=False)


NOTE_CHARS = 160  # a message in the Compare folder: about three lines of the panel


def short_message(text: str) -> str:
    """A refusal as the Compare folder shows it: its first sentence, a long list in it cut
    to its first two items ("(one of: walk.step_length, walk.step_time, ...)"), at most
    :data:`NOTE_CHARS` characters; a long message would push the form down the panel."""
    first = re.split(r"(?<=[.!?])\s+(?=[A-Z])", str(text).strip(), maxsplit=1)[0]

    def cut(m: re.Match[str]) -> str:
        items = m.group(2).split(", ")
        return m.group(0) if len(items) <= 3 else f"({m.group(1)}{', '.join(items[:2])}, ...)"

    first = re.sub(r"\(([\w ]+: )?([^()]*)\)", cut, first)
    return first if len(first) <= NOTE_CHARS else first[: NOTE_CHARS - 3].rstrip() + "..."


def strategy_titles() -> tuple[str, ...]:
    """The strategies a robot may run, by their titles ("pelvic MPC"), in the registry's
    order (the Add form's dropdown; :func:`strategy_of` maps a title back)."""
    return tuple(METHOD_INFO[n].title for n in strategy.names())


def strategy_of(title: str) -> str:
    """The strategy's name of a title :func:`strategy_titles` shows (a name as it is)."""
    return next((n for n in strategy.names() if METHOD_INFO[n].title == title), title)


def robot_names(shown: tuple[Robot, ...]) -> tuple[str, ...]:
    """The robots as the dropdowns name them: by their titles as the scene and legends show
    them ("pelvic MPC", "short horizon"), or by their keys if two titles were alike."""
    look = looks((r.key, r.strategy) for r in shown)
    titles = tuple(look[r.key].title for r in shown)
    return (
        titles
        if len(set(titles)) == len(titles) and ALL_ROBOTS not in titles
        else tuple(r.key for r in shown)
    )


def robots_html(shown: tuple[Robot, ...]) -> str:
    """The robots shown, one a line: marker in its colour, label, strategy, own settings."""
    look = looks((r.key, r.strategy) for r in shown)
    lines = []
    for r in shown:
        lk = look[r.key]
        what = METHOD_INFO[r.strategy].title if r.strategy in METHOD_INFO else r.strategy
        own = ", ".join(value_text(k, v) for k, v in r.overrides)
        about = ", ".join(x for x in (what if what != lk.title else "", own) if x)
        lines.append(
            f"<span aria-hidden='true' style='color:rgb{lk.color}'>{lk.marker}</span> "
            f"<b>{html.escape(lk.title)}</b>" + (f": {html.escape(about)}" if about else "")
        )
    return (
        "<div class='robots-shown' style='font-size:12.5px;line-height:1.6'>Robots shown:<br>"
        + "<br>".join(lines)
        + "</div>"
    )


class ControlPanel:
    """All the GUI of one view; writes intent into ``view.session``."""

    def __init__(self, gui: Any, view: ViewHost):
        self.gui = gui
        self.view = view
        self._local = threading.local()  # .reflecting: True inside reflect() on that thread
        self._reflected_version = -1
        # control key -> the intent's value last put in that control (see _put)
        self._reflected: dict[Any, Any] = {}
        self._session_id = id(view.session)
        self.controls: dict[tuple[str, str], tuple[Any, bool]] = {}  # -> (handle, log scale)
        self.metas: dict[tuple[str, str], dict[str, Any]] = {}
        self.method_boxes: dict[str, Any] = {}
        self.read_only = bool(getattr(view, "read_only", False))
        self.writers: list[Any] = []  # the controls that change the session
        self._message: str | None = None  # a one-off message in the status area
        self._target: str | None = None  # the key of the robot the sliders act on (None: all)
        self._message_at = -math.inf  # time.monotonic() when it was said (shown MESSAGE_S)
        self._status_time = -math.inf
        gui.main_panel.dock_right()  # docked, not floating over the scene (viser's default)
        gui.configure_theme(**THEME)
        notice = "  \n".join(
            x for x in (view.notice, READ_ONLY_NOTE if self.read_only else None) if x
        )
        # viser greys a disabled slider but not the number box beside it, which then looks
        # as if typing in it would act: grey that box too and let it take no clicks
        style = gui.add_html(DISABLED_SLIDER_STYLE + A11Y_STYLE)
        self.notice = gui.add_markdown(notice)
        self.notice.visible = bool(notice)
        self.status = gui.add_markdown("starting...")
        tabs = gui.add_tab_group()
        self._top = (style, self.notice, self.status, tabs)  # everything else is inside
        with tabs.add_tab("Controls", viser.Icon.ADJUSTMENTS):
            self._build_controls()
        with tabs.add_tab("Inspect", viser.Icon.CHART_LINE):
            self.inspector = HorizonInspector(gui)
            self.qp_view = QpView(gui, self.inspector)
        with tabs.add_tab("Plots", viser.Icon.CHART_DOTS):
            self.plots = LivePlots(gui, view.session)
        with tabs.add_tab("Learn", viser.Icon.SCHOOL):
            self.learn = LearnTab(gui, self)
        if self.read_only:
            for handle in self.writers:
                handle.disabled = True

    @property
    def session(self):
        return self.view.session

    def hide(self) -> None:
        """Hide the whole panel (a new one replaces it on the same page). Hidden, not removed:
        viser's client applies a batch's updates after its removals, so updates sent just
        before a removal would fail on the page as "Tried to update non-existent component"."""
        for handle in self._top:
            handle.visible = False

    # -- building ------------------------------------------------------------------------
    def guarded(self) -> bool:
        """True inside :meth:`reflect`, or on a read-only panel (the change is refused, said
        once in the status area): a callback that sees True does nothing."""
        if getattr(self._local, "reflecting", False):
            return True
        if self.read_only:
            self._say(REFUSED)
            return True
        return False

    def writer(self, handle: Any) -> Any:
        """Register a control that changes the session (disabled on a read-only panel)."""
        self.writers.append(handle)
        return handle

    def _build_controls(self) -> None:
        gui = self.gui
        intent = self.session.intent
        with gui.add_folder("Playback"):
            self.pause_button = self.writer(gui.add_button("Pause", icon=viser.Icon.PLAYER_PAUSE))
            self.pause_button.on_click(lambda _e: self._toggle_pause())
            # (viser disables a button group only when it is made, not through its handle)
            self.step_row = gui.add_button_group(
                "Step", ("5 ms tick", "to lift-off", "to landing"), disabled=self.read_only
            )
            self.step_row.on_click(lambda e: self._step(e.target.value))
            self.timeline = gui.add_slider(  # enabled while paused (see reflect)
                "Timeline [s] (when paused)",
                0.0,
                1.0,
                0.005,
                1.0,
                disabled=True,
                hint="Pause, then drag to replay the recent walk (the span under the slider)",
            )
            self.timeline.on_update(lambda _e: self._seek())
            self.speed = self.writer(
                gui.add_slider("Speed [x real time]", SPEED_MIN, SPEED_MAX, 0.1, intent.speed)
            )
            self.speed.on_update(lambda _e: self._speed_changed())
            reset = self.writer(
                gui.add_button("Restart all robots together", icon=viser.Icon.REFRESH)
            )
            reset.on_click(lambda _e: self._reset())
        with gui.add_folder("View"):
            cams = gui.add_button_group("Camera", tuple(CAMERA_VIEWS))
            cams.on_click(lambda e: self.view.scene.set_camera(e.target.value, e.client))
            sticks = gui.add_checkbox(
                "Stick diagram of the last step (Fig. 11)",
                False,
                hint="hips and legs at lift-off (grey) and landing (black) of the last step",
            )
            sticks.on_update(lambda _e: self.view.scene.set_sticks(sticks.value))
            gui.add_html(legend_html())
        with gui.add_folder("Compare"):
            for method in strategy.names():  # the paper's three, then the server's own
                box = self.writer(
                    gui.add_checkbox(
                        METHOD_INFO[method].title,
                        any(r.strategy == method for r in intent.robots),
                    )
                )
                box.on_update(lambda _e: self._methods_changed())
                self.method_boxes[method] = box
            self._build_robots(intent)
        with gui.add_folder("Presets", expand_by_default=False):
            for name, preset in PRESETS.items():
                button = self.writer(gui.add_button(name, hint=preset.get("hint")))
                button.on_click(lambda _e, name=name: self.apply_preset(name))
        self.target = self.writer(
            gui.add_dropdown(
                "Sliders act on",
                (ALL_ROBOTS, *robot_names(intent.robots)),
                initial_value=ALL_ROBOTS,
                hint="All robots (a shared value: a robot's own setting of it is dropped), or "
                "one robot's own settings (the others keep theirs)",
            )
        )
        self.target.on_update(lambda _e: self._target_changed())
        self.target_note = gui.add_markdown(target_note(ALL_ROBOTS))
        for group in GROUPS:
            meta_all = spec(getattr(intent.params, group))
            with gui.add_folder(GROUP_TITLES[group], expand_by_default=group == "walk"):
                for name, meta in meta_all.items():
                    if meta.get("gui", True):
                        self._add_param(
                            group, name, meta, getattr(getattr(intent.params, group), name)
                        )
        # a strategy's own parameters (its Params): a folder each, shown with its robots
        self.own_folders: dict[str, Any] = {}
        for name, cls in OWN_PARAMS.items():
            if not strategy.is_registered(name):
                continue
            folder = gui.add_folder(
                f"{METHOD_INFO[name].title} parameters", expand_by_default=False
            )
            with folder:
                for fname, meta in spec(cls).items():
                    if meta.get("gui", True):
                        self._add_param(name, fname, meta, intent.params.value(f"{name}.{fname}"))
            folder.visible = any(r.strategy == name for r in intent.robots)
            self.own_folders[name] = folder
        with gui.add_folder("Push a robot", expand_by_default=False):
            gui.add_markdown(
                "A horizontal push on the torso. The CoM MPC keeps its plan and the pelvis "
                "(eq. 19) moves to bring the measured CoM back onto it; **nothing moves the "
                "footsteps**, so a push must be absorbed "
                "within the planned footholds: a strong one makes the robot fall (it lies where "
                f"it fell for {FALL_HOLD_S:g} s, ringed in {COLOUR_NAMES[DANGER]}, then every "
                "robot restarts)."
            )
            self.push_robot = self.writer(gui.add_dropdown("Robot", robot_names(intent.robots)))
            self.push_force = self.writer(
                gui.add_slider("Force [N]", 10.0, PUSH_FORCE_MAX, 10.0, 60.0)
            )
            self.push_dir = self.writer(
                gui.add_dropdown("Direction", tuple(PUSH_DIRECTIONS), initial_value="left (+y)")
            )
            self.push_time = self.writer(
                gui.add_slider("Duration [s]", 0.05, PUSH_DURATION_MAX, 0.05, 0.1)
            )
            go = self.writer(gui.add_button("Push", icon=viser.Icon.HAND_STOP))
            go.on_click(lambda _e: self._push())
        with gui.add_folder("Layers", expand_by_default=False):
            self.layer_boxes = {}
            for key, (label, default) in LAYERS.items():
                box = gui.add_checkbox(label, default)
                box.on_update(lambda _e, key=key: self._layer_changed(key))
                self.layer_boxes[key] = box
        self.record = RecordFolder(gui, self)

    def _build_robots(self, intent: Any) -> None:
        """The robots shown, a refusal's line, and adding, removing and relabelling one (a
        folder of its own in the Compare folder, closed at first: the parameters stay near
        the top)."""
        gui = self.gui
        self.robot_list = gui.add_html(robots_html(intent.robots))
        self.compare_note = gui.add_markdown("")
        with gui.add_folder("Add, relabel or remove a robot", expand_by_default=False):
            gui.add_markdown(
                "**Add a robot** (two may run one strategy with different settings). "
                f"Settings, for example: `{SETTINGS_EXAMPLE}`"
            )
            self.add_strategy = self.writer(
                gui.add_dropdown(
                    "Strategy",
                    strategy_titles(),
                    initial_value=METHOD_INFO[strategy.MPC].title,
                    hint="What it runs",
                )
            )
            # (viser's text box has no placeholder: the example is said above it)
            self.add_settings = self.writer(gui.add_text("Settings", "", hint=SETTINGS_HINT))
            self.add_label = self.writer(
                gui.add_text("Label", "", hint="Its name on the scene, plots and tables (optional)")
            )
            add = self.writer(gui.add_button("Add robot", icon=viser.Icon.PLUS))
            add.on_click(lambda _e: self._add_robot())
            gui.add_markdown("**Relabel or remove a robot:**")
            self.edit_robot = self.writer(
                gui.add_dropdown(
                    "Robot", robot_names(intent.robots), hint="The robot to relabel or remove"
                )
            )
            self.new_label = self.writer(gui.add_text("New label", ""))
            relabel = self.writer(gui.add_button("Relabel"))
            relabel.on_click(lambda _e: self._relabel_robot())
            remove = self.writer(gui.add_button("Remove robot", icon=viser.Icon.TRASH))
            remove.on_click(lambda _e: self._remove_robot())

    def _add_param(self, group: str, name: str, meta: dict[str, Any], value: Any) -> None:
        gui = self.gui
        label = _label(meta)
        log = bool(meta.get("log"))
        if meta.get("choices"):
            handle = gui.add_dropdown(
                label, tuple(meta["choices"]), initial_value=value, hint=_hint(meta)
            )
        elif meta["type"] == "bool":
            handle = gui.add_checkbox(label, bool(value), hint=_hint(meta))
        elif log:
            lo, hi = math.log10(meta["log_min"]), math.log10(meta["max"])
            marks: tuple[tuple[float, str], ...] | None
            marks = tuple((round(x), f"1e{round(x)}") for x in (lo, hi))
            if meta.get("paper"):
                # the paper's value at (or near) an end: one mark there, not two labels on
                # top of each other (beta_pel's paper value is its slider's lower end)
                at = math.log10(meta["paper"])
                near = [m for m in marks if abs(m[0] - at) < 0.12 * (hi - lo)]
                marks = tuple(m for m in marks if m not in near)
                marks += ((at, f"{near[0][1]} paper" if near else "paper"),)
            handle = gui.add_slider(
                f"{meta['label']}, log10",
                lo,
                hi,
                0.1,
                self._to_slider(value, meta),
                marks=marks,
                hint=_hint(meta),
            )
        else:
            lo, hi, step = meta["min"], meta["max"], meta["step"]
            marks = ((meta["paper"], "paper"),) if meta.get("paper") is not None else None
            if (hi - lo) / step <= MAX_SLIDER_POSITIONS:
                handle = gui.add_slider(label, lo, hi, step, value, marks=marks, hint=_hint(meta))
            else:
                handle = gui.add_number(label, value, min=lo, max=hi, step=step, hint=_hint(meta))
        handle.on_update(lambda _e, g=group, n=name: self._param_changed(g, n))
        self.controls[(group, name)] = (self.writer(handle), log)
        self.metas[(group, name)] = meta

    @staticmethod
    def _to_slider(value: float, meta: dict[str, Any]) -> float:
        return math.log10(max(float(value), meta["log_min"]))

    # -- callbacks (write intent only) -----------------------------------------------------
    def _say(self, message: str) -> None:
        self._message, self._message_at = message, time.monotonic()
        self._reflected_version = -1  # put the controls back at the values in force
        self._reflected.clear()  # every one, the refused value included

    def _param_changed(self, group: str, name: str) -> None:
        if self.guarded():
            return
        handle, log = self.controls[(group, name)]
        value = 10.0**handle.value if log else handle.value
        if log:
            value = float(f"{value:.3g}")
        target = self.target_key()
        if target is None and self._target is not None:  # its robot went (not drawn yet)
            self._say("**Not applied:** the robot the sliders acted on is no longer shown.")
            return
        if self.shown_params().value(f"{group}.{name}") == value:
            return
        self._reflected.pop((group, name), None)  # shown as the intent takes it (rounded)
        try:
            self.session.update_params(target=target, **{group: {name: value}})
        except ValueError as exc:
            self._say(f"**Not applied:** {html.escape(str(exc))}")

    def target_key(self) -> str | None:
        """The robot the sliders act on (its key), or None: every robot (also when that
        robot is no longer shown: the dropdown follows at the next draw)."""
        shown = {r.key for r in self.session.intent.robots}
        return self._target if self._target in shown else None

    def _aim(self, key: str | None, shown: tuple[Robot, ...], why: str = "") -> None:
        """Point the sliders at robot ``key`` (None: every robot) among ``shown``: the
        dropdown's options and text, the note under it (after ``why``, when the robots'
        change moved it), and the sliders' values."""
        names = robot_names(shown)
        self._target = key if key in {r.key for r in shown} else None
        name = (
            ALL_ROBOTS
            if self._target is None
            else names[[r.key for r in shown].index(self._target)]
        )
        was, self._local.reflecting = getattr(self._local, "reflecting", False), True
        try:
            options = (ALL_ROBOTS, *names)
            if tuple(self.target.options) != options:
                self.target.options = options
            if self.target.value != name:
                self.target.value = name
            self.target_note.content = target_note(name, why)
            for control in self.controls:
                self._reflected.pop(control, None)
            self._reflect_params(self.shown_params())
        finally:
            self._local.reflecting = was

    def key_of(self, name: str) -> str | None:
        """The key of the robot a dropdown names ``name`` (None: no such robot shown)."""
        shown = self.session.intent.robots
        return dict(zip(robot_names(shown), (r.key for r in shown), strict=True)).get(name)

    def shown_params(self) -> ControllerParams:
        """The parameters the sliders show: the shared ones, or the targeted robot's."""
        intent = self.session.intent
        key = self.target_key()
        return intent.params if key is None else intent.params_of(key)

    def _target_changed(self) -> None:
        if getattr(self._local, "reflecting", False):
            return
        # the sliders move to the values of what they act on now (the view draws again only
        # when the session changes: a paused one may not)
        self._aim(self.key_of(self.target.value), self.session.intent.robots)

    def _methods_changed(self) -> None:
        if self.guarded():
            return
        chosen = [m for m, box in self.method_boxes.items() if box.value]
        if not chosen:
            self._say("**Choose at least one method.**")
            return
        shown = self.session.intent.robots
        kept = [r for r in shown if r.strategy in chosen]
        added = [Robot(m) for m in chosen if not any(r.strategy == m for r in kept)]
        if all(r == Robot(r.strategy) for r in kept):  # plain robots: in the registry's order
            self._set_robots(None, chosen)
        else:  # robots with settings keep them; a strategy ticked joins them
            self._set_robots(kept + added)

    def _set_robots(
        self,
        shown: list[Robot] | None,
        methods: list[str] | None = None,
        refused: str = "Not applied",
    ) -> bool:
        """Show these robots (or one per strategy of ``methods``); a refusal is said in one
        line in the Compare folder, after ``refused`` (the session keeps its robots)."""
        try:
            if shown is None:
                self.session.set_methods(methods or [])
            else:
                self.session.set_robots(shown)
        except (ValueError, PoolFull) as exc:
            self._refused(refused, exc)
            self._reflected_version = -1  # the checkboxes back to the robots shown
            self._reflected.clear()
            return False
        self.compare_note.content = ""
        return True

    def _refused(self, refused: str, exc: Exception) -> None:
        self.compare_note.content = f"**{refused}:** {_md(short_message(str(exc)))}"

    def _title(self, key: str, shown: tuple[Robot, ...] | None = None) -> str:
        """A robot's name as the dropdowns show it (among ``shown``: the robots in force)."""
        shown = self.session.intent.robots if shown is None else shown
        return dict(zip((r.key for r in shown), robot_names(shown), strict=True)).get(key, key)

    def _add_robot(self) -> None:
        if self.guarded():
            return
        settings = self.add_settings.value.strip().strip(",")
        name = strategy_of(self.add_strategy.value)
        try:
            parsed = robots_.parse(",".join(x for x in (name, settings) if x))
            new = robots_.make(parsed.strategy, parsed.overrides, self.add_label.value)
        except ValueError as exc:
            self._refused("Not added", exc)
            return
        shown = [*self.session.intent.robots, new]
        if self._set_robots(shown, refused="Not added"):
            self.add_label.value = ""
            self.add_settings.value = ""
            self.compare_note.content = (
                f"Added **{_md(self._title(new.key, tuple(shown)))}**; all robots restarted "
                "together, on one clock."
            )

    def _remove_robot(self) -> None:
        if self.guarded():
            return
        key = self.key_of(self.edit_robot.value)
        if key is None:
            self.compare_note.content = "**Not removed:** choose a robot shown."
            return
        title = self._title(key)
        shown = [r for r in self.session.intent.robots if r.key != key]
        if self._set_robots(shown, refused="Not removed"):
            self.compare_note.content = f"Removed **{_md(title)}**; the others restarted together."
            if self._target == key:  # the sliders act on every robot again, and say so
                self._aim(None, tuple(shown), f"{title} was removed")

    def _relabel_robot(self) -> None:
        if self.guarded():
            return
        key, label = self.key_of(self.edit_robot.value), self.new_label.value.strip()
        try:
            if key is None:
                raise ValueError("choose a robot shown")
            robot = self.session.intent.robot(key)
            if not label:
                raise ValueError("type the new label first")
            new = robots_.make(robot.strategy, robot.overrides, label)
        except ValueError as exc:
            self._refused("Not relabelled", exc)
            return
        title = self._title(key)
        shown = [new if r.key == key else r for r in self.session.intent.robots]
        if self._set_robots(shown, refused="Not relabelled"):
            self.new_label.value = ""
            new_title = self._title(new.key, tuple(shown))
            self.compare_note.content = (
                f"Relabelled **{_md(title)}** as **{_md(new_title)}**; all robots restarted "
                "together."
            )
            if self._target == key:  # the sliders keep acting on the same robot
                self._aim(new.key, tuple(shown), f"{title} is now {new_title}")

    def _speed_changed(self) -> None:
        if self.guarded() or self.speed.value == self.session.intent.speed:
            return
        self._reflected.pop("speed", None)
        self.session.set_speed(self.speed.value)

    def _reset(self) -> None:
        if self.guarded():
            return
        self.session.reset()

    def _toggle_pause(self) -> None:
        if self.guarded():
            return
        if self.session.intent.paused:
            self.session.resume()
        else:
            self.session.pause()

    def _step(self, which: str) -> None:
        if self.guarded():
            return
        until = {"5 ms tick": "tick", "to lift-off": "liftoff", "to landing": "landing"}[which]
        self.session.step(until)

    def _seek(self) -> None:
        if self.guarded() or not self.session.intent.paused:
            return
        self._reflected.pop("timeline", None)  # rests at the kept instant nearest the drag
        try:
            self.session.seek(float(self.timeline.value))
        except ValueError as exc:
            self._say(html.escape(str(exc)))

    def _push(self) -> None:
        if self.guarded():
            return
        dx, dy = PUSH_DIRECTIONS[self.push_dir.value]
        f = float(self.push_force.value)
        key = self.key_of(self.push_robot.value) or str(self.push_robot.value)
        try:
            self.session.push(key, (f * dx, f * dy), float(self.push_time.value))
        except ValueError as exc:
            self._say(f"**Not pushed:** {html.escape(str(exc))}")
            return
        self._message_at = time.monotonic()
        self._message = (
            f"Pushed **{self.push_robot.value}** {self.push_dir.value} with "
            f"{f:.0f} N for {self.push_time.value:.2f} s."
        )

    def _layer_changed(self, key: str) -> None:
        self.view.scene.set_layer(key, self.layer_boxes[key].value)

    def apply_preset(self, name: str) -> None:
        """Apply one of :data:`PRESETS`: parameters (and methods); restart the robots together
        so side-by-side robots compare the same instants."""
        if self.guarded():
            return
        preset = PRESETS[name]
        groups = {k: v for k, v in preset.items() if k in GROUPS}
        base = live_params() if preset.get("reset_groups") else self.session.intent.params
        self.session.set_params(base.replace(**groups))
        if "methods" in preset:
            self.session.set_methods(preset["methods"])
        self.session.reset()

    # -- reflecting the intent and the frames (display thread) ---------------------------
    def reflect(self, frame: LiveFrame | None, now: float) -> None:
        """Move the controls to the intent in force; update status, timeline and plots."""
        session = self.session
        intent = session.intent
        if id(session) != self._session_id:  # the view switched sessions
            self._session_id = id(session)
            self.plots.session = session
            self._reflected_version = -1
            self._reflected.clear()
        if intent.version != self._reflected_version:
            self._local.reflecting = True
            try:
                self._reflect_robots(intent)
                self._reflect_params(self.shown_params())
                for method, box in self.method_boxes.items():
                    self._put(
                        ("method", method), box, any(r.strategy == method for r in intent.robots)
                    )
                self.push_robot.options = robot_names(intent.robots)
                self._put("speed", self.speed, intent.speed)
                self.pause_button.label = "Resume" if intent.paused else "Pause"
                self.pause_button.icon = (
                    viser.Icon.PLAYER_PLAY if intent.paused else viser.Icon.PLAYER_PAUSE
                )
                self.timeline.disabled = self.read_only or not intent.paused
            finally:
                self._local.reflecting = False
            self._reflected_version = intent.version
        if frame is not None:
            playback = session.playback()
            if playback.paused or now - self._status_time >= 1.0 / STATUS_HZ:
                self._status_time = now
                self._update_status(frame, playback, intent)
                self._update_timeline(playback)
            self.plots.update(frame, now)
            self.inspector.update(frame, now)
            self.qp_view.update(frame, now, playback.paused)
            self.learn.update(frame, now)

    def _put(self, key: Any, handle: Any, value: Any) -> None:
        """Move a control to the intent's ``value`` if that value changed since it was last
        put there. viser sets a control's value when the viewer moves it and runs its
        callback later, on another thread: an intent change in between (a restart, the time
        base moving on a busy machine) must not set the control back and lose the move."""
        if key in self._reflected and self._reflected[key] == value:
            return
        self._reflected[key] = value
        if handle.value != value:
            handle.value = value

    def _reflect_robots(self, intent: Any) -> None:
        """The robots shown: their list, the dropdowns naming them, the own-parameter
        folders of their strategies. The sliders' target is a robot's key, not the text its
        dropdown showed: when that robot is gone (removed or relabelled elsewhere: another
        view, the API), they act on every robot again and the note says why."""
        keys = robot_names(intent.robots)
        gone = self._target is not None and self.target_key() is None
        if gone or tuple(self.target.options) != (ALL_ROBOTS, *keys):
            why = f"{self.target.value} is no longer shown" if gone else ""
            self._aim(self.target_key(), intent.robots, why)
        if tuple(self.edit_robot.options) != keys:
            self.edit_robot.options = keys
        content = robots_html(intent.robots)
        if self.robot_list.content != content:
            self.robot_list.content = content
        for name, folder in self.own_folders.items():
            visible = any(r.strategy == name for r in intent.robots)
            if folder.visible != visible:
                folder.visible = visible

    def _reflect_params(self, params: ControllerParams) -> None:
        for (group, name), (handle, log) in self.controls.items():
            value = params.value(f"{group}.{name}")
            meta = self.metas[(group, name)]
            self._put((group, name), handle, self._to_slider(value, meta) if log else value)

    def _update_timeline(self, playback: Playback) -> None:
        """The timeline spans what is kept (running or paused) and rests at the instant shown
        (the present while running)."""
        if playback.kept is None or playback.clock is None:
            return
        lo, hi = (
            round(playback.kept[0], 3),
            round(max(playback.kept[1], playback.kept[0] + 0.01), 3),
        )
        value = min(max(playback.clock, lo), hi)
        self._local.reflecting = True
        try:
            if (self.timeline.min, self.timeline.max) != (lo, hi):
                self.timeline.min, self.timeline.max = lo, hi
            self._put("timeline", self.timeline, value)  # not over a drag not yet sought
        finally:
            self._local.reflecting = False

    def _update_status(self, frame: LiveFrame, playback: Playback, intent: Any) -> None:
        lines = [playback.describe()]
        look = looks(frame.robots)
        for r in frame.robots:
            if r.error is not None:
                lines.append(
                    f"**{look[r.method].title}**: ⚠ stopped: `{r.error}`; it restarts "
                    "with the others (or press *Restart all robots together*)"
                )
                continue
            if r.fell:
                when, why, restart = fall_note(r, frame)
                lines.append(f"**{look[r.method].title}**: ⚠ fell {when}, {why}; {restart}")
                continue
            elif r.waiting:
                state = "standing by to start in phase"
            elif r.finished:
                state = "walked its whole plan"
            else:
                state = f"step {max(r.step_index, 0)}, {r.step_length:.2f} m"
            kappa = (  # no "kappa -" while there is nothing to measure (standing by)
                f"kappa {kappa_text(r.kappa_legs)}, " if math.isfinite(r.kappa_legs) else ""
            )
            slow = (
                f", ⚠ its strategy takes {r.strategy_ms:.1f} ms a tick (more than the "
                f"{r.params.control_dt * 1e3:g} ms tick: it cannot keep real time)"
                if r.strategy_ms > SLOW_STRATEGY_MS
                else ""
            )
            lines.append(
                f"**{look[r.method].title}**: {r.status}, {kappa}{state}, falls {r.falls}{slow}"
            )
        lines += [f"⚠ {w}" for w in robot_warnings(intent)]
        extra = self.view.alerts()
        if self._message and time.monotonic() - self._message_at < MESSAGE_S:
            extra.append(self._message)
        text = "  \n".join(extra + lines)
        if self.status.content != text:
            self.status.content = text


def robot_warnings(intent: Any) -> list[str]:
    """Settings known to break walking (:func:`warnings_for`): those of the shared values for
    the robots shown, then a robot's own (its settings of its own), named by its title."""
    shared = warnings_for(intent.params, tuple(r.strategy for r in intent.robots))
    out = list(shared)
    titles = robot_names(intent.robots)
    for r, title in zip(intent.robots, titles, strict=True):
        if r.overrides:
            mine = warnings_for(intent.params_of(r.key), (r.strategy,))
            out += [f"{title}: {w}" for w in mine if w not in shared]
    return out


def kappa_text(kappa: float) -> str:
    """kappa(J) for people: whole numbers up to 9999, then 1.3e+08 style (it spans decades)."""
    if not math.isfinite(kappa):
        return "-"
    return f"{kappa:.0f}" if kappa < 1e4 else f"{kappa:.1e}"
