"""Pinocchio kinematics layer against MuJoCo and finite differences."""

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from controller import compiled
from controller.kinematics import (
    KinState,
    RobotKinematics,
    condition_number,
    jacobian_conditions,
    leg_reach,
)
from models.dyros_jet import (
    ARM_QP_JOINTS,
    FOOT_SITES,
    JOINTS,
    LOWER_JOINTS,
    SCENE_XML,
    walk_ready_joint_angles,
)


@pytest.fixture(scope="module")
def kin():
    return RobotKinematics()


@pytest.fixture(scope="module")
def mj():
    model = mujoco.MjModel.from_xml_path(str(SCENE_XML))
    return model, mujoco.MjData(model)


def _random_joints(kin, rng):
    lo, hi = kin.q_min, kin.q_max
    return lo + rng.uniform(0.05, 0.95, size=lo.shape) * (hi - lo)


def _random_quat(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


def _set_mj(mj, qj, p=(0.0, 0.0, 0.0), quat=(1.0, 0.0, 0.0, 0.0), qvel=None):
    model, data = mj
    data.qpos[:3] = p
    data.qpos[3:7] = quat
    data.qpos[7:] = qj
    data.qvel[:] = 0.0 if qvel is None else qvel
    mujoco.mj_fwdPosition(model, data)
    mujoco.mj_comVel(model, data)


def _dof(model, name):
    return model.jnt_dofadr[model.joint(name).id]


def test_structure(kin, mj):
    model, _ = mj
    assert kin.n_joints == 19
    assert kin.model.nq == model.nq and kin.model.nv == model.nv
    assert tuple(kin.model.names[2:]) == JOINTS
    for name, iv in zip(LOWER_JOINTS, kin.lower_v_idx, strict=True):
        assert iv == _dof(model, name)
    for name, iv in zip(ARM_QP_JOINTS, kin.arm_qp_v_idx, strict=True):
        assert iv == _dof(model, name)
    assert [JOINTS[i] for i in kin.arm_qp_joint_idx] == list(ARM_QP_JOINTS)
    np.testing.assert_allclose(kin.q_min, model.jnt_range[1:, 0])
    np.testing.assert_allclose(kin.q_max, model.jnt_range[1:, 1])
    assert kin.total_mass == pytest.approx(mujoco.mj_getTotalmass(model), abs=1e-9)


def test_com_and_soles_match_mujoco(kin, mj):
    _, data = mj
    rng = np.random.default_rng(0)
    for _ in range(10):
        qj = _random_joints(kin, rng)
        p = rng.normal(size=3)
        quat = _random_quat(rng)
        _set_mj(mj, qj, p, quat)
        np.testing.assert_allclose(kin.com_world(qj, p, quat), data.subtree_com[0], atol=1e-9)
        q = kin.configuration(qj, p, quat)
        pin.framesForwardKinematics(kin.model, kin.data, q)
        for side, site in enumerate(FOOT_SITES):
            oMf = kin.data.oMf[kin.sole_frame_ids[side]]
            np.testing.assert_allclose(oMf.translation, data.site(site).xpos, atol=1e-9)
            np.testing.assert_allclose(oMf.rotation, data.site(site).xmat.reshape(3, 3), atol=1e-9)


def test_compute_matches_mujoco_at_identity_base(kin, mj):
    model, data = mj
    rng = np.random.default_rng(1)
    for _ in range(10):
        qj = _random_joints(kin, rng)
        _set_mj(mj, qj)
        s = kin.compute(qj)
        assert isinstance(s, KinState)
        np.testing.assert_allclose(s.p_pelvis_com, data.subtree_com[0], atol=1e-9)
        cols = [_dof(model, n) for n in LOWER_JOINTS]
        rows = []
        for side, site in enumerate(FOOT_SITES):
            T = (s.T_pelvis_left_sole, s.T_pelvis_right_sole)[side]
            np.testing.assert_allclose(T[:3, 3], data.site(site).xpos, atol=1e-9)
            np.testing.assert_allclose(T[:3, :3], data.site(site).xmat.reshape(3, 3), atol=1e-9)
            jacp = np.zeros((3, model.nv))
            jacr = np.zeros((3, model.nv))
            mujoco.mj_jacSite(model, data, jacp, jacr, model.site(site).id)
            rows += [jacp[:, cols], jacr[:, cols]]
        np.testing.assert_allclose(s.J_low, np.vstack(rows), atol=1e-9)


def test_foot_jacobian_matches_mujoco_with_random_base(kin, mj):
    """Hinge columns in world axes agree for any base pose (LOCAL_WORLD_ALIGNED)."""
    model, data = mj
    rng = np.random.default_rng(2)
    for _ in range(5):
        qj = _random_joints(kin, rng)
        p, quat = rng.normal(size=3), _random_quat(rng)
        _set_mj(mj, qj, p, quat)
        q = kin.configuration(qj, p, quat)
        pin.computeJointJacobians(kin.model, kin.data, q)
        pin.updateFramePlacements(kin.model, kin.data)
        for side, site in enumerate(FOOT_SITES):
            J = pin.getFrameJacobian(
                kin.model, kin.data, kin.sole_frame_ids[side], pin.LOCAL_WORLD_ALIGNED
            )
            jacp = np.zeros((3, model.nv))
            jacr = np.zeros((3, model.nv))
            mujoco.mj_jacSite(model, data, jacp, jacr, model.site(site).id)
            np.testing.assert_allclose(J[:3, 6:], jacp[:, 6:], atol=1e-9)
            np.testing.assert_allclose(J[3:, 6:], jacr[:, 6:], atol=1e-9)


def test_velocity_conversion_from_mujoco(kin, mj):
    """from_mujoco: world-frame free-joint linear velocity -> Pinocchio's local one."""
    model, data = mj
    rng = np.random.default_rng(3)
    qj = _random_joints(kin, rng)
    qvel = rng.normal(size=model.nv)
    _set_mj(mj, qj, rng.normal(size=3), _random_quat(rng), qvel)
    q, v = kin.from_mujoco(data.qpos.copy(), data.qvel.copy())
    pin.forwardKinematics(kin.model, kin.data, q, v)
    pin.updateFramePlacements(kin.model, kin.data)
    for side, site in enumerate(FOOT_SITES):
        vel = pin.getFrameVelocity(
            kin.model, kin.data, kin.sole_frame_ids[side], pin.LOCAL_WORLD_ALIGNED
        )
        jacp = np.zeros((3, model.nv))
        jacr = np.zeros((3, model.nv))
        mujoco.mj_jacSite(model, data, jacp, jacr, model.site(site).id)
        np.testing.assert_allclose(vel.linear, jacp @ qvel, atol=1e-9)
        np.testing.assert_allclose(vel.angular, jacr @ qvel, atol=1e-9)


def test_J_low_finite_differences(kin):
    rng = np.random.default_rng(4)
    h = 1e-6
    lower_joint_idx = [JOINTS.index(n) for n in LOWER_JOINTS]
    for _ in range(5):
        qj = _random_joints(kin, rng)
        J = kin.compute(qj).J_low
        J_fd = np.zeros_like(J)
        for c, jidx in enumerate(lower_joint_idx):
            dq = np.zeros(kin.n_joints)
            dq[jidx] = h
            for side in (0, 1):
                Tp = kin.sole_pose_pelvis(qj + dq, side)
                Tm = kin.sole_pose_pelvis(qj - dq, side)
                J_fd[6 * side : 6 * side + 3, c] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
                J_fd[6 * side + 3 : 6 * side + 6, c] = pin.log3(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)
        np.testing.assert_allclose(J, J_fd, atol=1e-6)


def test_cmm_yaw_rows_match_mujoco_angular_momentum(kin, mj):
    model, data = mj
    rng = np.random.default_rng(5)
    low_dofs = [_dof(model, n) for n in LOWER_JOINTS]
    up_dofs = [_dof(model, n) for n in ARM_QP_JOINTS]
    for _ in range(5):
        qj = _random_joints(kin, rng)
        qd_low, qd_up = rng.normal(size=13), rng.normal(size=4)
        qvel = np.zeros(model.nv)
        qvel[low_dofs] = qd_low
        qvel[up_dofs] = qd_up
        _set_mj(mj, qj, qvel=qvel)
        mujoco.mj_subtreeVel(model, data)
        h_mj = data.subtree_angmom[model.body("pelvis").id]
        s = kin.compute(qj)
        assert s.cmm_yaw_low @ qd_low + s.cmm_yaw_up @ qd_up == pytest.approx(h_mj[2], abs=1e-9)


def test_hips_ankles_and_reach(kin):
    s = kin.compute(np.zeros(19))
    np.testing.assert_allclose(s.p_pelvis_hips, [[0, 0.105, -0.1119], [0, -0.105, -0.1119]])
    np.testing.assert_allclose(leg_reach(s), [1.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(s.p_pelvis_ankles[:, 2], -0.1119 - 0.7442, atol=1e-12)
    s = kin.compute(walk_ready_joint_angles())
    # hips 0.68 m above the ankles, feet at y = +/-0.1215
    np.testing.assert_allclose(s.p_pelvis_hips[:, 2] - s.p_pelvis_ankles[:, 2], 0.68, atol=1e-9)
    np.testing.assert_allclose(s.T_pelvis_left_sole[:3, 3], [0, 0.1215, -0.8969], atol=1e-9)
    assert np.all(leg_reach(s) < 1.0)


def test_support_anchored_base(kin, mj):
    _, data = mj
    qj = _random_joints(kin, np.random.default_rng(6))
    target = np.array([0.3, -0.2, 0.01])
    for side, site in enumerate(FOOT_SITES):
        p = kin.support_anchored_base(qj, side, target)
        _set_mj(mj, qj, p)
        np.testing.assert_allclose(data.site(site).xpos, target, atol=1e-12)


def test_condition_number_known_matrices():
    assert condition_number(np.eye(4)) == pytest.approx(1.0)
    assert condition_number(np.diag([3.0, 2.0, 0.5])) == pytest.approx(6.0)
    R = np.linalg.qr(np.random.default_rng(7).normal(size=(5, 5)))[0]
    assert condition_number(R @ np.diag([10.0, 4, 3, 2, 1])) == pytest.approx(10.0)
    assert condition_number(np.array([[1.0, 2.0], [2.0, 4.0]])) == float("inf")
    assert condition_number(np.zeros((3, 3))) == float("inf")
    assert condition_number(np.ones((2, 3))) == float("inf")


def test_condition_number_grows_as_leg_straightens(kin):
    kappas = []
    for knee in (1.2, 0.8, 0.4, 0.2, 0.1, 0.05, 0.01):
        qj = walk_ready_joint_angles()
        for base in (1, 7):  # left and right leg
            qj[base + 2], qj[base + 3], qj[base + 4] = -knee / 2, knee, -knee / 2
        kappas.append(condition_number(kin.compute(qj).J_low))
    assert all(b > a for a, b in zip(kappas, kappas[1:], strict=False))
    assert kappas[-1] > 50 * kappas[0]
    qj = np.zeros(19)
    assert condition_number(kin.compute(qj).J_low) > 1e8


def _svd_kappa(J):
    """sigma_max / sigma_min by numpy's SVD: the reference the compiled kappa is checked on."""
    sigma = np.linalg.svd(J, compute_uv=False)
    return sigma[0] / sigma[-1]


def test_jacobian_conditions_match_the_svd_and_see_one_straight_knee(kin):
    """kappa of J_low and of its leg columns (eq. 45, the same for every method): with one
    knee straight the leg columns are singular, while the waist column keeps J_low's rank."""
    for knee in (1.0, 0.3, 0.05):
        qj = walk_ready_joint_angles()
        qj[3], qj[4], qj[5] = -knee / 2, knee, -knee / 2  # left leg
        J = kin.compute(qj).J_low
        low, legs = jacobian_conditions(J)
        assert low == pytest.approx(_svd_kappa(J), rel=1e-6)
        assert legs == pytest.approx(_svd_kappa(J[:, 1:]), rel=1e-6)
        assert condition_number(J) == low
    qj = walk_ready_joint_angles()
    qj[4] = 0.0  # left knee straight, the leg tilted as in a step (hip pitch -0.42 rad)
    low, legs = jacobian_conditions(kin.compute(qj).J_low)
    assert legs > 1e6 and low < 1e3


def test_extreme_eigenvalues_match_lapack():
    """The compiled eigenvalue kernel behind kappa: the smallest and largest eigenvalue of
    symmetric matrices (definite, indefinite, rank-deficient, repeated, diagonal) as LAPACK."""
    rng = np.random.default_rng(7)
    cases = [np.zeros((3, 3)), 2.0 * np.eye(4), np.array([[5.0]]), np.diag([1.0, 1.0, 3.0])]
    for _ in range(300):
        n = int(rng.integers(2, 14))
        X = rng.normal(size=(n, n)) * 10 ** rng.uniform(-3, 3)
        U = rng.normal(size=(n, n - 1))
        cases += [X @ X.T, X + X.T, U @ U.T]
    for A in cases:
        lam = np.linalg.eigvalsh(A)
        lo, hi = compiled.extreme_eigenvalues(A)
        scale = max(np.abs(lam).max(), 1e-300)
        assert abs(lo - lam[0]) <= 1e-13 * scale and abs(hi - lam[-1]) <= 1e-13 * scale
