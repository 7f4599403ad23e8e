"""The 3-D scene of a private session, as an attacker would try it: the scene's port (viser)
serves anyone, so what protects a session there is which session a connection is shown.

A served tool in private mode (one worker: the shared demo and two private sessions of one
robot). Connections are made as a browser makes them (the websocket, the camera it reports
first), with or without the seat cookie the page ``/`` gives; what each connection got is read
back through the API with the cookie (``/api/sessions/mine``), as its page reads it.
"""

from __future__ import annotations

import asyncio
import contextlib
import secrets
import threading
from collections.abc import Iterator

import httpx
import msgspec
import pytest
import websockets
from viser import __version__ as viser_version
from viser import _messages

from app.bench.local_server import local_server
from app.web.auth import SEAT_COOKIE

WAIT_S = 90.0  # [s] generous: a busy 2-core machine
HTTP_S = 60.0  # [s] one answer of the server, on a busy 2-core machine


@pytest.fixture(scope="module")
def tool():
    args = ("--sessions", "private", "--workers", "1", "--robots-per-worker", "3")
    with local_server((*args, "--methods", "mpc")) as server:
        yield server


def camera_message() -> bytes:
    """What a browser sends first: its camera (viser builds the view once it has it)."""
    msg = _messages.ViewerCameraMessage(
        wxyz=(1.0, 0.0, 0.0, 0.0),
        position=(3.0, -3.0, 2.0),
        fov=0.87,
        near=0.01,
        far=1000.0,
        image_height=720,
        image_width=1280,
        look_at=(0.0, 0.0, 1.0),
        up_direction=(0.0, 0.0, 1.0),
    )
    return msgspec.msgpack.encode(msg.as_serializable_dict())


class Scene:
    """One connection to the scene's port, held open in a thread of its own."""

    def __init__(self, url: str, cookie: str | None):
        self.url, self.cookie = url, cookie
        self.bytes = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=lambda: asyncio.run(self._run()), daemon=True)
        self._thread.start()

    async def _run(self) -> None:
        headers = {"Cookie": f"{SEAT_COOKIE}={self.cookie}"} if self.cookie else None
        async with websockets.connect(
            self.url,
            subprotocols=[f"viser-v{viser_version}"],  # type: ignore[list-item]
            additional_headers=headers,
            max_size=None,
            open_timeout=60,
        ) as ws:
            await ws.send(camera_message())
            while not self._stop.is_set():
                with contextlib.suppress(TimeoutError):
                    self.bytes += len(await asyncio.wait_for(ws.recv(), timeout=0.3))

    def close(self) -> None:
        self._stop.set()
        self._thread.join(30)


@contextlib.contextmanager
def scenes() -> Iterator:
    opened: list[Scene] = []

    def connect(url: str, cookie: str | None = None) -> Scene:
        opened.append(Scene(url, cookie))
        return opened[-1]

    try:
        yield connect
    finally:
        for s in opened:
            s.close()


def wait_until(check, what: str, timeout: float = WAIT_S):
    import time

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = check()
        if value:
            return value
        time.sleep(0.25)
    pytest.fail(f"waited {timeout:.0f} s for {what}")


def get(url: str) -> httpx.Response:
    """GET with the suite's patience: on a loaded machine an answer may take longer than
    httpx's default 5 s (seen: GET /api/health beside two busy loops)."""
    return httpx.get(url, timeout=HTTP_S)


def page_cookie(base: str) -> str:
    """The seat cookie the page gives a new browser (HttpOnly, this site only)."""
    r = httpx.get(f"{base}/", timeout=30)
    header = r.headers["set-cookie"]
    assert "HttpOnly" in header and "SameSite=strict" in header.replace("Strict", "strict")
    return r.cookies[SEAT_COOKIE]


def mine(base: str, cookie: str) -> dict:
    return httpx.get(f"{base}/api/sessions/mine", cookies={SEAT_COOKIE: cookie}, timeout=30).json()


def test_a_scene_connection_is_shown_its_own_session_only(tool):
    base, ws_url = tool.base, f"ws://127.0.0.1:{tool.viser_port}/"
    a = page_cookie(base)
    again = httpx.get(f"{base}/", cookies={SEAT_COOKIE: a}, timeout=30)
    assert SEAT_COOKIE not in again.headers.get("set-cookie", "")  # kept, not replaced
    with scenes() as connect:
        connect(ws_url, a)
        sid = wait_until(lambda: mine(base, a)["id"], "the page's session")
        row = mine(base, a)
        assert row["opened_by"] == "page" and row["viewers"] == 1
        # a stranger's connection without a cookie gets a session of its own, never A's
        stranger = connect(ws_url)
        wait_until(
            lambda: get(f"{base}/api/sessions").json()["private_sessions"] == 2,
            "the stranger's own session",
        )
        assert mine(base, a)["viewers"] == 1
        # a forged cookie is a new browser: the workers are full, so it waits in line (and
        # still is not shown A's session)
        forged = secrets.token_urlsafe(32)
        connect(ws_url, forged)
        wait_until(
            lambda: get(f"{base}/api/health").json()["viewers_waiting"] == 1,
            "the forged cookie's browser to wait in line",
        )
        assert mine(base, a)["viewers"] == 1 and mine(base, forged)["id"] is None
        # A's reload (or a second tab): the same session, one more viewer
        connect(ws_url, a)
        wait_until(lambda: mine(base, a)["viewers"] == 2, "A's second tab on its session")
        assert mine(base, a)["id"] == sid
        # the stranger leaves: its session ends at once and the browser in line gets the place
        stranger.close()
        got = wait_until(lambda: mine(base, forged)["id"], "the browser in line to get a session")
        assert got != sid
        assert get(f"{base}/api/health").json()["viewers_waiting"] == 0
        # nobody learns A's id without A's cookie
        listed = get(f"{base}/api/sessions").text + get(f"{base}/api/health").text
        assert sid not in listed
        r = httpx.post(f"{base}/api/sessions/{sid}/sim/pause", timeout=30)
        assert r.status_code == 404
