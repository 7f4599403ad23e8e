"""The lesson tables while a robot lies fallen (no server, no browser): it keeps saying what it
is (its settings do not change with a fall), and its fall (the collapse before the fall test
fires, the poses on the floor) enters no "max since the last change" nor the waist's range
of the last two steps. The lessons' text says what the panel does and quotes what was
measured, in one notation."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from app.live.history import COL


def _robot(clock: float, kappa: float, reach: float = 0.9, **kw):
    """A robot's frame as the tally and the table read it."""
    fields = dict(
        method="k_pel 0.45",
        clock=clock,
        waiting=False,
        finished=False,
        fell=False,
        fell_clock=None,
        error=None,
        status="clean",
        kappa_legs=kappa,
        reach=np.array([reach, reach - 0.1]),
        qp=None,
    )
    fields.update(kw)
    return SimpleNamespace(**fields)


def test_a_fall_enters_no_maximum_from_before_it_was_seen_until_the_restart():
    """The fall test fires up to 0.65 s after the legs gave way (kappa 1e8-1e9 in between,
    measured with H = 1.2 s, k_pel 0.45 at 0.40 m): none of that is the lesson's walk."""
    from app.web.learn_gui import _Tally

    tally = _Tally()
    dt = 0.02
    times = np.arange(0.0, 6.0, dt)
    for t in times:
        if t < 2.0:  # walking
            tally.add(_robot(t, 40.0))
        elif t < 2.6:  # collapsing: the knee straight, not yet counted as a fall
            tally.add(_robot(t, 3.3e9, reach=1.0))
        elif t < 4.6:  # lying fallen (fell at 2.6 s) until every robot restarts
            tally.add(_robot(t, 3.3e9, reach=1.0, fell=True, fell_clock=2.6, status="fell"))
        elif t < 4.8:  # standing by to start in phase
            tally.add(_robot(t, float("nan"), waiting=True))
        else:  # walking again after the restart
            tally.add(_robot(t, 50.0, reach=0.95))
    assert tally.kappa_max == 50.0, "the fall's kappa counted in the maximum"
    assert tally.reach_max == 0.95, "the fall's reach counted in the maximum"
    # a frame counts in the maxima once it is FALL_LOOKBACK_S old, or at the walk's end
    from app.web.learn_gui import FALL_LOOKBACK_S

    young = _Tally()
    young.add(_robot(0.0, 40.0))
    assert young.kappa_max == -np.inf
    young.add(_robot(0.5, 45.0, finished=True))
    assert young.kappa_max == 40.0
    assert FALL_LOOKBACK_S >= 0.65
    assert tally.status["fell"] == 100, "the share of the time still counts the fall"


def test_a_robot_lying_fallen_keeps_its_settings_in_the_table():
    from app.web.learn_gui import LearnTab
    from app.web.looks import looks

    tab = LearnTab.__new__(LearnTab)  # only the table's cells: no GUI
    tab.run = None
    from controller.params import ControllerParams

    shared = ControllerParams().replace(method="mpc")
    mine = shared.replace(pelvis={"k_pel": 0.45})
    frames = [
        SimpleNamespace(method="mpc", strategy="mpc", params=shared),
        SimpleNamespace(method="k_pel 0.45", strategy="mpc", params=mine),
    ]
    tab._look = looks(frames)
    down = _robot(3.0, 3.3e9, fell=True, fell_clock=2.6, status="fell")
    assert tab._cell("differ", down, None) == "k_pel=0.45"
    assert tab._cell("kappa_legs", down, None) == "-"  # what it measures says nothing now


def test_the_waist_of_the_last_two_steps_leaves_out_the_fall_and_the_walk_before():
    from app.web.learn_gui import this_walk

    rows = np.full((10, len(COL)), np.nan)
    rows[:, COL["t"]] = [3.0, 3.1, 3.2, 3.3, 3.4, 0.0, 0.1, 0.2, 0.3, 0.4]
    rows[:, COL["fell"]] = [0, 0, 1, 1, 1, 0, 0, 0, 0, 0]
    rows[:, COL["waist_deg"]] = [20, -20, 80, -90, 70, 1, 5, 10, 15, -24]
    assert list(this_walk(rows)[:, COL["waist_deg"]]) == [1, 5, 10, 15, -24]
    rows[5:, COL["fell"]] = 1  # fallen again: nothing of a walk to show
    assert len(this_walk(rows)) == 0
    assert list(this_walk(rows[:5])[:, COL["waist_deg"]]) == [20, -20]


def test_lesson_4_says_what_choosing_all_robots_does():
    from app.web.lessons import LESSONS
    from app.web.panel import target_note

    text = LESSONS[3].watch
    assert "gives both the same value again" not in text
    assert "changes nothing by itself" in text and "next slider you move" in text
    assert "dropped" in text and "dropped" in target_note("all robots")


def test_lesson_9_quotes_what_was_measured_in_one_notation():
    from app.web.lessons import LESSONS

    lesson = next(x for x in LESSONS if "beta_pel" in x.title)
    text = lesson.watch
    assert "±24.5°" in text and "±22.3°" in text, "the waist as measured (and as the table reads)"
    assert "own plan is not seen" not in text and "1e-2" not in text
    assert "kappa is higher" in text
    assert lesson.robots() == ("mpc", "beta_pel 0.01")
