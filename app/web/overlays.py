"""Geometry of the scene's overlays (footholds, prediction, swing path, stick diagram, fall
marker) and their colours; an :class:`Overlay` re-sends a handle's data only when it changed.

One colour per meaning, in the scene, its legend, the horizon inspector and the recordings:
REFERENCE (what a layer is asked to follow: ZMP reference, theta_ref; indigo, drawn dashed or
hollow), PREDICTED (what an MPC optimised or predicts over its horizon: CoM path, the MPC's
theta, the predicted ZMP; sky blue, solid), MEASURED (the simulated robot: centre of pressure,
yaw momentum; black), PLAN (the footstep plan's geometry: footholds, support polygon, swing
path; grey) and DANGER (a leg nearly straight, a fall; vermilion, an orange-red).

Chosen for every student (docs/TEACHING.md, "Colours"): sky blue, black and vermilion are
Okabe-Ito colours; the five stay at least ``tests/test_colours.py``'s distance apart (CAM02-UCS)
for normal vision, deuteranopia, protanopia, tritanopia and in grayscale, where lightness alone
tells them apart: black, indigo, dark grey, vermilion, sky blue from dark to light. Meaning is
never carried by colour alone: references are dashed, a fall is a ring, a straight leg is also
said on the robot's label. The words the page, legend and lessons use for them are
:data:`COLOUR_NAMES`."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from app.live import RobotFrame
from app.live.history import FrameStore
from controller.footsteps import LEFT
from controller.pelvis_reference import hip_points
from pelvic_walk.core.methods import METHOD_INFO, MethodInfo

# One colour per meaning (module docstring).
REFERENCE = (40, 27, 108)  # indigo, dark
PREDICTED = (86, 180, 233)  # sky blue (Okabe-Ito)
MEASURED = (0, 0, 0)  # black
PLAN = (80, 80, 80)  # dark grey
DANGER = (204, 90, 0)  # vermilion (Okabe-Ito's, a shade darker): a straight leg, a fall's ring
# The words for them wherever text names a colour (the page, the legend, the lessons)
COLOUR_NAMES: dict[tuple[int, int, int], str] = {
    REFERENCE: "indigo",
    PREDICTED: "sky blue",
    MEASURED: "black",
    PLAN: "grey",
    DANGER: "vermilion",
}
PREDICTION = PREDICTED  # the CoM path and the MPC's hip lines
GROUND = PLAN  # footholds, swing path
SUPPORT = (40, 40, 40)  # the support polygon: the plan's, darker (it is under the robot)
ZMP_REF, ZMP_MEAS = REFERENCE, MEASURED
MOMENTUM = MEASURED
STICK_START, STICK_END = (160, 160, 160), (30, 30, 30)
FALL_RING = 0.55  # [m] radius of the ring on the floor around a fallen robot
HIP_BAR = 0.18  # [m] half length of the hip lines drawn on the floor (the pelvis: 0.105)
HIP_EVERY = 4  # hip lines at every 4th horizon sample (0.4 s apart at T_p = 0.1 s)
FLOOR_Z = 0.006  # [m] overlays on the floor, just above it
FOOTHOLD_WINDOW = 1.2  # [m] footholds drawn ahead of and behind the robot


LEG_GREY = (150, 150, 150)  # a bent leg's gauge


# The colour a line or point of each colour (left, any channel) shows as in Chromium (right),
# measured on grey lines (tests/test_browser_colours.py measures again): viser's client takes
# a line's colour as linear light and tone-maps it, so sent as is every colour but black showed
# paler (the crimson reference pinkish, the dark grey plan a light grey) and no line shows
# lighter than about 226. :func:`line_color` inverts it, channel by channel.
LINE_IN = (0, 10, 20, 40, 60, 90, 120, 160, 200, 230, 255)
LINE_OUT = (0, 40, 72, 117, 147, 176, 193, 208, 218, 223, 226)


def line_color(rgb: tuple[int, int, int]) -> tuple[int, int, int]:
    """The colour to send for a line or point that shows as ``rgb`` (a channel lighter than
    the lines' lightest shows as near as it can)."""
    r, g, b = (int(round(np.interp(c, LINE_OUT, LINE_IN))) for c in rgb)
    return r, g, b


def reach_color(reach: float) -> tuple[int, int, int]:
    """Grey while the knee is bent (reach <= 0.85), to DANGER (vermilion) as the leg
    straightens (1.0)."""
    f = float(np.clip((reach - 0.85) / 0.15, 0.0, 1.0)) if math.isfinite(reach) else 0.0
    r, g, b = (int(round(a + (z - a) * f)) for a, z in zip(LEG_GREY, DANGER, strict=True))
    return r, g, b


def rectangle_segments(centres: np.ndarray, size: tuple[float, float], z: float) -> np.ndarray:
    """(4 M, 2, 3) outline segments of axis-aligned rectangles at ``centres`` (M, 2)."""
    hx, hy = size[0] / 2, size[1] / 2
    corners = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
    pts = centres[:, None, :2] + corners[None]  # (M, 4, 2)
    seg = np.stack([pts, np.roll(pts, -1, axis=1)], axis=2).reshape(-1, 2, 2)
    return np.concatenate([seg, np.full(seg.shape[:2] + (1,), z)], axis=2)


def polyline_segments(points: np.ndarray, closed: bool = False) -> np.ndarray:
    """(M - 1 (or M if closed), 2, 3) segments joining consecutive points (M, 3)."""
    points = np.asarray(points, dtype=float)
    if len(points) < 2:
        return np.zeros((0, 2, 3))
    b = np.roll(points, -1, axis=0) if closed else points[1:]
    a = points if closed else points[:-1]
    return np.stack([a, b], axis=1)


def dashed(segments: np.ndarray, pieces: int = 4) -> np.ndarray:
    """Each segment (M, 2, 3) cut into ``pieces`` dashes with gaps: (M * pieces, 2, 3)."""
    a, b = segments[:, 0], segments[:, 1]
    f = np.arange(pieces) / pieces
    start = a[:, None] + (b - a)[:, None] * f[None, :, None]
    end = a[:, None] + (b - a)[:, None] * (f + 0.6 / pieces)[None, :, None]
    return np.stack([start, end], axis=2).reshape(-1, 2, 3)


def legend_html() -> str:
    """The scene's colours and the robots' markers and line styles, for the GUI: every entry
    says in words what its colour shows (a colour is never the only cue)."""

    def sw(rgb: tuple[int, int, int], text: str, dash: str = "") -> str:
        style = f"border-top:3px {dash} rgb{rgb}" if dash else f"background:rgb{rgb}"
        return (
            f"<span aria-hidden='true' style='display:inline-block;width:16px;"
            f"height:{0 if dash else 10}px;{style};margin:0 4px 0 10px;"
            f"vertical-align:middle'></span>{text}"
        )

    def robot(i: MethodInfo) -> str:
        line = (
            "solid"
            if not i.dash
            else "dash-dot"
            if len(i.dash) > 2
            else "dashed"
            if i.dash[0] > 4
            else "dotted"
        )
        css = "dashed" if line == "dash-dot" else line
        return sw(i.color, f"<b>{i.marker}</b>&nbsp;{i.title} (plots: {line})", dash=css)

    robots = "<br>".join(robot(i) for i in METHOD_INFO.values())
    n = COLOUR_NAMES
    parts = [
        sw(
            PREDICTED,
            f"<b>predicted</b> / optimised ({n[PREDICTED]}, solid): CoM path, MPC hip line θ",
        ),
        sw(
            REFERENCE,
            f"<b>reference</b> ({n[REFERENCE]}, dashed): θ_ref hip line, ZMP reference (disc)",
            dash="dashed",
        ),
        sw(MEASURED, f"<b>measured</b> ({n[MEASURED]}): CoP (dot), yaw momentum (arrow)"),
        sw(PLAN, f"plan ({n[PLAN]}): footholds"),
        sw(DANGER, f"{n[DANGER]}: leg nearly straight; fall (ring)"),
    ]
    second = (
        "a second robot of one strategy: a shade of its colour, a hollow marker (○) and "
        "another line style, and always its own label"
    )
    return (
        f"<div style='font-size:12px;line-height:1.8'>Robots (torso and head; marker on the "
        f"label):<br>{robots}<br><span style='margin-left:10px'>{second}</span><br>"
        f"{'<br>'.join(parts)}</div>"
    )


def vertex_colors(color: tuple[int, int, int], n: int) -> np.ndarray:
    """(n, 2, 3) uint8: one colour at both ends of ``n`` line segments (as sent, so that the
    lines show ``color``: :func:`line_color`)."""
    return np.tile(np.asarray(line_color(color), np.uint8), (n, 2, 1))


class Overlay:
    """One handle for all robots' overlay of one kind, re-sent only when its data changed.

    Line segments always carry a colour per vertex (:meth:`lines`), from their creation on:
    viser's client builds a line's shader for one colour or for per-vertex colours when it
    first draws the line and keeps that form, so a line created with one colour and given
    per-vertex colours later is drawn white on a page that drew it in between (a page that
    joined before the first frame, or replayed the scene's messages in two batches)."""

    def __init__(self, handle: Any, color: tuple[int, int, int] | None = None):
        self.handle = handle
        self.color = color  # a line overlay's one colour (sent per vertex)
        self._last: dict[str, Any] = {}

    def lines(self, points: np.ndarray, colors: np.ndarray | None = None) -> None:
        """Set line segments (N, 2, 3) and their colours per vertex (default: the overlay's
        colour at every vertex)."""
        if colors is None:
            assert self.color is not None, "a line overlay without its own colour"
            colors = vertex_colors(self.color, len(points))
        self.set(points=points, colors=colors)

    def set(self, **props: Any) -> None:
        for attr, value in props.items():
            old = self._last.get(attr)
            if isinstance(value, np.ndarray) and isinstance(old, np.ndarray):
                if old.shape == value.shape and np.array_equal(old, value):
                    continue
            elif old is not None and old == value:
                continue
            setattr(self.handle, attr, value)
            self._last[attr] = value


EMPTY_SEG = np.zeros((1, 2, 3), dtype=np.float32)


def seg_array(parts: list[np.ndarray]) -> np.ndarray:
    parts = [p for p in parts if len(p)]
    return np.concatenate(parts).astype(np.float32) if parts else EMPTY_SEG


def colored(parts: list[tuple[np.ndarray, tuple[int, int, int]]]) -> tuple[np.ndarray, np.ndarray]:
    """Segments and per-segment colours from (segments, colour) pairs."""
    parts = [(s, c) for s, c in parts if len(s)]
    if not parts:
        return EMPTY_SEG, np.zeros((1, 2, 3), np.uint8)
    seg = np.concatenate([s for s, _c in parts]).astype(np.float32)
    col = np.concatenate([vertex_colors(c, len(s)) for s, c in parts])
    return seg, col


def robot_prediction(r: RobotFrame, y: np.ndarray) -> list[tuple[np.ndarray, tuple[int, int, int]]]:
    """Predicted CoM path and hip lines over the horizon, on the floor (Fig. 5-6), as
    (segments, colour) pairs."""
    hz = r.horizon
    if hz is None:
        return []
    com = np.vstack([r.com[None, :2], hz.com]) + y
    path = polyline_segments(np.column_stack([com, np.full(len(com), FLOOR_Z + 0.004)]))
    return [(path, PREDICTED), *robot_hip_lines(r, y)]


def robot_hip_lines(r: RobotFrame, y: np.ndarray) -> list[tuple[np.ndarray, tuple[int, int, int]]]:
    """The hip lines on the floor, (segments, colour) pairs: a robot that plans its pelvic
    angle (the MPC) shows its optimised theta (PREDICTED, solid) and its reference theta_ref
    (REFERENCE, dashed and longer, so both show where they coincide) at every HIP_EVERY-th
    predicted sample; one that turns without a plan (redundancy, most of a user's) its hip
    line now; a pelvis that does not turn (the fixed one) none."""
    hz = r.horizon
    if hz is None:
        return []

    def bars(p: np.ndarray, theta: np.ndarray, half: float = HIP_BAR) -> np.ndarray:
        hp = hip_points(p + y, theta, half)  # (N, 2, 2)
        return np.concatenate([hp, np.full((len(theta), 2, 1), FLOOR_Z + 0.006)], axis=2)

    if hz.planned:
        k = slice(HIP_EVERY - 1, None, HIP_EVERY)
        return [
            (bars(hz.com, hz.theta)[k], PREDICTED),
            (dashed(bars(hz.com, hz.theta_ref, 1.5 * HIP_BAR)[k]), REFERENCE),
        ]
    if abs(r.waist_angle_cmd) > 1e-9:
        return [(bars(r.com[None, :2], np.array([r.waist_angle_cmd])), PREDICTED)]
    return []


def fall_ring(r: RobotFrame, y: np.ndarray, pieces: int = 24) -> np.ndarray:
    """A ring on the floor around a fallen robot (the middle of its bodies), (pieces, 2, 3)."""
    centre = (r.body_xpos[1:, :2].min(axis=0) + r.body_xpos[1:, :2].max(axis=0)) / 2 + y
    a = np.linspace(0.0, 2 * np.pi, pieces + 1)
    pts = np.column_stack(
        [
            centre[0] + FALL_RING * np.cos(a),
            centre[1] + FALL_RING * np.sin(a),
            np.full(len(a), FLOOR_Z + 0.008),
        ]
    )
    return polyline_segments(pts)


def stick_segments(kept: FrameStore, r: RobotFrame) -> np.ndarray | None:
    """Hips and legs of the last finished step at its lift-off and landing (Fig. 11): the
    support and swing leg's hip-to-ankle lines and the hip line, (6, 2, 3), world frame."""
    plan, k = r.plan, r.step_index - 1
    span = kept.span()
    if k < 0 or k >= plan.n or span is None:
        return None
    frames = kept.between(*span)
    out = []
    for t_robot in (float(plan.liftoff_times()[k]), float(plan.landing_times()[k])):
        found = None
        for f in reversed(frames):
            rf = f.robot(r.method)
            if rf is not None and rf.plan is plan and abs(rf.t - t_robot) < 0.05:
                found = rf
                break
        if found is None:
            return None
        out += [
            [found.hips[0], found.ankles[0]],
            [found.hips[1], found.ankles[1]],
            [found.hips[0], found.hips[1]],
        ]
    return np.array(out)


def swing_path(r: RobotFrame, y: np.ndarray, samples: int = 20) -> np.ndarray:
    """Path of the swing foot over the step in progress (eq. 20-21)."""
    plan, k = r.plan, r.step_index
    if not (0 <= k < plan.n):
        return np.zeros((0, 2, 3))
    t = np.linspace(plan.step_start[k] + plan.step_dsp[k], plan.landing_times()[k], samples)
    feet = plan.sample(t)
    path = feet.p_left if int(plan.swing_side[k]) == LEFT else feet.p_right
    return polyline_segments(path + (*y, 0.0))
