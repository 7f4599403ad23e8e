"""What the real-browser tests share: a served tool (a ``pelvic-walk serve`` child process, or
the same parts in this process when a test must read what the browser reports), Debian's
Chromium through Playwright, and one helper for each viser idiom (tabs, folders, sliders,
buttons).

The rule every helper follows: act once, then wait for a condition (the DOM, ``/api/state``,
the camera the browser reports), never for a fixed time. A software-rendered page on a busy
2-core machine can take tens of seconds for what takes one on a desktop, so the waits are
generous and a wait that runs out says what it waited for. Playwright's actionability checks
("stable": two animation frames alike) are avoided: a scene redrawing in software can hold them
off past any timeout, so clicks are dispatched events or mouse clicks at a settled box.
"""

from __future__ import annotations

import contextlib
import logging
import os
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import httpx
import numpy as np
import pytest

from app.bench.local_server import free_port, local_server

CHROMIUM = "/usr/bin/chromium"
ROOT = Path(__file__).resolve().parents[1]
ARTIFACTS = ROOT / "tests" / "artifacts"
CHROME_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
needs_chromium = [
    pytest.mark.browser,
    pytest.mark.skipif(
        not os.path.exists(CHROMIUM), reason=f"{CHROMIUM} is missing (apt-get install chromium)"
    ),
]
WAIT_S = 90.0  # [s] the default wait for a condition (a busy machine, software WebGL)
PAGE_TIMEOUT_MS = 120_000  # Playwright's default per action on the pages opened here
__all__ = ["free_port"]  # re-exported for tests that bind a port themselves

T = TypeVar("T")


# -- waiting ---------------------------------------------------------------------------------
def _transient() -> tuple[type[BaseException], ...]:
    """Errors a poll retries: the server or the page was busy, not wrong."""
    from playwright.sync_api import Error as PlaywrightError

    return (httpx.HTTPError, PlaywrightError)


def wait_for(check: Callable[[], T], timeout: float = WAIT_S, every: float = 0.25) -> T | None:
    """Poll ``check()`` until it returns something truthy; that value, or None at ``timeout``
    [s]. A check that raises a transient error (an HTTP timeout, an element re-rendered under
    Playwright) is polled again."""
    transient = _transient()
    deadline = time.monotonic() + timeout
    while True:
        try:
            value = check()
            if value:
                return value
        except transient:
            pass
        if time.monotonic() >= deadline:
            return None
        time.sleep(every)


def wait_until(
    check: Callable[[], T], what: str, timeout: float = WAIT_S, every: float = 0.25
) -> T:
    """:func:`wait_for`, failing the test with ``what`` (what was awaited) at ``timeout``."""
    value = wait_for(check, timeout, every)
    if not value:
        pytest.fail(f"waited {timeout:.0f} s for {what}")
    return value


# -- the HTTP API ----------------------------------------------------------------------------
def api(base: str, sid: str | None = None) -> str:
    """The API prefix of the shared session, or of private session ``sid``."""
    return f"{base}/api/sessions/{sid}" if sid else f"{base}/api"


def get(base: str, path: str, sid: str | None = None) -> Any:
    """``GET`` an API route (``"state"``, ``"params"``, ...) as JSON."""
    r = httpx.get(f"{api(base, sid)}/{path}", timeout=30)
    r.raise_for_status()
    return r.json()


def put_params(base: str, body: dict, sid: str | None = None) -> dict:
    """``PUT /api/params``: the intent the tool answers with."""
    r = httpx.put(f"{api(base, sid)}/params", json=body, timeout=30)
    assert r.status_code == 200, r.text
    return r.json()


def post(base: str, path: str, body: dict | None = None, sid: str | None = None) -> dict:
    """``POST`` to an API route (``"sim/pause"``, ...)."""
    r = httpx.post(f"{api(base, sid)}/{path}", json=body, timeout=30)
    assert r.status_code == 200, r.text
    return r.json()


def wait_robots(
    base: str, what: str, ok: Callable[[dict], bool], sid: str | None = None, timeout=WAIT_S
) -> list[dict]:
    """Wait until every robot of ``GET /api/state`` satisfies ``ok``; the robots."""
    return wait_until(
        lambda: (rs := get(base, "state", sid)["robots"]) and all(ok(r) for r in rs) and rs,
        what,
        timeout,
    )


