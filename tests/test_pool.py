"""Sessions in worker processes: robots split across workers keep step; admission; a worker
that dies is reported, replaced, and its sessions restart; closing frees the slots."""

from __future__ import annotations

import os
import signal
import time

import pytest

from app.live.pool import PoolFull, WorkerPool
from app.live.registry import SessionRegistry
from app.live.session import initial_intent
from app.web.api import create_app
from controller.params import ControllerParams

PARAMS = ControllerParams().replace(walk={"n_steps": 40})


@pytest.fixture(scope="module")
def pool():
    p = WorkerPool(2, robots_per_worker=2).start()
    yield p
    p.stop()


def _walked(session, seconds: float):
    """The session's frame once its clock has advanced ``seconds`` from now."""
    f = session.wait_frame(timeout=60)
    assert f is not None
    start = f.clock
    while f is not None and f.clock < start + seconds:
        f = session.wait_frame(f.seq, timeout=30)
    assert f is not None
    return f


def test_a_session_split_across_workers_keeps_step(pool):
    s = pool.open(initial_intent(PARAMS, ["fixed", "redundancy", "mpc"]), sid="split")
    try:
        placed = {w["index"]: w["robots"] for w in pool.workers()}
        assert sorted(len(r) for r in placed.values()) == [1, 2]  # every core used
        f = _walked(s, 3.0)
        assert [r.method for r in f.robots] == ["fixed", "redundancy", "mpc"]
        assert [r.slot for r in f.robots] == [0, 1, 2]
        # one time base: the robots walk in phase (robot time = part clock - start clock). A
        # part that built its robot after the session's start clock stands by and joins a
        # whole step cycle later: a worker's first robot loads the compiled kernels (about
        # 0.4 s of CPU), which a busy machine can stretch past START_DELAY_S of wall time.
        # The restart while paused below, which leaves every part time to build, starts them
        # at one clock exactly.
        starts = [r.clock - r.t for r in f.robots]
        cycle = 2 * PARAMS.walk.step_time
        apart = [(x - starts[0]) % cycle for x in starts]
        assert all(min(a, cycle - a) < 0.011 for a in apart), starts  # two ticks
        # and the merged frame shows every robot at the slowest part's instant (its newest
        # frame not later than it; how far apart the parts' frames lie depends on how the
        # machine runs the workers: test_parts_merge_at_the_slowest_parts_instant)
        clocks = [r.clock for r in f.robots]
        assert max(clocks) <= f.clock + 1e-9 and f.clock in clocks, (f.clock, clocks)
        assert all(not r.fell for r in f.robots)
        # intent reaches every part; the session's rows merge one set per robot
        ticket = s.update_params(walk={"step_length": 0.25})
        f = s.wait_applied(ticket, timeout=60)
        assert f is not None and all(r.params.walk.step_length == 0.25 for r in f.robots)
        assert set(s.history.window().rows) == {"fixed", "redundancy", "mpc"}
        # pause and a single step reach every part
        f = s.wait_applied(s.pause(), timeout=60)
        before = [r.t for r in f.robots]
        f = s.wait_applied(s.step(), timeout=60)
        assert [round(r.t - b, 6) for r, b in zip(f.robots, before, strict=True)] == [0.005] * 3
        # a restart while paused (the parts may stand at different clocks): on resume every
        # robot starts at the same session clock, none stands by a step cycle
        s.wait_applied(s.reset(), timeout=60)
        f = s.wait_applied(s.resume(), timeout=60)
        while f is not None and any(r.t < 0.5 for r in f.robots):
            f = s.wait_frame(f.seq, timeout=30)
        assert f is not None and not any(r.waiting for r in f.robots)
        starts = [r.clock - r.t for r in f.robots]
        assert max(starts) - min(starts) < 0.011, starts
    finally:
        pool.close(s)
    assert pool.robots() == 0


