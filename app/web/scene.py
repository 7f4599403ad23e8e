"""The live 3-D scene (viser): robots side by side and what each controller layer plans.

Drawing only: :meth:`SceneView.draw` takes a published :class:`~app.live.LiveFrame` and
updates viser handles; nothing here touches the simulation. ``target`` is a
:class:`viser.ViserServer` (one scene every browser sees) or a :class:`viser.ClientHandle`
(a browser's own scene, private sessions).

Lean by design (every message is serialised once per viewer): the robots of all methods are
three batched meshes (a unit box, cylinder and sphere, instanced per geom with per-axis scales
and colours: a capsule is a cylinder and two spheres), so a frame moves them with five arrays
(a sphere needs no orientation); each overlay is one handle for all robots; world-fixed
overlays sit under one frame that follows the robots, so they are re-sent only when they
change; overlays are refreshed at ``OVERLAY_HZ`` and labels at ``LABEL_HZ``. Each robot wears
its strategy's colour (``pelvic_walk.core.methods.METHOD_INFO``; a second robot of one strategy a
shade of it, ``app.web.looks``) on its torso and head; the overlays
use one
colour per meaning (``app.web.overlays``), never a method colour.

Layout: robot ``slot`` i of n walks at y = ((n - 1) / 2 - i) * ``ROBOT_SPACING`` (seen from
the side, at x = (i - (n - 1) / 2) * ``ROBOT_SPACING``, the first one hindmost); the world
(robots, overlays, floor) is shifted back in x to the middle of the robots' progress (the
middle between the hindmost and the foremost), so every robot stays in view, a fallen one
lying behind the others included, while the footholds and the floor stay fixed to the ground.
A fallen robot gets a vermilion ring on the floor and a label saying when and why it fell and
when the session restarts every robot (app.live.session.FALL_HOLD_S). A robot its strategy
stopped (it raised) stays in view too, with its error on its label, until the restart.
Each label starts with the robot's marker (``MethodInfo.marker``, hollow for a second robot of
one strategy), a cue that is not colour, then its label and the settings by which it differs
from the others (``short horizon · H=0.8 s``);
the outermost labels on the screen are anchored at their inner edge, so their text extends
toward the middle and never out of the frame.

The prediction (the paper's Fig. 5-6), drawn on the floor so the body does not hide it: the
CoM the CoM MPC predicts over the horizon (eq. 25-26) as a sky-blue path from the robot
forward, and across it, at every fourth predicted sample, the pelvis's hip line: sky blue and
solid for the MPC's optimised angle theta (eq. 35), indigo, dashed and longer for the
reference theta_ref (eq. 30-33). Only the MPC robot plans its pelvis; the redundancy robot
shows its hip line now, the fixed one none.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import viser

from app.live import FALL_HOLD_S, LiveFrame, RobotFrame
from app.live.history import FrameStore
from app.web.camera import CAMERA_VIEWS, camera_pose, label_point, slot_offset
from app.web.looks import looks
from app.web.overlays import (
    DANGER,
    EMPTY_SEG,
    FLOOR_Z,
    FOOTHOLD_WINDOW,
    GROUND,
    MOMENTUM,
    PREDICTION,
    STICK_END,
    STICK_START,
    SUPPORT,
    ZMP_MEAS,
    ZMP_REF,
    Overlay,
    colored,
    fall_ring,
    line_color,
    polyline_segments,
    reach_color,
    rectangle_segments,
    robot_prediction,
    seg_array,
    stick_segments,
    swing_path,
    vertex_colors,
)
from app.web.qp_marks import LimitMarks
from app.web.robot_meshes import RobotMeshes
from models.dyros_jet import FOOT_SIZE

LAYERS: dict[str, tuple[str, bool]] = {  # key -> (GUI label, shown by default)
    "robots": ("Robots", True),
    "labels": ("Labels (method, status, numbers)", True),
    "prediction": ("Prediction: CoM path and hip lines (floor)", True),
    "footholds": ("Planned footholds", True),
    "zmp": ("ZMP: reference (indigo disc) and measured (black dot)", True),
    "support": ("Support polygon", False),
    "swing": ("Swing-foot path", False),
    "momentum": ("Yaw momentum arrow", True),
    "reach": ("Legs by reach (grey -> vermilion: knee straightening)", True),
    "falls": ("Fall marker (vermilion ring)", True),
}
MOMENTUM_SCALE = 0.5  # [m per kg m^2/s] arrow length
OVERLAY_HZ = 10.0  # overlay refreshes per second at most
LABEL_HZ = 4.0  # label text refreshes per second


class SceneView:
    """The 3-D scene of one view's robots; :meth:`draw` renders one :class:`LiveFrame`."""

    def __init__(self, target: Any, model: Any):
        self.target = target
        sc = self.scene = target.scene
        self.layers = {k: default for k, (_label, default) in LAYERS.items()}
        self.follow = True
        self.sticks = False
        self._follow_x = 0.0
        sc.set_up_direction("+z")
        self.world = sc.add_frame("/world", show_axes=False)
        sc.add_grid(
            "/world/floor",
            width=60.0,
            height=8.0,
            cell_size=0.25,
            section_size=1.0,
            position=(20.0, 0.0, 0.0),
            plane_color=(250, 250, 250),
            plane_opacity=1.0,
            shadow_opacity=0.2,
        )
        self.robots = RobotMeshes(sc, model, "/world")
        seg, grey = EMPTY_SEG, (120, 120, 120)
        lines = {
            "footholds": (GROUND, 2.0),
            "support": (SUPPORT, 2.5),
            "swing": (GROUND, 1.5),
            "prediction": (PREDICTION, 3.0),
            "reach": (grey, 6.0),
            "sticks": (grey, 3.0),
            "falls": (DANGER, 6.0),
        }
        self.ov = {  # colours per vertex from the start (Overlay says why)
            k: Overlay(
                sc.add_line_segments(
                    f"/world/{k}",
                    seg,
                    vertex_colors(c, len(seg)),
                    thickness=t,
                    thickness_units="screen",
                ),
                c,
            )
            for k, (c, t) in lines.items()
        }
        self.ov["zmp"] = Overlay(
            sc.add_point_cloud(
                "/world/zmp",
                np.zeros((1, 3), np.float32),
                line_color(ZMP_REF),
                point_size=0.05,
                point_shape="circle",
                precision="float32",
            )
        )
        self.ov["momentum"] = Overlay(
            sc.add_arrows(
                "/world/momentum",
                np.zeros((1, 2, 3), np.float32),
                line_color(MOMENTUM),
                shaft_radius=0.015,
                head_radius=0.04,
                head_length=0.08,
            )
        )
        self.ov["sticks"].handle.visible = False
        self.limit_marks = LimitMarks(sc, model)  # joints the IK holds at a limit (QP inspector)
        self.labels: list[Overlay] = []
        self._methods: tuple[str, ...] = ()
        self._strategies: tuple[str, ...] = ()  # the strategies of the robots laid out
        self._overlay_time = self._label_time = -math.inf
        self._keys: dict[str, Any] = {}
        self.camera_view = "follow"  # the last view asked for: how robots and labels lie
        self.version = 0  # changes when the layout changes: the shown frame is drawn again
        self._stagger = 0.0  # [m] along x the cameras are fitted for (a robot lying behind)
        self._placed: dict[Any, np.ndarray] = {}  # client id -> camera position set
        self._initial: np.ndarray | None = None  # where a new browser's camera starts
        if isinstance(target, viser.ViserServer):
            pos, look, _up, fov = camera_pose("follow", 3, 1.3, False)
            self._initial = np.asarray(pos, float)
            target.initial_camera.position = tuple(pos)
            target.initial_camera.look_at = tuple(look)
            target.initial_camera.fov = fov
        else:
            self.set_camera("follow", target)
        self._apply_layers()

    # -- settings (GUI callbacks) ----------------------------------------------------------
    def set_layer(self, key: str, visible: bool) -> None:
        self.layers[key] = visible
        self._apply_layers()

    def set_sticks(self, on: bool) -> None:
        self.sticks = on
        self._keys.pop("sticks", None)
        self.ov["sticks"].handle.visible = on

    def set_camera(self, name: str, client: Any) -> None:
        """Move one browser's camera to a named view (the world follows the robots)."""
        if client is None or name not in CAMERA_VIEWS:
            return
        # Seen from the side the robots stand one behind the other: spread them along x
        # then (for everyone looking at this scene), along y otherwise; seen from above, the
        # labels lie beside the robots.
        self.camera_view = name
        self.version += 1  # re-laid out at the next draw, paused or not
        try:
            aspect = client.camera.aspect
        except AssertionError:  # the browser has not reported its canvas yet
            aspect = 1.3
        pos, look, up, fov = camera_pose(
            name, len(self._methods) or 3, aspect, self.along_x, self._stagger
        )
        self._keys.clear()
        self._placed[client.client_id] = np.asarray(pos, float)
        with client.atomic():
            client.camera.up_direction = up
            client.camera.fov = fov
            client.camera.position = tuple(pos)
            client.camera.look_at = tuple(look)

    def _refit(self, stagger: float, moved_from: np.ndarray | None = None) -> None:
        """Fit the named view again for robots ``stagger`` [m] apart along x, for every
        browser whose camera is still where the view put it (one the viewer turned or
        zoomed is left alone); ``moved_from``: where a browser's camera stands that this
        view has not placed yet (the initial camera before it changed)."""
        self._stagger = stagger
        initial = self._initial if moved_from is None else moved_from
        clients = (
            list(self.target.get_clients().values())
            if isinstance(self.target, viser.ViserServer)
            else [self.target]
        )
        for client in clients:
            placed = self._placed.get(client.client_id, initial)
            try:
                here = np.asarray(client.camera.position, float)
            except AssertionError:  # nothing reported yet
                continue
            if placed is not None and np.allclose(here, placed, atol=0.05):
                self.set_camera(self.camera_view, client)

    def _fit_new_browsers(self) -> None:
        """A browser that joined the shared scene starts at the initial camera, fitted for a
        canvas of aspect 1.3: once it reports its own canvas there, fit the view to it (a
        narrow window's canvas cut the outer robots and labels off). One the viewer moved
        away is left alone."""
        if not isinstance(self.target, viser.ViserServer):
            return  # a browser's own scene was fitted to it when it was made
        for cid, client in self.target.get_clients().items():
            if cid in self._placed:
                continue
            try:
                here = np.asarray(client.camera.position, float)
            except AssertionError:  # nothing reported yet: at a later draw
                continue
            # (a browser reports a camera of its own before the initial one: wait for that)
            if self._initial is not None and np.allclose(here, self._initial, atol=0.05):
                self.set_camera(self.camera_view, client)

    @property
    def along_x(self) -> bool:
        """Robots side by side along x (seen from the side), else along y."""
        return self.camera_view == "side"

    @property
    def from_above(self) -> bool:
        """The top view: labels beside the robots, not over them."""
        return self.camera_view == "top"

    def _apply_layers(self) -> None:
        self.robots.set_visible(self.layers["robots"])
        for key, ov in self.ov.items():
            if key in self.layers:
                ov.handle.visible = self.layers[key]
        for label in self.labels:
            label.handle.visible = self.layers["labels"]
        self._overlay_time = -math.inf

    def _layout(self, robots: tuple[RobotFrame, ...]) -> None:
        methods = tuple(r.method for r in robots)
        shown = looks(robots)
        self.robots.layout(methods, tuple(shown[m].color for m in methods))
        for label in self.labels:
            label.handle.remove()
        self.labels = [
            Overlay(
                self.scene.add_label(
                    f"/world/label_{i}",
                    shown[m].title,
                    font_screen_scale=1.1,
                    anchor="bottom-center",  # the text above its point (from above: +y)
                    visible=self.layers["labels"],
                )
            )
            for i, m in enumerate(methods)
        ]
        refit = len(methods) != len(self._methods)
        self._methods = methods
        self._strategies = tuple(r.strategy for r in robots)
        self._keys.clear()
        self._apply_layers()
        if refit and methods:  # the views fitted for the number of robots now shown
            old_initial = self._initial
            if isinstance(self.target, viser.ViserServer):  # where a new browser starts
                pos, look, _up, _fov = camera_pose("follow", len(methods), 1.3, False)
                self.target.initial_camera.position = tuple(pos)
                self.target.initial_camera.look_at = tuple(look)
                self._initial = np.asarray(pos, float)
            self._refit(self._stagger, moved_from=old_initial)

    # -- drawing (display thread) ------------------------------------------------------------
    def draw(self, frame: LiveFrame, kept: FrameStore | None = None) -> None:
        """Update the scene from one published frame (only what changed is sent)."""
        methods = tuple(r.method for r in frame.robots)
        if methods != self._methods or self._strategies != tuple(r.strategy for r in frame.robots):
            self._layout(frame.robots)
        if not frame.robots:
            return
        robots = frame.robots
        n = len(robots)
        y = np.array(
            [
                # seen from the side, the first robot (the fixed pelvis, the one that falls in
                # the lessons) walks last in the row: the others walk on away from it, not
                # into it
                (-slot_offset(i, n), 0.0) if self.along_x else (0.0, slot_offset(i, n))
                for i in range(n)
            ]
        )  # (n, 2) each robot's offset in x, y
        stagger = stagger_x(robots)
        if stagger != self._stagger:
            self._refit(stagger)
        self._fit_new_browsers()
        target = follow_x(robots) if self.follow else 0.0
        jump = abs(target - self._follow_x) > 2.0 or frame.paused
        self._follow_x = target if jump else self._follow_x + 0.25 * (target - self._follow_x)
        now = time.monotonic()
        overlays = frame.paused or now - self._overlay_time >= 1.0 / OVERLAY_HZ
        labels = frame.paused or now - self._label_time >= 1.0 / LABEL_HZ
        with self.target.atomic():
            self.world.position = (-self._follow_x, 0.0, 0.0)
            if self.layers["robots"]:
                self.robots.draw(robots, y)
            if overlays:
                self._overlay_time = now
                self._draw_overlays(robots, y, kept)
                self.limit_marks.draw(robots, y)
            if labels and self.layers["labels"]:
                self._label_time = now
                anchors = label_anchors(self.camera_view, y)
                for r, yi, label, anchor in zip(robots, y, self.labels, anchors, strict=True):
                    label.set(
                        text=label_text(r, frame, compact=self._stagger >= COMPACT_STAGGER),
                        position=label_point(r.com[0], yi, r.slot, n, self.from_above),
                        anchor=anchor,
                    )

    def _draw_overlays(
        self, robots: tuple[RobotFrame, ...], y: np.ndarray, kept: FrameStore | None
    ) -> None:
        on, ov = self.layers, self.ov
        if on["footholds"]:
            key = tuple((id(r.plan), round(r.com[0] / FOOTHOLD_WINDOW)) for r in robots)
            if self._keys.get("footholds") != key:
                self._keys["footholds"] = key
                parts = []
                for r, yi in zip(robots, y, strict=True):
                    holds = r.plan.footholds()
                    near = np.abs(holds[:, 0] - r.com[0]) < FOOTHOLD_WINDOW
                    parts.append(rectangle_segments(holds[near, :2] + yi, FOOT_SIZE, FLOOR_Z))
                ov["footholds"].lines(seg_array(parts))
        if on["support"]:
            ov["support"].lines(
                seg_array(
                    [
                        polyline_segments(
                            np.column_stack([r.support + yi, np.full(len(r.support), FLOOR_Z)]),
                            closed=True,
                        )
                        for r, yi in zip(robots, y, strict=True)
                        if len(r.support) >= 3
                    ]
                )
            )
        if on["prediction"]:
            pred_pts, pred_cols = colored(  # a robot on the floor predicts nothing
                [
                    pair
                    for r, yi in zip(robots, y, strict=True)
                    if not r.fell
                    for pair in robot_prediction(r, yi)
                ]
            )
            ov["prediction"].lines(pred_pts, pred_cols)
        if on["falls"]:
            ov["falls"].lines(
                seg_array([fall_ring(r, yi) for r, yi in zip(robots, y, strict=True) if r.fell])
            )
        if on["zmp"]:
            pts, cols = [], []
            for r, yi in zip(robots, y, strict=True):
                if r.zmp_ref is not None:
                    pts.append((*(r.zmp_ref + yi), FLOOR_Z + 0.01))
                    cols.append(line_color(ZMP_REF))
                if r.cop is not None:
                    pts.append((*(r.cop + yi), FLOOR_Z + 0.02))
                    cols.append(line_color(ZMP_MEAS))
            if pts:
                ov["zmp"].set(points=np.array(pts, np.float32), colors=np.array(cols, np.uint8))
        if on["swing"]:
            ov["swing"].lines(
                seg_array([swing_path(r, yi) for r, yi in zip(robots, y, strict=True)])
            )
        if on["momentum"]:
            arrows = []
            for r, yi in zip(robots, y, strict=True):
                momentum = 0.0 if r.fell else r.yaw_momentum  # its arrow is over its head
                length = float(np.clip(MOMENTUM_SCALE * momentum, -1.0, 1.0))
                base = np.array([r.com[0] + yi[0], yi[1], 1.75])
                arrows.append([base, base + (0.0, 0.0, length if abs(length) > 0.01 else 0.01)])
            ov["momentum"].set(points=np.array(arrows, np.float32))
        if on["reach"]:
            legs = np.concatenate(
                [
                    np.stack([r.hips, r.ankles], axis=1) + (*yi, 0.0)
                    for r, yi in zip(robots, y, strict=True)
                ]
            )
            colors = np.array(
                [line_color(reach_color(v)) for r in robots for v in r.reach], np.uint8
            )
            ov["reach"].lines(legs.astype(np.float32), np.repeat(colors[:, None, :], 2, axis=1))
        if self.sticks and kept is not None:
            key = tuple((id(r.plan), r.step_index) for r in robots)
            if self._keys.get("sticks") != key:
                self._keys["sticks"] = key
                sticks = []
                for r, yi in zip(robots, y, strict=True):
                    seg = stick_segments(kept, r)
                    if seg is not None:
                        seg = seg + (*yi, 0.0)
                        sticks += [(seg[:3], STICK_START), (seg[3:], STICK_END)]
                stick_pts, stick_cols = colored(sticks)
                ov["sticks"].lines(stick_pts, stick_cols)


