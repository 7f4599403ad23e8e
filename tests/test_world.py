"""The MuJoCo world: contacts, support polygon, falls, energy accounting."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pelvic_walk.core.world import World, convex_hull, point_in_polygon, polygon_margin


def test_convex_hull_and_point_in_polygon():
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]], dtype=float)
    hull = convex_hull(square)
    assert len(hull) == 4
    assert point_in_polygon(np.array([0.5, 0.5]), hull)
    assert point_in_polygon(np.array([1.0005, 0.5]), hull)  # within the 1 mm tolerance
    assert not point_in_polygon(np.array([1.1, 0.5]), hull)
    assert not point_in_polygon(np.array([0.5, 0.5]), hull[:2])


def test_standing_robot_has_both_feet_in_contact_and_cop_between_them():
    world = World()
    q = world.keyframe_joints()
    for _ in range(100):
        world.step(q)
    c = world.contacts()
    assert c.in_contact.all() and not c.other_contact
    assert abs(c.normal_force.sum() - 50.19 * 9.81) < 30  # the weight rests on the feet
    hull = world.support_polygon(c.in_contact)
    assert point_in_polygon(c.cop, hull)
    assert abs(c.cop[1]) < 0.03  # between the feet
    assert world.fall_reason() is None
    # settling only: a fraction of a joule, either way it is counted
    assert 0.0 < world.energy_substep_per_joint.sum() < 1.0
    assert 0.0 <= world.energy_ctrl_per_joint.sum() < 1.0
    assert np.all(world.sole_tilts() < np.radians(0.5))  # flat on the floor


def test_a_limp_robot_falls_and_is_detected():
    world = World()
    world.model.actuator_gainprm[:, 0] = 0.0  # servos off
    world.model.actuator_biasprm[:, :] = 0.0
    q = world.keyframe_joints()
    reason = None
    for _ in range(600):  # 3 s
        world.step(q)
        reason = world.fall_reason() or ("other" if world.contacts().other_contact else None)
        if reason:
            break
    assert reason is not None


def test_reset_with_seed_perturbs_reproducibly():
    a, b = World(), World()
    a.reset(seed=3, perturbation=0.01)
    b.reset(seed=3, perturbation=0.01)
    np.testing.assert_array_equal(a.data.qpos, b.data.qpos)
    b.reset(seed=4, perturbation=0.01)
    assert not np.array_equal(a.data.qpos, b.data.qpos)


def test_polygon_margin_is_signed_distance_to_the_edge():
    square = convex_hull(np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float))
    assert polygon_margin(np.array([0.5, 0.5]), square) == pytest.approx(0.5)
    assert polygon_margin(np.array([0.9, 0.5]), square) == pytest.approx(0.1)
    assert polygon_margin(np.array([1.0, 0.3]), square) == pytest.approx(0.0)
    assert polygon_margin(np.array([1.2, 0.5]), square) == pytest.approx(-0.2)
    assert polygon_margin(np.array([0.5, 0.5]), square[:2]) == -math.inf


def test_a_push_moves_the_robot_and_stops():
    pushed, still = World(), World()
    q = pushed.keyframe_joints()
    pushed.push(np.array([0.0, 150.0]), 0.1)
    for _ in range(20):  # 0.1 s
        pushed.step(q)
        still.step(q)
    assert pushed.pushing is False  # over after its 0.1 s
    assert pushed.data.xfrc_applied[pushed.root_id, :3].tolist() == [0.0, 0.0, 0.0]
    # 150 N x 0.1 s on 50 kg: about 0.3 m/s sideways, none forward
    vy = pushed.data.qvel[1] - still.data.qvel[1]  # the free joint's world-frame velocity
    assert 0.1 < vy < 0.35
