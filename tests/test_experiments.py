"""The study: definitions as data (fast), and ``--quick`` end to end on the local process
pool and on a local 2-CPU Ray instance, which must give the same results.json (slow).

The claims' verdict rules are tested on synthetic results in ``test_claims.py``.
"""

import json
import math
import os
import sys
import time
from pathlib import Path

import pytest

from app.experiments.definitions import (
    FULL,
    QUICK,
    RunSpec,
    Study,
    planned_runs,
    refinement_runs,
    sweep_bracket,
)
from app.experiments.figures import FIGURES
from app.experiments.paper import TABLE1
from app.experiments.results import untimed
from app.experiments.verdicts import VERDICTS
from controller.params import LATERAL_MODES, ControllerParams

SECTIONS = (
    "ablation",
    "kinematics",
    "max_step",
    "equivalent_lengths",
    "waist",
    "yaw_momentum",
    "energy",
    "kappa",
    "zmp",
    "robustness",
    "sensitivity",
    "claims",
    "runs",
    "meta",
    "figures",
)


def test_paper_table1_copied():
    assert TABLE1["mpc"][0.40] == (412.34, 34.15)
    assert TABLE1["redundancy"][0.15] == (12.79, 3.04)
    assert TABLE1["fixed"][0.35] is None and TABLE1["fixed"][0.40] is None
    assert FULL.energy_lengths == tuple(TABLE1["mpc"])


def test_shared_runs_are_deduplicated():
    req = planned_runs(FULL)
    shared = FULL.figure_run("mpc", 0.30)
    assert {"step", "walk", "zmp"} <= req[shared]  # sweep, waist, kappa, yaw, ZMP: one run
    assert len(req) == len(set(req))
    energy = [s for s in req if s.seed is not None and s.push_std is None]
    assert len(energy) == len(FULL.energy_lengths) * 3 * FULL.energy_repeats
    assert all(s.n_steps == 20 and s.perturbation == 0.01 for s in energy)
    # the robustness section's walks under larger pushes: 20 per method at 0.30 m, 15 N
    heavy = [s for s in req if s.push_std is not None]
    assert FULL.falls is not None and len(heavy) == 3 * FULL.falls.walks
    assert {(s.step_length, s.disturbance, s.n_steps) for s in heavy} == {(0.3, 15.0, 10)}
    assert heavy[0].command().endswith("--seed 0 --disturbance 15")
    # the ablation: the MPC with the reference from the state now, at the figure lengths
    ablation = [s for s in req if ("pelvis.reference", "now") in s.overrides]
    assert sorted(s.step_length for s in ablation) == list(FULL.figure_lengths)


def test_sweep_bracket_and_refinement():
    clean = {0.30: True, 0.35: True, 0.40: False, 0.45: True}
    assert sweep_bracket(clean) == (0.35, 0.40)
    req = refinement_runs(FULL, {"fixed": clean, "mpc": {0.40: True, 0.45: False}})
    fixed = sorted(s.step_length for s in req if s.method == "fixed")
    assert fixed == [0.36, 0.37, 0.38, 0.39]
    assert RunSpec("mpc", 0.37, FULL.n_steps) in req  # the fixed pelvis's limit, every method
    assert RunSpec("mpc", 0.41, FULL.n_steps) in req
    assert sweep_bracket({0.3: False}) == (None, 0.3)
    assert refinement_runs(FULL, {"fixed": {0.3: False}}) == {}


def test_run_spec_keys_are_stable():
    assert RunSpec("mpc", 0.3, 10).key == "mpc_L0.300_n10_arms_s-"
    assert RunSpec("fixed", 0.15, 20, True, 3).key == "fixed_L0.150_n20_arms_s3"
    assert RunSpec("redundancy", 0.4, 6, False).key == "redundancy_L0.400_n6_noarms_s-"


def test_run_spec_push_size():
    """A seeded spec may push harder than the study's 5 N: its own key and command; the
    study's size keeps the old key, and a size needs a seed."""
    hard = RunSpec("mpc", 0.3, 20, True, 3, push_std=15.0)
    assert hard.disturbance == 15.0 and hard.config().disturbance == 15.0
    assert hard.key == "mpc_L0.300_n20_arms_s3_push15N"
    assert hard.command().endswith("--seed 3 --disturbance 15")
    assert RunSpec("mpc", 0.3, 20, True, 3, push_std=5.0).key == "mpc_L0.300_n20_arms_s3"
    with pytest.raises(ValueError, match="seed"):
        RunSpec("mpc", 0.3, 20, push_std=15.0)
    with pytest.raises(ValueError):
        RunSpec("mpc", 0.3, 20, True, 3, push_std=-1.0)


