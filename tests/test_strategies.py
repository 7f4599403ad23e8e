"""A user's pelvis strategy: one file, run beside the paper's methods everywhere (simulate, a
live session with four robots in worker processes, the sweep, the API), with no file of the
project changed; and its faults (raise, NaN, wrong type, slow, a file that does not import or
holds no strategy) stop its robot only, with the user's file and line."""

from __future__ import annotations

import json
import re
import subprocess
import textwrap
from pathlib import Path

import numpy as np
import pytest

from app.cli import main as cli_main
from app.live import FALL_HOLD_S
from app.live.engines import InProcessEngine
from app.live.pool import WorkerPool
from app.live.session import initial_intent
from controller import strategy
from controller.params import ControllerParams
from pelvic_walk.core.run import run, summarize
from pelvic_walk.core.session import RunConfig

ROOT = Path(__file__).resolve().parents[1]

GAIN = '''
from pelvic_walk import PelvisStrategy


class Gain(PelvisStrategy):
    """Follows the reference's first sample with a gain."""

    name = "{name}"

    def waist_rate(self, s):
        assert not s.theta_ref.flags.writeable and s.com.shape == (len(s.horizon_t), 2)
        return 8.0 * (s.theta_ref[0] - s.theta)
'''

FAULTS = """
import time

from pelvic_walk import PelvisStrategy


class Raises(PelvisStrategy):
    name = "raises"

    def waist_rate(self, s):
        if s.t >= 1.0:
            return 1.0 / (s.theta - s.theta)  # ZeroDivisionError at t = 1 s
        return 0.0


class Nan(PelvisStrategy):
    name = "nan"

    def waist_rate(self, s):
        return float("nan") if s.t >= 0.5 else 0.0


class Wrong(PelvisStrategy):
    name = "wrong"

    def waist_rate(self, s):
        return [0.0]


class Writes(PelvisStrategy):
    name = "writes"

    def waist_rate(self, s):
        s.theta_ref[0] = 0.0  # inputs are read-only
        return 0.0


class Slow(PelvisStrategy):
    name = "slow"

    def waist_rate(self, s):
        time.sleep(0.007)
        return 0.0
"""


def _line(path: Path, text: str) -> int:
    """The 1-based line of ``text`` in ``path``."""
    return next(i for i, line in enumerate(path.read_text().splitlines(), 1) if text in line)


@pytest.fixture
def user_file(tmp_path):
    """A strategy file written into a temporary folder, as a student would; unregistered after."""
    made: list[str] = []

    def write(source: str, name: str = "gain", file: str = "student.py") -> Path:
        path = tmp_path / file
        path.write_text(textwrap.dedent(source.format(name=name)))
        made.append(name)
        return path

    yield write
    for name in made + ["raises", "nan", "wrong", "writes", "slow"]:
        strategy.unregister(name)


def _git_status() -> str | None:
    try:
        out = subprocess.run(
            ["git", "status", "--porcelain"], cwd=ROOT, capture_output=True, text=True, timeout=30
        )
    except (OSError, subprocess.TimeoutExpired):
        return None
    return out.stdout if out.returncode == 0 else None


