"""The live loop and a live session: intent in, frames out, pacing, plan restarts and falls (a
fallen robot lies marked for FALL_HOLD_S, then the session restarts every robot together).

The sessions run in the worker pool (the one live mode) on its in-process engine with a
:class:`~app.live.engines.VirtualClock`: the same worker code, parts and merge as worker
processes, with a wall clock that moves only when every loop waits, so frames relate to
simulated time exactly on any machine."""

from __future__ import annotations

import dataclasses
import threading

import numpy as np
import pytest

from app.live import FALL_HOLD_S, check_methods, live_params
from app.live.engines import InProcessEngine, VirtualClock
from app.live.history import ROW_COLUMNS
from app.live.loop import PUBLISH_HZ, RTF_WINDOW_S, LiveLoop
from app.live.pool import RemoteSession, WorkerPool
from app.live.session import CATCH_UP_S, SessionView, initial_intent
from controller.footsteps import plan_footsteps
from controller.params import ControllerParams, WalkParams

DT = ControllerParams().control_dt


class FakeWallClock:
    """A wall clock that moves only when the loop sleeps (the loop's compute looks free)."""

    def __init__(self) -> None:
        self.now = 0.0
        self.slept = 0.0
        self.lock = threading.Lock()

    def clock(self) -> float:
        with self.lock:
            return self.now

    def sleep(self, seconds: float) -> None:
        with self.lock:
            self.now += seconds
            self.slept += seconds


def short_params(n_steps: int = 1) -> ControllerParams:
    return ControllerParams().replace(walk={"n_steps": n_steps})


def test_check_methods_orders_and_rejects():
    assert check_methods(["mpc", "fixed", "mpc"]) == ("fixed", "mpc")
    with pytest.raises(ValueError, match="unknown method 'walk'"):
        check_methods(["walk"])
    with pytest.raises(ValueError, match="at least one"):
        check_methods([])


def test_live_params_have_a_long_plan():
    assert live_params().walk.n_steps == 200


def test_intent_is_validated_and_versioned():
    sim = SessionView(initial_intent(short_params()))
    v0 = sim.intent.version
    v1 = sim.update_params(walk={"step_length": 0.3}).version
    assert v1 == v0 + 1 and sim.intent.params.walk.step_length == 0.3
    with pytest.raises(ValueError, match="step_length"):
        sim.update_params(walk={"step_length": 0.9})
    with pytest.raises(ValueError, match="speed"):
        sim.set_speed(float("nan"))
    assert sim.intent.params.walk.step_length == 0.3  # a rejected change leaves it alone


def test_step_length_in_force_follows_the_plan():
    plan = plan_footsteps(WalkParams(step_length=0.25, n_steps=4))
    assert plan.step_length(-1) == pytest.approx(0.25)
    assert plan.step_length(2) == pytest.approx(0.25)
    replanned = plan.replanned(WalkParams(step_length=0.35, n_steps=4), plan.step_start[1] + 0.1)
    assert replanned.step_length(1) == pytest.approx(0.25)
    assert replanned.step_length(2) == pytest.approx(0.35)


@pytest.fixture(scope="module")
def virtual_pool():
    """The module's pool: one in-process worker on a VirtualClock."""
    pool = WorkerPool(1, robots_per_worker=4, engine=InProcessEngine(VirtualClock())).start()
    yield pool
    pool.stop()


@pytest.fixture
def running(virtual_pool):
    """Open a session in the pool on a VirtualClock: the wall clock moves only when every
    loop waits, so the loops never fall behind their time base and publish a frame every
    display interval of simulated time (``publish_interval * speed``), however fast the
    machine runs them (they run unpaced in real time). Frames then relate to simulated events
    exactly; a loop on the real clock that catches up publishes by wall time instead, at
    intervals the machine decides."""
    sims: list[RemoteSession] = []

    def make(params, methods, speed: float = 1.0) -> RemoteSession:
        sim = virtual_pool.open(initial_intent(params, methods, speed), sid=f"v{len(sims)}")
        sims.append(sim)
        assert sim.wait_frame(timeout=30) is not None
        return sim

    yield make
    for sim in sims:
        virtual_pool.close(sim)
        assert sim.error is None


