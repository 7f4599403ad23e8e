"""Footstep plan: footholds, alternation, timing, ZMP reference and bounds, replanning."""

from __future__ import annotations

import numpy as np
import pytest

from controller.footsteps import LEFT, RIGHT, plan_footsteps
from controller.params import WalkParams
from models.dyros_jet import FOOT_SIZE

WALK = WalkParams(step_length=0.2, step_time=1.2, dsp_ratio=0.2, n_steps=4)


@pytest.fixture
def plan():
    return plan_footsteps(WALK)


def test_footholds_advance_and_alternate(plan):
    L, hw = WALK.step_length, WALK.step_width / 2
    assert plan.n == WALK.n_steps + 1 and plan.n_walking_steps == WALK.n_steps
    assert list(plan.swing_side) == [LEFT, RIGHT, LEFT, RIGHT, LEFT]
    np.testing.assert_allclose(plan.swing_to[:4, 0], L * np.arange(1, 5))
    np.testing.assert_allclose(plan.swing_to[:, 1], [hw, -hw, hw, -hw, hw])
    # first swing moves L, later ones 2L, the closing one L (feet together)
    np.testing.assert_allclose(
        plan.swing_to[:, 0] - plan.swing_from[:, 0], [L, 2 * L, 2 * L, 2 * L, L]
    )
    np.testing.assert_allclose(plan.feet_final[:, 0], [4 * L, 4 * L])
    fh = plan.footholds()
    assert fh.shape == (plan.n + 2, 3)
    np.testing.assert_allclose(fh[:2], [[0, hw, 0], [0, -hw, 0]])
    # the support foot of step k is the other foot, where it last landed
    np.testing.assert_allclose(plan.support_pos[1:], plan.swing_to[:-1])


def test_first_swing_right_and_x0():
    p = plan_footsteps(WALK, t_start=0.5, first_swing=RIGHT, x0=1.0)
    assert p.swing_side[0] == RIGHT and p.swing_to[0, 1] < 0
    assert p.swing_to[0, 0] == pytest.approx(1.2) and p.step_start[0] == 0.5


def test_timing(plan):
    T = WALK.step_time
    np.testing.assert_allclose(plan.step_start, 0.8 + T * np.arange(5))
    assert plan.dsp_time == pytest.approx(0.24) and plan.ssp_time == pytest.approx(0.96)
    assert plan.t_end == pytest.approx(0.8 + 5 * T + 0.24 + 1.0)
    steps = plan.sample(np.array([0.0, 0.8, 2.0 - 1e-9, plan.t_end, 0.1, 0.9, 2.1])).step
    np.testing.assert_array_equal(steps, [-1, 0, 0, plan.n, -1, 0, 1])
    ph = plan.sample(0.9)
    assert ph.in_dsp[0] and not ph.in_ssp[0]
    assert ph.swing_side[0] == LEFT and ph.support_side[0] == RIGHT
    ph = plan.sample(0.8 + 0.24 + 0.48)
    assert ph.in_ssp[0] and ph.s_ssp[0] == pytest.approx(0.5) and not ph.standing[0]
    ph = plan.sample(0.1)
    assert ph.standing[0] and ph.swing_side[0] == -1 and not ph.in_dsp[0]


def test_zmp_reference_path_and_continuity(plan):
    t = np.arange(-0.5, plan.t_end + 0.5, 0.001)
    z = plan.sample(t).zmp_ref
    assert z.shape == (t.size, 2)
    # continuous: max move per ms = distance / dsp_time
    assert np.max(np.abs(np.diff(z, axis=0))) < 0.3 / 0.24 * 0.001 + 1e-9
    np.testing.assert_allclose(plan.sample(np.array([0.0, 0.8])).zmp_ref, [[0, 0], [0, 0]])
    # SSP of step 0: on the right (support) foot; SSP of step 2: on the right foot at 0.4
    ssp_mid = plan.step_start + 0.24 + 0.48
    np.testing.assert_allclose(plan.sample(ssp_mid).zmp_ref, plan.support_pos[:, :2])
    np.testing.assert_allclose(plan.sample(plan.t_end + 5).zmp_ref, [[0.8, 0.0]])


