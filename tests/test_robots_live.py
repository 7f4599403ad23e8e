"""Robots with their own settings in a live session: two MPCs with different horizons side by
side, a change aimed at one robot or at all, a strategy's own parameter (a ``Params`` in a
student's file) in the API and on the next tick, the old names, the 422s, ``POST /api/runs``
with a live robot's settings, the Python client, recordings, ``serve --robot``, and the same
through worker processes."""

from __future__ import annotations

import json
import textwrap
import time
from typing import Any

import pytest
from fastapi.testclient import TestClient

from app.cli import main as cli_main
from app.live.engines import InProcessEngine
from app.live.pool import WorkerPool
from app.live.session import initial_intent
from app.web import recording
from app.web.api import RunManager, create_app
from app.web.record_plots import plots_png
from controller import strategy
from controller.params import ControllerParams
from pelvic_walk import Client, InvalidRequest
from pelvic_walk.core import robots

GAIN = '''
from dataclasses import dataclass

from pelvic_walk import PelvisStrategy, param


class Gain(PelvisStrategy):
    """Turns the pelvis toward the reference's first sample with its own gain."""

    name = "{name}"

    @dataclass(frozen=True)
    class Params:
        k: float = param(0.0, min=0.0, max=20.0, unit="1/s", label="gain")

    used_k = None  # the gain its last tick used

    def waist_rate(self, s):
        self.used_k = self.params.k
        return self.params.k * (s.theta_ref[0] - s.theta)
'''

PARAMS = ControllerParams().replace(walk={"n_steps": 6})


@pytest.fixture
def gain_file(tmp_path):
    """A student's strategy file with its own ``Params`` (gain ``k``), loaded; unloaded after."""
    names: list[str] = []

    def write(name: str = "gain") -> str:
        path = tmp_path / f"{name}.py"
        path.write_text(textwrap.dedent(GAIN.format(name=name)))
        names.extend(strategy.load_file(str(path)))
        return str(path)

    yield write
    for n in names:
        strategy.unregister(n)


class _Recorded(RunManager):
    """Runs as the server's, and the parameters each was submitted with."""

    def __init__(self) -> None:
        super().__init__(max_wall_s=60.0)
        self.submitted: list[ControllerParams] = []

    def submit(self, params, seed, client=None):  # type: ignore[override]
        self.submitted.append(params)
        return super().submit(params, seed, client)


def _open(pool, specs: list[str], params: ControllerParams = PARAMS):
    """A session of these robots that has shown every one of them."""
    session = pool.open(initial_intent(params, robots=[robots.parse(s) for s in specs]))
    f = session.wait_frame(timeout=60)
    while f is not None and len(f.robots) < len(specs):  # (a part may send first)
        f = session.wait_frame(f.seq, timeout=60)
    assert f is not None
    return session


def _plan(client, label: str, timeout: float = 20.0) -> dict[str, Any]:
    """The robot's plan over its horizon (GET /api/horizon?method=LABEL), once it has one."""
    deadline = time.monotonic() + timeout
    while True:
        r = client.get("/api/horizon", params={"method": label})
        if r.status_code == 200:
            return r.json()
        assert r.status_code == 409 and time.monotonic() < deadline, r.text
        time.sleep(0.05)


def _samples_become(client, label: str, n: int, timeout: float = 20.0) -> int:
    deadline = time.monotonic() + timeout
    while (got := len(_plan(client, label)["t"])) != n and time.monotonic() < deadline:
        time.sleep(0.05)
    return got


def _wait_run(client, run_id: str) -> dict[str, Any]:
    for _ in range(1200):
        rec = client.get(f"/api/runs/{run_id}").json()
        if rec["status"] in ("done", "error"):
            return rec
        time.sleep(0.1)
    raise AssertionError("the run did not finish")


