"""Where the QP inspector's constraints have a place in the 3-D scene: a joint the
IK or the arm QP holds at its angle limit is marked on the robot, a red dot at the joint.

Self-contained: the scene makes one :class:`LimitMarks` and draws it with its overlays; the
marks read each robot frame's explanation (:attr:`~pelvic_walk.core.frames.RobotFrame.qp`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from app.live import RobotFrame
from app.web.overlays import DANGER
from models.dyros_jet import ARM_QP_JOINTS, LOWER_JOINTS

_NONE = np.zeros((1, 3), np.float32)


def limit_joints(r: RobotFrame) -> list[str]:
    """The joints robot ``r``'s IK or arm QP holds at an angle limit at its last tick."""
    rec = r.qp
    if rec is None:
        return []
    return [
        c.joint
        for layer in ("ik", "arm_swing")
        for c in rec[layer].active
        if c.kind == "joint limit" and c.joint is not None
    ]


class LimitMarks:
    """Red dots on the joints held at their limits (one point cloud for every robot)."""

    def __init__(self, scene: Any, model: Any, name: str = "/world/qp_limits"):
        self.body = {
            j: int(model.jnt_bodyid[model.joint(j).id]) for j in (*LOWER_JOINTS, *ARM_QP_JOINTS)
        }
        self.handle = scene.add_point_cloud(
            name, _NONE, DANGER, point_size=0.06, point_shape="circle", precision="float32"
        )
        self.handle.visible = False
        self.shown: list[tuple[str, str]] = []  # (method, joint) marked now

    def draw(self, robots: tuple[RobotFrame, ...], offsets: np.ndarray) -> None:
        """Mark the joints at a limit; ``offsets`` (n, 2): each robot's place in the row."""
        pts, shown = [], []
        for r, (dx, dy) in zip(robots, offsets, strict=True):
            for j in limit_joints(r):
                p = np.asarray(r.body_xpos[self.body[j]], np.float32) + (dx, dy, 0.0)
                pts.append(p)
                shown.append((r.method, j))
        self.shown = shown
        if pts:
            self.handle.points = np.array(pts, np.float32)
            self.handle.colors = np.tile(np.array(DANGER, np.uint8), (len(pts), 1))
        self.handle.visible = bool(pts)