def test_run_spec_overrides_any_parameter():
    a = RunSpec("mpc", 0.3, 10, overrides=(("pelvis.k_pel", 0.3), ("walk.dsp_ratio", 0.1)))
    b = RunSpec("mpc", 0.3, 10, overrides=(("walk.dsp_ratio", 0.1), ("pelvis.k_pel", 0.3)))
    assert a == b and hash(a) == hash(b) and a != RunSpec("mpc", 0.3, 10)
    assert a.key == "mpc_L0.300_n10_arms_s-_pelvis.k_pel=0.3_walk.dsp_ratio=0.1"
    p = a.params()
    assert (p.method, p.walk.step_length, p.walk.n_steps, p.arms.enabled) == ("mpc", 0.3, 10, True)
    assert p.pelvis.k_pel == 0.3 and p.walk.dsp_ratio == 0.1
    assert RunSpec("fixed", 0.2, 4, arms=False).params().arms.enabled is False
    for bad in (
        ("pelvis.nope", 1.0),  # no such parameter
        ("nope.k_pel", 1.0),  # no such group
        ("walk.step_length", 0.3),  # a field of the spec itself
    ):
        with pytest.raises(ValueError):
            RunSpec("mpc", 0.3, 10, overrides=(bad,))
    with pytest.raises(ValueError):  # out of its range: checked by ControllerParams
        RunSpec("mpc", 0.3, 10, overrides=(("pelvis.k_pel", 5.0),)).params()
    study = Study("sweep", 4, 1, (0.3,), 0.05, (0.3,), 1, 4, overrides=(("pelvis.k_pel", 0.3),))
    runs = planned_runs(study)  # the study's overrides on every run (+ the lateral readings
    assert all(("pelvis.k_pel", 0.3) in s.overrides for s in runs)  # and the ablation)
    default = ControllerParams().pelvis.lateral_distance
    assert {s.overrides for s in runs} == {
        (("pelvis.k_pel", 0.3),),
        (("pelvis.k_pel", 0.3), ("pelvis.reference", "now")),
    } | {
        (("pelvis.k_pel", 0.3), ("pelvis.lateral_distance", m))
        for m in LATERAL_MODES
        if m != default
    }


def _check_tables(markdown: str) -> None:
    """Every row of every table has its header's number of cells (a "|" in a cell escaped)."""
    width = None
    for line in markdown.splitlines():
        if not line.startswith("|"):
            width = None
            continue
        cells = line.replace("\\|", "").count("|")
        width = width or cells
        assert cells == width, line


def _finite(x):
    return x is not None and math.isfinite(x)


def _children() -> set[int]:
    """Live (non-zombie) child processes of this test process."""
    me, out = os.getpid(), set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields_ = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields_[1]) == me and fields_[0] != "Z":
            out.add(int(stat.parent.name))
    return out


# a student's strategy outside the checkout: a gain on the waist toward half the reference
STUDENT = """
from pelvic_walk import PelvisStrategy


class HalfReference(PelvisStrategy):
    name = "half_ref"

    def waist_rate(self, s):
        return 6.0 * (0.5 * s.theta_ref[0] - s.theta)
"""


@pytest.fixture(scope="module")
def student_file(tmp_path_factory):
    from controller import strategy

    before = set(strategy.names())
    path = tmp_path_factory.mktemp("student") / "half_ref.py"
    path.write_text(STUDENT)
    yield str(path)
    for name in set(strategy.names()) - before:  # the student's and the examples
        strategy.unregister(name)


@pytest.fixture(scope="module")
def quick_local(tmp_path_factory, student_file):
    """``experiments --quick --strategy half_ref.py`` on the local process pool (2 workers)."""
    from app.experiments.runner import main

    out = tmp_path_factory.mktemp("quick_local")
    assert main(out, quick=True, jobs=2, strategies=(student_file,)) == 0
    return out


