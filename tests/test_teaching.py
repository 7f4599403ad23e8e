"""What ``serve`` tells the person starting a class (docs/TEACHING.md)."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.web.server import private_room_line


@pytest.mark.parametrize(
    ("workers", "per_worker", "robots", "demo", "fit"),
    [
        (4, 1, 3, True, 0),  # a 2-core machine: the demo's 3 robots leave one slot
        (4, 1, 3, False, 1),
        (4, 1, 1, True, 3),
        (8, 1, 3, True, 1),
        (3, 4, 2, True, 5),
        (1, 2, 3, False, 0),
    ],
)
def test_the_start_up_line_says_how_many_private_sessions_fit(
    workers, per_worker, robots, demo, fit
):
    line = private_room_line(workers, per_worker, robots, demo)
    assert line.startswith(f"pelvic-walk: {fit} private session")
    assert f"of {robots} robot" in line and f"{workers * per_worker} robot slots" in line
    if fit == 0:  # none: said plainly, with what to do
        assert "For private sessions start with" in line and "--workers" in line
        assert ("--no-shared-demo" in line) is demo
        assert ("every student watches the shared demo" in line) is demo
        assert ("--methods mpc" in line) is (robots > 1)
    else:
        assert "For private sessions" not in line


def test_falls_count_from_the_last_restart_asked_for():
    """The status line's "falls N": the session's own restarts after a fall keep counting (a
    student sees three falls after three), a restart someone asks for (a lesson's) starts at 0."""
    import dataclasses

    from app.live.loop import LiveLoop
    from app.live.session import initial_intent
    from controller.params import ControllerParams

    intent = [
        dataclasses.replace(
            initial_intent(ControllerParams().replace(walk={"n_steps": 6}), ["mpc"]),
            anchor=(0.0, 0.0),
        )
    ]
    frames: list = []
    wall = [0.0]

    def sleep(s: float) -> None:
        wall[0] += s

    loop = LiveLoop(lambda: intent[0], frames.append, clock=lambda: wall[0], sleep=sleep)

    def run_to(clock: float):
        while not frames or frames[-1].clock < clock:
            loop.iterate()
        return frames[-1].robots[0]

    def restart(auto: bool) -> None:
        cur = intent[0]
        clock = frames[-1].clock + 0.1
        intent[0] = dataclasses.replace(
            cur,
            reset_requests=cur.reset_requests + 1,
            auto_restarts=cur.auto_restarts + auto,
            start_clock=clock,
            version=cur.version + 1,
        )

    def fall() -> None:
        loop.robots["mpc"].session.fell = True
        loop.robots["mpc"].session.fall_reason = "a test's fall"

    run_to(0.5)
    for n in (1, 2):
        fall()
        assert run_to(frames[-1].clock + 0.1).falls == n
        restart(auto=True)  # the session's own restart after the fall was shown
        assert run_to(frames[-1].clock + 0.3).falls == n and not frames[-1].robots[0].fell
    restart(auto=False)  # a lesson or a user restarts the robots
    assert run_to(frames[-1].clock + 0.3).falls == 0
    fall()
    assert run_to(frames[-1].clock + 0.1).falls == 1


def test_lesson_2_points_at_the_button_that_stops_with_both_feet_down():
    """The double support lasts 0.24 s at lesson 2's 1.2 s steps: a student cannot press Pause
    inside it by hand; the lesson names the panel's "to landing" step that stops there."""
    import app.web.panel
    from app.web.lessons import LESSONS

    lesson = next(x for x in LESSONS if x.title.startswith("2."))
    assert "Step: to landing" in lesson.watch
    panel = Path(app.web.panel.__file__).read_text()
    assert '"Step", ("5 ms tick", "to lift-off", "to landing")' in panel  # the button exists
