"""Camera views fit every robot shown, whatever their number and the browser's aspect."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.web.camera import CAMERA_VIEWS, ROBOT_SPACING, camera_pose, label_point, slot_offset


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


def _pixels(name: str, n: int, aspect: float, height_px: float):
    """A function from world points to (right, up) pixels from the canvas centre."""
    pos, look, up, fov = camera_pose(name, n, aspect, name == "side")
    forward = (look - pos) / np.linalg.norm(look - pos)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    cam_up = np.cross(right, forward)
    scale = height_px / 2 / math.tan(fov / 2)

    def px(p):
        d = np.asarray(p, float) - pos
        depth = d @ forward
        return np.array([d @ right, d @ cam_up]) / depth * scale

    return px


@pytest.mark.parametrize("n", [1, 2, 3])
@pytest.mark.parametrize("aspect", [1.0, 1.5, 1.8])
@pytest.mark.parametrize("height_px", [500.0, 800.0])
def test_seen_from_above_a_label_hides_no_robot(n, aspect, height_px):
    """In the top view a label (three lines of text above its point, about 60 x 210 px)
    covers neither its robot nor another and lies inside the canvas."""
    text_h, text_w = 60.0, 210.0
    px = _pixels("top", n, aspect, height_px)
    boxes = []  # each robot's outline on the screen (|y| <= 0.325 m standing, arms included)
    for i in range(n):
        y = slot_offset(i, n)
        corners = np.array(
            [px((dx, y + dy, z)) for dx in (-0.35, 0.35) for dy in (-0.33, 0.33) for z in (0, 1.9)]
        )
        boxes.append((corners.min(axis=0), corners.max(axis=0)))
    for i in range(n):
        a = px(label_point(0.0, (0.0, slot_offset(i, n)), i, n, from_above=True))
        lo, hi = a - (text_w / 2, 0.0), a + (text_w / 2, text_h)  # text above its point
        half = np.array([height_px * aspect, height_px]) / 2
        assert np.all(np.abs(lo) <= half) and np.all(np.abs(hi) <= half), (n, aspect, i)
        for b_lo, b_hi in boxes:
            overlap = np.all(lo < b_hi) and np.all(b_lo < hi)
            assert not overlap, (n, aspect, i)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_elsewhere_labels_float_over_the_heads_at_different_heights(n):
    points = [label_point(0.3, (0.0, slot_offset(i, n)), i, n, from_above=False) for i in range(n)]
    assert all(p[2] > 1.95 for p in points)  # above the head (the robot is ~1.9 m tall)
    assert len({round(float(p[2]), 3) for p in points}) == n
    assert all(p[0] == pytest.approx(0.3) for p in points)
