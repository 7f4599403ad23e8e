"""Instructor mode in real browsers (``serve --instructor-token``): a student's page reads
that the instructor drives the demo and its controls for it are off, a student's API change
is refused with a message, and the instructor's slider change reaches every browser.

One served tool in shared mode with the token in its environment; two Chromium pages, the
instructor's (``/?token=...``) and a student's (``/``). Every step acts once and waits for a
condition, never for a fixed time.
"""

from __future__ import annotations

import os
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
    serving,
    slider,
    wait_for,
)

pytestmark = needs_chromium
TOKEN = "lecture-hall-3-token"
VIEWPORT = {"width": 1100, "height": 700}  # two pages render in software at once
WAIT_S = 120.0
LABEL = "Step length [m]"


def _until(check, what: str, timeout: float = WAIT_S):
    value = wait_for(check, timeout)
    if not value:
        pytest.fail(f"waited {timeout:.0f} s for {what}")
    return value


def _step_length(base: str) -> float:
    return httpx.get(f"{base}/api/params", timeout=30).json()["walk"]["step_length"]


@pytest.fixture(scope="module")
def tool():
    os.environ["PELVIC_WALK_INSTRUCTOR_TOKEN"] = TOKEN  # from the environment, as advised
    try:
        with serving("--methods", "fixed", "mpc") as (base, _viser, _proc):
            yield base
    finally:
        os.environ.pop("PELVIC_WALK_INSTRUCTOR_TOKEN", None)


def _open(browser, url: str):
    page = browser.new_context(viewport=VIEWPORT).new_page()
    page.set_default_timeout(WAIT_S * 1000)
    page.goto(url)
    scene = page.frame_locator("#scene")
    scene.locator("canvas").first.wait_for(state="visible")
    close_notice(scene)
    return page, scene


def test_students_watch_and_the_instructor_drives_everyone(tool):
    from playwright.sync_api import sync_playwright

    base = tool
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROME_ARGS)
        try:
            teacher, t_scene = _open(browser, f"{base}/?token={TOKEN}")
            student, s_scene = _open(browser, f"{base}/")
            assert "you drive the shared demo" in teacher.locator("aside .role").inner_text()
            assert "drives the shared demo" in student.locator("aside .role").inner_text()

            # the student's page: a line saying so, and its slider for the demo is off
            s_scene.get_by_text("The instructor drives this demo.").first.wait_for()
            s_thumb, _ = slider(s_scene, LABEL)
            _until(lambda: s_thumb.get_attribute("data-disabled") is not None, "disabled")
            t_thumb, _ = slider(t_scene, LABEL)
            assert t_thumb.get_attribute("data-disabled") is None
            t_scene.get_by_text("Instructor").first.wait_for()

            # a student's change through the API is refused, with a message
            r = httpx.put(f"{base}/api/params", json={"walk": {"step_length": 0.45}}, timeout=30)
            assert r.status_code == 401 and "instructor" in r.json()["detail"]
            before = _step_length(base)
            # and a click on the student's slider moves nothing (it is disabled)
            _thumb, s_track = slider(s_scene, LABEL)
            box = _until(lambda: s_track.bounding_box(), "the student's slider on screen")
            lo = float(s_thumb.get_attribute("aria-valuemin"))
            hi = float(s_thumb.get_attribute("aria-valuemax"))
            x = box["x"] + (0.45 - lo) / (hi - lo) * box["width"]
            student.mouse.click(x, box["y"] + box["height"] / 2)
            seen: list[float] = []

            # the instructor's slider applies to everyone: the API, then the student's slider
            target = 0.3 if abs(before - 0.3) > 1e-9 else 0.25
            click_slider(teacher, t_scene, LABEL, target)
            shown = float(t_thumb.get_attribute("aria-valuenow"))
            _until(
                lambda: seen.append(v := _step_length(base)) or v == pytest.approx(shown),
                "the API to read the instructor's value",
            )
            _until(
                lambda: float(s_thumb.get_attribute("aria-valuenow")) == pytest.approx(shown),
                "the student's slider to follow the instructor's",
            )
            assert shown != pytest.approx(before)
            assert 0.45 not in [round(v, 3) for v in seen]  # the student's click never applied
            ARTIFACTS.mkdir(parents=True, exist_ok=True)
            student.screenshot(path=str(ARTIFACTS / "class_student_read_only.png"))
            teacher.screenshot(path=str(ARTIFACTS / "class_instructor.png"))
        finally:
            browser.close()


def test_the_instructors_lesson_shows_on_every_students_page_and_the_token_hides(tool):
    """The page the instructor projects drops the token from its address bar and its links;
    a lesson the instructor starts shows on the student's Learn tab (head, text, live
    numbers), whose lesson buttons stay off."""
    from browser_util import open_tab, press, scroll_into_view
    from playwright.sync_api import sync_playwright

    from app.web.lessons import LESSONS

    base = tool
    lesson = LESSONS[0]
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROME_ARGS)
        try:
            teacher, t_scene = _open(browser, f"{base}/?token={TOKEN}")
            student, s_scene = _open(browser, f"{base}/")
            _until(lambda: TOKEN not in teacher.url, "the token to leave the address bar")
            assert TOKEN not in teacher.locator("nav").inner_html()
            # nor in the page or the scene frame's address: exchanged for an HttpOnly cookie
            assert TOKEN not in teacher.content()
            assert TOKEN not in (teacher.locator("#scene").get_attribute("src") or "")
            assert TOKEN not in str(teacher.context.cookies()) and not teacher.evaluate(
                "document.cookie"
            )
            t_scene.get_by_text("Instructor").first.wait_for()  # it still drives
            open_tab(t_scene, "Learn")
            open_tab(s_scene, "Learn")
            s_button = s_scene.get_by_role("button", name=lesson.title).first
            _until(lambda: s_button.is_disabled(), "the student's lesson buttons to be off")
            box = s_scene.locator(".lesson-live").first
            pressed = []

            def shown() -> bool:
                if box.count() and "into the lesson" in box.inner_text():
                    return True
                # again if a starved page dropped the click (a lesson started twice is
                # harmless), at most every 20 s
                if not pressed or time.monotonic() - pressed[-1] > 20.0:
                    button = t_scene.get_by_role("button", name=lesson.title).first
                    scroll_into_view(button)
                    press(button)
                    pressed.append(time.monotonic())
                return False

            _until(shown, "the lesson's live numbers on the student's page")
            assert s_scene.get_by_text(lesson.title).count() >= 2  # its button and its head
            assert s_scene.get_by_text(lesson.paper, exact=False).count() >= 1
            scroll_into_view(box)
            ARTIFACTS.mkdir(parents=True, exist_ok=True)
            student.screenshot(path=str(ARTIFACTS / "class_student_lesson.png"))
        finally:
            browser.close()
