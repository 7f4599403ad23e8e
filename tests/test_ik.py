"""Tests of the QP inverse kinematics, eq. (39)-(40)."""

import numpy as np
import pytest

from controller.ik import WAIST, build_ik, foot_velocity_command, log3, solve_ik
from controller.params import IkParams
from controller.qp import QpSolver, solve_exact

DT = 0.005
QMIN, QMAX = np.full(13, -2.0), np.full(13, 2.0)


def _rot(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _pose(R, p):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T


def _J(seed=0):
    return np.random.default_rng(seed).normal(size=(12, 13))


def test_log3():
    rng = np.random.default_rng(1)
    for angle in [0.0, 1e-8, 0.3, 2.0, np.pi - 1e-6, np.pi]:
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        w = log3(_rot(axis, angle))
        assert abs(np.linalg.norm(w) - angle) < 1e-6
        if 1e-3 < angle < np.pi - 1e-3:
            assert np.allclose(w, angle * axis, atol=1e-9)
        assert np.allclose(
            _rot(w, np.linalg.norm(w)) if angle > 0 else np.eye(3), _rot(axis, angle), atol=1e-5
        )


@pytest.mark.parametrize("waist_rate", [0.0, None])  # pinned (fixed, mpc) or free
def test_zero_when_on_target(waist_rate):
    T_l, T_r = _pose(np.eye(3), [0, 0.1, -0.7]), _pose(_rot([0, 0, 1], 0.1), [0.1, -0.1, -0.7])
    v = foot_velocity_command(T_l, T_l, np.zeros(6), T_r, T_r, np.zeros(6), 20.0)
    assert np.allclose(v, 0.0)
    qp = build_ik(_J(), v, np.zeros(13), QMIN, QMAX, IkParams(), DT, waist_rate)
    qd, ok = solve_ik(qp, QpSolver("osqp"))
    assert ok and np.max(np.abs(qd)) < 1e-6


def test_foot_velocity_command_error_terms():
    T_c = _pose(np.eye(3), [0, 0, 0])
    T_d = _pose(_rot([0, 0, 1], 0.2), [0.01, 0, 0])
    v = foot_velocity_command(T_c, T_d, np.ones(6), T_c, T_c, np.zeros(6), 10.0)
    assert np.allclose(v[:6], 1.0 + 10.0 * np.array([0.01, 0, 0, 0, 0, 0.2]))
    assert np.allclose(v[6:], 0.0)


@pytest.mark.parametrize("backend", ["osqp", "daqp"])
def test_reproduces_feasible_target(backend):
    J = _J(2)
    qd_true = np.random.default_rng(3).uniform(-0.5, 0.5, 13)
    qd_true[WAIST] = 0.0
    v = J @ qd_true
    p = IkParams(damping=1e-8)
    qp = build_ik(J, v, np.zeros(13), QMIN, QMAX, p, DT, 0.0)
    qd, ok = solve_ik(qp, QpSolver(backend))
    assert ok
    assert np.linalg.norm(J @ qd - v) < 1e-4 * np.linalg.norm(v)


def test_waist_rate_pinned_and_clipped():
    J, v = _J(4), np.random.default_rng(5).normal(size=12) * 0.1
    qp = build_ik(J, v, np.zeros(13), QMIN, QMAX, IkParams(), DT, 0.7)
    qd, ok = solve_ik(qp, QpSolver("osqp"))
    assert ok and abs(qd[WAIST] - 0.7) < 1e-7
    # Near the waist limit: the pinned rate is clipped into the joint-limit bound.
    q = np.zeros(13)
    q[WAIST] = 2.0 - 0.001
    qp = build_ik(J, v, q, QMIN, QMAX, IkParams(), DT, 5.0)
    qd, ok = solve_ik(qp, QpSolver("osqp"))
    assert ok and abs(qd[WAIST] - 0.001 / DT) < 1e-6


def test_joint_limits_respected():
    J = _J(6)
    v = np.random.default_rng(7).normal(size=12) * 50.0  # far too fast
    q = np.random.default_rng(8).uniform(-1.99, 1.99, 13)
    p = IkParams()
    qp = build_ik(J, v, q, QMIN, QMAX, p, DT, None)
    qd, ok = solve_ik(qp, QpSolver("osqp"))
    assert ok
    q_next = q + DT * qd
    assert np.all(q_next >= QMIN - 1e-6) and np.all(q_next <= QMAX + 1e-6)
    assert np.all(np.abs(qd) <= p.joint_speed_limit + 1e-6)


@pytest.mark.parametrize("waist_rate", [0.0, 0.3, None])
def test_osqp_matches_exact(waist_rate):
    rng = np.random.default_rng(9)
    solver = QpSolver("osqp")
    for _ in range(5):
        J = rng.normal(size=(12, 13))
        v = rng.normal(size=12) * 5.0
        q = rng.uniform(-1.9, 1.9, 13)
        qp = build_ik(J, v, q, QMIN, QMAX, IkParams(), DT, waist_rate)
        qd, ok = solve_ik(qp, solver)
        assert ok and np.max(np.abs(qd - solve_exact(qp))) < 1e-6


def test_redundancy_moves_waist_when_useful():
    # The waist column is the only way to produce the first task direction cheaply.
    J = _J(10)
    v = J[:, WAIST] * 1.0  # exactly the waist's own motion
    p = IkParams(damping=1e-3)
    qd_fixed, _ = solve_ik(build_ik(J, v, np.zeros(13), QMIN, QMAX, p, DT, 0.0), QpSolver("daqp"))
    qd_red, ok = solve_ik(build_ik(J, v, np.zeros(13), QMIN, QMAX, p, DT, None), QpSolver("daqp"))
    assert ok and abs(qd_fixed[WAIST]) < 1e-12
    assert qd_red[WAIST] > 0.5
    assert np.sum(qd_red**2) < np.sum(qd_fixed**2)


def test_redundancy_pulls_waist_to_zero_in_null_space():
    # Feet still (v = 0): only the null-space motion is free; the waist decays toward 0.
    J = _J(11)
    q = np.zeros(13)
    q[WAIST] = 0.3
    qd, ok = solve_ik(
        build_ik(J, np.zeros(12), q, QMIN, QMAX, IkParams(), DT, None), QpSolver("daqp")
    )
    assert ok and qd[WAIST] < 0.0
    assert np.linalg.norm(J @ qd) < 1e-3