@pytest.mark.slow
def test_quick_study(quick_local):
    tmp_path = quick_local
    report = (tmp_path / "report.md").read_text()
    assert "Generated by `pelvic-walk experiments" in report and "--quick" in report
    for n in range(1, 11):
        assert f"## {n}. " in report
    assert "## Summary" in report and "## Words used in this report" in report
    data = json.loads((tmp_path / "results.json").read_text())
    assert set(SECTIONS) <= set(data)
    assert not data["meta"]["errors"]
    assert data["meta"]["backend"] == "local process pool, 2 jobs"

    kin = data["kinematics"]
    assert abs(kin["paper_inputs"]["step_max_rotation_static"] - 0.42) < 0.01
    for m in ("fixed", "redundancy", "mpc"):
        ms = data["max_step"][m]
        assert _finite(ms["longest_clean"]) and ms["points"]
    for case in data["waist"]["cases"].values():
        assert _finite(case["peak_abs_angle_deg"]) and _finite(case["peak_abs_rate_deg_s"])
    for case in data["yaw_momentum"]["cases"].values():
        assert _finite(case["arms"]["peak"]) and _finite(case["no_arms"]["peak"])
    cell = data["energy"]["table"]["mpc"][f"{QUICK.energy_lengths[0]:.2f}"]
    assert _finite(cell["mean"]) and _finite(cell["std"]) and cell["n_windows"] > 0
    assert len(cell["run_windows"]) == cell["n_not_fallen"]
    kappa = data["kappa"]["cases"]["mpc@0.30"]
    assert _finite(kappa["kappa_landing_median"]) and _finite(kappa["kappa_legs_run_max"])
    z = data["zmp"]
    assert z["available"] and 0.0 <= z["lipm_in_planned_support_walking"] <= 1.0
    rob = data["robustness"]
    assert {c["runs"] for c in rob["cells"].values()} == {QUICK.energy_repeats}
    assert all(p["survived"] is not None for p in rob["pushes"].values())
    sens = data["sensitivity"]
    assert len(sens["rows"]) == 2 + 4 + 2  # fixed per DSP share, MPC per cell, the authors'
    assert all(len(r["runs_data"]) == r["runs"] for r in sens["rows"])
    assert {c["verdict"] for c in data["claims"]} <= set(VERDICTS)
    assert len(data["claims"]) >= 10
    # every run lists the command that reruns it
    run = next(r for r in data["runs"].values() if r["spec"]["seed"] == 1)
    assert (
        run["command"].startswith("pelvic-walk simulate --method") and "--seed 1" in run["command"]
    )
    _check_tables(report)
    assert "peak \\|d rate/dt\\|" in report
    # section 10: the two examples and the student's strategy beside the MPC, each measured
    rows = {w["method"]: w for w in data["ablation"]["rows"]}
    assert list(rows) == ["fixed", "redundancy", "mpc", "track_ref", "sine", "half_ref"]
    assert [rows[m]["role"] for m in rows] == ["paper"] * 3 + ["example", "example", "yours"]
    for w in rows.values():
        assert w["walks_limit"] is not None and w["waist_peak_deg"]["0.40"] is not None
        assert all(p["survived"] is not None for p in w["pushes"].values()), w["method"]
        assert set(w["pushes"]) == {"left", "right"}
    waist = {m: w["waist_peak_deg"]["0.40"] for m, w in rows.items()}
    assert waist["fixed"] < 0.1 < waist["track_ref"]
    assert rows["mpc"]["pushes"]["left"] == rob["pushes"]["mpc@0.30@left"]  # the same bisection
    mine = [r for r in data["runs"].values() if r["spec"]["method"] == "half_ref"]
    assert mine and all(r["command"].startswith("pelvic-walk simulate --strategy /") for r in mine)
    example = next(r for r in data["runs"].values() if r["spec"]["method"] == "sine")
    assert "--strategy examples/feedforward_sine.py:FeedForwardSine" in example["command"]
    assert "| gain on theta_ref (`track_ref`, example) |" in report
    assert "(`half_ref`, yours)" in report
    assert "**What the MPC's plan buys (section 10):**" in report
    assert "--strategy " in data["meta"]["command"]
    for name in FIGURES:
        png = tmp_path / "figures" / f"{name}.png"
        assert png.exists() and png.stat().st_size > 10_000, name
        assert f"figures/{name}.png" in report


@pytest.mark.slow
def test_quick_study_on_ray_gives_the_same_results(request, tmp_path):
    """``experiments --quick --ray`` (a local Ray instance with 2 CPUs) writes the same
    results.json as the local process pool, timing aside, and leaves no process behind."""
    ray = pytest.importorskip(
        "ray", reason="Ray is an optional extra: pip install '.[cluster]'", exc_type=ImportError
    )
    from app.experiments.runner import main

    local = request.getfixturevalue("quick_local")
    student = request.getfixturevalue("student_file")
    before = _children()
    assert main(tmp_path, quick=True, jobs=2, ray="", strategies=(student,)) == 0
    assert not ray.is_initialized()
    ours = json.loads((tmp_path / "results.json").read_text())
    theirs = json.loads((local / "results.json").read_text())
    assert ours["meta"]["backend"] == "local Ray instance, 2 CPUs"
    assert untimed(ours) == untimed(theirs)
    deadline = time.monotonic() + 120  # Ray's processes end shortly after ray.shutdown()
    while _children() - before and time.monotonic() < deadline:
        time.sleep(0.5)
    assert not _children() - before, "Ray left processes behind"


def test_experiments_without_ray_is_one_line(tmp_path, capsys, monkeypatch):
    from app.cli import main

    monkeypatch.setitem(sys.modules, "ray", None)  # import ray -> ImportError
    assert main(["experiments", "--quick", "--ray", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "pelvic-walk[cluster]" in err


def test_a_runs_command_is_a_valid_simulate_command():
    """The command results.json lists for a run parses as ``pelvic-walk simulate`` and asks
    for the run's parameters and seed."""
    import shlex

    from app.cli import build_parser
    from app.cli.options import params_from_args

    spec = RunSpec("mpc", 0.35, 20, False, 7, (("pelvis.k_pel", 0.45), ("walk.dsp_ratio", 0.3)))
    argv = shlex.split(spec.command())
    assert argv[:2] == ["pelvic-walk", "simulate"]
    args = build_parser().parse_args(argv[1:])
    assert args.seed == 7
    assert params_from_args(args, method=args.method) == spec.params()
    # a walk under larger pushes: simulate builds the same run
    from app.cli import simulate_config

    hard = RunSpec("mpc", 0.3, 20, True, 4, (("pelvis.reference", "now"),), push_std=15.0)
    args = build_parser().parse_args(shlex.split(hard.command())[1:])
    assert simulate_config(args) == hard.config()