STAGGER_STEP = 0.5  # [m] the cameras are fitted again when the robots' stagger crosses these
COMPACT_STAGGER = 1.5  # [m] robots this far apart along x: the view zooms out, labels shorten


def robot_xs(robots: tuple[RobotFrame, ...]) -> list[float]:
    """[m] the forward positions the view follows, every robot's: a walking robot's CoM, a
    fallen one's middle (it lies there until the restart), a stopped one's (its strategy
    raised: it stands with its error on its label until the restart) where it stopped. The
    view centres between the hindmost and the foremost and is fitted for their stagger, so
    none leaves the picture."""
    return [
        (float(r.body_xpos[1:, 0].min()) + float(r.body_xpos[1:, 0].max())) / 2
        if r.fell
        else float(r.com[0])
        for r in robots
    ]


def label_anchors(view: str, offsets: np.ndarray) -> list[str]:
    """Each label's anchor in the named view, robots at ``offsets`` (n, 2) [m] in x, y: the
    leftmost robot on the screen has its label's left edge at its point (the text extends
    toward the middle), the rightmost its right edge, the others their middle; seen from
    above (labels beside the robots, in the middle of the screen) every one its middle. A
    label centred over an outer robot ran out of the frame ("et line ahead · clean")."""
    n = len(offsets)
    if n < 2 or view == "top":
        return ["bottom-center"] * n
    direction, up, _fov = CAMERA_VIEWS[view]
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    u = np.asarray(up, float) - np.dot(up, d) * d
    right = np.cross(u / np.linalg.norm(u), d)  # the screen's right, as camera_pose
    xs = np.asarray(offsets, float)[:, :2] @ right[:2]
    lo, hi = int(np.argmin(xs)), int(np.argmax(xs))
    return [
        "bottom-left" if i == lo else "bottom-right" if i == hi else "bottom-center"
        for i in range(n)
    ]


