"""`pelvic-walk bench`: it runs and writes every key of docs/REFERENCE.md, "bench JSON" (no
timing assertions)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from app.bench.timings import BACKENDS, QP_LAYERS, main, urdf_from_mjcf

INTERFACE_KEYS = (
    "tick_ms_median",
    "tick_ms_p99",
    "realtime_factor",
    "bare_step_realtime_factor",
    "overhead_ratio",
    "realtime_factor_unrecorded",
    "overhead_ratio_unrecorded",
    "overhead_ratio_unrecorded_cpu",
)
LAYERS = ("com_mpc", "pelvis_mpc", "ik", "arm_swing", "kinematics")


def _finite_positive(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and x > 0


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> dict:
    path = tmp_path_factory.mktemp("bench") / "b.json"
    assert main(path, ticks=200) == 0
    return json.loads(path.read_text())


def test_interface_keys_are_finite_and_positive(report):
    for key in INTERFACE_KEYS:
        assert _finite_positive(report[key]), (key, report[key])
    assert set(LAYERS) <= set(report["layer_ms"])
    for name in LAYERS:
        assert _finite_positive(report["layer_ms"][name]), (name, report["layer_ms"][name])


def test_the_qp_layers_split_into_build_and_solve_and_the_tick_without_physics(report):
    """Each QP layer's mean time splits into its build (and data) and DAQP's solve, a part
    of it, both positive;
    the tick without physics between ticks (the peer's way) has its figures."""
    assert set(report["layer_solve_ms_mean"]) == set(QP_LAYERS)
    for name in QP_LAYERS:
        build, solve = report["layer_build_ms_mean"][name], report["layer_solve_ms_mean"][name]
        assert _finite_positive(build) and _finite_positive(solve), (name, build, solve)
        assert solve < report["layer_ms_mean"][name]  # DAQP's solve is a part of its layer
    for key in ("tick_ms_median", "tick_ms_mean", "tick_ms_p99", "tick_ms_max"):
        assert _finite_positive(report["open_loop"][key]), key


def test_overhead_ratio_is_the_ratio_of_the_two_factors(report):
    ratio = report["bare_step_realtime_factor"] / report["realtime_factor"]
    assert report["overhead_ratio"] == pytest.approx(ratio)
    unrecorded = report["bare_step_realtime_factor"] / report["realtime_factor_unrecorded"]
    assert report["overhead_ratio_unrecorded"] == pytest.approx(unrecorded)


def test_qp_backend_table(report):
    assert report["backend"] in BACKENDS
    for layer in QP_LAYERS:
        row = report["qp_backends"][layer]
        assert row["n_qps"] == report["ticks"]
        for backend in BACKENDS:
            cell = row[backend]
            assert _finite_positive(cell["solve_us_median"])
            assert math.isfinite(cell["max_abs_dev"]) and cell["max_abs_dev"] >= 0.0
            assert cell["failures"] == 0
    # the exact back-end reproduces the exact solution (the timings are not checked)
    for layer in QP_LAYERS:
        assert report["qp_backends"][layer]["daqp"]["max_abs_dev"] < 1e-8


def test_the_walk_did_not_fall_and_the_peer_ran_or_says_why(report):
    assert report["fell"] is False
    peer = report["peer"]
    if peer["installed"] and "error" not in peer:  # an interpreter with placo was given
        assert _finite_positive(peer["tick_ms_p99"]) and peer["ticks"] == report["ticks"]
    elif not peer["installed"]:
        assert peer["reason"] == "placo is not installed"


def test_the_peer_urdf_is_our_robot(tmp_path):
    """The URDF written for the peer from our MJCF: same joints, limits and mass, and its
    foot frames where our soles are (Pinocchio reads both)."""
    import pinocchio as pin

    from controller.kinematics import RobotKinematics
    from models.dyros_jet import JOINTS, ROBOT_XML

    path = tmp_path / "robot.urdf"
    path.write_text(urdf_from_mjcf(ROBOT_XML))
    urdf = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    ours = RobotKinematics(ROBOT_XML)
    assert sorted(urdf.names[2:]) == sorted(JOINTS)  # (the URDF's tree order differs)
    at = [urdf.joints[urdf.getJointId(n)].idx_q for n in JOINTS]  # ours -> the URDF's q
    assert pin.computeTotalMass(urdf) == pytest.approx(ours.total_mass)
    np.testing.assert_allclose(urdf.lowerPositionLimit[at], ours.q_min)
    np.testing.assert_allclose(urdf.upperPositionLimit[at], ours.q_max)
    q_joints = np.random.default_rng(0).uniform(-0.3, 0.3, len(JOINTS))
    data = urdf.createData()
    q = pin.neutral(urdf)
    q[at] = q_joints
    pin.framesForwardKinematics(urdf, data, q)
    for side, frame in enumerate(("left_foot", "right_foot")):
        want = ours.sole_pose_pelvis(q_joints, side)
        have = data.oMf[urdf.getFrameId(frame)].homogeneous
        np.testing.assert_allclose(have, want, atol=1e-12)
    com = pin.centerOfMass(urdf, data, q)
    np.testing.assert_allclose(com, ours.com_world(q_joints, (0, 0, 0), (1, 0, 0, 0)), atol=1e-12)


def test_bad_ticks_exit_2(capsys):
    assert main(None, ticks=0) == 2
    assert "ticks" in capsys.readouterr().err


def test_paced_share_is_cpu_per_simulated_second(report):
    """One robot paced at 1x: its share of a core and how many a core holds follow from it."""
    share = report["paced_core_share"]
    assert _finite_positive(share) and _finite_positive(report["paced_realtime_factor"])
    assert report["robots_per_core_paced"] == max(1, math.floor(1.0 / share))


def test_the_peer_replans_over_a_fixed_horizon():
    """placo's loop plans a few steps ahead at every re-plan, as placo's walk example does, not
    the whole walk: a run five times longer re-plans more often over the same horizon and walks
    on (timings are the bench's business, not checked). Needs an interpreter with placo."""
    from app.bench.timings import peer_loop, peer_python

    if peer_python() is None:
        pytest.skip("no interpreter with placo (make peers)")
    short, long = peer_loop(400), peer_loop(2000)
    for peer in (short, long):
        assert "error" not in peer, peer
    assert short["steps_ahead"] == long["steps_ahead"] and 2 <= long["steps_ahead"] <= 6
    assert long["horizon_s"] <= 8.0  # a few seconds
    assert long["replans"] >= 3 * max(short["replans"], 1)
    assert long["x_travelled"] > 4 * short["x_travelled"] > 0  # it walked on all along
