"""The HTTP API with FastAPI's TestClient around a real live simulation (short plans)."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from app.live.session import SessionView
from app.web.addresses import ClientAddresses
from app.web.api import create_app
from controller.params import ControllerParams
from pelvic_walk.core.run import SUMMARY_KEYS

DT = ControllerParams().control_dt


APP_OPTIONS = {"viser_port": 18765}  # the page names it (test_pages, test_health)


@pytest.fixture(autouse=True)
def running(client):
    """Every test starts with the simulation running."""
    assert client.post("/api/sim/resume").status_code == 200
    yield


def _state(client) -> dict:
    r = client.get("/api/state")
    assert r.status_code == 200
    return r.json()


def _wait_newer(live: SessionView, n: int = 3) -> None:
    f = live.frame()
    for _ in range(n):
        f = live.wait_frame(f.seq, timeout=60)
        assert f is not None


def _applied(live: SessionView, answer: dict | None = None) -> dict | None:
    """Return once the loop has carried out every request made so far. A playback route's
    answer says whether it had within its wait (``"applied"``); on a machine too busy for
    that it answers ``false``, which is no error: then the test waits here."""
    if answer is None or not answer["applied"]:
        assert live.wait_applied(live.intent, timeout=60) is not None
    return answer


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
    for _ in range(200):  # (a robot standing by to restart in phase takes them at its start)
        if not any(r.waiting for r in live.frame().robots):
            break
        _wait_newer(live, 1)
    _wait_newer(live, 2)
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
    _applied(live)
    assert [b["method"] for b in _state(client)["robots"]] == ["fixed", "redundancy", "mpc"]
    r = client.put("/api/params", json={"methods": ["fixed", "mpc"]})
    _applied(live)
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
    assert r.status_code == 200 and _applied(live, r.json())["paused"] is True
    t = [b["t"] for b in _state(client)["robots"]]
    assert live.wait_frame(live.frame().seq, timeout=0.3) is None  # nothing new while paused
    state = _state(client)
    assert state["paused"] is True
    assert [b["t"] for b in state["robots"]] == t
    r = client.post("/api/sim/step")
    assert r.status_code == 200
    if _applied(live, r.json())["applied"]:  # the answer shows the step it waited for
        assert r.json()["t"] == pytest.approx([x + DT for x in t], abs=1e-9)
    assert [b["t"] for b in _state(client)["robots"]] == pytest.approx(
        [x + DT for x in t], abs=1e-9
    )
    _applied(live, client.post("/api/sim/resume").json())
    _wait_newer(live, 4)
    # the session's clock moves on (a robot's own time may not: its plan may end meanwhile)
    assert _state(client)["clock"] > state["clock"] + DT


def test_reset_returns_time_to_zero(client, live):
    _wait_newer(live, 10)
    _applied(live, client.post("/api/sim/pause").json())
    r = client.post("/api/sim/reset")
    assert r.status_code == 200
    _applied(live, r.json())
    assert all(b["t"] == 0.0 for b in _state(client)["robots"])  # rebuilt, paused: standing


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
        assert set(b) >= {
            "method",
            "t",
            "step_index",
            "step_length",
            "fell",
            "success",
            "waist_angle_deg",
            "kappa",
            "yaw_momentum",
            "zmp_ref",
            "zmp_measured",
            "solver_failures",
            "reach",
        }


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


def test_serve_refuses_workers_that_cannot_hold_the_demo(capsys):
    """Checked before anything starts: one line, exit status 2, no traceback."""
    from app.web.server import serve

    assert serve("127.0.0.1", 1, 2, workers=1, robots_per_worker=1) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot hold the 3 robots" in err[0] and "--workers" in err[0]


def test_worker_layout_fills_the_measured_capacity_a_worker_per_core(monkeypatch):
    """ROBOTS_PER_CORE robots a core; by default one worker a core (a worker's robots share one
    core, the GIL), the capacity shared out over them; given one option, the other follows;
    the demo's robots always fit."""
    from app.web import settings

    monkeypatch.setattr(settings, "ROBOTS_PER_CORE", 4.5)
    monkeypatch.setattr(settings.os, "cpu_count", lambda: 2)
    assert settings.worker_layout(None, None) == (2, 5)  # 9 robots: 2 workers, 5 each at most
    assert settings.worker_layout(1, None) == (1, 9)
    assert settings.worker_layout(0, None) == (0, 9)  # in the web process: the capacity
    assert settings.worker_layout(4, None) == (4, 3)  # 9 robots over 4 workers: 3 each at most
    assert settings.worker_layout(None, 2) == (4, 2)
    assert settings.worker_layout(None, 20) == (1, 20)  # more than the capacity: one worker
    assert settings.worker_layout(5, 3) == (5, 3)  # both given: as given
    monkeypatch.setattr(settings.os, "cpu_count", lambda: None)  # unknown: one core
    assert settings.worker_layout(None, None) == (1, 4)  # the demo's three robots fit
    monkeypatch.setattr(settings.os, "cpu_count", lambda: 32)  # a big machine: capped workers
    assert settings.worker_layout(None, None) == (settings.MAX_DEFAULT_WORKERS, 9)
    monkeypatch.setattr(settings, "ROBOTS_PER_CORE", 1)  # the rule, not the figure
    monkeypatch.setattr(settings.os, "cpu_count", lambda: 2)
    assert settings.worker_layout(None, None) == (2, 2)  # 2 slots would not hold the demo


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
    """More than per_client runs of one client, or max_pending of all, are refused (429 at the
    API); the instructor (client None) is beyond both; old records pruned."""
    import threading

    from app.web.api.headless import RunBusy, RunManager
    from controller.params import ControllerParams

    params = ControllerParams()
    manager = RunManager(max_pending=3, keep=3, per_client=2)
    release = threading.Event()
    manager._work = lambda *_: release.wait(30)  # hold the worker: the runs stay pending
    manager.submit(params, None, "a")
    manager.submit(params, None, "a")
    with pytest.raises(RunBusy, match="you have 2 headless runs"):
        manager.submit(params, None, "a")
    manager.submit(params, None, "b")  # a's share is full, not b's
    with pytest.raises(RunBusy, match="clients have 3 headless runs"):
        manager.submit(params, None, "c")
    manager.submit(params, None, None)  # the instructor
    assert "_client" not in str(manager.get(manager.submit(params, None, None)))
    release.set()
    manager.shutdown()

    manager = RunManager(max_pending=2, keep=3)
    manager._work = lambda *_: None
    for i in range(5):  # finished records beyond `keep` are pruned on the next submit
        manager._runs[f"done{i}"] = {"id": f"done{i}", "status": "done"}
    manager.submit(params, None, "a")
    assert len(manager._runs) == 3
    manager.shutdown()


