"""The panel's robots (no browser): the Compare folder adds, removes and relabels robots (two
of one strategy side by side), says a refusal in one line and keeps the session's robots; the
sliders act on every robot or on the one chosen in "Sliders act on", and show its values; a
strategy's own parameters get their folder of sliders, shown with its robots; the scene's
labels, the plots' legends, the inspector and the lesson table name robots by their labels.

The panel is driven as viser drives it: a control's value set, then its callback run; the
view drawn (``View.draw``) reflects the intent into the controls. The session is paused: the
panel writes intent only, so nothing needs to walk (the last test runs it for the labels).
"""

from __future__ import annotations

import dataclasses
import time

import pytest

from controller import strategy
from controller.params import param
from controller.strategy import PelvisStrategy


class _Gain(PelvisStrategy):
    """A student's strategy with a parameter of its own."""

    name = "panelgain"
    label = "panel gain"

    @dataclasses.dataclass(frozen=True)
    class Params:
        k: float = param(2.0, min=0.0, max=10.0, label="gain k", help="how hard")

    def waist_rate(self, s):
        return -self.params.k * s.theta


@pytest.fixture(scope="module")
def panel_view(live_pool):
    import viser

    from app.bench.local_server import free_port
    from app.live.registry import SessionRegistry
    from app.live.session import initial_intent
    from app.web.view import View
    from controller.params import ControllerParams

    strategy.register(_Gain, builtin=False)
    params = ControllerParams().replace(walk={"n_steps": 20})
    sim = live_pool.open(initial_intent(params, ["fixed", "mpc"]), sid="shared")
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    view = View(server, sim, SessionRegistry.around(sim))
    try:
        assert sim.wait_frame(timeout=60) is not None
        sim.wait_applied(sim.pause(), 60)
        yield sim, view
    finally:
        server.stop()
        live_pool.close(sim)
        strategy.unregister(_Gain.name)


def _draw(view, clock=[0.0]) -> None:  # noqa: B006 (a clock that moves on between calls)
    clock[0] = max(clock[0] + 10.0, time.monotonic() + 1000.0)
    view.draw(clock[0])


def _run_until(sim, view, shows) -> None:
    """Let the robots walk, drawing each frame, until ``shows`` (the lesson's live box's
    text) is true (at most 120 s), then pause them."""
    live = view.panel.learn.live
    try:
        deadline = time.monotonic() + 120
        while not shows(live.content):
            assert time.monotonic() < deadline, live.content
            sim.wait_frame(timeout=30)
            _draw(view)
    finally:
        sim.wait_applied(sim.pause(), 60)


def _press(panel, text: str = "", label: str = "", name: str = "mpc") -> None:
    from pelvic_walk.core.methods import METHOD_INFO

    title = METHOD_INFO[name].title  # the dropdown shows the strategies' titles
    panel.add_strategy.value, panel.add_settings.value, panel.add_label.value = title, text, label
    panel._add_robot()


