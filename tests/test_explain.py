"""The QP inspector: each layer explains its solve (controller/explain.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from controller.com_mpc import ComMpc
from controller.explain import kkt_multipliers, multipliers
from controller.ik import build_ik, explain_ik
from controller.kinematics import RobotKinematics
from controller.params import ComMpcParams, ControllerParams, IkParams
from controller.qp import QpSolver
from controller.tick_explain import active_counts, explain_tick
from models.dyros_jet import LOWER_JOINTS, walk_ready_joint_angles
from pelvic_walk.core.run import RunConfig, Session

KNEE = LOWER_JOINTS.index("L_knee")


@pytest.fixture(scope="module")
def kin():
    return RobotKinematics()


def _forced_knee(kin, backend="daqp"):
    """An IK QP whose left knee is asked to straighten past its limit (q = 0.002 rad)."""
    q = kin.q_min.copy() * 0 + np.asarray(walk_ready_joint_angles(), dtype=float)
    q[KNEE] = 0.002
    ks = kin.compute(q)
    wanted = np.zeros(13)
    wanted[KNEE] = -3.0  # straighten at 3 rad/s: the limit allows 0.4 rad/s in this tick
    v_des = ks.J_low @ wanted
    qp = build_ik(ks.J_low, v_des, q[:13], kin.q_min[:13], kin.q_max[:13], IkParams(), 0.005, 0.0)
    solver = QpSolver(backend)
    res = solver.solve(qp)
    assert res.ok
    return qp, solver, ks


def test_a_joint_forced_to_its_bound_is_named(kin):
    qp, solver, ks = _forced_knee(kin)
    e = explain_ik(qp, solver, ks.J_low, kin.q_min[:13], kin.q_max[:13], IkParams(), 0.005)
    names = e.names()
    assert "left knee at its straight limit (0 deg)" in names, names
    assert any(n.startswith("waist rate pinned by the strategy") for n in names), names
    knee = next(c for c in e.active if c.joint == "L_knee")
    assert knee.side == "lower" and knee.lam < 0 and knee.multiplier > 0
    assert knee.bound == pytest.approx(-0.002 / 0.005)
    assert e.ok and e.iterations >= 0 and e.status == "solved"


def test_daqp_duals_match_the_kkt_multipliers(kin):
    qp, solver, _ = _forced_knee(kin)
    x = solver.last_result.x
    rows, lam = multipliers(qp, x, solver)  # DAQP's duals
    rows_kkt, lam_kkt = multipliers(qp, x, None)  # recovered at the solution
    np.testing.assert_array_equal(rows, rows_kkt)
    np.testing.assert_allclose(lam, lam_kkt, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(kkt_multipliers(qp, x, rows), lam, rtol=1e-6, atol=1e-12)


def test_osqp_names_the_same_constraints(kin):
    qp, solver, ks = _forced_knee(kin, "osqp")
    e = explain_ik(qp, solver, ks.J_low, kin.q_min[:13], kin.q_max[:13], IkParams(), 0.005)
    assert "left knee at its straight limit (0 deg)" in e.names()


def test_a_zmp_bound_over_the_horizon_is_named():
    p = ComMpcParams()
    mpc = ComMpc(p, 0.7, 0.005, "daqp")
    N = mpc.N
    times = mpc.sample_times(0.0)
    ref = np.tile([0.2, 0.0], (N, 1))  # a reference beyond the front edge
    lo, hi = np.tile([-0.05, -0.05], (N, 1)), np.tile([0.05, 0.05], (N, 1))
    plan = mpc.solve_references(np.zeros((3, 2)), 0.0, times, ref, lo, hi)
    e = mpc.explain(plan)
    assert e.ok and e.active
    last = f"ZMP x upper bound at +{round(N * p.sample_time, 2):g} s (front edge of the support)"
    assert last in e.names(), e.names()
    assert all(c.axis == "x" for c in e.active)  # y has nothing to do
    for c in e.active:
        assert c.bound == pytest.approx(0.05 if c.side == "upper" else -0.05)
        assert (c.lam > 0) == (c.side == "upper")


def _terms_add_up(e):
    assert sum(e.terms.values()) == pytest.approx(e.objective, rel=1e-12, abs=1e-15)


def test_cost_terms_add_up_to_each_layers_objective():
    """Every layer: the named terms (each computed from its definition in the paper) sum to
    the objective, and the objective less the constants the layer computes from its own data
    is the QP's 1/2 x'Px + q'x at the solution (computed here from the QP): the split is the
    QP's cost."""
    p = ControllerParams().replace(method="mpc", walk=dict(step_length=0.3, n_steps=2))
    s = Session(RunConfig(params=p))
    w = s.walker
    checked = 0
    for i in range(240):
        out = s.tick()
        if i % 20:
            continue
        rec = explain_tick(w, out)
        assert [e.layer for e in rec.layers] == ["com_mpc", "pelvis_mpc", "ik", "arm_swing"]
        solvers = {
            "com_mpc": w.com_mpc.solver,
            "pelvis_mpc": w.strategy.strategy.mpc.solver,
            "ik": w.ik_solver,
            "arm_swing": w.arm_solver,
        }
        for e in rec.layers:
            assert e.ran and e.ok, e
            _terms_add_up(e)
            qp, x = solvers[e.layer].last_qp, solvers[e.layer].last_result.x
            assert e.qp_objective == pytest.approx(
                0.5 * x @ qp.P @ x + qp.q @ x, rel=1e-9, abs=1e-12
            ), e.layer
            assert e.constant >= -1e-12  # the constants are squares
            checked += 1
        assert rec.counts() == {
            k: int(v) for k, v in zip(rec.counts(), active_counts(w), strict=True)
        }
    assert checked == 4 * 12