# -- bodies that are not JSON ---------------------------------------------------------------
BODY_ROUTES = [("PUT", "/api/params"), ("POST", "/api/runs"), ("PUT", "/api/sim/speed")]
NOT_JSON = {
    "text/plain": {"content-type": "text/plain"},
    "form": {"content-type": "application/x-www-form-urlencoded"},
    "multipart": {"content-type": "multipart/form-data; boundary=x"},
    "no content type": {},
}


@pytest.mark.parametrize("headers", NOT_JSON.values(), ids=NOT_JSON.keys())
@pytest.mark.parametrize(("method", "path"), BODY_ROUTES)
def test_a_body_that_is_not_json_gets_415(client, live, method, path, headers):
    before = client.get("/api/params").json()
    r = client.request(method, path, content=b'{"walk": {"step_length": 0.3}}', headers=headers)
    assert r.status_code == 415, r.text
    detail = r.json()["detail"]
    assert isinstance(detail, str) and "\n" not in detail and "application/json" in detail
    assert client.get("/api/params").json() == before
    _assert_still_running(client, live)


MALFORMED = {
    "truncated": b'{"walk": {"step_length": 0.3}',
    "not JSON at all": b"step_length=0.3",
    "not UTF-8": b'{"walk": {"step_length": "\xff"}}',
    "nested too deeply": b"[" * 100_000 + b"]" * 100_000,
}


@pytest.mark.parametrize("body", MALFORMED.values(), ids=MALFORMED.keys())
@pytest.mark.parametrize(("method", "path"), BODY_ROUTES)
def test_malformed_json_gets_422_with_a_message(client, method, path, body):
    r = client.request(method, path, content=body, headers={"content-type": "application/json"})
    assert r.status_code == 422, r.text
    assert r.json()["detail"].startswith("body is not valid JSON: ")
    assert r.json()["errors"][0]["type"] == "json_invalid"


