"""Tests of the pelvic-rotation MPC, eq. (34)-(38)."""

import dataclasses
import math

import numpy as np
import pytest

from controller.params import PelvisMpcParams
from controller.pelvis_mpc import PelvisMpc
from controller.qp import solve_exact

N, TP, DT = 16, 0.1, 0.005


@pytest.mark.parametrize("backend", ["osqp", "daqp"])
def test_tracks_constant_reference_closed_loop(backend):
    mpc = PelvisMpc(PelvisMpcParams(), TP, N, DT, backend)
    ref = np.full(N, 0.3)
    th, rate = 0.0, 0.0
    for _ in range(400):  # 2 s
        plan = mpc.solve(th, rate, ref)
        assert plan.ok
        th, rate = plan.next_angle, plan.next_rate
    assert abs(th - 0.3) < 1e-3 and abs(rate) < 1e-2


def test_prediction_consistent():
    mpc = PelvisMpc(PelvisMpcParams(), TP, N, DT)
    plan = mpc.solve(0.1, -0.2, np.linspace(0, 0.3, N))
    th, rate = 0.1, -0.2
    for k in range(N):
        th, rate = th + TP * rate + 0.5 * TP * TP * plan.acc[k], rate + TP * plan.acc[k]
        assert abs(th - plan.angles[k]) < 1e-9 and abs(rate - plan.rates[k]) < 1e-9
    assert abs(plan.next_rate - (-0.2 + DT * plan.acc[0])) < 1e-12


def test_angle_limit():
    p = PelvisMpcParams(angle_limit_deg=20.0)
    mpc = PelvisMpc(p, TP, N, DT, "osqp")
    ref = np.full(N, math.radians(40.0))
    plan = mpc.solve(0.0, 0.0, ref)
    assert plan.ok
    assert np.all(np.abs(plan.angles) <= math.radians(20.0) + 1e-5)
    assert np.all(np.abs(plan.acc) <= p.acc_limit + 1e-5)
    assert plan.angles[-1] > math.radians(19.0)


@pytest.mark.parametrize("seed", range(5))
def test_matches_exact(seed):
    rng = np.random.default_rng(seed)
    mpc = PelvisMpc(PelvisMpcParams(beta=1e-6), TP, N, DT, "osqp")  # QP variable: angles
    ref = 0.4 * np.sin(np.linspace(0, 3, N) + rng.uniform(0, 6))
    qp = mpc.build(rng.uniform(-0.3, 0.3), rng.uniform(-1, 1), ref)
    res = mpc.solver.solve(qp)
    assert res.ok
    assert np.max(np.abs(res.x - solve_exact(qp))) < 1e-6


def test_beta_zero():
    p = dataclasses.replace(PelvisMpcParams(), beta=0.0)
    mpc = PelvisMpc(p, TP, N, DT, "osqp")
    ref = 0.3 * np.sin(np.linspace(0, 2, N))
    qp = mpc.build(0.0, 0.0, ref)
    assert np.all(np.linalg.eigvalsh(qp.P) > 0)
    assert np.allclose(qp.P, np.eye(N))
    plan = mpc.solve(0.0, 0.0, ref)
    assert plan.ok
    exact = solve_exact(qp)
    assert np.max(np.abs(plan.angles - exact)) < 1e-6
    acc = mpc.inputs_from_angles(exact, 0.0, 0.0)
    assert abs(plan.next_rate - DT * acc[0]) < 1e-6


def test_failure_brakes():
    mpc = PelvisMpc(PelvisMpcParams(), TP, N, DT)
    # Beyond the limit and moving outward faster than the acceleration bound can stop.
    plan = mpc.solve(math.radians(50.0), 20.0, np.zeros(N))
    assert not plan.ok
    assert abs(plan.next_rate) < 20.0
    assert abs(plan.rates[-1]) < 1e-9


def test_set_params_changes_shape():
    mpc = PelvisMpc(PelvisMpcParams(), TP, N, DT)
    mpc.solve(0.0, 0.0, np.zeros(N))
    mpc.set_params(PelvisMpcParams(), 0.08, 20)
    plan = mpc.solve(0.0, 0.0, np.full(20, 0.1))
    assert plan.ok and plan.angles.shape == (20,)
    with pytest.raises(ValueError):
        mpc.build(0.0, 0.0, np.zeros(N))
