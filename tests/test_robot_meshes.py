"""The scene's robots: every batched instance sits where MuJoCo places its geom."""

from __future__ import annotations

from types import SimpleNamespace

import mujoco
import numpy as np
import viser.transforms as vtf

from app.web.robot_meshes import RobotMeshes
from pelvic_walk.core.world import World


class _Handle:
    """Stands in for a viser batched-mesh handle: records the properties set on it."""

    def __init__(self, **props):
        self.props = dict(props)
        self.sets: list[str] = []

    def __setattr__(self, name, value):
        if name.startswith("batched_"):
            self.props[name] = value
            self.sets.append(name)
        else:
            object.__setattr__(self, name, value)

    def remove(self) -> None:
        pass


class _Scene:
    def __init__(self):
        self.handles: dict[str, _Handle] = {}

    def add_batched_meshes_simple(self, name, vertices, faces, **props):
        self.handles[name] = _Handle(**props)
        return self.handles[name]


def _posed_world(seed: int) -> World:
    """The robot in a random joint configuration (so every geom has its own orientation)."""
    world = World()
    world.reset()
    rng = np.random.default_rng(seed)
    world.data.qpos[world.qpos_idx] += rng.uniform(-0.4, 0.4, len(world.qpos_idx))
    world.data.qpos[3:7] = vtf.SO3.from_rpy_radians(0.1, -0.2, 0.7).wxyz
    mujoco.mj_forward(world.model, world.data)
    return world


def test_instances_follow_the_geoms_and_spheres_send_no_orientation():
    world = _posed_world(3)
    m, d = world.model, world.data
    scene = _Scene()
    meshes = RobotMeshes(scene, m, "/world")
    meshes.layout(("fixed", "mpc"))
    frame = SimpleNamespace(body_xpos=d.xpos.copy(), body_xmat=d.xmat.reshape(-1, 3, 3).copy())
    offsets = np.array([[0.0, 0.5], [1.0, -0.5]])
    for h in scene.handles.values():
        h.sets.clear()
    meshes.draw((frame, frame), offsets)

    # where each visible geom of the robot must be drawn: its centre (a capsule: a cylinder
    # at its centre and a sphere at each end) with its orientation
    want: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {"box": [], "cylinder": [], "sphere": []}
    for g in range(m.ngeom):
        if m.geom_bodyid[g] == 0 or m.geom_rgba[g, 3] == 0:
            continue
        p, R = d.geom_xpos[g].copy(), d.geom_xmat[g].reshape(3, 3).copy()
        kind = {6: "box", 5: "cylinder", 2: "sphere", 3: "capsule"}[int(m.geom_type[g])]
        if kind == "capsule":
            axis = R[:, 2] * m.geom_size[g, 1]
            want["sphere"] += [(p + axis, R), (p - axis, R)]
            kind = "cylinder"
        want[kind].append((p, R))

    for kind, rows in want.items():
        h = scene.handles[f"/world/robot_{kind}"]
        pos = h.props["batched_positions"].reshape(2, -1, 3)
        assert pos.shape[1] == len(rows)
        for robot, off in enumerate(offsets):
            drawn = pos[robot]
            expected = np.array([p for p, _ in rows]) + (*off, 0.0)
            # the same set of points (instances are grouped by kind, not in geom order)
            for e in expected:
                assert np.min(np.linalg.norm(drawn - e, axis=1)) < 1e-5, (kind, e)
        if kind == "sphere":
            assert h.sets == ["batched_positions"]  # nothing else is sent per frame
            continue
        assert sorted(h.sets) == ["batched_positions", "batched_wxyzs"]
        mats = vtf.SO3(h.props["batched_wxyzs"].astype(float)).as_matrix().reshape(2, -1, 3, 3)
        for robot in range(2):
            shifted = pos[robot] - (*offsets[robot], 0.0)
            for p, R in rows:
                i = int(np.argmin(np.linalg.norm(shifted - p, axis=1)))
                assert np.allclose(mats[robot, i], R, atol=1e-5), (kind, p)