def test_json_media_types_and_bodiless_routes_are_accepted(client):
    for ctype in ("application/json; charset=utf-8", "application/merge-patch+json"):
        r = client.put("/api/params", content=b"{}", headers={"content-type": ctype})
        assert r.status_code == 200, r.text
    r = client.post("/api/sim/resume", content=b"ignored", headers={"content-type": "text/plain"})
    assert r.status_code == 200  # a route without a body ignores one
    r = client.put("/api/params", content=b"", headers={"content-type": "text/plain"})
    assert r.status_code == 422  # no body at all: the usual "Field required"


# -- docs, page and report from installed packages ------------------------------------------
def test_docs_assets_are_served_locally(client):
    page = client.get("/docs")
    assert page.status_code == 200
    assert "cdn." not in page.text and "https://" not in page.text
    for asset in ("swagger-ui-bundle.js", "swagger-ui.css", "favicon.png"):
        assert f"/docs-assets/{asset}" in page.text
        r = client.get(f"/docs-assets/{asset}")
        assert r.status_code == 200 and len(r.content) > 1000
    redoc = client.get("/redoc")
    assert redoc.status_code == 200 and "/docs-assets/redoc.standalone.js" in redoc.text
    assert "https://" not in redoc.text
    assert client.get("/docs-assets/../pyproject.toml").status_code == 404


def _outside_temp(monkeypatch, tmp_path):
    """Folders under ``tmp_path/home`` count as the user's own (not temporary) here."""
    import pelvic_walk.core.report_dir as report_dir

    home = tmp_path / "home"
    monkeypatch.setattr(report_dir, "is_temporary", lambda p: home not in Path(p).parents)
    return home


def test_report_shows_the_reference_unless_the_user_wrote_one(live, tmp_path, monkeypatch):
    from pelvic_walk.core.report_dir import record_report_dir, reference_report_dir

    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "state"))
    home = _outside_temp(monkeypatch, tmp_path)
    with TestClient(create_app(live)) as c:
        reference = c.get("/report").text
        assert "<table>" in reference and "<img" in reference
        assert "Which report:</b> The reference report shipped with pelvic-walk" in reference
        assert "pelvic-walk experiments --out report" in reference  # its run, from results.json
        figure = sorted((reference_report_dir() / "figures").glob("*.png"))[0]
        assert c.get(f"/report/figures/{figure.name}").content == figure.read_bytes()
        # a test's run (a temporary folder) is neither recorded nor shown
        scratch = tmp_path / "scratch"
        (scratch / "figures").mkdir(parents=True)
        (scratch / "report.md").write_text("# A test's quick study\n")
        record_report_dir(scratch)
        assert "A test's quick study" not in c.get("/report").text
        # the user's own run is
        out = home / "mine"
        (out / "figures").mkdir(parents=True)
        (out / "report.md").write_text("# My study\n\n![fig](figures/a.png)\n")
        (out / "figures" / "a.png").write_bytes(b"png")
        (out / "results.json").write_text(
            '{"meta": {"command": "pelvic-walk experiments --out mine --quick", '
            '"study": "quick", "date_utc": "2026-12-03 10:00 UTC"}}'
        )
        record_report_dir(out)
        page = c.get("/report").text
        assert "My study" in page and 'src="/report/figures/a.png"' in page
        assert "Your latest pelvic-walk experiments run" in page and str(out) in page
        assert "quick study" in page and "2026-12-03 10:00 UTC" in page
        assert c.get("/report/figures/a.png").content == b"png"


def test_report_dir_option(live, tmp_path, monkeypatch):
    from app.cli import build_parser
    from app.web.settings import Settings

    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "state"))
    (tmp_path / "report.md").write_text("# Chosen report\n")
    with TestClient(create_app(live, report_dir=tmp_path)) as c:
        page = c.get("/report").text
        assert "Chosen report" in page
        assert "The report chosen with serve --report" in page and "not known" in page
    for flag in ("--report", "--report-dir"):
        args = build_parser().parse_args(["serve", flag, str(tmp_path)])
        assert args.report_dir == tmp_path
    monkeypatch.setenv("PELVIC_WALK_REPORT_DIR", str(tmp_path))
    assert Settings().report_dir == tmp_path
    with TestClient(create_app(live, report_dir=tmp_path / "none")) as c:
        assert "No report yet" in c.get("/report").text


def test_tests_write_nothing_into_the_users_state():
    """The session-wide fixture of tests/conftest.py points XDG_STATE_HOME at a folder of the
    test session, so no test's `experiments` run lands in the user's ~/.local/state."""
    from pelvic_walk.core.report_dir import state_file

    home_state = Path.home() / ".local" / "state"
    assert home_state not in state_file().parents
    assert "pytest-of-" in str(state_file()) or "pytest" in str(state_file())


