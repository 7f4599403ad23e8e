"""The HTTP API with FastAPI's TestClient around a real live simulation (short plans)."""

from __future__ import annotations

import time

import pytest
from fastapi.testclient import TestClient

from app.runs import SUMMARY_KEYS
from app.web.api import create_app
from app.web.live import LiveSim
from controller.params import ControllerParams

DT = ControllerParams().control_dt


@pytest.fixture(scope="module")
def live():
    sim = LiveSim(ControllerParams().replace(walk={"n_steps": 4}), methods=["fixed", "mpc"])
    sim.start()
    assert sim.wait_frame(timeout=30) is not None
    yield sim
    sim.stop()
    assert sim.error is None


@pytest.fixture(scope="module")
def client(live):
    app = create_app(live, viser_port=18765)
    with TestClient(app) as c:
        yield c
    app.state.runs.shutdown()


@pytest.fixture(autouse=True)
def running(client):
    """Every test starts with the simulation running."""
    assert client.post("/api/sim/resume").status_code == 200
    yield


def _state(client) -> dict:
    r = client.get("/api/state")
    assert r.status_code == 200
    return r.json()


def _wait_newer(live: LiveSim, n: int = 3) -> None:
    f = live.frame()
    for _ in range(n):
        f = live.wait_frame(f.seq, timeout=10)
        assert f is not None


def _assert_still_running(client, live) -> None:
    t0 = _state(client)["clock"]
    _wait_newer(live, 5)
    assert _state(client)["clock"] > t0
    assert live.running and live.error is None


def test_health(client):
    r = client.get("/api/health")
    assert r.status_code == 200
    body = r.json()
    assert body["status"] == "ok" and body["live_running"] is True
    assert body["viser_port"] == 18765


def test_get_params_has_every_group_and_the_methods(client):
    body = client.get("/api/params").json()
    assert set(body) >= {"walk", "com", "pelvis", "ik", "arms", "methods", "control_dt"}
    assert body["walk"]["step_length"] == pytest.approx(0.2)
    assert body["methods"] == ["fixed", "mpc"]
    spec = client.get("/api/params/spec").json()
    assert spec["walk"]["step_length"]["max"] == 0.6


def test_put_params_partial_reaches_the_walkers(client, live):
    r = client.put("/api/params", json={"walk": {"step_length": 0.25}, "com": {"alpha": 2.0}})
    assert r.status_code == 200, r.text
    assert r.json()["walk"]["step_length"] == 0.25
    assert r.json()["walk"]["step_time"] == pytest.approx(1.2)  # untouched
    got = client.get("/api/params").json()
    assert got["walk"]["step_length"] == 0.25 and got["com"]["alpha"] == 2.0
    _wait_newer(live)  # one tick later every walker has taken them
    for method, robot in live.robots.items():
        params = robot.session.walker.params
        assert params.walk.step_length == 0.25 and params.com.alpha == 2.0
        assert params.method == method
    for robot in _state(client)["robots"]:
        assert robot["params"]["step_length"] == 0.25
    client.put("/api/params", json={"walk": {"step_length": 0.2}, "com": {"alpha": 1.0}})


def test_put_methods_changes_the_robots(client, live):
    r = client.put("/api/params", json={"methods": ["mpc", "redundancy", "fixed"]})
    assert r.status_code == 200, r.text
    assert [b["method"] for b in _state(client)["robots"]] == ["fixed", "redundancy", "mpc"]
    r = client.put("/api/params", json={"methods": ["fixed", "mpc"]})
    assert [b["method"] for b in _state(client)["robots"]] == ["fixed", "mpc"]


BAD_BODIES = {
    "NaN as a string": {"walk": {"step_length": "NaN"}},
    "a number as a string": {"walk": {"step_length": "0.3"}},
    "out of range": {"walk": {"step_length": 0.9}},
    "below range": {"com": {"horizon": 0.0}},
    "wrong type": {"arms": {"enabled": "yes"}},
    "a list for a number": {"pelvis": {"k_pel": [0.2]}},
    "unknown field": {"walk": {"stride": 0.3}},
    "unknown group": {"legs": {"step_length": 0.3}},
    "unknown method": {"methods": ["fixed", "moonwalk"]},
    "no method": {"methods": []},
    "integer steps as float": {"walk": {"n_steps": 2.5}},
}


@pytest.mark.parametrize("body", BAD_BODIES.values(), ids=BAD_BODIES.keys())
def test_bad_params_get_422_with_a_message(client, live, body):
    before = client.get("/api/params").json()
    r = client.put("/api/params", json=body)
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    assert isinstance(detail, str) and len(detail) > 5
    assert client.get("/api/params").json() == before
    _assert_still_running(client, live)