def test_pacing_sleeps_to_the_wall_clock(running, virtual_pool):
    """With free compute, the loop sleeps simulated time / speed on the wall clock."""
    sim = running(short_params(3), ["fixed"], speed=2.0)
    wall0 = sim.intent.anchor[0]  # the wall time at which the session's clock was 0
    frame = sim.wait_frame(timeout=30)
    while frame is not None and frame.clock < 1.5:
        frame = sim.wait_frame(frame.seq, timeout=30)
    assert frame is not None
    assert frame.realtime_factor == pytest.approx(2.0, rel=0.05)
    frame = sim.wait_applied(sim.pause(), timeout=60)
    # The wall clock is at (simulated time / speed), give or take the burst of one frame
    # (the loop runs a display interval's ticks back to back, then sleeps) and a tick.
    slept = virtual_pool.clock() - wall0
    assert slept == pytest.approx(frame.clock / 2.0, abs=1.0 / PUBLISH_HZ + DT)


def _costly_loop(wall, cost: float, publish, publish_hz: float, sleep=None) -> LiveLoop:
    """One fixed robot in a loop on the fake ``wall`` clock, each iteration costing ``cost``
    seconds of wall time, the time base anchored at wall time 0."""
    intent = dataclasses.replace(initial_intent(short_params(3), ["fixed"]), anchor=(0.0, 0.0))

    def intents():
        with wall.lock:
            wall.now += cost
        return intent

    return LiveLoop(
        intents, publish, clock=wall.clock, sleep=sleep or wall.sleep, publish_hz=publish_hz
    )


def test_the_loop_wakes_once_per_frame_and_leads_by_less_than_one():
    """The ticks between two frames run back to back and the loop then sleeps off its lead on
    the time base: with a tick costing 2 ms of a 5-ms period it sleeps about once per frame
    (not once per tick), keeps real time, and leads the time base by less than a display
    interval plus a tick (what a frame can show ahead of the wall clock)."""
    wall = FakeWallClock()
    frames, sleeps, leads = [], [], []

    def sleep(seconds: float) -> None:
        sleeps.append(seconds)
        wall.sleep(seconds)

    def publish(frame) -> None:
        frames.append(frame)
        leads.append(frame.clock - wall.clock())

    loop = _costly_loop(wall, 0.002, publish, 30.0, sleep)
    while loop.clock < 3.0:
        loop.iterate()
    ticks = round(loop.clock / DT)
    assert len(frames) == pytest.approx(3.0 * 30, rel=0.15)  # the display rate on the wall
    assert len(sleeps) <= 1.2 * len(frames) < ticks / 4  # one wake a frame, not one a tick
    assert 0 < max(leads) < loop.publish_interval + DT
    assert loop.clock / wall.clock() == pytest.approx(1.0, abs=0.02)  # real time kept


@pytest.mark.parametrize(("publish_hz", "cost"), [(30.0, 0.0005), (30.0, 0.0015), (12.0, 0.002)])
def test_a_loop_that_keeps_real_time_reads_a_factor_of_one(publish_hz, cost):
    """The factor is read between frames (ends of bursts), so a paced loop that keeps real time
    reads 1.00 on average, not a bias of its lead within a burst (a window from a burst's first
    tick to a burst's end read 1.006-1.008 in 20-viewer runs that kept 1.000). What is left
    is the jitter of a frame's lead (whole ticks in a burst) over the window."""
    wall = FakeWallClock()
    factors: list[tuple[float, float]] = []

    def publish(frame) -> None:
        if frame.realtime_factor is not None:
            factors.append((wall.clock(), frame.realtime_factor))

    loop = _costly_loop(wall, cost, publish, publish_hz)
    while loop.clock < 8.0:
        loop.iterate()
    steady = np.array([f for t, f in factors if t > RTF_WINDOW_S + 1.0])
    assert len(steady) > 3 * publish_hz
    assert steady.mean() == pytest.approx(1.0, abs=0.001)
    assert np.abs(steady - 1.0).max() < 2 * DT / RTF_WINDOW_S  # two ticks over the window


def _frame_interval(sim: RemoteSession) -> float:
    """[s] of simulated time between two frames of a loop on a VirtualClock."""
    return sim.intent.speed / sim.pool.publish_hz


def _published(sim: RemoteSession, start: float, end: float) -> list:
    """Every frame the loop published with start <= clock <= end (the session keeps them
    all, ``sim.frames``), not only those the test thread happened to wake for: a test thread
    on a busy machine misses frames, and the last one showing an event may be among them."""
    return sim.frames.between(start, end)


