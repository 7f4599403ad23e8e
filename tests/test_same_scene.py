"""Every page draws the same scene, without a browser: what the scene and the panel send is
such that a page that joins late, reloads or reconnects shows every overlay in its colour, and
no update reaches a page for a component that is gone; numbers that do not exist yet show as
a dash. (tests/test_browser_same_scene.py compares two real pages.)

viser's client builds a line's shader for one colour or for per-vertex colours when it first
draws the line, and keeps it: a line created with one colour and given per-vertex colours
later is drawn white on a page that drew it in between (the first page on a fresh server, a
page replaying the scene in two batches). So every line overlay carries per-vertex colours
from its creation on. And the client applies a batch's property updates after its removals,
so an update sent just before a removal fails on the page ("Tried to update non-existent
component"): the panel never removes a component it updates.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest
import viser

from app.bench.local_server import free_port
from app.live.loop import LiveLoop
from app.live.session import initial_intent
from app.web.overlays import PREDICTED, REFERENCE, line_color
from app.web.scene import LAYERS, SceneView, label_text
from controller.params import ControllerParams
from models.dyros_jet import SCENE_XML

PARAMS = ControllerParams().replace(walk={"n_steps": 6})


@pytest.fixture(scope="module")
def frames():
    """Frames of the three robots from standing to 2 s, paced by a fake clock."""
    intent = initial_intent(PARAMS, ["fixed", "redundancy", "mpc"])
    intent = dataclasses.replace(intent, anchor=(0.0, 0.0), start_clock=0.1)
    out: list = []
    wall = [0.0]

    def sleep(s: float) -> None:
        wall[0] += s

    loop = LiveLoop(lambda: intent, out.append, clock=lambda: wall[0], sleep=sleep)
    while not out or out[-1].clock < 2.0:
        loop.iterate()
    return out


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    yield s
    s.stop()


def line_handles(scene: SceneView) -> dict:
    return {
        k: ov.handle
        for k, ov in scene.ov.items()
        if type(ov.handle).__name__ == "LineSegmentsHandle"
    }


def per_vertex(handle) -> bool:
    colors, points = np.asarray(handle.colors), np.asarray(handle.points)
    return colors.shape == points.shape and colors.dtype == np.uint8


def test_every_line_overlay_has_a_colour_per_vertex_from_its_creation(server, frames):
    scene = SceneView(server, mujoco.MjModel.from_xml_path(str(SCENE_XML)))
    lines = line_handles(scene)
    assert {"prediction", "reach", "footholds", "falls", "support", "swing", "sticks"} <= set(lines)
    assert all(per_vertex(h) for h in lines.values()), {
        k: np.asarray(h.colors).shape for k, h in lines.items()
    }
    for key in LAYERS:
        scene.set_layer(key, True)
    scene.set_sticks(True)
    for f in frames[::10]:
        scene.draw(dataclasses.replace(f, paused=True))  # paused: every overlay is drawn
        bad = {k: np.asarray(h.colors).shape for k, h in lines.items() if not per_vertex(h)}
        assert not bad, (f.clock, bad)
    # and the colours mean something: the prediction is PREDICTED and REFERENCE, not white
    colours = {tuple(c) for c in np.asarray(lines["prediction"].colors).reshape(-1, 3)}
    assert line_color(PREDICTED) in colours and line_color(REFERENCE) in colours


def test_a_label_shows_a_dash_until_a_number_exists(frames):
    fresh = frames[0]  # before the robots started: nothing measured yet
    r = fresh.robots[0]
    assert np.all(np.isnan(r.reach))
    text = label_text(r, fresh)
    assert "nan" not in text.lower() and "reach left – · right –" in text
    walking = frames[-1].robots[0]
    assert "nan" not in label_text(walking, frames[-1]).lower()
    assert f"reach left {walking.reach[0]:.2f}" in label_text(walking, frames[-1])


def test_the_plots_hide_a_set_they_leave_and_never_remove_one(server, frames):
    """Robots shown change (a lesson, a frame before every robot of a session arrived): the
    plots of the robots shown are shown, the others hidden, none removed; a set comes back
    as it was."""
    from app.live.session import SessionView
    from app.web.plots import LivePlots

    removed: list = []
    sim = SessionView(initial_intent(PARAMS, ["fixed", "mpc"]))  # only its history is read
    plots = LivePlots(server.gui, sim)
    three = frames[-1]
    one = dataclasses.replace(three, robots=three.robots[2:])
    plots.update(three, 0.0)
    first = dict(plots.handles)
    for h in first.values():
        original = h.remove
        h.remove = lambda original=original: (removed.append(1), original())[1]
    plots.update(one, 1.0)
    # the sets by their robots: (key, strategy) each
    assert set(plots._sets) == {
        (("fixed", "fixed"), ("redundancy", "redundancy"), ("mpc", "mpc")),
        (("mpc", "mpc"),),
    }
    assert all(not h.visible for h in first.values())
    assert all(h.visible for h in plots.handles.values())
    plots.update(three, 2.0)
    assert plots.handles == first and all(h.visible for h in first.values())
    assert not removed
