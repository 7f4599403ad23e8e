"""Camera views fit every robot shown, whatever their number and the browser's aspect."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from app.web.camera import CAMERA_VIEWS, ROBOT_SPACING, camera_pose, label_point, slot_offset


@pytest.mark.parametrize("name", list(CAMERA_VIEWS))
@pytest.mark.parametrize("n", [1, 2, 3, 5])
@pytest.mark.parametrize("aspect", [0.6, 1.0, 1.8])
def test_a_view_shows_every_robot_whole(name, n, aspect):
    along_x = name == "side"
    pos, look, up, fov = camera_pose(name, n, aspect, along_x)
    forward = (look - pos) / np.linalg.norm(look - pos)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    cam_up = np.cross(right, forward)
    tan_v, tan_h = math.tan(fov / 2), math.tan(fov / 2) * aspect
    for i in range(n):
        off = slot_offset(i, n)
        x, y = (off, 0.0) if along_x else (0.0, off)
        for dx in (-0.5, 0.5):  # a robot's feet, head and label corners
            for dy in (-0.3, 0.3):
                for z in (0.0, 2.2):
                    p = np.array([x + dx, y + dy, z]) - pos
                    depth = p @ forward
                    assert depth > 0
                    assert abs(p @ right) / depth <= tan_h + 1e-9, (name, n, aspect, i)
                    assert abs(p @ cam_up) / depth <= tan_v + 1e-9, (name, n, aspect, i)


def test_more_robots_move_the_camera_back():
    for name in CAMERA_VIEWS:
        d = [
            np.linalg.norm(np.subtract(*camera_pose(name, n, 1.3, name == "side")[:2]))
            for n in (1, 2, 3)
        ]
        assert d[0] < d[1] < d[2]
    assert ROBOT_SPACING > 1.0


def _pixels(name: str, n: int, aspect: float, height_px: float):
    """A function from world points to (right, up) pixels from the canvas centre."""
    pos, look, up, fov = camera_pose(name, n, aspect, name == "side")
    forward = (look - pos) / np.linalg.norm(look - pos)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    cam_up = np.cross(right, forward)
    scale = height_px / 2 / math.tan(fov / 2)

    def px(p):
        d = np.asarray(p, float) - pos
        depth = d @ forward
        return np.array([d @ right, d @ cam_up]) / depth * scale

    return px


@pytest.mark.parametrize("n", [1, 2, 3])
@pytest.mark.parametrize("aspect", [1.0, 1.5, 1.8])
@pytest.mark.parametrize("height_px", [500.0, 800.0])
def test_seen_from_above_a_label_hides_no_robot(n, aspect, height_px):
    """In the top view a label (three lines of text above its point, about 60 x 210 px)
    covers neither its robot nor another and lies inside the canvas."""
    text_h, text_w = 60.0, 210.0
    px = _pixels("top", n, aspect, height_px)
    boxes = []  # each robot's outline on the screen (|y| <= 0.325 m standing, arms included)
    for i in range(n):
        y = slot_offset(i, n)
        corners = np.array(
            [px((dx, y + dy, z)) for dx in (-0.35, 0.35) for dy in (-0.33, 0.33) for z in (0, 1.9)]
        )
        boxes.append((corners.min(axis=0), corners.max(axis=0)))
    for i in range(n):
        a = px(label_point(0.0, (0.0, slot_offset(i, n)), i, n, from_above=True))
        lo, hi = a - (text_w / 2, 0.0), a + (text_w / 2, text_h)  # text above its point
        half = np.array([height_px * aspect, height_px]) / 2
        assert np.all(np.abs(lo) <= half) and np.all(np.abs(hi) <= half), (n, aspect, i)
        for b_lo, b_hi in boxes:
            overlap = np.all(lo < b_hi) and np.all(b_lo < hi)
            assert not overlap, (n, aspect, i)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_elsewhere_labels_float_over_the_heads_at_different_heights(n):
    points = [label_point(0.3, (0.0, slot_offset(i, n)), i, n, from_above=False) for i in range(n)]
    assert all(p[2] > 1.95 for p in points)  # above the head (the robot is ~1.9 m tall)
    assert len({round(float(p[2]), 3) for p in points}) == n
    assert all(p[0] == pytest.approx(0.3) for p in points)


# -- a robot lying behind the others, and one account of the playback -------------------------
@pytest.mark.parametrize("name", list(CAMERA_VIEWS))
@pytest.mark.parametrize("n", [2, 3])
@pytest.mark.parametrize("stagger", [0.5, 1.0, 2.0])
def test_a_view_fitted_for_a_stagger_shows_robots_that_far_apart(name, n, stagger):
    """One robot lying where it fell, the others walked on: the scene centres between the
    hindmost and the foremost, and the view fitted for that stagger shows them all whole."""
    along_x = name == "side"
    pos, look, up, fov = camera_pose(name, n, 1.3, along_x, stagger)
    px = _project(pos, look, up, fov, 1.3)
    for i in range(n):
        ahead = stagger / 2 if i % 2 else -stagger / 2
        off = slot_offset(i, n)
        x, y = (off + ahead, 0.0) if along_x else (ahead, off)
        for dx in (-0.5, 0.5):
            for dy in (-0.3, 0.3):
                for z in (0.0, 2.2):
                    assert px((x + dx, y + dy, z)), (name, n, stagger, i)


def _project(pos, look, up, fov, aspect):
    """A function telling whether a world point is inside the view."""
    forward = (look - pos) / np.linalg.norm(look - pos)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    cam_up = np.cross(right, forward)
    tan_v, tan_h = math.tan(fov / 2), math.tan(fov / 2) * aspect

    def inside(p) -> bool:
        d = np.asarray(p, float) - pos
        depth = d @ forward
        return bool(
            depth > 0
            and abs(d @ right) / depth <= tan_h + 1e-9
            and abs(d @ cam_up) / depth <= tan_v + 1e-9
        )

    return inside


@pytest.fixture(scope="module")
def two_robots():
    """Frames of a real loop (fixed, mpc): one walking, one marked fallen 1 s later."""
    import dataclasses

    from app.live.loop import LiveLoop
    from app.live.session import initial_intent
    from controller.params import ControllerParams

    intent = dataclasses.replace(
        initial_intent(ControllerParams().replace(walk={"n_steps": 6}), ["fixed", "mpc"]),
        anchor=(0.0, 0.0),
    )
    frames: list = []
    wall = [0.0]

    def sleep(s: float) -> None:
        wall[0] += s

    loop = LiveLoop(lambda: intent, frames.append, clock=lambda: wall[0], sleep=sleep)
    while not frames or frames[-1].clock < 1.5:
        loop.iterate()
    loop.robots["fixed"].session.fell = True
    loop.robots["fixed"].session.fall_reason = "torso tilted over 30 deg"
    while frames[-1].clock < 2.5:
        loop.iterate()
    return frames


def test_a_fallen_robot_is_marked_and_the_view_centres_between_the_robots(two_robots):
    from app.live import FALL_HOLD_S
    from app.web.scene import follow_x, label_text, stagger_x

    f = two_robots[-1]
    fixed, mpc = f.robots
    assert fixed.fell and fixed.fell_clock is not None and not mpc.fell
    text = label_text(fixed, f)
    left = fixed.fell_clock + FALL_HOLD_S - f.clock
    assert f"FELL at t = {fixed.fell_clock:.1f} s" in text and "tilted over 30°" in text
    assert f"restart in {left:.1f} s" in text
    paused = dataclasses_replace(f, paused=True, clock=fixed.fell_clock + FALL_HOLD_S + 1)
    assert "restart when you resume" in label_text(fixed, paused)
    assert "FELL" not in label_text(mpc, f) and "step" in label_text(mpc, f)
    # the view's middle lies between the fallen robot and the walking one
    lying = (fixed.body_xpos[1:, 0].min() + fixed.body_xpos[1:, 0].max()) / 2
    assert follow_x(f.robots) == pytest.approx((lying + mpc.com[0]) / 2)
    assert stagger_x(f.robots) in (0.0, 0.5, 1.0)
    assert stagger_x(two_robots[0].robots) == 0.0  # abreast


def dataclasses_replace(obj, **kw):
    import dataclasses

    return dataclasses.replace(obj, **kw)


@pytest.fixture(scope="module")
def panel_view(live_pool):
    """A live session, its API and the panel of a viser view on it (no browser)."""
    import viser
    from fastapi.testclient import TestClient

    from app.bench.local_server import free_port
    from app.live.registry import SessionRegistry
    from app.live.session import initial_intent
    from app.web.api import create_app
    from app.web.view import View
    from controller.params import ControllerParams

    params = ControllerParams().replace(walk={"n_steps": 20})
    sim = live_pool.open(initial_intent(params, ["fixed", "mpc"]), sid="shared")
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    registry = SessionRegistry.around(sim)
    view = View(server, sim, registry)
    app = create_app(registry)
    with TestClient(app) as client:
        yield sim, view, client
    app.state.runs.shutdown()
    server.stop()
    live_pool.close(sim)


def test_the_panel_the_state_and_the_sessions_list_agree_after_every_transition(panel_view):
    """Paused, speed, the instant shown and the timeline's range: one account in the panel,
    GET /api/state and GET /api/sessions, after pause, seek, step, seek + resume, restart
    and a new speed (the seek while paused read "Running at 1x" and "paused": false)."""
    import time

    sim, view, client = panel_view
    clock = [time.monotonic()]

    def read():
        clock[0] += 10.0  # the panel refreshes its status at most STATUS_HZ a second
        view.draw(clock[0])
        state = client.get("/api/state").json()
        listed = client.get("/api/sessions").json()["sessions"][0]
        panel = view.panel
        status = panel.status.content.splitlines()[0]
        return state, listed, panel, status

    def agree(paused: bool, sought: bool):
        state, listed, panel, status = read()
        playback = sim.playback()
        assert state["paused"] is listed["paused"] is playback.paused is paused
        assert state["speed"] == listed["speed"] == playback.speed
        assert panel.pause_button.label == ("Resume" if paused else "Pause")
        assert status.startswith("Paused" if paused else "Running"), status
        assert (state["shown_t"] is not None) is sought
        if paused:  # nothing moves: the three read the same instant and range
            assert state["shown_t"] == listed["shown_t"]
            assert state["clock"] == pytest.approx(listed["clock"])
            assert f"t = {state['clock']:.2f} s" in status
            assert panel.timeline.min == pytest.approx(state["kept"]["start"], abs=1e-3)
            assert panel.timeline.max == pytest.approx(state["kept"]["end"], abs=0.011)
            assert panel.timeline.value == pytest.approx(state["clock"], abs=1e-3)
            assert panel.timeline.disabled is False
        else:
            assert listed["shown_t"] is None and panel.timeline.disabled is True
        return state

    def done(answer: dict) -> bool:
        """A playback answer, once the loop has carried it out: within the route's wait it
        says so; on a machine too busy for that it answers false (no error) and we wait."""
        return answer["applied"] or sim.wait_applied(sim.intent, timeout=60) is not None

    f = sim.wait_frame(timeout=30)
    while f.clock < 3.0:
        f = sim.wait_frame(f.seq, timeout=30)
    agree(False, False)
    assert done(client.post("/api/sim/pause").json())
    state = agree(True, False)
    target = (state["kept"]["start"] + state["kept"]["end"]) / 2
    assert client.post("/api/sim/seek", json={"t": target}).status_code == 200
    state = agree(True, True)
    assert state["shown_t"] == sim.frames.nearest(target).clock  # the kept instant nearest
    assert "replaying" in read()[3]
    assert done(client.post("/api/sim/step").json())  # back to the present, one tick on
    state = agree(True, False)
    assert state["clock"] == pytest.approx(state["kept"]["end"])
    client.post("/api/sim/seek", json={"t": target})
    assert done(client.post("/api/sim/resume").json())
    state = agree(False, False)
    # running, the timeline spans what is kept now, not the range it had when paused
    f = sim.wait_frame(sim.frame().seq, timeout=30)
    while f.clock < state["kept"]["end"] + 1.0:
        f = sim.wait_frame(f.seq, timeout=30)
    # the end of what is kept moves on while the view draws: the timeline's end lies between
    # what was kept just before the draw and just after (rounded to 1 ms)
    before = sim.playback().kept[1]
    clock[0] += 10.0
    view.draw(clock[0])
    after = sim.playback().kept[1]
    panel = view.panel
    assert before - 1e-3 <= panel.timeline.max <= after + 1e-3, (before, after)
    assert before > state["kept"]["end"] + 1.0 - 1e-9  # the range it has now, not when paused
    assert panel.timeline.value == pytest.approx(panel.timeline.max)
    assert done(client.post("/api/sim/reset").json())
    agree(False, False)
    assert done(client.post("/api/sim/pause").json())
    assert done(client.post("/api/sim/reset").json())  # a restart while paused stays paused
    agree(True, False)
    client.post("/api/sim/resume")
    assert done(client.put("/api/sim/speed", json={"speed": 2.0}).json())
    assert agree(False, False)["speed"] == 2.0
    assert "Running at 2x" in read()[3]
    client.put("/api/sim/speed", json={"speed": 1.0})


def test_a_move_in_the_browser_survives_an_intent_change_before_its_callback(panel_view):
    """viser sets a control's value when the viewer moves it and runs its callback later, on
    another thread. An unrelated intent change drawn in between (a new speed here; on a busy
    machine the time base moving) must not set the control back: the slider snapped back and
    the move was lost. The same for the timeline dragged while paused."""
    import time

    sim, view, _client = panel_view
    panel = view.panel
    clock = [time.monotonic()]

    def draw():
        clock[0] += 10.0
        view.draw(clock[0])

    handle, log = panel.controls[("walk", "step_length")]
    assert not log
    before = sim.intent.params.walk.step_length
    target = round(before + 0.05, 2)
    draw()
    assert handle.value == before
    try:
        handle._impl.value = target  # what viser does with the viewer's message, first
        sim.wait_applied(sim.set_speed(1.5), 60)  # then an unrelated change is drawn
        draw()
        assert handle.value == target, "the control was set back over the viewer's move"
        panel._param_changed("walk", "step_length")  # the callback runs at last
        assert sim.intent.params.walk.step_length == target
        draw()
        assert handle.value == target
        # a change from elsewhere (the API, another viewer) still moves the control
        sim.wait_applied(sim.update_params(walk={"step_length": before}), 60)
        draw()
        assert handle.value == before

        f = sim.wait_frame(timeout=30)
        while f.clock < 3.0:  # something kept to seek in
            f = sim.wait_frame(f.seq, timeout=30)
        assert sim.wait_applied(sim.pause(), 60)
        draw()
        kept = sim.playback().kept
        mid = round((kept[0] + kept[1]) / 2, 2)
        panel.timeline._impl.value = mid  # dragged while paused, the callback not yet run
        sim.wait_applied(sim.set_speed(1.0), 60)
        draw()
        assert panel.timeline.value == mid
        panel._seek()
        assert sim.playback().shown_t == sim.frames.nearest(mid).clock  # where it was dragged
        assert abs(sim.playback().shown_t - mid) < (kept[1] - kept[0]) / 4
    finally:
        sim.update_params(walk={"step_length": before})
        sim.set_speed(1.0)
        sim.wait_applied(sim.resume(), 60)


def test_a_students_panel_is_read_only_and_says_why(panel_view, monkeypatch):
    """With an instructor, a student's view of the shared demo: every control that changes
    the session is disabled, a click that still arrives is refused with a message, and what
    is the viewer's own (camera, layers, recording) stays enabled."""
    import threading

    import viser

    from app.bench.local_server import free_port
    from app.live.registry import SessionRegistry
    from app.web.lessons import PRESETS
    from app.web.panel import READ_ONLY_NOTE, REFUSED
    from app.web.view import View

    sim, _view, _client = panel_view
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        view = View(server, sim, SessionRegistry.around(sim), read_only=True)
        panel = view.panel
        assert READ_ONLY_NOTE in panel.notice.content and panel.notice.visible
        assert panel.writers and all(h.disabled for h in panel.writers)
        assert panel.controls[("walk", "step_length")][0].disabled
        assert panel.step_row._impl.props.disabled  # the single-step buttons look off too
        assert all(b.disabled for b in panel.learn.buttons)
        assert not any(b.disabled for b in panel.layer_boxes.values())
        assert not panel.record.button.disabled
        # who changes the session's intent: its loop does by itself (a restart when a plan
        # ends, the time base moving after a late loop), a click that got through would here
        writers: list[str] = []
        modify = sim._box.modify  # noqa: SLF001 - the one place intent changes

        def spy(changes_of):
            writers.append(threading.current_thread().name)
            return modify(changes_of)

        monkeypatch.setattr(sim._box, "modify", spy)  # noqa: SLF001
        panel._step("5 ms tick")
        panel._toggle_pause()
        panel.learn.start(5)
        panel.apply_preset(next(iter(PRESETS)))
        here = threading.current_thread().name
        assert here not in writers  # nothing reached the session
        assert panel._message == REFUSED
        sim.set_speed(sim.intent.speed)  # (the spy sees a change made here)
        assert here in writers
    finally:
        server.stop()


