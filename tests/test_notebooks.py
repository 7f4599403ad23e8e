"""The course notebooks (notebooks/): stored without outputs, each runs top to bottom in a
Jupyter kernel (nbclient) with no error, and the exercises' checks accept the right answer,
refuse a wrong one and wait for a missing one.

The notebooks run in ``make test`` (``slow``: ``make check`` skips them); each is its own xdist
group (tests/conftest.py), so the two workers share them.
"""

from __future__ import annotations

import importlib.util
import math
import re
import sys
import time
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = ROOT / "notebooks"
BOOKS = sorted(p.name for p in NOTEBOOKS.glob("*.ipynb"))
# a number printed as nan (a student cannot read it); not the value a faulty strategy returned,
# which its message names ("waist_rate returned nan, not a finite number")
NAN = re.compile(r"(?<!returned )\bnan\b", re.IGNORECASE)
CELL_TIMEOUT_S = 900  # a cell's walks on a loaded machine; the lessons take ~30 s unloaded


def test_the_course_has_its_five_lessons_stored_without_outputs():
    import nbformat

    assert [b[:2] for b in BOOKS] == ["01", "02", "03", "04", "05"]
    for name in BOOKS:
        book = nbformat.read(NOTEBOOKS / name, as_version=4)
        nbformat.validate(book)
        assert book.cells[0].cell_type == "markdown", f"{name}: a lesson starts with prose"
        for cell in book.cells:
            if cell.cell_type == "code":
                assert cell.outputs == [] and cell.execution_count is None, (
                    f"{name}: stored with outputs (clear them before committing)"
                )


@pytest.mark.slow
@pytest.mark.parametrize("name", BOOKS)
def test_notebook_runs_top_to_bottom(name, capsys):
    """Every cell, in order, in a fresh kernel started in notebooks/ (as JupyterLab would)."""
    import nbformat
    from nbclient import NotebookClient

    book = nbformat.read(NOTEBOOKS / name, as_version=4)
    client = NotebookClient(
        book,
        timeout=CELL_TIMEOUT_S,
        kernel_name="python3",
        resources={"metadata": {"path": str(NOTEBOOKS)}},
    )
    start = time.perf_counter()
    client.execute()  # raises CellExecutionError with the cell and its traceback
    wall = time.perf_counter() - start
    printed = [
        out.get("text", "")
        for cell in book.cells
        if cell.cell_type == "code"
        for out in cell.outputs
        if out.output_type == "stream"
    ]
    verdicts = [line for text in printed for line in text.splitlines() if line[:1] in "✓✗…"]
    assert verdicts, f"{name}: no exercise check ran"
    shown = printed + [  # what a cell prints and the reprs it ends with (a table's missing
        # value, pandas' NaN in a DataFrame, is a table's convention: not checked here)
        out.get("data", {}).get("text/plain", "")
        for cell in book.cells
        if cell.cell_type == "code"
        for out in cell.outputs
        if out.output_type == "execute_result" and "text/html" not in out.get("data", {})
    ]
    nans = [line for text in shown for line in text.splitlines() if NAN.search(line)]
    assert not nans, f"{name}: a number printed as nan: {nans[:3]}"
    with capsys.disabled():
        print(f"\n{name}: {wall:.1f} s wall, {len(verdicts)} checks")