# -- served tools ----------------------------------------------------------------------------
@contextlib.contextmanager
def serving(*args: str) -> Iterator[tuple[str, str, Any]]:
    """``pelvic-walk serve *args`` in a child process; yields (API base URL, viser URL,
    process). Its last output is printed when the block fails."""
    # the page at full priority: here it shares the cores with another pytest process and a
    # browser (the classroom's priorities are measured by `pelvic-walk loadtest`)
    env = {**os.environ, "PELVIC_WALK_DISPLAY_NICE": "0"}
    with local_server(args, env=env, cwd=ROOT) as server:
        try:
            yield server.base, server.viser_url, server.proc
        except BaseException:
            print(f"--- the served tool's last output ---\n{server.output()}")  # on failure
            raise


class _Errors(logging.Handler):
    """Collects the display thread's logged errors (a drawing bug is logged, not raised)."""

    def __init__(self):
        super().__init__(logging.ERROR)
        self.records: list[str] = []

    def emit(self, record):
        self.records.append(self.format(record))


@dataclass
class InProcess:
    """The tool's parts in this process: the API's base URL, the display (its views and
    panels) and the viser server (its clients and the cameras they report)."""

    base: str
    display: Any
    viser: Any
    errors: list[str] = field(default_factory=list)  # what the display thread logged


@contextlib.contextmanager
def in_process(display_hz: float = 5.0) -> Iterator[InProcess]:
    """The shared session in a thread (as ``serve --workers 0``), the display and the API in
    this process, on free loopback ports. A test can then read what the browser reports of its
    camera (viser calls a camera's ``on_update`` only for messages from the browser). Fewer
    redraws than the default (``display_hz``): the page renders in software."""
    import uvicorn
    import viser

    from app.live.registry import SessionRegistry
    from app.live.session import initial_intent
    from app.web.api import create_app
    from app.web.view import Display

    port, viser_port = free_port(), free_port()
    errors = _Errors()
    logging.getLogger("app.web").addHandler(errors)
    vs = viser.ViserServer(host="127.0.0.1", port=viser_port, verbose=False)
    registry = SessionRegistry.start("shared", initial_intent())
    display = Display(vs, registry, display_hz).start()
    app = create_app(registry, viser_port=viser_port, health_extra=display.health)
    server = uvicorn.Server(
        uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning", lifespan="off")
    )
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    try:
        wait_until(lambda: server.started, "uvicorn to start", 60)
        yield InProcess(f"http://127.0.0.1:{port}", display, vs, errors.records)
    finally:
        server.should_exit = True
        thread.join(10)
        display.stop()
        registry.shutdown()
        app.state.runs.shutdown()
        vs.stop()
        logging.getLogger("app.web").removeHandler(errors)


# -- the browser -----------------------------------------------------------------------------
@contextlib.contextmanager
def chromium() -> Iterator[Any]:
    """Debian's Chromium, headless, through Playwright."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROME_ARGS)
        try:
            yield browser
        finally:
            browser.close()


def open_scene(browser, url: str, viewport: dict, framed: bool = True) -> tuple[Any, Any]:
    """A new page (in its own context: its own viser client) at ``url``; (page, scene), the
    scene being the page's ``#scene`` frame (the tool's page) or the page itself (viser's own
    URL). Returns once the canvas shows, with the software-WebGL notice closed."""
    page = browser.new_context(viewport=viewport).new_page()
    page.set_default_timeout(PAGE_TIMEOUT_MS)
    page.goto(url)
    scene = page.frame_locator("#scene") if framed else page
    scene.locator("canvas").first.wait_for(state="visible")
    close_notice(scene)
    return page, scene


def screenshot(page, name: str) -> Path:
    """A screenshot for people to look at (nothing asserts on its pixels)."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / name
    page.screenshot(path=str(path))
    return path


def scroll_into_view(locator, timeout: float = WAIT_S) -> None:
    """Scroll an element to the middle of its scroll area by script (Playwright's
    ``scroll_into_view_if_needed`` waits for "stable" first)."""
    locator.first.evaluate("e => e.scrollIntoView({block: 'center'})", timeout=timeout * 1000)


def press(locator, timeout: float = WAIT_S) -> None:
    """Press a viser tab, button or folder by dispatching the event its handler takes (a real
    mouse click waits for the page to take input). viser's tabs activate on Enter (a
    pointer-down starts a tab drag), its buttons and folders on click."""
    el = locator.first
    if el.get_attribute("role", timeout=timeout * 1000) == "tab":
        el.dispatch_event("keydown", {"key": "Enter"}, timeout=timeout * 1000)
    else:
        el.dispatch_event("click", timeout=timeout * 1000)


def open_tab(scene, name: str, timeout: float = WAIT_S) -> None:
    """Select a tab of the control panel and wait until it shows as selected."""
    tab = scene.get_by_role("tab", name=name).first
    pressed: list[float] = []

    def selected() -> bool:
        if tab.get_attribute("aria-selected") == "true":
            return True
        # pressed again if a starved page dropped the last press, at most every 2 s; read more
        # often than that, so that the tab is seen open as soon as it is
        if not pressed or time.monotonic() - pressed[-1] >= 2.0:
            press(tab, timeout)
            pressed.append(time.monotonic())
        return False

    wait_until(selected, f"the {name!r} tab to open", timeout)


