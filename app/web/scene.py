"""The live 3-D scene (viser): robots side by side and what each controller layer plans.

Drawing only: every ``draw_*`` helper takes a published :class:`~app.live.RobotFrame`
and updates viser handles; nothing here touches the simulation. The robots themselves are
drawn by mjviser (:class:`mjviser.ViserMujocoScene`, one batched mesh per body shape and one
"environment" per robot) from the MuJoCo body poses copied into each frame.

Layout: robot ``slot`` i of n stands at y = ((n - 1) / 2 - i) * ``ROBOT_SPACING``; the whole
scene (robots, overlays, floor grid) is shifted back in x by the robots' mean progress so the
robots stay in view while the footholds and the floor stay fixed to the ground.

What is drawn per robot (each a layer that can be hidden):
    footholds       planned footholds (0.30 x 0.17 m rectangles), blue left / red right
    support         support polygon of the feet in contact (measured), green
    zmp             ZMP reference (orange sphere) and measured ZMP = centre of pressure (magenta)
    com             CoM predicted by the CoM MPC over the horizon (eq. 25-26), cyan, at CoM height
    hips            hip lines at the predicted pelvis positions: reference pelvic angle
                    (eq. 27-33, yellow) and the pelvic MPC's optimised angle (eq. 34-38,
                    orange); the measured pelvis (white)
    swing           swing-foot path of the step in progress (eq. 20-21)
    momentum        whole-body yaw angular momentum about the CoM (vertical arrow)
    reach           each leg's hip-to-ankle distance / leg length, as a coloured line over the
                    leg and a gauge bar: green when bent, red as it nears 1.0 (straight leg)
    labels          the method and live numbers above each robot
"""

from __future__ import annotations

import types
from collections.abc import Callable
from typing import Any

import numpy as np
import viser

from app.live import LiveFrame, RobotFrame
from app.sim.world import convex_hull
from controller.footsteps import LEFT
from controller.params import METHOD_INFO
from controller.pelvis_reference import hip_points
from models.dyros_jet import FOOT_SIZE, HIP_OFFSET

ROBOT_SPACING = 1.6  # [m] between robots, in y
LAYERS = {  # key -> label (GUI); all shown by default
    "robots": "Robots",
    "footholds": "Planned footholds",
    "support": "Support polygon",
    "zmp": "ZMP reference / measured",
    "com": "Predicted CoM (horizon)",
    "hips": "Hip lines (pelvic angle)",
    "swing": "Swing-foot path",
    "momentum": "Yaw momentum arrow",
    "reach": "Leg reach gauges",
    "labels": "Labels",
}
FOOT_COLORS = ((70, 130, 255), (255, 80, 80))  # left, right
MOMENTUM_SCALE = 0.5  # [m per kg m^2/s] arrow length
GAUGE_HEIGHT = 0.5  # [m] a reach of 1.0
REACH_GREEN, REACH_RED = 0.85, 1.0


def slot_offset(slot: int, n: int) -> float:
    """[m] y offset of robot ``slot`` among ``n``, centred on y = 0."""
    return ((n - 1) / 2.0 - slot) * ROBOT_SPACING


def reach_color(reach: float) -> tuple[int, int, int]:
    """Green below 0.85, through yellow, to red at 1.0 (a straight leg)."""
    f = float(np.clip((reach - REACH_GREEN) / (REACH_RED - REACH_GREEN), 0.0, 1.0))
    return (int(255 * min(1.0, 2 * f)), int(220 * min(1.0, 2 * (1 - f))), 40)


def rectangle_segments(centres: np.ndarray, size: tuple[float, float], z: float) -> np.ndarray:
    """(4 M, 2, 3) outline segments of axis-aligned rectangles at ``centres`` (M, 2)."""
    hx, hy = size[0] / 2, size[1] / 2
    corners = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
    pts = centres[:, None, :2] + corners[None]  # (M, 4, 2)
    a, b = pts, np.roll(pts, -1, axis=1)
    seg = np.stack([a, b], axis=2).reshape(-1, 2, 2)
    return np.concatenate([seg, np.full(seg.shape[:2] + (1,), z)], axis=2)