# -- the instructor's token --------------------------------------------------------------------
TOKEN = "class-token-7Qx"


@pytest.fixture(scope="module")
def taught(live):
    from app.web.auth import Instructor

    app = create_app(live, viser_port=18765, instructor=Instructor(TOKEN))
    with TestClient(app) as c:
        yield c
    app.state.runs.shutdown()


CHANGES = [  # every route that changes a session: (method, path, body)
    ("put", "/api/params", {"walk": {"step_length": 0.25}}),
    ("post", "/api/sim/pause", None),
    ("post", "/api/sim/resume", None),
    ("post", "/api/sim/reset", None),
    ("post", "/api/sim/step", None),
    ("put", "/api/sim/speed", {"speed": 1.0}),
    ("post", "/api/sim/seek", {"t": 1.0}),
    ("post", "/api/sim/push", {"method": "mpc", "force": [0, 20], "duration": 0.05}),
]


@pytest.mark.parametrize(("method", "path", "body"), CHANGES, ids=[c[1] for c in CHANGES])
def test_with_an_instructor_only_the_token_changes_the_shared_session(
    taught, live, monkeypatch, method, path, body
):
    import threading

    send = getattr(taught, method)
    kw = {"json": body} if body is not None else {}
    # every change of the session's intent, by the thread that made it: the session changes
    # it by itself too (a restart when a plan ends, the time base moving after a late loop),
    # on the pool's threads that receive its frames; a request that reached it would change
    # it on the server's
    writers: list[str] = []
    box, modify = live._box, live._box.modify  # noqa: SLF001 - the one place intent changes

    def spy(changes_of):
        writers.append(threading.current_thread().name)
        return modify(changes_of)

    monkeypatch.setattr(box, "modify", spy)
    receivers = {f"worker-{w['index']}-frames" for w in live.pool.workers()}
    r = send(path, **kw)
    assert r.status_code == 401, r.text
    assert "Authorization: Bearer" in r.json()["detail"] and r.headers["www-authenticate"]
    r = send(path, headers={"Authorization": "Bearer not-the-token"}, **kw)
    assert r.status_code == 403 and "wrong instructor token" in r.json()["detail"]
    r = send(path.replace("/api/", "/api/sessions/shared/"), **kw)  # the same session
    assert r.status_code == 401
    assert send(path, headers={"Authorization": f"Basic {TOKEN}"}, **kw).status_code == 401
    assert [w for w in writers if w not in receivers] == []  # nothing was changed
    assert live.shown_clock is None
    r = send(path, headers={"Authorization": f"Bearer {TOKEN}"}, **kw)
    assert r.status_code in (200, 409), r.text  # 409: a seek while running
    assert r.status_code == 409 or any(w not in receivers for w in writers)  # (the spy sees it)
    taught.post("/api/sim/resume", headers={"Authorization": f"Bearer {TOKEN}"})


def test_with_an_instructor_anyone_reads(taught):
    for path in ("/api/state", "/api/params", "/api/horizon", "/api/sessions", "/api/health"):
        assert taught.get(path).status_code == 200, path
    assert taught.get("/api/health").json()["instructor"] is True
    page = taught.get("/").text
    assert "The <b>instructor</b> drives the shared demo" in page and TOKEN not in page
    assert "That instructor token is wrong" in taught.get("/?token=guess").text


