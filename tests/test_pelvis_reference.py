"""Tests of the reference pelvic angle, eq. (27)-(33)."""

import numpy as np
import pytest

from controller.params import LATERAL_MODES, ControllerParams
from controller.pelvis_reference import hip_points, lateral_distances, reference_pelvic_angles
from models.dyros_jet import ARM_JOINTS

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


def _walker(params):
    """A controller alone (no physics) at the model's walk-ready pose."""
    import mujoco

    from controller.kinematics import RobotKinematics
    from controller.walker import Walker
    from models.dyros_jet import KEYFRAME, LOWER_JOINTS, ROBOT_XML, SCENE_XML

    model = mujoco.MjModel.from_xml_path(str(SCENE_XML))
    key = model.key(KEYFRAME)
    names = LOWER_JOINTS + ARM_JOINTS
    q0 = np.array([key.qpos[model.jnt_qposadr[model.joint(n).id]] for n in names])
    return Walker(params, RobotKinematics(ROBOT_XML), q0, key.qpos[:3].copy())


@pytest.mark.parametrize("mode", LATERAL_MODES)
def test_theta_ref_carries_no_measurement_noise(mode):
    """Every reading of the lateral distance is taken on the CoM MPC's own state and plan:
    noise on the measured joints reaches the pelvis position (eq. 19) but not theta_ref."""
    params = ControllerParams().replace(
        method="mpc",
        walk={"step_length": 0.3, "n_steps": 3},
        pelvis={"lateral_distance": mode},
    )
    clean, noisy = _walker(params), _walker(params)
    rng = np.random.default_rng(0)
    for _ in range(300):  # the standing start, the first DSP and into its single support
        a = clean.tick(clean.q_cmd.copy())
        b = noisy.tick(noisy.q_cmd + rng.normal(0.0, 0.005, noisy.q_cmd.shape))
        np.testing.assert_array_equal(a.lateral, b.lateral)
        np.testing.assert_array_equal(a.theta_ref, b.theta_ref)
    assert np.abs(a.theta_ref).max() > np.radians(2.0)  # the reference does turn
    # the noise did reach the controller: the measured CoM moved the pelvis
    assert np.abs(a.p_world_pelvis_des - b.p_world_pelvis_des).max() > 1e-4
    assert np.abs(a.p_world_com_meas - b.p_world_com_meas).max() > 1e-4
