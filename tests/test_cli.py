"""The pelvic-walk command line: good runs and bad arguments (exit 2, one line)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from app.cli import main
from pelvic_walk.core.run import SUMMARY_KEYS
from pelvic_walk.core.summary import TIMING_KEYS

BAD = [
    ["simulate", "--method", "fixed", "--step-length", "0"],
    ["simulate", "--method", "fixed", "--step-length", "-0.1"],
    ["simulate", "--method", "fixed", "--step-length", "0.7"],
    ["simulate", "--method", "fixed", "--step-length", "nan"],
    ["simulate", "--method", "fixed", "--step-length", "abc"],
    ["simulate", "--method", "sideways", "--step-length", "0.2"],
    ["simulate", "--method", "mpc", "--step-length", "0.2", "--horizon", "0.01"],
    ["simulate", "--method", "mpc", "--step-length", "0.2", "--steps", "0"],
    ["simulate", "--method", "mpc", "--step-length", "0.2", "--step-time", "inf"],
    ["simulate", "--step-length", "0.2"],
    ["fly"],
    ["simulate", "--method", "fixed", "--step-length", "0.2", "--json", "/nonexistent/x.json"],
    ["simulate", "--method", "fixed", "--step-length", "0.2", "--csv", "/"],
    ["bench", "--json", "/nonexistent/b.json"],
    ["simulate", "--method", "mpc", "--step-length", "0.2", "--disturbance", "5"],  # no seed
    ["simulate", "--method", "mpc", "--step-length", "0.2", "--seed", "1", "--disturbance", "-1"],
    ["serve", "--methods", "fixed,sideways"],
    ["push-study", "--methods", ","],
    ["sweep", "--set", "walk.dsp_ratio=0.1,0.2", "--methods", "fixed,sideways"],
]


@pytest.mark.parametrize("argv", BAD, ids=lambda a: " ".join(a))
def test_bad_arguments_exit_2_with_one_line(argv):
    proc = subprocess.run(
        [sys.executable, "-m", "app.cli", *argv], capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 2
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stderr
    assert "error" in lines[0]
    assert "Traceback" not in proc.stderr
    assert proc.stdout == ""  # nothing started


def test_simulate_writes_every_json_key_and_csv(tmp_path, capsys):
    out, csv = tmp_path / "out.json", tmp_path / "series.csv"
    code = main(
        [
            "simulate",
            "--method",
            "mpc",
            "--step-length",
            "0.15",
            "--steps",
            "2",
            "--json",
            str(out),
            "--csv",
            str(csv),
        ]
    )
    assert code == 0
    summary = json.loads(out.read_text())
    assert set(SUMMARY_KEYS) <= set(summary)
    assert summary["success"] is True
    assert summary["steps_planned"] == 2
    header = csv.read_text().splitlines()[0].split(",")
    assert {"t", "waist_angle", "yaw_momentum", "kappa_low"} <= set(header)
    assert "success" in capsys.readouterr().out


def test_analyze_reproduces_the_paper_numbers(tmp_path):
    out = tmp_path / "a.json"
    assert main(["analyze", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["step_max_fixed_static"] == pytest.approx(0.31, abs=0.01)
    assert data["step_max_rotation_static"] == pytest.approx(0.42, abs=0.01)


def _simulate(tmp_path, *extra: str, length: str = "0.3", steps: str = "3") -> dict:
    out = tmp_path / f"run{len(list(tmp_path.iterdir()))}.json"
    argv = ["simulate", "--method", "mpc", "--step-length", length, "--steps", steps]
    assert main([*argv, *extra, "--json", str(out)]) == 0
    return json.loads(out.read_text())


def test_simulate_seed_runs_the_studys_repeat(tmp_path):
    """`simulate --seed N` is the study's repeat N of the same cell: every summary key equal."""
    from app.experiments.worker import execute
    from pelvic_walk.core.run_spec import RunSpec

    cli = _simulate(tmp_path, "--seed", "4", "--set", "pelvis.k_pel=0.3")
    spec = RunSpec("mpc", 0.3, 3, True, 4, (("pelvis.k_pel", 0.3),))
    study = execute(spec, (), 0).summary.as_dict()
    keys = (set(cli) & set(study)) - set(TIMING_KEYS)
    assert set(SUMMARY_KEYS) - set(TIMING_KEYS) <= keys
    assert {k: cli[k] for k in keys} == {k: study[k] for k in keys}
    assert spec.command().startswith("pelvic-walk simulate --method mpc --step-length 0.3")