def test_a_new_strategy_runs_in_simulate_a_live_session_and_the_sweep(user_file, tmp_path):
    before = _git_status()
    path = user_file(GAIN, name="gain")
    # simulate: no --method needed
    out = tmp_path / "run.json"
    assert cli_main(["simulate", "--strategy", str(path), "--step-length", "0.3", "--steps",
                     "3", "--json", str(out)]) == 0  # fmt: skip
    summary = json.loads(out.read_text())
    assert summary["method"] == "gain" and summary["success"] and summary["strategy_error"] is None
    assert summary["waist_yaw_max_deg"] > 5.0  # it turns the pelvis
    # a live session with four robots in worker processes (spawned: they load the file)
    pool = WorkerPool(2, robots_per_worker=2).start()
    try:
        methods = [*strategy.BUILTINS, "gain"]
        session = pool.open(initial_intent(ControllerParams(), methods), sid="four")
        f = session.wait_frame(timeout=60)
        while f is not None and min(r.t for r in f.robots) < 2.0:
            f = session.wait_frame(f.seq, timeout=60)
        assert f is not None
        assert [r.method for r in f.robots] == methods
        gain = f.robot("gain")
        assert gain is not None and gain.error is None and not gain.fell
        assert gain.step_index >= 0 and gain.horizon is not None and not gain.horizon.planned
        assert f.robot("mpc").horizon.planned
        pool.close(session)
    finally:
        pool.stop()
    # the sweep, on a process pool whose workers load the file from the run spec
    sweep_out = tmp_path / "sweep"
    assert cli_main(["sweep", "--strategy", str(path), "--methods", "gain,fixed", "--set",
                     "walk.step_length=0.25", "--set", "walk.n_steps=2", "--measure",
                     "summary", "--jobs", "2", "--out", str(sweep_out)]) == 0  # fmt: skip
    rows = [json.loads(line) for line in (sweep_out / "sweep.jsonl").read_text().splitlines()]
    assert {r["method"] for r in rows} == {"gain", "fixed"}
    assert all(r["success"] for r in rows)
    assert _git_status() == before  # no file of the project changed


def test_the_api_lists_the_servers_strategies_and_runs_one_by_name(user_file, tmp_path):
    from fastapi.testclient import TestClient

    from app.web.api import create_app

    path = user_file(GAIN, name="gain_api")
    strategy.load_file(str(path))
    pool = WorkerPool(1, robots_per_worker=1, engine=InProcessEngine()).start()
    sim = pool.open(initial_intent(ControllerParams().replace(walk={"n_steps": 2}), ["mpc"]))
    with TestClient(create_app(sim)) as client:
        listed = client.get("/api/strategies").json()["strategies"]
        assert [s["name"] for s in listed][:3] == list(strategy.BUILTINS)
        mine = next(s for s in listed if s["name"] == "gain_api")
        assert mine["file"] == "student.py" and not mine["builtin"]  # no server path shown
        assert mine["description"] == "Follows the reference's first sample with a gain."
        body = {"method": "gain_api", "walk": {"step_length": 0.2, "n_steps": 1}}
        r = client.post("/api/runs", json=body)
        assert r.status_code == 202, r.text
        run_id = r.json()["id"]
        for _ in range(600):
            status = client.get(f"/api/runs/{run_id}").json()
            if status["status"] in ("done", "error"):
                break
            __import__("time").sleep(0.2)
        assert status["status"] == "done" and status["summary"]["method"] == "gain_api"
        bad = client.post("/api/runs", json={"method": "nobody"})
        assert bad.status_code == 422 and "unknown method 'nobody'" in bad.text
        # code is never loaded over HTTP: no route takes a file
        assert not [p for p in client.get("/openapi.json").json()["paths"] if "strateg" in p
                    and p != "/api/strategies"]  # fmt: skip
    pool.close(sim)
    pool.stop()


@pytest.mark.parametrize(
    ("cls", "message", "where"),
    [
        ("Raises", "ZeroDivisionError: float division by zero", "1.0 / (s.theta"),
        ("Nan", "waist_rate returned nan", "class Nan"),
        ("Wrong", "waist_rate returned list [0.0], not a number", "class Wrong"),
        ("Writes", "ValueError: assignment destination is read-only", "s.theta_ref[0] = 0.0"),
    ],
)
def test_a_faulty_strategy_stops_its_own_run_with_file_and_line(user_file, cls, message, where):
    path = user_file(FAULTS, name="faults", file="faulty.py")
    (name,) = strategy.load_file(f"{path}:{cls}")
    session = run(RunConfig(ControllerParams().replace(method=name, walk={"n_steps": 2})))
    s = summarize(session)
    line = _line(path, where)
    if where.startswith("class"):  # a bad return value: the line of its waist_rate's def
        text = path.read_text().splitlines()
        line = next(i for i in range(line, len(text) + 1) if "def waist_rate" in text[i - 1])
    assert s["success"] is False and s["fell"] is False
    assert message in s["strategy_error"] and s["strategy_error"].endswith(f"(faulty.py:{line})")
    assert s["strategy_error_time"] is not None


