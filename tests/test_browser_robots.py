"""Real-browser test of two robots of one strategy side by side: lesson 4 shows two MPC robots
(k_pel 0.25 and 0.45) with their labels; "Sliders act on" chooses one of them, and a slider
moved in the page then changes that robot's parameters only (read back through
``GET /api/state``, which gives each robot's walk parameters in force, and the session).

Screenshots go to ``tests/artifacts/`` (robots_lesson4.png: the scene's labels;
robots_sliders.png: the panel with the sliders' target; robots_compare.png: the Compare
folder; robots_inspect.png: the Inspect tab; robots_added.png and robots_removed.png: the
Compare folder after adding a robot and removing the one the sliders acted on), for people
to look at.
"""

from __future__ import annotations

import re
import time

import pytest
from browser_util import (
    chromium,
    click_slider,
    get,
    needs_chromium,
    open_folder,
    open_scene,
    open_tab,
    press,
    screenshot,
    scroll_into_view,
    wait_robots,
    wait_until,
)

from app.web.lessons import LESSONS

pytestmark = needs_chromium
VIEWPORT = {"width": 1300, "height": 820}


def test_lesson_4_two_mpcs_and_a_slider_aimed_at_one(tmp_path):
    from browser_util import in_process

    lesson = LESSONS[3]
    keys = ("mpc", "k_pel 0.45")
    assert lesson.robots() == keys
    with in_process() as tool, chromium() as browser:
        page, scene = open_scene(browser, tool.base + "/", VIEWPORT)
        panel = tool.display.views[None].panel
        session = tool.display.views[None].session
        open_tab(scene, "Learn")
        pressed: list[float] = []

        def started():
            if session.intent.methods == keys and panel.learn.lesson is lesson:
                return True
            if not pressed or time.monotonic() - pressed[-1] > 20.0:  # a click dropped
                button = scene.get_by_role("button", name=lesson.title).first
                scroll_into_view(button)
                press(button)
                pressed.append(time.monotonic())
            return False

        wait_until(started, "lesson 4's two robots", every=1.0)
        wait_until(
            lambda: [r["method"] for r in get(tool.base, "state")["robots"]] == list(keys),
            "GET /api/state to name both robots by their labels",
        )
        wait_robots(tool.base, "both robots walking", lambda r: r["step_index"] >= 1)
        # the lesson's table names both, with the setting that differs
        box = scene.locator(".lesson-live").first
        wait_until(lambda: "k_pel=0.45" in box.inner_text(), "the table's differing settings")
        text = box.inner_text()
        assert "pelvic MPC" in text and "k_pel 0.45" in text and "k_pel=0.25" in text
        # the scene's labels: marker, label and the setting that differs
        # the scene's labels (drawn in WebGL: read as the display sent them)
        drawn = tool.display.views[None].scene

        def labels() -> list[str]:
            return [str(x.handle.text).split("\n")[0] for x in drawn.labels]

        wait_until(
            lambda: (
                (t := labels())[0].startswith("● pelvic MPC · k_pel=0.25 · clean")
                and t[1].startswith("○ k_pel 0.45 · clean")
            ),
            "the scene's labels of both robots",
        )
        screenshot(page, "robots_lesson4.png")

        # the sliders act on the second robot
        open_tab(scene, "Controls")
        target = scene.locator("label", has_text="Sliders act on").first
        scroll_into_view(target)
        field = scene.locator(f'[id="{target.get_attribute("for")}"]')
        chosen = []

        def aimed():
            if panel.target.value == "k_pel 0.45":
                return True
            field.first.click()
            option = scene.get_by_role("option", name="k_pel 0.45")
            if option.count():
                option.first.click()
                chosen.append(1)
            return False

        wait_until(aimed, "the sliders aimed at 'k_pel 0.45'", every=1.0)
        assert "k_pel 0.45" in scene.get_by_text("own values only", exact=False).first.inner_text()
        before = session.intent
        assert before.params.walk.step_length == pytest.approx(0.40)
        click_slider(page, scene, "Step length [m]", 0.30)
        wait_until(
            lambda: session.intent.params_of("k_pel 0.45").walk.step_length != 0.40,
            "the slider to change the chosen robot's step",
        )
        intent = session.intent
        mine = intent.params_of("k_pel 0.45")
        assert mine.walk.step_length == pytest.approx(0.30, abs=0.02)
        assert mine.pelvis.k_pel == 0.45
        assert intent.params == before.params, "the shared parameters stayed"
        assert intent.params_of("mpc").walk.step_length == pytest.approx(0.40)
        # and the walkers took it: each robot's walk parameters in force (GET /api/state)
        state = wait_until(
            lambda: (
                s
                if (s := get(tool.base, "state"))["robots"][1]["params"]["step_length"] != 0.40
                else None
            ),
            "the robot to walk with its own step length",
        )
        steps = {r["method"]: r["params"]["step_length"] for r in state["robots"]}
        assert steps["mpc"] == pytest.approx(0.40)
        assert steps["k_pel 0.45"] == pytest.approx(mine.walk.step_length)
        screenshot(page, "robots_sliders.png")
        scroll_into_view(scene.get_by_text("Add, relabel or remove a robot", exact=True))
        open_folder(scene, "Add, relabel or remove a robot", "Relabel or remove a robot:")
        scroll_into_view(scene.get_by_role("button", name="Add robot"))
        screenshot(page, "robots_compare.png")
        # the Inspect tab: its robot chosen by label, its caption with the settings that differ
        open_tab(scene, "Inspect")
        assert tuple(panel.inspector.robot.options) == ("pelvic MPC", "k_pel 0.45")
        panel.inspector.robot.value = "k_pel 0.45"
        caption = scene.get_by_text("○ k_pel 0.45 · step=0.3 m", exact=False)
        wait_until(lambda: caption.count() >= 1, "the inspector's caption of the second robot")
        screenshot(page, "robots_inspect.png")

        # a robot added from the page: one line says so (every robot restarts with it)
        open_tab(scene, "Controls")
        assert scene.get_by_text("Settings, for example:", exact=False).first.is_visible()
        for label, value, handle in (
            ("Settings", "k_pel=0.35", panel.add_settings),
            ("Label", "k 0.35", panel.add_label),
        ):
            tag = scene.locator("label", has_text=re.compile(f"^{label}$")).first
            scroll_into_view(tag)
            box = tag.locator("xpath=ancestor::div[.//input][1]").locator("input").first
            box.fill(value)
            wait_until(lambda h=handle, v=value: h.value == v, f"the {label} box's text")
        press(scene.get_by_role("button", name="Add robot"))
        wait_until(lambda: session.intent.methods == (*keys, "k 0.35"), "the robot added")
        added = scene.get_by_text("Added k 0.35; all robots restarted together", exact=False)
        wait_until(lambda: added.count() >= 1 and added.first.is_visible(), "the Add line")
        scroll_into_view(added.first)
        screenshot(page, "robots_added.png")
        # a refusal: the core's words as they come, its long list of names cut short
        box = scene.locator("label", has_text=re.compile("^Settings$")).first
        box = box.locator("xpath=ancestor::div[.//input][1]").locator("input").first
        box.fill("k=1")
        wait_until(lambda: panel.add_settings.value == "k=1", "the Settings box's text")
        press(scene.get_by_role("button", name="Add robot"))
        refused = scene.get_by_text(
            "Not added: unknown parameter 'k' (one of: walk.step_length, walk.step_time, ...)",
            exact=False,
        )
        wait_until(lambda: refused.count() >= 1, "the refusal in one short line")
        screenshot(page, "robots_refused.png")
        box.fill("")
        # the robot the sliders act on removed: they act on all robots again, and say so
        panel.edit_robot.value = "k_pel 0.45"
        press(scene.get_by_role("button", name="Remove robot"))
        wait_until(lambda: session.intent.methods == ("mpc", "k 0.35"), "the robot removed")
        # the panel aims its sliders after the session has the new robots (same callback)
        wait_until(lambda: panel.target.value == "all robots", "the sliders on all robots")
        said = scene.get_by_text("k_pel 0.45 was removed. The sliders", exact=False)
        wait_until(lambda: said.count() >= 1, "the note under 'Sliders act on'")
        scroll_into_view(said.first)
        screenshot(page, "robots_removed.png")
        page.context.close()
    assert tool.errors == [], tool.errors[:3]
