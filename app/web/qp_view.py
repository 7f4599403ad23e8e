"""The QP view of the Inspect tab: what each of the selected robot's four optimisations did at
the shown instant, side by side (the record is :class:`controller.explain.TickExplain`,
made with the frame, so it follows pause and scrub like the horizon inspector).

Pure HTML from a frame (:func:`qp_html`, tested without a browser) and a small GUI holder
(:class:`QpView`) that the panel updates with the inspector's chosen robot.
"""

from __future__ import annotations

import html
import math
import threading
from typing import Any

from controller.explain import ACTIVE_SET_MEANING, QpExplain, TickExplain
from pelvic_walk.core.frames import LiveFrame, RobotFrame
from pelvic_walk.core.methods import METHOD_INFO

QP_VIEW_HZ = 4.0  # updates per second while running (paused: every shown frame)
MAX_LISTED = 6  # active constraints listed per layer (the largest multipliers first)


def _num(v: float) -> str:
    if not math.isfinite(v):
        return "–"
    return f"{v:.3g}"


def _layer_html(e: QpExplain) -> str:
    esc = html.escape
    head = f'<div style="font-weight:600">{esc(e.title)}</div>'
    if not e.ran:
        return (
            f'<div data-layer="{e.layer}" data-active="0">{head}'
            f'<div style="color:#666">{esc(e.note)}</div></div>'
        )
    if e.ok:
        it = f", {e.iterations} it." if e.iterations >= 0 else ""
        # the solver's own clock (DAQP's active-set iterations alone, warm-started: often
        # under a microsecond); the layer's whole tick, building the QP included, is longer
        ms = f", {1e3 * e.solve_ms:.2g} µs in the solver" if math.isfinite(e.solve_ms) else ""
        status = f'<div style="color:#2a7a2a">solved{it}{ms}</div>'
    else:
        status = f'<div style="color:#b00020">failed ({esc(e.status)}): {esc(e.fallback)}</div>'
    terms = "".join(f"<div>{esc(k)}: {_num(v)}</div>" for k, v in e.terms.items())
    cost = f"<div>cost {_num(e.objective)}</div><div style='color:#555'>{terms}</div>"
    if e.active:
        items = "".join(
            f'<li data-name="{esc(c.name)}">{esc(c.name)} '
            f'<span style="color:#555">(λ {_num(c.multiplier)})</span></li>'
            for c in e.active[:MAX_LISTED]
        )
        more = len(e.active) - MAX_LISTED
        items += f"<li>… and {more} more</li>" if more > 0 else ""
        active = (
            f"<div>active ({len(e.active)}):</div>"
            f'<ul style="margin:0;padding-left:1.1em">{items}</ul>'
        )
    else:
        active = "<div>active: none (nothing stops it)</div>"
    return (
        f'<div data-layer="{e.layer}" data-active="{len(e.active)}">'
        f"{head}{status}{cost}{active}</div>"
    )


def qp_html(r: RobotFrame | None, clock: float) -> str:
    """The view of robot ``r``'s explanation at the session clock ``clock``."""
    rec: TickExplain | None = r.qp if r is not None else None
    if r is None or rec is None:
        return (
            '<div class="qp-view" data-t="">The QP view appears once the robot has ticked '
            "(resume or step).</div>"
        )
    # the robot's label (and its strategy when the label is not the strategy's name)
    name = r.strategy
    what = METHOD_INFO[name].title if name in METHOD_INFO else name
    title = html.escape(what if r.method == name else f"{r.method} ({what})")
    cols = "".join(_layer_html(e) for e in rec.layers)
    return (
        f'<div class="qp-view" data-t="{rec.t:.3f}" data-method="{html.escape(r.method)}" '
        'style="font-size:12px;line-height:1.35">'
        f"<div><b>What stops each optimisation</b>: {title}, the tick ending at t = "
        f"{rec.t:.3f} s of its walk (session clock {clock:.2f} s).</div>"
        f'<div style="color:#444;margin:2px 0 6px">{html.escape(ACTIVE_SET_MEANING)}</div>'
        '<div style="display:grid;gap:8px;'
        'grid-template-columns:repeat(auto-fit,minmax(150px,1fr))">'
        f"{cols}</div></div>"
    )


class QpView:
    """The QP view's GUI element; :meth:`update` with each shown frame and the robot chosen
    in the horizon inspector's dropdown."""

    def __init__(self, gui: Any, inspector: Any):
        # the horizon inspector: its dropdown chooses the tab's robot (by its label), and
        # ``inspector.selected()`` names that robot's method
        self.inspector = inspector
        with gui.add_folder("QP: what stops each optimisation"):
            self.html = gui.add_html(qp_html(None, 0.0))
        self._key: tuple | None = None
        self._time = -math.inf
        self._shown: tuple[LiveFrame, float, bool | None] | None = None
        self._lock = threading.Lock()  # the display thread and the dropdown's callback draw
        inspector.robot.on_update(lambda _e: self._reselected())

    def _reselected(self) -> None:
        """Another robot chosen: draw it at once from the last frame (paused, no new frame
        may come to draw it)."""
        if self._shown is not None:
            self.update(*self._shown)

    def update(self, frame: LiveFrame, now: float, paused: bool | None = None) -> None:
        """Show ``frame``'s explanation for the chosen robot. ``paused``: the session is
        paused (the intent's word: a kept frame shown after a seek was made while running,
        so its own ``paused`` says nothing of now); paused, every shown frame is drawn at
        once, running, at most :data:`QP_VIEW_HZ` a second."""
        with self._lock:
            self._shown = (frame, now, paused)
            method = self.inspector.selected()
            r = frame.robot(method) if method is not None else None
            key = (frame.seq, method)
            if key == self._key:
                return
            paused = frame.paused if paused is None else paused
            same_robot = self._key is not None and key[1] == self._key[1]
            if same_robot and not paused and now - self._time < 1.0 / QP_VIEW_HZ:
                return
            self._key, self._time = key, now
            content = qp_html(r, frame.clock)
            if self.html.content != content:
                self.html.content = content