def test_the_instructors_token_is_exchanged_once_for_an_httponly_cookie(live):
    """/?token=T answers 303 to / with the instructor cookie (HttpOnly, SameSite=Strict): the
    token is in no frame's address, no page, no redirect; the cookie then makes the page the
    instructor's and changes the shared session through the API; a made-up cookie, the token
    as the cookie or a wrong token do not."""
    from app.web.auth import INSTRUCTOR_COOKIE, Instructor

    app = create_app(live, viser_port=18765, instructor=Instructor(TOKEN))
    with TestClient(app, follow_redirects=False) as browser:
        r = browser.get(f"/?token={TOKEN}&lang=en")
        assert r.status_code == 303 and r.headers["location"] == "/?lang=en"
        set_cookie = r.headers["set-cookie"]
        assert set_cookie.startswith(f"{INSTRUCTOR_COOKIE}=") and "HttpOnly" in set_cookie
        assert "samesite=strict" in set_cookie.lower() and "max-age" not in set_cookie.lower()
        assert TOKEN not in r.text + str(r.headers)
        cookie = browser.cookies.get(INSTRUCTOR_COOKIE)
        assert cookie and cookie != TOKEN
        page = browser.get("/").text
        assert "you drive the shared demo" in page
        src = page.split('<iframe id="scene" src="', 1)[1].split('"', 1)[0]
        assert src == "http://testserver:18765/"  # no token, no websocket address
        assert TOKEN not in page and cookie not in page
        # the cookie is the instructor's credential at the API too
        assert browser.post("/api/sim/pause").status_code == 200
        assert browser.post("/api/sim/resume").status_code == 200
    for forged in ("made-up", TOKEN, ""):
        with TestClient(app, cookies={INSTRUCTOR_COOKIE: forged}) as student:
            assert "The <b>instructor</b> drives the shared demo" in student.get("/").text
            assert student.post("/api/sim/pause").status_code == 401
    with TestClient(app, follow_redirects=False) as guess:
        r = guess.get("/?token=guess")
        assert r.status_code == 303 and r.headers["location"] == "/?token_wrong=1"
        assert INSTRUCTOR_COOKIE not in r.headers.get("set-cookie", "") and "guess" not in str(
            r.headers
        )
        assert "That instructor token is wrong" in guess.get("/?token_wrong=1").text
    app.state.runs.shutdown()


def test_the_token_is_compared_in_constant_time(monkeypatch):
    import hmac

    from app.web import auth

    calls = []
    compare = hmac.compare_digest

    def spy(a, b):
        calls.append((a, b))
        return compare(a, b)

    monkeypatch.setattr(auth.hmac, "compare_digest", spy)
    teacher = auth.Instructor(TOKEN)
    assert teacher.is_token(TOKEN) and not teacher.is_token("x") and not teacher.is_token(None)
    assert len(calls) == 2 and all(isinstance(a, bytes) for a, _b in calls)
    assert TOKEN not in repr(teacher)
    assert not auth.Instructor(None).is_token(TOKEN)
    with pytest.raises(ValueError):
        auth.Instructor("  ")


def test_private_sessions_need_no_token(live):
    """The check guards the shared session only (a student drives their own robots)."""
    from fastapi import HTTPException

    from app.web.api.live import instructor_check
    from app.web.auth import Instructor

    check = instructor_check(Instructor(TOKEN), lambda: None)
    assert check(("p1", live), None) == ("p1", live)
    with pytest.raises(HTTPException) as exc:
        check(("shared", live), None)
    assert exc.value.status_code == 401


def test_a_served_tool_never_logs_the_token(tmp_path):
    """``serve`` with the token from the environment: requests carrying it in the URL and as a
    bearer credential, right and wrong, and the token is in none of the tool's output."""
    import httpx

    from app.bench.local_server import local_server

    env = {**os.environ, "PELVIC_WALK_INSTRUCTOR_TOKEN": TOKEN, "PELVIC_WALK_DISPLAY_NICE": "0"}
    with local_server(("--workers", "0"), env=env) as server:
        base = server.base
        assert httpx.get(f"{base}/?token={TOKEN}", timeout=30).status_code == 303
        assert httpx.get(f"{base}/?token={TOKEN}x", timeout=30).status_code == 303
        auth = {"Authorization": f"Bearer {TOKEN}"}
        assert httpx.post(f"{base}/api/sim/pause", headers=auth, timeout=30).status_code == 200
        bad = {"Authorization": f"Bearer {TOKEN}x"}
        assert httpx.post(f"{base}/api/sim/resume", headers=bad, timeout=30).status_code == 403
        assert httpx.get(f"{base}/api/nope?token={TOKEN}", timeout=30).status_code == 404
        proc = server.proc
    assert proc.poll() is not None
    out = server.output(400)
    assert "pelvic-walk: stopped" in out or "instructor" in out, out
    assert TOKEN not in out, out


def test_redaction_blanks_tokens_in_log_records():
    import logging

    from app.web.auth import RedactTokens, redact

    assert redact(f"GET /?token={TOKEN}&x=1 HTTP/1.1") == "GET /?token=***&x=1 HTTP/1.1"
    assert redact(f"Authorization: Bearer {TOKEN}") == "Authorization: Bearer ***"
    record = logging.LogRecord(
        "uvicorn.access", 20, "", 0, '%s "%s"', ("1.2.3.4", f"/?token={TOKEN}"), None
    )
    RedactTokens().filter(record)
    assert TOKEN not in record.getMessage()