def polyline_segments(points: np.ndarray, closed: bool = False) -> np.ndarray:
    """(M - 1 (or M if closed), 2, 3) segments joining consecutive points (M, 3)."""
    points = np.asarray(points, dtype=float)
    if len(points) < 2:
        return np.zeros((0, 2, 3))
    b = np.roll(points, -1, axis=0) if closed else points[1:]
    a = points if closed else points[:-1]
    return np.stack([a, b], axis=1)


_EMPTY_SEG = np.zeros((1, 2, 3), dtype=np.float32)


class _Handles:
    """Viser handles of one robot's overlays, with change detection to spare the websocket."""

    def __init__(self, server: viser.ViserServer, root: str, method: str):
        sc = server.scene
        color = METHOD_INFO[method].color
        self.root = sc.add_frame(root, show_axes=False)
        seg = _EMPTY_SEG
        self.label = sc.add_label(f"{root}/label", METHOD_INFO[method].title,
                                  position=(0.0, 0.0, 2.0), font_screen_scale=0.8)
        self.footholds = sc.add_line_segments(f"{root}/footholds", seg, (255, 255, 255),
                                              thickness=0.012)
        self.support = sc.add_line_segments(f"{root}/support", seg, (60, 230, 90),
                                            thickness=0.015)
        self.zmp_ref = sc.add_icosphere(f"{root}/zmp_ref", radius=0.03, color=(255, 150, 0))
        self.cop = sc.add_icosphere(f"{root}/cop", radius=0.03, color=(230, 40, 230))
        self.com_line = sc.add_line_segments(f"{root}/com_plan", seg, (0, 220, 255),
                                             thickness=0.012)
        self.com_points = sc.add_point_cloud(f"{root}/com_points", np.zeros((1, 3)),
                                             (0, 220, 255), point_size=0.03,
                                             point_shape="circle")
        self.hips_ref = sc.add_line_segments(f"{root}/hips_ref", seg, (250, 225, 60),
                                             thickness=0.008)
        self.hips_mpc = sc.add_line_segments(f"{root}/hips_mpc", seg, (255, 110, 20),
                                             thickness=0.01)
        self.hips_now = sc.add_line_segments(f"{root}/hips_now", seg, (255, 255, 255),
                                             thickness=0.02)
        self.swing = sc.add_line_segments(f"{root}/swing", seg, (255, 255, 255),
                                          thickness=0.01)
        self.momentum = sc.add_arrows(f"{root}/momentum", np.array([[[0, 0, 0], [0, 0, 0.1]]]),
                                      color, shaft_radius=0.015, head_radius=0.04,
                                      head_length=0.08)
        self.legs = sc.add_line_segments(f"{root}/legs", np.zeros((2, 2, 3)),
                                         np.zeros((2, 2, 3)), thickness=0.035)
        self.gauges = [
            sc.add_box(f"{root}/gauge_{side}", dimensions=(0.05, 0.05, 0.01), color=(0, 200, 0),
                       position=(0.0, 0.0, 0.0))
            for side in ("left", "right")
        ]
        self.gauge_frames = [
            sc.add_box(f"{root}/gauge_{side}_max", dimensions=(0.07, 0.07, GAUGE_HEIGHT),
                       color=(200, 200, 200), wireframe=True, position=(0.0, 0.0, 0.0))
            for side in ("left", "right")
        ]
        self.layer_of = {
            "labels": [self.label],
            "footholds": [self.footholds],
            "support": [self.support],
            "zmp": [self.zmp_ref, self.cop],
            "com": [self.com_line, self.com_points],
            "hips": [self.hips_ref, self.hips_mpc, self.hips_now],
            "swing": [self.swing],
            "momentum": [self.momentum],
            "reach": [self.legs, *self.gauges, *self.gauge_frames],
        }
        self._last: dict[tuple[int, str], Any] = {}
        self.swing_key: tuple[int, int] | None = None

    def set(self, handle: Any, attr: str, value: Any) -> None:
        """Assign ``handle.attr = value`` only if it changed since the last assignment."""
        key = (id(handle), attr)
        old = self._last.get(key)
        if old is not None:
            if isinstance(value, np.ndarray):
                if isinstance(old, np.ndarray) and np.array_equal(old, value):
                    return
            elif old == value:
                return
        setattr(handle, attr, value)
        self._last[key] = value

    def remove(self) -> None:
        self.root.remove()