def follow_x(robots: tuple[RobotFrame, ...]) -> float:
    """[m] where the view centres in x: the middle between the hindmost and the foremost
    robot, so that all stay in view. (The slots' own offsets, along x seen from the side, are
    laid out around it.)"""
    xs = robot_xs(robots)
    return (min(xs) + max(xs)) / 2


def stagger_x(robots: tuple[RobotFrame, ...]) -> float:
    """[m] how far apart along x the robots are, rounded up to STAGGER_STEP (0 while they
    walk abreast): what the cameras are fitted for (``camera_pose``'s ``stagger_x``)."""
    xs = robot_xs(robots)
    spread = max(xs) - min(xs)
    return 0.0 if spread < 0.3 else STAGGER_STEP * math.ceil(spread / STAGGER_STEP)


def fall_note(r: RobotFrame, frame: LiveFrame) -> tuple[str, str, str]:
    """(when, why, restart) of a fallen robot, for its label and the status line: "at t =
    3.1 s", "torso tilted over 30°", "all robots restart in 2.4 s"."""
    when = f"at t = {r.fell_clock:.1f} s" if r.fell_clock is not None else ""
    why = (r.fall_reason or "fell").replace(" deg", "°")
    if r.fell_clock is None:
        return when, why, "all robots restart soon"
    left = r.fell_clock + FALL_HOLD_S - frame.clock
    if frame.paused:
        restart = (
            "all robots restart when you resume"
            if left <= 0
            else f"all robots restart {left:.1f} s after you resume"
        )
    else:
        restart = f"all robots restart in {max(left, 0.0):.1f} s"
    return when, why, restart


