"""The live 3-D scene (viser): robots side by side and what each controller layer plans.

Drawing only: :meth:`SceneView.draw` takes a published :class:`~app.live.LiveFrame` and
updates viser handles; nothing here touches the simulation. ``target`` is a
:class:`viser.ViserServer` (one scene every browser sees) or a :class:`viser.ClientHandle`
(a browser's own scene, private sessions).

Lean by design (every message is serialised once per viewer): the robots of all methods are
three batched meshes (a unit box, cylinder and sphere, instanced per geom with per-axis scales
and colours: a capsule is a cylinder and two spheres), so a frame moves them with six arrays;
each overlay is one handle for all robots; world-fixed overlays sit under one frame that
follows the robots, so they are re-sent only when they change; overlays are refreshed at
``OVERLAY_HZ`` and labels at ``LABEL_HZ``. Each robot wears its method's colour
(``METHOD_INFO``) on its torso and head; no other overlay uses the method colours.

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
import trimesh
import viser
import viser.transforms as vtf

from app.live import LiveFrame, RobotFrame
from app.live.history import FrameStore
from controller.footsteps import LEFT
from controller.params import METHOD_INFO
from controller.pelvis_reference import hip_points
from models.dyros_jet import FOOT_SIZE

ROBOT_SPACING = 1.8  # [m] between robots, in y: labels and gauges never overlap
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
# Overlay colours (none of them a method colour).
PREDICTION = (140, 60, 200)  # predicted CoM path and hip lines
GROUND = (120, 120, 120)  # footholds, swing path
SUPPORT = (40, 40, 40)
ZMP_REF, ZMP_MEAS = (200, 30, 60), (20, 20, 20)
MOMENTUM = (90, 40, 130)
STICK_START, STICK_END = (160, 160, 160), (30, 30, 30)
TINTED_GEOMS = ("torso", "head")  # drawn in the robot's method colour
MOMENTUM_SCALE = 0.5  # [m per kg m^2/s] arrow length
OVERLAY_HZ = 10.0  # overlay refreshes per second at most
LABEL_HZ = 4.0  # label text refreshes per second
HIP_BAR = 0.18  # [m] half length of the hip lines drawn on the floor (the pelvis: 0.105)
HIP_EVERY = 4  # hip lines at every 4th horizon sample (0.4 s apart at T_p = 0.1 s)
FLOOR_Z = 0.006  # [m] overlays on the floor, just above it
FOOTHOLD_WINDOW = 1.2  # [m] footholds drawn ahead of and behind the robot
CAMERA_VIEWS: dict[str, tuple[tuple[float, float, float], tuple[float, float, float], float]] = {
    # name -> (direction from the robots to the camera, up, vertical field of view [deg]);
    # the distance is fitted to the robots shown and the browser's aspect (camera_pose).
    # A narrow field from afar comes close to an orthographic view (side and top, as the
    # paper's Fig. 11 and Fig. 5-6).
    "follow": ((0.74, -0.55, 0.38), (0.0, 0.0, 1.0), 50.0),  # front-right, three quarters
    "side": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0), 22.0),  # x-z plane
    "top": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0), 22.0),  # x-y plane
    "front": ((1.0, 0.0, 0.15), (0.0, 0.0, 1.0), 35.0),
}
VIEW_MARGIN = 0.9  # [m] around the outer robots (labels, footholds ahead and behind)


def camera_pose(
    name: str, n: int, aspect: float, along_x: bool
) -> tuple[np.ndarray, np.ndarray, tuple[float, float, float], float]:
    """(position, look_at, up, vertical fov [rad]) of a named view that shows ``n`` robots
    side by side (along x when ``along_x``) whole in a canvas of ``aspect`` = width/height."""
    direction, up, fov_deg = CAMERA_VIEWS[name]
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    spread = (max(n, 1) - 1) / 2 * ROBOT_SPACING + VIEW_MARGIN
    top = 2.3 + 0.3 * max(n - 1, 0)  # the highest label
    lo = np.array([-spread if along_x else -VIEW_MARGIN, -VIEW_MARGIN if along_x else -spread, 0])
    hi = np.array([spread if along_x else 1.2, VIEW_MARGIN if along_x else spread, top])
    centre = (lo + hi) / 2
    corners = (
        np.array(
            [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
        )
        - centre
    )
    u = np.asarray(up, float) - np.dot(up, d) * d
    u /= np.linalg.norm(u)
    right = np.cross(u, d)  # the camera looks along -d
    half_w, half_h = np.abs(corners @ right).max(), np.abs(corners @ u).max()
    depth = np.abs(corners @ d).max()
    fov = math.radians(fov_deg)
    tan_v = math.tan(fov / 2)
    dist = depth + max(half_h / tan_v, half_w / (tan_v * max(aspect, 0.2)))
    return centre + d * dist, centre, up, fov


def slot_offset(slot: int, n: int) -> float:
    """[m] offset of robot ``slot`` among ``n``, centred on 0 (along y; along x, seen from
    the side, so that no robot hides another)."""
    return ((n - 1) / 2.0 - slot) * ROBOT_SPACING


def reach_color(reach: float) -> tuple[int, int, int]:
    """Grey while the knee is bent (reach <= 0.85), to red as the leg straightens (1.0)."""
    f = float(np.clip((reach - 0.85) / 0.15, 0.0, 1.0)) if math.isfinite(reach) else 0.0
    return (int(150 + 90 * f), int(150 - 150 * f), int(150 - 150 * f))


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
    """The scene's colours, for the GUI."""

    def sw(rgb: tuple[int, int, int], text: str, dash: bool = False) -> str:
        style = f"border-top:3px dashed rgb{rgb}" if dash else f"background:rgb{rgb}"
        return (
            f"<span style='display:inline-block;width:16px;height:{0 if dash else 10}px;"
            f"{style};margin:0 4px 0 10px;vertical-align:middle'></span>{text}"
        )

    robots = "".join(sw(i.color, i.title) for i in METHOD_INFO.values())
    parts = [
        sw(PREDICTION, "predicted CoM and MPC hip line"),
        sw(PREDICTION, "theta_ref", dash=True),
        sw(ZMP_REF, "ZMP reference"),
        sw(ZMP_MEAS, "measured ZMP (CoP)"),
        sw(GROUND, "footholds"),
        sw((240, 0, 0), "leg nearly straight"),
    ]
    return (
        f"<div style='font-size:12px;line-height:1.8'>Robots (torso): {robots}<br>"
        f"{''.join(parts)}</div>"
    )


