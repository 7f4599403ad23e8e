"""A clean server log: browsers that close leave no traceback.

Closing a browser while the display draws its view made viser refuse the write ("Cannot
assign to 'position' on a removed FrameHandle"), logged as "display update failed" with a
traceback, once per closed browser and frame in flight.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
import time

import httpx
import pytest
import websockets
from viser import __version__ as viser_version

from app.bench.local_server import local_server
from app.web.view import Display

HTTP_S = 60.0
WAIT_S = 90.0
REMOVED = "Cannot assign to 'position' on a removed FrameHandle."


# -- the display's own rule ------------------------------------------------------------------
class _Server:
    def __init__(self, clients):
        self.clients = clients

    def get_clients(self):
        return dict.fromkeys(self.clients)


class _View:
    def __init__(self, error: Exception | None = None):
        self.error, self.draws = error, 0

    def draw(self, now: float) -> None:
        self.draws += 1
        if self.error is not None:
            raise self.error


def _display(server: _Server, views: dict) -> Display:
    d = Display.__new__(Display)  # (no viser server, no thread: only the drawing rule)
    d.server, d._lock, d.views = server, threading.Lock(), dict(views)
    return d


def test_a_browser_that_left_while_drawn_is_dropped_without_a_traceback(caplog):
    gone = _View(RuntimeError(REMOVED))
    here = _View()
    d = _display(_Server([2]), {1: gone, 2: here})
    with caplog.at_level(logging.DEBUG, logger="app.web.view"):
        d._draw_all(list(d.views.items()), 0.0)
    assert here.draws == 1 and 1 not in d.views and 2 in d.views
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING]
    assert not any(r.exc_info for r in caplog.records)


def test_a_drawing_fault_of_a_connected_browser_is_still_logged(caplog, monkeypatch):
    monkeypatch.setattr("app.web.view.time.sleep", lambda _s: None)
    broken = _View(ValueError("a real bug"))
    d = _display(_Server([1]), {1: broken, None: _View(ValueError("the server's view"))})
    with caplog.at_level(logging.ERROR, logger="app.web.view"):
        d._draw_all(list(d.views.items()), 0.0)
    failed = [r for r in caplog.records if r.getMessage() == "display update failed"]
    assert len(failed) == 2 and all(r.exc_info for r in failed)
    assert 1 in d.views and None in d.views  # kept: its browser is still there


def test_a_view_built_for_a_browser_that_left_meanwhile_is_not_kept():
    """A browser that closed while its view was built (its disconnect already ran) would keep
    a view drawn to a closed connection for ever; its session is detached again."""

    class _Registry:
        detached: list[str] = []

        def detach(self, owner: str) -> None:
            self.detached.append(owner)

    class _Client:
        client_id = 7

    d = _display(_Server([]), {})
    d.waiting, d.registry = {}, _Registry()
    d._add(_Client(), _View())
    assert d.views == {} and d.registry.detached == ["7"]
    d.server = _Server([7])  # still there: kept
    d._add(_Client(), _View())
    assert list(d.views) == [7]


# -- a served tool, browsers coming and going ------------------------------------------------
class _Scene:
    """A scene connection (a browser's tab) held open in a thread until closed."""

    def __init__(self, url: str):
        self.url = url
        self._stop = threading.Event()
        self._thread = threading.Thread(target=lambda: asyncio.run(self._run()), daemon=True)
        self._thread.start()

    async def _run(self) -> None:
        from test_private_scene import camera_message  # (tests/ is on the path)

        async with websockets.connect(
            self.url,
            subprotocols=[f"viser-v{viser_version}"],  # type: ignore[list-item]
            max_size=None,
            open_timeout=60,
        ) as ws:
            await ws.send(camera_message())
            while not self._stop.is_set():
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(ws.recv(), timeout=0.2)

    def close(self) -> None:  # mid-stream, as a closed tab
        self._stop.set()
        self._thread.join(30)


def _until(check, what: str, state=lambda: "") -> None:
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        if check():
            return
        time.sleep(0.25)
    pytest.fail(f"waited {WAIT_S:.0f} s for {what}; {state()}")


@pytest.mark.slow
def test_closing_browsers_leaves_no_traceback_in_the_log():
    """Private sessions, room for two: three browsers (the third waits in line), then the
    first closes, the one in line gets its place (its view and scene are rebuilt on the same
    page), and all close; twice. The server's output then holds no traceback (before: "display
    update failed ... Cannot assign to 'position' on a removed FrameHandle", from the old view
    of the admitted browser drawn after its scene was reset)."""
    args = ("--sessions", "private", "--workers", "1", "--robots-per-worker", "3")
    with local_server((*args, "--methods", "mpc")) as server:
        url = f"ws://127.0.0.1:{server.viser_port}/"

        def health() -> dict:
            return httpx.get(f"{server.base}/api/health", timeout=HTTP_S).json()

        def private() -> int:
            r = httpx.get(f"{server.base}/api/sessions", timeout=HTTP_S)
            return r.json()["private_sessions"]

        for _round in range(2):
            tabs = [_Scene(url), _Scene(url)]
            _until(lambda: private() == 2, "two browsers' sessions")
            tabs.append(_Scene(url))
            _until(lambda: health()["viewers_waiting"] == 1, "the third browser in line")
            time.sleep(1.0)  # its view of the shared demo is drawn a while
            tabs.pop(0).close()
            _until(lambda: health()["viewers_waiting"] == 0, "the one in line to get a place")
            time.sleep(2.0)  # its new view is drawn a while
            for tab in tabs:
                tab.close()
            _until(
                lambda: health()["views"] == 0 and private() == 0,
                "every view to go",
                lambda: f"health {health()}, {private()} private; {server.output(30)}",
            )
        time.sleep(1.0)  # a frame in flight when the last browser closed
        out = server.output(400)
    assert "Traceback" not in out and "display update failed" not in out, out
    assert "removed FrameHandle" not in out and "on a closed connection" not in out, out
