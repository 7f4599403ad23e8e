"""Real-browser tests of the shared-mode page: the framed viser scene and GUI, a slider that
acts, pause and scrub with the timeline, the camera views, and ``/docs`` without internet.

Starts ``pelvic-walk serve`` in a subprocess on free localhost ports and drives Debian's
Chromium through Playwright. Screenshots go to ``tests/artifacts/`` (looked at by people;
nothing here asserts on pixels).
"""

from __future__ import annotations

import time

import httpx
import pytest
from browser_util import (
    ARTIFACTS,
    CHROME_ARGS,
    CHROMIUM,
    click_slider,
    close_notice,
    needs_chromium,
    press,
    serving,
    slider,
    wait_for,
)

pytestmark = needs_chromium


@pytest.fixture(scope="module")
def server():
    with serving() as (base, _viser_url, _proc):
        yield base


def _robots(base: str) -> list[dict]:
    return httpx.get(f"{base}/api/state", timeout=5).json()["robots"]


def test_page_scene_gui_slider_timeline_and_views(server):
    from playwright.sync_api import sync_playwright

    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROME_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 900})
            page.goto(server + "/")
            assert "pelvic-walk" in page.title()
            assert page.locator("header a[href='/docs']").count() == 1
            scene = page.frame_locator("#scene")
            scene.locator("canvas").first.wait_for(state="visible", timeout=60_000)
            thumb, _track = slider(scene, "Step length [m]")
            for folder in ("Presets", "Walk", "Compare", "Playback", "View"):
                assert scene.get_by_text(folder, exact=True).count() >= 1
            close_notice(scene)

            # The step-length slider: the parameters, then the robots from their next step.
            assert float(thumb.get_attribute("aria-valuenow")) == pytest.approx(0.2)
            click_slider(page, scene, "Step length [m]", 0.30)
            assert float(thumb.get_attribute("aria-valuenow")) == pytest.approx(0.3)
            assert wait_for(
                lambda: (
                    httpx.get(f"{server}/api/params", timeout=30).json()["walk"]["step_length"]
                    == pytest.approx(0.3)
                )
            )
            robots = wait_for(
                lambda: (
                    (rs := _robots(server))
                    and all(
                        r["step_length"] == pytest.approx(0.3) and r["step_index"] >= 0 for r in rs
                    )
                    and rs
                ),
                timeout=60,
            )
            assert robots and all(r["params"]["step_length"] == pytest.approx(0.3) for r in robots)
            # An API change moves the slider (the GUI reflects PUT /api/params).
            r = httpx.put(f"{server}/api/params", json={"walk": {"step_length": 0.25}}, timeout=30)
            assert r.status_code == 200
            assert wait_for(
                lambda: float(thumb.get_attribute("aria-valuenow")) == pytest.approx(0.25)
            )

            # Three robots at 0.3 m from the default camera, then the plots with phases.
            httpx.put(
                f"{server}/api/params",
                json={"methods": ["fixed", "redundancy", "mpc"], "walk": {"step_length": 0.3}},
                timeout=30,
            )
            time.sleep(12)
            page.screenshot(path=str(ARTIFACTS / "three_robots.png"))
            press(scene.get_by_role("tab", name="Plots"))
            scene.get_by_text("Waist yaw [deg]").first.wait_for(state="visible")
            time.sleep(3)
            page.screenshot(path=str(ARTIFACTS / "plots.png"))
            press(scene.get_by_role("tab", name="Controls"))

            # Pause, then move the timeline back: the scene, the API show the kept instant.
            # (More than 12 s kept first: the robots restarted with the methods above, and on
            # a busy machine their clock runs slower than the wall's.)
            assert wait_for(
                lambda: (
                    (k := httpx.get(f"{server}/api/state", timeout=30).json()["kept"])
                    and k["end"] - k["start"] > 12.0
                ),
                timeout=120,
            )
            press(scene.get_by_role("button", name="Pause"))
            state = wait_for(
                lambda: (s := httpx.get(f"{server}/api/state", timeout=30).json())["paused"] and s
            )
            assert state and state["shown_t"] is None
            timeline, _t = slider(scene, "Timeline [s] (when paused)")
            assert wait_for(lambda: timeline.get_attribute("data-disabled") is None)

            def _range_shown():
                """The kept span once the slider shows it (frames made just before the pause
                can still arrive and move it; a click maps pixels on the slider's range)."""
                k = httpx.get(f"{server}/api/state", timeout=30).json()["kept"]
                lo = float(timeline.get_attribute("aria-valuemin"))
                hi = float(timeline.get_attribute("aria-valuemax"))
                return abs(lo - k["start"]) < 0.02 and abs(hi - k["end"]) < 0.02 and k

            kept = wait_for(_range_shown, timeout=60)
            assert kept, "the timeline never showed the kept span"
            assert kept["end"] - kept["start"] > 10.0
            click_slider(
                page, scene, "Timeline [s] (when paused)", kept["end"] - 10.0
            )  # ten seconds back
            sought = wait_for(
                lambda: (
                    (s := httpx.get(f"{server}/api/state", timeout=30).json())["shown_t"]
                    is not None
                    and s
                )
            )
            assert sought, "the timeline did not seek"
            assert sought["shown_t"] == pytest.approx(kept["end"] - 10.0, abs=0.5)
            assert sought["clock"] == pytest.approx(sought["shown_t"])
            time.sleep(2)
            page.screenshot(path=str(ARTIFACTS / "scrubbed_10s_back.png"))
            press(scene.get_by_role("button", name="Resume"))
            back = wait_for(
                lambda: (
                    (s := httpx.get(f"{server}/api/state", timeout=30).json())["shown_t"] is None
                    and not s["paused"]
                    and s
                )
            )
            assert back and back["clock"] >= kept["end"]

            # The camera views, and the horizon inspector at 0.4 m (Fig. 5-7).
            for view in ("side", "top"):
                press(scene.get_by_role("button", name=view, exact=True))
                time.sleep(2)
                page.screenshot(path=str(ARTIFACTS / f"view_{view}.png"))
            press(scene.get_by_role("button", name="follow", exact=True))
            httpx.put(f"{server}/api/params", json={"walk": {"step_length": 0.4}}, timeout=30)
            time.sleep(6)
            press(scene.get_by_role("tab", name="Inspect"))
            scene.get_by_text("horizon 1.6 s, 16 samples").first.wait_for(state="visible")
            time.sleep(3)
            page.screenshot(path=str(ARTIFACTS / "inspector_040.png"))
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