def test_simulate_says_a_stopped_walk_by_its_exit_status(user_file, capsys):
    path = user_file(FAULTS, name="faults", file="faulty.py")
    argv = ["simulate", "--strategy", f"{path}:Raises", "--step-length", "0.2", "--steps", "2"]
    assert cli_main(argv) == 1  # the strategy stopped the walk: not the walk asked for
    out = capsys.readouterr().out
    assert "STOPPED by its strategy" in out and "landing error max -" in out
    assert f"ZeroDivisionError: float division by zero (faulty.py:{_line(path, '1.0 / (')})" in out


@pytest.mark.slow
def test_a_slow_strategy_is_reported_with_its_time(user_file, tmp_path, capsys):
    path = user_file(FAULTS, name="faults", file="faulty.py")
    out = tmp_path / "slow.json"
    assert cli_main(["simulate", "--strategy", f"{path}:Slow", "--step-length", "0.2",
                     "--steps", "1", "--json", str(out)]) == 0  # fmt: skip
    s = json.loads(out.read_text())
    assert s["success"] and s["strategy_ms_median"] >= 7.0
    assert re.search(
        r"the strategy takes \d+\.\d ms a tick .* more than the 5 ms", capsys.readouterr().out
    )


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("import numpy\n\nx = 1 / 0\n", "student.py:3: ZeroDivisionError: division by zero"),
        ("def f(:\n", "student.py:1: SyntaxError"),
        ("x = 1\n", "student.py: defines no strategy"),
        (GAIN.replace('"{name}"', '"has space"'), "name must be 1-40 letters"),
        (GAIN.replace('"{name}"', '"mpc"'), "the name 'mpc' is taken by a built-in strategy"),
        ("import no_such_module_here\n", "ModuleNotFoundError: No module named"),
    ],
)
@pytest.mark.parametrize("command", ["simulate", "serve"])
def test_a_file_that_is_not_a_strategy_exits_2_with_one_line(
    user_file, capsys, command, source, expected
):
    path = user_file(source.replace("{", "{{").replace("}", "}}"), name="gain")
    argv = [command, "--strategy", str(path)]
    argv += ["--step-length", "0.2"] if command == "simulate" else ["--port", "1"]
    assert cli_main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    assert err.startswith(f"pelvic-walk {command}: error: --strategy ") and expected in err


def test_missing_file_and_unknown_class_and_ambiguous_file(user_file, capsys):
    path = user_file(FAULTS, name="faults", file="faulty.py")
    assert cli_main(["simulate", "--strategy", "nowhere.py", "--step-length", "0.2"]) == 2
    assert "nowhere.py: no such file" in capsys.readouterr().err
    assert cli_main(["simulate", "--strategy", f"{path}:Nope", "--step-length", "0.2"]) == 2
    assert "no PelvisStrategy subclass named Nope" in capsys.readouterr().err
    assert cli_main(["simulate", "--strategy", str(path), "--step-length", "0.2"]) == 2
    assert "defines 5 strategies" in capsys.readouterr().err
    strategy.unregister("raises")  # (one process: the file above was loaded)
    with pytest.raises(SystemExit) as exited:  # argparse's own error: one line, status 2
        cli_main(["simulate", "--method", "raises", "--step-length", "0.2"])
    assert exited.value.code == 2
    assert "unknown method 'raises'" in capsys.readouterr().err


