"""Colours every student tells apart, and cues that are not colour (docs/TEACHING.md, "Colours").

The scene is drawn (a :class:`~app.web.scene.SceneView` on a viser server, no browser) with the
paper's three robots and two of a student's own strategies (the palette's colours); the
colours it sends for the robots' torsos and for the overlays are then seen as normal vision,
deuteranopia, protanopia and tritanopia see them (Machado et al. 2009 at severity 100, through
colorspacious) and in grayscale (the colour's luminance as a neutral grey), and every pair of
robot colours and every pair of overlay colours must stay :data:`MIN_DELTA_E` apart in
CAM02-UCS under each. docs/TEACHING.md holds the table of every pair's distance (printed by
``python tests/test_colours.py``); a test checks it is the one these colours give.

The old palette failed it: under deuteranopia the green redundancy torso was 0.9 from the
robot's grey body in grayscale and a student's magenta 6.3 from the teal of another.
tests/test_browser_colours.py renders the torsos in Chromium and measures the colours shown.
"""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path

import mujoco
import numpy as np
import pytest
from conftest import only_builtin_strategies

ROOT = Path(__file__).resolve().parents[1]
# [CAM02-UCS delta E] every pair apart under each simulation: well beyond the 1-2 at which two
# large patches side by side stop looking alike, since a torso seen across a room and a 2 px
# line on the floor are small; the old palette's worst pairs (0.9 to 8) were the ones a class
# could not tell apart
MIN_DELTA_E = 15.0
SIMULATIONS = ("normal", "deuteranopia", "protanopia", "tritanopia", "grayscale")
_CVD = {"deuteranopia": "deuteranomaly", "protanopia": "protanomaly", "tritanopia": "tritanomaly"}


def simulate(rgb: tuple[int, int, int], how: str) -> np.ndarray:
    """An sRGB colour (0-255) as seen under ``how`` (one of SIMULATIONS), sRGB 0-255."""
    from colorspacious import cspace_convert

    c = np.asarray(rgb, float)
    if how == "normal":
        return c
    if how == "grayscale":  # its luminance Y as a neutral grey (D65 white)
        y = cspace_convert(c, "sRGB255", "XYZ100")[1]
        grey = cspace_convert(np.array([0.95047, 1.0, 1.08883]) * y, "XYZ100", "sRGB255")
        return np.clip(grey, 0, 255)
    space = {"name": "sRGB1+CVD", "cvd_type": _CVD[how], "severity": 100}
    return 255 * np.clip(cspace_convert(c / 255, space, "sRGB1"), 0, 1)


def delta_e(a: tuple[int, int, int], b: tuple[int, int, int], how: str) -> float:
    """CAM02-UCS distance of two colours as seen under ``how``."""
    from colorspacious import deltaE

    return float(deltaE(simulate(a, how), simulate(b, how), input_space="sRGB255"))


def robot_colours() -> dict[str, tuple[int, int, int]]:
    """The robots a class sees at once: the paper's three and a student's two (the palette)."""
    from controller import strategy
    from pelvic_walk.core.methods import METHOD_INFO

    out = {METHOD_INFO[m].title: METHOD_INFO[m].color for m in strategy.BUILTINS}
    for i, c in enumerate(strategy.PALETTE[:2]):
        out[f"own strategy {i + 1}"] = c
    return out


def overlay_colours() -> dict[str, tuple[int, int, int]]:
    from app.web import overlays as o

    return {
        "predicted": o.PREDICTED,
        "reference": o.REFERENCE,
        "measured": o.MEASURED,
        "plan": o.PLAN,
        "danger": o.DANGER,
    }


def table(colours: dict[str, tuple[int, int, int]]) -> str:
    """Markdown: every pair's distance under each simulation."""
    head = "| pair | " + " | ".join(SIMULATIONS) + " |"
    rows = [head, "|" + "---|" * (len(SIMULATIONS) + 1)]
    for (na, a), (nb, b) in itertools.combinations(colours.items(), 2):
        ds = " | ".join(f"{delta_e(a, b, s):.1f}" for s in SIMULATIONS)
        rows.append(f"| {na} / {nb} | {ds} |")
    return "\n".join(rows)


