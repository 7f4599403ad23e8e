"""The Learn tab of one view's panel: guided lessons with live numbers, the per-layer
explanations and the kinematic analysis (Fig. 1-2, eq. 1-5). The text lives in
:mod:`app.web.lessons`; this module builds the controls and reads the numbers from the frames.

A lesson button writes intent only (parameters from their defaults, its robots, a restart,
as a preset does) and moves the clicking browser's camera. Which lesson runs is the *session's*
state (:class:`LessonRun`, one per session, kept beside it on the web side): every view of
the session shows its head, text, equations and live numbers, so the students watching an
instructor's demo read the lesson the instructor started (their buttons are off). The live
numbers are computed on the display thread from the frames the views show and the session's
50 Hz plot rows: nothing under a lesson is written in advance. The "max seen" and "share of
the time" columns count from the last change (the lesson's start, a parameter, the robots
shown, a restart asked for; not the session's own restart after a fall), so a change's effect
can be read, and every view reads the same tallies (each frame is counted once, whichever
view draws it first); a fall enters no maximum (from the second before it was seen until the
restart), nor the last two steps' rows. The falls count from the last restart asked for (the
lesson's). The lesson's text follows the state (``Lesson.now``), and when the numbers cannot
follow the robots (changed by hand, waiting for a restart), the tab says so rather than
freezing.
"""

from __future__ import annotations

import html
import math
import threading
import weakref
from collections import deque
from typing import TYPE_CHECKING, Any

import numpy as np

from app.live import LiveFrame, live_params
from app.live.history import COL
from app.live.pool import PoolFull
from app.web.lessons import CLEAN_LIMIT_M, EXPLAIN, LESSONS, Lesson, analysis_html
from app.web.looks import RobotLook, looks
from controller.params import GROUPS

if TYPE_CHECKING:
    from app.live.intent import Intent
    from app.live.session import SessionView
    from app.web.host import PanelHost
    from pelvic_walk.core.frames import RobotFrame

NUMBERS_HZ = 2.0  # live-number refreshes per second while running
STATUS_COLOURS = {
    "clean": "#1e8e3e",
    "knee nearly straight": "#e8710a",
    "IK at the speed limit": "#e8710a",
    "fell": "#d93025",
    "stopped": "#d93025",
}
COLUMNS = {  # row label of each live number (Lesson.numbers)
    "status": "status now",
    "shares": "share of the time since the last change",
    "step": "step length in force",
    "falls": "falls since the lesson (or a restart asked for)",
    "reach": "leg reach now (max since the last change)",
    "kappa_legs": "kappa(J) of the legs now (max since the last change)",
    "waist": "waist yaw now (last two steps)",
    "rate": "peak waist rate, last two steps",
    "rate_now": "waist rate now",
    "jerk": "peak change of the waist rate (50 Hz)",
    "liftoff": "waist yaw at the last lift-off",
    "dsp_turn": "share of the waist's travel made in the double support (two steps)",
    "yaw": "yaw momentum now (peak, two steps)",
    "arms": "arm swing",
    "settings": "k_pel, horizon in force",
    "differ": "its settings that differ from the other robots'",
    "phase": "phase",
    "plan": "MPC angle: now → horizon end",
    "hip": "hip advance measured / eq. 2",
    "pushing": "push",
    "lateral": "CoM from the support centre (y)",
    "active": "what stops the IK: its active limits now (most seen since the last change)",
}


# the rows a robot lying fallen (or stopped) still shows: what it is, not what it measures
SHOWN_WHEN_DOWN = ("status", "falls", "step", "arms", "settings", "differ", "shares")


def _num(v: float, digits: int = 0) -> str:
    if not math.isfinite(v):
        return "-"
    return f"{v:.1e}" if abs(v) >= 1e4 else f"{v:.{digits}f}"


