"""Camera views fit every robot shown, whatever their number and the browser's aspect."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.web.camera import CAMERA_VIEWS, ROBOT_SPACING, camera_pose, slot_offset


@pytest.mark.parametrize("name", list(CAMERA_VIEWS))
@pytest.mark.parametrize("n", [1, 2, 3, 5])
@pytest.mark.parametrize("aspect", [0.6, 1.0, 1.8])
def test_a_view_shows_every_robot_whole(name, n, aspect):
    along_x = name == "side"
    pos, look, up, fov = camera_pose(name, n, aspect, along_x)
    forward = (look - pos) / np.linalg.norm(look - pos)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    cam_up = np.cross(right, forward)
    tan_v, tan_h = math.tan(fov / 2), math.tan(fov / 2) * aspect
    for i in range(n):
        off = slot_offset(i, n)
        x, y = (off, 0.0) if along_x else (0.0, off)
        for dx in (-0.5, 0.5):  # a robot's feet, head and label corners
            for dy in (-0.3, 0.3):
                for z in (0.0, 2.2):
                    p = np.array([x + dx, y + dy, z]) - pos
                    depth = p @ forward
                    assert depth > 0
                    assert abs(p @ right) / depth <= tan_h + 1e-9, (name, n, aspect, i)
                    assert abs(p @ cam_up) / depth <= tan_v + 1e-9, (name, n, aspect, i)


def test_more_robots_move_the_camera_back():
    for name in CAMERA_VIEWS:
        d = [
            np.linalg.norm(np.subtract(*camera_pose(name, n, 1.3, name == "side")[:2]))
            for n in (1, 2, 3)
        ]
        assert d[0] < d[1] < d[2]
    assert ROBOT_SPACING > 1.0
