"""What viewers see: a :class:`View` per scene target, drawn by one :class:`Display` thread.

- In ``shared`` mode there is one view on the viser server itself: every browser sees the same
  scene and GUI, and every control acts on the shared session.
- With an instructor (``serve --instructor-token``), each browser gets its own view of the
  shared session (viser's per-client scene and GUI): the instructor's (its instructor cookie,
  given for the page opened once with ``?token=``) drives it, the students' are read-only,
  with a line saying so.
- In ``private`` mode each browser gets its own view (viser's per-client scene and GUI) on its
  own session. A browser that brings its page's seat cookie (:func:`app.web.auth.client_seat`)
  gets the session that cookie holds, opened at its first connection and found again on a
  reload, a reconnect or a second tab; it ends a while after its last view closed
  (:data:`app.live.registry.LINGER_S`). A scene connected without a page's cookie gets a
  session of its own that ends with the connection. Each view is built on its own client: no
  other browser receives its scene or GUI.
  When the workers are full (or the browser's address holds its share), the browser's view
  shows the shared demo with a notice (read-only with an instructor), or, without a shared
  demo, only that notice; it waits in line, and the display gives it a session of its own as
  soon as one fits (:meth:`Display._admit_waiting`), first come first served. With an
  instructor, the instructor's browser gets the shared demo instead of a private session.

The display thread draws each view's *shown* frame (the latest, or the sought one while
paused) at most ``hz`` times a second and only when something changed, so the viewers are
sent only what changed, at a rate they can use.
"""

from __future__ import annotations

import logging
import math
import threading
import time
import warnings
from typing import Any

import mujoco

from app.live.pool import PoolFull
from app.live.registry import AddressFull, SessionRegistry, usable_credential
from app.live.session import SessionView
from app.web.addresses import ClientAddresses
from app.web.auth import (
    Instructor,
    client_address,
    client_headers,
    client_instructor,
    client_seat,
)
from app.web.panel import A11Y_STYLE, THEME, ControlPanel
from app.web.scene import SceneView
from models.dyros_jet import SCENE_XML

log = logging.getLogger(__name__)
# A frame drawn for a browser in the instant between its tab closing and the display hearing
# of it is only dropped by viser; not worth a warning in the server's log per closed browser
warnings.filterwarnings(
    "ignore", message=r"Queued a \w+ on a closed connection", category=UserWarning
)
DISPLAY_HZ = 20.0  # scene updates per second at most (--display-hz)
ALERT_S = 300.0  # [s] a worker's death is shown this long
ADMIT_EVERY_S = 1.0  # [s] how often the display looks for room for the browsers in line
OWN = "**Your own session**: these robots and every control here are yours alone."


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
        client.gui.configure_theme(**THEME)
        client.gui.add_html(A11Y_STYLE)
        self.notice = client.gui.add_markdown(notice)

    def draw(self, now: float) -> None:
        """Nothing moves."""

    def hide(self) -> None:
        self.notice.visible = False


class _Waiting:
    """A browser in line for a private session: what it brought, and why it waits."""

    def __init__(self, client: Any, seat: str | None, address: str | None, for_room: bool):
        self.client = client
        self.seat = seat
        self.address = address
        self.for_room = for_room  # waits for room in the workers (else for its address)


