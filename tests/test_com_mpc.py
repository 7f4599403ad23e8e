"""CoM MPC, eq. (10)-(18) and (25)-(26)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from controller.com_mpc import GRAVITY, ComMpc, lipm_discrete, prediction_matrices
from controller.footsteps import plan_footsteps
from controller.params import ComMpcParams, WalkParams, horizon_samples
from controller.qp import solve_exact

ZC = 0.80  # [m]
PARAMS = ComMpcParams()


def test_prediction_matrices_match_step_by_step_simulation():
    T, N = 0.1, 16
    PA, PB = prediction_matrices(T, N)
    A, B = lipm_discrete(T)
    rng = np.random.default_rng(0)
    x0, u = rng.normal(size=3), rng.normal(size=N)
    x, rows = x0.copy(), []
    for k in range(N):
        x = A @ x + B * u[k]
        rows.append(x)
    sim = np.array(rows)  # (N, 3)
    pred = PA @ x0 + PB @ u
    np.testing.assert_allclose(pred[:N], sim[:, 0], atol=1e-12)
    np.testing.assert_allclose(pred[N : 2 * N], sim[:, 1], atol=1e-12)
    np.testing.assert_allclose(pred[2 * N :], sim[:, 2], atol=1e-12)


def test_zmp_and_velocity_difference_matrices():
    mpc = ComMpc(PARAMS, ZC)
    N = mpc.N
    rng = np.random.default_rng(1)
    x0, u = rng.normal(size=3), rng.normal(size=N)
    traj = mpc.state_from_state @ x0 + mpc.state_from_jerk @ u
    zmp = traj[:N] - ZC / GRAVITY * traj[2 * N :]
    np.testing.assert_allclose(mpc.zmp_from_state @ x0 + mpc.zmp_from_jerk @ u, zmp)
    v = np.concatenate([[x0[1]], traj[N : 2 * N]])
    np.testing.assert_allclose(mpc.dvel_from_state @ x0 + mpc.dvel_from_jerk @ u, np.diff(v))


def test_tracks_constant_zmp_reference():
    mpc = ComMpc(PARAMS, ZC)
    walk = WalkParams(n_steps=1)
    plan = plan_footsteps(walk, t_start=100.0)  # standing still: ZMP ref at the midpoint (0, 0)
    state = np.zeros((3, 2))
    state[0] = [0.03, -0.02]  # CoM offset from the reference
    for i in range(600):
        cp = mpc.solve(state, i * 0.005, plan)
        assert cp.ok
        assert np.all(cp.zmp >= cp.zmp_lo - 1e-6) and np.all(cp.zmp <= cp.zmp_hi + 1e-6)
        state = cp.next_state
    np.testing.assert_allclose(state[0], [0.0, 0.0], atol=2e-3)
    np.testing.assert_allclose(state[1], [0.0, 0.0], atol=1e-2)


def test_closed_loop_walk_keeps_zmp_in_bounds_and_ends_at_midpoint():
    walk = WalkParams(step_length=0.2, n_steps=4)
    plan = plan_footsteps(walk)
    mpc = ComMpc(PARAMS, ZC)
    dt = mpc.control_dt
    state = np.zeros((3, 2))
    worst = 0.0
    for i in range(int(round(plan.t_end / dt))):
        cp = mpc.solve(state, i * dt, plan)
        assert cp.ok
        state = cp.next_state
        zmp = state[0] - ZC / GRAVITY * state[2]
        box = plan.sample((i + 1) * dt, PARAMS.zmp_margin)
        lo, hi = box.zmp_lo, box.zmp_hi
        worst = max(worst, float(np.max(lo[0] - zmp)), float(np.max(zmp - hi[0])))
    assert worst <= 1e-3
    np.testing.assert_allclose(state[0], plan.feet_final[:, :2].mean(axis=0), atol=0.01)
    assert np.all(np.abs(state[1]) < 0.02)


def test_osqp_matches_exact_daqp():
    plan = plan_footsteps(WalkParams(step_length=0.3, n_steps=4))
    mpc = ComMpc(dataclasses.replace(PARAMS, zmp_margin=0.05), ZC)
    daqp = ComMpc(dataclasses.replace(PARAMS, zmp_margin=0.05), ZC, backend="daqp")
    state = np.zeros((3, 2))
    for i in range(0, 1200):
        t = i * 0.005
        cp = mpc.solve(state, t, plan)
        if i % 40 == 0:
            exact = solve_exact(mpc.last_qp)
            np.testing.assert_allclose(cp.jerk.T.ravel(), exact, atol=1e-5)
            np.testing.assert_allclose(daqp.solve(state, t, plan).jerk, cp.jerk, atol=1e-5)
        state = cp.next_state


def test_next_state_applies_first_jerk_for_one_control_period():
    mpc = ComMpc(PARAMS, ZC, control_dt=0.005)
    plan = plan_footsteps(WalkParams(n_steps=2))
    state = np.array([[0.01, 0.0], [0.1, -0.05], [0.2, 0.3]])
    cp = mpc.solve(state, 1.0, plan)
    A, B = lipm_discrete(0.005)
    np.testing.assert_allclose(cp.next_state, A @ state + np.outer(B, cp.jerk[0]))
    np.testing.assert_allclose(cp.times, 1.0 + 0.1 * np.arange(1, 17))


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.floats(-0.05, 0.05), min_size=2, max_size=2),
    st.lists(st.floats(-0.2, 0.2), min_size=2, max_size=2),
)
def test_zero_alpha_ignores_the_reference(state_xy, ref):
    """With alpha = 0 the ZMP reference has no weight: from rest, inside wide bounds, U = 0."""
    mpc = ComMpc(dataclasses.replace(PARAMS, alpha=0.0), ZC, backend="daqp")
    state = np.zeros((3, 2))
    state[0] = state_xy
    zr = np.tile(ref, (mpc.N, 1))
    qp = mpc.build(state, zr, zr - 1.0, zr + 1.0)
    np.testing.assert_allclose(qp.q, 0.0, atol=1e-15)
    np.testing.assert_allclose(solve_exact(qp), 0.0, atol=1e-9)


@pytest.mark.parametrize("backend", ["osqp", "daqp"])
def test_bounds_hold_when_the_reference_is_outside(backend):
    """A reference 0.2 m away and bounds of +/-0.05 m: the ZMP stops at the bound."""
    mpc = ComMpc(PARAMS, ZC, backend=backend)
    zr = np.full((mpc.N, 2), 0.2)
    lo, hi = np.full((mpc.N, 2), -0.05), np.full((mpc.N, 2), 0.05)
    qp = mpc.build(np.zeros((3, 2)), zr, lo, hi)
    r = mpc.solver.solve(qp)
    assert r.ok
    z = qp.A @ r.x  # ZMP minus its zero-jerk part (zero from rest at the origin)
    assert np.all(z <= 0.05 + 1e-6) and np.all(z >= -0.05 - 1e-6)
    assert z.max() == pytest.approx(0.05, abs=1e-6)


def test_failure_falls_back_to_shifted_previous_jerks():
    mpc = ComMpc(PARAMS, ZC)
    plan = plan_footsteps(WalkParams(n_steps=2))
    state = np.zeros((3, 2))
    good = mpc.solve(state, 1.0, plan)
    bad_plan = dataclasses.replace(plan, support_pos=plan.support_pos * np.nan)
    bad = mpc.solve(state, 1.0 + 0.1, dataclasses.replace(bad_plan, zmp_from=plan.zmp_from))
    assert good.ok and not bad.ok
    np.testing.assert_allclose(bad.jerk[:-1], good.jerk[1:])


def test_set_params_rebuilds_and_resets_on_new_horizon():
    mpc = ComMpc(PARAMS, ZC)
    H = mpc.hessian
    mpc.set_params(PARAMS)
    assert mpc.hessian is H
    mpc.set_params(dataclasses.replace(PARAMS, horizon=2.0))
    assert mpc.N == horizon_samples(mpc.params) == 20 and mpc.hessian.shape == (40, 40)
    cp = mpc.solve(np.zeros((3, 2)), 0.0, plan_footsteps(WalkParams(n_steps=1)))
    assert cp.ok and cp.jerk.shape == (20, 2)


@pytest.mark.parametrize("T", [0.05, 0.1, 0.2])
def test_hessian_positive_definite(T):
    mpc = ComMpc(dataclasses.replace(PARAMS, sample_time=T), ZC)
    assert np.linalg.eigvalsh(mpc.hessian).min() > 0
