"""The public Python API (``pelvic_walk``, docs/PYTHON.md): a run equals the CLI's, bad input
raises the CLI's line as a ValueError, tables and plots, strategies defined in this process,
the sweep on the CLI's engine, and :class:`pelvic_walk.Client` driving a served tool."""

from __future__ import annotations

import json
import math
import time

import numpy as np
import pytest

import pelvic_walk as pw
from app.cli import main
from controller import strategy
from pelvic_walk.core.metrics import COLUMNS
from pelvic_walk.core.summary import SUMMARY_KEYS, TIMING_KEYS


def _cli_summary(tmp_path, *argv: str) -> dict:
    out = tmp_path / f"cli{len(list(tmp_path.iterdir()))}.json"
    assert main(["simulate", *argv, "--json", str(out)]) == 0
    return json.loads(out.read_text())


def _same(a: dict, b: dict) -> None:
    keys = (set(a) | set(b)) - set(TIMING_KEYS)
    assert set(SUMMARY_KEYS) - set(TIMING_KEYS) <= keys
    assert {k: a.get(k) for k in keys} == {k: b.get(k) for k in keys}


@pytest.fixture(scope="module")
def walk():
    """One short MPC walk with a parameter and a seed set, shared by the tests below."""
    return pw.simulate("mpc", step_length=0.3, steps=2, seed=3, pelvis_k_pel=0.3)


def test_a_run_is_the_clis_run(tmp_path, walk):
    """The same arguments give the same summary as ``simulate --json`` (timings aside)."""
    cli = _cli_summary(
        tmp_path,
        "--method",
        "mpc",
        "--step-length",
        "0.3",
        "--steps",
        "2",
        "--seed",
        "3",
        "--pelvis-k-pel",
        "0.3",
    )
    _same(json.loads(json.dumps(walk.summary)), cli)
    assert walk.command == (
        "pelvic-walk simulate --method mpc --step-length 0.3 --steps 2 --seed 3 "
        "--set pelvis.k_pel=0.3"
    )
    # the dotted name reaches the same field
    assert pw.simulate(step_length=0.3, steps=2, seed=3, **{"pelvis.k_pel": 0.3}).summary[
        "energy_total"
    ] == pytest.approx(walk.summary["energy_total"], rel=0, abs=0)


@pytest.mark.parametrize(
    ("kwargs", "cli"),
    [
        ({"step_length": 0.9}, ["--step-length", "0.9"]),
        ({"step_length": 0.3, "pelvis_k_pel": 1.5}, ["--pelvis-k-pel", "1.5"]),
        ({"step_length": 0.3, "steps": 0}, ["--steps", "0"]),
        ({"step_length": 0.3, "steps": 2.5}, None),
        ({"step_length": 0.3, "walk_dsp_split": "middle"}, ["--walk-dsp-split", "middle"]),
        ({"step_length": 0.3, "arms": "no"}, None),
    ],
)
def test_bad_input_raises_the_clis_line(kwargs, cli, capsys):
    """A bad value raises ValueError with the line ``simulate`` prints before exiting 2."""
    with pytest.raises(ValueError) as exc:
        pw.simulate("fixed", **kwargs)
    message = str(exc.value)
    assert "\n" not in message and message
    if cli is not None:
        argv = ["simulate", "--method", "fixed", "--step-length", "0.3", *cli]
        with pytest.raises(SystemExit) as code:
            main(argv)
        assert code.value.code == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("pelvic-walk simulate: error:") and err.endswith(message), err


def test_bad_names_and_arguments_are_one_line_value_errors():
    cases = [
        (dict(method="nope"), "unknown method 'nope'"),
        (dict(method="mpc", strategy="x.py"), "not both"),
        (dict(strategy="/no/such/file.py"), "no such file"),
        (dict(colour=3), "unknown parameter 'colour'"),
        (dict(seed=1.5), "seed must be a whole number"),
        (dict(disturbance=5.0), "disturbance needs a seed"),
        (dict(backend="cplex"), "backend must be one of daqp, osqp"),
        (dict(step_length=float("nan")), "must be finite"),
    ]
    for kwargs, expected in cases:
        with pytest.raises(ValueError, match=expected):
            pw.simulate(**kwargs)
    with pytest.raises(ValueError, match="theta_pel_deg must be within"):
        pw.analyze(theta_pel_deg=120)
    with pytest.raises(ValueError, match="l_leg must be a positive length"):
        pw.analyze(l_leg=-1)


