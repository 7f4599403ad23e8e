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
from typing import Any, NoReturn

from app.params_cli import add_strategy_argument, positive_int, split_list
from app.sweep.grid import (
    MEASURES,
    Grid,
    GridError,
    assignments,
    grid_from_file,
    make_grid,
    parse_sets,
)

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
    parser.add_argument(
        "--set",
        dest="grid_set",
        action="extend",
        nargs="+",
        default=[],
        metavar="GROUP.NAME=V1,V2,...",
        help="an axis of the grid: any parameter of controller/params.py and its values, "
        "separated by commas or spaces (repeatable; one value = fixed)",
    )
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
    parser.add_argument(
        "--jobs",
        type=positive_int,
        default=None,
        metavar="J",
        help="worker processes (default: the CPU count); with --ray and no "
        "address, the local Ray instance's CPUs",
    )
    parser.add_argument(
        "--ray",
        nargs="?",
        const="",
        default=None,
        metavar="ADDRESS",
        help="run on Ray: a cluster at ADDRESS, or without one a local Ray instance "
        "(pip install 'pelvic-walk[cluster]')",
    )


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


def check_runs(grid: Grid) -> None:
    """Every cell's parameters are valid together for every method at every length it may
    run (e.g. a horizon shorter than the MPC sample); GridError naming the cell otherwise."""
    from app.sweep.measure import SEARCH_MAX, SEARCH_MIN

    lengths: tuple[float | None, ...] = (
        (SEARCH_MIN, SEARCH_MAX) if grid.measure == "limit" else (None,)
    )
    for cell in grid.cells():
        for method in grid.methods:
            for x in lengths:
                try:
                    cell.spec(method, x).params()
                except ValueError as exc:
                    raise GridError(f"cell {cell.label}: {exc}") from None


def check_out(out: Path) -> str | None:
    """A one-line complaint if ``out`` cannot be a writable folder (creates it otherwise)."""
    if out.exists() and not out.is_dir():
        return f"--out {out}: is a file, not a folder"
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        return f"--out {out}: cannot create it ({exc.strerror or exc})"
    if not os.access(out, os.W_OK | os.X_OK):
        return f"--out {out}: not writable"
    return None


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

    try:
        grid = grid_from_args(args)
        check_runs(grid)
    except GridError as exc:
        return fail(exc)
    out = Path(args.out)
    problem = check_out(out)
    if problem:
        return fail(problem)

    from app.sweep import output
    from app.sweep.engine import make_backend, run_tasks
    from app.sweep.measure import make_tasks

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


class _Parser(argparse.ArgumentParser):
    """argparse that reports errors on one line (no usage dump) and exits 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser(prog: str = PROG) -> argparse.ArgumentParser:
    parser = _Parser(
        prog=prog,
        description="A parameter grid over walking methods: each "
        "cell's step-length limits or run summary, as one tidy table and figures.",
    )
    add_sweep_arguments(parser)
    return parser


def main(argv: list[str] | None = None) -> int:
    """``python -m app.sweep ...``: the same as ``pelvic-walk sweep ...``."""
    args = build_parser().parse_args(argv)
    try:
        return sweep_main(args)
    except KeyboardInterrupt:
        return 130
