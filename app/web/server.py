"""``pelvic-walk serve``: viser (3-D scene + GUI), the live simulation and FastAPI, together.

Three kinds of threads in one process (the machine may have only two cores):

- the **live simulation** thread (:class:`~app.live.LiveSim`) ticks the robots;
- the **display** thread (:class:`LiveView`) reads the latest published frame at
  ``DISPLAY_HZ`` and draws it (scene, plots, GUI reflection); viser's own thread sends it;
- **uvicorn** serves the page and the HTTP API in the main thread.

viser silently takes the next free port when its port is busy, so :func:`serve` checks
``get_port()`` and stops with one clear line (exit status 2); the FastAPI port is checked
before anything starts.
"""

from __future__ import annotations

import logging
import socket
import sys
import threading
import time
from pathlib import Path

import viser

from app.live import LiveSim
from app.web.api import create_app
from app.web.gui import ControlPanel
from app.web.scene import SceneView
from app.web.settings import Settings

DISPLAY_HZ = 25.0
log = logging.getLogger(__name__)


class LiveView:
    """The viser scene and GUI of a :class:`LiveSim`, redrawn by a display thread."""

    def __init__(self, server: viser.ViserServer, live: LiveSim, hz: float = DISPLAY_HZ):
        from app.sim.world import World

        self.server = server
        self.live = live
        self.period = 1.0 / hz
        model = World().model  # the same MJCF as the simulation (only read for shapes)
        self.scene = SceneView(server, model)
        self.panel = ControlPanel(server, live, self.scene)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.draw_count = 0

    def start(self) -> LiveView:
        self._thread = threading.Thread(target=self._run, name="live-display", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2.0)

    def draw_once(self) -> None:
        frame = self.live.shown_frame()
        if frame is not None:
            self.scene.draw(frame)
        self.panel.reflect(frame)
        self.draw_count += 1

    def _run(self) -> None:
        last_seq = -1
        while not self._stop.is_set():
            t0 = time.perf_counter()
            frame = self.live.shown_frame()
            try:
                if frame is None or frame.seq != last_seq or (
                    self.panel._reflected_version != self.live.intent.version
                ):
                    self.draw_once()
                    last_seq = frame.seq if frame else -1
            except Exception:  # noqa: BLE001 - a drawing bug must not kill the display
                log.exception("display update failed")
                time.sleep(0.5)
            self._stop.wait(max(0.0, self.period - (time.perf_counter() - t0)))


def port_free(host: str, port: int) -> bool:
    """True if a TCP server could bind ``host:port`` now."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host, port))
        except OSError:
            return False
    return True


def _fail(message: str) -> int:
    print(f"pelvic-walk serve: error: {message}", file=sys.stderr)
    return 2


def serve(
    host: str | None = None,
    port: int | None = None,
    viser_port: int | None = None,
    report_dir: Path | None = None,
) -> int:
    """Run the web tool until Ctrl-C; returns the exit status (2 on a busy port).

    ``report_dir``: what ``/report`` shows (default: the latest ``pelvic-walk experiments``
    output, else the packaged reference report).
    """
    import uvicorn

    settings = Settings()
    host = host or settings.host
    port = port or settings.port
    viser_port = viser_port or settings.viser_port
    report_dir = report_dir or settings.report_dir
    if port == viser_port:
        return _fail(f"--port and --viser-port must differ (both {port})")
    if not port_free(host, port):
        return _fail(f"port {port} on {host} is in use; choose another with --port")
    if not port_free(host, viser_port):
        return _fail(f"port {viser_port} on {host} is in use; choose another with --viser-port")

    viser_server = viser.ViserServer(host=host, port=viser_port, verbose=False)
    if viser_server.get_port() != viser_port:
        viser_server.stop()
        return _fail(f"port {viser_port} on {host} is in use; choose another with --viser-port")

    live = LiveSim().start()
    view = LiveView(viser_server, live).start()
    app = create_app(live, viser_port=viser_port, report_dir=report_dir)
    config = uvicorn.Config(app, host=host, port=port, log_level="warning")
    server = uvicorn.Server(config)
    shown = f"[{host}]" if ":" in host else host
    print(f"pelvic-walk: open http://{shown}:{port}/  (3-D scene: http://{shown}:{viser_port}/,"
          f" API docs: http://{shown}:{port}/docs); Ctrl-C to stop", flush=True)
    status = 0
    try:
        server.run()
    except SystemExit as exc:  # uvicorn exits when it cannot bind (a race with another server)
        status = 2 if exc.code else 0
    except KeyboardInterrupt:
        status = 0
    finally:
        view.stop()
        live.stop()
        app.state.runs.shutdown()
        viser_server.stop()
    if not server.started and status == 0:
        return _fail(f"the web server could not start on {host}:{port}")
    print("pelvic-walk: stopped", flush=True)
    return status
