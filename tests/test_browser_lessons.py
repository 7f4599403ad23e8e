"""Real-browser test of the guided lessons (Learn tab): each button sets the parameters, the
robots and the camera view, and the lesson's live numbers appear and move.

The server runs in this process (the shared session in a thread, as ``serve --workers 0``)
so the test can read what the browser reports of its camera: viser calls a camera's
``on_update`` only for messages from the browser, so a reported pose equal to the lesson's
named view means the browser's camera really moved there. Screenshots of two lessons go to
``tests/artifacts/`` (looked at by people; nothing here asserts on pixels).
"""

from __future__ import annotations

import contextlib
import logging
import re
import threading
import time

import httpx
import numpy as np
import pytest
from browser_util import (
    ARTIFACTS,
    CHROME_ARGS,
    CHROMIUM,
    close_notice,
    free_port,
    press,
    scroll_into_view,
    wait_for,
)

from app.web.camera import camera_pose
from app.web.learn_gui import COLUMNS
from app.web.lessons import LESSONS

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not __import__("os").path.exists(CHROMIUM), reason=f"{CHROMIUM} missing"),
]
SMALL, LARGE = {"width": 1100, "height": 760}, {"width": 1400, "height": 900}
SCREENSHOTS = {0: "lesson_reach.png", 4: "lesson_waist_rate.png"}  # lesson index -> file


class _Errors(logging.Handler):
    """Collects the display thread's logged errors (a drawing bug is logged, not raised)."""

    def __init__(self):
        super().__init__(logging.ERROR)
        self.records: list[str] = []

    def emit(self, record):
        self.records.append(self.format(record))


@contextlib.contextmanager
def _server():
    import uvicorn
    import viser

    from app.live.registry import SessionRegistry
    from app.live.session import initial_intent
    from app.web.api import create_app
    from app.web.view import Display

    port, viser_port = free_port(), free_port()
    vs = viser.ViserServer(host="127.0.0.1", port=viser_port, verbose=False)
    registry = SessionRegistry.start("shared", initial_intent())
    display = Display(vs, registry, 5.0).start()  # software WebGL: fewer redraws
    app = create_app(registry, viser_port=viser_port, health_extra=display.health)
    server = uvicorn.Server(
        uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning", lifespan="off")
    )
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    try:
        assert wait_for(lambda: server.started, timeout=30), "uvicorn did not start"
        yield f"http://127.0.0.1:{port}", display, vs
    finally:
        server.should_exit = True
        thread.join(10)
        display.stop()
        registry.shutdown()
        app.state.runs.shutdown()
        vs.stop()


def _close(a, b, tol=1e-3) -> bool:
    return bool(np.allclose(np.asarray(a, float), np.asarray(b, float), atol=tol))


