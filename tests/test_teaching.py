"""What ``serve`` tells the person starting a class (docs/TEACHING.md)."""

from __future__ import annotations

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
