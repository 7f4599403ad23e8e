"""The robots' and the overlays' colours as Chromium renders them (docs/TEACHING.md, "Colours").

viser's client lights an instance colour brightly (grey 128 showed as 210, the MPC's orange as
yellow), so the colours a student sees are not the ones sent. Here each robot's torso colour
goes through :func:`app.web.robot_meshes.mesh_color` and the same batched-mesh call as the
robots (a sphere per robot, lit as the scene lights them), Chromium renders it, and the colour
where each sphere faces the camera is read back: it must be the robot's colour (the legends
and plots use that one) and every pair must stay ``tests/test_colours.py``'s distance apart
under normal vision, deuteranopia, protanopia, tritanopia and in grayscale. The overlays'
colours likewise, drawn as thick lines through :func:`app.web.overlays.line_color` (a line's
colour is taken as linear light and tone-mapped too: the crimson reference read pink).
"""

from __future__ import annotations

import itertools
import time

import numpy as np
import pytest
from browser_util import CHROME_ARGS, CHROMIUM, close_notice, free_port, needs_chromium
from test_colours import MIN_DELTA_E, SIMULATIONS, delta_e, overlay_colours, robot_colours

pytestmark = needs_chromium

MATCH_DELTA_E = 12.0  # [CAM02-UCS] a rendered torso at most this far from its legend colour
BODY = (191, 191, 204)  # the limbs' colour (models/dyros_jet), through mesh_color too


def settled(canvas, timeout: float = 90.0) -> bytes:
    """A screenshot of the canvas once two taken 2 s apart agree (the environment map has
    loaded and the frame settled: a busy machine takes longer)."""
    deadline = time.monotonic() + timeout
    last = None
    while True:
        time.sleep(2.0)
        png = canvas.screenshot(timeout=120_000)
        import io

        from PIL import Image

        now = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
        if last is not None and last.shape == now.shape and np.abs(now - last).max() <= 3:
            return png
        if time.monotonic() > deadline:
            pytest.fail("the rendered canvas never settled")
        last = now


def render_spheres(colours: list[tuple[int, int, int]]) -> list[tuple[int, int, int]]:
    """Each colour on a sphere drawn as the robots are; the median colour of a disc around
    each sphere's centre as Chromium shows it."""
    import trimesh
    import viser
    from PIL import Image
    from playwright.sync_api import sync_playwright

    from app.web.robot_meshes import mesh_color

    vs = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        vs.scene.set_up_direction("+z")
        sphere = trimesh.creation.icosphere(subdivisions=3)
        n = len(colours)
        d = np.array((0.74, -0.55, 0.38))  # the follow view's direction (app.web.camera)
        d /= np.linalg.norm(d)
        u = np.array((0.0, 0.0, 1.0)) - d[2] * d
        u /= np.linalg.norm(u)
        right = np.cross(u, d)
        width, height, dist = 1700, 300, 60.0
        fov = 2 * np.arctan(1.6 / dist)
        px_per_m = height / 2 / np.tan(fov / 2) / dist
        ks = [2.3 * (i - (n - 1) / 2) - 1.5 for i in range(n)]  # left of viser's panel
        vs.scene.add_batched_meshes_simple(
            "/spheres",
            sphere.vertices,
            sphere.faces,
            batched_wxyzs=np.tile([1.0, 0, 0, 0], (n, 1)),
            batched_positions=np.array([right * k for k in ks]),
            batched_colors=np.array([mesh_color(c) for c in colours], np.uint8),
            lod="off",
        )
        vs.initial_camera.position = tuple(d * dist)
        vs.initial_camera.look_at = (0.0, 0.0, 0.0)
        vs.initial_camera.fov = fov
        vs.initial_camera.up = (0.0, 0.0, 1.0)
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROME_ARGS)
            try:
                page = browser.new_context(viewport={"width": width, "height": height}).new_page()
                page.goto(f"http://127.0.0.1:{vs.get_port()}/")
                canvas = page.locator("canvas").first
                canvas.wait_for(state="visible", timeout=120_000)
                close_notice(page)
                png = settled(canvas)
            finally:
                browser.close()
    finally:
        vs.stop()
    import io

    im = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(float)
    h, w = im.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w]
    out = []
    for k in ks:
        cx, cy, r = w / 2 + k * px_per_m, h / 2, 0.4 * px_per_m
        disc = (xx - cx) ** 2 + (yy - cy) ** 2 <= r * r
        out.append(tuple(int(v) for v in np.median(im[disc], axis=0)))
    return out