def _segments(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=np.float32)
    return x if len(x) else _EMPTY_SEG


def draw_label(h: _Handles, r: RobotFrame) -> None:
    """The method and live numbers above the robot."""
    title = METHOD_INFO[r.method].title
    reach = r.reach
    status = "FELL (reset in 2 s)" if r.fell else f"step {max(r.step_index, 0)}"
    text = (
        f"{title}\n{status}, {r.step_length:.2f} m, waist {np.degrees(r.waist_angle):+.0f} deg, "
        f"reach {reach[0]:.2f} / {reach[1]:.2f}"
    )
    h.set(h.label, "text", text)
    h.set(h.label, "position", np.array([r.com[0], r.com[1], 2.05]))


def draw_footholds(h: _Handles, r: RobotFrame, window: float = 1.6) -> None:
    """Planned footholds near the robot, as 0.30 x 0.17 m rectangles (blue left, red right)."""
    plan = r.plan
    holds = plan.footholds()  # (n + 2, 3): left, right initial, then the landings
    sides = np.concatenate([[0, 1], plan.swing_side])
    near = np.abs(holds[:, 0] - r.com[0]) < window
    holds, sides = holds[near], sides[near]
    seg = rectangle_segments(holds[:, :2], FOOT_SIZE, 0.004)
    colors = np.repeat(np.array(FOOT_COLORS, dtype=np.uint8)[sides], 4, axis=0)
    colors = np.repeat(colors[:, None, :], 2, axis=1)
    if len(seg) == 0:
        return
    h.set(h.footholds, "points", seg.astype(np.float32))
    h.set(h.footholds, "colors", colors)


def draw_support(h: _Handles, r: RobotFrame) -> None:
    """Support polygon: convex hull of the soles in contact (measured)."""
    hx, hy = FOOT_SIZE[0] / 2, FOOT_SIZE[1] / 2
    corners = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
    pts = []
    for side in range(2):
        if r.in_contact[side]:
            c, s = np.cos(r.sole_yaws[side]), np.sin(r.sole_yaws[side])
            pts.append(corners @ np.array([[c, s], [-s, c]]) + r.soles[side, :2])
    if not pts:
        h.set(h.support, "visible", False)
        return
    hull = convex_hull(np.vstack(pts))
    loop = np.column_stack([hull, np.full(len(hull), 0.008)])
    h.set(h.support, "points", _segments(polyline_segments(loop, closed=True)))


def draw_zmp(h: _Handles, r: RobotFrame) -> None:
    """ZMP reference (orange) and the measured centre of pressure (magenta)."""
    if r.zmp_ref is not None:
        h.set(h.zmp_ref, "position", np.array([*r.zmp_ref, 0.01]))
    if r.cop is None:
        h.set(h.cop, "visible", False)
    else:
        h.set(h.cop, "position", np.array([*r.cop, 0.012]))


def draw_com_plan(h: _Handles, r: RobotFrame) -> None:
    """The CoM the CoM MPC predicts over its horizon (eq. 25-26), at the CoM height."""
    if r.horizon is None:
        return
    com = r.horizon.com
    pts = np.column_stack([com, np.full(len(com), r.com[2])])
    h.set(h.com_line, "points", _segments(polyline_segments(pts)))
    h.set(h.com_points, "points", pts.astype(np.float32))


