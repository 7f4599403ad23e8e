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


# -- the Learn tab's drawing of eq. (1)-(5) (app/web/lesson_math.py) ---------------------------
def test_analysis_view_shows_both_readings_of_eq5_and_one_percentage():
    import xml.dom.minidom

    from app.web.lesson_math import EQUATIONS, analysis_html, analysis_svg
    from app.web.lessons import CLEAN_LIMIT_M, EXPLAIN

    for theta in (0.0, 20.0, 45.0):
        xml.dom.minidom.parseString(analysis_svg(theta))  # well-formed SVG
        xml.dom.minidom.parseString(f"<div>{analysis_html(theta, CLEAN_LIMIT_M)}</div>")
    page = analysis_html(45.0, CLEAN_LIMIT_M)
    assert "0.391 m" in page and "0.421 m" in page and "0.316 m" in page  # eq. 5 x2, eq. 4
    assert "148 mm" in page  # eq. 2: l_pel sin 45 deg between the hips
    # one figure for the paper's gain everywhere: +33 % (its +35 % only as "the paper writes")
    assert "+33 %" in page and "+33 %" in EXPLAIN["Kinematic analysis (eq. 1-5)"]
    assert page.count("35 %") == 1 and "writes +35 %" in page
    # at 0 deg the drawing puts both feet at eq. 4
    assert analysis_html(0.0, CLEAN_LIMIT_M).count("0.316 m") >= 3
    for number, math_block in EQUATIONS.items():
        xml.dom.minidom.parseString(f"<div>{math_block}</div>")
        assert f"({number})" in math_block


def test_the_lessons_quote_the_reference_report():
    """The lessons' limits, the MPC's waist and the paper's numbers are the reference report's
    (app.reference_report's results.json), not typed: the clean limits are section 2's, the
    paper's are app/experiments/paper.py's."""
    import json

    from app.experiments import paper
    from app.web import lesson_numbers
    from app.web.lessons import CLEAN_LIMIT_M, LESSONS, PAPER_LIMIT_M, PRESETS
    from pelvic_walk.core.report_dir import reference_report_dir

    data = json.loads((reference_report_dir() / "results.json").read_text())
    assert CLEAN_LIMIT_M == {m: d["longest_clean"] for m, d in data["max_step"].items()}
    assert PAPER_LIMIT_M == paper.MAX_STEP and lesson_numbers.paper() == paper.numbers()
    first = LESSONS[0].watch
    assert f"fixed {CLEAN_LIMIT_M['fixed']:.2f} m, MPC {CLEAN_LIMIT_M['mpc']:.2f} m" in first
    waist = data["waist"]["cases"]["mpc@0.40"]["peak_abs_angle_deg"]
    assert f"about {waist:.0f}°" in first
    eq5 = paper.KINEMATICS.step_max_rotation
    assert f"{eq5:.2f} m (eq. 5): the fixed pelvis falls" in PRESETS


def test_every_lesson_names_the_paper_and_is_shown_live():
    from app.web.camera import CAMERA_VIEWS
    from app.web.learn_gui import COLUMNS
    from app.web.lesson_math import EQUATIONS
    from app.web.lessons import LESSONS
    from controller.params import ControllerParams
    from controller.strategy import BUILTINS as METHODS

    assert len(LESSONS) >= 6
    for lesson in LESSONS:
        assert "eq." in lesson.paper
        assert lesson.view in CAMERA_VIEWS
        assert set(lesson.methods) <= set(METHODS) and lesson.methods
        assert all(n in EQUATIONS for n in lesson.equations)
        assert all(k in COLUMNS for k in lesson.numbers)
        setup = lesson.setup()
        ControllerParams().replace(
            **{k: v for k, v in setup.items() if k in ("walk", "pelvis", "com", "arms")}
        ).validated()