def test_zmp_bounds_contain_reference_and_shrink_in_ssp(plan):
    t = np.linspace(0, plan.t_end, 3000)
    s = plan.sample(t, 0.02)
    assert np.all(s.zmp_ref >= s.zmp_lo - 1e-12) and np.all(s.zmp_ref <= s.zmp_hi + 1e-12)
    ssp = plan.sample(plan.step_start[1] + 0.5, 0.02)
    lo, hi = ssp.zmp_lo, ssp.zmp_hi
    c = plan.support_pos[1, :2]
    np.testing.assert_allclose(hi[0] - c, np.array(FOOT_SIZE) / 2 - 0.02)
    np.testing.assert_allclose(c - lo[0], np.array(FOOT_SIZE) / 2 - 0.02)
    stand = plan.sample(0.1)  # standing: both feet's box
    width = stand.zmp_hi[0, 1] - stand.zmp_lo[0, 1]
    assert width == pytest.approx(WALK.step_width + FOOT_SIZE[1])


def test_feet_on_ground(plan):
    t = np.array([0.1, 0.9, 0.8 + 0.24 + 0.1, 2.0 + 0.3, plan.t_end])
    g = plan.sample(t).on_ground
    np.testing.assert_array_equal(g, [[1, 1], [1, 1], [0, 1], [1, 0], [1, 1]])


def test_replanned_keeps_started_steps(plan):
    new = WalkParams(step_length=0.3, step_time=1.0, dsp_ratio=0.3, n_steps=6)
    t_now = plan.step_start[1] + 0.3  # in step 1
    r = plan.replanned(new, t_now)
    for name in (
        "step_start",
        "swing_side",
        "swing_from",
        "swing_to",
        "support_pos",
        "step_duration",
        "step_dsp",
    ):
        np.testing.assert_array_equal(getattr(r, name)[:2], getattr(plan, name)[:2])
    assert r.n_walking_steps == 6 and r.n == 7
    # the next foothold advances the new step length from the current step's landing point
    assert r.swing_to[2, 0] == pytest.approx(plan.swing_to[1, 0] + 0.3)
    np.testing.assert_allclose(np.diff(r.step_start[1:]), [1.2, 1.0, 1.0, 1.0, 1.0])
    assert r.step_dsp[2] == pytest.approx(0.3)
    # the reference is unchanged up to now and continuous after
    t = np.arange(0, t_now, 0.01)
    np.testing.assert_allclose(r.sample(t).zmp_ref, plan.sample(t).zmp_ref)
    z = r.sample(np.arange(0, r.t_end, 0.001)).zmp_ref
    assert np.max(np.abs(np.diff(z, axis=0))) < 0.01
    # before the start: a fresh plan; in the closing step: only walk changes
    assert plan.replanned(new, 0.1).n == 7
    late = plan.replanned(new, plan.step_start[-1] + 0.1)
    np.testing.assert_array_equal(late.swing_to, plan.swing_to)


def test_both_ends_split_keeps_the_double_support_between_swings():
    """The authors' split: half the DSP before the lift-off, half after the touch-down."""
    walk = WalkParams(step_length=0.2, step_time=1.2, dsp_ratio=0.2, n_steps=4)
    ours = plan_footsteps(walk)
    theirs = plan_footsteps(WalkParams(**{**vars(walk), "dsp_split": "both_ends"}))
    dsp = walk.dsp_ratio * walk.step_time
    np.testing.assert_allclose(theirs.step_dsp, dsp / 2)
    np.testing.assert_allclose(theirs.step_dsp_end, dsp / 2)
    np.testing.assert_allclose(ours.step_dsp_end, 0.0)
    # swings last the same; between two swings both feet are down for one whole DSP
    np.testing.assert_allclose(
        theirs.landing_times() - theirs.liftoff_times(), ours.landing_times() - ours.liftoff_times()
    )
    np.testing.assert_allclose(theirs.liftoff_times()[1:] - theirs.landing_times()[:-1], dsp)
    assert theirs.dsp_after_landing(0) == pytest.approx(dsp)
    # in the end DSP both feet are down and the ZMP is half-way to the landed foot at its end
    t = theirs.landing_times()[1] + dsp / 2 - 1e-9
    s = theirs.sample(t)
    assert s.in_dsp[0] and s.on_ground[0].all()
    mid = 0.5 * (theirs.support_pos[1, :2] + theirs.swing_to[1, :2])
    np.testing.assert_allclose(s.zmp_ref[0], mid, atol=1e-6)
    # the ZMP path is continuous across the step boundary
    t0 = theirs.step_start[2]
    a, b = theirs.sample(np.array([t0 - 1e-7, t0 + 1e-7])).zmp_ref
    np.testing.assert_allclose(a, b, atol=1e-5)
