"""A lesson is the session's state: every view of the session shows it (no browser).

With an instructor, each browser has its own view (panel) of the shared session; the
instructor starts a lesson in theirs, and each student's Learn tab, read-only, shows the
lesson's head, text, equations and the same live numbers, a student who joins later too.
"""

from __future__ import annotations

import time

import pytest

from app.web.lessons import LESSONS


@pytest.fixture(scope="module")
def class_views(live_pool):
    """A live session and three views on it: the instructor's and two students'."""
    import viser

    from app.bench.local_server import free_port
    from app.live.registry import SessionRegistry
    from app.live.session import initial_intent
    from app.web.view import View
    from controller.params import ControllerParams

    params = ControllerParams().replace(walk={"n_steps": 20})
    sim = live_pool.open(initial_intent(params, ["fixed", "mpc"]), sid="shared")
    registry = SessionRegistry.around(sim)
    servers = []

    def view(read_only: bool) -> View:
        server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
        servers.append(server)
        return View(server, sim, registry, read_only=read_only)

    try:
        yield sim, view
    finally:
        for server in servers:
            server.stop()
        live_pool.close(sim)


def test_every_view_of_the_session_shows_the_lesson_the_instructor_started(class_views):
    sim, make_view = class_views
    teacher, student = make_view(False), make_view(True)
    views = [teacher, student]
    clock = [time.monotonic()]

    def draw_until(check, what: str, timeout: float = 120.0):
        """Draw every view on each new frame until ``check()`` holds."""
        deadline = time.monotonic() + timeout
        f = sim.frame()
        while time.monotonic() < deadline:
            clock[0] += 10.0  # past the tabs' refresh interval: each draw refreshes them
            for v in views:
                v.draw(clock[0])
            if check():
                return
            f = sim.wait_frame(f.seq if f else -1, timeout=30)
        pytest.fail(f"waited {timeout:.0f} s for {what}")

    draw_until(lambda: sim.frame() is not None, "a first frame")
    student.panel.learn.start(5)  # a student's button: refused, nothing starts
    assert student.panel.learn.lesson is None and teacher.panel.learn.lesson is None
    lesson = LESSONS[5]
    teacher.panel.learn.start(5)

    def shown(v) -> bool:
        learn = v.panel.learn
        return (
            learn.lesson is lesson
            and lesson.title in learn.head.content
            and "into the lesson" in learn.live.content
        )

    draw_until(lambda: all(shown(v) for v in views), "every view to show the lesson")
    s, t = student.panel.learn, teacher.panel.learn
    assert s.text.content == t.text.content and "<math" in s.text.content  # text + equations
    assert s.head.content == t.head.content and s.run is t.run  # one lesson, the session's
    assert all(b.disabled for b in s.buttons) and not any(b.disabled for b in t.buttons)

    # a student who opens the page now reads the lesson too, with the same numbers
    late = make_view(True)
    views.append(late)
    draw_until(lambda: shown(late), "the late student's view to show the lesson")
    try:
        # the frame that shows the pause (the loop publishes it at once; waiting for a frame
        # newer than the one read after asking could wait for one that never comes)
        f = sim.wait_applied(sim.pause(), timeout=60)
        assert f is not None and f.paused
        draw_until(
            lambda: len({v.panel.learn.live.content for v in views}) == 1,
            "the paused frame's numbers in every view",
        )
        assert "paused" in late.panel.learn.live.content
    finally:
        sim.resume()

    # the next lesson replaces it everywhere
    teacher.panel.learn.start(2)
    draw_until(
        lambda: (
            all(v.panel.learn.lesson is LESSONS[2] for v in views)
            and LESSONS[2].title in late.panel.learn.head.content
        ),
        "every view to show the next lesson",
    )
