"""A strategy's own parameters (its ``Params``) on the headless faces: ``simulate --set
NAME.FIELD=V``, ``pelvic_walk.simulate(**{"NAME.FIELD": v})``, sweep axes, run specs (also in a
fresh process that must load the file first), the summary's ``own_params``, the one-line errors;
the paper's names under the strategies that own them (``mpc.alpha``) and every old name; the
study's reading of which parameters a method reads (the registry's, not a hand-kept list);
and the held-out check: a strategy written from docs/STRATEGIES.md alone, tuned and swept."""

from __future__ import annotations

import json
import pickle
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import pelvic_walk as pw
from app.cli import main as cli_main
from app.cli.options import params_from_args
from controller import strategy
from controller.params import ControllerParams
from pelvic_walk.core.grid import make_grid
from pelvic_walk.core.measure import SameRuns, make_tasks
from pelvic_walk.core.run import spec_of
from pelvic_walk.core.run_spec import RunSpec

ROOT = Path(__file__).resolve().parents[1]

KNOB = '''
from dataclasses import dataclass

from pelvic_walk import PelvisStrategy, param


class Knob(PelvisStrategy):
    """Tracks theta_ref[0] with a gain of its own."""

    name = "knob"

    @dataclass(frozen=True)
    class Params:
        k: float = param(8.0, min=0.0, max=40.0, unit="1/s", label="gain k")
        ahead: int = param(0, min=0, max=15, label="sample of theta_ref")

    def waist_rate(self, s):
        return self.params.k * (s.theta_ref[self.params.ahead] - s.theta)
'''


@pytest.fixture
def knob(tmp_path):
    """The strategy file ``knob.py`` in a temporary folder (no project file changed)."""
    path = tmp_path / "knob.py"
    path.write_text(textwrap.dedent(KNOB))
    yield path
    strategy.unregister("knob")


def _simulate(tmp_path: Path, *argv: str) -> tuple[dict, np.ndarray]:
    """``simulate --json --csv`` -> (summary, the measured waist angle per tick)."""
    n = len(list(tmp_path.iterdir()))
    js, csv = tmp_path / f"s{n}.json", tmp_path / f"s{n}.csv"
    assert cli_main(["simulate", *argv, "--json", str(js), "--csv", str(csv)]) == 0
    header = csv.read_text().splitlines()[0].split(",")
    col = header.index("waist_angle")
    waist = np.loadtxt(csv, delimiter=",", skiprows=1, usecols=[col])
    return json.loads(js.read_text()), waist


def test_set_reaches_a_strategys_own_parameter_and_two_values_walk_differently(knob, tmp_path):
    walk = ["--strategy", str(knob), "--step-length", "0.3", "--steps", "2"]
    slow, waist_slow = _simulate(tmp_path, *walk, "--set", "knob.k=2")
    fast, waist_fast = _simulate(tmp_path, *walk, "--set", "knob.k=20")
    assert slow["own_params"] == {"knob.k": 2.0, "knob.ahead": 0}
    assert fast["own_params"] == {"knob.k": 20.0, "knob.ahead": 0}
    assert slow["success"] and fast["success"]
    assert len(waist_slow) == len(waist_fast)
    assert np.max(np.abs(waist_slow - waist_fast)) > np.radians(1.0)  # two different walks
    # the same walk from Python, by the dotted name
    run = pw.simulate(strategy=str(knob), step_length=0.3, steps=2, **{"knob.k": 20})
    assert run.summary["waist_yaw_max_deg"] == fast["waist_yaw_max_deg"]
    assert run.summary["own_params"] == fast["own_params"]
    assert run.command.endswith("--set knob.k=20.0")
    other = pw.simulate(strategy=str(knob), step_length=0.3, steps=2, **{"knob.k": 2})
    assert list(pw.compare([other, run]).columns[:3]) == ["method", "step_length", "knob.k"]