def test_robots_are_added_relabelled_removed_and_refusals_said_in_one_line(panel_view):
    sim, view = panel_view
    panel = view.panel
    _draw(view)
    _press(panel, "com.horizon=0.8", "short horizon")
    intent = sim.intent
    assert intent.methods == ("fixed", "mpc", "short horizon")
    short = intent.robot("short horizon")
    assert (short.strategy, short.overrides) == ("mpc", (("com.horizon", 0.8),))
    assert panel.compare_note.content == (
        "Added **short horizon**; all robots restarted together, on one clock."
    )
    # every registered strategy by its title (another test's loaded examples may be among them)
    titles = tuple(strategy.info(n).label for n in strategy.names())
    assert panel.add_strategy.options == titles
    assert titles[:3] == ("fixed pelvis", "redundancy", "pelvic MPC") and "panel gain" in titles
    assert intent.params_of("short horizon").com.horizon == 0.8
    assert intent.params_of("mpc").com.horizon == intent.params.com.horizon == 1.6
    _draw(view)
    assert "short horizon" in panel.robot_list.content and "H=0.8 s" in panel.robot_list.content
    # the dropdowns name the robots as the scene and legends do
    names = ("fixed pelvis", "pelvic MPC", "short horizon")
    assert tuple(panel.target.options) == ("all robots", *names)
    assert tuple(panel.edit_robot.options) == names
    assert tuple(panel.push_robot.options) == names

    # refusals: one short line in the Compare folder, as the core says them, the robots
    # unchanged; a short name read when one group has it
    for text, label, said in (
        ("com.horizon=99", "far", "com.horizon = 99.0 is above the maximum 3.0 s"),
        ("com.nonsense=1", "x", "unknown parameter 'com.nonsense' (one of: walk.step_length, "),
        ("com.horizon=1.0", "short horizon", "called 'short horizon': give one of them another"),
        ("alpha=2", "x", "'alpha' is ambiguous: write com.alpha or pelvis.alpha"),
        ("", "a,b", "label"),
    ):
        _press(panel, text, label)
        note = panel.compare_note.content
        assert note.startswith("**Not added:** ") and said in note and "\n" not in note, note
        assert "Traceback" not in note and "@LABEL" not in note and "&#x27;" not in note, note
        assert len(note) < 200, "a long message pushes the form down the panel"
        assert sim.intent.methods == ("fixed", "mpc", "short horizon")
    _press(panel, "com.horizon=1.2", "H 1.2")
    _press(panel, "", "", name="redundancy")
    _press(panel, "pelvis.k_pel=0.45", "k 0.45")
    assert len(sim.intent.robots) == 6
    _press(panel, "pelvis.k_pel=0.3", "one too many")
    assert "at most 6 robots" in panel.compare_note.content
    assert len(sim.intent.robots) == 6

    # remove, relabel (the sliders keep acting on the robot relabelled)
    for key in ("H 1.2", "redundancy", "k 0.45"):
        panel.edit_robot.value = key
        panel._remove_robot()
    assert panel.compare_note.content == "Removed **k 0.45**; the others restarted together."
    assert sim.intent.methods == ("fixed", "mpc", "short horizon")
    _draw(view)
    panel.target.value = "short horizon"
    panel._target_changed()
    panel.edit_robot.value, panel.new_label.value = "short horizon", "H 0.8"
    panel._relabel_robot()
    assert sim.intent.methods == ("fixed", "mpc", "H 0.8")
    assert sim.intent.robot("H 0.8").overrides == (("com.horizon", 0.8),)
    assert panel.target.value == "H 0.8" and panel.target_key() == "H 0.8"
    assert "short horizon is now H 0.8" in panel.target_note.content
    assert panel.compare_note.content.startswith("Relabelled **short horizon** as **H 0.8**")
    panel.edit_robot.value, panel.new_label.value = "H 0.8", "mpc"
    panel._relabel_robot()
    assert panel.compare_note.content.startswith("**Not relabelled:** two robots would both")
    assert "another label" in panel.compare_note.content
    assert sim.intent.methods == ("fixed", "mpc", "H 0.8")
    _draw(view)
    assert panel.target.value == "H 0.8"

    # the robot the sliders act on removed: they act on all robots again, and say why
    panel.edit_robot.value = "H 0.8"
    panel._remove_robot()
    assert sim.intent.methods == ("fixed", "mpc")
    assert panel.target.value == "all robots" and panel.target_key() is None
    assert tuple(panel.target.options) == ("all robots", "fixed pelvis", "pelvic MPC")
    assert panel.target_note.content.startswith("H 0.8 was removed. The sliders show and set")
    _press(panel, "com.horizon=0.8", "H 0.8")  # back as it was for the next lines

    # a strategy's checkbox: the robots with settings keep them
    panel.method_boxes["fixed"].value = False
    panel._methods_changed()
    assert sim.intent.methods == ("mpc", "H 0.8")
    assert sim.intent.robot("H 0.8").overrides == (("com.horizon", 0.8),)
    _draw(view)
    assert panel.method_boxes["mpc"].value and not panel.method_boxes["fixed"].value


