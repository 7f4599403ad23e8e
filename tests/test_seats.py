"""One address source for every seat (app/web/addresses.py): the page, the API and the 3-D
scene's websocket connections count a client by the same address, behind a reverse proxy too
(forwarded headers trusted only from the configured proxy).

Before, the API took the address uvicorn gave it (which read X-Forwarded-For from 127.0.0.1)
and the scene the socket's: behind a proxy on this machine every scene connection was the
proxy's loopback address, which is not limited, so scene-only connections each got a private
session.
"""

from __future__ import annotations

import asyncio
import contextlib
import threading

import httpx
import pytest
import websockets
from viser import __version__ as viser_version

from app.bench.local_server import local_server
from app.web.addresses import ClientAddresses, parse_trusted

WAIT_S = 90.0
HTTP_S = 60.0


# -- the resolver ----------------------------------------------------------------------------
def test_forwarded_headers_count_only_from_a_trusted_proxy():
    direct = ClientAddresses()
    assert direct.resolve("192.0.2.1", {"X-Forwarded-For": "198.51.100.9"}) == "192.0.2.1"
    assert direct.resolve("::ffff:192.0.2.1", {}) == "192.0.2.1"  # one spelling of one address
    behind = ClientAddresses("127.0.0.1, 10.0.0.0/8")
    fwd = {"x-forwarded-for": "203.0.113.5"}
    assert behind.resolve("127.0.0.1", fwd) == "203.0.113.5"
    assert behind.resolve("10.1.2.3", fwd) == "203.0.113.5"
    assert behind.resolve("192.0.2.1", fwd) == "192.0.2.1"  # not a proxy of ours: ignored
    # read from the right: what the client wrote itself (the left) is not believed
    assert behind.resolve("127.0.0.1", {"X-Forwarded-For": "1.1.1.1, 203.0.113.5"}) == (
        "203.0.113.5"
    )
    # a chain of our proxies: the nearest address that is not one of them
    assert behind.resolve("127.0.0.1", {"X-Forwarded-For": "203.0.113.5, 10.0.0.2"}) == (
        "203.0.113.5"
    )
    # garbage in the header: the last good hop (the proxy), never the garbage
    assert behind.resolve("127.0.0.1", {"X-Forwarded-For": "not-an-ip"}) == "127.0.0.1"
    assert behind.resolve("127.0.0.1", {}) == "127.0.0.1"
    assert behind.resolve(None, fwd) is None
    with pytest.raises(ValueError, match="not an IP address or network: 'proxy.local'"):
        parse_trusted("127.0.0.1, proxy.local")


def test_a_bad_trusted_proxy_stops_serve_with_one_line(capsys):
    from app.cli import main

    assert main(["serve", "--trusted-proxy", "nonsense", "--port", "1", "--viser-port", "2"]) == 2
    err = capsys.readouterr().err
    assert "--trusted-proxies" in err and "nonsense" in err and "Traceback" not in err


# -- served: the scene and the API behind a proxy at 127.0.0.1 ---------------------------------
@pytest.fixture(scope="module")
def behind_proxy():
    """Private mode, one worker of three robots: the demo's one robot and two private
    sessions of one; 127.0.0.1 (where the proxy runs) is the trusted proxy."""
    args = ("--sessions", "private", "--workers", "1", "--robots-per-worker", "3")
    with local_server((*args, "--methods", "mpc", "--trusted-proxy", "127.0.0.1")) as server:
        yield server


class Scene:
    """A scene connection as a proxy forwards it: from 127.0.0.1, with X-Forwarded-For."""

    def __init__(self, url: str, forwarded_for: str):
        self.url, self.headers = url, {"X-Forwarded-For": forwarded_for}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=lambda: asyncio.run(self._run()), daemon=True)
        self._thread.start()

    async def _run(self) -> None:
        from test_private_scene import camera_message  # (tests/ is on the path)

        async with websockets.connect(
            self.url,
            subprotocols=[f"viser-v{viser_version}"],  # type: ignore[list-item]
            additional_headers=self.headers,
            max_size=None,
            open_timeout=60,
        ) as ws:
            await ws.send(camera_message())
            while not self._stop.is_set():
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(ws.recv(), timeout=0.3)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(30)


def _wait(check, what: str):
    import time

    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        value = check()
        if value:
            return value
        time.sleep(0.25)
    pytest.fail(f"waited {WAIT_S:.0f} s for {what}")


def test_the_scene_and_the_api_count_one_client_by_one_address_behind_a_proxy(behind_proxy):
    base, ws = behind_proxy.base, f"ws://127.0.0.1:{behind_proxy.viser_port}/"

    def health() -> dict:
        return httpx.get(f"{base}/api/health", timeout=HTTP_S).json()

    def private() -> int:
        return httpx.get(f"{base}/api/sessions", timeout=HTTP_S).json()["private_sessions"]

    scenes = [Scene(ws, "198.51.100.5")]
    try:
        _wait(lambda: private() == 1, "the first client's scene to get its session")
        # the same client's second scene-only connection (no cookie): its address holds its
        # one session, so it waits (before: the proxy's 127.0.0.1, unlimited, got another)
        scenes.append(Scene(ws, "198.51.100.5"))
        _wait(lambda: health()["viewers_waiting"] == 1, "the second connection to wait")
        assert private() == 1
        # the API reads the same address: that client may not open one by script either
        fwd = {"X-Forwarded-For": "198.51.100.5"}
        r = httpx.post(f"{base}/api/sessions", headers=fwd, timeout=HTTP_S)
        assert r.status_code == 429, r.text
        assert "holds 1 private session" in r.json()["detail"] and "198.51.100.5" in r.text
        # a client behind the proxy that writes its own X-Forwarded-For is read from the
        # right: the proxy appends the address it saw, which is what counts
        spoof = {"X-Forwarded-For": "203.0.113.1, 198.51.100.5"}
        assert httpx.post(f"{base}/api/sessions", headers=spoof, timeout=HTTP_S).status_code == 429
        # another client behind the same proxy is another address
        other = {"X-Forwarded-For": "198.51.100.6"}
        r = httpx.post(f"{base}/api/sessions", headers=other, timeout=HTTP_S)
        assert r.status_code == 201, r.text
        httpx.delete(
            f"{base}/api/sessions/mine",
            headers={"Authorization": f"Bearer {r.json()['token']}"},
            timeout=HTTP_S,
        )
    finally:
        for s in scenes:
            s.close()
    assert "Traceback" not in behind_proxy.output(400)


