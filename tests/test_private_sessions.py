"""Private sessions as an attacker would try them, through the HTTP API: listing, reading,
acting, deleting and guessing, with and without an instructor, on every route that takes a
session; and the seats: one a client, a second request answered with its own, no script
draining them, a full server saying so in a way a client can act on.

Every route under ``/api/sessions/{sid}`` is read from the app itself, so a route added later
is tried too. Clients are told apart by their address (TestClient's ``client``); a session's
credential is the token ``POST /api/sessions`` gave, or a browser's seat cookie (the display
opens those: here the registry opens one as the display does).
"""

from __future__ import annotations

import contextlib
import re
import secrets
import time

import pytest
from fastapi.testclient import TestClient

from app.live.pool import WorkerPool
from app.live.registry import AddressFull, SessionRegistry, limited
from app.live.session import initial_intent
from app.web.api import create_app
from app.web.auth import SEAT_COOKIE, Instructor
from controller.params import ControllerParams

PARAMS = ControllerParams().replace(walk={"n_steps": 40})
TOKEN = "instructor-7Qx-private"
# a minimal valid body per route (a stranger must be refused whatever the body)
BODIES = {
    "params": {"walk": {"step_length": 0.25}},
    "sim/step": {"until": "tick"},
    "sim/speed": {"speed": 1.0},
    "sim/seek": {"t": 0.0},
    "sim/push": {"method": "mpc", "force": [10.0, 0.0], "duration": 0.05},
}


@pytest.fixture(scope="module")
def pool():
    p = WorkerPool(1, robots_per_worker=4).start()  # the demo's robot and 3 private sessions
    yield p
    p.stop()


@contextlib.contextmanager
def served(pool, instructor: str | None):
    """A private-mode app (shared demo of one robot) around ``pool``; its private sessions
    closed at the end."""
    registry = SessionRegistry.start("private", initial_intent(PARAMS, ["mpc"]), pool)
    app = create_app(registry, instructor=Instructor(instructor))
    try:
        yield app, registry
    finally:
        registry.shutdown()
        app.state.runs.shutdown()
    assert pool.robots() == 0


def client_at(app, address: str) -> TestClient:
    return TestClient(app, client=(address, 40000))