def test_two_seeds_differ_and_the_disturbance_can_be_sized_or_turned_off(tmp_path):
    e = {
        name: _simulate(tmp_path, *extra)["energy_two_step_mean"]
        for name, extra in {
            "seed 0": ("--seed", "0"),
            "seed 1": ("--seed", "1"),
            "seed 0, 5 N": ("--seed", "0", "--disturbance", "5"),
            "seed 0, no pushes": ("--seed", "0", "--disturbance", "0"),
        }.items()
    }
    assert abs(e["seed 0"] - e["seed 1"]) > 0.005 * e["seed 0"]  # the repeats are not copies
    assert e["seed 0, 5 N"] == e["seed 0"]  # 5 N is the study's default
    assert e["seed 0, no pushes"] != e["seed 0"]


def test_a_seeded_api_run_is_the_clis_run(tmp_path):
    """POST /api/runs with a seed runs what `simulate --seed` runs (the study's repeat)."""
    import time

    from app.web.api.headless import RunManager
    from controller.params import ControllerParams

    cli = _simulate(tmp_path, "--seed", "2", steps="2")
    params = ControllerParams().replace(method="mpc", walk={"step_length": 0.3, "n_steps": 2})
    manager = RunManager()
    run_id = manager.submit(params, 2)
    deadline = time.monotonic() + 240
    while (rec := manager.get(run_id)) is not None and rec["status"] not in ("done", "error"):
        assert time.monotonic() < deadline
        time.sleep(0.1)
    assert rec is not None and rec["status"] == "done", rec
    api = rec["summary"]
    assert api["energy_two_step_windows"] == cli["energy_two_step_windows"]
    assert api["landing_errors"] == cli["landing_errors"]


@pytest.mark.parametrize(
    ("argv", "want"),
    [
        (["serve", "--methods", "fixed,mpc"], ["fixed", "mpc"]),
        (["serve", "--methods", "fixed", "mpc"], ["fixed", "mpc"]),
        (["serve", "--methods", "fixed,", "redundancy", "mpc"], ["fixed", "redundancy", "mpc"]),
        (["push-study", "--methods", "mpc,fixed"], ["mpc", "fixed"]),
        (["push-study", "--methods", "mpc", "mpc"], ["mpc"]),
    ],
)
def test_method_lists_take_commas_or_spaces(argv, want):
    from app.cli import build_parser

    assert build_parser().parse_args(argv).methods == want


def test_sweep_lists_take_commas_or_spaces():
    from app.cli import build_parser
    from app.cli.sweep import grid_from_args

    grids = [
        grid_from_args(build_parser().parse_args(["sweep", *argv]))
        for argv in (
            ["--set", "walk.dsp_ratio=0.1,0.2", "--methods", "fixed,mpc", "--measure", "summary"],
            ["--set", "walk.dsp_ratio=0.1", "0.2", "--methods", "fixed", "mpc"],
        )
    ]
    assert grids[0].methods == grids[1].methods == ("fixed", "mpc")
    assert grids[0].axes == grids[1].axes and len(grids[1].cells()) == 2


def test_serve_ray_without_ray_or_with_no_workers_is_one_line(capsys, monkeypatch):
    """``serve --ray``: Ray missing, or ``--workers 0`` (the robots in this process), exit 2
    with one line before anything starts."""
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray -> ImportError
    assert main(["serve", "--ray", "--port", "1", "--viser-port", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "pip install 'pelvic-walk[cluster]'" in err, err
    assert main(["serve", "--ray", "--workers", "0"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--workers 0" in err and "--ray" in err, err


def test_serve_ray_at_an_address_nobody_answers_is_one_line(capsys):
    pytest.importorskip("ray", exc_type=ImportError)
    from app.bench.local_server import free_port

    port = free_port()  # (free: nothing listens there)
    assert main(["serve", "--ray", f"127.0.0.1:{port}"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "cannot reach Ray" in err, err