# -- the scene as drawn ----------------------------------------------------------------------
@pytest.fixture(scope="module")
def drawn():
    """(torso colours by method, overlay colours) the scene sends for five robots: the paper's
    three and two of a student's own strategies without a colour of their own."""
    import viser

    from app.bench.local_server import free_port
    from app.live.loop import LiveLoop
    from app.live.session import initial_intent
    from app.web.robot_meshes import mesh_color
    from app.web.scene import LAYERS, SceneView
    from controller import strategy
    from controller.params import ControllerParams
    from controller.strategy import PelvisStrategy
    from models.dyros_jet import SCENE_XML

    class OwnA(PelvisStrategy):
        name = "colours_own_a"

        def waist_rate(self, s):
            return 0.0

    class OwnB(PelvisStrategy):
        name = "colours_own_b"

        def waist_rate(self, s):
            return None

    isolated = only_builtin_strategies()
    isolated.__enter__()
    for cls in (OwnA, OwnB):
        strategy.register(cls, builtin=False)
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        methods = [*strategy.BUILTINS, OwnA.name, OwnB.name]
        params = ControllerParams().replace(walk={"n_steps": 4})
        intent = dataclasses.replace(
            initial_intent(params, methods), anchor=(0.0, 0.0), start_clock=0.1
        )
        frames: list = []
        wall = [0.0]

        def sleep(s: float) -> None:
            wall[0] += s

        loop = LiveLoop(lambda: intent, frames.append, clock=lambda: wall[0], sleep=sleep)
        while not frames or frames[-1].clock < 1.5:
            loop.iterate()
        scene = SceneView(server, mujoco.MjModel.from_xml_path(str(SCENE_XML)))
        for key in LAYERS:
            scene.set_layer(key, True)
        scene.draw(dataclasses.replace(frames[-1], paused=True))
        model = mujoco.MjModel.from_xml_path(str(SCENE_XML))
        body = {  # the limbs' colours as sent (the scene's light curve inverted, mesh_color)
            tuple(int(v) for v in mesh_color(tuple(int(255 * c) for c in model.geom_rgba[g, :3])))
            for g in range(model.ngeom)
        }
        torsos: dict[str, set] = {m: set() for m in methods}
        for handle in scene.robots.handles.values():
            colours = np.asarray(handle.batched_colors).reshape(len(methods), -1, 3)
            for m, rows in zip(methods, colours, strict=True):
                torsos[m] |= {tuple(int(v) for v in c) for c in rows} - body
        lines = {
            tuple(int(v) for v in c)
            for k in ("prediction", "falls", "footholds")
            for c in np.asarray(scene.ov[k].handle.colors).reshape(-1, 3)
        }
        yield torsos, lines, frames[-1], scene
    finally:
        server.stop()
        for cls in (OwnA, OwnB):
            strategy.unregister(cls.name)
        isolated.__exit__(None, None, None)


def test_the_scene_draws_each_robot_in_its_colour_and_the_overlays_in_theirs(drawn):
    from app.web.overlays import DANGER, PLAN, PREDICTED, REFERENCE, line_color
    from app.web.robot_meshes import mesh_color
    from pelvic_walk.core.methods import METHOD_INFO

    torsos, lines, _frame, _scene = drawn
    for m, colours in torsos.items():  # sent so that it shows as the robot's colour when lit
        assert colours == {tuple(int(v) for v in mesh_color(METHOD_INFO[m].color))}, (m, colours)
    shown = {METHOD_INFO[m].color for m in torsos}
    assert shown == set(robot_colours().values())  # the ones measured below
    assert {line_color(c) for c in (PREDICTED, REFERENCE, PLAN)} <= lines, lines
    assert DANGER in overlay_colours().values()


@pytest.mark.parametrize("how", SIMULATIONS)
def test_every_pair_of_robot_colours_stays_apart(how):
    close = [
        (a, b, round(delta_e(ca, cb, how), 1))
        for (a, ca), (b, cb) in itertools.combinations(robot_colours().items(), 2)
        if delta_e(ca, cb, how) < MIN_DELTA_E
    ]
    assert not close, f"{how}: robot colours closer than {MIN_DELTA_E}: {close}"


@pytest.mark.parametrize("how", SIMULATIONS)
def test_every_pair_of_overlay_colours_stays_apart(how):
    close = [
        (a, b, round(delta_e(ca, cb, how), 1))
        for (a, ca), (b, cb) in itertools.combinations(overlay_colours().items(), 2)
        if delta_e(ca, cb, how) < MIN_DELTA_E
    ]
    assert not close, f"{how}: overlay colours closer than {MIN_DELTA_E}: {close}"