def test_series_has_a_row_per_tick_and_columns_with_units(walk):
    df = walk.series
    assert len(df) == round(walk.summary["sim_time"] / walk.params.control_dt)
    assert len(df.columns) == len(COLUMNS)
    named = {"t [s]", "waist_angle [rad]", "yaw_momentum [kg m^2/s]", "kappa_legs", "energy [J]"}
    assert named <= set(df.columns)
    assert np.allclose(np.diff(df["t [s]"]), walk.params.control_dt)
    assert (
        np.degrees(np.nanmax(np.abs(df["waist_angle [rad]"])))
        >= walk.summary["waist_yaw_max_deg"] - 1e-9
    )
    df.iloc[:, 1] = 0.0  # a copy: the run keeps its numbers
    assert np.any(walk.series.iloc[:, 1] != 0.0)


def test_horizon_holds_the_plan_at_an_instant(walk):
    p = walk.params
    h = walk.horizon(2.0)
    assert len(h) == round(p.com.horizon / p.com.sample_time)
    assert abs(h.attrs["t"] - 2.0) <= 0.05 + 1e-9
    assert np.allclose(h["ahead [s]"], p.com.sample_time * np.arange(1, len(h) + 1))
    assert np.allclose(h["t [s]"], h.attrs["t"] + h["ahead [s]"])
    assert (h["zmp_min_y [m]"] <= h["zmp_max_y [m]"]).all()
    with pytest.raises(ValueError, match="outside the run"):
        walk.horizon(99.0)


def test_compare_plot_and_player(walk):
    fixed = pw.simulate("fixed", step_length=0.3, steps=2, seed=3, pelvis_k_pel=0.3)
    table = pw.compare([fixed, walk])
    assert list(table.index) == ["fixed", "mpc"]
    assert table.loc["mpc", "waist_yaw_max_deg"] > 5 > table.loc["fixed", "waist_yaw_max_deg"]
    assert {"success", "clean", "energy_two_step_mean", "yaw_momentum_peak"} <= set(table.columns)
    with pytest.raises(ValueError, match="unknown summary key"):
        pw.compare([walk], keys=["speed"])
    fig = walk.plot(others=[fixed])
    assert len(fig.axes) == len(pw.DEFAULT_PANELS)
    assert len(fig.axes[0].lines) == 2
    assert len(pw.plot([walk], "waist", "theta_ref").axes) == 2
    with pytest.raises(ValueError, match="unknown panel"):
        walk.plot("speed")
    player = walk.player()
    assert "Embedded" in player.html or "viser" in player.html.lower()
    frame = player._repr_html_()
    assert frame.startswith("<iframe srcdoc=") and "&lt;" in frame
    with pytest.raises(RuntimeError, match="in a notebook"):
        walk.show()  # no IPython kernel here: says what to do instead


def test_runs_of_one_method_are_labelled_by_what_differs():
    a = pw.simulate("fixed", step_length=0.2, steps=1)
    b = pw.simulate("fixed", step_length=0.2, steps=1, step_time=1.0)
    table = pw.compare([a, b])
    assert list(table.index) == ["fixed (walk.step_time=1.2)", "fixed (walk.step_time=1.0)"]
    assert list(table["walk.step_time"]) == [1.2, 1.0]


def test_analyze_is_the_clis_and_knows_our_robot():
    from controller.analysis import kinematic_analysis

    assert pw.analyze() == kinematic_analysis()
    ours = pw.robot()
    assert ours["l_pel"] == pytest.approx(0.21) and ours["z0"] == pytest.approx(0.68)
    assert pw.analyze(**ours)["step_max_fixed_static"] == pytest.approx(
        math.sqrt(ours["l_leg"] ** 2 - ours["z0"] ** 2)
    )