def _started(sim: RemoteSession):
    """The first frame in which every robot has ticked (they start together after a delay)."""
    f = sim.frame()
    while f is not None and any(r.t <= 0.0 or r.waiting for r in f.robots):
        f = sim.wait_frame(f.seq, timeout=30)
    assert f is not None
    return f


def _advance(sim: RemoteSession, frames: int = 3):
    f = sim.frame()
    for _ in range(frames):
        f = sim.wait_frame(f.seq, timeout=60)
    return f


def test_pause_step_and_reset(running):
    sim = running(params=short_params(3), methods=["fixed", "mpc"])
    f = sim.wait_applied(sim.pause(), timeout=60)
    t = [r.t for r in f.robots]
    assert sim.wait_frame(f.seq, timeout=0.5) is None  # paused: nothing new is published
    assert [r.t for r in sim.frame().robots] == t  # and time stands still
    f = sim.wait_applied(sim.step(), timeout=60)
    assert [r.t for r in f.robots] == pytest.approx([x + DT for x in t], abs=1e-9)
    sim.step()
    f = sim.wait_applied(sim.step(), timeout=60)  # two more single steps
    assert [r.t for r in f.robots] == pytest.approx([x + 3 * DT for x in t], abs=1e-9)
    f = sim.wait_applied(sim.reset(), timeout=60)
    assert all(r.t <= DT + 1e-9 for r in f.robots)
    f = sim.wait_applied(sim.resume(), timeout=60)
    assert _advance(sim).robots[0].t > f.robots[0].t


def test_params_reach_every_walker_and_methods_rebuild(running):
    sim = running(params=short_params(3), methods=["fixed", "mpc"])
    ticket = sim.update_params(com={"alpha": 2.0}, walk={"step_length": 0.25})
    assert sim.wait_applied(ticket, timeout=60) is not None
    _started(sim)  # a walker takes new parameters on its next tick: after the start delay
    f = _advance(sim)
    for r in f.robots:
        assert r.params.com.alpha == 2.0 and r.params.walk.step_length == 0.25
        assert r.params.method == r.method
    for method, robot in sim.robots.items():
        assert robot.session.walker.params.com.alpha == 2.0
        assert robot.session.walker.params.method == method
    ticket = sim.set_methods(["redundancy", "fixed", "mpc"])
    f = sim.wait_applied(ticket, timeout=60)
    assert [r.method for r in f.robots] == ["fixed", "redundancy", "mpc"]
    assert [r.slot for r in f.robots] == [0, 1, 2]
    # restarted together: the first frame of the new robots (the kept frames start anew with
    # them) comes one frame interval after they were built, at most that far into their walk
    first = _published(sim, -np.inf, np.inf)[0]
    assert first.restarted and first.intent_version >= ticket.version
    assert [r.method for r in first.robots] == ["fixed", "redundancy", "mpc"]
    assert all(r.t <= _frame_interval(sim) + 1e-9 for r in first.robots)
    # one start clock (for those that have begun: each shown at its part's newest frame)
    assert len({round(_start(r), 9) for r in first.robots if r.t > 0}) <= 1


def _start(robot) -> float:
    """[s] the session clock at which a robot's walk began (its part's clock less its time):
    robots in step began at one clock, whichever frame of its part a merged frame shows."""
    return robot.clock - robot.t


def _in_step_once_walking(sim: RemoteSession) -> None:
    """Run until every robot walks: they began at one session clock."""
    f = sim.wait_applied(sim.resume(), timeout=60)
    while f is not None and not all(r.t > 0.05 for r in f.robots):
        f = sim.wait_frame(f.seq, timeout=60)
    assert f is not None
    assert _start(f.robots[0]) == pytest.approx(_start(f.robots[1]), abs=1e-9)


def _restarts(frames: list) -> list[int]:
    """Indices of the frames that show a restart: every robot is rebuilt standing, so the
    furthest robot time goes back (while they walk or lie it never does)."""
    return [
        i
        for i in range(1, len(frames))
        if max(r.t for r in frames[i].robots) < max(r.t for r in frames[i - 1].robots)
    ]