class RobotMeshes:
    """Every robot as three batched meshes, a unit box, cylinder and sphere scaled per
    instance (a capsule is a cylinder and two spheres): six arrays move all robots."""

    def __init__(self, scene: Any, model: Any, parent: str):
        self.scene, self.parent = scene, parent
        groups: dict[tuple, list] = {}
        tinted = {model.geom(n).id for n in TINTED_GEOMS}
        for g in range(model.ngeom):
            body = int(model.geom_bodyid[g])
            if body == 0 or model.geom_rgba[g, 3] == 0:
                continue  # the floor, invisible geoms
            size, kind = model.geom_size[g], int(model.geom_type[g])
            if kind == 6:  # box: a unit cube scaled by the half sizes
                key, scale = ("box",), size[:3]
            elif kind == 5:  # cylinder: radius, radius, half height
                key, scale = ("cylinder",), (size[0], size[0], size[1])
            elif kind == 2:  # sphere
                key, scale = ("sphere",), (size[0],) * 3
            elif kind == 3:  # capsule: a cylinder and two spheres (caps would not scale)
                axis = vtf.SO3(model.geom_quat[g]).as_matrix()[:, 2] * size[1]
                rgb = tuple(int(255 * c) for c in model.geom_rgba[g, :3])
                for end in (model.geom_pos[g] + axis, model.geom_pos[g] - axis):
                    groups.setdefault(("sphere",), []).append(
                        (body, end, model.geom_quat[g].copy(), (size[0],) * 3, rgb, g in tinted)
                    )
                key, scale = ("cylinder",), (size[0], size[0], size[1])
            else:
                continue
            rgb = tuple(int(255 * c) for c in model.geom_rgba[g, :3])
            groups.setdefault(key, []).append(
                (body, model.geom_pos[g].copy(), model.geom_quat[g].copy(), scale, rgb, g in tinted)
            )
        self.kinds = {}
        units = {
            "box": lambda: trimesh.creation.box(extents=(2.0, 2.0, 2.0)),
            "cylinder": lambda: trimesh.creation.cylinder(radius=1.0, height=2.0, sections=16),
            "sphere": lambda: trimesh.creation.icosphere(subdivisions=2),
        }
        for key, rows in groups.items():
            mesh = units[key[0]]()
            name = "_".join(str(k).replace(".", "p") for k in key)
            self.kinds[name] = (
                mesh,
                np.array([r[0] for r in rows]),
                np.array([r[1] for r in rows]),
                vtf.SO3(np.array([r[2] for r in rows])).as_matrix(),
                np.array([r[3] for r in rows], np.float32),
                np.array([r[4] for r in rows], np.uint8),
                np.array([r[5] for r in rows], bool),
            )
        self.handles: dict[str, Any] = {}
        self._methods: tuple[str, ...] = ()

    def layout(self, methods: tuple[str, ...]) -> None:
        """(Re)create the handles for these robots (instance colours carry the method)."""
        for h in self.handles.values():
            h.remove()
        self.handles = {}
        n = len(methods)
        for kind, (mesh, body, _p, _R, scale, rgb, tint) in self.kinds.items():
            colors = np.concatenate(
                [np.where(tint[:, None], METHOD_INFO[m].color, rgb) for m in methods]
            ).astype(np.uint8)
            k = len(body) * n
            self.handles[kind] = self.scene.add_batched_meshes_simple(
                f"{self.parent}/robot_{kind}",
                mesh.vertices,
                mesh.faces,
                batched_wxyzs=np.tile([1.0, 0, 0, 0], (k, 1)).astype(np.float32),
                batched_positions=np.zeros((k, 3), np.float32),
                batched_scales=np.tile(scale, (n, 1)),
                batched_colors=colors,
                lod="off",
            )
        self._methods = methods

    def draw(self, robots: tuple[RobotFrame, ...], offsets: np.ndarray) -> None:
        """Pose every instance: each robot's bodies, moved by its (x, y) offset (n, 2)."""
        for kind, (_mesh, body, pos, R, _s, _c, _t) in self.kinds.items():
            xpos = np.stack([r.body_xpos[body] for r in robots]).astype(float)  # (n, k, 3)
            xmat = np.stack([r.body_xmat[body] for r in robots]).astype(float)  # (n, k, 3, 3)
            world = xpos + np.einsum("nkij,kj->nki", xmat, pos)
            world[:, :, :2] += offsets[:, None, :]
            rot = np.einsum("nkij,kjl->nkil", xmat, R).reshape(-1, 3, 3)
            h = self.handles[kind]
            h.batched_positions = world.reshape(-1, 3).astype(np.float32)
            h.batched_wxyzs = vtf.SO3.from_matrix(rot).wxyz.astype(np.float32)

    def set_visible(self, visible: bool) -> None:
        for h in self.handles.values():
            h.visible = visible