def _used(session, label: str) -> float | None:
    """The gain robot ``label``'s strategy used at its last tick (the in-process engine), once
    the loop has carried out the intent in force (the PUT waits for it only APPLY_TIMEOUT_S:
    a busy machine may answer first)."""
    assert session.wait_applied(session.intent, timeout=30) is not None
    return session.robots[label].session.walker.strategy.strategy.used_k


@pytest.fixture
def pool():
    pool = WorkerPool(1, robots_per_worker=2, engine=InProcessEngine()).start()
    yield pool
    pool.stop()


def test_two_mpcs_walk_each_with_its_own_horizon_and_a_change_aims_at_one_or_all(pool):
    session = _open(pool, ["mpc", "mpc,com.horizon=0.8@short"])
    runs = _Recorded()
    with TestClient(create_app(session, runs=runs)) as client:
        # each walks with its own horizon: its plan is 16 or 8 samples of 0.1 s long
        assert len(_plan(client, "mpc")["t"]) == 16
        assert len(_plan(client, "short")["t"]) == 8
        assert _plan(client, "short")["strategy"] == "mpc"
        state = client.get("/api/state").json()
        shown = {r["label"]: r for r in state["robots"]}
        assert list(shown) == ["mpc", "short"]
        assert all(r["strategy"] == "mpc" and r["method"] == r["label"] for r in shown.values())
        assert shown["short"]["settings"] == {"com.horizon": 0.8}
        assert shown["mpc"]["settings"] == {}
        got = client.get("/api/params").json()
        assert got["methods"] == ["mpc", "short"] and got["com"]["horizon"] == 1.6
        assert got["robots"][1] == {
            "label": "short",
            "strategy": "mpc",
            "settings": {"com.horizon": 0.8},
            "text": "mpc,com.horizon=0.8@short",
        }
        assert got["mpc"]["alpha"] == got["pelvis"]["alpha"]  # the MPC owns its weights

        # POST /api/runs with the live robot's settings runs the live robot's parameters
        groups = {g: got[g] for g in ("walk", "com", "pelvis", "ik", "arms")}
        r = client.post("/api/runs", json={**groups, "robot": got["robots"][1]["text"]})
        assert r.status_code == 202, r.text
        com = {**got["com"], "horizon": 0.8}
        r = client.post("/api/runs", json={**groups, "com": com, "method": "mpc"})
        assert r.status_code == 202, r.text
        assert runs.submitted == [session.intent.params_of("short")] * 2
        runs.shutdown()

        # a change aimed at one robot: its own setting; the other walks on unchanged
        r = client.put("/api/params", json={"robot": "short", "com": {"horizon": 1.2}})
        assert r.status_code == 200, r.text
        assert r.json()["robots"][1]["settings"] == {"com.horizon": 1.2}
        assert r.json()["com"]["horizon"] == 1.6
        assert _samples_become(client, "short", 12) == 12
        assert len(_plan(client, "mpc")["t"]) == 16
        assert session.intent.params_of("mpc").com.horizon == 1.6
        # without a robot: every robot's, and no robot keeps its own value of it
        r = client.put("/api/params", json={"com": {"horizon": 1.0}})
        assert r.status_code == 200, r.text
        assert [x["settings"] for x in r.json()["robots"]] == [{}, {}]
        assert [x["label"] for x in r.json()["robots"]] == ["mpc", "short"]  # (kept)
        assert _samples_become(client, "short", 10) == 10
        assert _samples_become(client, "mpc", 10) == 10

        # the old names still work: the paper's groups, an owned one under its strategy
        r = client.put("/api/params", json={"pelvis": {"k_pel": 0.3}, "mpc": {"alpha": 2.0}})
        assert r.status_code == 200, r.text
        assert r.json()["pelvis"]["k_pel"] == 0.3 and r.json()["pelvis"]["alpha"] == 2.0
        assert r.json()["mpc"]["alpha"] == 2.0
        r = client.put("/api/params", json={"robot": "short", "mpc": {"beta": 0.01}})
        assert r.status_code == 200, r.text
        assert r.json()["robots"][1]["settings"] == {"pelvis.beta": 0.01}

        # refused with one line, and nothing changed
        before = session.intent
        bad = [
            ({"robot": "nobody", "com": {"horizon": 1.0}}, "no robot 'nobody' is shown"),
            ({"robot": "short", "walk": {"step_length": 9.0}}, "less than or equal to 0.6"),
            ({"robots": ["mpc,com.horizon=99"]}, "com.horizon = 99.0 is above the maximum"),
            ({"robots": ["mpc", "mpc"]}, "two robots would both be called 'mpc'"),
            ({"robots": ["nobody"]}, "unknown method 'nobody'"),
            ({"robots": ["mpc,walk.nope=1"]}, "unknown parameter 'walk.nope'"),
            ({"robots": [{"strategy": "mpc", "label": "a,b"}]}, "without ',' or '@'"),
            ({"gainz": {"k": 1.0}}, "unknown parameter group 'gainz'"),
            ({"fixed": {"k": 1.0}}, "strategy 'fixed' has no parameters of its own"),
            ({"mpc": {"nope": 1.0}}, "unknown parameter"),
            ({"robots": ["mpc@x"], "robot": "short", "com": {"horizon": 1.0}}, "no robot"),
        ]
        for body, words in bad:
            r = client.put("/api/params", json=body)
            assert r.status_code == 422 and words in r.json()["detail"], (body, r.text)
            assert "\n" not in r.json()["detail"]
        assert session.intent.robots == before.robots and session.intent.params == before.params
        r = client.get("/api/horizon", params={"method": "nobody"})
        assert r.status_code == 422 and "no robot 'nobody'" in r.text
        r = client.post("/api/sim/push", json={"robot": "nobody", "force": [10, 0]})
        assert r.status_code == 422 and "no robot 'nobody'" in r.text

        # labels with spaces, sent URL-encoded; robots as forms or objects
        body = {"robots": ["mpc@long one", {"strategy": "mpc", "settings": {"com.horizon": 0.8},
                                            "label": "short one"}]}  # fmt: skip
        r = client.put("/api/params", json=body)
        assert r.status_code == 200, r.text
        assert r.json()["methods"] == ["long one", "short one"]
        assert len(_plan(client, "short one")["t"]) == 8
        assert client.get("/api/qp?robot=short%20one").json()["method"] == "short one"
        r = client.post("/api/sim/push", json={"robot": "short one", "force": [20.0, 0.0]})
        assert r.status_code == 200, r.text
        # the old way: one robot per strategy
        r = client.put("/api/params", json={"methods": ["fixed", "mpc"]})
        assert r.status_code == 200 and r.json()["methods"] == ["fixed", "mpc"]
        assert [x["settings"] for x in r.json()["robots"]] == [{}, {}]
    pool.close(session)
    assert session.error is None


