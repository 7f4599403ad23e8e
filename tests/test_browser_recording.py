"""A recording of about 10 s opens in Chromium from the files alone and shows the robots
moving ("Record and share" in the README).

``pelvic-walk simulate ... --record walk.zip`` (in this process; no server runs at any time,
and its recorder's viser server is stopped before the browser starts), unzipped; Chromium
opens ``index.html`` from ``file://``; every request it makes must stay on ``file:``,
``data:`` or ``blob:``. The scene's playback bar must run on its own; then, paused at two
instants of the recording, the scene's canvas must differ (the robots walked). Screenshots go
to ``tests/artifacts/`` (looked at by people).
"""

from __future__ import annotations

import zipfile

import numpy as np
import pytest
from browser_util import ARTIFACTS, CHROME_ARGS, CHROMIUM, close_notice, needs_chromium, wait_for
from PIL import Image

from app.cli import main
from pelvic_walk.core.methods import METHOD_INFO

pytestmark = needs_chromium
PAUSE_JS = """() => {
  const bar = [...document.querySelectorAll('.mantine-Paper-root')]
    .find(p => p.querySelector('[role=slider]'));
  bar.querySelector('button').click();
}"""


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A ~10 s headless walk (0.25 m x 6 steps) recorded to a zip and unzipped."""
    tmp = tmp_path_factory.mktemp("recording")
    out = tmp / "walk.zip"
    args = ["simulate", "--method", "mpc", "--step-length", "0.25", "--steps", "6"]
    assert main([*args, "--record", str(out)]) == 0
    with zipfile.ZipFile(out) as z:
        z.extractall(tmp)
    return tmp / "walk", out.stat().st_size


def _canvas_shot(page, frame, path):
    """A screenshot of the scene's canvas only (not the playback bar): pixels (h, w, 3)."""
    box = frame.locator("canvas").first.bounding_box()
    page.screenshot(path=str(path), clip=box)
    return np.asarray(Image.open(path).convert("RGB"), dtype=np.int16)


def test_recording_plays_from_the_files_alone(recorded):
    from playwright.sync_api import sync_playwright

    folder, zip_size = recorded
    assert zip_size < 5e6  # one robot, ~10 s
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROME_ARGS)
        try:
            page = browser.new_page(viewport={"width": 640, "height": 420})
            page.set_default_timeout(120_000)  # software WebGL on a busy machine: slow starts
            urls: list[str] = []
            page.on("request", lambda r: urls.append(r.url))
            page.goto((folder / "index.html").as_uri())
            assert page.title().startswith(f"pelvic-walk recording: {METHOD_INFO['mpc'].title}")
            scene = page.frame_locator("iframe")
            scene.locator("canvas").first.wait_for(state="visible")
            assert page.evaluate("document.querySelector('img').naturalWidth") > 0  # plots.png

            bar = scene.locator('[role="slider"]').first
            duration = float(bar.get_attribute("aria-valuemax"))
            assert 9.5 <= duration <= 12.0
            first = bar.get_attribute("aria-valuenow")
            assert wait_for(lambda: bar.get_attribute("aria-valuenow") != first, 90), (
                "the recording does not play"
            )

            inner = next(f for f in page.frames if f.url.endswith("scene.html"))
            inner.evaluate(PAUSE_JS)
            close_notice(scene)
            clock = scene.locator("input.mantine-NumberInput-input")
            shots = []
            for i, t in enumerate(("2", "7")):
                clock.fill(t)
                assert wait_for(
                    lambda t=t: (
                        float(bar.get_attribute("aria-valuenow")) == pytest.approx(float(t))
                    ),
                    30,
                ), f"the time bar did not move to {t} s"
                shots.append(_canvas_shot(page, scene, ARTIFACTS / f"recording_{i + 1}.png"))
            page.screenshot(path=str(ARTIFACTS / "recording_page.png"), full_page=True)
        finally:
            browser.close()

    a, b = shots
    assert a.shape == b.shape
    changed = np.abs(a - b).max(axis=2) > 40  # pixels that changed clearly
    assert changed.mean() > 0.005, f"only {changed.mean():.4%} of the scene changed"
    assert urls and all(u.split(":", 1)[0] in ("file", "data", "blob") for u in urls), urls
