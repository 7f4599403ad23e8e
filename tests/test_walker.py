"""Closed-loop smoke tests of the whole controller in MuJoCo, and controller/ purity."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from controller.footsteps import LEFT, RIGHT
from controller.params import ControllerParams
from pelvic_walk.core.run import SUMMARY_KEYS, RunConfig, Session, run, summarize
from pelvic_walk.core.run_spec import RunSpec

ROOT = Path(__file__).resolve().parents[1]
SIDE = {LEFT: "left", RIGHT: "right"}  # StrategyInputs.support and .swing


def _params(method: str, length: float = 0.2, steps: int = 3, arms: bool = True):
    return ControllerParams().replace(
        method=method, walk=dict(step_length=length, n_steps=steps), arms=dict(enabled=arms)
    )


@pytest.mark.parametrize("method", ["fixed", "redundancy", "mpc"])
def test_three_step_closed_loop_walks(method):
    session = run(RunConfig(params=_params(method)))
    s = summarize(session)
    assert set(SUMMARY_KEYS) <= set(s)
    assert s["success"] and not s["fell"], s
    assert s["steps_completed"] == 3
    assert s["landing_error_max"] < 0.02
    assert s["zmp_in_support_ratio"] >= 0.95
    assert s["solver_failures"] == 0
    data = session.series.as_dict()
    for name in ("waist_angle", "yaw_momentum", "kappa_low", "com_x", "energy"):
        assert np.all(np.isfinite(data[name])), name
    # the robot actually moved forward by the planned distance (3 steps of 0.2 m)
    assert data["com_x"][-1] == pytest.approx(0.6, abs=0.05)
    if method == "fixed":
        assert s["waist_yaw_max_deg"] < 0.5
    else:
        assert s["waist_yaw_max_deg"] > 3.0


def test_mpc_pins_the_ik_waist_rate_to_the_pelvic_mpc():
    session = Session(RunConfig(params=_params("mpc", 0.3, 2)))
    rates = []
    for _ in range(400):
        out = session.tick()
        assert out.pelvis_plan is not None
        rates.append((out.waist_rate, out.pelvis_plan.next_rate))
    rates = np.array(rates)
    assert np.max(np.abs(rates[:, 1])) > 0.05  # the MPC does turn the pelvis
    np.testing.assert_allclose(rates[:, 0], rates[:, 1], atol=1e-6)


def test_the_strategy_reads_each_input_under_its_own_name(monkeypatch):
    """The tick builds StrategyInputs by field name: each field is what the tick's output
    calls by that name (two inputs of one shape swapped, e.g. the soles, would still run)."""
    session = Session(RunConfig(params=_params("mpc", 0.3, 2)))
    walker = session.walker
    mpc = walker.strategy.strategy
    seen = []
    rate = mpc.waist_rate
    monkeypatch.setattr(mpc, "waist_rate", lambda s: seen.append(s) or rate(s))
    theta, theta_dot = float(walker.q_cmd[0]), 0.0  # the commanded waist before the tick
    phases = set()
    for _ in range(600):  # the stand, then two steps' double and single supports
        out = session.tick()
        s, plan = seen[-1], out.plan_sample
        assert (s.t, s.dt, s.theta, s.theta_dot) == (out.t, 0.005, theta, theta_dot)
        assert s.theta_ref is out.theta_ref and s.com is out.com_plan.com
        assert s.com_now is out.p_world_com_des
        np.testing.assert_array_equal(out.t + s.horizon_t, out.com_plan.times)
        for got, want in [
            (s.left_sole, plan.p_left[2:]),
            (s.right_sole, plan.p_right[2:]),
            (s.left_sole_now, plan.p_left[0]),
            (s.right_sole_now, plan.p_right[0]),
        ]:
            np.testing.assert_array_equal(got, want)
        assert s.support == (SIDE[int(plan.support_side[0])] if out.in_ssp else "both")
        assert s.swing == SIDE.get(out.swing_side)
        assert (s.step, s.phase) == (out.step_index, plan.s_ssp[0])
        assert s.params is walker.params
        assert not any(a.flags.writeable for a in s if isinstance(a, np.ndarray))
        theta, theta_dot = out.waist_angle, out.waist_rate
        phases.add(s.support)
    assert phases == {"both", "left", "right"} and s.step == 1
    assert s.left_sole_now[1] > s.right_sole_now[1]  # the soles are told apart


def test_mpc_turns_the_pelvis_toward_the_forward_foot():
    """The hip of the leading foot goes forward: the leading leg's reach shrinks
    (docs/DESIGN.md, "Sign of the pelvic angle")."""
    session = Session(RunConfig(params=_params("mpc", 0.4, 2)))
    plan = session.walker.plan
    t_land = plan.step_start[1] + plan.step_duration[1]  # the second step (right foot) lands
    while session.t < t_land:
        out = session.tick()
    # right foot ahead at landing: a positive yaw moves the right hip (at -y) forward
    assert out.waist_angle > np.deg2rad(10)


def test_the_ablation_holds_the_reference_of_now_over_the_horizon():
    """pelvis.reference = now (the study's ablation): the reference angle is the one of the
    state now at every horizon sample; with the prediction it changes over the horizon."""
    spans = {}
    for source in ("predicted", "now"):
        p = _params("mpc", 0.3, 2).replace(pelvis={"reference": source})
        session = Session(RunConfig(params=p))
        spans[source] = max(float(np.ptp(session.tick().theta_ref)) for _ in range(300))
    assert spans["now"] == 0.0 and spans["predicted"] > 0.05


def test_arm_swing_reduces_commanded_yaw_momentum():
    on = Session(RunConfig(params=_params("mpc", 0.3, 2, arms=True)))
    off = Session(RunConfig(params=_params("mpc", 0.3, 2, arms=False)))
    tot_on, tot_off = [], []
    for _ in range(700):
        a, b = on.tick(), off.tick()
        tot_on.append(a.h_low + a.h_up)
        tot_off.append(b.h_low + b.h_up)
    assert np.max(np.abs(tot_on)) < 0.6 * np.max(np.abs(tot_off))


def test_live_parameter_change_takes_effect_on_a_later_step():
    session = Session(RunConfig(params=_params("fixed", 0.1, 6)))
    for _ in range(300):
        session.tick()
    session.walker.replace_params(walk=dict(step_length=0.25))
    for _ in range(2):
        session.tick()
    plan = session.walker.plan
    lengths = np.diff(plan.footholds()[:, 0])
    assert np.isclose(session.walker.params.walk.step_length, 0.25)
    assert np.any(np.isclose(np.abs(lengths), 0.25, atol=1e-9)) or np.any(
        np.isclose(np.diff(plan.swing_to[:, 0]), 0.25, atol=1e-9)
    )


def test_bad_parameters_are_rejected_before_anything_starts():
    with pytest.raises(ValueError, match="step_length"):
        ControllerParams().replace(walk=dict(step_length=float("nan")))
    with pytest.raises(ValueError, match="method"):
        ControllerParams().replace(method="")
    with pytest.raises(ValueError, match="unknown method 'sideways': choose from fixed"):
        RunSpec("sideways", 0.3, 3)  # a robot is made of registered strategies only
    with pytest.raises(ValueError, match="horizon"):
        ControllerParams().replace(com=dict(horizon=0.05, sample_time=0.1))


def test_controller_is_pure():
    """controller/ never imports the simulator loop, the web stack, threads or clocks."""
    banned = {"mujoco", "viser", "fastapi", "uvicorn", "threading", "time", "app"}
    for path in (ROOT / "controller").glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names = [a.name.split(".")[0] for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [(node.module or "").split(".")[0]]
            else:
                continue
            assert not banned & set(names), f"{path.name} imports {names}"


def test_switching_method_live_keeps_walking():
    """fixed -> mpc -> redundancy mid-walk: the robot keeps walking, the waist starts turning."""
    session = Session(RunConfig(params=_params("fixed", 0.25, 6)))
    angles = []
    for method in ("fixed", "mpc", "redundancy"):
        session.walker.replace_params(method=method)
        for _ in range(300):
            out = session.tick()
            angles.append((method, out.waist_angle))
    assert not session.fell
    assert max(abs(a) for m, a in angles if m == "fixed") < 1e-9
    assert max(abs(a) for m, a in angles if m == "mpc") > np.deg2rad(3)


@pytest.mark.parametrize("layer", ["ik_solver", "arm_solver", "pelvis_mpc", "com_mpc"])
def test_a_failing_qp_is_counted_and_the_loop_goes_on(layer):
    """Every layer's QP fails for 10 ticks (0.05 s) mid-walk, whichever way it solves (its
    compiled step or solve): no crash, counted, still walks."""
    from controller.qp import QpResult

    session = Session(RunConfig(params=_params("mpc", 0.2, 3)))
    if layer == "pelvis_mpc":  # the MPC strategy's own, built at its first tick
        session.tick()
        owner = session.walker.strategy.strategy.mpc
    else:
        owner = getattr(session.walker, layer)
    solver = owner if layer.endswith("_solver") else owner.solver
    real_solve = solver.solve
    calls = {"n": 0}

    def flaky(qp):
        calls["n"] += 1
        if 400 <= calls["n"] < 410:
            solver.failures += 1
            fallback = solver.x_prev if solver.x_prev is not None else np.zeros(len(qp.q))
            return QpResult(fallback, False, "forced failure")
        return real_solve(qp)

    real_settle = solver.settle

    def flaky_settle(qp, x, status, flag, setup):  # a layer's compiled step: the same ticks
        calls["n"] += 1
        if 400 <= calls["n"] < 410:
            status, flag = -3, -1  # DAQP's "infeasible"
        return real_settle(qp, x, status, flag, setup)

    solver.solve = flaky
    solver.settle = flaky_settle
    while not session.done:
        out = session.tick()
        assert np.all(np.isfinite(out.q_target))
    s = summarize(session)
    name = {"ik_solver": "ik", "arm_solver": "arm_swing"}.get(layer, layer)
    assert s["solver_failures_by_layer"][name] == 10
    assert s["solver_failures"] == 10
    assert not s["fell"]
    # 10 failed ticks of about 1400: within the share a success allows (pelvic_walk.core.summary)
    assert s["solver_failure_share"] == 10 / session.walker.ticks < 0.01 and s["success"]


def test_energy_windows_skip_the_start_and_landings_follow_a_replan():
    """Two-step energy windows start at step 1; a step-time change keeps landing checks right."""
    session = Session(RunConfig(params=_params("fixed", 0.2, 6)))
    for _ in range(500):  # into step 1
        session.tick()
    session.walker.replace_params(walk=dict(step_time=0.9))
    while not session.done:
        session.tick()
    s = summarize(session)
    assert s["success"]
    assert max(s["landing_errors"]) < 0.02  # measured after each (re-timed) touch-down
    # steps 1..6 (6 = the closing step's start): windows (1->3), (3->5)
    assert len(s["energy_two_step_windows"]) == 2
    w = np.array(s["energy_two_step_windows"])
    assert np.all(w > 0) and np.std(w) < 0.5 * np.mean(w)


def test_peaks_stop_at_a_fall():
    session = run(RunConfig(params=_params("fixed", 0.5, 6)))
    s = summarize(session)
    assert s["fell"]
    t = session.series.column("t")
    ym = np.abs(session.series.column("yaw_momentum"))
    assert s["yaw_momentum_peak"] == pytest.approx(np.max(ym[t <= s["fall_time"]]))


def test_the_tick_reads_the_plan_the_sampler_gives_through_a_replan():
    """The walker's plan rows (a table filled ahead) are the sampler's answer at the tick's
    times, also after a replan and a change of the horizon."""
    session = Session(RunConfig(params=_params("mpc", 0.3, 4)))
    w = session.walker
    for i in range(420):
        if i == 250:
            w.replace_params(walk=dict(step_length=0.2))
        if i == 330:
            w.replace_params(com=dict(horizon=1.2, zmp_margin=0.03))
        out = session.tick()
        times = np.concatenate(((out.t, out.t + w.dt), out.com_plan.times))
        want = w.plan.sample(times, w.params.com.zmp_margin)
        for name, have, expected in zip(want._fields, out.plan_sample, want, strict=True):
            np.testing.assert_array_equal(have, expected, err_msg=f"{name} at tick {i}")
    assert w.plan.walk.step_length == 0.2 and len(out.com_plan.times) == 12


def test_a_session_measured_at_display_rate_walks_and_measures_as_one_measured_every_tick():
    """record=False (live) skips the per-tick measurement and series: the walk is the same,
    and a measurement taken when read equals the every-tick one (its LIPM ZMP needs the tick
    before measured too)."""
    cfg = RunConfig(params=_params("mpc", 0.3, 2))
    every, lazy = Session(cfg), Session(cfg, record=False)
    for i in range(700):
        a, b = every.tick(), lazy.tick()
        np.testing.assert_array_equal(a.q_target, b.q_target)
        if i % 7 in (0, 1):  # read at some ticks only, two in a row now and then
            ma, mb = every.measured, lazy.measured
            assert ma is not None and mb is not None
            np.testing.assert_array_equal(ma.support, mb.support)
            np.testing.assert_array_equal(ma.com, mb.com)
            assert (ma.cop_inside, ma.yaw_momentum, ma.energy) == (
                mb.cop_inside,
                mb.yaw_momentum,
                mb.energy,
            )
            if i % 7 == 1:
                assert np.isfinite(mb.lipm_zmp).all()
            else:
                assert np.isnan(mb.lipm_zmp).all()
            assert (a.kappa_low, a.kappa_legs) == (b.kappa_low, b.kappa_legs)
    assert lazy.fell == every.fell is False
    assert lazy.energy_at_step_start.keys() == every.energy_at_step_start.keys()
    assert len(lazy.series) == 0 and len(every.series) == 700


def test_the_measured_com_hands_over_between_the_soles_without_a_jump():
    """Eq. (19)'s CoM estimate anchors the measured legs at the planned soles with weights that
    follow the ZMP reference: the support sole alone in single support, 0.5 standing, and a
    hand-over no faster than the DSP (switching at lift-off jerked the pelvis sideways)."""
    from controller.footsteps import LEFT, plan_footsteps
    from controller.params import CONTROL_DT, WalkParams
    from controller.walker import support_share

    for split in ("start", "both_ends"):
        plan = plan_footsteps(WalkParams(step_length=0.3, n_steps=4, dsp_split=split))
        t = np.arange(0.0, plan.t_end, CONTROL_DT)
        s = plan.sample(t)
        w = np.array(
            [support_share(s.p_left[i], s.p_right[i], s.zmp_ref[i]) for i in range(len(t))]
        )
        ssp = s.in_ssp
        assert ssp.any()
        np.testing.assert_allclose(w[ssp], (s.support_side[ssp] == LEFT).astype(float), atol=1e-9)
        assert w[0] == pytest.approx(0.5) and w[-1] == pytest.approx(0.5)
        dsp = plan.dsp_time / (2 if split == "both_ends" else 1)
        assert np.abs(np.diff(w)).max() <= CONTROL_DT / dsp + 1e-9


def test_the_measured_com_moves_smoothly_at_lift_off_and_touch_down():
    session = Session(RunConfig(params=_params("fixed", 0.3, 3)))
    error, phase = [], []  # measured - desired CoM (what eq. 19 corrects), single support
    while not session.done:
        out = session.tick()
        error.append(out.p_world_com_meas[:2] - out.p_world_com_des)
        phase.append(out.in_ssp)
    change = np.linalg.norm(np.diff(np.array(error), axis=0), axis=1)
    edges = np.flatnonzero(np.diff(np.array(phase, dtype=int)))  # lift-offs and touch-downs
    assert len(edges) >= 6
    # a switch between the two anchors changed it by 1.5-3 mm in one tick
    assert change[edges].max() < 0.5e-3, change[edges]
