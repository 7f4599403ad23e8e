"""Every page draws the same scene, in real browsers: two students' pages in private mode,
loaded at different times, each on a session of its own that starts as the page connects,
show the overlays in their colours -- the sky-blue prediction and the indigo reference hip
lines -- and neither page logs an error while it loads.

(The first page of a fresh session drew those lines near-white: viser's client keeps the
shader a line was first drawn with, and the lines were created with one colour, drawn empty
until the session's first frame, and given one colour per vertex then;
tests/test_same_scene.py checks what the scene sends.)

The colours are read from screenshots of the scene: a pixel counts as sky blue or indigo by
its hue and saturation, so software rendering, fog and antialiasing change the counts but not
the verdict; each page is waited for until it shows both (a page drawing white lines never
does).
"""

from __future__ import annotations

import io

import httpx
import numpy as np
import pytest
from browser_util import (
    ARTIFACTS,
    chromium,
    close_notice,
    needs_chromium,
    serving,
    wait_until,
)

pytestmark = needs_chromium
TOKEN = "same-scene-token-5pQ"
VIEWPORT = {"width": 1500, "height": 900}  # a wide canvas beside the page and the panel
WAIT_S = 120.0
MIN_PIXELS = 12  # of each overlay colour in a scene that shows the MPC robot's hip lines


@pytest.fixture(scope="module")
def tool():
    args = ("--sessions", "private", "--instructor-token", TOKEN, "--workers", "1")
    with serving(*args, "--robots-per-worker", "3", "--methods", "mpc") as (base, _v, _p):
        yield base


def colour_counts(png: bytes) -> dict[str, int]:
    """Pixels of the overlays' hues: sky blue (predicted, 86 180 233: hue 202) and indigo
    (reference, 40 27 108: hue 251), saturated enough not to be the floor, a label or a
    robot's grey (the MPC robot alone is shown: no blue torso)."""
    from PIL import Image

    a = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(float) / 255
    hi, lo = a.max(-1), a.min(-1)
    span = np.maximum(hi - lo, 1e-9)
    r, g, b = a[..., 0], a[..., 1], a[..., 2]
    hue = np.where(
        hi == r, ((g - b) / span) % 6, np.where(hi == g, (b - r) / span + 2, (r - g) / span + 4)
    )
    hue *= 60
    strong = ((hi - lo) / np.maximum(hi, 1e-9) > 0.35) & (hi > 0.3)
    return {
        "sky blue": int((strong & (hue > 190) & (hue < 215)).sum()),
        "indigo": int((strong & (hue > 238) & (hue < 265)).sum()),
    }


def open_page(browser, url: str):
    page = browser.new_context(viewport=VIEWPORT).new_page()
    page.set_default_timeout(WAIT_S * 1000)
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(url)
    scene = page.frame_locator("#scene")
    scene.locator("canvas").first.wait_for(state="visible")
    close_notice(scene)
    return page, errors


def shows_colours(page, name: str) -> dict[str, int] | None:
    # the 3-D canvas only (the panel's legend has swatches of the same colours)
    png = page.frame_locator("#scene").locator("canvas").first.screenshot()
    counts = colour_counts(png)
    if min(counts.values()) >= MIN_PIXELS:
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        (ARTIFACTS / f"same_scene_{name}.png").write_bytes(png)
        return counts
    return None


def test_two_pages_loaded_at_different_times_draw_the_overlays_in_colour(tool):
    base = tool
    teacher = {"Authorization": f"Bearer {TOKEN}"}

    def private_sessions() -> int:
        return httpx.get(f"{base}/api/sessions", timeout=30).json()["private_sessions"]

    with chromium() as browser:
        first, first_errors = open_page(browser, f"{base}/")
        wait_until(lambda: private_sessions() == 1, "the first page's own session")
        shown_first = wait_until(
            lambda: shows_colours(first, "first"),
            "the first page to draw the prediction sky blue and the reference indigo",
            WAIT_S,
        )
        later, later_errors = open_page(browser, f"{base}/")
        wait_until(lambda: private_sessions() == 2, "the later page's own session")
        shown_later = wait_until(
            lambda: shows_colours(later, "later"),
            "the page loaded later to draw the prediction sky blue and the reference indigo",
            WAIT_S,
        )
        # the instructor sees both sessions, neither student the other's
        listed = httpx.get(f"{base}/api/sessions", headers=teacher, timeout=30).json()
        assert len([s for s in listed["sessions"] if s["kind"] == "private"]) == 2
        print(f"overlay pixels: first page {shown_first}, later page {shown_later}")
        assert not first_errors and not later_errors, (first_errors, later_errors)
