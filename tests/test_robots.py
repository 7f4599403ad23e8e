"""A robot of a live session as plain data (pelvic_walk/core/robots.py): its form
``NAME[,KEY=VALUE...][@LABEL]``, its parameters over the shared ones, the names it answers to."""

from __future__ import annotations

import pytest

from controller.params import ControllerParams
from pelvic_walk.core import robots as R


def test_the_form_reads_and_writes_back():
    r = R.parse("mpc, com.horizon=0.8 ,pelvis.k_pel=0.45@short horizon")
    assert (r.strategy, r.key) == ("mpc", "short horizon")
    assert r.overrides == (("com.horizon", 0.8), ("pelvis.k_pel", 0.45))
    assert R.parse(r.text()) == r
    plain = R.parse("fixed")
    assert (plain.key, plain.text()) == ("fixed", "fixed")
    unlabelled = R.parse("mpc,com.horizon=0.8")
    assert unlabelled.key == "mpc horizon=0.8" and R.parse(unlabelled.text()) == unlabelled


def test_a_robots_parameters_are_the_shared_ones_with_its_own_on_top():
    base = ControllerParams().replace(walk={"step_length": 0.3}, pelvis={"k_pel": 0.3})
    p = R.params_of(base, R.parse("mpc,com.horizon=0.8,mpc.beta=0.01@x"))
    assert (p.method, p.com.horizon, p.pelvis.beta) == ("mpc", 0.8, 0.01)
    assert (p.walk.step_length, p.pelvis.k_pel) == (0.3, 0.3)  # shared
    assert R.params_of(base, R.parse("fixed")) == base.replace(method="fixed")


def test_short_names_are_read_when_one_group_has_them():
    assert R.parse("mpc,k_pel=0.35@x").overrides == (("pelvis.k_pel", 0.35),)
    assert R.parse("mpc,horizon=1.2@x").overrides == (("com.horizon", 1.2),)
    with pytest.raises(ValueError, match="'alpha' is ambiguous: write com.alpha or pelvis.alpha"):
        R.parse("mpc,alpha=2")
    with pytest.raises(ValueError, match="unknown parameter 'nope'"):
        R.parse("mpc,nope=1")


@pytest.mark.parametrize(
    "text, message",
    [
        ("nope", "unknown method 'nope'"),
        ("mpc,com.horizon=9", "com.horizon = 9.0 is above the maximum 3.0 s"),
        ("mpc,com.horizon", "expected KEY=VALUE, got 'com.horizon'"),
        ("mpc@", "an empty label after '@'"),
        ("mpc,com.horizon=abc", "com.horizon must be a number, got 'abc'"),
        (",com.horizon=1", "expected NAME[,KEY=VALUE...][@LABEL]"),
    ],
)
def test_bad_forms_are_one_line_errors(text, message):
    with pytest.raises(ValueError) as err:
        R.parse(text)
    assert message in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize(
    "forms, called",
    [
        (["mpc", "mpc"], "mpc"),
        (["fixed", "mpc@fixed"], "fixed"),
        (["mpc", "fixed@pelvic MPC"], "pelvic MPC"),  # the MPC is shown by its title
        (["mpc,k_pel=0.4@A", "fixed@a"], "a"),  # names differ by more than case
    ],
)
def test_no_two_robots_answer_to_one_name(forms, called):
    with pytest.raises(ValueError, match=f"two robots would both be called '{called}'"):
        R.check_all([R.parse(f) for f in forms])


def test_a_session_shows_one_to_six_robots():
    with pytest.raises(ValueError, match="at least one robot"):
        R.check_all([])
    many = [R.parse(f"mpc,k_pel={0.1 * i:.1f}@r{i}") for i in range(1, 8)]
    with pytest.raises(ValueError, match="at most 6 robots, got 7"):
        R.check_all(many)
    assert len(R.check_all(many[:6])) == 6


def test_settings_for_one_robot_keep_its_name_and_drop_what_equals_the_shared():
    base = ControllerParams()
    r = R.parse("mpc,com.horizon=0.8")
    moved = R.with_settings(r, {"pelvis.k_pel": 0.4}, base)
    assert moved.key == r.key  # the same robot, not another
    assert dict(moved.overrides) == {"com.horizon": 0.8, "pelvis.k_pel": 0.4}
    back = R.with_settings(moved, {"com.horizon": base.com.horizon}, base)
    assert dict(back.overrides) == {"pelvis.k_pel": 0.4}
    with pytest.raises(ValueError, match="above the maximum"):
        R.with_settings(r, {"com.horizon": 5.0}, base)


def test_what_differs_is_what_not_every_robot_shares():
    a, b, c = R.parse("mpc"), R.parse("mpc,com.horizon=0.8@b"), R.parse("mpc,com.horizon=0.8@c")
    assert R.differing([a, b, c]) == {
        "mpc": {},
        "b": {"com.horizon": 0.8},
        "c": {"com.horizon": 0.8},
    }
    assert R.differing([b, c]) == {"b": {}, "c": {}}


def test_a_whole_number_for_a_real_parameter_is_kept_as_a_real():
    """The API's JSON gives 25 for 25.0: a robot's settings read the same however typed."""
    r = R.make("mpc", {"com.horizon": 1}, "x")
    assert r.overrides == (("com.horizon", 1.0),) and isinstance(r.overrides[0][1], float)
    moved = R.with_settings(r, {"pelvis.k_pel": 0}, ControllerParams())
    assert dict(moved.overrides)["pelvis.k_pel"] == 0.0
    assert isinstance(dict(moved.overrides)["pelvis.k_pel"], float)