# -- strategies defined in this process --------------------------------------------------------
def _gain_class(gain: float, name: str = "nb_gain"):
    class Gain(pw.PelvisStrategy):
        def waist_rate(self, s):
            return gain * (s.theta_ref[0] - s.theta)

    Gain.name = name
    return Gain


def test_a_class_defined_here_runs_and_a_new_definition_replaces_it():
    try:
        first = pw.simulate(strategy=_gain_class(8.0), step_length=0.3, steps=1)
        assert first.method == "nb_gain" and first.summary["success"]
        info = strategy.info("nb_gain")
        assert not info.builtin and info.source is None
        # the cell run again: a new class object under the same name takes its place
        again = pw.simulate(strategy=_gain_class(0.0), step_length=0.3, steps=1)
        assert again.summary["waist_yaw_max_deg"] < 1.0 < first.summary["waist_yaw_max_deg"]
        assert "nb_gain" in pw.strategies()
        # method= takes the class too; an instance or a built-in's name is refused
        assert pw.simulate(_gain_class(8.0), step_length=0.3, steps=1).method == "nb_gain"
        with pytest.raises(ValueError, match="the class, not an instance"):
            pw.simulate(strategy=_gain_class(8.0)())
        with pytest.raises(ValueError, match="taken by a built-in"):
            pw.simulate(strategy=_gain_class(8.0, name="mpc"))
    finally:
        strategy.unregister("nb_gain")


def test_a_sweep_of_a_class_defined_here_runs_in_this_process_or_says_why_not():
    cls = _gain_class(8.0, name="nb_sweep")
    try:
        with pytest.raises(ValueError, match="worker processes cannot import"):
            pw.sweep([cls], measure="summary", steps=1, jobs=2)
        with pytest.raises(ValueError, match="worker processes cannot import"):
            pw.sweep([cls], measure="summary", steps=1, ray=True)
        table = pw.sweep([cls], measure="summary", steps=1, step_length=[0.2, 0.25])
        assert list(table["method"]) == ["nb_sweep", "nb_sweep"]
        assert list(table["walk.step_length"]) == [0.2, 0.25]
        assert table["success"].all()
    finally:
        strategy.unregister("nb_sweep")


def test_sweep_runs_on_the_clis_engine_and_checks_the_grid(tmp_path):
    out = tmp_path / "sweep"
    table = pw.sweep(
        ["fixed", "mpc"], measure="summary", steps=1, dsp_ratio=[0.2, 0.3], jobs=2, out=out
    )
    assert len(table) == 4
    assert list(table.columns[:2]) == ["walk.dsp_ratio", "walk.n_steps"]
    assert (out / "sweep.csv").is_file() and (out / "README.md").is_file()
    assert "pelvic_walk.sweep(" in (out / "README.md").read_text()
    for kwargs, expected in [
        (dict(dsp_ratio=[0.2, 0.9]), "walk.dsp_ratio = 0.9 is above the maximum 0.5"),
        (dict(step_length=[0.2, 0.3]), "what --measure limit searches over"),
        (dict(dsp_ratio=[0.2], measure="best"), "unknown measure 'best'"),
        (dict(dsp_ratio=[0.2], methods=["nope"]), "unknown method 'nope'"),
        (dict(dsp_ratio=[0.2], jobs=0), "jobs must be a whole number"),
    ]:
        with pytest.raises(ValueError, match=expected):
            pw.sweep(**kwargs)


# -- a served tool ---------------------------------------------------------------------------
TOKEN = "lecture-token-36"


@pytest.fixture(scope="module")
def served():
    """``pelvic-walk serve`` with an instructor and private sessions, on free loopback ports."""
    import os

    from app.bench.local_server import local_server

    env = {**os.environ, "PELVIC_WALK_DISPLAY_NICE": "0"}
    args = ("--instructor-token", TOKEN, "--sessions", "private", "--methods", "fixed", "mpc")
    with local_server(args, env=env) as server:
        yield server.base