def test_a_strategys_own_parameter_in_the_api_and_on_the_next_tick(pool, gain_file):
    gain_file("gain")
    session = _open(pool, ["gain", "gain,gain.k=6@six"])
    with TestClient(create_app(session)) as client:
        spec = client.get("/api/params/spec").json()
        assert spec["gain"]["k"]["max"] == 20.0 and spec["gain"]["k"]["unit"] == "1/s"
        got = client.get("/api/params").json()
        assert got["gain"] == {"k": 0.0}
        assert got["robots"][1]["settings"] == {"gain.k": 6.0}
        state = client.get("/api/state").json()
        assert [r["settings"] for r in state["robots"]] == [{}, {"gain.k": 6.0}]
        deadline = time.monotonic() + 30
        while _used(session, "six") is None and time.monotonic() < deadline:
            time.sleep(0.05)  # (it stands by until the session's start)
        assert _used(session, "six") == 6.0

        # every robot's gain: acts on the next tick (the answer waits until it is applied)
        r = client.put("/api/params", json={"gain": {"k": 12}})
        assert r.status_code == 200, r.text
        assert r.json()["gain"] == {"k": 12.0} and r.json()["robots"][1]["settings"] == {}
        assert [_used(session, "gain"), _used(session, "six")] == [12.0, 12.0]
        # one robot's
        r = client.put("/api/params", json={"robot": "six", "gain": {"k": 3}})
        assert r.status_code == 200, r.text
        assert [_used(session, "gain"), _used(session, "six")] == [12.0, 3.0]
        assert session.intent.params_of("six").value("gain.k") == 3.0
        r = client.put("/api/params", json={"gain": {"k": 99}})
        assert r.status_code == 422 and r.json()["detail"] == (
            "gain.k = 99.0 is above the maximum 20.0 1/s"
        )

        # the Python client: by label, a strategy's own parameter by its dotted name
        pw = Client("http://testserver", _http=client)
        assert [r["label"] for r in pw.robots()] == ["gain", "six"]
        pw.set_params(robot="gain", **{"gain.k": 5})
        assert pw.robots()[0]["settings"] == {"gain.k": 5.0}
        assert pw.params()["gain"] == {"k": 12.0}
        with pytest.raises(InvalidRequest, match="no robot 'x' is shown"):
            pw.set_params(robot="x", step_length=0.3)
        shown = pw.set_robots(["mpc", "mpc,com.horizon=0.8@short"])
        assert [(r["label"], r["settings"]) for r in shown] == [
            ("mpc", {}),
            ("short", {"com.horizon": 0.8}),
        ]
        pw.set_params(robot="short", **{"pelvis.k_pel": 0.3})  # an old name, one robot
        assert session.intent.params_of("short").pelvis.k_pel == 0.3
        assert session.intent.params_of("mpc").pelvis.k_pel != 0.3
        assert pw.set_params(methods=["mpc"])["methods"] == ["mpc"]
    pool.close(session)
    assert session.error is None