def test_a_finished_plan_restarts_every_robot_together(running):
    sim = running(params=short_params(1), methods=["fixed", "mpc"], speed=4.0)
    f = sim.frame()
    while f is not None and not (
        f.robots[0].walks_completed >= 1 and all(r.t > 0.05 and not r.finished for r in f.robots)
    ):
        f = sim.wait_frame(f.seq, timeout=60)
    assert f is not None  # both walked their plan, stood, restarted and walk again
    assert sim.wait_applied(sim.pause(), timeout=60) is not None
    frames = _published(sim, 0.0, np.inf)
    done = next(i for i, x in enumerate(frames) if all(r.finished for r in x.robots))
    restarts = _restarts(frames)
    # the restart is the session's own, made from the first frame that shows them all
    # finished: the next frame shows the robots rebuilt (and each later walk did the same)
    assert restarts[0] == done + 1
    assert sim.intent.auto_restarts == len(restarts)
    shown, after = frames[done], frames[done + 1]
    for r in after.robots:
        assert r.walks_completed == 1 and r.last_walk_success is True and not r.finished
        # a new walk, begun after the restart (give or take a frame: each robot is shown at
        # its part's newest frame not later than the merged instant)
        assert r.t <= after.clock - shown.clock + _frame_interval(sim) + 1e-9
        assert not r.waiting and np.all(np.isfinite(r.body_xpos))
    walking = next(x for x in frames[done + 1 :] if all(r.t > 0.05 for r in x.robots))
    assert _start(walking.robots[0]) == pytest.approx(_start(walking.robots[1]), abs=1e-9)


def test_a_frame_that_shows_a_walk_finished_has_counted_it():
    """The session restarts every robot from the first frame that shows them all finished, and
    the loop applies that restart before its next tick: the walk must already be counted then
    (it was counted one tick late, and a restart in between lost it)."""
    wall = FakeWallClock()
    intent = dataclasses.replace(initial_intent(short_params(1), ["fixed"]), anchor=(0.0, 0.0))
    frames: list = []
    loop = LiveLoop(  # a frame every tick: the first one that shows the robot finished
        lambda: intent, frames.append, clock=wall.clock, sleep=wall.sleep, publish_hz=1e6
    )
    while not frames or not frames[-1].robots[0].finished:
        loop.iterate()
    assert frames[-1].robots[0].walks_completed == 1
    assert frames[-1].robots[0].last_walk_success is True


def test_a_fallen_robot_lies_marked_until_every_robot_restarts_together(running):
    sim = running(params=short_params(6), methods=["fixed", "mpc"], speed=4.0)
    _started(sim)
    assert sim.wait_applied(sim.pause(), timeout=60) is not None
    robot = sim.robots["fixed"]
    robot.session.fell = True  # as the world's fall check would mark it
    robot.session.fall_reason = "test: marked as fallen"
    f = sim.wait_applied(sim.step(), timeout=60)
    fixed, mpc = f.robots
    assert fixed.fell and fixed.falls == 1 and fixed.last_walk_success is False
    assert fixed.fell_clock == pytest.approx(f.clock - DT, abs=1e-9)  # marked at once
    assert fixed.fall_reason == "test: marked as fallen"
    assert not mpc.fell and mpc.fell_clock is None
    fell_at, t_fixed, shown_at = fixed.fell_clock, fixed.t, f.clock  # (its first frame)
    # paused, the hold does not run out: steps past FALL_HOLD_S of it leave the robot down
    for _ in range(3):
        f = sim.wait_applied(sim.step("liftoff"), timeout=30)
    assert f.robots[0].fell and f.robots[0].t == t_fixed  # its controller stopped
    sim.resume()
    while f is not None and f.robots[0].fell:
        f = sim.wait_frame(f.seq, timeout=30)
    assert f is not None
    assert sim.wait_applied(sim.pause(), timeout=60) is not None
    # every frame published since the one that first showed the fall, not only those this
    # thread woke for
    frames = _published(sim, shown_at, np.inf)
    n_down = next(i for i, x in enumerate(frames) if not x.robots[0].fell)
    down, after = frames[:n_down], frames[n_down]
    held = fell_at + FALL_HOLD_S - 1e-9
    # shown down for the whole hold, and restarted after it: every frame that shows the robot
    # as it was before the hold's end shows it down, and the last one down is at or past the
    # end (the session restarts from the first such frame; a merged frame shows each part at
    # its newest frame not later than the slowest part's instant, so a frame or two more can)
    assert all(x.robots[0].fell for x in frames if x.robots[0].clock < held)
    assert down[-1].clock >= held
    assert all(x.robots[0].t == t_fixed for x in down)  # lying, no controller
    assert max(x.robots[1].t for x in down) > FALL_HOLD_S  # while the other robot walked on
    # then all restarted together, the falls counted on; the new walk began after the frame
    # that made the restart (give or take a frame: the parts' frames merge at an instant)
    assert _restarts(frames)[0] <= n_down
    for r in after.robots:
        assert r.t <= after.clock - down[-1].clock + _frame_interval(sim) + 1e-9
        assert not r.fell and not r.waiting
    _in_step_once_walking(sim)
    assert [r.falls for r in after.robots] == [1, 0]
    assert sim.intent.auto_restarts == 1 and not after.restarted
    assert sim.frames.span()[0] < fell_at  # the fall is still kept, to scrub back to