# -- path traversal, with requests that keep their ".." -------------------------------------
@pytest.fixture(scope="module")
def raw_server(live, tmp_path_factory, serve_app):
    """uvicorn on a free localhost port in a thread, serving a report dir with a secret beside."""
    base = tmp_path_factory.mktemp("raw")
    (base / "secret.txt").write_text("SECRET-CONTENT")
    report = base / "report"
    (report / "figures").mkdir(parents=True)
    (report / "report.md").write_text("# r\n")
    (report / "figures" / "a.png").write_bytes(b"PNGDATA")
    with serve_app(create_app(live, report_dir=report)) as url:
        yield int(url.rsplit(":", 1)[1]), report


def _raw_get(port: int, target: str) -> tuple[int, bytes]:
    """GET exactly ``target`` (no client-side normalisation of ``..``)."""
    import socket

    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        s.sendall(
            f"GET {target} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n".encode(
                "latin-1"
            )
        )
        data = b""
        while chunk := s.recv(65536):
            data += chunk
    head, _, body = data.partition(b"\r\n\r\n")
    return int(head.split()[1]), body


TRAVERSALS = [
    "/report/../secret.txt",
    "/report/..%2fsecret.txt",
    "/report/..%2f..%2fpyproject.toml",
    "/report/%2e%2e/secret.txt",
    "/report/figures/../../secret.txt",
    "/report/../../../../../../etc/passwd",
    "/report/%00",
    "/report/" + "a" * 5000,
    "/static/../pyproject.toml",
    "/static/..%2f..%2fpyproject.toml",
    "/static/../app/web/api.py",
    "/static/__init__.py",
]


def test_raw_requests_reach_the_files(raw_server):
    port, _ = raw_server
    assert _raw_get(port, "/report/figures/a.png") == (200, b"PNGDATA")
    status, body = _raw_get(port, "/static/index.html")
    assert status == 200 and b"<html" in body


@pytest.mark.parametrize("target", TRAVERSALS)
def test_path_traversal_gets_404(raw_server, target):
    port, report = raw_server
    assert (report / "../secret.txt").resolve().is_file()  # the guard is what stops it
    status, body = _raw_get(port, target)
    # The guard's own answer (the router's would be "Not Found"): the request reached it.
    assert (status, body) == (404, b'{"detail":"not found"}')


def test_path_traversal_of_the_docs_assets_gets_404(raw_server):
    port, _ = raw_server
    for target in ("/docs-assets/../__init__.py", "/docs-assets/..%2f..%2ffastapi/__init__.py"):
        status, body = _raw_get(port, target)
        assert status == 404 and b"import" not in body


def _horizon(client, live, method: str = "mpc"):
    """GET /api/horizon, waiting through a restart (a robot that finished its walk or fell
    restarts with the others and answers 409 until it has ticked again)."""
    for _ in range(200):
        r = client.get("/api/horizon", params={"method": method})
        if r.status_code != 409:
            break
        _wait_newer(live, 1)
    assert r.status_code == 200, r.text
    return r.json()


def test_horizon_has_one_value_per_sample_and_follows_the_horizon(client, live):
    body = _horizon(client, live)
    keys = (
        "t",
        "com_x",
        "com_y",
        "zmp_x",
        "zmp_y",
        "zmp_ref_x",
        "zmp_ref_y",
        "zmp_min_x",
        "zmp_max_x",
        "zmp_min_y",
        "zmp_max_y",
        "left_foot_x",
        "left_foot_y",
        "right_foot_x",
        "right_foot_y",
        "theta_ref_deg",
        "theta_deg",
    )
    params = live.intent.params.com
    n = round(params.horizon / params.sample_time)
    assert all(len(body[k]) == n for k in keys), {k: len(body[k]) for k in keys}
    t = body["t"]
    assert all(b > a for a, b in zip(t, t[1:], strict=False))
    assert t[-1] == pytest.approx(params.horizon, abs=1e-6)
    assert all(
        lo <= z + 1e-6 and z <= hi + 1e-6
        for lo, z, hi in zip(body["zmp_min_y"], body["zmp_y"], body["zmp_max_y"], strict=True)
    )
    r = client.put("/api/params", json={"com": {"horizon": 1.2}})
    assert r.status_code == 200
    for _ in range(50):  # the next tick the robot shows plans over the new horizon
        _wait_newer(live, 1)
        short = _horizon(client, live)
        if len(short["t"]) != n:
            break
    assert len(short["t"]) == 12 and short["t"][-1] == pytest.approx(1.2, abs=1e-6)
    client.put("/api/params", json={"com": {"horizon": 1.6}})
    assert client.get("/api/horizon", params={"method": "walk"}).status_code == 422
    fixed = _horizon(client, live, "fixed")
    assert fixed["theta_deg"] == [pytest.approx(fixed["theta_deg"][0])] * len(fixed["t"])