def test_a_stopped_loop_is_said_in_the_status(panel_view):
    """A loop that died (its part's thread raised) leaves the last frame on screen: the
    status says so rather than leaving a frozen view to puzzle the class."""
    sim, view, _client = panel_view
    sim.error = "RuntimeError: a test's loop stopped"
    try:
        assert any("the simulation stopped: RuntimeError" in a for a in view.alerts())
    finally:
        sim.error = None


def test_no_two_slider_marks_share_a_place_and_presets_read_whole(panel_view):
    """Tick labels of a slider never lie on each other (beta_pel's paper value is its
    slider's lower end: one mark says both), and the preset buttons' labels are short
    enough to read whole in the docked panel."""
    from app.web.lessons import PRESETS
    from app.web.plots import log_axis

    _sim, view, _client = panel_view
    for (group, name), (handle, _log) in view.panel.controls.items():
        marks = getattr(getattr(handle, "_impl", None), "props", None)
        marks = [(m.value, m.label) for m in (getattr(marks, "_marks", None) or ())]
        if not marks:
            continue
        at = sorted(m[0] for m in marks)
        span = handle.max - handle.min
        assert all(b - a >= 0.12 * span for a, b in zip(at, at[1:], strict=False)), (
            group,
            name,
            marks,
        )
    beta = view.panel.controls[("pelvis", "beta")][0]._impl.props._marks
    assert any("paper" in (m.label or "") and "1e-10" in (m.label or "") for m in beta), beta
    assert all(len(name) <= 40 for name in PRESETS), list(PRESETS)
    axis = log_axis(1.0, 1e4)  # the top decade, the plot's edge, is left unlabelled
    assert axis["values"][-1] == "" and axis["values"][-2] == "1e3"


