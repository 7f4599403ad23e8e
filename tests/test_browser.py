"""One real-browser test: the page, the framed viser scene and GUI, and a slider that acts.

Starts ``pelvic-walk serve`` in a subprocess on free localhost ports, opens the page in
Debian's Chromium through Playwright, moves the "Step length [m]" slider inside the viser
iframe with a mouse click on its track, and checks through ``GET /api/state``
that the robots walk with the new step length. Saves ``tests/artifacts/browser.png``.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

CHROMIUM = "/usr/bin/chromium"
ROOT = Path(__file__).resolve().parents[1]
ARTIFACTS = ROOT / "tests" / "artifacts"
CHROME_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
]

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not os.path.exists(CHROMIUM),
                       reason=f"{CHROMIUM} is missing (apt-get install chromium)"),
]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def server():
    port, viser_port = _free_port(), _free_port()
    exe = Path(sys.executable).with_name("pelvic-walk")
    proc = subprocess.Popen(
        [str(exe), "serve", "--port", str(port), "--viser-port", str(viser_port)],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if proc.poll() is not None:
                pytest.fail(f"serve exited with {proc.returncode}: {proc.stdout.read()[-2000:]}")
            try:
                if httpx.get(f"{base}/api/health", timeout=1).status_code == 200:
                    break
            except httpx.HTTPError:
                time.sleep(0.3)
        else:
            pytest.fail("serve did not answer /api/health within 60 s")
        yield base
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)


def _robots(base: str) -> list[dict]:
    return httpx.get(f"{base}/api/state", timeout=5).json()["robots"]


def test_page_scene_gui_and_step_length_slider(server):
    from playwright.sync_api import sync_playwright

    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROME_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 860})
            page.goto(server + "/")
            assert "pelvic-walk" in page.title()
            assert page.locator("header a[href='/docs']").count() == 1

            scene = page.frame_locator("#scene")
            scene.locator("canvas").first.wait_for(state="visible", timeout=30_000)
            label = scene.locator("label", has_text="Step length [m]")
            label.wait_for(timeout=30_000)
            for folder in ("Presets", "Walk", "Compare", "Playback"):
                assert scene.get_by_text(folder, exact=True).count() >= 1

            # Move the slider: click its track where 0.30 m lies (keyboard arrows would also
            # reach viser's camera controls and turn the view).
            slider_id = label.get_attribute("for")
            root = scene.locator(f'[id="{slider_id}"]')
            thumb = root.locator('[role="slider"]')
            assert float(thumb.get_attribute("aria-valuenow")) == pytest.approx(0.2)
            track = root.locator(".mantine-Slider-track").bounding_box()
            lo, hi = float(thumb.get_attribute("aria-valuemin")), float(
                thumb.get_attribute("aria-valuemax"))
            frac = (0.30 - lo) / (hi - lo)
            page.mouse.click(track["x"] + frac * track["width"],
                             track["y"] + track["height"] / 2)
            assert float(thumb.get_attribute("aria-valuenow")) == pytest.approx(0.3)

            deadline = time.monotonic() + 20
            while time.monotonic() < deadline:
                params = httpx.get(f"{server}/api/params", timeout=5).json()
                if params["walk"]["step_length"] == pytest.approx(0.3):
                    break
                time.sleep(0.2)
            assert params["walk"]["step_length"] == pytest.approx(0.3)

            # The robots take the new length from their next step on.
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline:
                robots = _robots(server)
                if all(r["step_length"] == pytest.approx(0.3) and r["step_index"] >= 0
                       for r in robots):
                    break
                time.sleep(0.3)
            assert all(r["step_length"] == pytest.approx(0.3) for r in robots), robots
            assert all(r["params"]["step_length"] == pytest.approx(0.3) for r in robots)

            # An API change moves the slider in the GUI (the GUI reflects PUT /api/params).
            r = httpx.put(f"{server}/api/params", json={"walk": {"step_length": 0.25}})
            assert r.status_code == 200
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline:
                if float(thumb.get_attribute("aria-valuenow")) == pytest.approx(0.25):
                    break
                time.sleep(0.2)
            assert float(thumb.get_attribute("aria-valuenow")) == pytest.approx(0.25)

            # Screenshots: the controls, then the live plots.
            notice = scene.get_by_text("Software WebGL rendering detected")
            if notice.count():  # headless Chromium renders without a GPU; not our message
                scene.locator(".mantine-Notification-closeButton").first.click()
            time.sleep(1.0)
            page.screenshot(path=str(ARTIFACTS / "browser.png"))
            scene.get_by_role("tab", name="Plots").click()
            time.sleep(2.0)
            page.screenshot(path=str(ARTIFACTS / "browser_plots.png"))
        finally:
            browser.close()


def test_docs_list_the_operations_without_internet(server):
    """Swagger UI's scripts come from the installed package: the page renders the operations
    although Chromium reaches nothing beyond localhost."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROME_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1200, "height": 900})
            outside: list[str] = []
            page.on(
                "request",
                lambda req: outside.append(req.url) if not req.url.startswith(server) else None,
            )
            page.goto(server + "/docs")
            block = page.locator(".opblock", has_text="/api/params").filter(has_text="PUT")
            block.first.wait_for(state="visible", timeout=30_000)
            assert page.locator(".opblock-summary-method", has_text="PUT").count() >= 1
            assert page.get_by_text("/api/params", exact=True).first.is_visible()
            assert page.locator(".opblock-summary-path").count() >= 10  # every operation
            assert outside == []
        finally:
            browser.close()
