"""The QP inspector's faces without a browser: the Inspect tab's HTML, the joint
marks on the robot, the touched ZMP bounds on the horizon strip, the lessons' row, Run.qp."""

from __future__ import annotations

import numpy as np
import pytest

import pelvic_walk as pw
from app.web.learn_gui import COLUMNS, ik_limits
from app.web.lessons import LESSONS
from app.web.plots import touched_y
from app.web.qp_marks import limit_joints
from app.web.qp_view import qp_html


@pytest.fixture(scope="module")
def fixed_042():
    return pw.simulate(method="fixed", step_length=0.42, steps=4)


def _knee_frames(run):
    return [f for f in run._frames if f.robots[0].qp and limit_joints(f.robots[0])]


def test_run_qp_returns_the_nearest_record_and_the_series_counts(fixed_042):
    run = fixed_042
    rec = run.qp(1.0)
    assert abs(rec.t - 1.0) <= 0.03 and [e.layer for e in rec.layers][0] == "com_mpc"
    assert not rec["pelvis_mpc"].ran
    ik = run.column("active_ik")
    assert np.nanmax(ik) >= 2  # the pin and a knee at its limit
    assert "active_ik" in run.series.columns
    with pytest.raises(ValueError):
        run.qp(1e6)


def test_a_knee_at_its_limit_is_marked_and_named(fixed_042):
    frames = _knee_frames(fixed_042)
    assert frames, "the fixed pelvis at 0.42 m holds a knee at its limit in a recorded frame"
    r = frames[0].robots[0]
    joints = limit_joints(r)
    assert set(joints) <= {"L_knee", "R_knee"}
    page = qp_html(r, frames[0].clock)
    assert "knee at its straight limit (0 deg)" in page
    assert 'data-layer="ik"' in page and "A constraint is active" in page
    assert any("knee at its straight limit" in n for n in ik_limits(r))


def test_the_touched_zmp_bounds_sit_on_the_bounds(fixed_042):
    for f in fixed_042._frames:
        r = f.robots[0]
        if r.qp is None or r.horizon is None:
            continue
        h = r.horizon
        y = touched_y(r, h.zmp_lo[:, 1], h.zmp_hi[:, 1])
        hit = np.isfinite(y)
        n_y = sum(c.axis == "y" for c in r.qp["com_mpc"].active)
        assert hit.sum() == n_y
        assert np.all((y[hit] == h.zmp_lo[hit, 1]) | (y[hit] == h.zmp_hi[hit, 1]))


def test_lessons_1_and_6_show_the_active_constraints():
    assert "active" in COLUMNS
    for title in ("1. ", "6. "):
        lesson = next(x for x in LESSONS if x.title.startswith(title))
        assert "active" in lesson.numbers and "what stops the IK" in lesson.watch


def test_the_view_shows_the_robot_the_dropdown_names_and_follows_a_new_choice(fixed_042):
    """The Inspect tab's dropdown names robots by their label; the QP view draws the chosen
    robot's explanation, and a new choice is drawn at once from the last frame (paused, no new
    frame comes to draw it)."""
    import dataclasses

    import viser

    from app.bench.local_server import free_port
    from app.web.plots import HorizonInspector
    from app.web.qp_view import QpView
    from pelvic_walk.core.methods import METHOD_INFO

    frame = _knee_frames(fixed_042)[0]
    mpc = dataclasses.replace(frame.robots[0], method="mpc", qp=None)
    frame = dataclasses.replace(frame, robots=(mpc, frame.robots[0]), paused=True)
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        inspector = HorizonInspector(server.gui)
        view = QpView(server.gui, inspector)
        inspector.update(frame, 0.0)
        view.update(frame, 0.0, paused=True)
        assert 'data-layer="ik"' not in view.html.content  # the MPC robot, no record
        inspector.robot.value = METHOD_INFO["fixed"].title  # fires the dropdown's callback
        assert 'data-layer="ik"' in view.html.content and "knee" in view.html.content
    finally:
        server.stop()
