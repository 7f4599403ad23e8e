"""Tests of the reference pelvic angle, eq. (27)-(33)."""

import numpy as np
import pytest

from controller.pelvis_reference import hip_points, lateral_distances, reference_pelvic_angles

K, HW = 0.25, 0.1215
NOMINAL = np.array([[HW, -HW]])


def _ref(dx_left, dx_right, px=0.0):
    p = np.array([[px, 0.0]])
    return reference_pelvic_angles(
        p, np.array([[px + dx_left, HW]]), np.array([[px + dx_right, -HW]]), K, NOMINAL
    )


def test_paper_magnitude_and_sign():
    theta = _ref(0.2, -0.2)
    assert np.degrees(theta[0]) == np.float64(np.degrees(theta[0]))
    assert abs(np.degrees(theta[0]) - (-22.36)) < 0.05
    # The rotated left hip moves forward, so the forward (left) leg's hip-to-foot distance
    # shrinks and the rear leg's too.
    hips0 = hip_points(np.zeros((1, 2)), np.zeros(1))[0]
    hips = hip_points(np.zeros((1, 2)), theta)[0]
    assert hips[0, 0] > 0.0 and hips[1, 0] < 0.0
    foot_l, foot_r = np.array([0.2, HW]), np.array([-0.2, -HW])
    assert np.linalg.norm(foot_l - hips[0]) < np.linalg.norm(foot_l - hips0[0])
    assert np.linalg.norm(foot_r - hips[1]) < np.linalg.norm(foot_r - hips0[1])


def test_symmetric_gives_zero():
    assert abs(_ref(0.1, 0.1)[0]) < 1e-12
    assert abs(_ref(0.0, 0.0)[0]) < 1e-12


def test_mirror_symmetry():
    rng = np.random.default_rng(0)
    for _ in range(20):
        a, b = rng.uniform(-0.4, 0.4, 2)
        assert abs(_ref(a, b)[0] + _ref(b, a)[0]) < 1e-12


def test_vectorised_and_translation_invariant():
    n = 16
    p = np.column_stack([np.linspace(0, 0.4, n), 0.03 * np.sin(np.linspace(0, 3, n))])
    left = np.column_stack([np.full(n, 0.4), np.full(n, HW)])
    right = np.column_stack([np.full(n, 0.0), np.full(n, -HW)])
    lateral = np.tile(NOMINAL, (n, 1))
    th = reference_pelvic_angles(p, left, right, K, lateral)
    assert th.shape == (n,)
    shift = np.array([1.0, 0.5])
    th2 = reference_pelvic_angles(p + shift, left + shift, right + shift, K, lateral)
    assert np.allclose(th, th2)
    # Pelvis midway between the feet at 0.2: left ahead by 0.2 -> -22.4 deg.
    mid = np.argmin(np.abs(p[:, 0] - 0.2))
    assert np.degrees(th[mid]) < -20.0


def test_hip_points_shape_and_width():
    th = np.radians([0.0, 30.0, -45.0])
    h = hip_points(np.zeros((3, 2)), th, 0.105)
    assert h.shape == (3, 2, 2)
    assert np.allclose(np.linalg.norm(h[:, 0] - h[:, 1], axis=1), 0.21)
    assert h[1, 0, 0] < 0.0  # positive yaw: left hip backward


def test_lateral_distance_modes():
    n = 4
    pelvis = np.column_stack([np.zeros(n), np.linspace(-0.05, 0.11, n)])  # sways to the left
    left = np.tile([0.3, HW], (n, 1))
    right = np.tile([0.0, -HW], (n, 1))
    now = np.array([0.0, 0.02]), np.array([0.3, HW]), np.array([0.0, -HW])
    nominal = lateral_distances("nominal", pelvis, left, right, *now, HW, 0.03)
    np.testing.assert_allclose(nominal, np.tile([HW, -HW], (n, 1)))
    current = lateral_distances("current", pelvis, left, right, *now, HW, 0.03)
    np.testing.assert_allclose(current, np.tile([HW - 0.02, -HW - 0.02], (n, 1)))
    pred = lateral_distances("predicted", pelvis, left, right, *now, HW, 0.03)
    np.testing.assert_allclose(pred[:, 1], -HW - pelvis[:, 1])
    # over the left foot (0.11 of 0.1215): the floor keeps the distance at 3 cm, sign kept
    np.testing.assert_allclose(pred[:, 0], np.maximum(HW - pelvis[:, 1], 0.03))
    assert pred[-1, 0] == pytest.approx(0.03)
    with pytest.raises(ValueError, match="lateral distance mode"):
        lateral_distances("sideways", pelvis, left, right, *now, HW, 0.03)


def test_a_wrongly_signed_lateral_distance_is_refused():
    with pytest.raises(ValueError, match="left foot"):
        reference_pelvic_angles(
            np.zeros((1, 2)), np.zeros((1, 2)), np.zeros((1, 2)), K, np.array([[-HW, -HW]])
        )