@pytest.mark.slow
def test_a_fall_restarts_every_part_of_the_session_together(pool):
    """The robots run in different worker processes: the session (where their frames meet)
    restarts them all FALL_HOLD_S after one fell, at one session clock."""
    from app.live import FALL_HOLD_S

    s = pool.open(initial_intent(PARAMS, ["fixed", "mpc"]), sid="fall")
    try:
        assert len(set(s.worker_pids)) == 2
        f = _walked(s, 3.0)
        s.wait_applied(s.push("mpc", (0.0, 300.0), 0.2), timeout=60)
        while f is not None and not f.robots[1].fell:
            f = s.wait_frame(f.seq, timeout=30)
        assert f is not None
        fell_at = f.robots[1].fell_clock
        while f is not None and f.robots[1].fell:
            f = s.wait_frame(f.seq, timeout=30)
        assert f is not None
        # every merged frame since the fall (the session keeps them), not only those this
        # thread woke for: each one that shows the mpc part as it was after its fall (a merged
        # frame shows a part's newest frame up to its instant, so the first ones after the fall
        # may show the last before it) shows it down until the hold's end, and the last one
        # showing it down is at or past that end
        held = fell_at + FALL_HOLD_S - 1e-9
        frames = s.frames.between(fell_at, f.clock)
        assert all(x.robots[1].fell for x in frames if fell_at <= x.robots[1].clock < held)
        assert max(x.clock for x in frames if x.robots[1].fell) >= held
        while f is not None and any(r.t < 0.5 for r in f.robots):
            f = s.wait_frame(f.seq, timeout=30)
        assert f is not None and not any(r.fell or r.waiting for r in f.robots)
        starts = [r.clock - r.t for r in f.robots]
        assert max(starts) - min(starts) < 0.011, starts
        assert starts[0] >= fell_at + FALL_HOLD_S
        assert s.intent.auto_restarts == 1
    finally:
        pool.close(s)


def test_admission_and_closing_free_the_slots(pool):
    a = pool.open(initial_intent(PARAMS, ["fixed", "mpc"]), sid="a")
    b = pool.open(initial_intent(PARAMS, ["fixed", "mpc"]), sid="b")
    try:
        assert pool.robots() == 4 == pool.capacity
        with pytest.raises(PoolFull, match="room"):
            pool.open(initial_intent(PARAMS, ["mpc"]))
        with pytest.raises(PoolFull):
            a.set_methods(["fixed", "redundancy", "mpc"])
        assert a.intent.methods == ("fixed", "mpc")  # refused: nothing changed
        pool.close(b)
        assert pool.robots() == 2
        c = pool.open(initial_intent(PARAMS, ["mpc"]), sid="c")
        assert _walked(c, 1.0).robots[0].method == "mpc"
        pool.close(c)
    finally:
        pool.close(a)
        pool.close(b)


def test_a_dead_worker_is_reported_replaced_and_its_sessions_restart(pool):
    registry = SessionRegistry.start("shared", initial_intent(PARAMS, ["fixed", "mpc"]), pool)
    app = create_app(registry)
    from fastapi.testclient import TestClient

    try:
        with TestClient(app) as client:
            shared = registry.shared
            _walked(shared, 1.0)
            victim = next(w for w in pool.workers() if w["robots"])
            os.kill(victim["pid"], signal.SIGKILL)
            deadline = time.monotonic() + 180  # a new worker imports MuJoCo first: slow if busy
            health = client.get("/api/health").json()
            while time.monotonic() < deadline and not (
                health["worker_deaths"]
                and all(w["alive"] for w in health["workers"])
                and health["status"] == "ok"
            ):
                time.sleep(0.5)
                health = client.get("/api/health").json()
            assert health["worker_deaths"], health
            assert f"pid {victim['pid']}" in health["worker_deaths"][-1]
            assert "1 session restarted" in health["worker_deaths"][-1]
            assert health["status"] == "ok" and victim["pid"] not in [
                w["pid"] for w in health["workers"]
            ]
            # the session walks again on the new worker: its robots restarted together
            f = _walked(shared, 2.0)
            assert all(not r.fell for r in f.robots)
            assert client.get("/api/state").status_code == 200
    finally:
        registry.shutdown()


def test_a_part_is_shown_at_its_newest_frame_not_later_than_the_instant():
    import collections
    from types import SimpleNamespace

    from app.live.pool import _at

    recent = collections.deque(SimpleNamespace(clock=c) for c in (1.0, 1.1, 1.2, 1.3))
    assert _at(recent, 1.25).clock == 1.2
    assert _at(recent, 1.2).clock == 1.2
    assert _at(recent, 5.0).clock == 1.3
    assert _at(recent, 0.5).clock == 1.0  # ran ahead beyond the kept window: its oldest


