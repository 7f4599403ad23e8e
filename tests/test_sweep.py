"""``pelvic-walk sweep`` (``app/cli/sweep.py`` on ``pelvic_walk.core``): grids, the limit search,
the table, the backends.

Fast: grid parsing and expansion (``--set`` and files, every parameter of params.py), bad
arguments (exit 2, one line), the limit search on fake outcomes (monotonic and not), the
driver and outputs on a fake run function. Real runs: a tiny summary sweep on the local
process pool (2 cells x 1 method, 1-step walks), and the same sweep on a local Ray instance
with 2 CPUs, which must give the same table.
"""

from __future__ import annotations

import json
import os
import random
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from app.cli import main as cli_main
from controller import strategy
from controller.strategy import BUILTINS as METHODS
from pelvic_walk.core import sweep_output as output
from pelvic_walk.core.engine import InProcess, OneJob, run_tasks
from pelvic_walk.core.grid import grid_from_file, make_grid, parse_sets
from pelvic_walk.core.measure import (
    LIMIT_COLUMNS,
    OUTCOMES,
    LimitSearch,
    LimitTask,
    clean,
    criteria,
    make_tasks,
    threshold_of,
    walks,
)
from pelvic_walk.core.params import fields
from pelvic_walk.core.summary import SUMMARY_KEYS

TINY = [
    "--set",
    "walk.dsp_ratio=0.15,0.25",
    "--set",
    "walk.n_steps=1",
    "--methods",
    "fixed",
    "--measure",
    "summary",
    "--jobs",
    "2",
]


def main(argv: list[str]) -> int:
    """``pelvic-walk sweep ARGV``."""
    return cli_main(["sweep", *argv])


def _call(argv: list[str]) -> int:
    try:
        return main(argv)
    except SystemExit as exc:  # argparse's own errors
        return int(exc.code)


# -- grids ------------------------------------------------------------------------------------
def test_set_options_expand_to_the_cartesian_product():
    grid = make_grid(
        parse_sets(["walk.dsp_ratio=0.1,0.2", "pelvis.k_pel=0.15,0.25,0.35", "walk.n_steps=4"]),
        methods=["fixed", "mpc"],
    )
    assert [a.name for a in grid.axes] == ["walk.dsp_ratio", "pelvis.k_pel"]
    assert grid.fixed == (("walk.n_steps", 4),)
    assert grid.measure == "limit" and grid.methods == ("fixed", "mpc")
    cells = grid.cells()
    assert len(cells) == 6
    assert [dict(c.values) for c in cells[:3]] == [
        {"walk.dsp_ratio": 0.1, "pelvis.k_pel": k} for k in (0.15, 0.25, 0.35)
    ]  # first axis slowest
    spec = cells[4].spec("mpc", 0.33)
    assert (spec.method, spec.step_length, spec.n_steps, spec.arms) == ("mpc", 0.33, 4, True)
    assert dict(spec.overrides) == {"walk.dsp_ratio": 0.2, "pelvis.k_pel": 0.25}
    p = spec.params()
    assert (p.walk.dsp_ratio, p.pelvis.k_pel, p.walk.n_steps) == (0.2, 0.25, 4)
    # default: every registered strategy (the paper's first; another test's loaded examples
    # may follow them in this process)
    default = make_grid(parse_sets(["walk.dsp_ratio=0.3"])).methods
    assert default[:3] == METHODS and default == strategy.names()


def _other_value(meta):
    """An in-range value different from the default, for any field type."""
    if meta["type"] == "bool":
        return not meta["default"]
    if meta.get("choices"):
        return next(c for c in meta["choices"] if c != meta["default"])
    lo, hi, d = meta["min"], meta["max"], meta["default"]
    v = hi if d != hi else lo
    if meta.get("lo_open") and v <= 0:
        v = (d + hi) / 2
    return int(v) if meta["type"] == "int" else v


@pytest.mark.parametrize(
    "group,name,meta", list(fields()), ids=[f"{g}.{n}" for g, n, _ in fields()]
)
def test_every_parameter_can_be_an_axis(group, name, meta):
    dotted = f"{group}.{name}"
    values = [meta["default"], _other_value(meta)]
    text = f"{dotted}=" + ",".join(
        str(v).lower() if isinstance(v, bool) else str(v) for v in values
    )
    grid = make_grid(parse_sets([text]), methods=["mpc"], measure="summary")
    assert grid.axes[0].values == tuple(values)
    for cell in grid.cells():
        p = cell.spec("mpc").params()
        assert getattr(getattr(p, group), name) == dict(cell.values)[dotted]