# -- labels inside the frame, stopped robots in view --------------------------------
LABEL_W = 280.0  # [px] the widest label line (48 characters of a wrapped error, 13 px font)


@pytest.mark.parametrize("name", ["follow", "side", "front"])
@pytest.mark.parametrize("n", [2, 3, 4, 5])
@pytest.mark.parametrize("size", [(640, 820), (800, 700), (1000, 860), (1400, 900)])
def test_every_label_lies_inside_the_frame(name, n, size):
    """The outer robots' labels extend toward the middle (with four robots the leftmost,
    centred over its head, was cut: "et line ahead · clean"); the others are centred."""
    from app.web.scene import label_anchors

    width, height = size
    along_x = name == "side"
    px = _pixels(name, n, width / height, height)
    offsets = np.array(
        [(-slot_offset(i, n), 0.0) if along_x else (0.0, slot_offset(i, n)) for i in range(n)]
    )
    anchors = label_anchors(name, offsets)
    for i, anchor in enumerate(anchors):
        x = px(label_point(0.0, tuple(offsets[i]), i, n, from_above=False))[0]
        lo = {"bottom-left": x, "bottom-right": x - LABEL_W}.get(anchor, x - LABEL_W / 2)
        assert -width / 2 <= lo and lo + LABEL_W <= width / 2, (name, n, size, i, anchor)