def test_a_faulty_robot_stops_alone_and_the_others_walk_on(user_file):
    """Live: the faulty robot stops with its message (file and line) on its frame and in
    /api/state; the MPC robot walks on well past a fall's hold, and the session does not
    restart the others for it."""
    from fastapi.testclient import TestClient

    from app.web.api import create_app

    path = user_file(FAULTS, name="faults", file="faulty.py")
    strategy.load_file(f"{path}:Raises")
    pool = WorkerPool(1, robots_per_worker=2, engine=InProcessEngine()).start()
    params = ControllerParams().replace(walk={"n_steps": 20})
    sim = pool.open(initial_intent(params, ["mpc", "raises"], speed=4.0))
    with TestClient(create_app(sim)) as client:
        try:
            # one part per robot: the first merged frames may show only the part that sent one
            f = sim.wait_applied(sim.intent, timeout=60)
            while f is not None and (
                (m := f.robot("mpc")) is None or m.t < 1.0 + FALL_HOLD_S + 1.0
            ):
                f = sim.wait_frame(f.seq, timeout=60)
            assert f is not None
            bad, mpc = f.robot("raises"), f.robot("mpc")
            line = _line(path, "1.0 / (s.theta")
            assert bad.error == f"ZeroDivisionError: float division by zero (faulty.py:{line})"
            assert bad.status == "stopped" and not bad.fell and not bad.finished
            assert mpc.error is None and not mpc.fell and mpc.step_index >= 3
            assert sim.intent.auto_restarts == 0  # nobody restarted for it
            state = client.get("/api/state").json()
            robots = {r["method"]: r for r in state["robots"]}
            assert (
                robots["raises"]["error"] == bad.error and robots["raises"]["status"] == "stopped"
            )
            assert robots["mpc"]["error"] is None
            assert sim.error is None  # the loop itself runs on
        finally:
            pool.close(sim)
            pool.stop()


def test_the_example_in_the_docs_runs(tmp_path):
    """docs/STRATEGIES.md's example, as a student copies it, runs through simulate."""
    text = (ROOT / "docs" / "STRATEGIES.md").read_text()
    code = re.search(r"```python\n(.*?)```", text, re.S)
    assert code is not None
    path = tmp_path / "my_pelvis.py"
    path.write_text(code.group(1))
    names = strategy.load_file(str(path))
    try:
        assert len(names) == 1
        s = summarize(run(RunConfig(ControllerParams().replace(method=names[0],
                                                              walk={"n_steps": 2}))))  # fmt: skip
        assert s["success"] and s["strategy_error"] is None
    finally:
        strategy.unregister(names[0])


@pytest.mark.parametrize("example", ["track_reference.py", "feedforward_sine.py", "my_pelvis.py"])
def test_the_examples_load_and_walk(example):
    (name,) = strategy.load_file(str(ROOT / "examples" / example))
    try:
        s = summarize(run(RunConfig(ControllerParams().replace(method=name,
                                                              walk={"n_steps": 2}))))  # fmt: skip
        assert s["success"], s
    finally:
        strategy.unregister(name)


def test_the_three_methods_are_strategies_on_the_same_contract():
    assert strategy.BUILTINS == ("fixed", "redundancy", "mpc")
    for name in strategy.BUILTINS:
        info = strategy.info(name)
        assert issubclass(info.cls, strategy.PelvisStrategy) and info.builtin
    inputs = strategy.StrategyInputs(
        0.0, 0.005, 0.1, 0.0, np.zeros(16), np.arange(1, 17) * 0.1, np.zeros((16, 2)),
        np.zeros(2), np.zeros((16, 3)), np.zeros((16, 3)), np.zeros(3), np.zeros(3), "both",
        None, -1, 0.0, ControllerParams(),
    )  # fmt: skip
    assert strategy.create("fixed").waist_rate(inputs) == 0.0
    assert strategy.create("redundancy").waist_rate(inputs) is None
    rate = strategy.create("mpc").waist_rate(inputs)  # theta 0.1 toward theta_ref 0: turns back
    assert rate is not None and rate < 0.0


