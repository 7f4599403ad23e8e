"""Headless runs are independent of whatever else runs in the process."""

from __future__ import annotations

import math
import threading
import time

from app.live.engines import InProcessEngine
from app.live.pool import WorkerPool
from app.live.session import initial_intent
from controller.params import ControllerParams
from pelvic_walk.core.run import RunConfig, run, summarize
from pelvic_walk.core.summary import TIMING_KEYS


def _same(a, b, path="summary") -> None:
    """Equal to 1e-9 (numbers), recursively."""
    if isinstance(a, dict):
        assert set(a) == set(b), path
        for k in a:
            if k not in TIMING_KEYS:
                _same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _same(x, y, f"{path}[{i}]")
    elif isinstance(a, float) and isinstance(b, float) and math.isfinite(a):
        assert abs(a - b) <= 1e-9 * max(1.0, abs(a)), (path, a, b)
    else:
        assert a == b, (path, a, b)


def test_a_headless_run_beside_a_live_session_gives_the_same_summary():
    params = ControllerParams().replace(method="mpc", walk={"step_length": 0.3, "n_steps": 4})
    cfg = RunConfig(params=params, seed=1, perturbation=0.01)
    alone = summarize(run(cfg))

    # Three live robots ticking in threads of this process at the fastest speed (4x): the
    # pool's in-process engine.
    pool = WorkerPool(1, robots_per_worker=3, engine=InProcessEngine()).start()
    params = ControllerParams().replace(walk={"step_length": 0.3, "n_steps": 6})
    live = pool.open(initial_intent(params, ["fixed", "redundancy", "mpc"], speed=4.0))
    try:
        first = live.wait_frame(timeout=30)
        assert first is not None
        t0 = time.monotonic()
        beside = summarize(run(cfg))
        t1 = time.monotonic()
        # the live robots walked meanwhile: frames made while the run ran (their number is the
        # threads' share of the interpreter, not a speed; two show ticks between them)
        during = [f for f in live.frames.between(first.clock, math.inf) if t0 < f.wall < t1]
        assert len(during) >= 2 and during[-1].clock > during[0].clock
    finally:
        pool.close(live)
        pool.stop()
    assert live.error is None
    _same(alone, beside)


def test_runs_in_threads_at_once_match_a_run_alone():
    params = ControllerParams().replace(
        method="redundancy", walk={"step_length": 0.25, "n_steps": 3}
    )
    cfg = RunConfig(params=params)
    alone = summarize(run(cfg))
    out: list[dict] = [{}, {}]

    def work(i: int) -> None:
        out[i] = summarize(run(cfg))

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    for s in out:
        _same(alone, s)


def test_the_lipm_zmp_reads_this_periods_com_velocity():
    """MuJoCo's step does not compute subtree_linvel (mj_subtreeVel does, on demand): the
    measurement must read it after this period's call, not the period before's value."""
    import mujoco
    import numpy as np

    from pelvic_walk.core.run import Session

    params = ControllerParams().replace(method="mpc", walk={"step_length": 0.3, "n_steps": 2})
    session = Session(RunConfig(params=params))
    world = session.world
    before = None
    for _ in range(300):  # into the first step: the CoM accelerates
        session.tick()
        read = session._com_vel_prev.copy()
        mujoco.mj_subtreeVel(world.model, world.data)
        fresh = world.data.subtree_linvel[world.root_id][:2].copy()
        np.testing.assert_array_equal(read, fresh)
        if before is not None:
            assert not np.array_equal(fresh, before)  # a stale read would have differed
        before = fresh
