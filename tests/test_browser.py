"""Real-browser tests of the shared-mode page: the framed viser scene and GUI, a slider that
acts (and an API change that moves it), the plots, pause and scrub with the timeline, the
camera views, the horizon inspector, and ``/docs`` without internet.

The tool runs in this process (``tests/browser_util.in_process``) so a test can read the camera
the browser reports; Chromium drives the page through Playwright. Every step acts once and
then waits for the page, the API or the reported camera to show the effect. Screenshots go to
``tests/artifacts/`` (looked at by people; nothing here asserts on pixels).
"""

from __future__ import annotations

import pytest
from browser_util import (
    camera_reports,
    chromium,
    click_slider,
    get,
    needs_chromium,
    open_scene,
    open_tab,
    press,
    put_params,
    screenshot,
    slider,
    slider_value,
    wait_robots,
    wait_until,
)

from app.web.camera import camera_pose

pytestmark = needs_chromium
VIEWPORT = {"width": 1400, "height": 900}
THREE = ["fixed", "redundancy", "mpc"]


@pytest.fixture(scope="module")
def tool():
    from browser_util import in_process

    with in_process() as tool:
        yield tool
    assert tool.errors == [], tool.errors[:3]  # the display thread drew without an error


@pytest.fixture(scope="module")
def browser():
    with chromium() as b:
        yield b


def _step_length(base: str) -> float:
    return get(base, "params")["walk"]["step_length"]


def test_slider_and_api_change_the_robots_and_the_plots_show_them(tool, browser):
    base = tool.base
    put_params(base, {"methods": THREE, "walk": {"step_length": 0.2}})
    page, scene = open_scene(browser, base + "/", VIEWPORT)
    try:
        assert "pelvic-walk" in page.title()
        assert page.locator("header a[href='/docs']").count() == 1
        for folder in ("Presets", "Walk", "Compare", "Playback", "View"):
            scene.get_by_text(folder, exact=True).first.wait_for()

        # The step-length slider: the parameters, then the robots from their next step.
        wait_until(lambda: slider_value(scene, "Step length [m]") == pytest.approx(0.2), "0.2 m")
        click_slider(page, scene, "Step length [m]", 0.30)
        assert slider_value(scene, "Step length [m]") == pytest.approx(0.3)
        wait_until(lambda: _step_length(base) == pytest.approx(0.3), "the API to read 0.3 m")
        wait_robots(
            base,
            "every robot walking 0.3 m steps",
            lambda r: r["step_length"] == pytest.approx(0.3) and r["step_index"] >= 1,
        )
        screenshot(page, "three_robots.png")

        # An API change moves the slider (the GUI reflects PUT /api/params).
        put_params(base, {"walk": {"step_length": 0.25}})
        wait_until(
            lambda: slider_value(scene, "Step length [m]") == pytest.approx(0.25),
            "the slider to show the API's 0.25 m",
        )

        # The plots, with the double-support phases shaded, once they have data to draw.
        open_tab(scene, "Plots")
        scene.get_by_text("Waist yaw [deg]").first.wait_for(state="visible")
        wait_until(
            lambda: scene.locator(".uplot canvas").count() >= 4,
            "the live plots to draw",
        )
        screenshot(page, "plots.png")
    finally:
        page.context.close()


def test_pause_scrub_resume_views_and_inspector(tool, browser):
    base = tool.base
    put_params(base, {"methods": THREE, "walk": {"step_length": 0.3}})
    page, scene = open_scene(browser, base + "/", VIEWPORT)
    try:
        # More than 12 s kept first (the robots restarted with the methods above).
        wait_until(
            lambda: (k := get(base, "state")["kept"]) and k["end"] - k["start"] > 12.0,
            "12 s of kept frames",
            180,
        )
        press(scene.get_by_role("button", name="Pause"))
        state = wait_until(lambda: (s := get(base, "state"))["paused"] and s, "the pause")
        assert state["shown_t"] is None
        timeline, _track = slider(scene, "Timeline [s] (when paused)")
        wait_until(lambda: timeline.get_attribute("data-disabled") is None, "timeline enabled")

        def range_shown():
            """The kept span once the slider shows it (frames made just before the pause can
            still arrive and move it; a click maps pixels on the slider's range)."""
            k = get(base, "state")["kept"]
            lo = float(timeline.get_attribute("aria-valuemin"))
            hi = float(timeline.get_attribute("aria-valuemax"))
            return abs(lo - k["start"]) < 0.02 and abs(hi - k["end"]) < 0.02 and k

        kept = wait_until(range_shown, "the timeline to show the kept span")
        assert kept["end"] - kept["start"] > 10.0
        click_slider(page, scene, "Timeline [s] (when paused)", kept["end"] - 10.0)
        sought = wait_until(
            lambda: (s := get(base, "state"))["shown_t"] is not None and s, "the seek"
        )
        assert sought["shown_t"] == pytest.approx(kept["end"] - 10.0, abs=0.5)
        assert sought["clock"] == pytest.approx(sought["shown_t"])
        assert sought["paused"]
        wait_until(
            lambda: abs(float(timeline.get_attribute("aria-valuenow")) - sought["shown_t"]) < 0.05,
            "the timeline to rest at the instant shown",
        )
        screenshot(page, "scrubbed_10s_back.png")
        press(scene.get_by_role("button", name="Resume"))
        back = wait_until(
            lambda: (s := get(base, "state"))["shown_t"] is None and not s["paused"] and s,
            "the resume",
        )
        assert back["clock"] >= kept["end"]

        # The camera views: the browser reports the named view's pose for 3 robots.
        cams = camera_reports(tool.viser)
        for view in ("side", "top"):
            cams.clear()
            press(scene.get_by_role("button", name=view, exact=True))
            pos, _look, up, _fov = camera_pose(view, 3, cams.client.camera.aspect, view == "side")
            wait_until(lambda pos=pos, up=up: cams.at(pos, up), f"the browser camera at {view}")
            screenshot(page, f"view_{view}.png")
        press(scene.get_by_role("button", name="follow", exact=True))

        # The horizon inspector (Fig. 5-7) at 0.4 m.
        put_params(base, {"walk": {"step_length": 0.4}})
        wait_robots(
            base,
            "every robot walking 0.4 m steps",
            lambda r: r["step_length"] == pytest.approx(0.4) and r["step_index"] >= 1,
        )
        open_tab(scene, "Inspect")
        scene.get_by_text("horizon 1.6 s, 16 samples").first.wait_for(state="visible")
        wait_until(lambda: scene.locator(".uplot canvas").count() >= 2, "the inspector's plots")
        screenshot(page, "inspector_040.png")
    finally:
        page.context.close()


def test_docs_list_the_operations_without_internet(tool, browser):
    """Swagger UI's scripts come from the installed package: the page renders the operations
    although Chromium reaches nothing beyond localhost."""
    base = tool.base
    page = browser.new_page(viewport={"width": 1200, "height": 900})
    try:
        outside: list[str] = []
        page.on(
            "request",
            lambda req: outside.append(req.url) if not req.url.startswith(base) else None,
        )
        page.goto(base + "/docs")
        block = page.locator(".opblock", has_text="/api/params").filter(has_text="PUT")
        block.first.wait_for(state="visible", timeout=60_000)
        assert page.locator(".opblock-summary-method", has_text="PUT").count() >= 1
        assert page.get_by_text("/api/params", exact=True).first.is_visible()
        assert page.locator(".opblock-summary-path").count() >= 10  # every operation
        assert outside == []
    finally:
        page.close()