def test_a_strategy_imports_a_module_beside_it_and_takes_a_free_colour(tmp_path):
    (tmp_path / "helper_mod_for_test.py").write_text("def rate(s):\n    return 0.0\n")
    (tmp_path / "two.py").write_text(
        textwrap.dedent(
            """
            from helper_mod_for_test import rate
            from pelvic_walk import PelvisStrategy

            class Teal(PelvisStrategy):
                name = "wears_black"
                color = (0, 0, 0)  # the palette's first colour, chosen by the student

                def waist_rate(self, s):
                    return rate(s)

            class Plain(PelvisStrategy):
                name = "wears_none"

                def waist_rate(self, s):
                    return rate(s)
            """
        )
    )
    names = strategy.load_file(str(tmp_path / "two.py"))
    try:
        assert set(names) == {"wears_black", "wears_none"}
        assert strategy.info("wears_none").color == strategy.PALETTE[1]  # black is worn
        s = summarize(run(RunConfig(ControllerParams().replace(method="wears_none",
                                                              walk={"n_steps": 1}))))  # fmt: skip
        assert s["success"]
    finally:
        for n in names:
            strategy.unregister(n)


STOPS_AT_STEP_3 = """
from pelvic_walk import PelvisStrategy


class AtThree(PelvisStrategy):
    name = "at_three"

    def waist_rate(self, s):
        if s.step == 3:
            raise ValueError("stop at step 3")
        return 0.0


class Undocumented(PelvisStrategy):
    name = "undocumented"

    def waist_rate(self, s):
        return 0.0
"""


def test_a_strategy_stopped_at_step_3_is_said_stopped_at_step_3_everywhere(user_file, capsys):
    """One count of steps, s.step's (from 0): a strategy raised at s.step == 3 stopped in
    step 3 after 3 steps (0, 1, 2) had landed, in the summary, the command line, a live
    robot's frame and /api/state (it was "step 2" and "2/10 steps": the last landing is
    measured half a DSP after touch-down, after the stop)."""
    from fastapi.testclient import TestClient

    from app.web.api import create_app

    path = user_file(STOPS_AT_STEP_3, name="at_three", file="at_three.py")
    strategy.load_file(f"{path}:AtThree")
    params = ControllerParams().replace(method="at_three", walk={"step_length": 0.2, "n_steps": 10})
    s = summarize(run(RunConfig(params=params)))
    assert s["strategy_error"].startswith("ValueError: stop at step 3")
    assert s["strategy_error_step"] == 3
    assert (s["steps_completed"], s["steps_planned"]) == (3, 10)
    capsys.readouterr()
    cli_main(["simulate", "--strategy", f"{path}:AtThree", "--step-length", "0.2", "--steps", "10"])
    out = capsys.readouterr().out
    assert "3/10 steps" in out and "in step 3 (s.step): ValueError: stop at step 3" in out

    pool = WorkerPool(1, robots_per_worker=1, engine=InProcessEngine()).start()
    params = ControllerParams().replace(walk={"n_steps": 10})
    sim = pool.open(initial_intent(params, ["at_three"], speed=4.0))
    with TestClient(create_app(sim)) as client:
        try:
            f = sim.wait_frame(timeout=60)
            while f is not None and f.robot("at_three").error is None:
                f = sim.wait_frame(f.seq, timeout=60)
            assert f is not None and f.robot("at_three").step_index == 3
            robot = client.get("/api/state").json()["robots"][0]
            assert robot["status"] == "stopped" and robot["step_index"] == 3
        finally:
            pool.close(sim)
            pool.stop()


def test_a_class_without_a_docstring_is_described_by_nothing(user_file):
    """Not by the base class's docstring ("Base class of a pelvis strategy: ...")."""
    path = user_file(STOPS_AT_STEP_3, name="undocumented", file="undocumented.py")
    strategy.load_file(f"{path}:Undocumented")
    assert strategy.info("undocumented").description == ""
    assert strategy.info(strategy.MPC).description  # the built-ins keep theirs