# -- the checks themselves -------------------------------------------------------------------
def _checks():
    spec = importlib.util.spec_from_file_location("course_checks", NOTEBOOKS / "checks.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["course_checks"] = module
    spec.loader.exec_module(module)
    return module


def test_checks_of_numbers_accept_the_right_answer_only(capsys):
    import pelvic_walk as pw

    checks = _checks()
    assert checks.eq4(...).ok is None
    assert checks.eq4(math.sqrt(0.75**2 - 0.68**2)).ok is True
    assert checks.eq4(0.31 + 0.01).ok is False
    assert checks.eq4("a lot").ok is False
    assert checks.best_angle(45).ok is True and checks.best_angle(90).ok is False
    ours = pw.robot()
    fixed = math.sqrt(ours["l_leg"] ** 2 - ours["z0"] ** 2)
    right = 100 * ours["l_pel"] * 0.5 / fixed  # sin 45 cos 45 = 1/2
    assert checks.our_increase(right).ok is True
    assert checks.our_increase(35.0).ok is False
    out = capsys.readouterr().out
    assert "not answered yet" in out and "✓" in out and "✗" in out and "Hint" in out


def test_checks_of_runs_read_the_runs(capsys):
    import pelvic_walk as pw

    checks = _checks()
    walk = pw.simulate("mpc", step_length=0.3, steps=2)
    fixed = pw.simulate("fixed", step_length=0.3, steps=2)
    s = walk.series
    plan = walk.horizon(2.0)
    assert checks.horizon_samples(16, walk).ok is True
    assert checks.horizon_samples(15, walk).ok is False
    assert checks.zmp_inside(True, plan).ok is True and checks.zmp_inside(False, plan).ok is False
    moved = plan.copy()
    moved["zmp_y [m]"] = moved["zmp_max_y [m]"] + 0.1  # a plan outside its bounds
    assert checks.zmp_inside(False, moved).ok is True

    row = plan[np.isclose(plan["ahead [s]"], 1.0)].iloc[0]
    measured = np.interp(row["t [s]"], s["t [s]"], s["com_y [m]"])
    error_cm = abs(row["com_y [m]"] - measured) * 100
    assert checks.prediction_error(error_cm, walk, plan, 1.0).ok is True
    assert checks.prediction_error(error_cm + 1, walk, plan, 1.0).ok is False

    walking = s["step_index"] >= 0
    d = (s["waist_angle_cmd [rad]"] - s["theta_ref [rad]"])[walking]
    assert checks.tracking_error(np.degrees(np.sqrt(np.nanmean(d**2))), walk).ok is True
    assert checks.tracking_error(0.0, walk).ok is False

    ssp = np.flatnonzero((s["step_index"].to_numpy() == 0) & (s["in_ssp"].to_numpy() == 1))
    at_touchdown = abs(np.degrees(s["waist_angle [rad]"].iloc[ssp[-1]]))
    assert checks.angle_at_touchdown(at_touchdown, walk).ok is True
    assert checks.angle_at_touchdown(at_touchdown + 1.0, walk).ok is False

    assert checks.more_turn("high", fixed, walk).ok is True  # walk turns, fixed does not
    assert checks.more_turn("low", fixed, walk).ok is False
    assert checks.method_with("mpc", [fixed, walk], "waist_yaw_max_deg").ok is True
    assert checks.method_with("fixed", [fixed, walk], "waist_yaw_max_deg").ok is False
    assert checks.method_with("nope", [fixed, walk], "waist_yaw_max_deg").ok is False
    assert checks.clean_at_long_step({"fixed", "mpc"}, [fixed, walk]).ok is True
    assert checks.clean_at_long_step({"mpc"}, [fixed, walk]).ok is False
    a, b = walk.summary["yaw_momentum_peak"], fixed.summary["yaw_momentum_peak"]
    assert checks.arms_share(100 * (1 - a / b), walk, fixed).ok is True
    assert checks.clean_beside_mpc(fixed, walk).ok is False  # a paper's method, not yours
    assert checks.shortest_walking_horizon(1.6, {1.6: walk}).ok is True
    assert checks.stopped_at(1.0, walk).ok is False  # nothing stopped it
    capsys.readouterr()


def test_the_check_of_what_stops_the_fixed_pelvis_wants_a_name(capsys):
    import pelvic_walk as pw

    checks = _checks()
    fixed = pw.simulate("fixed", step_length=0.42, steps=3)
    s = fixed.series
    rec = fixed.qp(float(s.loc[s["active_ik"] > 1, "t [s]"].iloc[-1]))
    assert checks.stops_the_fixed_pelvis(..., fixed).ok is None
    assert checks.stops_the_fixed_pelvis("knee at its straight limit", fixed).ok is True
    assert checks.stops_the_fixed_pelvis("Right knee at its straight limit (0 deg)", fixed).ok
    # the reference's answer passed in (the record, its names, their text) does not pass
    for given in (rec, rec["ik"], rec["ik"].names(), str(rec["ik"].names()), rec["ik"].active):
        assert checks.stops_the_fixed_pelvis(given, fixed).ok is False, given
    assert checks.stops_the_fixed_pelvis("waist rate pinned by the strategy", fixed).ok is False
    assert checks.stops_the_fixed_pelvis("knee at its speed limit", fixed).ok is False
    walk = pw.simulate("mpc", step_length=0.3, steps=2)  # nothing but the pin binds
    assert checks.stops_the_fixed_pelvis("knee at its straight limit", walk).ok is False
    out = capsys.readouterr().out
    assert "binds too, but less often" in out and "as a string" in out


def test_checks_of_a_stopped_strategy():
    import pelvic_walk as pw
    from controller import strategy

    checks = _checks()

    class Stops(pw.PelvisStrategy):
        name = "nb_stops"

        def waist_rate(self, s):
            return float("nan") if s.t > 1.0 else 0.0

    try:
        run = pw.simulate(strategy=Stops, step_length=0.2, steps=1)
    finally:
        strategy.unregister("nb_stops")
    assert run.summary["strategy_error"] and run.summary["strategy_error_time"] > 1.0
    assert checks.stopped_at(run.column("t")[-1], run).ok is True
    assert checks.stopped_at(0.5, run).ok is False
    assert checks.clean_beside_mpc(run, run).ok is False


def test_exercise_5_1_is_passed_by_a_students_strategy_not_by_the_references_run(capsys):
    """The MPC's own run (or another of the paper's methods) passed in as the student's is
    refused; a student's strategy that walks cleanly passes."""
    import pelvic_walk as pw
    from controller import strategy

    checks = _checks()
    mpc = pw.simulate("mpc", step_length=0.3, steps=2)

    class Still(pw.PelvisStrategy):
        name = "nb_still"

        def waist_rate(self, s):
            return 0.0

    try:
        mine = pw.simulate(strategy=Still, step_length=0.3, steps=2)
    finally:
        strategy.unregister("nb_still")
    capsys.readouterr()
    assert checks.clean_beside_mpc(mpc, mpc).ok is False
    assert "not your strategy's" in capsys.readouterr().out
    assert checks.clean_beside_mpc(mine, mine).ok is False  # the second must be the MPC's
    assert checks.clean_beside_mpc(mine, mpc).ok is True


def test_a_run_stopped_before_its_first_landing_prints_no_nan():
    """Notebook 5's buggy example: a walk its strategy stopped before any landing error was
    measured says so, never "nan"."""
    import pelvic_walk as pw
    from controller import strategy

    class Early(pw.PelvisStrategy):
        name = "nb_early"

        def waist_rate(self, s):
            return float("nan") if s.step == 0 else 0.0

    try:
        run = pw.simulate(strategy=Early, step_length=0.2, steps=2)
    finally:
        strategy.unregister("nb_early")
    assert run.summary["landing_error_max"] is None
    text = repr(run)
    assert "nan" not in text.lower(), text
    assert "landing error max - (none measured)" in text


def test_the_notebook_extra_installs_nbconvert():
    """`pip install -e '.[notebook]'` brings `jupyter nbconvert` (most courses run and grade
    notebooks with it)."""
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = project["optional-dependencies"]
    assert any(d.startswith("nbconvert") for d in extras["notebook"])
    assert any(d.startswith("nbconvert") for d in extras["test"])  # for the test below


@pytest.mark.slow
def test_a_notebook_runs_through_jupyter_nbconvert(tmp_path):
    """Lesson 5 (a student's strategy, a buggy one, the checks) as a course runs it:
    `jupyter nbconvert --to notebook --execute`; no error, its checks print, no nan."""
    import subprocess

    import nbformat

    name = "05_your_own_pelvis.ipynb"
    jupyter = Path(sys.executable).with_name("jupyter")
    done = subprocess.run(
        [str(jupyter), "nbconvert", "--to", "notebook", "--execute", f"--output-dir={tmp_path}",
         f"--ExecutePreprocessor.timeout={CELL_TIMEOUT_S}", str(NOTEBOOKS / name)],
        capture_output=True, text=True, timeout=3 * CELL_TIMEOUT_S, cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    book = nbformat.read(tmp_path / name, as_version=4)
    outputs = [o for c in book.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    text = "\n".join(
        o.get("text", "") or o.get("data", {}).get("text/plain", "")
        for o in outputs
        if "text/html" not in o.get("data", {})  # (tables: pandas' NaN is a missing value)
    )
    assert "STOPPED by its strategy" in text and ("✓" in text or "✗" in text)
    assert not NAN.search(text), text


def test_the_check_of_the_smallest_clean_gain_reads_the_sweeps_table(capsys):
    import pandas as pd

    checks = _checks()
    table = pd.DataFrame({"tuned.gain": [1.0, 4.0, 8.0, 16.0], "clean": [False, False, True, True]})
    assert checks.smallest_clean_gain(..., table, "tuned.gain").ok is None
    assert checks.smallest_clean_gain(8, table, "tuned.gain").ok is True
    assert checks.smallest_clean_gain(16, table, "tuned.gain").ok is False
    assert checks.smallest_clean_gain(8, table, "gain").ok is False  # no such column
    none = table.assign(clean=False)
    assert checks.smallest_clean_gain(8, none, "tuned.gain").ok is False
    out = capsys.readouterr().out
    assert "sweep larger values" in out and "no column 'gain'" in out