def test_a_pushed_robot_falls_and_lies_where_it_fell(running):
    """A real fall (300 N for 0.2 s topples the MPC robot): its body stays where it fell,
    marked, while the fixed pelvis walks on; then both restart at t = 0 together."""
    sim = running(params=live_params(), methods=["fixed", "mpc"], speed=4.0)
    f = _started(sim)
    while f.robots[1].step_index < 2:
        f = sim.wait_frame(f.seq, timeout=30)
    sim.wait_applied(sim.push("mpc", (0.0, 300.0), 0.2), timeout=30)
    while f is not None and not f.robots[1].fell:
        f = sim.wait_frame(f.seq, timeout=30)
    assert f is not None and f.robots[1].fell_clock is not None
    assert "tilted" in f.robots[1].fall_reason or "pelvis" in f.robots[1].fall_reason
    fell_at = f.robots[1].fell_clock
    while f is not None and f.robots[1].fell:
        f = sim.wait_frame(f.seq, timeout=30)
    assert f is not None
    assert sim.wait_applied(sim.pause(), timeout=60) is not None
    frames = _published(sim, fell_at, np.inf)  # every frame since the fall
    n_down = next(i for i, x in enumerate(frames) if not x.robots[1].fell)
    down, after = frames[:n_down], frames[n_down]
    # the restart comes once the hold is over, from the first frame at or past its end
    held = fell_at + FALL_HOLD_S - 1e-9
    assert down[-1].clock >= held and all(x.clock < held for x in down[:-1])
    late = [d for d in down if d.clock > fell_at + 1.5]  # on the floor by then
    pelvis = np.array([d.robots[1].body_xpos[1] for d in late])
    assert pelvis[:, 2].max() < 0.5  # lying
    assert np.ptp(pelvis[:, :2], axis=0).max() < 0.05  # where it fell, not sliding about
    assert down[-1].robots[0].t > down[0].robots[0].t + 2.0  # the fixed pelvis walked on
    assert not down[-1].robots[0].fell
    # both began a new walk after the frame that made the restart
    assert all(r.t <= after.clock - down[-1].clock + 1e-9 for r in after.robots)
    assert all(not r.fell for r in after.robots)
    _in_step_once_walking(sim)


def test_history_has_one_column_set_per_method(running):
    sim = running(params=short_params(3), methods=["fixed", "mpc"], speed=4.0)
    f = sim.frame()
    while f is not None and len(sim.history.window().column("mpc", "clock")) < 20:
        f = sim.wait_frame(f.seq, timeout=30)
    h = sim.history.window()
    assert set(h.rows) == {"fixed", "mpc"}
    for method, arr in h.rows.items():
        assert arr.shape[1] == len(ROW_COLUMNS)
        assert np.all(np.isfinite(h.column(method, "waist_deg")))
        assert np.all(np.diff(h.column(method, "clock")) > 0)


