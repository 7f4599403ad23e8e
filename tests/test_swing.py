"""Swing-foot trajectories, eq. (20)-(21)."""

from __future__ import annotations

import numpy as np
import pytest

from controller.footsteps import LEFT, plan_footsteps
from controller.params import WalkParams

WALK = WalkParams(step_length=0.25, foot_height=0.08, n_steps=3)
PLAN = plan_footsteps(WALK)


def foot_trajectories(plan, t):
    return plan.sample(t)


def _swing_window(k: int) -> tuple[float, float]:
    t0 = PLAN.step_start[k] + PLAN.step_dsp[k]
    return t0, PLAN.step_start[k] + PLAN.step_duration[k]


def _swing_foot(tr, k):
    return (tr.p_left, tr.v_left) if PLAN.swing_side[k] == LEFT else (tr.p_right, tr.v_right)


def _support_foot(tr, k):
    return (tr.p_right, tr.v_right) if PLAN.swing_side[k] == LEFT else (tr.p_left, tr.v_left)


@pytest.mark.parametrize("k", range(4))
def test_endpoints_and_zero_velocity(k):
    t0, t1 = _swing_window(k)
    tr = foot_trajectories(PLAN, np.array([PLAN.step_start[k], t0, t1 - 1e-12]))
    p, v = _swing_foot(tr, k)
    np.testing.assert_allclose(p[0], PLAN.swing_from[k])
    np.testing.assert_allclose(p[1], PLAN.swing_from[k], atol=1e-12)
    np.testing.assert_allclose(p[2], PLAN.swing_to[k], atol=1e-9)
    np.testing.assert_allclose(v, 0.0, atol=1e-8)
    ps, vs = _support_foot(tr, k)
    np.testing.assert_allclose(ps, np.tile(PLAN.support_pos[k], (3, 1)))
    np.testing.assert_array_equal(vs, 0.0)


def test_velocity_is_derivative_of_position():
    t = np.arange(0.0, PLAN.t_end, 0.002)
    h = 1e-6
    a, b = foot_trajectories(PLAN, t - h), foot_trajectories(PLAN, t + h)
    tr = foot_trajectories(PLAN, t)
    for p0, p1, v in ((a.p_left, b.p_left, tr.v_left), (a.p_right, b.p_right, tr.v_right)):
        np.testing.assert_allclose((p1 - p0) / (2 * h), v, atol=1e-5)


def test_height_peak_and_ground():
    t0, t1 = _swing_window(1)
    t = np.linspace(t0, t1, 1001)
    p, _ = _swing_foot(foot_trajectories(PLAN, t), 1)
    assert p[:, 2].max() == pytest.approx(WALK.foot_height)
    assert p[500, 2] == pytest.approx(WALK.foot_height)
    assert p[:, 2].min() >= 0.0
    # monotone forward progress
    assert np.all(np.diff(p[:, 0]) >= 0)
    tr = foot_trajectories(PLAN, np.array([0.0, PLAN.t_end + 1.0]))
    np.testing.assert_allclose(tr.p_left, [PLAN.feet_init[0], PLAN.feet_final[0]])
    np.testing.assert_allclose(tr.p_right, [PLAN.feet_init[1], PLAN.feet_final[1]])


def test_feet_on_ground_matches_height():
    t = np.arange(0.0, PLAN.t_end, 0.01)
    tr = foot_trajectories(PLAN, t)
    g = tr.on_ground
    assert np.all(tr.p_left[g[:, 0], 2] == 0.0) and np.all(tr.p_right[g[:, 1], 2] == 0.0)