def test_sliders_act_on_the_robot_chosen_or_on_all(panel_view):
    sim, view = panel_view
    panel = view.panel
    sim.wait_applied(sim.set_robots([r for r in _robots("mpc", "mpc,com.horizon=0.8@short")]))
    panel.target.value = "all robots"
    panel._target_changed()
    _draw(view)
    horizon, _log = panel.controls[("com", "horizon")]
    steps, _log = panel.controls[("walk", "step_length")]
    assert horizon.value == 1.6 and "every robot" in panel.target_note.content

    panel.target.value = "short"
    panel._target_changed()
    _draw(view)
    assert horizon.value == 0.8, "the sliders show the chosen robot's own value"
    assert "short" in panel.target_note.content and "only" in panel.target_note.content
    shared = sim.intent.params
    steps.value = 0.3  # viser sets the value and runs the callback (here, at once)
    _draw(view)
    intent = sim.intent
    assert intent.params == shared, "a slider aimed at one robot left the shared ones alone"
    assert intent.params_of("short").walk.step_length == 0.3
    assert intent.params_of("short").com.horizon == 0.8
    assert intent.params_of("mpc").walk.step_length == shared.walk.step_length
    assert steps.value == 0.3 and horizon.value == 0.8

    panel.target.value = "all robots"
    panel._target_changed()
    _draw(view)
    assert horizon.value == 1.6 and steps.value == shared.walk.step_length
    horizon.value = 1.4
    _draw(view)
    intent = sim.intent
    assert intent.params.com.horizon == 1.4
    assert intent.params_of("short").com.horizon == 1.4, "all robots: its own setting dropped"
    assert intent.params_of("short").walk.step_length == 0.3  # the other setting kept
    horizon.value = 1.6
    _draw(view)

    # a robot removed while chosen: the sliders act on all robots again
    panel.target.value = "short"
    panel._target_changed()
    sim.wait_applied(sim.set_robots(_robots("fixed", "mpc")))
    shared = sim.intent.params
    steps.value = 0.25  # moved before the view drew the change: not for every robot
    assert sim.intent.params == shared, "a slider aimed at a robot gone set every robot's"
    _draw(view)
    assert panel.target.value == "all robots" and "every robot" in panel.target_note.content
    assert panel.target_note.content.startswith("short is no longer shown. ")
    assert steps.value == shared.walk.step_length


def test_a_strategys_own_parameters_get_their_folder(panel_view):
    sim, view = panel_view
    panel = view.panel
    folder = panel.own_folders["panelgain"]
    k, log = panel.controls[("panelgain", "k")]
    assert not log and (k.min, k.max) == (0.0, 10.0) and "how hard" in k.hint
    assert "next tick" in k.hint
    sim.wait_applied(sim.set_robots(_robots("fixed", "mpc")))
    _draw(view)
    assert not folder.visible, "no robot of that strategy is shown"
    sim.wait_applied(sim.set_robots(_robots("panelgain", "panelgain,panelgain.k=5@stiff")))
    _draw(view)
    assert folder.visible and k.value == 2.0
    panel.target.value = "stiff"
    panel._target_changed()
    _draw(view)
    assert k.value == 5.0
    k.value = 7.0
    intent = sim.intent
    assert intent.params_of("stiff").value("panelgain.k") == 7.0
    assert intent.params_of("panelgain").value("panelgain.k") == 2.0
    # the built-ins' own paper parameters stay in the paper's folders: no second slider
    assert not any(g in ("mpc", "redundancy") for g, _n in panel.controls)


def test_two_robots_of_one_strategy_are_told_apart_everywhere(panel_view):
    """Labels, legends, the inspector and the lesson table name each robot by its label; the
    second of a strategy wears a shade of its colour and a hollow marker."""
    from app.web.looks import looks
    from app.web.scene import label_text

    sim, view = panel_view
    panel = view.panel
    sim.wait_applied(sim.set_robots(_robots("mpc", "mpc,com.horizon=1.2@short horizon")), 60)
    sim.wait_applied(sim.resume(), 60)
    try:
        f = sim.wait_frame(timeout=60)
        while f is None or tuple(r.method for r in f.robots) != ("mpc", "short horizon"):
            f = sim.wait_frame(f.seq if f else -1, timeout=60)
    finally:
        sim.wait_applied(sim.pause(), 60)
    _draw(view)
    look = looks(f.robots)
    a, b = look["mpc"], look["short horizon"]
    assert a.color != b.color and a.marker != b.marker and a.dash != b.dash
    assert (a.settings, b.settings) == ("H=1.6 s", "H=1.2 s")
    mine = f.robot("short horizon")
    assert label_text(mine, f).startswith(f"{b.marker} short horizon · H=1.2 s")
    assert label_text(f.robot("mpc"), f).startswith(f"{a.marker} pelvic MPC · H=1.6 s")
    assert tuple(panel.inspector.robot.options) == ("pelvic MPC", "short horizon")
    legend = [s["label"] for s in panel.plots.handles["waist_deg"].series[1:3]]
    assert legend == [a.tag, b.tag]


