"""What the real-browser tests share: a ``pelvic-walk serve`` subprocess on free loopback
ports, Debian's Chromium through Playwright, and moving a viser slider with the mouse."""

from __future__ import annotations

import collections
import contextlib
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

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


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextlib.contextmanager
def serving(*args: str) -> Iterator[tuple[str, str, subprocess.Popen]]:
    """``pelvic-walk serve`` with ``args``; yields (API base URL, viser URL, process)."""
    port, viser_port = free_port(), free_port()
    exe = Path(sys.executable).with_name("pelvic-walk")
    proc = subprocess.Popen(
        [str(exe), "serve", "--port", str(port), "--viser-port", str(viser_port), *args],
        cwd=ROOT,
        # the page at full priority: here it shares the cores with another pytest process and a
        # browser (the classroom's priorities are measured by `pelvic-walk loadtest`)
        env={**os.environ, "PELVIC_WALK_DISPLAY_NICE": "0"},
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    # Drain its output all along (an unread pipe fills and then blocks the server's logging),
    # keeping the last lines for a failure's message.
    proc.log = collections.deque(maxlen=200)  # type: ignore[attr-defined]
    threading.Thread(target=lambda: proc.log.extend(proc.stdout), daemon=True).start()
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if proc.poll() is not None:
                time.sleep(0.5)  # the last lines reach the log
                pytest.fail(f"serve exited with {proc.returncode}: {server_log(proc)}")
            try:
                if httpx.get(f"{base}/api/health", timeout=1).status_code == 200:
                    break
            except httpx.HTTPError:
                time.sleep(0.3)
        else:
            pytest.fail("serve did not answer /api/health within 120 s")
        yield base, f"http://127.0.0.1:{viser_port}/", proc
    except BaseException:
        print(f"--- the served tool's last output ---\n{server_log(proc)}")  # shown on failure
        raise
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)


def server_log(proc: subprocess.Popen, lines: int = 40) -> str:
    """The last lines ``serving``'s server printed."""
    return "".join(list(getattr(proc, "log", []))[-lines:])


def wait_for(check, timeout: float = 30.0, every: float = 0.3):
    """Poll ``check()`` until it returns something truthy; that value, or None."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = check()
        if value:
            return value
        time.sleep(every)
    return None


def slider(frame, label: str):
    """The ``role=slider`` thumb and the track box of a viser slider, by its label."""
    handle = frame.locator("label", has_text=label).first
    handle.wait_for(timeout=90_000)
    root = frame.locator(f'[id="{handle.get_attribute("for", timeout=90_000)}"]')
    return root.locator('[role="slider"]'), root.locator(".mantine-Slider-track")


def scroll_into_view(locator, timeout: float = 90.0) -> None:
    """Scroll an element to the middle of its scroll area by script: Playwright's
    ``scroll_into_view_if_needed`` first waits for the element to be "stable" (two animation
    frames alike), which a software-rendered scene on a busy 2-core machine can hold off past
    any timeout (seen in CI)."""
    locator.first.evaluate("e => e.scrollIntoView({block: 'center'})", timeout=timeout * 1000)


def click_slider(page, frame, label: str, value: float, timeout: float = 90.0) -> None:
    """Click a slider's track where ``value`` lies (keyboard arrows would move the camera) and
    wait for the thumb to show a new value. No actionability waits: Playwright's "stable" check
    needs two animation frames alike, which a busy machine can hold off past any timeout (see
    :func:`scroll_into_view`); the track is clicked once its box has stopped moving."""
    thumb, track = slider(frame, label)
    scroll_into_view(track, timeout)
    boxes: list = []

    def settled():
        boxes.append(track.bounding_box(timeout=timeout * 1000))
        return len(boxes) > 1 and boxes[-1] is not None and boxes[-1] == boxes[-2]

    assert wait_for(settled, timeout=timeout, every=0.2), f"{label!r}: its track kept moving"
    box = boxes[-1]
    lo, hi = (
        float(thumb.get_attribute("aria-valuemin", timeout=timeout * 1000)),
        float(thumb.get_attribute("aria-valuemax", timeout=timeout * 1000)),
    )
    before = thumb.get_attribute("aria-valuenow")
    page.mouse.click(
        box["x"] + (value - lo) / (hi - lo) * box["width"], box["y"] + box["height"] / 2
    )
    # the page re-renders the thumb when it gets to it; a click on the value shown changes nothing
    wait_for(
        lambda: thumb.get_attribute("aria-valuenow") != before or abs(float(before) - value) < 1e-9,
        timeout=timeout,
        every=0.2,
    )


def press(locator, timeout: float = 90_000) -> None:
    """Press a viser tab or button by dispatching the event its handler takes: a real mouse
    click waits for the page to take input, which a software-rendered scene can hold off past
    any timeout on a busy 2-core machine (seen in CI). viser's tabs activate on Enter (a
    pointer-down starts a tab drag), its buttons and folders on click."""
    el = locator.first
    if el.get_attribute("role", timeout=timeout) == "tab":
        el.dispatch_event("keydown", {"key": "Enter"}, timeout=timeout)
    else:
        el.dispatch_event("click", timeout=timeout)


def close_notice(frame) -> None:
    """Close viser's 'Software WebGL rendering' toast (headless Chromium has no GPU) if it is
    (still) there. A dispatched click: on a busy machine the toast's animation can keep a real
    click waiting past its timeout, and the toast is cosmetic."""
    button = frame.locator(".mantine-Notification-closeButton")
    with contextlib.suppress(Exception):  # it may have gone by itself meanwhile
        button.first.dispatch_event("click", timeout=3000)