class Display:
    """Views for the viewers and the thread that draws them."""

    def __init__(
        self,
        server: Any,
        registry: SessionRegistry,
        hz: float = DISPLAY_HZ,
        instructor: Instructor | None = None,
        addresses: ClientAddresses | None = None,
    ):
        self.server = server
        self.registry = registry
        self.instructor = instructor or Instructor(None)
        self.addresses = addresses or ClientAddresses()  # the API's source too
        self.period = 1.0 / hz
        self.hz = hz
        self._lock = threading.Lock()
        self.views: dict[Any, View | NoticeOnly] = {}
        self.waiting: dict[Any, _Waiting] = {}  # client id -> in line (first come first)
        self._admitted_at = -math.inf
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
        drives = instructor.is_cookie(client_instructor(self.server, client))
        notice, read_only = None, False
        try:
            if registry.mode == "shared" or (drives and registry.has_shared):
                session = registry.shared
                read_only = not drives
                if drives:
                    notice = "**Instructor**: you drive the shared demo every student watches."
            else:
                seat = usable_credential(client_seat(self.server, client))
                address = self.addresses.resolve(
                    client_address(self.server, client), client_headers(self.server, client)
                )
                try:
                    if self._in_line() and (seat is None or registry.owned([seat]) is None):
                        raise PoolFull("browsers wait in line for room")  # first come first
                    session = self._open(owner, seat, address)
                    notice = OWN
                except (PoolFull, AddressFull) as exc:
                    self.refused += 1
                    waiting = _Waiting(client, seat, address, isinstance(exc, PoolFull))
                    with self._lock:
                        self.waiting[client.client_id] = waiting
                    notice, read_only = self._refusal(exc)
                    if not registry.has_shared:
                        self._add(client, NoticeOnly(client, notice))
                        return
                    session = registry.shared
            view = View(client, session, registry, notice, read_only=read_only)
        except Exception:  # noqa: BLE001 - a browser that left while its view was built
            if not self._gone(client.client_id, built=False):
                log.exception("could not build the view of a browser")
            self._forget(client)
            return
        self._add(client, view)

    def _in_line(self) -> bool:
        """Whether browsers wait for room in the workers (a newcomer queues behind them)."""
        with self._lock:
            return any(w.for_room for w in self.waiting.values())

    def _open(self, owner: str, seat: str | None, address: str | None) -> SessionView:
        """The browser's own session: the one its seat cookie holds, or a new one (PoolFull,
        AddressFull)."""
        registry = self.registry
        if seat is not None:
            sid = registry.owned([seat])
            if sid is not None:
                return registry.attach(sid, owner)
        _sid, session = registry.open_private(
            credential=seat, address=address, opened_by="page" if seat else "scene", viewer=owner
        )
        return session

    def _refusal(self, exc: Exception) -> tuple[str, bool]:
        """(the notice of a browser in line, whether its view of the shared demo is
        read-only)."""
        registry = self.registry
        read_only = self.instructor.enabled
        if isinstance(exc, AddressFull):
            why = (
                "**Your computer holds a private session already** (one an address: "
                "`serve --sessions-per-address`)"
            )
            when = (
                f"this page gets robots of its own {registry.linger_s:g} s after that "
                "session's page closes"
            )
        else:
            n = registry.count_private()
            why = f"**{n} private sessions run, as many as the workers hold**"
            when = "this page gets robots of its own as soon as a place frees (no reload needed)"
        if not registry.has_shared:
            return f"{why}: {when}.", read_only
        watching = "you are watching the shared demo" + (
            "" if read_only else " (your changes act on it too)"
        )
        return f"{why}: {watching}; {when}.", read_only

    def _admit_waiting(self, now: float) -> None:
        """Give the browsers in line a session of their own while one fits, first come first
        served: a new view (scene and panel) on the same page, no reload."""
        if now - self._admitted_at < ADMIT_EVERY_S:
            return
        self._admitted_at = now
        with self._lock:
            line = list(self.waiting.values())
        for waiting in line:
            client = waiting.client
            owner = str(client.client_id)
            try:
                session = self._open(owner, waiting.seat, waiting.address)
            except AddressFull:
                continue  # its address's other session still runs; the next one may fit
            except PoolFull:
                return
            with self._lock:
                gone = self.waiting.pop(client.client_id, None) is None
                old = self.views.pop(client.client_id, None)  # drawn no more
            if gone:  # it left meanwhile
                self.registry.detach(owner)
                continue
            try:
                # the old panel is hidden, not removed (ControlPanel.hide says why); the scene
                # is rebuilt (a scene node's late update is only a note on the page)
                if isinstance(old, View):
                    old.panel.hide()
                elif old is not None:
                    old.hide()
                client.scene.reset()
                view = View(client, session, self.registry, OWN)
            except Exception:  # noqa: BLE001 - a browser that left while its view was built
                if not self._gone(client.client_id, built=False):
                    log.exception("could not build the view of a browser")
                self._forget(client)
                continue
            self._add(client, view)

    def _add(self, client: Any, view: View | NoticeOnly) -> None:
        with self._lock:
            self.views[client.client_id] = view
        # a browser that closed while its view was built: its disconnect may have run before
        # this (viser unlists a client before it calls back), so the view would be drawn to a
        # closed connection for ever, its session gone
        if self._gone(client.client_id, built=False):
            self._forget(client)

    def _forget(self, client: Any) -> None:
        with self._lock:
            self.views.pop(client.client_id, None)
            self.waiting.pop(client.client_id, None)
        self.registry.detach(str(client.client_id))

    def _disconnect(self, client: Any) -> None:
        self._forget(client)

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
            if self.waiting:
                try:
                    self._admit_waiting(t0)
                except Exception:  # noqa: BLE001 - must not kill the display either
                    log.exception("admitting a browser in line failed")
            # the views after the admissions: a browser admitted had its old view replaced and
            # its scene reset (drawing the old one wrote to removed nodes)
            with self._lock:
                views = list(self.views.items())
            self._draw_all(views, t0)
            self._stop.wait(max(0.0, self.period - (time.perf_counter() - t0)))

    def _draw_all(self, views: list[tuple[Any, View | NoticeOnly]], now: float) -> None:
        """Draw each view. A browser that closed while its view was drawn (viser has removed
        its scene and panel: "Cannot assign to 'position' on a removed FrameHandle") is not a
        fault: its view is dropped without a traceback; any other failure is logged."""
        for key, view in views:
            with self._lock:
                if self.views.get(key) is not view:  # replaced or forgotten meanwhile
                    continue
            try:
                view.draw(now)
            except Exception:  # noqa: BLE001 - a drawing bug must not kill the display
                if self._gone(key):
                    log.debug("a browser left while its view was drawn")
                    with self._lock:
                        self.views.pop(key, None)
                    continue
                log.exception("display update failed")
                time.sleep(0.5)

    def _gone(self, key: Any, built: bool = True) -> bool:
        """Whether the browser of view ``key`` has disconnected (None: the server's own view,
        never). ``built``: its view was added (a view forgotten meanwhile has left too)."""
        if key is None:
            return False
        if built:
            with self._lock:
                if key not in self.views:
                    return True
        try:
            return key not in self.server.get_clients()
        except Exception:  # noqa: BLE001 - a server stopping: say gone, not an error
            return True

    def health(self) -> dict[str, Any]:
        with self._lock:
            n, waiting = len(self.views), len(self.waiting)
        return {
            "display_hz": self.hz,
            "views": n,
            "viewers_refused": self.refused,
            "viewers_waiting": waiting,
            "display_running": self._thread is not None and self._thread.is_alive(),
        }