def test_each_lesson_sets_params_view_and_shows_live_numbers():
    from playwright.sync_api import sync_playwright

    errors = _Errors()
    logging.getLogger("app.web.view").addHandler(errors)
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    with _server() as (base, display, vs), sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROME_ARGS)
        try:
            page = browser.new_page(viewport=SMALL)  # less to render in software WebGL
            page.goto(base + "/")
            scene = page.frame_locator("#scene")
            scene.locator("canvas").first.wait_for(state="visible", timeout=60_000)
            client = wait_for(lambda: next(iter(vs.get_clients().values()), None))
            assert client is not None
            reported: list[tuple[np.ndarray, np.ndarray]] = []
            client.camera.on_update(
                lambda cam: reported.append((np.array(cam.position), np.array(cam.up_direction)))
            )
            close_notice(scene)
            press(scene.get_by_role("tab", name="Learn"))
            learn = display.views[None].panel.learn
            params = None
            t_start = time.monotonic()
            for i, lesson in enumerate(LESSONS):
                # the parameters (GET /api/params) and the robots; a click that a starved
                # software-WebGL page dropped is repeated (at most twice)
                for _attempt in range(3):
                    reported.clear()
                    button = scene.get_by_role("button", name=lesson.title).first
                    scroll_into_view(button)
                    press(button)
                    params = wait_for(
                        lambda lesson=lesson: (
                            (b := httpx.get(f"{base}/api/params", timeout=5).json())["methods"]
                            == list(lesson.methods)
                            and b["walk"]["step_length"]
                            == pytest.approx(lesson.walk["step_length"])
                            and learn.lesson is lesson
                            and b
                        ),
                        timeout=15,
                    )
                    if params:
                        break
                print(f"{time.monotonic() - t_start:5.1f} s: {lesson.title} (click {_attempt + 1})")
                assert params, f"{lesson.title}: the parameters did not change"
                for group, values in lesson.groups.items():
                    for name, value in values.items():
                        assert params[group][name] == value, (lesson.title, group, name)
                # the view: the browser reports the lesson's named camera pose
                n = len(lesson.methods)
                pos, _look, up, _fov = camera_pose(
                    lesson.view, n, client.camera.aspect, lesson.view == "side"
                )
                moved = wait_for(
                    lambda pos=pos, up=up: any(
                        _close(q, pos, 0.05) and _close(u, up) for q, u in list(reported)
                    ),
                    timeout=15,
                )
                assert moved, f"{lesson.title}: the browser camera did not move to {lesson.view}"
                assert learn.lesson is lesson
                # the lesson's text and its live numbers, read from the robots, moving on
                box = scene.locator(".lesson-live").first
                text = wait_for(lambda box=box: "into the lesson" in box.inner_text() and box, 30)
                assert text, f"{lesson.title}: no live numbers"
                first = box.inner_text()
                for key in lesson.numbers:
                    assert COLUMNS[key] in first, (lesson.title, key)
                assert scene.get_by_text(lesson.paper, exact=False).count() >= 1
                t0 = float(re.search(r"t = ([\d.]+) s", first).group(1))
                assert wait_for(
                    lambda box=box, t0=t0: (
                        float(re.search(r"t = ([\d.]+) s", box.inner_text()).group(1)) > t0
                    )
                ), f"{lesson.title}: the numbers do not move"
                if i == 0:  # 0.40 m: the fixed pelvis's knee straightens, shown live
                    assert wait_for(
                        lambda box=box: "knee nearly straight" in box.inner_text(), 40
                    ), "lesson 1 never showed the fixed pelvis's straight knee"
                if i == 5:  # eq. 5's 0.42 m: the fixed robot falls (and the MPC walks)
                    fell = wait_for(
                        lambda: [
                            r
                            for r in httpx.get(f"{base}/api/state", timeout=30).json()["robots"]
                            if r["falls"] >= 1
                        ],
                        60,
                    )
                    assert fell and [r["method"] for r in fell] == ["fixed"], fell
                if i in SCREENSHOTS:
                    page.set_viewport_size(LARGE)
                    time.sleep(6 if i else 3)
                    close_notice(scene)
                    for _ in range(5):  # the numbers are re-rendered twice a second
                        with contextlib.suppress(Exception):
                            box.evaluate("e => e.scrollIntoView({block: 'start'})")
                            break
                    page.screenshot(path=str(ARTIFACTS / SCREENSHOTS[i]))
                    page.set_viewport_size(SMALL)
            print(f"{time.monotonic() - t_start:5.1f} s: all lessons checked")
            # the kinematic analysis (Fig. 1-2): eq. 5 as printed beside the paper's reading
            page.set_viewport_size(LARGE)
            press(scene.get_by_text("Kinematic analysis (Fig. 1-2, eq. 1-5)"))
            drawing = scene.get_by_text("Eq. 5 as printed").first
            drawing.wait_for(state="visible", timeout=30_000)
            drawing.evaluate("e => e.scrollIntoView({block: 'center'})")
            text = drawing.locator("xpath=ancestor::div[1]").inner_text()
            assert "0.391 m" in text and "0.421 m" in text and "+33 %" in text
            time.sleep(1)
            page.screenshot(path=str(ARTIFACTS / "lesson_analysis.png"))
        finally:
            browser.close()
            logging.getLogger("app.web.view").removeHandler(errors)
    assert errors.records == [], errors.records[:3]
