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
its method's colour (``METHOD_INFO``) on its torso and head; no other overlay uses the method
colours.

Layout: robot ``slot`` i of n walks at y = ((n - 1) / 2 - i) * ``ROBOT_SPACING``; the world
(robots, overlays, floor) is shifted back in x by the robots' mean progress, so the robots
stay in view while the footholds and the floor stay fixed to the ground.

The prediction (the paper's Fig. 5-6), drawn on the floor so the body does not hide it: the
CoM the CoM MPC predicts over the horizon (eq. 25-26) as a purple path from the robot
forward, and across it, at every other predicted sample, the pelvis's hip line, solid for the
MPC's optimised angle theta (eq. 35) and dashed for the reference theta_ref (eq. 30-33).
Only the MPC robot plans its pelvis; the redundancy robot shows its hip line now, the fixed
one none.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import viser

from app.live import LiveFrame, RobotFrame
from app.live.history import FrameStore
from app.web.camera import CAMERA_VIEWS, camera_pose, label_point, slot_offset
from app.web.overlays import (
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
    polyline_segments,
    reach_color,
    rectangle_segments,
    robot_prediction,
    seg_array,
    stick_segments,
    swing_path,
)
from app.web.robot_meshes import RobotMeshes
from controller.params import METHOD_INFO
from models.dyros_jet import FOOT_SIZE

LAYERS: dict[str, tuple[str, bool]] = {  # key -> (GUI label, shown by default)
    "robots": ("Robots", True),
    "labels": ("Labels (method, status, numbers)", True),
    "prediction": ("Prediction: CoM path and hip lines (floor)", True),
    "footholds": ("Planned footholds", True),
    "zmp": ("ZMP: reference (red) and measured (black)", True),
    "support": ("Support polygon", False),
    "swing": ("Swing-foot path", False),
    "momentum": ("Yaw momentum arrow", True),
    "reach": ("Legs by reach (grey -> red: knee straightening)", True),
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
        }
        self.ov = {
            k: Overlay(
                sc.add_line_segments(f"/world/{k}", seg, c, thickness=t, thickness_units="screen")
            )
            for k, (c, t) in lines.items()
        }
        self.ov["zmp"] = Overlay(
            sc.add_point_cloud(
                "/world/zmp",
                np.zeros((1, 3), np.float32),
                ZMP_REF,
                point_size=0.05,
                point_shape="circle",
                precision="float32",
            )
        )
        self.ov["momentum"] = Overlay(
            sc.add_arrows(
                "/world/momentum",
                np.zeros((1, 2, 3), np.float32),
                MOMENTUM,
                shaft_radius=0.015,
                head_radius=0.04,
                head_length=0.08,
            )
        )
        self.ov["sticks"].handle.visible = False
        self.labels: list[Overlay] = []
        self._methods: tuple[str, ...] = ()
        self._overlay_time = self._label_time = -math.inf
        self._keys: dict[str, Any] = {}
        self.camera_view = "follow"  # the last view asked for: how robots and labels lie
        self.version = 0  # changes when the layout changes: the shown frame is drawn again
        if isinstance(target, viser.ViserServer):
            pos, look, _up, fov = camera_pose("follow", 3, 1.3, False)
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
        pos, look, up, fov = camera_pose(name, len(self._methods) or 3, aspect, self.along_x)
        self._keys.clear()
        with client.atomic():
            client.camera.up_direction = up
            client.camera.fov = fov
            client.camera.position = tuple(pos)
            client.camera.look_at = tuple(look)

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

    def _layout(self, methods: tuple[str, ...]) -> None:
        self.robots.layout(methods)
        for label in self.labels:
            label.handle.remove()
        self.labels = [
            Overlay(
                self.scene.add_label(
                    f"/world/label_{i}",
                    METHOD_INFO[m].title,
                    font_screen_scale=1.1,
                    anchor="bottom-center",  # the text above its point (from above: +y)
                    visible=self.layers["labels"],
                )
            )
            for i, m in enumerate(methods)
        ]
        self._methods = methods
        self._keys.clear()
        self._apply_layers()

    # -- drawing (display thread) ------------------------------------------------------------
    def draw(self, frame: LiveFrame, kept: FrameStore | None = None) -> None:
        """Update the scene from one published frame (only what changed is sent)."""
        methods = tuple(r.method for r in frame.robots)
        if methods != self._methods:
            self._layout(methods)
        if not frame.robots:
            return
        robots = frame.robots
        n = len(robots)
        y = np.array(
            [
                (slot_offset(i, n), 0.0) if self.along_x else (0.0, slot_offset(i, n))
                for i in range(n)
            ]
        )  # (n, 2) each robot's offset in x, y
        target = float(np.mean([r.com[0] for r in robots])) if self.follow else 0.0
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
            if labels and self.layers["labels"]:
                self._label_time = now
                for r, yi, label in zip(robots, y, self.labels, strict=True):
                    label.set(
                        text=_label_text(r),
                        position=label_point(r.com[0], yi, r.slot, n, self.from_above),
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
                ov["footholds"].set(points=seg_array(parts))
        if on["support"]:
            ov["support"].set(
                points=seg_array(
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
            ov["prediction"].set(
                points=seg_array(
                    [
                        seg
                        for r, yi in zip(robots, y, strict=True)
                        for seg in robot_prediction(r, yi)
                    ]
                )
            )
        if on["zmp"]:
            pts, cols = [], []
            for r, yi in zip(robots, y, strict=True):
                if r.zmp_ref is not None:
                    pts.append((*(r.zmp_ref + yi), FLOOR_Z + 0.01))
                    cols.append(ZMP_REF)
                if r.cop is not None:
                    pts.append((*(r.cop + yi), FLOOR_Z + 0.02))
                    cols.append(ZMP_MEAS)
            if pts:
                ov["zmp"].set(points=np.array(pts, np.float32), colors=np.array(cols, np.uint8))
        if on["swing"]:
            ov["swing"].set(
                points=seg_array([swing_path(r, yi) for r, yi in zip(robots, y, strict=True)])
            )
        if on["momentum"]:
            arrows = []
            for r, yi in zip(robots, y, strict=True):
                length = float(np.clip(MOMENTUM_SCALE * r.yaw_momentum, -1.0, 1.0))
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
            colors = np.array([reach_color(v) for r in robots for v in r.reach], np.uint8)
            ov["reach"].set(
                points=legs.astype(np.float32), colors=np.repeat(colors[:, None, :], 2, axis=1)
            )
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
                ov["sticks"].set(points=stick_pts, colors=stick_cols)


def _label_text(r: RobotFrame) -> str:
    """Method, status badge and live numbers, above the robot."""
    reach = r.reach
    head = METHOD_INFO[r.method].title
    if r.waiting:
        return f"{head}\nstanding by to start in phase"
    return (
        f"{head} · {r.status}\nstep {max(r.step_index, 0)} · {r.step_length:.2f} m · "
        f"waist {math.degrees(r.waist_angle):+.0f}°\nreach left {reach[0]:.2f} · right "
        f"{reach[1]:.2f}"
    )