def test_a_recording_names_robots_by_label_with_their_parameters(pool):
    session = _open(pool, ["mpc", "mpc,com.horizon=0.8@short"])
    deadline = time.monotonic() + 30
    while recording.kept_seconds(session) < 1.0 and time.monotonic() < deadline:
        time.sleep(0.1)
    rec = recording.from_session(session, 1.0)
    assert rec.methods == ("mpc", "short") and rec.strategies == {"mpc": "mpc", "short": "mpc"}
    saved = json.loads(recording.robots_json(rec))["robots"]
    assert [r["label"] for r in saved] == ["mpc", "short"]
    assert [r["settings"] for r in saved] == [{"com.horizon": 1.6}, {"com.horizon": 0.8}]
    assert saved[1]["params"]["com.horizon"] == 0.8 and saved[1]["strategy"] == "mpc"
    page = recording.index_html(rec)
    assert "short (pelvic MPC)" in page and "com.horizon = 0.8" in page
    assert {line.split(",")[0] for line in recording.timeseries_csv(rec).splitlines()[1:]} == {
        "mpc",
        "short",
    }
    assert plots_png(rec).startswith(b"\x89PNG")
    pool.close(session)


def _status(argv: list[str]) -> int:
    try:
        return cli_main(argv)
    except SystemExit as exc:  # the parser's error
        return int(exc.code or 0)


def test_serve_refuses_bad_robots_with_one_line(capsys):
    for argv, words in [
        (["--robot", "mpc,com.horizon=9"], "argument --robot: com.horizon = 9.0 is above"),
        (["--robot", "nobody"], "argument --robot: unknown method 'nobody'"),
        (["--robot", "mpc@"], "an empty label after '@'"),
        (["--robot", "mpc", "--robot", "mpc"], "--robot: two robots would both be called 'mpc'"),
        (["--robot", "mpc", "--methods", "fixed"], "--robot and --methods both name"),
        (["--set", "gain.k=1"], "--set: unknown parameter 'gain.k'"),
    ]:
        status = _status(["serve", *argv])
        err = capsys.readouterr().err
        assert status == 2 and words in err and err.count("\n") == 1, (argv, err)