def bearer(token: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {token}"}


def session_routes(app) -> list[tuple[str, str]]:
    """(HTTP method, path) of every route that takes a session id in its path (from the
    OpenAPI schema: every route the app documents)."""
    out = [
        (method.upper(), path)
        for path, ops in app.openapi()["paths"].items()
        if path.startswith("/api/sessions/{sid}")
        for method in ops
    ]
    assert len(out) >= 12, out  # state, params x2, horizon, recording, 7 playback, DELETE
    # DELETE last: it ends the session
    return sorted(out, key=lambda mp: mp[0] == "DELETE")


def call(c: TestClient, method: str, path: str, sid: str, **kw):
    suffix = path.removeprefix("/api/sessions/{sid}").lstrip("/")
    body = BODIES.get(suffix)
    url = path.replace("{sid}", sid)
    if suffix == "recording":
        url += "?seconds=0.2&format=csv"
    return c.request(method, url, json=body, **kw)


def refused(r, sid: str) -> None:
    """The one answer a stranger gets, whether the session exists or not: 404, a message that
    says who may use a private session, and nothing of the session's state."""
    assert r.status_code == 404, (r.status_code, r.text)
    detail = r.json()["detail"]
    assert f"no session {sid!r} that you may use" in detail and "holder" in detail
    assert set(r.json()) == {"detail"}


@pytest.mark.parametrize("instructor", [None, TOKEN], ids=["no instructor", "instructor"])
def test_a_stranger_can_neither_see_nor_use_a_private_session(pool, instructor):
    with served(pool, instructor) as (app, registry):
        owner, stranger = client_at(app, "10.1.0.1"), client_at(app, "10.1.0.2")
        opened = owner.post("/api/sessions")
        assert opened.status_code == 201, opened.text
        sid, token = opened.json()["id"], opened.json()["token"]
        assert token and token not in sid and len(token) >= 40
        theirs = stranger.post("/api/sessions").json()  # the stranger's own session and token
        # listing: the stranger learns how many there are, never an id or a state
        listed = stranger.get("/api/sessions").json()
        assert [s["kind"] for s in listed["sessions"]] == ["shared"]
        assert listed["private_sessions"] == 2
        assert sid not in str(listed) and sid not in stranger.get("/api/health").text
        for w in stranger.get("/api/health").json()["workers"]:
            assert all(r.startswith(("shared/", "private/")) for r in w["robots"]), w
        mine = stranger.get("/api/sessions", headers=bearer(theirs["token"])).json()
        assert [s["id"] for s in mine["sessions"] if s["kind"] == "private"] == [theirs["id"]]
        assert stranger.get("/api/sessions/mine").json()["id"] is None
        # every route, as a stranger: no credential, a wrong one, another session's token,
        # the same under the header form of the routes; a guessed id reads the same
        guessed = f"p-{secrets.token_urlsafe(9)}"
        for method, path in session_routes(app):
            for kw in ({}, {"headers": bearer("not-a-token-" + "x" * 30)}):
                refused(call(stranger, method, path, sid, **kw), sid)
                refused(call(stranger, method, path, guessed, **kw), guessed)
            refused(call(stranger, method, path, sid, headers=bearer(theirs["token"])), sid)
            if method != "DELETE":
                header_path = path.replace("/api/sessions/{sid}", "/api")
                r = call(stranger, method, header_path, "", headers={"X-Pelvic-Session": sid})
                refused(r, sid)
        assert registry.may_use(sid, [token]) and registry.get(sid) is not None  # untouched
        # the owner and the instructor may use every route (some answer 409/422: paused
        # first, nothing kept yet; never "not yours")
        users = [bearer(token)] + ([bearer(TOKEN)] if instructor else [])
        for headers in users:
            for method, path in session_routes(app):
                if method == "DELETE":
                    continue
                r = call(owner, method, path, sid, headers=headers)
                assert r.status_code not in (401, 403, 404), (method, path, r.text)
            r = owner.get("/api/sessions/mine/state", headers=bearer(token))
            assert r.status_code == 200 and r.json()["session"] == sid
        if instructor:
            everyone = stranger.get("/api/sessions", headers=bearer(TOKEN)).json()["sessions"]
            rows = {s["id"]: s for s in everyone}
            assert {sid, theirs["id"]} <= set(rows) and rows[sid]["address"] == "10.1.0.1"
            health = stranger.get("/api/health", headers=bearer(TOKEN)).json()
            assert any(f"{sid}/mpc" in w["robots"] for w in health["workers"])
            # the instructor ends anyone's session
            assert stranger.delete(f"/api/sessions/{theirs['id']}", headers=bearer(TOKEN)).json()
        assert owner.delete("/api/sessions/mine", headers=bearer(token)).json() == {
            "id": sid,
            "closed": True,
        }
        refused(owner.get(f"/api/sessions/{sid}/state", headers=bearer(token)), sid)


def test_a_browser_s_seat_cookie_is_its_credential(pool):
    """A page's session (opened by the display with the browser's seat cookie) answers that
    cookie, through /api/sessions/mine too, and no other browser's."""
    with served(pool, None) as (app, registry):
        cookie = secrets.token_urlsafe(32)
        sid, _session = registry.open_private(
            credential=cookie, address="10.2.0.1", opened_by="page", viewer="1"
        )
        browser = client_at(app, "10.2.0.1")
        browser.cookies.set(SEAT_COOKIE, cookie)
        mine = browser.get("/api/sessions/mine").json()
        assert mine["id"] == sid and mine["opened_by"] == "page" and mine["viewers"] == 1
        assert browser.get(f"/api/sessions/{sid}/state").status_code == 200
        assert browser.post("/api/sessions/mine/sim/pause").json()["paused"] is True
        # asking for a session again returns the one it holds
        again = browser.post("/api/sessions")
        assert again.status_code == 200 and again.json()["id"] == sid
        assert again.json()["token"] is None
        other = client_at(app, "10.2.0.2")
        other.cookies.set(SEAT_COOKIE, secrets.token_urlsafe(32))
        refused(other.get(f"/api/sessions/{sid}/state"), sid)
        assert other.get("/api/sessions/mine").json()["id"] is None
        short = client_at(app, "10.2.0.3")
        short.cookies.set(SEAT_COOKIE, "x")  # too short to be anyone's credential
        assert short.get("/api/sessions/mine").json()["id"] is None


def test_seats_are_shared_fairly(pool):
    """One session a client: a second request with its credential returns its own; an
    anonymous second request from the same address is refused with 429 and what to do; the
    server's own machine is not limited; with an instructor, the instructor hands out more;
    a full server answers 503 with Retry-After and a message naming what to do."""
    with served(pool, TOKEN) as (app, registry):
        script = client_at(app, "10.3.0.1")
        first = script.post("/api/sessions").json()
        again = script.post("/api/sessions", headers=bearer(first["token"]))
        assert again.status_code == 200 and again.json()["id"] == first["id"]
        drain = script.post("/api/sessions")  # a fuzzer's next anonymous call
        assert drain.status_code == 429, drain.text
        assert "holds 1 private session already" in drain.json()["detail"]
        assert "/api/sessions/mine" in drain.json()["detail"] and drain.headers["retry-after"]
        assert registry.count_private() == 1
        # the instructor decides: a session for that address beyond the limit
        handed = script.post("/api/sessions", headers=bearer(TOKEN))
        assert handed.status_code == 201 and handed.json()["token"]
        # loopback (the server's own machine) is not limited: it fills the workers
        local = client_at(app, "127.0.0.1")
        assert local.post("/api/sessions").status_code == 201
        full = local.post("/api/sessions")
        assert full.status_code == 503, full.text
        assert int(full.headers["retry-after"]) > 0
        detail = full.json()["detail"]
        assert "the workers are full" in detail and "GET /api/state" in detail
        assert "instructor may end one" in detail
        # a place frees: the next request gets it
        assert local.delete(f"/api/sessions/{handed.json()['id']}", headers=bearer(TOKEN))
        assert local.post("/api/sessions").status_code == 201


def test_the_registry_limits_addresses_and_lets_a_page_s_session_linger(pool):
    registry = SessionRegistry(
        "private", None, pool, initial=initial_intent(PARAMS, ["mpc"]), linger_s=0.5
    )
    try:
        assert not limited("127.0.0.1") and not limited("::1") and not limited("::ffff:127.0.0.1")
        assert limited("10.0.0.1") and limited("testclient") and limited(None)
        cookie = secrets.token_urlsafe(32)
        sid, _ = registry.open_private(cookie, "10.4.0.1", "page", viewer="a")
        with pytest.raises(AddressFull, match="10.4.0.1"):
            registry.open_private(None, "10.4.0.1", "scene", viewer="b")
        # the same credential again (a second tab at the same moment): its own session
        assert registry.open_private(cookie, "10.4.0.1", "page", viewer="c")[0] == sid
        registry.detach("a")
        registry.detach("c")
        assert registry.owned([cookie]) == sid  # lingers: a reload gets it back
        end = time.monotonic() + 30.0  # the reaper looks every second (a busy machine: later)
        while registry.owned([cookie]) is not None and time.monotonic() < end:
            time.sleep(0.2)
        assert registry.owned([cookie]) is None  # ended once nothing used it for linger_s
        # a scene's own session (no cookie) ends with its connection
        scene, _ = registry.open_private(None, "127.0.0.1", "scene", viewer="d")
        registry.detach("d")
        assert scene not in [s["id"] for s in registry.list(lambda _sid: True)]
        # ids never repeat a pattern a stranger could count on
        assert re.fullmatch(r"p-[A-Za-z0-9_-]{12}", sid)
    finally:
        registry.shutdown()