def test_history_and_kept_frames_are_bounded():
    """Run 20 s of simulated time keeping 3 s: memory stops growing.

    The loop is stepped here, on a FakeWallClock, with a frame every tick, and the memory kept
    is read every 0.25 s of simulated time: a thread running it would publish faster than a
    busy test thread reads, and which frames it read (and so where memory was sampled) would
    depend on the machine."""
    wall = FakeWallClock()
    sim = SessionView(initial_intent(short_params(20), ["fixed", "mpc"]), keep_s=3.0)
    loop = LiveLoop(sim._box.get, sim.receive, wall.clock, wall.sleep, publish_hz=1e9)
    sim.history = type(sim.history)(seconds=8.0)
    sizes = []  # (clock, bytes kept)
    while loop.clock < 20.0:
        loop.iterate()
        f = sim.frame()
        if f is not None and (not sizes or f.clock >= sizes[-1][0] + 0.25):
            sizes.append((f.clock, sim.frames.nbytes()))
    assert sim.error is None
    lo, hi = sim.frames.span()
    assert hi - lo <= 3.0 + 1e-6
    full = max(b for c, b in sizes if 3.0 < c <= 6.0)  # one window, full
    assert max(b for c, b in sizes if c > 6.0) < 1.5 * full  # no growth after
    rows = sim.history.window().rows
    assert all(len(a) <= sim.history.capacity for a in rows.values())
    assert max(len(a) for a in rows.values()) == sim.history.capacity


def test_step_to_the_next_liftoff_and_landing(running):
    sim = running(params=short_params(3), methods=["mpc"])
    f = sim.wait_applied(sim.pause(), timeout=60)
    f = sim.wait_applied(sim.step("liftoff"), timeout=30)
    r = f.robots[0]
    plan = sim.robots["mpc"].session.plan
    assert not r.in_dsp and r.step_index >= 0
    assert min(abs(r.t - t) for t in plan.liftoff_times()) <= 2 * DT + 1e-9  # its tick
    f = sim.wait_applied(sim.step("landing"), timeout=30)
    r = f.robots[0]
    assert r.in_dsp and min(abs(r.t - t) for t in plan.landing_times()) <= 2 * DT + 1e-9


def test_robots_built_late_stand_by_and_start_in_phase():
    """A loop that builds its robots after the session's start (a slow part of a session
    split over processes) starts them in phase with the session's rhythm."""
    wall = FakeWallClock()
    wall.now = 100.0
    params = short_params(6)
    intent = dataclasses.replace(
        initial_intent(params, ["fixed", "mpc"]), anchor=(100.0 - 1.7, 0.0), start_clock=0.0
    )
    frames: list = []
    loop = LiveLoop(lambda: intent, frames.append, clock=wall.clock, sleep=wall.sleep)
    loop.iterate()
    assert all(r.waiting for r in frames[-1].robots)  # 1.7 s late: standing by
    while frames[-1].robots[0].t < 0.1:
        loop.iterate()
    f = frames[-1]
    cycle = 2 * params.walk.step_time
    for r in f.robots:
        # in phase with robots that started at start_clock: the same point of the cycle
        offset = (f.clock - intent.start_clock - r.t) % cycle
        assert min(offset, cycle - offset) < 0.011, (f.clock, r.t)
    assert f.robots[0].t == pytest.approx(f.robots[1].t, abs=1e-9)


def test_the_time_base_moves_only_for_a_loop_that_ran_late():
    from pelvic_walk.core.frames import LiveFrame

    now = [100.0]
    sim = SessionView(initial_intent(short_params(3), ["mpc"]), wall=lambda: now[0])
    sim._box.modify(lambda cur: {"anchor": (100.0, 0.0)})
    intent = sim.intent

    def frame(clock: float, wall: float) -> LiveFrame:
        return LiveFrame(
            seq=1, clock=clock, wall=wall, paused=False, speed=1.0, realtime_factor=None,
            compute_realtime_factor=None, intent_version=intent.version, steps_done=0,
            pushes_done=0, robots=(),
        )  # fmt: skip

    # made on time at wall 102 (clock 2.0) but delivered 1 s late: the base stays
    now[0] = 103.0
    sim._catch_up(frame(2.0, 102.0))
    assert sim.intent.anchor == (100.0, 0.0)
    # made less than CATCH_UP_S behind: the loop catches up by itself, the base stays
    now[0] = 104.5
    sim._catch_up(frame(2.0 - 0.8 * CATCH_UP_S, 102.0))
    assert sim.intent.anchor == (100.0, 0.0)
    # made more than CATCH_UP_S behind its base: the base moves to where that loop was, then
    behind = 2.0 - CATCH_UP_S - 0.2
    sim._catch_up(frame(behind, 102.0))
    assert sim.intent.anchor == (102.0, behind)