def draw_hips(h: _Handles, r: RobotFrame) -> None:
    """Hip lines at the predicted pelvis positions: reference angle and MPC's optimised angle."""
    if r.horizon is None or r.pelvis_des is None:
        return
    z_hip = float(r.pelvis_des[2] + HIP_OFFSET[2])
    com = r.horizon.com
    n = min(len(com), len(r.horizon.theta_ref))

    def lines(theta: np.ndarray, z: float) -> np.ndarray:
        hp = hip_points(com[:n], theta[:n])  # (n, 2, 2)
        return np.concatenate([hp, np.full((n, 2, 1), z)], axis=2)

    h.set(h.hips_ref, "points", _segments(lines(r.horizon.theta_ref, z_hip)))
    if r.method == "mpc":
        h.set(h.hips_mpc, "points", _segments(lines(r.horizon.theta, z_hip + 0.03)))
    else:
        h.set(h.hips_mpc, "visible", False)
    h.set(h.hips_now, "points", _segments(r.hips[None]))


def draw_swing(h: _Handles, r: RobotFrame, samples: int = 24) -> None:
    """Path of the swing foot over the step in progress (eq. 20-21)."""
    plan = r.plan
    k = r.step_index
    if r.horizon is None or not (0 <= k < plan.n):
        h.set(h.swing, "visible", False)
        return
    key = (id(plan), k)
    if h.swing_key != key:  # the path changes only with the step (or a replan)
        start = plan.step_start[k] + plan.step_dsp[k]
        end = plan.step_start[k] + plan.step_duration[k]
        feet = plan.sample(np.linspace(start, end, samples))
        side = int(plan.swing_side[k])
        path = feet.p_left if side == LEFT else feet.p_right
        h.swing_key = key
        h.set(h.swing, "points", _segments(polyline_segments(path)))
        h.set(h.swing, "colors", np.array(FOOT_COLORS[side], dtype=np.uint8))


def draw_momentum(h: _Handles, r: RobotFrame) -> None:
    """Whole-body yaw angular momentum about the CoM, as a vertical arrow at the CoM."""
    length = float(np.clip(MOMENTUM_SCALE * r.yaw_momentum, -1.0, 1.0))
    if abs(length) < 0.01:
        h.set(h.momentum, "visible", False)
        return
    base = r.com + np.array([0.0, 0.0, 0.35])
    h.set(h.momentum, "points", np.array([[base, base + [0, 0, length]]], dtype=np.float32))


def draw_reach(h: _Handles, r: RobotFrame) -> None:
    """Each leg's reach (hip-to-ankle / leg length): coloured leg lines and gauge bars."""
    if r.horizon is None:
        return
    reach = np.asarray(r.reach, dtype=float)
    colors = np.array([reach_color(v) for v in reach], dtype=np.uint8)  # (2, 3)
    legs = np.stack([r.hips, r.ankles], axis=1)  # (2, 2, 3)
    h.set(h.legs, "points", legs.astype(np.float32))
    h.set(h.legs, "colors", np.repeat(colors[:, None, :], 2, axis=1))
    for side in range(2):
        height = float(np.clip(reach[side], 0.0, 1.2)) * GAUGE_HEIGHT
        y = r.com[1] + (0.32 if side == LEFT else -0.32)
        base = np.array([r.com[0] - 0.25, y, 0.0])
        h.set(h.gauges[side], "dimensions", (0.05, 0.05, max(height, 1e-3)))
        h.set(h.gauges[side], "position", base + [0, 0, height / 2])
        h.set(h.gauges[side], "color", tuple(int(c) for c in colors[side]))
        h.set(h.gauge_frames[side], "position", base + [0, 0, GAUGE_HEIGHT / 2])


