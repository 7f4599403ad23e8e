"""What viewers see: a :class:`View` per scene target, drawn by one :class:`Display` thread.

- In ``shared`` mode there is one view on the viser server itself: every browser sees the same
  scene and GUI, and every control acts on the shared session.
- With an instructor (``serve --instructor-token``), each browser gets its own view of the
  shared session (viser's per-client scene and GUI): the instructor's (the page opened with
  ``?token=``) drives it, the students' are read-only, with a line saying so.
- In ``private`` mode each browser gets its own view (viser's per-client scene and GUI) on its
  own session, opened when it connects and ended when it disconnects (freeing its worker).
  When the workers are full, the browser's view shows the shared demo with a one-line notice
  (read-only with an instructor), or, without a shared demo, only that notice. With an
  instructor, the instructor's browser gets the shared demo instead of a private session.

The display thread draws each view's *shown* frame (the latest, or the sought one while
paused) at most ``hz`` times a second and only when something changed, so the viewers are
sent only what changed, at a rate they can use.
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Any

import mujoco

from app.live.pool import PoolFull
from app.live.registry import SessionRegistry
from app.live.session import SessionView
from app.web.auth import Instructor, client_token
from app.web.panel import ControlPanel
from app.web.scene import SceneView
from models.dyros_jet import SCENE_XML

log = logging.getLogger(__name__)
DISPLAY_HZ = 20.0  # scene updates per second at most (--display-hz)
ALERT_S = 300.0  # [s] a worker's death is shown this long


class View:
    """One scene and control panel (on the server, or on one browser) showing one session."""

    def __init__(
        self,
        target: Any,
        session: SessionView,
        registry: SessionRegistry,
        notice: str | None = None,
        read_only: bool = False,
    ):
        self.target = target
        self.session = session
        self.registry = registry
        self.notice = notice
        self.read_only = read_only  # a student watching the instructor's demo
        model = mujoco.MjModel.from_xml_path(str(SCENE_XML))  # only read for its shapes
        self.scene = SceneView(target, model)
        self.panel = ControlPanel(target.gui, self)
        self._drawn: tuple = ()
        self.draws = 0

    def alerts(self) -> list[str]:
        """Lines for the status area: a loop of this session that stopped (its robots no
        longer move: said, not left for a frozen view to tell), workers that died lately."""
        out = []
        if self.session.error:
            out.append(f"⚠ the simulation stopped: {self.session.error}")
        pool = self.registry.pool
        if pool is not None:
            now = time.time()
            out += [f"⚠ {d.describe()}" for d in pool.deaths if now - d.time < ALERT_S]
        return out

    def draw(self, now: float) -> None:
        """Draw the shown frame if anything changed since the last draw."""
        session = self.session
        frame = session.shown_frame()
        key = (
            frame.seq if frame else -1,
            session.intent.version,
            id(session),
            len(self.registry.pool.deaths) if self.registry.pool else 0,
            self.scene.version,  # a new camera view lays the robots and labels out anew
        )
        if key == self._drawn:
            return
        self._drawn = key
        if frame is not None:
            self.scene.draw(frame, session.frames)
        self.panel.reflect(frame, now)
        self.draws += 1


class NoticeOnly:
    """A browser's view with nothing to show but a notice (the workers are full and no
    shared demo runs)."""

    def __init__(self, client: Any, notice: str):
        self.target = client
        client.gui.configure_theme(dark_mode=False, show_logo=False, show_share_button=False)
        client.gui.add_markdown(notice)

    def draw(self, now: float) -> None:
        """Nothing moves."""


class Display:
    """Views for the viewers and the thread that draws them."""

    def __init__(
        self,
        server: Any,
        registry: SessionRegistry,
        hz: float = DISPLAY_HZ,
        instructor: Instructor | None = None,
    ):
        self.server = server
        self.registry = registry
        self.instructor = instructor or Instructor(None)
        self.period = 1.0 / hz
        self.hz = hz
        self._lock = threading.Lock()
        self.views: dict[Any, View | NoticeOnly] = {}
        self.refused = 0  # browsers told the workers were full
        if registry.mode == "shared" and not self.instructor.enabled:
            self.views[None] = View(server, registry.shared, registry)
        else:
            server.on_client_connect(self._connect)
            server.on_client_disconnect(self._disconnect)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # -- one view per browser (private sessions, or an instructor) ---------------------------
    def _connect(self, client: Any) -> None:
        owner = str(client.client_id)
        registry, instructor = self.registry, self.instructor
        drives = instructor.is_token(client_token(self.server, client))
        notice, read_only = None, False
        try:
            if registry.mode == "shared" or (drives and registry.has_shared):
                session = registry.shared
                read_only = not drives
                if drives:
                    notice = "**Instructor**: you drive the shared demo every student watches."
            else:
                try:
                    _sid, session = registry.open_private(owner=owner)
                    notice = (
                        "**Your own session**: these robots and every control here are yours alone."
                    )
                except PoolFull:
                    self.refused += 1
                    n = registry.count_private()
                    full = f"**{n} private sessions run, as many as the workers hold**"
                    if not registry.has_shared:
                        self._add(
                            client, NoticeOnly(client, f"{full}: reload this page when one ends.")
                        )
                        return
                    session = registry.shared
                    read_only = instructor.enabled
                    notice = f"{full}: you are watching the shared demo" + (
                        "." if read_only else " (your changes act on it too)."
                    )
            view = View(client, session, registry, notice, read_only=read_only)
        except Exception:  # noqa: BLE001 - a browser that left while its view was built
            log.exception("could not build the view of client %s", owner)
            registry.close_owned_by(owner)
            return
        self._add(client, view)

    def _add(self, client: Any, view: View | NoticeOnly) -> None:
        with self._lock:
            self.views[client.client_id] = view

    def _disconnect(self, client: Any) -> None:
        with self._lock:
            self.views.pop(client.client_id, None)
        self.registry.close_owned_by(str(client.client_id))

    # -- the thread ------------------------------------------------------------------------
    def start(self) -> Display:
        self._thread = threading.Thread(target=self._run, name="display", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(3.0)

    def _run(self) -> None:
        while not self._stop.is_set():
            t0 = time.perf_counter()
            with self._lock:
                views = list(self.views.values())
            for view in views:
                try:
                    view.draw(t0)
                except Exception:  # noqa: BLE001 - a drawing bug must not kill the display
                    log.exception("display update failed")
                    time.sleep(0.5)
            self._stop.wait(max(0.0, self.period - (time.perf_counter() - t0)))

    def health(self) -> dict[str, Any]:
        with self._lock:
            n = len(self.views)
        return {
            "display_hz": self.hz,
            "views": n,
            "viewers_refused": self.refused,
            "display_running": self._thread is not None and self._thread.is_alive(),
        }