@pytest.fixture(scope="module")
def rendered():
    colours = robot_colours()
    shown = render_spheres([*colours.values(), BODY])
    return dict(zip([*colours, "limbs"], shown, strict=True)), colours


def test_a_torso_shows_its_robots_colour(rendered):
    shown, colours = rendered
    off = {
        name: (colours[name], shown[name], round(delta_e(colours[name], shown[name], "normal"), 1))
        for name in colours
        if delta_e(colours[name], shown[name], "normal") > MATCH_DELTA_E
    }
    assert not off, f"rendered torsos far from their colours: {off}"


@pytest.mark.parametrize("how", SIMULATIONS)
def test_the_rendered_robot_colours_stay_apart(rendered, how):
    shown, colours = rendered
    close = [
        (a, b, round(delta_e(shown[a], shown[b], how), 1))
        for a, b in itertools.combinations(colours, 2)
        if delta_e(shown[a], shown[b], how) < MIN_DELTA_E
    ]
    assert not close, f"{how}: rendered robot colours closer than {MIN_DELTA_E}: {close} {shown}"


def render_lines(colours: list[tuple[int, int, int]]) -> list[tuple[int, int, int]]:
    """Each colour as a thick line drawn as the overlays are (from the top, on white); the
    median colour across the middle of each line as Chromium shows it."""
    import io

    import viser
    from PIL import Image
    from playwright.sync_api import sync_playwright

    from app.web.overlays import vertex_colors

    vs = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        n = len(colours)
        ys = [0.8 * (i - (n - 1) / 2) for i in range(n)]
        pts = np.array([[[-3.0, y, 0.0], [3.0, y, 0.0]] for y in ys], np.float32)
        cols = np.concatenate([vertex_colors(c, 1) for c in colours])
        vs.scene.add_line_segments("/lines", pts, cols, thickness=16, thickness_units="screen")
        vs.initial_camera.position = (0.0, 0.0, 15.0)
        vs.initial_camera.look_at = (0.0, 0.0, 0.0)
        vs.initial_camera.up = (0.0, 1.0, 0.0)
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROME_ARGS)
            try:
                page = browser.new_context(viewport={"width": 900, "height": 700}).new_page()
                page.goto(f"http://127.0.0.1:{vs.get_port()}/")
                canvas = page.locator("canvas").first
                canvas.wait_for(state="visible", timeout=120_000)
                close_notice(page)
                png = settled(canvas)
            finally:
                browser.close()
    finally:
        vs.stop()
    im = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(float)
    column = im[:, im.shape[1] // 2]
    rows = [y for y in range(len(column)) if np.abs(column[y] - 255).max() > 3]
    groups: list[list[int]] = []
    for y in rows:
        if groups and y - groups[-1][-1] <= 1:
            groups[-1].append(y)
        else:
            groups.append([y])
    assert len(groups) == n, f"{len(groups)} lines seen, {n} drawn"
    out = []
    for g in groups[::-1]:  # the first colour lies lowest on the screen
        mid, x = g[len(g) // 2], im.shape[1] // 2
        patch = im[mid - 2 : mid + 3, x - 30 : x + 30].reshape(-1, 3)
        out.append(tuple(int(v) for v in np.median(patch, axis=0)))
    return out


@pytest.fixture(scope="module")
def rendered_lines():
    colours = overlay_colours()
    return dict(zip(colours, render_lines(list(colours.values())), strict=True)), colours


def test_an_overlay_shows_its_colour(rendered_lines):
    shown, colours = rendered_lines
    off = {
        name: (colours[name], shown[name], round(delta_e(colours[name], shown[name], "normal"), 1))
        for name in colours
        if delta_e(colours[name], shown[name], "normal") > MATCH_DELTA_E
    }
    assert not off, f"rendered overlays far from their colours: {off}"


@pytest.mark.parametrize("how", SIMULATIONS)
def test_the_rendered_overlay_colours_stay_apart(rendered_lines, how):
    shown, colours = rendered_lines
    close = [
        (a, b, round(delta_e(shown[a], shown[b], how), 1))
        for a, b in itertools.combinations(colours, 2)
        if delta_e(shown[a], shown[b], how) < MIN_DELTA_E
    ]
    assert not close, f"{how}: rendered overlay colours closer than {MIN_DELTA_E}: {close}"
