"""The clock jump after a long pause and a lesson press (seen once in a class walk-through:
paused in lesson 2, lesson 6 pressed, the clock went from 164.81 back to 156.75 s and both
robots stood at t = 0, step -1, for about 30 s before the lesson started).

The cause: paused, a session's time base stands where it was last anchored (its last resume),
while single steps ("to lift-off") move the session's loops on. Lesson 6 adds a robot (lesson 2
shows one), and the new robot's loop (its own part, in a worker process) joined the session at
that stale anchor, seconds behind the others. The merged frames show every robot at the
slowest part's clock, so the session clock went back; the catch-up then moved the time base
back too, and the other loops waited out the difference with their robots rebuilt and
standing (at speed 1 on a loaded machine: tens of seconds).
"""

from __future__ import annotations

import dataclasses
import threading

import pytest

from app.live.intent import IntentBox
from app.live.loop import LiveLoop
from app.live.pool import START_DELAY_S, WorkerPool
from app.live.session import initial_intent
from controller.params import ControllerParams
from pelvic_walk.core.robots import Robot

PARAMS = ControllerParams().replace(walk={"n_steps": 40})


class Wall:
    """A wall clock the loop's pacing sleep advances (no real waiting)."""

    def __init__(self) -> None:
        self.now = 1000.0
        self.lock = threading.Lock()

    def clock(self) -> float:
        with self.lock:
            return self.now

    def sleep(self, seconds: float) -> None:
        with self.lock:
            self.now += max(seconds, 0.0)


def test_a_loop_built_while_paused_joins_at_the_sessions_present():
    wall = Wall()
    box = IntentBox(
        dataclasses.replace(
            initial_intent(PARAMS, ["mpc"]), anchor=(wall.now, 0.0), start_clock=0.0
        )
    )
    frames: list = []
    first = LiveLoop(box.get, frames.append, clock=wall.clock, sleep=wall.sleep)
    while first.clock < 2.0:
        first.iterate()
    box.modify(lambda _c: {"paused": True})
    first.iterate()
    for _ in range(3):  # Step: to lift-off, three times, while paused
        box.modify(lambda c: {"step_requests": c.step_requests + 1, "step_until": "liftoff"})
        first.iterate()
    present = first.clock
    assert present > 2.5 and box.get().anchor[1] < 1.0  # the time base stayed behind
    # a robot added while paused (what the session's set_methods asks: a restart at the
    # present, app.live.session.SessionView._restart_at), its loop built now
    box.modify(
        lambda c: {
            "robots": (Robot("fixed"), Robot("mpc")),
            "reset_requests": c.reset_requests + 1,
            "start_clock": present,
        }
    )
    added: list = []
    second = LiveLoop(
        lambda: dataclasses.replace(box.get(), robots=(Robot("fixed"),)),
        added.append,
        clock=wall.clock,
        sleep=wall.sleep,
    )
    second.iterate()
    assert added[-1].clock == pytest.approx(present, abs=PARAMS.control_dt / 2)
    # and a loop rebuilt by that restart while paused stands at the present too
    first.iterate()
    assert frames[-1].clock == pytest.approx(present, abs=PARAMS.control_dt / 2)


@pytest.fixture(scope="module")
def pool():
    p = WorkerPool(1, robots_per_worker=2).start()
    yield p
    p.stop()


def test_a_lesson_pressed_after_steps_while_paused_never_takes_the_clock_back(pool):
    """The whole sequence with robots in worker processes, as the Learn tab's button does it
    (app.web.learn_gui.LearnTab.start): paused in a one-robot lesson, stepped to lift-off,
    then a two-robot lesson pressed."""
    s = pool.open(initial_intent(PARAMS, ["mpc"]), sid="lesson")
    try:
        f = s.wait_frame(timeout=60)
        while f is not None and f.clock < 1.5:
            f = s.wait_frame(f.seq, timeout=30)
        assert f is not None
        s.wait_applied(s.pause(), timeout=20)
        for _ in range(3):
            f = s.wait_applied(s.step("liftoff"), timeout=30)
        assert f is not None
        present = f.clock
        seen: list[float] = []
        # lesson 6: its robots, its parameters, resume, restart (learn_gui.LearnTab.start)
        s.set_methods(["fixed", "mpc"])
        s.set_params(PARAMS.replace(walk={"step_length": 0.3}))
        s.resume()
        start = s.reset().start_clock
        while f is not None and not (len(f.robots) == 2 and all(r.t > 0.2 for r in f.robots)):
            f = s.wait_frame(f.seq, timeout=30)
            if f is not None:
                seen.append(f.clock)
        assert f is not None, "the lesson's robots never walked"
        assert min(seen) >= present - 1e-6, f"the clock went back from {present} to {min(seen)}"
        # the robots started after the restart's delay, not after a wait for a lagging loop
        assert start - present <= START_DELAY_S * 1.0 + 1.0, (present, start)
        starts = [r.clock - r.t for r in f.robots]
        assert max(starts) - min(starts) < 0.011 and min(starts) <= start + 0.011, starts
    finally:
        pool.close(s)
