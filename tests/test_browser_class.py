"""Real-browser checks of what a class sees: a fall that stays on screen, then every robot
restarting in step (lesson 6), and a paused, sought session that reads paused everywhere.

One served tool (``pelvic-walk serve``, shared mode) and one Chromium page. Every step acts
once, then waits for a condition of the page or the API, never for a fixed time. Screenshots
go to ``tests/artifacts/`` (looked at by people); the fall's ring is found in the canvas's
pixels: it is drawn in vermilion (DANGER, 204 90 0), which no robot's torso wears.
"""

from __future__ import annotations

import re
import time

import httpx
import numpy as np
import pytest
from browser_util import (
    ARTIFACTS,
    CHROME_ARGS,
    CHROMIUM,
    click_slider,
    close_notice,
    needs_chromium,
    press,
    scroll_into_view,
    serving,
    slider,
    wait_for,
)
from PIL import Image

from app.live import FALL_HOLD_S
from app.web.lessons import LESSONS
from app.web.overlays import DANGER

pytestmark = needs_chromium
VIEWPORT = {"width": 1200, "height": 760}
WAIT_S = 120.0  # software WebGL on a busy 2-core machine


def _get(base: str, path: str) -> dict:
    r = httpx.get(f"{base}/api/{path}", timeout=30)
    r.raise_for_status()
    return r.json()


def _post(base: str, path: str, body: dict | None = None) -> dict:
    r = httpx.post(f"{base}/api/{path}", json=body, timeout=30)
    assert r.status_code == 200, r.text
    return r.json()


def _until(check, what: str, timeout: float = WAIT_S):
    value = wait_for(check, timeout)
    if not value:
        pytest.fail(f"waited {timeout:.0f} s for {what}")
    return value


def _shared(base: str) -> dict:
    return next(s for s in _get(base, "sessions")["sessions"] if s["id"] == "shared")


@pytest.fixture(scope="module")
def tool():
    with serving() as (base, _viser_url, _proc):
        yield base


@pytest.fixture(scope="module")
def page(tool):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROME_ARGS)
        try:
            pg = browser.new_context(viewport=VIEWPORT).new_page()
            pg.set_default_timeout(WAIT_S * 1000)
            pg.goto(tool + "/")
            scene = pg.frame_locator("#scene")
            scene.locator("canvas").first.wait_for(state="visible")
            close_notice(scene)
            yield pg, scene
        finally:
            browser.close()