class _Overlay:
    """One handle for all robots' overlay of one kind, re-sent only when its data changed."""

    def __init__(self, handle: Any):
        self.handle = handle
        self._last: dict[str, Any] = {}

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


_EMPTY_SEG = np.zeros((1, 2, 3), dtype=np.float32)


def _seg(parts: list[np.ndarray]) -> np.ndarray:
    parts = [p for p in parts if len(p)]
    return np.concatenate(parts).astype(np.float32) if parts else _EMPTY_SEG


def _colored(parts: list[tuple[np.ndarray, tuple[int, int, int]]]) -> tuple[np.ndarray, np.ndarray]:
    """Segments and per-segment colours from (segments, colour) pairs."""
    parts = [(s, c) for s, c in parts if len(s)]
    if not parts:
        return _EMPTY_SEG, np.zeros((1, 2, 3), np.uint8)
    seg = np.concatenate([s for s, _c in parts]).astype(np.float32)
    col = np.concatenate([np.tile(np.asarray(c, np.uint8), (len(s), 2, 1)) for s, c in parts])
    return seg, col


def _robot_prediction(r: RobotFrame, y: np.ndarray) -> list[np.ndarray]:
    """Predicted CoM path and hip lines over the horizon, on the floor (Fig. 5-6)."""
    hz = r.horizon
    if hz is None:
        return []
    com = np.vstack([r.com[None, :2], hz.com]) + y
    path = polyline_segments(np.column_stack([com, np.full(len(com), FLOOR_Z + 0.004)]))

    def bars(p: np.ndarray, theta: np.ndarray, half: float = HIP_BAR) -> np.ndarray:
        hp = hip_points(p + y, theta, half)  # (N, 2, 2)
        return np.concatenate([hp, np.full((len(theta), 2, 1), FLOOR_Z + 0.006)], axis=2)

    out = [path]
    if r.method == "mpc":  # theta_ref's lines longer, so both show where they coincide
        k = slice(HIP_EVERY - 1, None, HIP_EVERY)
        out += [bars(hz.com, hz.theta)[k], dashed(bars(hz.com, hz.theta_ref, 1.5 * HIP_BAR)[k])]
    elif r.method == "redundancy":  # no plan: its hip line now
        out.append(bars(r.com[None, :2], np.array([r.waist_angle_cmd])))
    return out


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
        seg, grey = _EMPTY_SEG, (120, 120, 120)
        lines = {
            "footholds": (GROUND, 2.0),
            "support": (SUPPORT, 2.5),
            "swing": (GROUND, 1.5),
            "prediction": (PREDICTION, 3.0),
            "reach": (grey, 6.0),
            "sticks": (grey, 3.0),
        }
        self.ov = {
            k: _Overlay(
                sc.add_line_segments(f"/world/{k}", seg, c, thickness=t, thickness_units="screen")
            )
            for k, (c, t) in lines.items()
        }
        self.ov["zmp"] = _Overlay(
            sc.add_point_cloud(
                "/world/zmp",
                np.zeros((1, 3), np.float32),
                ZMP_REF,
                point_size=0.05,
                point_shape="circle",
                precision="float32",
            )
        )
        self.ov["momentum"] = _Overlay(
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
        self.labels: list[_Overlay] = []
        self._methods: tuple[str, ...] = ()
        self._overlay_time = self._label_time = -math.inf
        self._keys: dict[str, Any] = {}
        self.along_x = False  # robots side by side along y (along x: seen from the side)
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
        # then (for everyone looking at this scene), along y otherwise.
        self.along_x = name == "side"
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
            _Overlay(
                self.scene.add_label(
                    f"/world/label_{i}",
                    METHOD_INFO[m].title,
                    font_screen_scale=1.1,
                    anchor="bottom-center",
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
                    # staggered heights: labels never overlap, whatever the camera
                    z = 2.05 + 0.3 * (len(robots) - 1 - r.slot)
                    label.set(
                        text=_label_text(r),
                        position=np.array([r.com[0] + yi[0], yi[1], z], np.float32),
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
                ov["footholds"].set(points=_seg(parts))
        if on["support"]:
            ov["support"].set(
                points=_seg(
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
                points=_seg(
                    [
                        seg
                        for r, yi in zip(robots, y, strict=True)
                        for seg in _robot_prediction(r, yi)
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
                points=_seg([_swing_path(r, yi) for r, yi in zip(robots, y, strict=True)])
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
                parts = []
                for r, yi in zip(robots, y, strict=True):
                    seg = stick_segments(kept, r)
                    if seg is not None:
                        seg = seg + (*yi, 0.0)
                        parts += [(seg[:3], STICK_START), (seg[3:], STICK_END)]
                pts, cols = _colored(parts)
                ov["sticks"].set(points=pts, colors=cols)


def _swing_path(r: RobotFrame, y: np.ndarray, samples: int = 20) -> np.ndarray:
    """Path of the swing foot over the step in progress (eq. 20-21)."""
    plan, k = r.plan, r.step_index
    if not (0 <= k < plan.n):
        return np.zeros((0, 2, 3))
    t = np.linspace(plan.step_start[k] + plan.step_dsp[k], plan.landing_times()[k], samples)
    feet = plan.sample(t)
    path = feet.p_left if int(plan.swing_side[k]) == LEFT else feet.p_right
    return polyline_segments(path + (*y, 0.0))


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
