"""Real-browser tests of the guided lessons (Learn tab): each button sets the parameters, the
robots and the camera view, and the lesson's live numbers appear and move; the kinematic
analysis draws eq. 5 both ways.

The tool runs in this process (``tests/browser_util.in_process``) so a test can read the camera
the browser reports: a reported pose equal to the lesson's named view means the browser's
camera really moved there. One page serves every lesson (one test each, in order, so a failing
lesson does not hide the others). Screenshots of two lessons go to ``tests/artifacts/``
(looked at by people; nothing here asserts on pixels).
"""

from __future__ import annotations

import re
import time

import pytest
from browser_util import (
    camera_reports,
    chromium,
    get,
    needs_chromium,
    open_scene,
    open_tab,
    press,
    screenshot,
    scroll_into_view,
    wait_for,
    wait_until,
)

from app.web.camera import camera_pose
from app.web.learn_gui import COLUMNS
from app.web.lessons import LESSONS

pytestmark = needs_chromium
SMALL, LARGE = {"width": 1100, "height": 760}, {"width": 1400, "height": 900}
SCREENSHOTS = {0: "lesson_reach.png", 4: "lesson_waist_rate.png"}  # lesson index -> file


@pytest.fixture(scope="module")
def learn_page():
    """(tool, page, scene, camera reports) with the Learn tab open, for every test here."""
    from browser_util import in_process

    with in_process() as tool, chromium() as browser:
        page, scene = open_scene(browser, tool.base + "/", SMALL)  # less to render in software
        cams = camera_reports(tool.viser)
        open_tab(scene, "Learn")
        yield tool, page, scene, cams
        page.context.close()
    assert tool.errors == [], tool.errors[:3]  # the display thread drew without an error


def _live_t(box) -> float:
    """The lesson time its live numbers show ("t = 12.3 s into the lesson")."""
    return float(re.search(r"t = ([\d.]+) s", box.inner_text()).group(1))


@pytest.mark.parametrize(
    "i", range(len(LESSONS)), ids=[f"lesson{i + 1}" for i in range(len(LESSONS))]
)
def test_a_lesson_sets_params_view_and_shows_live_numbers(learn_page, i):
    tool, page, scene, cams = learn_page
    lesson = LESSONS[i]
    learn = tool.display.views[None].panel.learn

    # the parameters (GET /api/params) and the robots; a click that a starved software-WebGL
    # page dropped is repeated after 20 s (a lesson started twice is harmless)
    pressed: list[float] = []

    def started():
        b = get(tool.base, "params")
        if (
            b["methods"] == list(lesson.robots())
            and b["walk"]["step_length"] == pytest.approx(lesson.walk["step_length"])
            and learn.lesson is lesson
        ):
            return b
        if not pressed or time.monotonic() - pressed[-1] > 20.0:
            cams.clear()
            button = scene.get_by_role("button", name=lesson.title).first
            scroll_into_view(button)
            press(button)
            pressed.append(time.monotonic())
        return None

    params = wait_until(started, f"{lesson.title}: the parameters to change", every=0.5)
    for group, values in lesson.groups.items():
        for name, value in values.items():
            assert params[group][name] == value, (lesson.title, group, name)

    # the view: the browser reports the lesson's named camera pose
    n = len(lesson.robots())
    pos, _look, up, _fov = camera_pose(
        lesson.view, n, cams.client.camera.aspect, lesson.view == "side"
    )
    if not wait_for(lambda: cams.at(pos, up), 90.0):
        scene_view = tool.display.views[None].scene
        pytest.fail(
            f"waited 90 s for {lesson.title}: the browser camera at {lesson.view} {pos.round(3)};"
            f" it reported {[p.round(3).tolist() for p, _u in cams.poses[-3:]]}, stands at"
            f" {cams.now()[0].round(3).tolist()}; the scene's view {scene_view.camera_view!r},"
            f" a view still to set {learn._camera!r}, the lesson's start clock {learn.start_clock}"
        )
    assert learn.lesson is lesson

    # the lesson's text and its live numbers, read from the robots, moving on
    box = scene.locator(".lesson-live").first
    wait_until(lambda: "into the lesson" in box.inner_text(), f"{lesson.title}: live numbers")
    first = box.inner_text()
    for key in lesson.numbers:
        assert COLUMNS[key] in first, (lesson.title, key)
    assert scene.get_by_text(lesson.paper, exact=False).count() >= 1
    t0 = _live_t(box)
    wait_until(lambda: _live_t(box) > t0, f"{lesson.title}: the numbers to move")
    if i == 0:  # 0.40 m: the fixed pelvis's knee straightens, shown live
        wait_until(
            lambda: "knee nearly straight" in box.inner_text(),
            "lesson 1 to show the fixed pelvis's straight knee",
        )
    if i == 5:  # eq. 5's 0.42 m: the fixed robot falls (and the MPC walks)
        fell = wait_until(
            lambda: [r for r in get(tool.base, "state")["robots"] if r["falls"] >= 1],
            "lesson 6: a fall",
        )
        assert [r["method"] for r in fell] == ["fixed"], fell
    if i in SCREENSHOTS:
        page.set_viewport_size(LARGE)
        try:
            # the page has laid out anew and redrawn once the numbers move again
            t1 = _live_t(box)
            wait_until(lambda: _live_t(box) > t1, "the numbers to move at the larger size")
            close_notice_and_scroll(scene, box)
            screenshot(page, SCREENSHOTS[i])
        finally:
            page.set_viewport_size(SMALL)


def close_notice_and_scroll(scene, box) -> None:
    from browser_util import close_notice

    close_notice(scene)
    # the numbers are re-rendered twice a second: an element gone under us is looked up again
    wait_for(lambda: box.evaluate("e => e.scrollIntoView({block: 'start'}) || true"), 30)


def test_the_kinematic_analysis_draws_eq5_both_ways(learn_page):
    """Fig. 1-2: eq. 5 as printed beside the reading that gives the paper's 0.42 m."""
    _tool, page, scene, _cams = learn_page
    page.set_viewport_size(LARGE)
    try:
        press(scene.get_by_text("Kinematic analysis (Fig. 1-2, eq. 1-5)"))
        drawing = scene.get_by_text("Eq. 5 as printed").first
        drawing.wait_for(state="visible")
        scroll_into_view(drawing)
        text = drawing.locator("xpath=ancestor::div[1]").inner_text()
        assert "0.391 m" in text and "0.421 m" in text and "+33 %" in text
        screenshot(page, "lesson_analysis.png")
    finally:
        page.set_viewport_size(SMALL)
