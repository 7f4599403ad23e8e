"""Every robot as three batched meshes (a unit box, cylinder and sphere, instanced per geom
with per-axis scales and colours): a frame moves all robots with five arrays."""

from __future__ import annotations

from typing import Any

import numpy as np
import trimesh
import viser.transforms as vtf

from app.live import RobotFrame
from pelvic_walk.core.methods import METHOD_INFO

TINTED_GEOMS = ("torso", "head")  # drawn in the robot's method colour

# The scene's light curve: the colour (sRGB 0-255, red/green and blue) a grey mesh of each
# instance colour (left) shows where it faces the camera, under viser's default lighting
# (environment map and lights), measured in Chromium (tests/test_browser_colours.py renders
# and measures again). viser's client takes an instance colour as linear light and lights it
# brightly: sent as is, grey 128 shows as 210 and every colour but black looks pale (the MPC's
# orange read yellow, the three torsos were similar light greys in grayscale).
# :func:`mesh_color` inverts it channel by channel, so a torso shows its method's colour.
LIGHT_IN = (0, 5, 10, 15, 20, 30, 40, 45, 50, 60, 70, 80, 90, 100, 128, 160, 200, 230, 255)
LIGHT_RG = (20, 45, 65, 82, 96, 120, 140, 146, 154, 164, 175, 182, 189, 198, 210, 218.5, 226,
            229, 232)  # fmt: skip
LIGHT_B = (22, 49, 70, 88, 103, 127, 147, 153, 161, 171, 181, 187, 195, 203, 214, 222, 229,
           231, 234)  # fmt: skip


def mesh_color(rgb: tuple[int, int, int] | np.ndarray) -> np.ndarray:
    """(3,) uint8: the instance colour that shows as ``rgb`` in the lit scene (a colour out
    of the light's range, darker than its black or lighter than its white, shows as near it
    as it can)."""
    c = np.asarray(rgb, float)
    out = [np.interp(c[i], LIGHT_B if i == 2 else LIGHT_RG, LIGHT_IN) for i in range(3)]
    return np.round(out).astype(np.uint8)


class RobotMeshes:
    """Every robot as three batched meshes, a unit box, cylinder and sphere scaled per
    instance (a capsule is a cylinder and two spheres): five arrays move all robots (a sphere,
    scaled alike on every axis, needs no orientation)."""

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

    def layout(
        self, methods: tuple[str, ...], colors: tuple[tuple[int, int, int], ...] | None = None
    ) -> None:
        """(Re)create the handles for these robots (instance colours carry the method: its
        strategy's, or ``colors``, one a robot)."""
        if colors is None:
            colors = tuple(METHOD_INFO[m].color for m in methods)
        for h in self.handles.values():
            h.remove()
        self.handles = {}
        n = len(methods)
        for kind, (mesh, body, _p, _R, scale, rgb, tint) in self.kinds.items():
            lit = np.array([mesh_color(c) for c in rgb], np.uint8).reshape(-1, 3)
            instance_colors = np.concatenate(
                [np.where(tint[:, None], mesh_color(c), lit) for c in colors]
            ).astype(np.uint8)
            k = len(body) * n
            self.handles[kind] = self.scene.add_batched_meshes_simple(
                f"{self.parent}/robot_{kind}",
                mesh.vertices,
                mesh.faces,
                batched_wxyzs=np.tile([1.0, 0, 0, 0], (k, 1)).astype(np.float32),
                batched_positions=np.zeros((k, 3), np.float32),
                batched_scales=np.tile(scale, (n, 1)),
                batched_colors=instance_colors,
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
            h = self.handles[kind]
            h.batched_positions = world.reshape(-1, 3).astype(np.float32)
            if kind == "sphere":
                continue  # a sphere, scaled alike on every axis, looks the same turned
            rot = np.einsum("nkij,kjl->nkil", xmat, R).reshape(-1, 3, 3)
            h.batched_wxyzs = vtf.SO3.from_matrix(rot).wxyz.astype(np.float32)

    def set_visible(self, visible: bool) -> None:
        for h in self.handles.values():
            h.visible = visible