def test_parts_merge_at_the_slowest_parts_instant():
    """The merge of a session's parts, on frames made by real loops stepped here (the split
    session above runs it on worker processes, where how far apart the parts' frames lie is
    the machine's business): however far one part runs ahead, every merged frame shows the
    slowest part's newest instant and each other robot at its part's newest frame not later,
    within one display interval of it; a part ahead by more than the kept window shows its
    oldest kept frame."""
    import dataclasses
    from types import SimpleNamespace

    from app.live.loop import LiveLoop
    from app.live.pool import ALIGN_S, RemoteSession

    def part_frames(method: str, seconds: float) -> list:
        """A one-robot part's frames at the display rate, its wall clock free-running."""
        intent = dataclasses.replace(initial_intent(PARAMS, [method]), anchor=(0.0, 0.0))
        wall, out = [0.0], []
        loop = LiveLoop(
            lambda: intent,
            out.append,
            clock=lambda: wall[0],
            sleep=lambda dt: wall.__setitem__(0, wall[0] + dt),
        )
        while loop.clock < seconds:
            loop.iterate()
        return out

    lead, other = part_frames("fixed", 8.0), part_frames("mpc", 8.0)
    interval = 1.0 / 30.0  # PUBLISH_HZ at speed 1
    for ahead in (0.0, 0.5, 2.0, ALIGN_S + 1.0):  # [s] the other part runs ahead by
        pool = SimpleNamespace(
            publish_hz=30.0, sync_parts=lambda *_: None, clock=time.monotonic, start_delay=1.0
        )
        s = RemoteSession("m", initial_intent(PARAMS, ["fixed", "mpc"]), pool)
        s.parts = dict.fromkeys(("fixed", "mpc"), SimpleNamespace(send=lambda _m: None))
        merged: list = []
        s.receive = merged.append  # the merged frames, in order
        ahead_frames = iter(other)
        nxt = next(ahead_frames)
        for f in lead:  # the other part's frames up to `ahead` later arrive first
            while nxt is not None and nxt.clock <= f.clock + ahead + 1e-9:
                s.receive_part("mpc", nxt)
                nxt = next(ahead_frames, None)
            s.receive_part("fixed", f)
        both = [m for m in merged if len(m.robots) == 2]  # (before the lead's first frame,
        assert len(both) >= len(lead) - 1  # the robots of the parts heard from are shown)
        for m in both:
            fixed, mpc = m.robots
            assert (fixed.method, mpc.method) == ("fixed", "mpc")
            assert m.clock == fixed.clock  # the lead part is the slowest here
            if ahead <= ALIGN_S - 0.5:
                assert m.clock - interval - 1e-9 <= mpc.clock <= m.clock + 1e-9, (ahead, m.clock)
            elif m.clock + ahead < other[-1].clock - interval:  # (its frames go on)
                assert mpc.clock > m.clock  # beyond its kept window: its oldest kept frame


def test_without_a_shared_demo_every_slot_is_for_private_sessions(pool):
    """``serve --sessions private --no-shared-demo``: no shared session holds slots; the API
    says so in one line where the shared session is asked for."""
    from fastapi.testclient import TestClient

    registry = SessionRegistry.start(
        "private", initial_intent(PARAMS, ["fixed", "mpc"]), pool, shared_demo=False
    )
    app = create_app(registry)
    try:
        assert not registry.has_shared and pool.robots() == 0
        with TestClient(app) as client:
            r = client.get("/api/state")
            assert r.status_code == 404 and "no shared demo" in r.json()["detail"]
            health = client.get("/api/health").json()
            assert health["status"] == "ok" and health["shared_demo"] is False
            assert health["sessions"] == 0
            listed = client.get("/api/sessions").json()
            assert listed["shared_demo"] is False and listed["sessions"] == []
        # two clients (addresses), one session each
        opened = []
        for address in ("10.0.0.1", "10.0.0.2"):
            with TestClient(app, client=(address, 5000)) as client:
                opened.append(client.post("/api/sessions").json())
        assert pool.robots() == 4 == pool.capacity  # every slot a student's
        with TestClient(app, client=("10.0.0.3", 5000)) as client:
            assert client.post("/api/sessions").status_code == 503  # full: said so
            auth = {"Authorization": f"Bearer {opened[0]['token']}"}
            sid = opened[0]["id"]
            assert client.get(f"/api/sessions/{sid}/state", headers=auth).status_code == 200
            r = client.post(f"/api/sessions/{sid}/sim/pause", headers=auth)
            assert r.json()["paused"] is True
    finally:
        registry.shutdown()
    assert pool.robots() == 0