def test_a_grid_file_yaml_or_json(tmp_path):
    yaml_text = (
        "walk.dsp_ratio: [0.1, 0.2, 0.3]\n"
        "pelvis.k_pel: [0.15, 0.45]\n"
        "arms.enabled: [true, false]\n"
        "walk.n_steps: 6\n"
        "fixed: {com.horizon: 1.4}\n"
        "methods: [mpc, fixed]\n"
        "measure: summary\n"
    )
    (tmp_path / "g.yaml").write_text(yaml_text)
    (tmp_path / "g.json").write_text(
        json.dumps(
            {
                "walk.dsp_ratio": [0.1, 0.2, 0.3],
                "pelvis.k_pel": [0.15, 0.45],
                "arms.enabled": [True, False],
                "walk.n_steps": 6,
                "fixed": {"com.horizon": 1.4},
                "methods": ["mpc", "fixed"],
                "measure": "summary",
            }
        )
    )
    a, b = grid_from_file(tmp_path / "g.yaml"), grid_from_file(tmp_path / "g.json")
    assert a == b
    assert len(a.cells()) == 12 and a.methods == ("mpc", "fixed") and a.measure == "summary"
    assert dict(a.fixed) == {"walk.n_steps": 6, "com.horizon": 1.4}
    spec = a.cells()[-1].spec("fixed")
    assert spec.arms is False and spec.n_steps == 6
    assert dict(spec.overrides) == {"walk.dsp_ratio": 0.3, "pelvis.k_pel": 0.45, "com.horizon": 1.4}
    # the command line's methods and measure win over the file's
    c = grid_from_file(tmp_path / "g.yaml", methods=["redundancy"], measure="limit")
    assert c.methods == ("redundancy",) and c.measure == "limit"
    # grid.json as written by a sweep reads back to the same grid
    (tmp_path / "out").mkdir()
    assert grid_from_file(output.write_grid(tmp_path / "out", a)) == a


BAD_FILES = {
    "malformed.yaml": "walk.dsp_ratio: [0.1, 0.2\n",
    "malformed.json": '{"walk.dsp_ratio": [0.1, }',
    "list.yaml": "- walk.dsp_ratio\n- 0.1\n",
    "empty.yaml": "",
    "unknown.yaml": "walk.speed: [1, 2]\n",
    "nested.yaml": "walk.dsp_ratio: [[0.1, 0.2]]\n",
    "no_values.yaml": "walk.dsp_ratio: []\n",
    "range.yaml": "walk.dsp_ratio: [0.1, 0.9]\n",
    "type.yaml": "walk.n_steps: [2, 2.5]\n",
    "bool.yaml": "arms.enabled: [true, 3]\n",
    "method.yaml": "walk.dsp_ratio: [0.1]\nmethods: [fixed, hover]\n",
    "measure.yaml": "walk.dsp_ratio: [0.1]\nmeasure: speed\n",
    "fixed.yaml": "walk.dsp_ratio: [0.1]\nfixed: [1, 2]\n",
    "searched.yaml": "walk.step_length: [0.2, 0.3]\nmeasure: limit\n",
}