def open_folder(scene, title: str, shows: str, timeout: float = WAIT_S) -> Any:
    """Open a collapsed GUI folder by its title and wait until ``shows`` (a text inside it)
    is visible; that text's locator. A folder already open is left open."""
    inside = scene.get_by_text(shows).first
    if not inside.is_visible():
        press(scene.get_by_text(title, exact=True))
    inside.wait_for(state="visible", timeout=timeout * 1000)
    return inside


def close_notice(frame) -> None:
    """Close viser's 'Software WebGL rendering' toast (headless Chromium has no GPU) if it is
    (still) there: cosmetic, and it may have gone by itself meanwhile."""
    button = frame.locator(".mantine-Notification-closeButton")
    with contextlib.suppress(Exception):
        button.first.dispatch_event("click", timeout=3000)


def slider(frame, label: str):
    """The ``role=slider`` thumb and the track box of a viser slider, by its label."""
    handle = frame.locator("label", has_text=label).first
    handle.wait_for(timeout=WAIT_S * 1000)
    root = frame.locator(f'[id="{handle.get_attribute("for", timeout=WAIT_S * 1000)}"]')
    return root.locator('[role="slider"]'), root.locator(".mantine-Slider-track")


def slider_value(frame, label: str) -> float:
    """The value a slider's thumb shows."""
    thumb, _track = slider(frame, label)
    return float(thumb.get_attribute("aria-valuenow"))


def click_slider(page, frame, label: str, value: float, timeout: float = WAIT_S) -> None:
    """Click a slider's track where ``value`` lies (keyboard arrows would move the camera) and
    wait for the thumb to show a new value. The track is clicked once its box has stopped
    moving (two reads 0.2 s apart agree), without Playwright's "stable" wait."""
    thumb, track = slider(frame, label)
    scroll_into_view(track, timeout)
    boxes: list = []

    def settled():
        boxes.append(track.bounding_box(timeout=timeout * 1000))
        return len(boxes) > 1 and boxes[-1] is not None and boxes[-1] == boxes[-2]

    wait_until(settled, f"the {label!r} slider's track to stop moving", timeout, every=0.2)
    box = boxes[-1]
    lo = float(thumb.get_attribute("aria-valuemin", timeout=timeout * 1000))
    hi = float(thumb.get_attribute("aria-valuemax", timeout=timeout * 1000))
    before = float(thumb.get_attribute("aria-valuenow"))
    page.mouse.click(
        box["x"] + (value - lo) / (hi - lo) * box["width"], box["y"] + box["height"] / 2
    )
    # the page re-renders the thumb when it gets to it; a click on the value shown changes nothing
    wait_until(
        lambda: float(thumb.get_attribute("aria-valuenow")) != before or abs(before - value) < 1e-9,
        f"the {label!r} slider to take a click at {value}",
        timeout,
        every=0.2,
    )


# -- the camera a browser reports (in-process servers) ---------------------------------------
@dataclass
class CameraReports:
    """The camera poses one viser client reported, as (position, up) pairs."""

    client: Any
    poses: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)

    def at(self, position, up, tol: float = 0.05) -> bool:
        """Whether the browser reported this pose since the last :meth:`clear`, or its camera
        stands there now (a view set again where the camera already was moves nothing, so the
        browser reports nothing new: a lesson's button pressed twice)."""
        return any(
            np.allclose(p, position, atol=tol) and np.allclose(u, up, atol=1e-3)
            for p, u in [*list(self.poses), self.now()]
        )

    def now(self) -> tuple[np.ndarray, np.ndarray]:
        """(position, up) the browser reported last (NaN before its first report)."""
        try:
            cam = self.client.camera
            return np.array(cam.position), np.array(cam.up_direction)
        except AssertionError:  # viser: nothing reported yet
            return np.full(3, np.nan), np.full(3, np.nan)

    def clear(self) -> None:
        self.poses.clear()


def camera_reports(vs) -> CameraReports:
    """Start collecting what the browser that connected last to viser server ``vs`` reports
    of its camera (a page closed a moment ago may still be listed)."""
    clients = wait_until(lambda: vs.get_clients(), "a viser client")
    client = clients[max(clients)]  # client ids count up
    reports = CameraReports(client)
    client.camera.on_update(
        lambda cam: reports.poses.append((np.array(cam.position), np.array(cam.up_direction)))
    )
    return reports