def test_with_an_instructor_only_the_instructor_sees_private_sessions_ids(pool):
    """A private session's id is listed only to its holder and the instructor; a script drives
    its own with the token it was given (tests/test_private_sessions.py tries the rest)."""
    from fastapi.testclient import TestClient

    from app.web.auth import Instructor

    registry = SessionRegistry.start(
        "private", initial_intent(PARAMS, ["mpc"]), pool, shared_demo=False
    )
    app = create_app(registry, instructor=Instructor("T0k3n"))
    try:
        opened = []
        for address in ("10.0.0.1", "10.0.0.2"):
            with TestClient(app, client=(address, 5000)) as client:
                opened.append(client.post("/api/sessions").json())
        mine, other = (o["id"] for o in opened)
        assert len({mine, other}) == 2 and min(len(mine), len(other)) >= 12
        with TestClient(app, client=("10.0.0.9", 5000)) as client:
            stranger = client.get("/api/sessions").json()
            assert stranger["sessions"] == [] and stranger["private_sessions"] == 2
            teacher = client.get("/api/sessions", headers={"Authorization": "Bearer T0k3n"})
            assert sorted(s["id"] for s in teacher.json()["sessions"]) == sorted([mine, other])
            wrong = client.get("/api/sessions", headers={"Authorization": "Bearer nope"})
            assert wrong.json()["sessions"] == []
            auth = {"Authorization": f"Bearer {opened[0]['token']}"}
            own = client.get("/api/sessions", headers=auth).json()["sessions"]
            assert [s["id"] for s in own] == [mine]
            # a script drives its own session with its token
            r = client.post(f"/api/sessions/{mine}/sim/pause", headers=auth)
            assert r.json()["paused"] is True
    finally:
        registry.shutdown()


@pytest.mark.slow
def test_the_end_of_the_plans_restarts_every_part_together(pool):
    """Robots in different processes walk their whole (short) plan, stand, and the session
    restarts them all at one clock: none restarts alone and stands by (a view once stayed
    on "standing by to start in phase" beside a robot at its plan's end)."""
    s = pool.open(initial_intent(PARAMS.replace(walk={"n_steps": 1}), ["fixed", "mpc"]))
    try:
        f = s.wait_frame(timeout=60)
        while f is not None and not all(r.walks_completed >= 1 for r in f.robots):
            f = s.wait_frame(f.seq, timeout=30)
        assert f is not None
        while f is not None and any(r.t < 0.5 or r.finished for r in f.robots):
            assert not any(r.waiting for r in f.robots)
            f = s.wait_frame(f.seq, timeout=30)
        assert f is not None
        starts = [r.clock - r.t for r in f.robots]
        assert max(starts) - min(starts) < 0.011, starts
        assert s.intent.auto_restarts >= 1
    finally:
        pool.close(s)


@pytest.mark.slow
def test_a_pause_keeps_every_frame_kept_while_running(pool):
    """Paused, every part's frame is merged, on each part's receiver thread: the merged frames
    reach the session in the order they were made (a frame handed on after a newer one read as
    the clock going back and cleared the kept frames: the first pause after a run kept 0.18 s
    of a 40 s timeline). Each pause keeps what was kept; every frame handed on is made under
    the merge lock, so none overtakes another."""
    s = pool.open(initial_intent(PARAMS, ["fixed", "redundancy", "mpc"]), sid="pauses")
    order_kept = []
    receive = s.receive

    def spy(frame):
        order_kept.append(s._merge_lock._is_owned())  # noqa: SLF001 - the ordering's guard
        receive(frame)

    s.receive = spy
    try:
        f = _walked(s, 2.0)
        for _ in range(3):
            f = _walked(s, 1.0)
            span_before = s.frames.span()
            f = s.wait_applied(s.pause(), timeout=60)
            while not f.paused:  # every part paused and merged
                f = s.wait_frame(f.seq, timeout=30)
            kept = s.frames.span()
            assert kept is not None and kept[0] == pytest.approx(span_before[0], abs=0.5), (
                span_before,
                kept,
            )
            assert kept[1] - kept[0] > 2.0, kept
            s.wait_applied(s.resume(), timeout=60)
        assert order_kept and all(order_kept)
    finally:
        pool.close(s)