def test_a_proxy_nobody_trusted_is_named_once_in_the_log(caplog):
    """Behind a proxy on this machine without --trusted-proxy every student is 127.0.0.1
    (not limited): the server says so once, with the option to give."""
    import logging

    untrusted = ClientAddresses()
    with caplog.at_level(logging.WARNING, logger="app.web.addresses"):
        for _ in range(3):
            assert untrusted.resolve("127.0.0.1", {"X-Forwarded-For": "203.0.113.5"}) == (
                "127.0.0.1"
            )
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and "--trusted-proxy 127.0.0.1" in lines[0]


# -- through a small local reverse proxy -----------------------------------------------------
class _Proxy:
    """A reverse proxy in a thread: a loopback port relaying to ``upstream``, stamping each
    connection's request head with ``X-Forwarded-For: <client>`` (as nginx's
    ``$proxy_add_x_forwarded_for`` does, after what the client wrote); the websocket upgrade
    and everything after it is relayed as bytes. ``client`` plays the browser's address."""

    def __init__(self, upstream: int, client: str):
        from app.bench.local_server import free_port

        self.port, self.upstream, self.client = free_port(), upstream, client
        self._loop = asyncio.new_event_loop()
        started = threading.Event()
        threading.Thread(target=self._serve, args=(started,), daemon=True).start()
        assert started.wait(30)

    def _serve(self, started: threading.Event) -> None:
        asyncio.set_event_loop(self._loop)

        async def pipe(reader, writer) -> None:
            with contextlib.suppress(OSError, ConnectionError):
                while data := await reader.read(65536):
                    writer.write(data)
                    await writer.drain()
            writer.close()

        async def handle(reader, writer) -> None:
            up_reader, up_writer = await asyncio.open_connection("127.0.0.1", self.upstream)
            head = await reader.readuntil(b"\r\n\r\n")
            stamp = f"X-Forwarded-For: {self.client}\r\n\r\n".encode()
            up_writer.write(head[:-2] + stamp)
            await up_writer.drain()
            await asyncio.gather(pipe(reader, up_writer), pipe(up_reader, writer))

        async def main() -> None:
            await asyncio.start_server(handle, "127.0.0.1", self.port)
            started.set()
            await asyncio.Event().wait()

        with contextlib.suppress(RuntimeError):
            self._loop.run_until_complete(main())

    def stop(self) -> None:
        self._loop.call_soon_threadsafe(self._loop.stop)


def test_behind_a_local_reverse_proxy_each_browser_is_its_own_address(behind_proxy):
    """Two students behind a real (small) reverse proxy on 127.0.0.1, each with a page port
    and a scene port of the proxy: A's scene gets A's session through the proxy, A's second
    scene-only connection waits (A's address holds its one), A's script is refused (429), B's
    script gets a session."""
    base = behind_proxy.base
    proxies = {
        who: (_Proxy(behind_proxy.port, ip), _Proxy(behind_proxy.viser_port, ip))
        for who, ip in (("a", "198.51.100.30"), ("b", "198.51.100.31"))
    }

    def health() -> dict:
        return httpx.get(f"{base}/api/health", timeout=HTTP_S).json()

    def private() -> int:
        return httpx.get(f"{base}/api/sessions", timeout=HTTP_S).json()["private_sessions"]

    page_a, scene_a = proxies["a"]
    page_b, _ = proxies["b"]
    headers = {"Connection": "close"}  # one request a connection: each is stamped
    scenes = [Scene(f"ws://127.0.0.1:{scene_a.port}/", "203.0.113.66")]  # A writes a lie
    try:
        _wait(lambda: private() == 1, "A's scene to get its session through the proxy")
        scenes.append(Scene(f"ws://127.0.0.1:{scene_a.port}/", "203.0.113.67"))
        _wait(lambda: health()["viewers_waiting"] == 1, "A's second connection to wait")
        r = httpx.post(f"http://127.0.0.1:{page_a.port}/api/sessions", headers=headers,
                       timeout=HTTP_S)  # fmt: skip
        assert r.status_code == 429 and "198.51.100.30" in r.text, r.text
        r = httpx.post(f"http://127.0.0.1:{page_b.port}/api/sessions", headers=headers,
                       timeout=HTTP_S)  # fmt: skip
        assert r.status_code == 201, r.text
        httpx.delete(
            f"{base}/api/sessions/mine",
            headers={"Authorization": f"Bearer {r.json()['token']}"},
            timeout=HTTP_S,
        )
    finally:
        for s in scenes:
            s.close()
        for pair in proxies.values():
            for p in pair:
                p.stop()
    assert "Traceback" not in behind_proxy.output(400)