@pytest.mark.parametrize("literal", ["NaN", "Infinity", "-Infinity", "1e999"])
def test_non_finite_json_numbers_get_422(client, live, literal):
    r = client.put(
        "/api/params",
        content='{"walk": {"step_length": LITERAL}}'.replace("LITERAL", literal),
        headers={"content-type": "application/json"},
    )
    assert r.status_code == 422, r.text
    assert "step_length" in r.json()["detail"]
    _assert_still_running(client, live)


def test_pause_holds_time_and_step_advances_one_period(client, live):
    r = client.post("/api/sim/pause")
    assert r.status_code == 200 and r.json()["paused"] is True
    t = [b["t"] for b in _state(client)["robots"]]
    _wait_newer(live, 4)
    state = _state(client)
    assert state["paused"] is True
    assert [b["t"] for b in state["robots"]] == t
    r = client.post("/api/sim/step")
    assert r.status_code == 200 and r.json()["applied"] is True
    assert [b["t"] for b in _state(client)["robots"]] == pytest.approx(
        [x + DT for x in t], abs=1e-9
    )
    client.post("/api/sim/resume")
    _wait_newer(live, 4)
    assert _state(client)["robots"][0]["t"] > t[0] + DT


def test_reset_returns_time_to_zero(client, live):
    _wait_newer(live, 10)
    client.post("/api/sim/pause")
    r = client.post("/api/sim/reset")
    assert r.status_code == 200
    assert all(b["t"] < 0.05 for b in _state(client)["robots"])


def test_speed(client):
    r = client.put("/api/sim/speed", json={"speed": 2.0})
    assert r.status_code == 200 and r.json()["speed"] == 2.0
    assert client.put("/api/sim/speed", json={"speed": 40}).status_code == 422
    assert client.put("/api/sim/speed", json={"speed": "fast"}).status_code == 422
    client.put("/api/sim/speed", json={"speed": 1.0})


def test_state_reports_every_robot(client):
    state = _state(client)
    assert state["paused"] is False
    assert [b["method"] for b in state["robots"]] == ["fixed", "mpc"]
    for b in state["robots"]:
        assert set(b) >= {"method", "t", "step_index", "step_length", "fell", "success",
                          "waist_angle_deg", "kappa", "yaw_momentum", "zmp_ref",
                          "zmp_measured", "solver_failures", "reach"}


def test_headless_run_returns_the_simulate_summary(client):
    r = client.post("/api/runs", json={"method": "mpc", "walk": {"n_steps": 2}})
    assert r.status_code == 202, r.text
    run_id = r.json()["id"]
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline:
        body = client.get(f"/api/runs/{run_id}").json()
        if body["status"] in ("done", "error"):
            break
        time.sleep(0.5)
    assert body["status"] == "done", body
    summary = body["summary"]
    assert set(SUMMARY_KEYS) <= set(summary)
    assert summary["method"] == "mpc" and summary["steps_planned"] == 2


def test_bad_runs(client):
    assert client.post("/api/runs", json={"method": "hop"}).status_code == 422
    assert client.post("/api/runs", json={"walk": {"n_steps": 0}}).status_code == 422
    assert client.post("/api/runs", json={"seed": "1"}).status_code == 422
    r = client.get("/api/runs/nope")
    assert r.status_code == 404 and "nope" in r.json()["detail"]


def test_serve_refuses_a_busy_port(capsys):
    import socket

    from app.web.server import serve

    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        assert serve("127.0.0.1", port, port + 1 if port < 65535 else port - 1) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"port {port}" in err[0] and "--port" in err[0]
        with socket.socket() as probe:
            probe.bind(("127.0.0.1", 0))
            free = probe.getsockname()[1]
        assert serve("127.0.0.1", free, port) == 2  # the viser port is the busy one
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--viser-port" in err[0]


def test_pages(client):
    r = client.get("/")
    assert r.status_code == 200
    assert 'src="http://testserver:18765/"' in r.text
    assert "/docs" in r.text and "/report" in r.text
    assert client.get("/report").status_code == 200
    assert client.get("/report/../pyproject.toml").status_code == 404
    assert client.get("/docs").status_code == 200
    assert "/api/params" in client.get("/openapi.json").json()["paths"]


def test_run_manager_is_bounded():
    """More than max_pending queued runs are refused (429 at the API), old records pruned."""
    import threading

    from app.web.api import RunBusy, RunManager
    from controller.params import ControllerParams

    params = ControllerParams()
    manager = RunManager(max_pending=2, keep=3)
    release = threading.Event()
    manager._work = lambda *_: release.wait(30)  # hold the worker: the runs stay pending
    manager.submit(params, None)
    manager.submit(params, None)
    with pytest.raises(RunBusy):
        manager.submit(params, None)
    release.set()
    manager.shutdown()

    manager = RunManager(max_pending=2, keep=3)
    manager._work = lambda *_: None
    for i in range(5):  # finished records beyond `keep` are pruned on the next submit
        manager._runs[f"done{i}"] = {"id": f"done{i}", "status": "done"}
    manager.submit(params, None)
    assert len(manager._runs) == 3
    manager.shutdown()