# [s] samples of the last second stay out of the "max since the last change" columns until
# the robot is seen not to have fallen in that time: the fall test (pelvis below half its
# height, torso over 30°) fires after the legs gave way, and the collapse before it is no
# walking pose (measured at 0.40 m, k_pel 0.45: H = 1.2 s, legs straight from 1.90 s, fall at
# 2.55 s; H = 0.8 s, from 1.02 s, fall at 1.40 s; kappa up to 1e9 in between)
FALL_LOOKBACK_S = 1.0


class _Tally:
    """What one robot did since the last change, from the frames the view showed. The maxima
    (reach, kappa, the IK's limits) leave out a fall: the frames from FALL_LOOKBACK_S before
    it until the robot's restart."""

    def __init__(self) -> None:
        self.frames = 0
        self.status: dict[str, int] = {}
        self.reach_max = -math.inf  # (shown as "-" until a frame is counted)
        self.kappa_max = -math.inf
        self.limits: dict[str, int] = {}  # the IK's active limits: frames each was seen in
        # (clock, reach, kappa, limits) of the frames not yet counted in the maxima
        self._pending: deque[tuple[float, float, float, list[str]]] = deque()

    def add(self, r: RobotFrame) -> None:
        if r.waiting or r.finished:
            self._count(math.inf)  # a walk that ended without a fall: all of it counts
            return
        self.frames += 1
        self.status[r.status] = self.status.get(r.status, 0) + 1
        if r.error is not None:  # stopped: its legs' reach and kappa say nothing
            self._count(math.inf)
            return
        if r.fell:  # lying on the floor, and in the collapse before the fall was seen
            fell = r.fell_clock if r.fell_clock is not None else r.clock
            self._count(fell - FALL_LOOKBACK_S)
            self._pending.clear()
            return
        reach = float(np.max(r.reach)) if np.all(np.isfinite(r.reach)) else math.nan
        self._pending.append((r.clock, reach, r.kappa_legs, ik_limits(r)))
        self._count(r.clock - FALL_LOOKBACK_S)

    def _count(self, before: float) -> None:
        """Count the pending frames older than session clock ``before`` in the maxima."""
        while self._pending and self._pending[0][0] < before:
            _clock, reach, kappa, limits = self._pending.popleft()
            if math.isfinite(reach):
                self.reach_max = max(self.reach_max, reach)
            if math.isfinite(kappa):
                self.kappa_max = max(self.kappa_max, kappa)
            for name in limits:
                self.limits[name] = self.limits.get(name, 0) + 1


def this_walk(rows: np.ndarray) -> np.ndarray:
    """The plot rows of a robot's walk in progress: from its newest restart (its own time
    starts again), without those it lay fallen (the fall's poses are no walk)."""
    back = np.flatnonzero(np.diff(rows[:, COL["t"]]) < 0)
    if back.size:
        rows = rows[back[-1] + 1 :]
    return rows[rows[:, COL["fell"]] != 1.0]


def ik_limits(r: RobotFrame) -> list[str]:
    """The IK's active constraints at the frame other than the waist's pin (a joint at its
    angle or speed limit: what stops the legs; controller.explain)."""
    if r.qp is None:
        return []
    return [c.name for c in r.qp["ik"].active if c.kind != "pinned"]


class LessonRun:
    """The lesson running in one session and what its robots did since the last change:
    shared by every view of the session (a lesson button replaces it)."""

    def __init__(self, lesson: Lesson, start_clock: float):
        self.lesson = lesson
        self.start_clock = start_clock  # [s] session clock the lesson's robots started at
        self.tallies: dict[str, _Tally] = {}  # since the last change
        self.since = math.inf  # [s] session clock of the last change
        self._change: tuple | None = None  # (params, robots, restarts asked for) in force
        self._change_version = 0  # the intent of the last change: frames before it not counted
        self._last_seq = -1
        self._lock = threading.Lock()  # views draw on one thread today; a lock costs nothing

    def observe(self, frame: LiveFrame, intent: Intent) -> None:
        """Start the tallies anew at a change; count ``frame`` once (whichever view shows it
        first)."""
        with self._lock:
            change = (intent.params, intent.robots, intent.reset_requests - intent.auto_restarts)
            if change != self._change:  # the "max seen" columns count from here
                first = self._change is None
                restarted = first or change[2] != self._change[2]  # type: ignore[index]
                self._change, self._change_version = change, intent.version
                self.tallies = {}
                # from the lesson's start, the robots' restart or (a new setting) now
                self.since = (
                    self.start_clock
                    if first
                    else max(frame.clock, intent.start_clock)
                    if restarted
                    else frame.clock
                )
            counted = frame.intent_version >= self._change_version and frame.clock >= self.since
            if frame.seq > self._last_seq and not frame.paused and counted:
                self._last_seq = frame.seq
                for r in frame.robots:
                    self.tallies.setdefault(r.method, _Tally()).add(r)