DRAWERS: dict[str, Callable[[_Handles, RobotFrame], None]] = {
    "labels": draw_label,
    "footholds": draw_footholds,
    "support": draw_support,
    "zmp": draw_zmp,
    "com": draw_com_plan,
    "hips": draw_hips,
    "swing": draw_swing,
    "momentum": draw_momentum,
    "reach": draw_reach,
}


class SceneView:
    """The 3-D scene of all robots; :meth:`draw` renders one :class:`LiveFrame`."""

    def __init__(self, server: viser.ViserServer, model: Any, follow: bool = True):
        from mjviser import ViserMujocoScene

        self.server = server
        self.model = model
        self.layers = dict.fromkeys(LAYERS, True)
        self.follow = follow
        self._follow_x = 0.0
        server.scene.set_up_direction("+z")
        self.mj = ViserMujocoScene(server, model, num_envs=1)
        self.mj.camera_tracking_enabled = False
        # mjviser resets its fixed-body frame (the floor grid) on every update; take it over so
        # the floor shifts with the robots (a stand-in absorbs mjviser's own assignments).
        self._floor = self.mj.fixed_bodies_frame
        self.mj.fixed_bodies_frame = types.SimpleNamespace(position=None)
        self.overlay = server.scene.add_frame("/overlay", show_axes=False)
        self._robots: tuple[str, ...] = ()
        self._handles: list[_Handles] = []
        server.initial_camera.position = (2.9, -2.7, 1.7)
        server.initial_camera.look_at = (0.0, 0.0, 0.65)

    def _layout(self, methods: tuple[str, ...]) -> None:
        """(Re)create the per-robot handles when the set of robots changes."""
        for h in self._handles:
            h.remove()
        n = len(methods)
        self.mj.num_envs = n
        self.mj.rebuild_visual_handles()
        self._handles = []
        for slot, method in enumerate(methods):
            h = _Handles(self.server, f"/overlay/r{slot}_{method}", method)
            h.root.position = (0.0, slot_offset(slot, n), 0.0)
            self._handles.append(h)
        self._robots = methods
        self.apply_layers()

    def apply_layers(self) -> None:
        """Show or hide every overlay according to :attr:`layers`."""
        for group in self.mj._mesh_groups:
            group.handle.visible = self.layers["robots"]
        for h in self._handles:
            for layer, handles in h.layer_of.items():
                for handle in handles:
                    handle.visible = self.layers[layer]
                    h._last.pop((id(handle), "visible"), None)

    def draw(self, frame: LiveFrame) -> None:
        """Update the whole scene from one published frame."""
        methods = tuple(r.method for r in frame.robots)
        if methods != self._robots:
            self._layout(methods)
        if not frame.robots:
            return
        n = len(frame.robots)
        if self.follow:
            target = float(np.mean([r.com[0] for r in frame.robots]))
            jump = abs(target - self._follow_x) > 2.0
            self._follow_x = target if jump else self._follow_x + 0.2 * (target - self._follow_x)
        else:
            self._follow_x = 0.0
        shift = np.array([-self._follow_x, 0.0, 0.0])
        with self.server.atomic():
            self.overlay.position = shift
            self._floor.position = shift
            for r, h in zip(frame.robots, self._handles, strict=True):
                for layer, draw in DRAWERS.items():
                    if not self.layers[layer]:
                        continue
                    visible_before = [hd.visible for hd in h.layer_of[layer]]
                    for hd, vis in zip(h.layer_of[layer], visible_before, strict=True):
                        if not vis:  # a drawer hid it last time (e.g. no CoP): show again
                            hd.visible = True
                            h._last.pop((id(hd), "visible"), None)
                    draw(h, r)
        if self.layers["robots"]:
            xpos = np.stack([r.body_xpos for r in frame.robots])  # (n, nbody, 3)
            xmat = np.stack([r.body_xmat for r in frame.robots])  # (n, nbody, 3, 3)
            offsets = np.array([[-self._follow_x, slot_offset(i, n), 0.0] for i in range(n)])
            self.mj.update_from_arrays(xpos + offsets[:, None, :], xmat)