def test_seek_shows_a_kept_instant_while_paused(client, live):
    assert client.post("/api/sim/seek", json={"t": 0.5}).status_code == 409  # running
    _wait_newer(live, 10)
    client.post("/api/sim/pause")
    state = client.get("/api/state").json()
    assert state["shown_t"] is None and state["kept"]["frames"] > 1
    start, end = state["kept"]["start"], state["kept"]["end"]
    target = (start + end) / 2
    r = client.post("/api/sim/seek", json={"t": target})
    assert r.status_code == 200, r.text
    sought = client.get("/api/state").json()
    # the kept instant nearest to it (frames lie a display interval apart, or further when a
    # busy machine made the loop catch up: how far is the machine's business)
    shown = live.frames.nearest(target)
    assert sought["shown_t"] == shown.clock and start <= shown.clock <= end
    assert sought["clock"] == pytest.approx(sought["shown_t"])
    horizon = client.get("/api/horizon")
    if shown.robot("mpc").horizon is not None:  # the plan at the instant shown
        assert horizon.json()["clock"] == pytest.approx(sought["shown_t"])
    else:  # (the plans are short: it may fall where the robots stood by to restart)
        assert horizon.status_code == 409 and "not ticked" in horizon.json()["detail"]
    assert client.post("/api/sim/seek", json={"t": "soon"}).status_code == 422
    assert client.post("/api/sim/seek", json={}).status_code == 422
    client.post("/api/sim/resume")
    assert client.get("/api/state").json()["shown_t"] is None


def _qp(client, live, method: str = "mpc"):
    """GET /api/qp, waiting through a restart (409 until the robot has ticked again)."""
    for _ in range(200):
        r = client.get("/api/qp", params={"method": method})
        if r.status_code != 409:
            break
        _wait_newer(live, 1)
    assert r.status_code == 200, r.text
    return r.json()


def test_qp_explains_the_four_layers_of_a_robot(client, live):
    for method in ("mpc", "fixed"):
        body = _qp(client, live, method)
        assert body["method"] == method and "active" in body["meaning"]
        layers = {e["layer"]: e for e in body["layers"]}
        assert list(layers) == ["com_mpc", "pelvis_mpc", "ik", "arm_swing"]
        assert layers["pelvis_mpc"]["ran"] is (method == "mpc")
        for e in body["layers"]:
            if e["ran"] and e["ok"]:
                assert sum(e["terms"].values()) == pytest.approx(e["objective"], abs=1e-12)
        for c in layers["ik"]["active"]:  # both pin the waist: the pin is a row of its own
            pin = c["name"].startswith("waist rate pinned by the strategy")
            assert pin == (c["side"] == "pinned") and c["multiplier"] >= 0
    assert client.get("/api/qp", params={"method": "redundancy"}).status_code == 422


def test_qp_is_in_the_openapi_schema_with_its_response_model(client):
    schema = client.get("/openapi.json").json()
    op = schema["paths"]["/api/qp"]["get"]
    ref = op["responses"]["200"]["content"]["application/json"]["schema"]["$ref"]
    assert ref.endswith("/QpResponse")
    comps = schema["components"]["schemas"]
    assert {"session", "method", "clock", "t", "meaning", "layers"} <= set(
        comps["QpResponse"]["properties"]
    )
    assert {"terms", "active", "fallback", "iterations", "solve_ms"} <= set(
        comps["QpLayer"]["properties"]
    )
    assert {"name", "multiplier", "side", "joint"} <= set(comps["QpConstraint"]["properties"])
    assert "/api/sessions/{sid}/qp" in schema["paths"]