def test_the_fixed_pelvis_at_0_42_m_is_stopped_by_a_straight_knee():
    """A step the fixed pelvis cannot make: its IK holds a knee at the straight limit while
    the waist stays pinned at 0 by the strategy; it solves no pelvic QP."""
    p = ControllerParams().replace(method="fixed", walk=dict(step_length=0.42, n_steps=4))
    s = Session(RunConfig(params=p))
    names: set[str] = set()
    while not s.walker.finished and not s.fell:
        out = s.tick()
        if active_counts(s.walker)[2] > 1:  # cheap: something beyond the waist's pin
            rec = explain_tick(s.walker, out)
            names.update(rec["ik"].names())
            ik, qp = rec["ik"], s.walker.ik_solver.last_qp
            x = s.walker.ik_solver.last_result.x
            _terms_add_up(ik)  # and the split holds with a knee near straight (J ill-conditioned)
            assert ik.qp_objective == pytest.approx(0.5 * x @ qp.P @ x + qp.q @ x, abs=1e-9)
            assert not rec["pelvis_mpc"].ran and "pins the waist" in rec["pelvis_mpc"].note
    assert {
        "right knee at its straight limit (0 deg)",
        "left knee at its straight limit (0 deg)",
    } & names
    assert "waist rate pinned by the strategy (+0.000 rad/s)" in names
    counts = s.series.as_dict()["active_ik"]
    assert np.nanmax(counts) >= 2
    assert np.all(np.isnan(s.series.as_dict()["active_pelvis_mpc"]))


def test_the_pelvic_mpc_names_its_angle_limit():
    p = ControllerParams().replace(
        method="mpc", walk=dict(step_length=0.35, n_steps=2), pelvis=dict(angle_limit_deg=5.0)
    )
    s = Session(RunConfig(params=p))
    names: set[str] = set()
    for _ in range(600):
        out = s.tick()
        if active_counts(s.walker)[1] > 0:
            names.update(explain_tick(s.walker, out)["pelvis_mpc"].names())
    assert any(n.startswith("waist angle limit (+5 deg) at +") for n in names) or any(
        n.startswith("waist angle limit (-5 deg) at +") for n in names
    ), names


def test_a_failed_solve_says_what_the_fallback_did():
    mpc = ComMpc(ComMpcParams(), 0.7, 0.005, "daqp")
    N = mpc.N
    lo, hi = np.full((N, 2), 0.1), np.full((N, 2), -0.1)  # crossed: infeasible
    plan = mpc.solve_references(np.zeros((3, 2)), 0.0, mpc.sample_times(0.0), lo * 0, lo, hi)
    e = mpc.explain(plan)
    assert not e.ok and e.fallback.startswith("the previous optimal jerks")
    assert e.active == () and e.status
    assert math.isnan(e.solve_ms) or e.solve_ms >= 0