@pytest.mark.parametrize(
    ("assignment", "line"),
    [
        ("knob.k=99", "knob.k = 99.0 is above the maximum 40.0 1/s"),
        ("knob.k=-1", "knob.k = -1.0 is below the minimum 0.0 1/s"),
        ("knob.ahead=1.5", "knob.ahead must be an integer, got '1.5'"),
        ("knob.q=1", "unknown parameter 'knob.q' (one of: "),
    ],
)
def test_bad_own_values_are_one_line_errors_everywhere(knob, tmp_path, capsys, assignment, line):
    walk = ["--strategy", str(knob), "--step-length", "0.3", "--steps", "2"]
    assert cli_main(["simulate", *walk, "--set", assignment]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pelvic-walk simulate: error: {line}") and err.count("\n") == 1
    many = assignment.replace("=", "=1,")  # a sweep axis holding the bad value
    out = tmp_path / "sweep"
    assert cli_main(["sweep", "--strategy", str(knob), "--set", many, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pelvic-walk sweep: error: {line}") and err.count("\n") == 1
    name, _, value = assignment.partition("=")
    with pytest.raises(ValueError) as python_error:
        pw.simulate(strategy=str(knob), step_length=0.3, steps=2, **{name: float(value)})
    if "unknown" in line:
        assert "unknown parameter 'knob.q'" in str(python_error.value)
    elif "an integer" in line:  # from Python: the value itself, not its text
        assert str(python_error.value) == "knob.ahead must be an integer, got 1.5"
    else:
        assert str(python_error.value) == line


def test_run_specs_take_own_parameters_and_aliases_by_their_stored_names(knob):
    (name,) = strategy.load_file(str(knob))
    spec = RunSpec(name, 0.3, 2, overrides=(("knob.k", 12.0), ("com.horizon", 1.2)))
    assert spec.strategy_file is not None and spec.strategy_file.startswith(str(knob))
    assert spec.params().value("knob.k") == 12.0 and spec.params().com.horizon == 1.2
    assert spec.params().own == (("knob.k", 12.0),)
    assert "--set knob.k=12.0" in spec.command() and spec.key.endswith("_knob.k=12.0")
    # a paper parameter by the name under the strategy that owns it: stored by the paper's
    alias = RunSpec("mpc", 0.3, 2, overrides=(("mpc.alpha", 2.0),))
    assert alias == RunSpec("mpc", 0.3, 2, overrides=(("pelvis.alpha", 2.0),))
    assert alias.overrides == (("pelvis.alpha", 2.0),)
    assert alias.params().pelvis.alpha == 2.0 == alias.params().value("mpc.alpha")
    for overrides, message in [
        ((("knob.k", 99.0),), "knob.k = 99.0 is above the maximum 40.0 1/s"),
        ((("knob.q", 1.0),), "override 'knob.q': no such parameter"),
        ((("knob.k", 2.0), ("knob.k", 3.0)), "an override is given twice"),
        ((("mpc.alpha", 2.0), ("pelvis.alpha", 3.0)), "an override is given twice"),
    ]:
        with pytest.raises(ValueError, match=re.escape(message)):
            RunSpec(name, 0.3, 2, overrides=overrides)
    with pytest.raises(ValueError, match="a parameter of the strategy 'knob', not of this run's"):
        RunSpec("mpc", 0.3, 2, overrides=(("knob.k", 2.0),))


def test_a_spec_with_an_own_parameter_crosses_to_a_process_that_loads_the_file_first(knob):
    """The spec pickled as a worker gets it: a fresh interpreter knows no ``knob`` until the
    spec's ``strategy_file`` is loaded, then reads and checks the override."""
    (name,) = strategy.load_file(str(knob))
    blob = pickle.dumps(RunSpec(name, 0.3, 2, overrides=(("knob.k", 12.0),)))
    code = textwrap.dedent(
        """
        import pickle, sys
        from controller import strategy
        assert not strategy.is_registered("knob")
        spec = pickle.loads(sys.stdin.buffer.read())
        p = spec.config().params
        print(p.method, p.value("knob.k"), p.own_params("knob").k)
        """
    )
    out = subprocess.run(
        [sys.executable, "-c", code], input=blob, capture_output=True, cwd=ROOT, timeout=120
    )
    assert out.returncode == 0, out.stderr.decode()
    assert out.stdout.decode().split() == ["knob", "12.0", "12.0"]


def test_spec_of_keeps_the_runs_own_values_and_leaves_other_strategies_out(knob):
    (name,) = strategy.load_file(str(knob))
    p = ControllerParams().replace(method=name, knob={"k": 3.0}, walk={"step_length": 0.3})
    assert spec_of(p).overrides == (("knob.k", 3.0),)
    # an MPC robot that carries a shared setting of knob's (a live session's): the same walk
    mpc = p.replace(method="mpc", pelvis={"alpha": 2.0})
    spec = spec_of(mpc)
    assert spec.overrides == (("pelvis.alpha", 2.0),) and spec.params().own == ()


def test_a_sweep_over_an_own_parameter_one_row_per_value_others_share_their_run(knob, tmp_path):
    out = tmp_path / "sweep"
    argv = ["sweep", "--strategy", str(knob), "--methods", "fixed,knob", "--set",
            "knob.k=2,20", "walk.n_steps=2", "walk.step_length=0.3", "--measure", "summary",
            "--out", str(out), "--jobs", "2"]  # fmt: skip
    assert cli_main(argv) == 0  # a local process pool: the workers load knob.py first
    rows = [json.loads(line) for line in (out / "sweep.jsonl").read_text().splitlines()]
    assert [(r["knob.k"], r["method"], r["runs"]) for r in rows] == [
        (2.0, "fixed", 1),
        (2.0, "knob", 1),
        (20.0, "fixed", 0),  # the fixed pelvis does not read knob.k: the first cell's run
        (20.0, "knob", 1),
    ]
    fixed = [r for r in rows if r["method"] == "fixed"]
    assert fixed[0]["waist_yaw_max_deg"] == fixed[1]["waist_yaw_max_deg"]
    mine = [r for r in rows if r["method"] == "knob"]
    assert mine[0]["waist_yaw_max_deg"] != mine[1]["waist_yaw_max_deg"]
    assert "knob.k" in json.loads((out / "grid.json").read_text())
    # the tasks: the fixed pelvis's second cell shares the first's runs
    grid = make_grid([("knob.k", [2, 20])], methods=["fixed", "knob"], measure="summary")
    tasks = make_tasks(grid.cells(), grid.methods, grid.measure)
    assert [isinstance(t, SameRuns) for t in tasks] == [False, False, True, False]


def test_every_old_parameter_name_still_works(tmp_path):
    from app.cli import build_parser

    def params(*argv: str) -> ControllerParams:
        args = build_parser().parse_args(["simulate", "--method", "mpc", "--step-length", "0.3",
                                          *argv])  # fmt: skip
        return params_from_args(args, method="mpc")

    k = params("--pelvis-k-pel", "0.3")
    assert k == params("--set", "pelvis.k_pel=0.3") and k.pelvis.k_pel == 0.3
    h = params("--horizon", "1.2")
    assert h == params("--set", "com.horizon=1.2") and h.com.horizon == 1.2
    a = params("--set", "mpc.alpha=2")
    assert a == params("--set", "pelvis.alpha=2") == params("--pelvis-alpha", "2")
    w = params("--set", "redundancy.weight=0.5")
    assert w == params("--set", "ik.redundancy_weight=0.5")
    # the Python keywords: the CLI's names with underscores, dotted names, aliases
    from pelvic_walk._params import controller_params

    assert controller_params("mpc", {"pelvis_k_pel": 0.3, "step_length": 0.3}) == k
    assert controller_params("mpc", {"horizon": 1.2, "step_length": 0.3}) == h
    assert controller_params("mpc", {"mpc.alpha": 2, "step_length": 0.3}) == a
    with pytest.raises(ValueError, match="pelvis.alpha is given twice"):
        controller_params("mpc", {"mpc.alpha": 2, "pelvis.alpha": 2})
    # an old grid file's names
    grid = make_grid([("pelvis.k_pel", [0.2, 0.3]), ("mpc.beta", 1e-4)], methods=["mpc"])
    assert grid.axes[0].name == "pelvis.k_pel" and grid.fixed == (("pelvis.beta", 1e-4),)


def test_the_example_keeps_its_gain_as_a_parameter(tmp_path):
    example = str(ROOT / "examples" / "track_reference.py")
    try:
        walk = ["--strategy", example, "--step-length", "0.3", "--steps", "2"]
        default, _ = _simulate(tmp_path, *walk)
        assert default["own_params"] == {"track_ref.gain": 8.0}
        low, _ = _simulate(tmp_path, *walk, "--set", "track_ref.gain=1")
        assert low["own_params"] == {"track_ref.gain": 1.0}
        assert low["waist_yaw_max_deg"] < default["waist_yaw_max_deg"] - 1.0  # it lags more
        run = pw.simulate(strategy=example, step_length=0.3, steps=2, **{"track_ref.gain": 1})
        assert run.summary["waist_yaw_max_deg"] == low["waist_yaw_max_deg"]
    finally:
        strategy.unregister("track_ref")


def test_the_study_reads_whose_parameters_from_the_registry(knob):
    from app.experiments import definitions, sensitivity

    strategy.load_file(str(knob))
    eff = sensitivity.effective
    paper = (("pelvis.k_pel", 0.3), ("pelvis.alpha", 2.0), ("walk.dsp_ratio", 0.3))
    assert eff("mpc", paper) == tuple(sorted(paper))
    assert eff("fixed", paper) == (("walk.dsp_ratio", 0.3),)
    assert eff("knob", paper) == (("pelvis.k_pel", 0.3), ("walk.dsp_ratio", 0.3))
    assert eff("fixed", (("knob.k", 3.0),)) == () and eff("mpc", (("knob.k", 3.0),)) == ()
    assert eff("knob", (("knob.k", 3.0),)) == (("knob.k", 3.0),)
    weight = (("ik.redundancy_weight", 0.5),)
    assert eff("redundancy", weight) == weight and eff("mpc", weight) == ()
    assert sensitivity.owner("pelvis.beta") == "mpc" and sensitivity.owner("knob.k") == "knob"
    assert sensitivity.owner("pelvis.k_pel") is None
    # on every parameter the study varies, the registry's reading is the old hand-kept one
    # (the fixed pelvis read no "pelvis" parameter, the MPC every one): the same runs
    for study in (definitions.FULL, definitions.QUICK):
        s = study.sensitivity
        cells = sensitivity.grid_cells(s) + [c.overrides for c in s.cells]
        for ov in cells:
            assert eff("mpc", ov) == tuple(sorted(ov))
            paperless = tuple(sorted(o for o in ov if not o[0].startswith("pelvis.")))
            assert eff("fixed", ov) == paperless


def test_the_held_out_strategy_from_the_docs_alone_is_tuned_and_swept(tmp_path):
    """docs/STRATEGIES.md, "Its own parameters": its example copied into a file, run with two
    values of its parameter (two different walks) and swept (one row per value)."""
    text = (ROOT / "docs" / "STRATEGIES.md").read_text()
    section = text.split("## Its own parameters", 1)[1].split("\n## ", 1)[0]
    code = re.search(r"```python\n(.*?)```", section, re.S)
    assert code is not None and "param(" in code.group(1)
    path = tmp_path / "my_pelvis.py"
    path.write_text(code.group(1))
    (name,) = strategy.load_file(str(path))
    try:
        ((field, meta),) = [(f, m) for f, m in _fields_of(name)]
        dotted = f"{name}.{field}"
        low, high = meta["min"] + 1.0, meta["default"] * 2.5
        runs = [
            pw.simulate(strategy=str(path), step_length=0.3, steps=2, **{dotted: v})
            for v in (low, high)
        ]
        waist = [r.column("waist_angle") for r in runs]
        assert all(r.summary["success"] for r in runs)
        assert np.max(np.abs(waist[0] - waist[1])) > np.radians(1.0)
        table = pw.sweep([str(path)], measure="summary", jobs=1, steps=2, step_length=0.3,
                         **{dotted: [low, high]})  # fmt: skip
        assert list(table[dotted]) == [low, high] and list(table["method"]) == [name] * 2
        assert list(table["waist_yaw_max_deg"]) == [r.summary["waist_yaw_max_deg"] for r in runs]
    finally:
        strategy.unregister(name)


def _fields_of(name: str):
    from controller.params import OWN_PARAMS, spec

    return spec(OWN_PARAMS[name]).items()


def test_experiments_set_reaches_the_runs_whose_strategy_reads_it(knob, capsys):
    """``experiments --set``: a paper parameter sets every run, a strategy's own only its
    strategy's runs (the MPC's runs do not carry ``knob.k``); bad ones exit 2 in one line."""
    import dataclasses

    from app.cli.options import study_overrides
    from app.experiments.definitions import QUICK, planned_runs
    from app.experiments.sensitivity import plan

    strategy.load_file(str(knob))
    overrides = study_overrides(["pelvis.k_pel=0.3", "knob.k=12", "mpc.beta=1e-4"])
    assert overrides == (("knob.k", 12.0), ("pelvis.beta", 1e-4), ("pelvis.k_pel", 0.3))
    study = dataclasses.replace(QUICK, methods=(*QUICK.methods, "knob"), overrides=overrides)
    specs = list(planned_runs(study))
    assert {s.method for s in specs} >= {"fixed", "mpc", "knob"}
    for s in specs:
        ov = dict(s.overrides)
        assert ov["pelvis.k_pel"] == 0.3 and ov["pelvis.beta"] == 1e-4
        assert ("knob.k" in ov) == (s.method == "knob")
        assert s.params().pelvis.k_pel == 0.3
    knob_runs = [s for s in specs if s.method == "knob"]
    assert knob_runs and all(s.params().own_params("knob").k == 12.0 for s in knob_runs)
    for m, _ov, task in plan(study):
        assert ("knob.k" in dict(task.cell.fixed)) == (m == "knob")
    for bad, line in [
        ("pelvis.k_pel=3", "pelvis.k_pel = 3.0 is above the maximum 1.0"),
        ("walk.n_steps=4", "--set walk.n_steps: the study sets it for each run"),
        ("knob.nope=1", "unknown parameter 'knob.nope'"),
    ]:
        assert cli_main(["experiments", "--out", "/nonexistent/o", "--set", bad]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and line in err, err


@pytest.mark.parametrize("name", ["walk", "pelvis", "robot", "robots", "methods"])
def test_a_strategy_may_not_take_a_groups_or_a_request_fields_name(tmp_path, name):
    """Its own parameters are named NAME.FIELD beside the paper's groups, and the API's
    parameter requests hold these fields: such a name would be ambiguous, so it is refused."""
    path = tmp_path / f"s_{name}.py"
    path.write_text(
        "from pelvic_walk import PelvisStrategy\n\n"
        f"class S(PelvisStrategy):\n    name = {name!r}\n\n"
        "    def waist_rate(self, s):\n        return 0.0\n"
    )
    with pytest.raises(strategy.StrategyLoadError, match=f"the name '{name}' is a parameter"):
        strategy.load_file(str(path))
    assert not strategy.is_registered(name)