def _red_ring_pixels(pg, scene, name: str) -> int:
    """Pixels of the canvas in the fall ring's vermilion (DANGER, drawn as it is sent through
    line_color: within a few levels of it) and in its shape; a screenshot saved as ``name``."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    box = scene.locator("canvas").first.bounding_box()
    path = ARTIFACTS / name
    pg.screenshot(path=str(path), clip=box)
    rgb = np.asarray(Image.open(path).convert("RGB"), dtype=np.int16)
    near = np.abs(rgb - np.array(DANGER, np.int16)).max(axis=-1) <= 22
    red = near & (rgb[..., 2] <= 25)
    # Only the ring's: it lies flat on the ground, so its edges cross the side view in long
    # horizontal runs. The knee marks (nearly straight: the same vermilion) lie along the legs,
    # a few pixels wide, and on a busy machine a pause could land where they outnumbered a
    # ring seen from afar.
    total = 0
    for row in red:
        x = np.flatnonzero(row)
        for run in np.split(x, np.flatnonzero(np.diff(x) > 3) + 1) if len(x) else ():
            if run[-1] - run[0] + 1 >= 15:
                total += len(run)
    return total


def _open_tab(scene, name: str) -> None:
    tab = scene.get_by_role("tab", name=name).first

    def selected() -> bool:
        if tab.get_attribute("aria-selected") == "true":
            return True
        tab.dispatch_event("keydown", {"key": "Enter"})  # viser's tabs take Enter
        return False

    _until(selected, f"the {name} tab")


def test_lesson6_shows_the_fall_then_every_robot_walks_in_step(tool, page):
    """The fixed pelvis falls at 0.42 m: on screen it lies inside its vermilion ring and the panel
    says when and why, for FALL_HOLD_S; then both robots walk again, in step."""
    pg, scene = page
    lesson = LESSONS[5]
    assert lesson.title.startswith("6.") and lesson.view == "side"
    _open_tab(scene, "Learn")
    button = scene.get_by_role("button", name=lesson.title).first

    pressed: list[float] = []

    def started() -> bool:
        params = _get(tool, "params")
        if params["methods"] == ["fixed", "mpc"] and params["walk"]["step_length"] == 0.42:
            return True
        # again if a starved page dropped the click, but not so often that a late one
        # restarts the lesson while the fall below is looked at
        if not pressed or time.monotonic() - pressed[-1] > 20.0:
            scroll_into_view(button)
            press(button)
            pressed.append(time.monotonic())
        return False

    _until(started, "lesson 6 to set 0.42 m and its two robots")

    def fixed_lying(state: dict) -> bool:
        fixed = next((r for r in state["robots"] if r["method"] == "fixed"), None)
        return bool(fixed and fixed["fell"] and fixed["fell_at"] is not None)

    def fallen_and_paused():
        """The fixed robot lying, and the simulation paused there. The hold is measured on the
        simulation clock, so it waits while paused however long the screenshots take; a pause
        that lands after the restart is resumed and the next fall (3 s into the walk) awaited."""
        state = _get(tool, "state")
        if not fixed_lying(state):
            if state["paused"]:
                _post(tool, "sim/resume")
            return None
        if not _post(tool, "sim/pause")["applied"]:
            return None  # the loop has not taken it yet: look again
        state = _get(tool, "state")
        fixed = next(r for r in state["robots"] if r["method"] == "fixed")
        if not fixed_lying(state) or state["clock"] >= fixed["fell_at"] + FALL_HOLD_S:
            _post(tool, "sim/resume")  # paused after the hold (restart due): the next fall
            return None
        return state

    state = _until(fallen_and_paused, "the fixed robot to fall (paused there)")
    fixed = next(r for r in state["robots"] if r["method"] == "fixed")
    fell_at = fixed["fell_at"]
    assert fixed["fell"] and state["clock"] < fell_at + FALL_HOLD_S  # paused within its hold
    mpc = next(r for r in state["robots"] if r["method"] == "mpc")
    assert not mpc["fell"]  # the MPC robot walked on meanwhile
    # the panel (DOM) says when it fell; the canvas shows its ring (the robot in frame)
    note = scene.get_by_text(re.compile(rf"fell at t = {fell_at:.1f} s")).first
    note.wait_for(state="visible")
    ring = _until(
        lambda: (n := _red_ring_pixels(pg, scene, "class_lesson6_fallen.png")) > 150 and n,
        "the fall's vermilion ring on the screen",
    )
    after_shot = _get(tool, "state")  # still paused where it lies, whatever the wait took
    assert after_shot["clock"] == state["clock"], (after_shot["clock"], state["clock"])
    assert any(r["fell"] for r in after_shot["robots"])
    _post(tool, "sim/resume")

    # then every robot restarts together and walks in step
    def walking_in_step():
        s = _get(tool, "state")
        rs = s["robots"]
        ok = (
            s["clock"] > fell_at + FALL_HOLD_S
            and all(not r["fell"] and not r["waiting"] and r["step_index"] >= 1 for r in rs)
            and max(r["t"] for r in rs) - min(r["t"] for r in rs) < 0.05
            and all(r["t"] < s["clock"] - fell_at for r in rs)  # restarted after the fall
        )
        return s if ok else None

    def paused_walking():
        """Paused while both walk in step (the next fall comes 3 s into the walk: a pause
        that lands after it is resumed, and the next restart awaited)."""
        if not walking_in_step():
            return None
        if not _post(tool, "sim/pause")["applied"]:
            return None  # the loop has not taken it yet: look again
        state = _get(tool, "state")
        if not state["paused"] or any(r["fell"] for r in state["robots"]):
            _post(tool, "sim/resume")
            return None
        return True

    _until(paused_walking, "both robots walking again, in step (paused there)")
    scene.get_by_text(re.compile(r"Paused at t = ")).first.wait_for(state="visible")
    after = _until(
        lambda: (n := _red_ring_pixels(pg, scene, "class_lesson6_walking.png")) < ring / 4 and (n,),
        "the scene to show the restarted robots (no ring)",
    )[0]
    _post(tool, "sim/resume")
    assert after < ring / 4, (ring, after)  # the ring went with the restart


def test_a_paused_then_sought_session_reads_paused_everywhere(tool, page):
    """Pause (through the API), then drag the timeline back in the page: the panel, GET
    /api/state and GET /api/sessions all say paused, at the instant sought; the timeline
    spans what is kept; resuming returns all three to running."""
    pg, scene = page
    _until(lambda: (k := _get(tool, "state")["kept"])["end"] - k["start"] > 6.0, "6 s kept")
    _until(lambda: _post(tool, "sim/pause")["applied"], "the pause to be taken")
    _open_tab(scene, "Controls")
    label = "Timeline [s] (when paused)"
    thumb, _track = slider(scene, label)

    def spans_kept():
        kept = _get(tool, "state")["kept"]
        lo, hi = (
            float(thumb.get_attribute("aria-valuemin")),
            float(thumb.get_attribute("aria-valuemax")),
        )
        enabled = thumb.get_attribute("data-disabled") is None
        return enabled and abs(lo - kept["start"]) < 0.02 and abs(hi - kept["end"]) < 0.02 and kept

    kept = _until(spans_kept, "the timeline to span the kept frames, enabled")
    target = kept["end"] - 4.0
    click_slider(pg, scene, label, target)
    state = _until(
        lambda: (s := _get(tool, "state"))["shown_t"] is not None and s, "the seek to arrive"
    )
    assert state["paused"] is True
    assert state["shown_t"] == pytest.approx(target, abs=0.5)
    listed = _shared(tool)
    assert listed["paused"] is True and listed["shown_t"] == pytest.approx(state["shown_t"])
    status = scene.get_by_text(re.compile(r"Paused at t = [\d.]+ s \(replaying")).first
    status.wait_for(state="visible")
    assert f"{state['shown_t']:.2f}" in status.inner_text()
    assert scene.get_by_role("button", name="Resume").count() >= 1
    assert scene.get_by_text("Running at").count() == 0  # the old contradiction
    pg.screenshot(path=str(ARTIFACTS / "class_paused_sought.png"))

    _post(tool, "sim/resume")
    scene.get_by_text(re.compile(r"Running at [\d.]+x")).first.wait_for(state="visible")
    running = _get(tool, "state")
    assert running["paused"] is False and running["shown_t"] is None
    assert _shared(tool)["paused"] is False
    scene.get_by_role("button", name="Pause").first.wait_for(state="visible")