# The lesson each session runs (weak: it goes with its session).
_RUNS: weakref.WeakKeyDictionary[SessionView, LessonRun] = weakref.WeakKeyDictionary()


def lesson_run(session: SessionView) -> LessonRun | None:
    """The lesson ``session`` runs, or None."""
    return _RUNS.get(session)


class LearnTab:
    """The Learn tab's controls (built inside the tab by :class:`~app.web.panel.ControlPanel`)."""

    def __init__(self, gui: Any, panel: PanelHost):
        self.gui = gui
        self.panel = panel
        self.run: LessonRun | None = None  # the session's lesson this tab shows
        self._shown_time = -math.inf
        self._look: dict[str, RobotLook] = {}  # the robots' looks in the table drawn
        # a view to set once the robots are drawn (the browser that started the lesson)
        self._camera: tuple[LessonRun, str, Any] | None = None
        with gui.add_folder("Guided lessons"):
            gui.add_markdown(
                "Each button sets the parameters, the robots and the camera, and restarts the "
                "robots; the table above the lesson's text is read from them as they walk."
            )
            self.buttons = []
            for i, lesson in enumerate(LESSONS):
                button = panel.writer(gui.add_button(lesson.title))
                button.on_click(lambda e, i=i: self.start(i, e.client))
                self.buttons.append(button)
            # title, then the live numbers (seen without scrolling), then what to look for
            self.head = gui.add_html("")
            self.live = gui.add_html("")
            self.now = gui.add_html("")
            self.text = gui.add_html("")
        with gui.add_folder("Explain", expand_by_default=False):
            self.layer_choice = gui.add_dropdown(
                "Layer", tuple(EXPLAIN), initial_value=next(iter(EXPLAIN))
            )
            self.layer_text = gui.add_markdown(EXPLAIN[self.layer_choice.value])
            self.layer_choice.on_update(
                lambda _e: setattr(self.layer_text, "content", EXPLAIN[self.layer_choice.value])
            )
        with gui.add_folder("Kinematic analysis (Fig. 1-2, eq. 1-5)", expand_by_default=False):
            self.theta_slider = gui.add_slider("Pelvic angle [deg]", 0.0, 45.0, 1.0, 45.0)
            self.analysis_view = gui.add_html(analysis_html(45.0, CLEAN_LIMIT_M))
            self.theta_slider.on_update(
                lambda _e: setattr(
                    self.analysis_view,
                    "content",
                    analysis_html(self.theta_slider.value, CLEAN_LIMIT_M),
                )
            )

    # -- a lesson starts (GUI callback: intent only) ------------------------------------------
    def start(self, index: int, client: Any = None) -> None:
        """Set up lesson ``index``: parameters from their defaults plus the lesson's, its
        robots, a restart (so the numbers count from the same instant), its camera view."""
        if self.panel.guarded():
            return
        lesson = LESSONS[index]
        session = self.panel.session
        setup = lesson.setup()
        groups = {k: v for k, v in setup.items() if k in GROUPS}
        try:
            session.set_robots(lesson.robot_list())
        except PoolFull as exc:
            self.live.content = (
                f"<b>Not started:</b> {html.escape(str(exc))}: this lesson needs "
                f"{len(lesson.robots())} robots and the workers are full."
            )
            return
        session.set_params(live_params().replace(**groups))
        if session.intent.paused:  # an experiment starts walking
            session.resume()
        intent = session.reset()
        run = _RUNS[session] = LessonRun(lesson, intent.start_clock)
        self._adopt(run, camera_moved=client is not None)
        # The view is fitted to the robots shown: set it once the scene shows the lesson's.
        self._camera = (run, lesson.view, client)

    def _adopt(self, run: LessonRun, camera_moved: bool = False) -> None:
        """Show the session's lesson ``run``: its head and text now, its numbers as the
        robots restart. ``camera_moved``: this view's camera is set to the lesson's view (the
        browser that pressed the button); every other view keeps its own and is told which
        view the lesson is seen best from."""
        lesson = run.lesson
        self.run = run
        self._shown_time = -math.inf
        camera = (
            f"camera: {lesson.view}"
            if camera_moved
            else f"best seen from the camera view <i>{lesson.view}</i> (Controls tab, View: "
            "yours stays where you put it)"
        )
        self.head.content = (
            f'<div style="font: 13px/1.45 sans-serif"><b>{html.escape(lesson.title)}</b><br/>'
            f'<span style="color:#5f6368">Paper: {html.escape(lesson.paper)}; {camera}'
            "</span></div>"
        )
        self.text.content = (
            f'<div style="font: 13px/1.45 sans-serif"><p style="margin:4px 0">{lesson.watch}</p>'
            f"{lesson.equations_html()}</div>"
        )
        self.live.content = "<i>waiting for the robots to restart...</i>"
        self.now.content = ""

    @property
    def lesson(self) -> Lesson | None:
        """The lesson this tab shows (the session's)."""
        return self.run.lesson if self.run is not None else None

    @property
    def start_clock(self) -> float:
        """[s] The session clock the shown lesson's robots started at (inf: no lesson)."""
        return self.run.start_clock if self.run is not None else math.inf

    # -- live numbers (display thread) ------------------------------------------------------
    def update(self, frame: LiveFrame, now: float) -> None:
        """Tally the shown ``frame`` and refresh the lesson's live numbers (at most
        :data:`NUMBERS_HZ` a second while running, every new frame while paused)."""
        run = lesson_run(self.panel.session)
        if run is None:
            return
        if run is not self.run:  # a lesson started (here, or in another view of the session)
            self._adopt(run)
        lesson = run.lesson
        if tuple(r.method for r in frame.robots) != lesson.robots():
            # the robots were changed by hand (or a new robot has not sent a frame yet)
            self._show(
                now,
                frame,
                '<div class="lesson-live" style="font: 12.5px sans-serif"><i>This lesson\'s '
                "robots are not the ones shown now: press its button to start it again."
                "</i></div>",
            )
            return
        if frame.clock < run.start_clock - 1e-9:
            return  # the robots have not restarted yet: "waiting for the robots to restart"
        if self._camera is not None:  # the scene has drawn this frame's robots already
            started, view, client = self._camera
            self._camera = None
            if started is run:
                self.panel.view.scene.set_camera(view, client)
        intent = self.panel.session.intent
        run.observe(frame, intent)
        if lesson.now is not None:
            sentence = f'<div style="font: 13px/1.45 sans-serif">{lesson.now(intent.params)}</div>'
            if self.now.content != sentence:
                self.now.content = sentence
        self._show(now, frame, None)

    def _show(self, now: float, frame: LiveFrame, content: str | None) -> None:
        if not (frame.paused or now - self._shown_time >= 1.0 / NUMBERS_HZ):
            return
        self._shown_time = now
        content = content if content is not None else self.numbers_html(frame)
        if self.live.content != content:
            self.live.content = content

    def numbers_html(self, frame: LiveFrame) -> str:
        """The lesson's live numbers as a table: one column per robot."""
        run = self.run
        assert run is not None
        lesson = run.lesson
        window = self.panel.session.history.window(
            2.0 * frame.robots[0].params.walk.step_time, until=frame.clock
        )
        look = self._look = looks(frame.robots)
        head = "".join(
            f'<th style="text-align:left;padding:2px 6px"><span aria-hidden="true" '
            f'style="color:rgb{look[r.method].color}">{look[r.method].marker}</span> '
            f"{html.escape(look[r.method].title)}</th>"
            for r in frame.robots
        )
        rows = []
        for key in lesson.numbers:
            cells = "".join(
                f'<td style="padding:2px 6px">{self._cell(key, r, window.rows.get(r.method))}</td>'
                for r in frame.robots
            )
            rows.append(
                f'<tr><td style="color:#5f6368;padding:2px 4px">{COLUMNS[key]}</td>{cells}</tr>'
            )
        since = frame.clock - run.start_clock
        state = "paused" if frame.paused else "live"
        changed = (
            f"; last change at t = {run.since:.1f} s"
            if math.isfinite(run.since) and run.since > run.start_clock + 0.05
            else ""
        )
        return (
            f'<div class="lesson-live" style="font: 12.5px sans-serif">'
            f"<b>{state}</b>, t = {frame.clock:.2f} s ({since:.1f} s into the lesson{changed})"
            f'<table style="border-collapse:collapse;margin-top:4px"><tr><th></th>{head}</tr>'
            f"{''.join(rows)}</table></div>"
        )

    def _cell(self, key: str, r: RobotFrame, rows: np.ndarray | None) -> str:
        tally = (self.run.tallies.get(r.method) if self.run else None) or _Tally()
        recent = this_walk(rows) if rows is not None else rows
        if recent is None or not len(recent):
            recent = np.full((1, len(COL)), np.nan)

        def col(name: str) -> np.ndarray:
            v = recent[:, COL[name]]
            return v[np.isfinite(v)]

        if (r.fell or r.error is not None) and key not in SHOWN_WHEN_DOWN:
            return "-"  # lying on the floor or stopped: its measurements say nothing of a walk
        if key == "status":
            if r.fell and r.fell_clock is not None:
                return (
                    f'<b style="color:{STATUS_COLOURS["fell"]}">fell at t = '
                    f"{r.fell_clock:.1f} s</b>"
                )
            status = "standing by to start" if r.waiting else r.status
            colour = STATUS_COLOURS.get(status, "#444")
            return f'<b style="color:{colour}">{status}</b>'
        if key == "shares":
            n = max(tally.frames, 1)
            parts = [
                f'<span style="color:{STATUS_COLOURS[s]}">{s} {100 * c / n:.0f} %</span>'
                for s, c in sorted(tally.status.items(), key=lambda kv: -kv[1])
            ]
            return "<br/>".join(parts) or "-"
        if key == "step":
            return f"{r.step_length:.2f} m (step {max(r.step_index, 0)})"
        if key == "falls":  # the lesson's restart started the count again
            return str(r.falls)
        if key == "reach":
            return f"{_num(float(np.max(r.reach)), 3)} ({_num(tally.reach_max, 3)})"
        if key == "kappa_legs":
            return f"{_num(r.kappa_legs)} ({_num(tally.kappa_max)})"
        if key == "waist":
            w = col("waist_deg")
            span = f"{w.min():+.1f} to {w.max():+.1f}°" if w.size else "-"
            return f"{math.degrees(r.waist_angle):+.1f}° ({span})"
        if key == "rate":
            v = col("waist_rate_deg_s")
            return f"{np.abs(v).max():.0f}°/s" if v.size else "-"
        if key == "rate_now":
            v = recent[-1, COL["waist_rate_deg_s"]]
            return f"{v:+.1f}°/s" if math.isfinite(v) else "-"
        if key == "jerk":
            t, v = recent[:, COL["clock"]], recent[:, COL["waist_rate_deg_s"]]
            ok = np.isfinite(v[1:]) & np.isfinite(v[:-1]) & (np.diff(t) > 0)
            if not ok.any():
                return "-"
            return f"{np.max(np.abs(np.diff(v) / np.diff(t))[ok]):.0f}°/s²"
        if key == "liftoff":
            return self._liftoff(recent)
        if key == "dsp_turn":
            return self._dsp_turn(recent)
        if key == "yaw":
            h = col("yaw_momentum")
            peak_text = f"{np.abs(h).max():.2f}" if h.size else "-"
            return f"{r.yaw_momentum:+.2f} ({peak_text}) kg m²/s"
        if key == "arms":
            return "on" if r.params.arms.enabled else "<b>off</b>"
        if key == "settings":
            return f"{r.params.pelvis.k_pel:g}, {r.params.com.horizon:g} s"
        if key == "differ":
            look = self._look.get(r.method)
            return html.escape(look.differs) if look and look.differs else "as the others"
        if key == "phase":
            return self._phase(r)
        if key == "plan":
            hz = r.horizon
            if hz is None:
                return "-"
            th, ref = np.degrees(hz.theta), np.degrees(hz.theta_ref)
            return (
                f"{th[0]:+.1f}° → {th[-1]:+.1f}° (reference {ref.min():+.0f} to "
                f"{ref.max():+.0f}° over {hz.t[-1]:.1f} s)"
            )
        if key == "hip":
            l_pel = float(np.linalg.norm(r.hips[0, :2] - r.hips[1, :2]))
            measured = abs(float(r.hips[0, 0] - r.hips[1, 0]))
            predicted = l_pel * abs(math.sin(r.waist_angle))
            return f"{1000 * measured:.0f} / {1000 * predicted:.0f} mm"
        if key == "active":
            now = ik_limits(r)
            seen = sorted(tally.limits.items(), key=lambda kv: -kv[1])[:2]
            most = "; ".join(f"{name} ×{n}" for name, n in seen)
            return f"{'; '.join(now) or 'none'}" + (f" ({most})" if most else "")
        if key == "pushing":
            return "<b>pushing</b>" if r.pushing else "-"
        if key == "lateral":
            if not len(r.support):
                return "-"
            dy = float(r.com[1] - np.mean(r.support[:, 1]))
            return f"{1000 * dy:+.0f} mm"
        raise KeyError(key)

    @staticmethod
    def _dsp_turn(rows: np.ndarray) -> str:
        """How much of the waist's travel (the sum of |change| of its angle) fell in the double
        support over the rows: the paper's "turns before the swing" as a number."""
        dsp, waist = rows[:, COL["in_dsp"]], rows[:, COL["waist_deg"]]
        ok = np.isfinite(waist[1:]) & np.isfinite(waist[:-1]) & np.isfinite(dsp[1:])
        step = np.abs(np.diff(waist))[ok]
        total = float(step.sum())
        if total < 1.0:  # [deg] a pelvis that barely turns: no share to speak of
            return "-"
        in_dsp = float(step[dsp[1:][ok] == 1.0].sum())
        return f"{100 * in_dsp / total:.0f} % ({in_dsp:.1f}° of {total:.0f}°)"

    @staticmethod
    def _liftoff(rows: np.ndarray) -> str:
        """Waist yaw at the newest DSP -> SSP change of the 50 Hz rows (within 20 ms)."""
        dsp, waist = rows[:, COL["in_dsp"]], rows[:, COL["waist_deg"]]
        lift = np.flatnonzero((dsp[:-1] == 1.0) & (dsp[1:] == 0.0))
        if not lift.size:
            return "-"
        return f"{waist[lift[-1] + 1]:+.1f}°"

    @staticmethod
    def _phase(r: RobotFrame) -> str:
        if r.waiting or r.step_index < 0 or r.step_index >= r.plan.n:
            return "standing"
        k = r.step_index
        if r.in_dsp:
            return f"<b>DSP</b>, lift-off in {max(r.plan.liftoff_times()[k] - r.t, 0.0):.2f} s"
        return f"SSP, landing in {max(r.plan.landing_times()[k] - r.t, 0.0):.2f} s"
