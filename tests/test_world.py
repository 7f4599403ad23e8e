"""The MuJoCo world: contacts, support polygon, falls, energy accounting."""

from __future__ import annotations

import numpy as np

from app.sim.world import World, convex_hull, point_in_polygon


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
    assert 0.0 < world.energy_per_joint.sum() < 1.0  # settling only: a fraction of a joule


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