def test_qp_follows_a_seek(client, live):
    _wait_newer(live, 10)
    client.post("/api/sim/pause")
    try:
        state = client.get("/api/state").json()
        start, end = state["kept"]["start"], state["kept"]["end"]
        for target in (start + 0.3 * (end - start), start + 0.8 * (end - start)):
            assert client.post("/api/sim/seek", json={"t": target}).status_code == 200
            shown = live.frames.nearest(target)
            r = client.get("/api/qp")
            robot = shown.robot("mpc")
            if robot is None or robot.qp is None:
                assert r.status_code == 409
                continue
            assert r.status_code == 200, r.text
            body = r.json()
            assert body["clock"] == pytest.approx(shown.clock)
            assert body["t"] == pytest.approx(robot.qp.t)
    finally:
        client.post("/api/sim/resume")


def test_push_is_applied_or_refused_with_a_message(client, live):
    r = client.post("/api/sim/push", json={"method": "mpc", "force": [0, 40], "duration": 0.1})
    assert r.status_code == 200
    _applied(live, r.json())
    assert live.frame().pushes_done >= 1
    for body in (
        {"method": "redundancy", "force": [0, 40]},  # not shown
        {"method": "mpc", "force": [0, 1000]},  # above the maximum
        {"method": "mpc", "force": [0, 40], "duration": 5.0},
        {"method": "mpc", "force": [0, "x"]},
    ):
        r = client.post("/api/sim/push", json=body)
        assert r.status_code == 422, (body, r.text)
        assert r.json()["detail"]
    _assert_still_running(client, live)


def test_sessions_are_listed_and_addressed(client):
    body = client.get("/api/sessions").json()
    assert body["mode"] == "shared" and [s["id"] for s in body["sessions"]] == ["shared"]
    assert client.get("/api/sessions/shared/state").status_code == 200
    assert client.get("/api/state", headers={"X-Pelvic-Session": "shared"}).status_code == 200
    assert client.get("/api/sessions/nope/state").status_code == 404
    assert client.get("/api/state", headers={"X-Pelvic-Session": "nope"}).status_code == 404
    assert client.post("/api/sessions").status_code == 409  # shared mode
    assert client.delete("/api/sessions/shared").status_code == 409


def test_one_client_cannot_fill_everyones_run_queue(live):
    """Four anonymous POST /api/runs from one address filled the shared queue and everyone got
    429. Now: that address's share is full (429 with Retry-After and a line to act on, the
    same line for every refused client), another address and the instructor still get 202;
    a credential the server never gave makes no new client; a forwarded header from an
    untrusted peer is ignored, from the trusted proxy it names the client."""
    import threading

    from app.web.api.headless import RunManager
    from app.web.auth import Instructor

    runs = RunManager(per_client=2, max_pending=8)
    release = threading.Event()
    runs._work = lambda *_: release.wait(60)  # the runs stay queued
    body = {"method": "fixed", "walk": {"step_length": 0.2, "n_steps": 1}}
    app = create_app(live, runs=runs, instructor=Instructor(TOKEN))
    addresses = ClientAddresses("10.9.0.1")  # a proxy that no request below comes through
    app2 = create_app(live, runs=runs, instructor=Instructor(TOKEN), addresses=addresses)
    try:
        student = TestClient(app, client=("192.0.2.10", 5000))
        other = TestClient(app, client=("192.0.2.11", 5000))
        assert [student.post("/api/runs", json=body).status_code for _ in range(2)] == [202] * 2
        refused = [
            student.post("/api/runs", json=body),
            student.post("/api/runs", json=body, headers={"Authorization": "Bearer made-up"}),
            student.post("/api/runs", json=body, headers={"X-Forwarded-For": "198.51.100.7"}),
        ]
        for r in refused:
            assert r.status_code == 429, r.text
            assert r.headers["retry-after"] == "10"
            assert r.json()["detail"].startswith("you have 2 headless runs queued or running")
        assert other.post("/api/runs", json=body).status_code == 202
        teacher = {"Authorization": f"Bearer {TOKEN}"}
        assert [
            student.post("/api/runs", json=body, headers=teacher).status_code for _ in range(3)
        ] == [202] * 3
        # behind the trusted proxy each forwarded client has its own share
        proxy = TestClient(app2, client=("10.9.0.1", 5000))
        for ip in ("198.51.100.1", "198.51.100.2"):
            fwd = {"X-Forwarded-For": f"203.0.113.99, {ip}"}  # the client's own claim, then ours
            codes = [proxy.post("/api/runs", json=body, headers=fwd).status_code for _ in range(3)]
            assert codes == [202, 202, 429], (ip, codes)
    finally:
        release.set()
        runs.shutdown()