# [ms] a strategy whose waist_rate takes longer than a control period cannot run live: said on
# its label (the tick is 5 ms, and the other layers need their share of it)
SLOW_STRATEGY_MS = 5.0


def wrap(text: str, width: int = 48) -> str:
    """``text`` on lines of at most about ``width`` characters (a label's lines)."""
    import textwrap

    return "\n".join(textwrap.wrap(text, width)) or text


def label_text(r: RobotFrame, frame: LiveFrame, compact: bool = False) -> str:
    """Method, status badge and live numbers, above the robot; when it fell, when and why,
    and when the session restarts every robot. ``compact``: the robots are far apart along
    x (one stopped or fallen behind, the view zoomed out) and their labels crowd: a walking
    robot's label is its first line, a stopped or fallen one's says what happened without
    the restart line (the status area says it all)."""
    # its marker, title and the settings that differ: "■ fixed pelvis", "○ short · H=0.8 s"
    head = looks(frame.robots if frame.robot(r.method) is not None else (r,))[r.method].full
    if r.error is not None:
        rest = "" if compact else "\nRestart all robots together runs it again"
        return f"⚠ {head} STOPPED\n{wrap(r.error, 40 if compact else 48)}{rest}"
    if r.fell:
        when, why, restart = fall_note(r, frame)
        return f"⚠ {head} FELL {when}\n{why}" + ("" if compact else f"\n{restart}")
    if compact:
        return f"{head} · {r.status}"
    if r.waiting:
        return f"{head}\nstanding by to start in phase"
    if r.finished and r.unsuccessful:  # the reasons one a line
        why = r.unsuccessful.replace("; ", "\n")
        return f"⚠ {head} · finished its plan, NO SUCCESS\n{why}\nall robots restart together"
    if r.finished:
        return f"{head} · walked its whole plan\nall robots restart together"
    reach = r.reach
    if r.strategy_ms > SLOW_STRATEGY_MS:
        head = f"{head} · slow: {r.strategy_ms:.0f} ms a tick"
    return (
        f"{head} · {r.status}\nstep {max(r.step_index, 0)} · {shown(r.step_length, '.2f')} m · "
        f"waist {shown(math.degrees(r.waist_angle), '+.0f')}°\nreach left "
        f"{shown(reach[0], '.2f')} · right {shown(reach[1], '.2f')}"
    )


def shown(value: float, spec: str) -> str:
    """A number for a label, or a dash until it exists (a robot that has not ticked since
    its restart has no reach yet: NaN)."""
    return format(value, spec) if math.isfinite(value) else "–"