def test_the_camera_is_fitted_again_when_the_number_of_robots_changes(two_robots):
    """Four robots in a camera fitted for three put the outermost at the frame's edge."""
    import mujoco
    import viser

    from app.bench.local_server import free_port
    from app.web.scene import SceneView
    from models.dyros_jet import SCENE_XML

    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        scene = SceneView(server, mujoco.MjModel.from_xml_path(str(SCENE_XML)))
        f = two_robots[0]  # two robots
        scene.draw(f)
        two = camera_pose("follow", 2, 1.3, False)[0]
        assert np.allclose(server.initial_camera.position, two)
        r = f.robots[0]
        more = tuple(
            dataclasses_replace(r, method=m, slot=i)
            for i, m in enumerate(("fixed", "redundancy", "mpc", "fixed")[:3])
        )
        scene.draw(dataclasses_replace(f, robots=more))
        three = camera_pose("follow", 3, 1.3, False)[0]
        assert np.allclose(server.initial_camera.position, three)
    finally:
        server.stop()


def test_a_stopped_robot_stays_in_view_with_its_message(two_robots):
    """A robot its strategy stopped stands where it stopped until the restart: the view
    centres between it and the walkers and is fitted for their stagger, as for a fall, and
    its label says why it stopped."""
    from app.web.scene import follow_x, label_text, stagger_x

    f = two_robots[-1]
    fixed, mpc = two_robots[0].robots[0], f.robots[1]  # fixed stopped at the start
    stopped = dataclasses_replace(fixed, error="ZeroDivisionError: division by zero (mine.py:3)")
    mpc = dataclasses_replace(mpc, com=mpc.com + np.array([2.5, 0.0, 0.0]))  # walked on
    robots = (stopped, mpc)
    assert follow_x(robots) == pytest.approx((stopped.com[0] + mpc.com[0]) / 2)
    assert stagger_x(robots) >= mpc.com[0] - stopped.com[0]
    text = label_text(stopped, dataclasses_replace(f, robots=robots))
    assert "STOPPED" in text and "ZeroDivisionError" in text
    # far apart, the view zoomed out: the labels shorten, the message stays
    crowded = dataclasses_replace(f, robots=robots)
    short = label_text(stopped, crowded, compact=True)
    assert "STOPPED" in short and "ZeroDivisionError" in short and "Restart" not in short
    assert "\n" not in label_text(mpc, crowded, compact=True)
    for name in CAMERA_VIEWS:  # the view fitted for that stagger holds both
        along_x = name == "side"
        pos, look, up, fov = camera_pose(name, 2, 1.3, along_x, stagger_x(robots))
        inside = _project(pos, look, up, fov, 1.3)
        centre = follow_x(robots)
        for r, slot in zip(robots, (0, 1), strict=True):
            off = slot_offset(slot, 2)
            x = r.com[0] - centre + (-off if along_x else 0.0)
            y = 0.0 if along_x else off
            assert inside((x, y, 1.0)), (name, slot)


