"""A ``pelvic-walk serve`` in a child process on free loopback ports: started, waited for
until ``GET /api/health`` answers, and stopped (SIGINT, then a kill if it hangs).

One harness for everything that needs a served tool it does not own: ``pelvic-walk
loadtest``, the install test (the wheel's own ``pelvic-walk``) and the real-browser tests.
Traffic stays on 127.0.0.1.
"""

from __future__ import annotations

import collections
import contextlib
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import httpx

HOST = "127.0.0.1"
START_TIMEOUT = 120.0  # [s] a cold start on a busy 2-core machine takes 5-30 s
STOP_TIMEOUT = 20.0  # [s] after SIGINT, before the process is killed


class ServeError(RuntimeError):
    """The served tool exited or never answered; the message ends with its last output."""


def free_port() -> int:
    """A TCP port free on the loopback interface now."""
    with socket.socket() as s:
        s.bind((HOST, 0))
        return int(s.getsockname()[1])


@dataclass
class LocalServer:
    """A running ``pelvic-walk serve``: its URLs, its process and its last output lines."""

    proc: subprocess.Popen
    port: int
    viser_port: int
    log: collections.deque = field(default_factory=lambda: collections.deque(maxlen=400))

    @property
    def base(self) -> str:
        """The page and API, e.g. ``http://127.0.0.1:8000``."""
        return f"http://{HOST}:{self.port}"

    @property
    def viser_url(self) -> str:
        """The 3-D scene on its own port."""
        return f"http://{HOST}:{self.viser_port}/"

    def output(self, lines: int = 40) -> str:
        """The last ``lines`` lines the server printed."""
        return "".join(list(self.log)[-lines:])


def wait_healthy(base: str, proc: subprocess.Popen | None = None, timeout: float = START_TIMEOUT):
    """Poll ``GET {base}/api/health`` until it answers 200; raise :class:`ServeError` when
    ``proc`` exits first or ``timeout`` [s] passes."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc is not None and proc.poll() is not None:
            raise ServeError(f"serve exited with status {proc.returncode}")
        try:
            if httpx.get(f"{base}/api/health", timeout=2).status_code == 200:
                return
        except httpx.HTTPError:
            pass
        time.sleep(0.3)
    raise ServeError(f"no server answered {base}/api/health within {timeout:.0f} s")


@contextlib.contextmanager
def local_server(
    args: Sequence[str] = (),
    *,
    exe: str | Path | None = None,
    env: Mapping[str, str] | None = None,
    cwd: str | Path | None = None,
    timeout: float = START_TIMEOUT,
) -> Iterator[LocalServer]:
    """``pelvic-walk serve --port P --viser-port V *args`` until the block ends.

    Args:
        args: more ``serve`` options.
        exe: the ``pelvic-walk`` to run (default: the one beside this Python).
        env: the child's environment (default: this process's).
        cwd: its working folder.
        timeout: [s] to answer ``/api/health``.

    Raises:
        ServeError: it exited or did not answer in time (with its last output).
    """
    port, viser_port = free_port(), free_port()
    exe = Path(exe) if exe else Path(sys.executable).with_name("pelvic-walk")
    proc = subprocess.Popen(
        [str(exe), "serve", "--port", str(port), "--viser-port", str(viser_port), *args],
        cwd=cwd,
        env=dict(env) if env is not None else None,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    server = LocalServer(proc, port, viser_port)
    output = proc.stdout
    assert output is not None  # stdout=PIPE
    # Drain the output all along (an unread pipe fills and then blocks the server's logging).
    reader = threading.Thread(target=lambda: server.log.extend(output), daemon=True)
    reader.start()
    try:
        try:
            wait_healthy(server.base, proc, timeout)
        except ServeError as exc:
            if proc.poll() is not None:
                reader.join(2)  # the last lines reach the log
            raise ServeError(f"{exc}; its last output:\n{server.output()}") from None
        yield server
    finally:
        stop(proc)


def stop(proc: subprocess.Popen) -> int | None:
    """Stop a served tool as Ctrl-C would; kill it if it does not exit in time."""
    if proc.poll() is None:
        with contextlib.suppress(ProcessLookupError):
            proc.send_signal(signal.SIGINT)
        try:
            proc.wait(STOP_TIMEOUT)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)
    return proc.returncode
