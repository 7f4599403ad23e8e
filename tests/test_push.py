"""The push study (pelvic_walk/core/pushes.py) and the push API's refusals.

Short walks (4 steps, pushed in the third) keep the file fast; the README's table comes from
``pelvic-walk push-study`` with the full defaults.
"""

from __future__ import annotations

import mujoco
import pytest

import pelvic_walk.core.pushes as pushes
from app.cli import main as cli_main
from app.live.intent import PUSH_FORCE_MAX
from controller.strategy import BUILTINS as METHODS
from pelvic_walk.core.world import World

SHORT = {"n_steps": 4, "step": 2}  # push mid-SSP of the third step, two more to recover
MASS = mujoco.mj_getTotalmass(World().model)  # [kg]


@pytest.mark.parametrize("method", METHODS)
def test_a_60n_sideways_push_at_mid_stance(method):
    """60 N for 0.1 s to the left at mid-SSP of a 0.3 m step: each method recovers."""
    out = pushes.run_push(method, 0.3, 60.0, "left", 0.1, **SHORT)
    print(
        f"{method}: 60 N left 0.1 s on the {out.support} foot at t = {out.push_time:.2f} s: "
        f"{'recovered' if out.recovered else 'FELL (' + str(out.fall_reason) + ')'}, "
        f"CoM speed change {out.com_speed_change:.3f} m/s"
    )
    assert out.recovered, f"{method} fell: {out.fall_reason}"
    assert out.steps_completed == 4
    # the push reached the body: the CoM sped up along it by roughly F dt / m (the feet's
    # friction and the controller take some of it)
    impulse_speed = 60.0 * 0.1 / MASS
    assert 0.3 * impulse_speed < out.com_speed_change < 1.5 * impulse_speed


def test_300n_makes_the_robot_fall():
    """The study can fail: 300 N (the live tool's maximum) for 0.1 s topples the MPC robot."""
    out = pushes.run_push("mpc", 0.3, 300.0, "left", 0.1, **SHORT)
    assert not out.recovered
    assert out.fall_reason and out.fall_time is not None and out.fall_time > out.push_time


def test_bisection_brackets_the_edge(monkeypatch):
    """largest_survived narrows to the resolution around the force where falls start."""
    edge = {"fixed": 123.0, "mpc": 250.0, "redundancy": -1.0}  # redundancy: falls unpushed

    def fake(method, step_length, force, *_args):
        ok = force < edge[method]
        return pushes.PushOutcome(
            method, step_length, force, "left", 0.1, 3.0, "right", 0.0, ok, None, None, 4
        )

    monkeypatch.setattr(pushes, "run_push", fake)
    for method in ("fixed", "mpc"):
        s = pushes.largest_survived(method, 0.3, f_high=400.0, resolution=5.0)
        assert s.survived < edge[method] <= s.failed and s.failed - s.survived <= 5.0
    assert pushes.largest_survived("redundancy", 0.3).survived is None
    s = pushes.largest_survived("mpc", 0.3, f_high=200.0)
    assert s.survived == 200.0 and s.failed is None
    assert "survives 200 N" in s.describe()


def test_bad_arguments():
    with pytest.raises(ValueError, match="unknown method"):
        pushes.run_push("moonwalk", 0.3, 60.0)
    with pytest.raises(ValueError, match="direction"):
        pushes.run_push("mpc", 0.3, 60.0, "up")
    with pytest.raises(ValueError, match="duration"):
        pushes.run_push("mpc", 0.3, 60.0, duration=-0.1)
    assert cli_main(["push-study", "--step-length", "2"]) == 2
    assert cli_main(["push-study", "--duration", "-1"]) == 2


# -- the API: refusals with a message, and the live loop goes on ----------------------------
@pytest.fixture(scope="module")
def api(client, live):
    """The shared TestClient (tests/conftest.py) and its live simulation."""
    return client, live


@pytest.mark.parametrize(
    ("body", "words"),
    [
        ({"method": "mpc", "force": [0, PUSH_FORCE_MAX + 1]}, "maximum"),
        ({"method": "redundancy", "force": [0, 60]}, "no robot 'redundancy'"),
        ({"method": "moonwalk", "force": [0, 60]}, "no robot 'moonwalk'"),  # a label
        ({"method": "mpc", "force": [0, 60], "duration": -0.1}, "duration"),
    ],
)
def test_bad_pushes_are_refused_and_the_loop_goes_on(api, body, words):
    c, sim = api
    before = sim.frame()
    r = c.post("/api/sim/push", json=body)
    assert r.status_code == 422, r.text
    assert words in r.text
    later = sim.wait_frame(before.seq, timeout=60)
    later = sim.wait_frame(later.seq, timeout=60)
    assert later is not None and later.clock > before.clock
    assert sim.running and sim.error is None


def test_a_good_push_is_applied(api):
    c, sim = api
    r = c.post("/api/sim/push", json={"method": "mpc", "force": [0, 60], "duration": 0.1})
    assert r.status_code == 200
    if not r.json()["applied"]:  # not within the route's wait: a busy machine, no error
        assert sim.wait_applied(sim.intent, timeout=60) is not None
    assert sim.frame().pushes_done >= 1