def test_the_parser_reads_robots_in_their_form():
    from app.cli import build_parser

    args = build_parser().parse_args(
        ["serve", "--robot", "mpc", "--robot", "mpc,com.horizon=0.8@short horizon"]
    )
    assert [r.key for r in args.robots] == ["mpc", "short horizon"]
    assert args.robots[1].overrides == (("com.horizon", 0.8),)


def test_robots_with_their_settings_in_worker_processes(gain_file):
    """The process engine: each robot's part gets its own settings; a change aimed at one
    reaches its part only, and survives its worker's restart."""
    import os
    import signal

    gain_file("gain")  # loaded before the workers start: they load the same file
    pool = WorkerPool(1, robots_per_worker=2).start()
    try:
        session = _open(pool, ["mpc,com.horizon=0.8@short", "gain,gain.k=6@six"])

        def both(pred, timeout=60.0):
            f = session.wait_frame(timeout=timeout)
            deadline = time.monotonic() + timeout
            while f is not None and not (len(f.robots) == 2 and pred(f)):
                assert time.monotonic() < deadline, "no such frame"
                f = session.wait_frame(f.seq, timeout=timeout)
            return f

        f = both(lambda f: f.robot("short").horizon is not None)
        assert len(f.robot("short").horizon.t) == 8
        assert f.robot("six").params.value("gain.k") == 6.0 and f.robot("six").strategy == "gain"
        ticket = session.update_params(target="six", gain={"k": 9})
        assert session.wait_applied(ticket, timeout=30) is not None
        f = both(lambda f: f.robot("six").params.value("gain.k") == 9.0)
        assert f.robot("short").params.value("gain.k") == 0.0
        assert f.robot("short").params.com.horizon == 0.8
        (pid,) = session.worker_pids
        os.kill(pid, signal.SIGKILL)
        f = both(
            lambda f: (
                bool(pool.deaths)
                and session.worker_pids != [pid]
                and f.robot("short").horizon is not None
            ),
            timeout=90,
        )
        assert f.robot("six").params.value("gain.k") == 9.0
        assert len(f.robot("short").horizon.t) == 8
        pool.close(session)
    finally:
        pool.stop()


def test_a_headless_run_takes_a_strategys_own_parameters(pool, gain_file):
    """``POST /api/runs`` with a strategy's own parameter, as a group or in a robot's form:
    the same walk either way, and the range checked."""
    gain_file("gain")
    session = _open(pool, ["mpc"])
    with TestClient(create_app(session)) as client:
        r = client.post("/api/runs", json={"method": "gain", "gain": {"k": 12},
                                           "walk": {"n_steps": 1, "step_length": 0.2}})  # fmt: skip
        assert r.status_code == 202, r.text
        rec = _wait_run(client, r.json()["id"])
        assert rec["status"] == "done", rec
        assert rec["summary"]["method"] == "gain"
        r = client.post("/api/runs", json={"robot": "gain,gain.k=12", "walk": {"n_steps": 1,
                                           "step_length": 0.2}})  # fmt: skip
        again = _wait_run(client, r.json()["id"])
        for key in ("steps_completed", "waist_yaw_max_deg", "landing_error_max", "fell"):
            assert again["summary"][key] == rec["summary"][key], key
        r = client.post("/api/runs", json={"method": "gain", "walk": {"n_steps": 1,
                                           "step_length": 0.2}})  # fmt: skip
        still = _wait_run(client, r.json()["id"])["summary"]  # its default gain: 0
        assert still["waist_yaw_max_deg"] < 0.5 < rec["summary"]["waist_yaw_max_deg"]
        r = client.post("/api/runs", json={"method": "gain", "gain": {"k": -1}})
        assert r.status_code == 422 and "below the minimum" in r.text
    pool.close(session)
