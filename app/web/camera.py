"""Named camera views fitted to the robots shown (follow, side, top, front) and where each
robot stands in the scene."""

from __future__ import annotations

import math

import numpy as np

ROBOT_SPACING = 1.8  # [m] between robots, in y: labels and gauges never overlap

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
LABEL_HEIGHT = 2.05  # [m] the lowest label's point, over the head (the robot is ~1.9 m tall)
LABEL_STAGGER = 0.3  # [m] between the labels' heights
LABEL_SIDE_Y = 0.55  # [m] from a robot's line to its label's point, seen from above
LABEL_TEXT_Y = 0.7  # [m] room the label's text takes up the screen in the top view (~60 px)


def camera_pose(
    name: str, n: int, aspect: float, along_x: bool, stagger_x: float = 0.0
) -> tuple[np.ndarray, np.ndarray, tuple[float, float, float], float]:
    """(position, look_at, up, vertical fov [rad]) of a named view that shows ``n`` robots
    side by side (along x when ``along_x``) whole in a canvas of ``aspect`` = width/height,
    and still whole when they are up to ``stagger_x`` [m] apart along x (one lying where it
    fell while the others walk on: the scene centres between them)."""
    direction, up, fov_deg = CAMERA_VIEWS[name]
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    spread = (max(n, 1) - 1) / 2 * ROBOT_SPACING + VIEW_MARGIN
    top = LABEL_HEIGHT + 0.25 + LABEL_STAGGER * max(n - 1, 0)  # the highest label
    half = stagger_x / 2 if n > 1 else 0.0
    lo = np.array(
        [(-spread if along_x else -VIEW_MARGIN) - half, -VIEW_MARGIN if along_x else -spread, 0]
    )
    hi = np.array([(spread if along_x else 1.2) + half, VIEW_MARGIN if along_x else spread, top])
    if name == "top":  # the outer label lies beside its robot, up the screen (label_point)
        hi[1] = max(hi[1], lo[1] + 2 * spread - VIEW_MARGIN + LABEL_SIDE_Y + LABEL_TEXT_Y)
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


def label_point(
    x: float, offset: tuple[float, float], slot: int, n: int, from_above: bool
) -> np.ndarray:
    """(3,) [m] where robot ``slot``'s label (anchored at its text's bottom centre) is put.

    Over the head at staggered heights, so labels never overlap whatever the camera; seen from
    above a label there hides its robot, so it is put beside the head, on the +y side (up the
    screen in the top view), between the rows of robots (ROBOT_SPACING apart); at the head's
    height the perspective moves it with the head.
    ``x`` is the robot's forward position, ``offset`` its (x, y) offset in the scene.
    """
    if from_above:
        return np.array([x + offset[0], offset[1] + LABEL_SIDE_Y, 1.9], np.float32)
    z = LABEL_HEIGHT + LABEL_STAGGER * (n - 1 - slot)
    return np.array([x + offset[0], offset[1], z], np.float32)