def test_client_drives_a_served_tool_and_raises_the_apis_refusals(served):
    """Pause, step to the next lift-off, seek, parameters, a push; without the instructor's
    token a change of the shared session raises NotAllowed with the API's message."""
    student = pw.Client(served)
    assert student.health()["instructor"] is True
    # the session's robots run in two workers: a frame shows both once both parts delivered
    shown: list[str] = []
    for _ in range(600):
        shown = [r["method"] for r in student.state()["robots"]]
        if len(shown) == 2:
            break
        time.sleep(0.1)
    assert shown == ["fixed", "mpc"]
    with pytest.raises(pw.NotAllowed) as refused:
        student.pause()
    assert refused.value.status == 401
    assert str(refused.value).startswith("the instructor drives the shared session")
    assert isinstance(refused.value, PermissionError)
    with pytest.raises(pw.NotAllowed, match="instructor"):
        student.set_params(step_length=0.3)
    with pytest.raises(pw.NotAllowed, match="wrong instructor token"):
        pw.Client(served, token=TOKEN + "x").pause()

    with pw.Client(served, token=TOKEN) as teacher:
        assert teacher.pause()["paused"] is True
        with pytest.raises(pw.InvalidRequest) as bad:
            teacher.set_params(step_length=0.9)
        assert bad.value.status == 422 and "step_length" in str(bad.value)
        assert isinstance(bad.value, ValueError)
        params = teacher.set_params(step_length=0.3, pelvis_k_pel=0.3)
        assert params["walk"]["step_length"] == 0.3 and params["pelvis"]["k_pel"] == 0.3
        assert teacher.params()["pelvis"]["k_pel"] == 0.3
        for _ in range(5):  # a restart may come between (the plan's end): the next lift-off
            lifted = teacher.next_liftoff()
            assert lifted["paused"] is True
            try:
                plan = teacher.horizon("mpc")  # the plan at the lift-off
                break
            except pw.Conflict as exc:  # the robot has not ticked since it restarted
                assert "not ticked" in str(exc)
        assert len(plan["com_x"]) > 1
        state = teacher.state()
        kept = state["kept"]
        target = (kept["start"] + kept["end"]) / 2
        sought = teacher.seek(target)  # the nearest kept instant
        assert kept["start"] <= sought["shown_t"] <= kept["end"]
        assert teacher.state()["shown_t"] == sought["shown_t"]
        assert teacher.seek(kept["start"])["shown_t"] == pytest.approx(kept["start"])
        assert teacher.push("mpc", (0.0, 20.0), 0.05)["applied"] in (True, False)
        teacher.resume()
        with pytest.raises(pw.Conflict, match="pause first"):
            teacher.seek(target)
        with pytest.raises(pw.NotFound, match="no run with id"):
            teacher.get_run("nope")

        # a private session: a student's own; the client sends the token the server gave it
        mine = student.open_session()
        try:
            assert mine.session and mine.session != "shared"
            assert student.open_session().session == mine.session  # one seat a client
            stranger = pw.Client(served)
            with pytest.raises(pw.NotFound):  # knowing the id grants nothing
                pw.Client(served, session=mine.session).pause()
            stranger.close()
            assert mine.pause()["paused"] is True
            assert mine.set_params(step_length=0.25)["walk"]["step_length"] == 0.25
            assert student.params()["walk"]["step_length"] == 0.3  # the shared one unchanged
        finally:
            mine.close_session()
        with pytest.raises(pw.NotFound):
            mine.state()

        summary = teacher.run("fixed", step_length=0.2, steps=1)
        assert set(SUMMARY_KEYS) <= set(summary) and summary["method"] == "fixed"
    student.close()


def test_client_says_when_nothing_answers():
    from app.bench.local_server import free_port

    with pytest.raises(ConnectionError, match="no pelvic-walk server answers"):
        pw.Client(f"http://127.0.0.1:{free_port()}", timeout=2).state()
    with pytest.raises(ValueError, match="unknown parameter"):
        pw.Client("http://127.0.0.1:1").set_params(colour=1)
