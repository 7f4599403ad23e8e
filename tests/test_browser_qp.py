"""Real-browser test of the Inspect tab's QP view: the four layers side by side for
the chosen robot, following a seek while paused (the instant ``GET /api/qp`` explains).

Screenshots go to ``tests/artifacts/`` (looked at by people; nothing asserts on pixels).
"""

from __future__ import annotations

import pytest
from browser_util import (
    chromium,
    get,
    needs_chromium,
    open_scene,
    open_tab,
    post,
    put_params,
    screenshot,
    scroll_into_view,
    wait_robots,
    wait_until,
)

pytestmark = needs_chromium
VIEWPORT = {"width": 1400, "height": 1000}


@pytest.fixture(scope="module")
def tool():
    from browser_util import in_process

    with in_process() as tool:
        yield tool
    assert tool.errors == [], tool.errors[:3]


@pytest.fixture(scope="module")
def browser():
    with chromium() as b:
        yield b


def test_the_qp_view_follows_a_seek(tool, browser):
    base = tool.base
    put_params(base, {"methods": ["fixed", "mpc"], "walk": {"step_length": 0.42}})
    wait_robots(base, "the robots walking", lambda r: r["step_index"] >= 1, timeout=180)
    page, scene = open_scene(browser, base + "/", VIEWPORT)
    try:
        open_tab(scene, "Inspect")
        view = scene.locator(".qp-view[data-method]").first
        view.wait_for(state="attached", timeout=120_000)
        # the robots just rebuilt (new methods) show no record until their first tick is drawn
        wait_until(
            lambda: all(
                scene.locator(f'.qp-view [data-layer="{layer}"]').count() == 1
                for layer in ("com_mpc", "pelvis_mpc", "ik", "arm_swing")
            ),
            "the four layers in the QP view",
            120,
        )
        assert "What stops each optimisation" in view.inner_text()
        wait_until(
            lambda: (k := get(base, "state")["kept"]) and k["end"] - k["start"] > 4.0,
            "4 s of kept frames",
            180,
        )
        post(base, "sim/pause")
        kept = wait_until(lambda: (s := get(base, "state"))["paused"] and s["kept"], "the pause")
        for i, target in enumerate((kept["end"] - 3.0, kept["end"] - 1.0)):
            post(base, "sim/seek", {"t": target})

            def same_tick(target: float = target) -> dict | None:
                # the robot the view shows (the Inspect tab's choice: the MPC's unless the
                # client chose another) and the API's record of it at the shown instant, read
                # together: a seek on a busy machine may be applied after the first read
                method = scene.locator(".qp-view[data-method]").first.get_attribute("data-method")
                qp = get(base, f"qp?method={method}")
                shown = scene.locator(f'.qp-view[data-t="{qp["t"]:.3f}"]').count() == 1
                return qp if shown and abs(qp["clock"] - target) < 0.1 else None

            qp = wait_until(same_tick, f"the QP view to show the tick sought at {target:.2f} s")
            ik = scene.locator('.qp-view [data-layer="ik"]').first
            active = [c["name"] for c in qp["layers"][2]["active"]]
            assert int(ik.get_attribute("data-active")) == len(active)
            for name in active[:6]:
                assert ik.locator(f'li[data-name="{name}"]').count() == 1
            scroll_into_view(view)
            screenshot(page, f"qp_view_seek_{i}.png")
    finally:
        post(base, "sim/resume")  # a failed try leaves the session walking for its rerun
        page.context.close()
