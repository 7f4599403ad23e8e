"""Tests of the arm-swing QP, eq. (41)-(43)."""

import dataclasses

import numpy as np
import pytest

from controller.arm_swing import build_arm_qp, solve_arm, yaw_momentum
from controller.params import ArmParams
from controller.qp import QpSolver, solve_exact

DT = 0.005
QMIN, QMAX = np.full(4, -2.5), np.full(4, 2.5)
A_UP = np.array([0.15, 0.05, -0.15, -0.05])  # shoulder pitch/elbow, left/right
A_LOW = np.linspace(-0.1, 0.5, 13)


def _case(q_dot_low, q_up=None, q_init=None, params=None):
    q_up = np.zeros(4) if q_up is None else q_up
    q_init = np.zeros(4) if q_init is None else q_init
    params = ArmParams() if params is None else params
    return build_arm_qp(A_LOW, q_dot_low, A_UP, q_up, q_init, QMIN, QMAX, 10.0, params, DT)


@pytest.mark.parametrize("backend", ["osqp", "daqp"])
def test_reduces_total_yaw_momentum(backend):
    q_dot_low = np.full(13, 0.2)
    h_low = yaw_momentum(A_LOW, q_dot_low)
    assert abs(h_low) > 0.1
    qd, ok = solve_arm(_case(q_dot_low), QpSolver(backend))
    assert ok
    assert abs(h_low + yaw_momentum(A_UP, qd)) < 0.5 * abs(h_low)
    assert np.all(np.abs(qd) <= 10.0 + 1e-6)


def test_inert_without_momentum_term():
    p = dataclasses.replace(ArmParams(), omega1=0.0)
    qd, ok = solve_arm(_case(np.full(13, 0.2), params=p), QpSolver("osqp"))
    assert ok and np.max(np.abs(qd)) < 1e-9


def test_returns_to_initial_pose():
    p = dataclasses.replace(ArmParams(), omega1=0.0)
    qd, ok = solve_arm(_case(np.zeros(13), q_up=np.full(4, 0.1), params=p), QpSolver("daqp"))
    assert ok and np.all(qd < 0.0)


def test_bounds():
    q_up = np.array([2.499, 0.0, -2.499, 0.0])
    qd, ok = solve_arm(_case(np.full(13, 50.0), q_up=q_up), QpSolver("osqp"))
    assert ok
    q_next = q_up + DT * qd
    assert np.all(q_next <= QMAX + 1e-6) and np.all(q_next >= QMIN - 1e-6)


def test_osqp_matches_exact():
    rng = np.random.default_rng(0)
    solver = QpSolver("osqp")
    for _ in range(20):
        qp = _case(rng.normal(size=13) * 2.0, q_up=rng.uniform(-1, 1, 4))
        qd, ok = solve_arm(qp, solver)
        exact = solve_exact(qp)
        # P's condition number is ~200 (omega1 a a' vs omega3 I): OSQP's 1e-7 residual
        # tolerance gives ~1e-6 relative accuracy on q_dot.
        assert ok and np.max(np.abs(qd - exact)) < 1e-6 * max(1.0, np.max(np.abs(exact)))