def test_the_inspect_tab_lists_the_robots_by_their_labels(panel_view):
    """As every legend names them ("pelvic MPC"), not by internal name ("mpc")."""
    import time

    from pelvic_walk.core.methods import METHOD_INFO

    sim, view, _client = panel_view
    assert sim.wait_frame(timeout=60) is not None
    view.draw(time.monotonic() + 1000.0)
    inspector = view.panel.inspector
    titles = tuple(METHOD_INFO[m].title for m in ("fixed", "mpc"))
    assert tuple(inspector.robot.options) == titles
    assert inspector.robot.value == METHOD_INFO["mpc"].title


def test_the_colour_words_are_those_of_the_colours_drawn():
    """Lesson 1 said the swing leg "turns red" where it read pinkish; the page, the lessons
    and the layers' names now use the words of the colours drawn (app.web.overlays)."""
    import re

    from app.web.api.pages import WORDS
    from app.web.lessons import EXPLAIN, LESSONS
    from app.web.overlays import COLOUR_NAMES, DANGER, LEG_GREY, reach_color
    from app.web.scene import LAYERS

    ROOT = Path(__file__).resolve().parents[1]

    assert reach_color(1.0) == DANGER and reach_color(0.5) == LEG_GREY  # what the legs show
    lesson1 = LESSONS[0].watch
    assert f"turn {COLOUR_NAMES[DANGER]}" in lesson1, lesson1
    page = (ROOT / "static" / "index.html").read_text(encoding="utf-8")
    for key, words in WORDS.items():
        page = page.replace(f"{{{{{key}}}}}", words)
    texts = [
        *(lesson.watch for lesson in LESSONS),
        *EXPLAIN.values(),
        *(label for label, _on in LAYERS.values()),
        page,
    ]
    # colour words no overlay or gauge is drawn in ("orange-red" says what vermilion is)
    stale = re.compile(r"(?<![-\w])(red|crimson|purple|pink|pinkish|magenta|teal)(?![-\w])", re.I)
    found = [(m.group(0), t[max(0, m.start() - 30) : m.end() + 10]) for t in texts
             for m in stale.finditer(t)]  # fmt: skip
    assert not found, found
