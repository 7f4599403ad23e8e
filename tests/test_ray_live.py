"""Live sessions on Ray (``serve --ray``): the pool's workers as Ray actors.

- ``serve --ray`` on a local Ray instance: a private session's robots run in a Ray actor (its
  node in ``/api/health``), its frames advance at real time, a killed actor's robots restart
  and the session's clock goes on, a full cluster refuses with the usual message, and the
  server leaves no process behind;
- a two-node cluster on this machine (``ray.cluster_utils.Cluster``, started and stopped
  here): the actors spread over the nodes, seats come from the cluster's CPUs, and a node lost
  is a session that goes on, its robots restarted together on the node left.

Marked ``ray`` (``pytest -m ray``: this shorter set alone) and ``slow`` (``make check`` leaves
them out); skipped without Ray (the ``cluster`` extra).
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import httpx
import pytest

from app.live.session import initial_intent
from controller.params import ControllerParams

pytestmark = [pytest.mark.ray, pytest.mark.slow]

PARAMS = ControllerParams().replace(walk={"n_steps": 40})


def _ray():
    return pytest.importorskip(
        "ray", reason="Ray is an optional extra: pip install '.[cluster]'", exc_type=ImportError
    )


def _descendants(root: int) -> set[int]:
    """Live (non-zombie) processes below ``root``."""
    parent: dict[int, int] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields_ = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if fields_[0] != "Z":
            parent[int(stat.parent.name)] = int(fields_[1])
    out: set[int] = set()
    frontier = {root}
    while frontier:
        frontier = {p for p, pp in parent.items() if pp in frontier and p not in out}
        out |= frontier
    return out


def _alive(pids: set[int]) -> set[int]:
    out = set()
    for p in pids:
        try:
            state = Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if state != "Z":
            out.add(p)
    return out


def _clock_rate(get_state, seconds: float) -> tuple[float, dict]:
    """(session seconds per wall second over ``seconds``, the last state)."""
    s0, w0 = get_state(), time.monotonic()
    time.sleep(seconds)
    s1, w1 = get_state(), time.monotonic()
    return (s1["clock"] - s0["clock"]) / (w1 - w0), s1


def test_serve_ray_runs_private_sessions_in_actors_and_restarts_a_killed_one():
    _ray()
    from app.bench.local_server import local_server

    args = [
        "--ray",
        "--sessions",
        "private",
        "--no-shared-demo",
        "--workers",
        "1",
        "--robots-per-worker",
        "2",
        "--methods",
        "fixed",
        "mpc",
    ]
    with local_server(args) as server:
        base = server.base
        assert "robot seats" in server.output(), server.output()
        opened = httpx.post(f"{base}/api/sessions", timeout=30)
        assert opened.status_code == 201, opened.text
        sid, token = opened.json()["id"], opened.json()["token"]
        auth = {"Authorization": f"Bearer {token}"}

        def state() -> dict:
            r = httpx.get(f"{base}/api/sessions/{sid}/state", headers=auth, timeout=30)
            assert r.status_code == 200, r.text
            return r.json()

        def health() -> dict:
            return httpx.get(f"{base}/api/health", headers=auth, timeout=30).json()

        # its robots run in a Ray actor, on a node of the cluster
        h = health()
        (worker,) = h["workers"]
        assert sorted(worker["robots"]) == [f"{sid}/fixed", f"{sid}/mpc"]
        assert worker["node"] and worker["pid"]
        (node,) = h["cluster"]["nodes"]
        assert node["node"] == worker["node"] and node["robots"] == 2 and node["alive"]
        assert h["cluster"]["robot_seats"] == 2
        # a full cluster answers as a full server does
        full = httpx.post(f"{base}/api/sessions", timeout=30)
        assert full.status_code == 503 and "the workers are full" in full.json()["detail"]
        # frames at real time (the session clock against the wall clock)
        deadline = time.monotonic() + 60
        while state()["clock"] < 1.0 and time.monotonic() < deadline:
            time.sleep(0.2)
        # the session clock runs on the wall clock's time base (printed: a measurement, not a
        # test of this machine's speed; docs/TEACHING.md has the measured figures)
        rate, before = _clock_rate(state, 3.0)
        print(f"session clock over 3 s of wall time: {rate:.2f} s/s")
        assert rate > 0 and before["clock"] >= 1.0
        # a killed actor: its robots restart together on a new one, the session goes on
        descendants = _descendants(server.proc.pid)
        os.kill(worker["pid"], signal.SIGKILL)
        killed_at = time.monotonic()
        while time.monotonic() < killed_at + 60:
            h = health()
            if h["worker_deaths"] and all(w["alive"] for w in h["workers"]):
                break
            time.sleep(0.3)
        assert h["worker_deaths"] and f"pid {worker['pid']} on node" in h["worker_deaths"][-1]
        assert "1 session restarted" in h["worker_deaths"][-1]
        assert h["workers"][0]["pid"] != worker["pid"]

        def restarted(s: dict) -> bool:  # walked 0.5 s since a start after the kill
            starts = [s["clock"] - r["t"] for r in s["robots"]]
            return min(starts) > before["clock"] and all(r["t"] > 0.5 for r in s["robots"])

        s = state()
        while time.monotonic() < killed_at + 60 and not restarted(s):
            time.sleep(0.2)
            s = state()
        print(f"actor killed -> robots walking again in {time.monotonic() - killed_at:.1f} s")
        assert restarted(s), (before["clock"], s["clock"], s["robots"])
        assert s["clock"] > before["clock"]  # the session's clock went on
        # restarted together (the state shows each robot at its newest frame up to the
        # shown instant: their own clocks lie less than a display interval apart)
        starts = [s["clock"] - r["t"] for r in s["robots"]]
        assert max(starts) - min(starts) < 0.06, starts
        rate, _ = _clock_rate(state, 2.0)
        print(f"after the restart: {rate:.2f} s/s")
        assert rate > 0  # and goes on
        descendants |= _descendants(server.proc.pid)
    # stopped: Ray's processes end with the server
    deadline = time.monotonic() + 60
    while _alive(descendants) and time.monotonic() < deadline:
        time.sleep(0.5)
    assert not _alive(descendants), "serve --ray left processes behind"


def test_a_node_lost_is_a_session_that_goes_on():
    """Two nodes on this machine: a session's robots on both; the node of one removed, its
    robot restarts with the other (together) on the node left, and the session goes on."""
    ray = _ray()
    from ray.cluster_utils import Cluster

    from app.live.pool import WorkerPool
    from app.live.ray_engine import RayEngine

    assert not ray.is_initialized()
    cluster = Cluster(
        initialize_head=True,
        head_node_args={"num_cpus": 1, "include_dashboard": False},
    )
    pool = None
    try:
        second = cluster.add_node(num_cpus=1)
        ray.init(address=cluster.address, include_dashboard=False, logging_level="ERROR")
        cluster.wait_for_nodes()
        engine = RayEngine(robots_per_worker=1, robot_cpu=0.25)
        assert engine.workers_for() == 8  # 2 CPUs, a worker of one robot takes 0.25
        pool = WorkerPool(2, 1, engine=engine).start()
        s = pool.open(initial_intent(PARAMS, ["fixed", "mpc"]), sid="class")
        f = s.wait_frame(timeout=60)
        assert f is not None
        nodes = {n["node"]: n for n in pool.nodes() or []}
        assert len(nodes) == 2 and all(n["robots"] == 1 for n in nodes.values()), nodes
        while f.clock < 2.0:
            f = s.wait_frame(f.seq, timeout=30)
        # in step across the nodes: one time base (as tests/test_pool.py reads it: a part that
        # built its robot after the start clock joins a whole step cycle later)
        starts = [r.clock - r.t for r in f.robots]
        cycle = 2 * PARAMS.walk.step_time
        apart = [(x - starts[0]) % cycle for x in starts]
        assert all(min(a, cycle - a) < 0.011 for a in apart), starts
        lost = next(w for w in pool.workers() if w["node"] == second.node_id[:8])
        clock_before = f.clock
        cluster.remove_node(second)
        removed_at = time.monotonic()
        while not pool.deaths and time.monotonic() < removed_at + 60:
            time.sleep(0.05)
        assert pool.deaths and f"pid {lost['pid']} on node" in pool.deaths[-1].describe()
        f = s.wait_frame(timeout=30)
        while f is not None and (f.clock < clock_before or any(r.t < 0.5 for r in f.robots)):
            f = s.wait_frame(f.seq, timeout=30)
        walking = time.monotonic() - removed_at
        assert f is not None and f.clock > clock_before
        starts = [r.clock - r.t for r in f.robots]
        assert max(starts) - min(starts) < 0.011, starts  # restarted together
        alive = [n for n in pool.nodes() or [] if n["alive"]]
        assert len(alive) == 1 and alive[0]["robots"] == 2, alive
        print(f"node lost -> robots walking again (0.5 s walked) in {walking:.1f} s")
    finally:
        if pool is not None:
            pool.stop()
        ray.shutdown()
        cluster.shutdown()