def test_lesson_4_shows_two_mpcs_and_the_settings_that_differ(panel_view):
    from app.web.learn_gui import LessonRun
    from app.web.lessons import LESSONS

    sim, view = panel_view
    panel = view.panel
    lesson = LESSONS[3]
    assert lesson.title.startswith("4.")
    panel.learn.start(3)
    intent = sim.intent
    assert intent.methods == ("mpc", "k_pel 0.45") == lesson.robots()
    assert [r.strategy for r in intent.robots] == ["mpc", "mpc"]
    assert intent.params_of("k_pel 0.45").pelvis.k_pel == 0.45
    assert intent.params_of("mpc").pelvis.k_pel == 0.25
    assert not intent.paused
    _run_until(sim, view, lambda live: "lesson-live" in live and "k_pel=" in live)
    table = panel.learn.live.content
    assert "pelvic MPC" in table and "k_pel 0.45" in table
    assert "k_pel=0.25" in table and "k_pel=0.45" in table
    assert isinstance(panel.learn.run, LessonRun)


def test_lesson_4_table_while_a_robot_lies_fallen(panel_view):
    """A short horizon fells the k_pel 0.45 robot (measured: H = 0.8 s falls at 1.4 s): while
    it lies, its column keeps its settings, and its fall enters none of the maxima."""
    from app.web.lessons import LESSONS

    sim, view = panel_view
    panel = view.panel
    panel.learn.start(3)
    sim.wait_applied(sim.update_params(target="k_pel 0.45", com={"horizon": 0.8}), 60)
    try:
        deadline = time.monotonic() + 120
        f = sim.wait_frame(timeout=30)
        while not (f is not None and f.robot("k_pel 0.45").fell):
            assert time.monotonic() < deadline, "the robot with H = 0.8 s did not fall"
            f = sim.wait_frame(f.seq if f else -1, timeout=30)
            _draw(view)
        for _ in range(5):  # a few frames of it lying there
            f = sim.wait_frame(f.seq, timeout=30)
            _draw(view)
    finally:
        sim.wait_applied(sim.pause(), 60)
    _draw(view)
    assert panel.learn.lesson is LESSONS[3]
    table = panel.learn.live.content
    assert "fell at t =" in table and "H=0.8 s, k_pel=0.45" in table, table
    tally = panel.learn.run.tallies["k_pel 0.45"]
    kappa, reach = tally.kappa_max, tally.reach_max
    assert 1.0 < kappa < 1e3 and 0.5 < reach < 1.0, "the fall entered a maximum"


def test_lesson_9_compares_beta_pel(panel_view):
    from app.web.lessons import LESSONS

    sim, view = panel_view
    panel = view.panel
    i = next(i for i, x in enumerate(LESSONS) if "beta_pel" in x.title)
    panel.learn.start(i)
    intent = sim.intent
    assert [r.strategy for r in intent.robots] == ["mpc", "mpc"]
    assert intent.params_of("beta_pel 0.01").pelvis.beta == 0.01
    assert intent.params_of("mpc").pelvis.beta == 1e-6
    _run_until(sim, view, lambda live: "beta_pel=0.01" in live)
    table = panel.learn.live.content
    assert "beta_pel=1e-6" in table and "beta_pel 0.01" in table
    assert "β" not in table, "one notation: the sliders' (beta_pel)"
    # the scene's tags: the label says the setting already, the plain MPC's says its value
    tags = [str(x.handle.text).split("\n")[0] for x in view.scene.labels]
    assert tags[0].startswith("● pelvic MPC · beta_pel=1e-6"), tags
    assert tags[1].startswith("○ beta_pel 0.01") and "=0.01" not in tags[1], tags


def _robots(*forms: str):
    from pelvic_walk.core import robots

    return [robots.parse(f) for f in forms]


def test_a_robots_own_setting_known_to_break_walking_is_said_with_its_name():
    from app.live.session import initial_intent
    from app.web.panel import robot_warnings

    intent = initial_intent(robots=_robots("mpc", "mpc,com.horizon=0.8@short horizon"))
    said = robot_warnings(intent)
    assert len(said) == 1 and said[0].startswith("short horizon: The MPC horizon (0.8 s)"), said
    assert robot_warnings(initial_intent(robots=_robots("mpc", "fixed"))) == []
