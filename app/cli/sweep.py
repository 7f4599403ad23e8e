"""``pelvic-walk sweep``: its options (:func:`add_sweep_arguments`) and run (:func:`sweep_main`).

Bad arguments (an unknown parameter or method, a value out of range, a malformed grid file,
both or neither of ``--grid`` and ``--set``, an unwritable ``--out``, Ray missing) exit 2 with
one line on stderr before any run starts. A sweep whose runs all ran exits 0; 1 if a run
raised (its row says which); 130 on Ctrl-C.
"""

from __future__ import annotations

import argparse
import os
import shlex
import sys
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from app.cli.options import (
    add_jobs_argument,
    add_ray_argument,
    add_set_argument,
    add_strategy_argument,
)
from pelvic_walk.core.grid import (
    MEASURES,
    Grid,
    GridError,
    assignments,
    grid_from_file,
    make_grid,
    parse_sets,
)
from pelvic_walk.core.params import split_list

PROG = "pelvic-walk sweep"
DEFAULT_OUT = Path("sweep")


def add_sweep_arguments(parser: argparse.ArgumentParser) -> None:
    """The ``sweep`` options (docs/REFERENCE.md) on ``parser``; :func:`sweep_main` reads them."""
    parser.add_argument(
        "--grid",
        type=Path,
        default=None,
        metavar="FILE",
        help="a YAML or JSON grid: {GROUP.NAME: [V1, V2, ...], ..., methods: [...], "
        "measure: limit|summary, fixed: {GROUP.NAME: V}}",
    )
    add_set_argument(parser, grid=True)
    parser.add_argument(
        "--methods",
        nargs="+",
        default=None,
        metavar="METHOD",
        help="walking methods, separated by commas or spaces (default: the grid file's, else "
        "fixed redundancy mpc and every --strategy)",
    )
    add_strategy_argument(parser)
    parser.add_argument(
        "--measure",
        default=None,
        metavar="|".join(MEASURES),
        help="limit: each cell's longest step that walks and that is clean (bisection, "
        "0.10-0.60 m at 0.01 m); summary: one walk per cell, its summary keys "
        "(default: the grid file's, else limit)",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=DEFAULT_OUT,
        metavar="DIR",
        help=f"output folder (default {DEFAULT_OUT}/)",
    )
    add_jobs_argument(parser)
    add_ray_argument(parser)


def grid_from_args(args: argparse.Namespace) -> Grid:
    """The grid the options ask for (GridError, one line, otherwise)."""
    sets = assignments(getattr(args, "grid_set", None) or [])
    methods = split_list(args.methods) if args.methods is not None else None
    if args.grid is not None and sets:
        raise GridError("give either --grid FILE or --set GROUP.NAME=V1,V2,..., not both")
    if args.grid is None and not sets:
        raise GridError("give the grid: --grid FILE or --set GROUP.NAME=V1,V2,...")
    if args.grid is not None:
        return grid_from_file(args.grid, methods=methods, measure=args.measure)
    return make_grid(parse_sets(sets), methods=methods, measure=args.measure)


def command_of(args: argparse.Namespace) -> str:
    """The command line that reproduces this sweep."""
    parts = ["pelvic-walk", "sweep"]
    if args.grid is not None:
        parts += ["--grid", str(args.grid)]
    for text in assignments(getattr(args, "grid_set", None) or []):
        parts += ["--set", text]
    if args.methods:
        parts += ["--methods", ",".join(split_list(args.methods))]
    if args.measure:
        parts += ["--measure", args.measure]
    parts += ["--out", str(args.out)]
    if args.jobs:
        parts += ["--jobs", str(args.jobs)]
    if args.ray is not None:
        parts += ["--ray", *([args.ray] if args.ray else [])]
    return shlex.join(parts)


def _describe(grid: Grid, row: dict[str, Any]) -> str:
    where = " ".join(f"{a.name}={row[a.name]}" for a in grid.axes) or "cell"
    if grid.measure == "limit":

        def limit(key: str) -> str:
            v, fail = row[f"{key}_limit"], row[f"{key}_first_fail"]
            if v is None:
                return "none" if fail is None else f"<{fail:.2f} m"
            return f"{v:.2f} m" + ("+" if fail is None else "")

        what = f"walks {limit('walks')}, clean {limit('clean')}"
    elif row.get("error"):
        what = f"the run raised {row['error']}"
    else:
        what = (
            f"walks {'yes' if row.get('walks') else 'no'}, clean "
            f"{'yes' if row.get('clean') else 'no'}, "
            f"{row.get('steps_completed')}/{row.get('steps_planned')} steps"
        )
    err = " (a run raised)" if row.get("error") else ""
    return f"{where} {row['method']}: {what} [{row['runs']} runs, {row['wall_s']:.0f} s]{err}"


def sweep_main(args: argparse.Namespace) -> int:
    """Run the sweep the options describe; write the table, figures and README in ``--out``."""

    def fail(message: object) -> int:
        print(f"{PROG}: error: {message}", file=sys.stderr)
        return 2

    from pelvic_walk.core import sweep_output as output
    from pelvic_walk.core.measure import check_runs

    try:
        grid = grid_from_args(args)
        check_runs(grid)
    except GridError as exc:
        return fail(exc)
    out = Path(args.out)
    problem = output.check_out(out)
    if problem:
        return fail(problem)

    from pelvic_walk.core.engine import make_backend, run_tasks
    from pelvic_walk.core.measure import make_tasks

    jobs = args.jobs or os.cpu_count() or 1
    tasks = make_tasks(grid.cells(), grid.methods, grid.measure)
    started = datetime.now(UTC)
    t0 = time.perf_counter()
    try:
        backend = make_backend(args.ray, jobs, len(tasks))
    except (ImportError, ConnectionError) as exc:
        return fail(exc)
    try:
        n_cells, n_methods = len(grid.cells()), len(grid.methods)
        desc = f"sweep {grid.measure} ({n_cells} cells x {n_methods} methods: {backend.name})"
        n_runs = run_tasks(tasks, backend, desc=desc)
    except KeyboardInterrupt:
        return 130
    finally:
        backend.close()
    duration = time.perf_counter() - t0

    rows = output.rows_of(grid, tasks)
    columns = output.columns_of(grid, rows)
    files = output.write_table(out, columns, rows)
    files.append(output.write_grid(out, grid))
    files += output.plot_all(grid, rows, out)
    n_errors = sum(1 for r in rows if r.get("error"))
    files.insert(
        0,
        output.write_readme(
            out,
            command=command_of(args),
            grid=grid,
            started=started,
            duration_s=duration,
            n_runs=n_runs,
            backend=backend.name,
            files=files,
            n_errors=n_errors,
        ),
    )
    for row in rows:
        print(_describe(grid, row))
    print(f"wrote {out / output.TABLE_CSV} ({len(rows)} rows, {n_runs} runs, {duration:.0f} s)")
    return 1 if n_errors else 0
