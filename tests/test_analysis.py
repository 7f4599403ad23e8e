"""Tests of the kinematic analysis, eq. (1)-(5)."""

import math

from controller.analysis import hip_points_for_angle, kinematic_analysis, reachable_step

KEYS = {
    "l_leg",
    "z0",
    "l_pel",
    "w_step",
    "theta_pel_deg",
    "step_max_fixed_static",
    "step_max_rotation_static",
    "step_max_fixed_stretched",
    "step_max_rotation_stretched",
    "increase_percent",
}


def test_keys():
    assert set(kinematic_analysis()) == KEYS


def test_paper_numbers():
    r = kinematic_analysis()
    assert abs(r["step_max_fixed_static"] - 0.31) < 0.01
    assert abs(r["step_max_rotation_static"] - 0.42) < 0.01
    assert 30.0 < r["increase_percent"] < 36.0  # paper: +35 % on rounded values
    assert abs(r["step_max_fixed_stretched"] - 2 * r["step_max_fixed_static"]) < 1e-12
    assert r["step_max_rotation_stretched"] > r["step_max_fixed_stretched"]


def test_literal_rule():
    r = kinematic_analysis(rule="literal")
    assert abs(r["step_max_rotation_static"] - (0.3164 + 0.105 * math.sin(math.pi / 4))) < 1e-3


def test_helpers():
    x = hip_points_for_angle(45.0, 0.21)
    assert abs(x[1] - x[0] - 0.21 * math.sin(math.pi / 4)) < 1e-12
    assert x[0] < 0 < x[1]
    assert abs(reachable_step(0.75, 0.68, 0.21, 0.0) - 0.3164) < 1e-3
    assert (
        abs(
            reachable_step(0.75, 0.68, 0.21, 45.0)
            - kinematic_analysis()["step_max_rotation_static"]
        )
        < 1e-12
    )
    assert reachable_step(0.75, 0.68, 0.21, 30.0) < reachable_step(0.75, 0.68, 0.21, 45.0)