@pytest.mark.parametrize("name", list(BAD_FILES))
def test_bad_grid_files_exit_2_with_one_line(name, tmp_path, capsys):
    path = tmp_path / name
    path.write_text(BAD_FILES[name])
    assert _call(["--grid", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr()
    lines = [ln for ln in err.err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "error" in lines[0], err.err
    assert err.out == ""
    assert not (tmp_path / "o").exists()  # nothing started, nothing written


BAD_ARGS = [
    [],  # neither --grid nor --set
    ["--set", "walk.dsp_ratio=0.1,0.2", "--grid", "g.yaml"],  # both
    ["--set", "walk.speed=1,2"],  # unknown parameter
    ["--set", "nogroup=1,2"],
    ["--set", "walk.dsp_ratio"],  # no values
    ["--set", "walk.dsp_ratio=0.1,0.9"],  # out of range
    ["--set", "walk.dsp_ratio=0.1,abc"],
    ["--set", "walk.dsp_ratio=0.1,0.1"],  # a value twice
    ["--set", "walk.dsp_ratio=0.1", "--set", "walk.dsp_ratio=0.2"],  # a parameter twice
    ["--set", "walk.dsp_ratio=0.1", "--methods", "fixed", "hover"],  # unknown method
    ["--set", "walk.dsp_ratio=0.1", "--methods", "fixed", "fixed"],
    ["--set", "walk.dsp_ratio=0.1", "--measure", "speed"],
    ["--set", "walk.step_length=0.2,0.3"],  # what the limit measure searches
    ["--set", "walk.dsp_ratio=0.1", "--jobs", "0"],
    ["--set", "walk.dsp_ratio=0.1", "--out", "/dev/null/sweep"],  # unwritable
    ["--set", "walk.dsp_ratio=0.1", "--bogus"],
]


@pytest.mark.parametrize("argv", BAD_ARGS, ids=lambda a: " ".join(a) or "nothing")
def test_bad_arguments_exit_2_with_one_line(argv, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "g.yaml").write_text("walk.dsp_ratio: [0.1, 0.2]\n")
    assert _call(argv) == 2
    err = capsys.readouterr()
    lines = [ln for ln in err.err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "error" in lines[0], err.err
    assert err.out == ""
    assert not (tmp_path / "sweep").exists()


def test_an_out_that_is_a_file_exits_2(tmp_path, capsys):
    (tmp_path / "f").write_text("x")
    assert _call(["--set", "walk.dsp_ratio=0.1", "--out", str(tmp_path / "f")]) == 2
    assert "is a file" in capsys.readouterr().err


def test_python_m_app_cli_sweep_reports_without_traceback(tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "app.cli",
            "sweep",
            "--set",
            "pelvis.k_pel=2",
            "--out",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 2
    assert proc.stderr.strip().count("\n") == 0 and "k_pel" in proc.stderr
    assert "Traceback" not in proc.stderr and proc.stdout == ""


def test_missing_ray_is_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray -> ImportError
    argv = ["--set", "walk.dsp_ratio=0.1", "--ray", "--out", str(tmp_path / "o")]
    assert _call(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "pelvic-walk[cluster]" in err


def _grid_of(argv: list[str]):
    from app.cli import build_parser
    from app.cli.sweep import grid_from_args

    return grid_from_args(build_parser().parse_args(["sweep", *argv]))


def test_lists_take_commas_or_spaces_alike():
    """``--methods fixed mpc`` = ``--methods fixed,mpc``; ``--set X=0.1,0.2`` = ``--set X=0.1
    0.2``, and one --set may carry several assignments."""
    from pelvic_walk.core.params import split_list

    assert split_list(["fixed,mpc"]) == split_list(["fixed", "mpc"]) == ["fixed", "mpc"]
    assert split_list(["fixed,", "mpc"]) == split_list([" fixed , mpc "]) == ["fixed", "mpc"]
    base = _grid_of(
        [
            "--set",
            "walk.dsp_ratio=0.1,0.2",
            "--set",
            "pelvis.k_pel=0.2,0.3",
            "--methods",
            "fixed",
            "mpc",
        ]
    )
    for argv in (
        [
            "--set",
            "walk.dsp_ratio=0.1",
            "0.2",
            "--set",
            "pelvis.k_pel=0.2,0.3",
            "--methods",
            "fixed,mpc",
        ],
        [
            "--set",
            "walk.dsp_ratio=0.1,",
            "0.2",
            "pelvis.k_pel=0.2",
            "0.3",
            "--methods",
            "fixed,",
            "mpc",
        ],
    ):
        assert _grid_of(argv) == base, argv
    assert base.methods == ("fixed", "mpc") and len(base.cells()) == 4


# -- the limit search -------------------------------------------------------------------------
def _search(outcome_of_length) -> LimitSearch:
    search = LimitSearch()
    while (x := search.next_length()) is not None:
        search.record(x, outcome_of_length(x))
    return search


def _threshold(walk_max: float, clean_max: float):
    def outcome(x: float) -> str:
        if x <= clean_max + 1e-9:
            return "clean"
        return "walks" if x <= walk_max + 1e-9 else "fails"

    return outcome


@pytest.mark.parametrize(
    "walk_max,clean_max", [(0.43, 0.37), (0.30, 0.30), (0.55, 0.12), (0.20, 0.10), (0.41, 0.40)]
)
def test_the_limit_search_finds_both_limits_in_few_runs(walk_max, clean_max):
    s = _search(_threshold(walk_max, clean_max))
    r = s.result()
    assert set(r) == set(LIMIT_COLUMNS)
    assert r["walks_limit"] == walk_max and r["walks_first_fail"] == round(walk_max + 0.01, 3)
    assert r["clean_limit"] == clean_max and r["clean_first_fail"] == round(clean_max + 0.01, 3)
    assert r["walks_above"] == [] and r["clean_above"] == []
    assert len(s.order) <= 11 and len(r["trace"].split()) == len(s.order)


def test_the_limit_search_run_counts_over_every_monotonic_case():
    counts = []
    lengths = LimitSearch().lengths
    for wi, walk_max in enumerate(lengths):
        for clean_max in lengths[: wi + 1]:
            s = _search(_threshold(walk_max, clean_max))
            assert s.result()["walks_limit"] == walk_max
            assert s.result()["clean_limit"] == clean_max
            counts.append(len(s.order))
    assert max(counts) <= 11
    assert sum(counts) / len(counts) <= 10


def test_the_limit_search_at_the_range_ends():
    nothing = _search(lambda x: "fails").result()
    assert nothing["walks_limit"] is None and nothing["walks_first_fail"] == 0.10
    assert nothing["clean_limit"] is None
    everything = _search(lambda x: "clean").result()
    assert everything["walks_limit"] == everything["clean_limit"] == 0.60
    assert everything["walks_first_fail"] is None  # at least the range's top
    crashes = _search(lambda x: "error" if x > 0.25 else "clean").result()
    assert crashes["walks_limit"] == crashes["clean_limit"] == 0.25  # a crash is a failure


def test_a_failure_below_a_success_moves_the_limit_below_it():
    # walks up to 0.45 except a hole at 0.35, the very first length tried
    s = _search(lambda x: "fails" if abs(x - 0.35) < 1e-9 or x > 0.45 + 1e-9 else "clean")
    r = s.result()
    assert r["walks_limit"] == 0.34 and r["walks_first_fail"] == 0.35
    assert r["clean_limit"] == 0.34
    # a hole found late (at 0.38, tried in the clean phase after 0.41-0.43 walked): the walks
    # limit moves below it, and the lengths that walked above it are listed
    s = _search(
        lambda x: (
            "fails"
            if abs(x - 0.38) < 1e-9 or x > 0.43 + 1e-9
            else ("clean" if x < 0.395 else "walks")
        )
    )
    r = s.result()
    assert 0.38 in [s.lengths[i] for i in s.order]
    assert r["walks_limit"] == 0.37 and r["walks_first_fail"] == 0.38
    assert r["walks_above"] == [0.41, 0.42, 0.43]
    assert r["clean_limit"] == 0.37 and r["clean_first_fail"] == 0.38


@settings(max_examples=200, deadline=None)
@given(st.lists(st.sampled_from(OUTCOMES), min_size=51, max_size=51))
def test_the_limit_search_is_consistent_with_every_run_it_made(table):
    s = _search(lambda x: table[round((x - 0.10) / 0.01)])
    r = s.result()
    tested = {s.lengths[i]: o for i, o in s.outcomes.items()}
    for crit, ok in (("walks", {"clean", "walks"}), ("clean", {"clean"})):
        lim, fail = r[f"{crit}_limit"], r[f"{crit}_first_fail"]
        if lim is not None:
            assert tested[lim] in ok
        if fail is not None:
            assert tested[fail] not in ok
            assert min(x for x, o in tested.items() if o not in ok) == fail
        if lim is not None and fail is not None:
            assert round(fail - lim, 3) == 0.01  # resolved to 0.01 m
        assert all(o in ok for x, o in tested.items() if lim is not None and x <= lim)
        assert r[f"{crit}_above"] == sorted(
            x for x, o in tested.items() if fail is not None and x > fail and o in ok
        )


class _Spec:
    def __init__(self, x: float):
        self.step_length = x


def _graded_run(spec):
    """Falls past 0.47 m; lands 1 cm off per 0.2 m of step; kappa(legs) 10 ** (10 x - 0.5)."""
    x = spec.step_length
    out = {
        "success": x <= 0.47 + 1e-9,
        "landing_error_max": x / 20,
        "condition_number_legs_max": 10 ** (10 * x - 0.5),
        "solver_failures": 0,
        "servo_saturation_substeps": 0,
        "speed_limited_ticks": 0,
        "wall_s": 0.1,
    }
    return out | {"walks": walks(out), "clean": clean(out)}  # as run_one sets them


def test_one_search_brackets_the_clean_limit_at_every_threshold():
    """A landing error of 1-4 cm and a kappa(legs) bound of 300-3000, from the same runs: each
    limit is the longest length passing that criterion, found in far fewer runs than one
    search per threshold."""
    from pelvic_walk.core.grid import Cell

    tests = criteria(landings=(0.01, 0.02, 0.03, 0.04), kappas=(300.0, 1000.0, 3000.0))
    assert list(tests) == [
        "walks",
        "clean",
        "clean@1cm",
        "clean@3cm",
        "clean@4cm",
        "clean@kappa300",
        "clean@kappa3000",
    ]
    assert threshold_of("clean@3cm") == (0.03, 1000.0) and threshold_of("clean@kappa300") == (
        0.02,
        300.0,
    )
    search = LimitSearch(names=tuple(tests), first=0.40)
    task = LimitTask(Cell(0, (), ()), "mpc", search, tests, run=_graded_run)
    assert run_tasks([task], InProcess()) == task.runs
    row = task.row()
    lengths = search.lengths
    for name, test in tests.items():
        passing = [x for x in lengths if test(_graded_run(_Spec(x)))]
        good = [x for x in passing if all(y in passing for y in lengths if y <= x)]
        assert row[f"{name}_limit"] == (max(good) if good else None), name
    assert (row["walks_limit"], row["clean_limit"]) == (0.39, 0.34)
    assert row["clean@1cm_limit"] == 0.19 and row["clean@3cm_limit"] == 0.34
    assert row["clean@kappa300_limit"] == 0.29 and row["clean@kappa3000_limit"] == 0.39
    assert search.order[0] == lengths.index(0.40)  # tried first
    assert task.runs <= 20 and set(task.outcomes) == {lengths[i] for i in search.order}


def test_clean_at_other_thresholds():
    ok = _graded_run(_Spec(0.25))  # lands 1.25 cm off, kappa(legs) 100
    assert walks(ok) and clean(ok) and not clean(ok, landing=0.01)
    assert not clean(ok, kappa=50.0) and clean(ok, kappa=1e9)
    for bad in ("solver_failures", "servo_saturation_substeps", "speed_limited_ticks"):
        assert not clean({**ok, bad: 1})
    assert not clean({**ok, "condition_number_legs_max": None})


def test_the_engine_runs_one_jobs_in_order_on_any_backend():
    tasks = [OneJob(pow, 2, k, label=str(k)) for k in range(5)]
    assert run_tasks(tasks, _Shuffled(3)) == 5
    assert [t.result for t in tasks] == [1, 2, 4, 8, 16]


# -- the driver and the outputs, on a fake run function -------------------------------------
def _fake_run(spec):
    """Walks up to 0.3 + dsp_ratio + (0.05 for mpc), clean 0.04 m less; deterministic."""
    over = dict(spec.overrides)
    walk_max = 0.3 + over.get("walk.dsp_ratio", 0.2) + (0.05 if spec.method == "mpc" else 0)
    x = spec.step_length
    ok = x <= walk_max + 1e-9
    return {
        "walks": ok,
        "clean": x <= walk_max - 0.04 + 1e-9,
        "success": ok,
        "step_length": x,
        "wall_s": 0.5,
    }


class _Shuffled(InProcess):
    """Finishes the runs in flight in a random order (as a pool or Ray may)."""

    slots = 4

    def __init__(self, seed):
        super().__init__()
        self.rng = random.Random(seed)

    def wait_any(self, handles):
        h = self.rng.choice(list(handles))
        fn, args = self._queue.pop(h)
        return [(h, fn(*args))]


def _limit_rows(grid, backend, run=_fake_run):
    tasks = make_tasks(grid.cells(), grid.methods, grid.measure, run=run)
    n = run_tasks(tasks, backend)
    return output.rows_of(grid, tasks), n


def test_a_2d_limit_sweep_table_and_heatmaps(tmp_path):
    grid = make_grid(
        parse_sets(["walk.dsp_ratio=0.1,0.2,0.3", "pelvis.k_pel=0.2,0.3", "walk.n_steps=3"]),
        methods=["fixed", "mpc"],
    )
    rows, n_runs = _limit_rows(grid, InProcess())
    assert len(rows) == 3 * 2 * 2
    for row in rows:
        expect = 0.3 + row["walk.dsp_ratio"] + (0.05 if row["method"] == "mpc" else 0)
        assert row["walks_limit"] == pytest.approx(min(expect, 0.6))
        assert row["clean_limit"] == pytest.approx(min(expect - 0.04, 0.6))
        assert row["walk.n_steps"] == 3 and 6 <= row["runs"] <= 11
        assert row["wall_s"] == pytest.approx(0.5 * row["runs"])
    assert n_runs == sum(r["runs"] for r in rows)
    # the same table whatever order the runs finish in
    for seed in range(3):
        assert _limit_rows(grid, _Shuffled(seed))[0] == rows

    columns = output.columns_of(grid, rows)
    assert columns[:4] == ["walk.dsp_ratio", "pelvis.k_pel", "walk.n_steps", "method"]
    assert columns[4:] == [*LIMIT_COLUMNS, "runs", "wall_s", "error"]
    csv_path, jsonl_path = output.write_table(tmp_path, columns, rows)
    lines = csv_path.read_text().splitlines()
    assert lines[0].split(",") == columns and len(lines) == 1 + len(rows)
    assert output.read_table(jsonl_path) == [{c: r.get(c) for c in columns} for r in rows]
    figures = output.plot_all(grid, rows, tmp_path)
    assert sorted(p.name for p in figures) == sorted(
        f"heatmap_{q}_{m}.png" for q in ("walks_limit", "clean_limit") for m in ("fixed", "mpc")
    )
    assert all(p.stat().st_size > 5000 for p in figures)


def test_1d_grids_get_line_plots_and_3d_grids_the_table_only(tmp_path):
    one = make_grid(parse_sets(["walk.dsp_ratio=0.1,0.2"]), methods=["fixed", "mpc"])
    rows, _ = _limit_rows(one, InProcess())
    paths = output.plot_all(one, rows, tmp_path)
    assert sorted(p.name for p in paths) == ["line_clean_limit.png", "line_walks_limit.png"]
    three = make_grid(
        parse_sets(["walk.dsp_ratio=0.1,0.2", "pelvis.k_pel=0.2,0.3", "arms.enabled=true,false"]),
        methods=["mpc"],
    )
    rows, _ = _limit_rows(three, InProcess())
    assert len(rows) == 8
    assert {r["arms.enabled"] for r in rows} == {True, False}
    assert output.plot_all(three, rows, tmp_path / "3d") == []


def _fake_summary(spec):
    """A summary-like outcome; the cell with k_pel 0.45 and mpc raises."""
    over = dict(spec.overrides)
    if over.get("pelvis.k_pel") == 0.45 and spec.method == "mpc":
        return {"error": "RuntimeError: boom", "wall_s": 0.1}
    dsp = over.get("walk.dsp_ratio", 0.2)
    return {
        "method": spec.method,
        "step_length": spec.step_length,
        "success": True,
        "steps_completed": spec.n_steps,
        "steps_planned": spec.n_steps,
        "landing_error_max": None if dsp > 0.25 else 0.01,
        "clean": dsp < 0.25,
        "walks": True,
        "waist_yaw_max_deg": 10 * dsp,
        "yaw_momentum_peak": 1.0,
        "energy_two_step_mean": 5.0,
        "condition_number_max": 10 ** (1 + 20 * dsp),
        "condition_number_legs_max": 10 ** (1 + 25 * dsp),
        "wall_s": 0.25,
    }


def test_a_2d_summary_sweep_end_to_end_on_a_fake_run(tmp_path, monkeypatch, capsys):
    from pelvic_walk.core import engine, measure

    real = measure.make_tasks
    monkeypatch.setattr(engine, "make_backend", lambda ray, jobs, n: InProcess())
    monkeypatch.setattr(
        measure,
        "make_tasks",
        lambda cells, methods, kind: real(cells, methods, kind, _fake_summary),
    )
    out = tmp_path / "s"
    argv = [
        "--set",
        "walk.dsp_ratio=0.1,0.3",
        "--set",
        "pelvis.k_pel=0.25,0.45",
        "--set",
        "walk.step_length=0.3",
        "--methods",
        "fixed",
        "mpc",
        "--measure",
        "summary",
        "--out",
        str(out),
    ]
    assert main(argv) == 1  # a run raised: the sweep finishes and says so
    rows = output.read_table(out / output.TABLE_JSONL)
    assert len(rows) == 8
    assert [(r["walk.dsp_ratio"], r["pelvis.k_pel"], r["method"]) for r in rows[:4]] == [
        (0.1, 0.25, "fixed"),
        (0.1, 0.25, "mpc"),
        (0.1, 0.45, "fixed"),
        (0.1, 0.45, "mpc"),
    ]
    assert all(r["walk.step_length"] == 0.3 == (r["step_length"] or 0.3) for r in rows)
    failed = [r for r in rows if r["error"]]
    assert len(failed) == 2 and all(r["clean"] is None and r["runs"] == 1 for r in failed)
    assert set(rows[0]) == set(failed[0])  # every row has every column
    names = {p.name for p in (out / "figures").iterdir()}
    assert names == {
        f"heatmap_{q}_{m}.png" for q in output.QUANTITIES["summary"] for m in ("fixed", "mpc")
    }
    readme = (out / "README.md").read_text()
    assert "2 run(s) raised" in readme and "figures/heatmap_clean_mpc.png" in readme
    assert "(a run raised)" in capsys.readouterr().out


# -- real runs --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def tiny_local(tmp_path_factory):
    """The tiny summary sweep on the local process pool (2 runs of one step)."""
    out = tmp_path_factory.mktemp("sweep_local")
    assert main([*TINY, "--out", str(out)]) == 0
    return out


def test_a_tiny_summary_sweep_writes_the_tidy_table(tiny_local):
    rows = output.read_table(tiny_local / output.TABLE_JSONL)
    assert len(rows) == 2
    assert [r["walk.dsp_ratio"] for r in rows] == [0.15, 0.25]
    assert all(r["method"] == "fixed" and r["walk.n_steps"] == 1 for r in rows)
    keys = set(rows[0])
    assert set(SUMMARY_KEYS) <= keys and {"clean", "walks", "runs", "wall_s", "error"} <= keys
    for r in rows:
        assert r["steps_planned"] == 1 and r["runs"] == 1 and r["error"] is None
        assert r["walks"] == walks(r)  # derived the same way from the summary
        assert r["clean"] == clean(r)  # the thresholds' clean is the summary's at the defaults
        assert r["success"] and r["walks"]  # a 0.2 m step at the default parameters
    header = (tiny_local / output.TABLE_CSV).read_text().splitlines()[0].split(",")
    assert header == list(rows[0])
    readme = (tiny_local / "README.md").read_text()
    assert "pelvic-walk sweep --set walk.dsp_ratio=0.15,0.25" in readme and "sweep.csv" in readme
    assert (tiny_local / "figures" / "line_clean.png").exists()


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


@pytest.mark.slow
def test_ray_gives_the_same_table_as_the_local_pool(request, tmp_path):
    ray = pytest.importorskip(
        "ray", reason="Ray is an optional extra: pip install '.[cluster]'", exc_type=ImportError
    )
    tiny_local = request.getfixturevalue("tiny_local")  # only when Ray is there
    before = _children()
    out = tmp_path / "ray"
    assert main([*TINY, "--ray", "--out", str(out)]) == 0
    assert not ray.is_initialized()
    ours = output.read_table(out / output.TABLE_JSONL)
    theirs = output.read_table(tiny_local / output.TABLE_JSONL)

    def untimed(rows):
        return [{k: v for k, v in r.items() if k not in output.TIMING_COLUMNS} for r in rows]

    assert untimed(ours) == untimed(theirs)
    assert "local Ray instance, 2 CPUs" in (out / "README.md").read_text()
    deadline = time.monotonic() + 120  # Ray's processes end shortly after ray.shutdown()
    while _children() - before and time.monotonic() < deadline:
        time.sleep(0.5)
    assert not _children() - before, "Ray left processes behind"