@pytest.mark.parametrize("how", SIMULATIONS[:4])
def test_a_torso_stands_out_from_the_robots_grey_body(how):
    """Under each deficiency a torso is not the grey of the limbs (the green one was, under
    deuteranopia). In grayscale the orange and yellow torsos come within 11 of the limbs'
    lightness: there the torso's place on the robot and the label's marker tell them."""
    body = (191, 191, 204)  # the limbs (models/dyros_jet)
    for name, c in robot_colours().items():
        assert delta_e(c, body, how) >= MIN_DELTA_E, (how, name, delta_e(c, body, how))


def test_the_table_in_teaching_md_is_the_one_these_colours_give():
    text = (ROOT / "docs" / "TEACHING.md").read_text(encoding="utf-8")
    assert table(robot_colours()) in text, "python tests/test_colours.py prints the new table"
    assert table(overlay_colours()) in text, "python tests/test_colours.py prints the new table"
    assert f"{MIN_DELTA_E:g}" in text


# -- cues that are not colour ----------------------------------------------------------------
def test_every_robot_has_its_own_marker_and_line_style(drawn):
    from app.web.overlays import legend_html
    from app.web.scene import label_text
    from pelvic_walk.core.methods import METHOD_INFO

    torsos, _lines, frame, scene = drawn
    infos = [METHOD_INFO[m] for m in torsos]
    assert len({i.marker for i in infos}) == len(infos)
    assert len({i.dash for i in infos}) == len(infos)
    assert len({i.mpl_marker for i in infos}) == len(infos)
    legend = legend_html()
    for r in frame.robots:  # on the label in the scene, and in the legend
        info = METHOD_INFO[r.method]
        assert label_text(r, frame).startswith(info.marker), label_text(r, frame)
        assert f"<b>{info.marker}</b>&nbsp;{info.title}" in legend
    texts = [label.handle.text for label in scene.labels]
    assert [t.split(" ", 1)[0] for t in texts] == [i.marker for i in infos]


def test_the_live_plots_draw_each_robot_in_its_own_dashes_with_its_marker():
    import viser

    from app.bench.local_server import free_port
    from app.web.plots import LivePlots
    from pelvic_walk.core.methods import METHOD_INFO

    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        plots = LivePlots(server.gui, session=None)
        methods = ("fixed", "redundancy", "mpc")
        handles = plots._make(methods)
        series = handles["waist_deg"].series
        robots = series[1:4]
        for m, s in zip(methods, robots, strict=True):
            assert s["label"] == METHOD_INFO[m].tag
            assert tuple(s.get("dash") or ()) == METHOD_INFO[m].dash
        assert len({tuple(s.get("dash") or ()) for s in robots}) == 3
    finally:
        server.stop()


if __name__ == "__main__":  # the tables of docs/TEACHING.md
    print(f"Robots (at least {MIN_DELTA_E:g} apart):\n\n{table(robot_colours())}\n")
    print(f"Overlays (at least {MIN_DELTA_E:g} apart):\n\n{table(overlay_colours())}")


def test_a_second_and_third_robot_of_one_strategy_wear_shades_told_apart():
    """Two robots of one strategy side by side (an MPC beside an MPC with a shorter horizon):
    the second wears a shade of the strategy's colour and the third another, each pair
    MIN_DELTA_E apart under every simulation; and colour is not the only cue: each has its
    own marker and dash pattern (app.web.looks)."""
    from app.web.looks import looks, shade

    for name, c in robot_colours().items():
        shades = (c, shade(c, 1), shade(c, 2))
        for a, b in itertools.combinations(shades, 2):
            for how in SIMULATIONS:
                assert delta_e(a, b, how) >= MIN_DELTA_E, (name, a, b, how)
    shown = looks([("mpc", "mpc"), ("short", "mpc"), ("long", "mpc"), ("fixed", "fixed")])
    mpcs = [shown[k] for k in ("mpc", "short", "long")]
    assert len({x.marker for x in mpcs}) == 3 and len({x.dash for x in mpcs}) == 3
    assert len({x.color for x in mpcs}) == 3
    assert [x.title for x in mpcs] == ["pelvic MPC", "short", "long"]
    assert shown["fixed"].color == robot_colours()["fixed pelvis"]
