"""A parameter grid over methods from Python, on the engine of ``pelvic-walk sweep``
(``pelvic_walk/core``): the same grid checks, tasks, backends (process pool, Ray, in-process) and
rows."""

from __future__ import annotations

import os
import time
from collections.abc import Iterable, Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pelvic_walk import _params

if TYPE_CHECKING:
    import pandas as pd


def _entries(axes: Mapping[str, Any]) -> list[tuple[str, Any]]:
    """Keywords -> (dotted name, value or list of values), as ``--set`` gives them."""
    out = []
    for key, values in axes.items():
        group, name, _ = _params._field_of(key)
        if isinstance(values, (str, bytes)) or not isinstance(values, Iterable):
            values = [values]
        out.append((f"{group}.{name}", [_params._plain(v) for v in values]))
    return out


def sweep(
    methods: Iterable[Any] | None = None,
    *,
    measure: str = "limit",
    jobs: int | None = None,
    ray: str | bool | None = None,
    out: str | os.PathLike | None = None,
    **axes: Any,
) -> pd.DataFrame:
    """A grid of parameters over methods, run headless on a process pool (or Ray), as
    ``pelvic-walk sweep`` runs it; one row per (cell, method).

    Args:
        methods: names, ``PelvisStrategy`` subclasses or files ``"FILE.py[:Class]"``
            (default: the paper's three and every strategy loaded).
        measure: ``"limit"``: each cell's longest step that walks and that is clean (bisection
            over 0.10-0.60 m at 0.01 m, up to about 11 walks per cell and method); ``"summary"``:
            one walk per cell, its summary keys.
        jobs: worker processes (default: the CPU count). A strategy class defined in this
            process (a notebook cell) runs in this process: other processes cannot import it.
        ray: ``True`` for a local Ray instance, or a cluster's address (``pelvic-walk[cluster]``).
        out: a folder for the CLI's files (table, figures, README), or None.
        **axes: the grid, parameters by keyword as :func:`simulate` takes them, each a list of
            values (an axis) or one value (fixed): ``dsp_ratio=[0.1, 0.2], steps=4``; a
            strategy's own parameter by its dotted name, ``**{"gain.k": [4, 8, 16]}`` (the
            other methods' rows of cells that differ only there share one run).

    Raises:
        ValueError: a bad grid or method, one line (``pelvic-walk sweep``'s).
    """
    from pelvic_walk._run import pandas
    from pelvic_walk.core import sweep_output as output
    from pelvic_walk.core.engine import make_backend, run_tasks
    from pelvic_walk.core.grid import make_grid
    from pelvic_walk.core.measure import check_runs, make_tasks

    pd = pandas()
    names = None
    if methods is not None:
        if isinstance(methods, (str, type)):
            methods = [methods]
        names = [
            _params.method_name(m)
            if isinstance(m, str) and not m.endswith(".py") and ":" not in m
            else _params.register_strategy(m)
            for m in methods
        ]
    grid = make_grid(_entries(axes), methods=names, measure=measure)  # GridError: ValueError
    check_runs(grid)
    local = [m for m in grid.methods if _params.in_process_only(m)]
    if ray is True:
        ray = ""
    if ray is False:
        ray = None
    if ray is not None and not isinstance(ray, str):
        raise ValueError(f"ray must be True, False, None or a cluster address, got {ray!r}")
    if jobs is not None:
        jobs = _params._plain(jobs)
        if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
            raise ValueError(f"jobs must be a whole number >= 1, got {jobs!r}")
    if local and (ray is not None or (jobs or 1) > 1):
        raise ValueError(
            f"the strategy {local[0]!r} is a class defined in this process, which worker "
            "processes cannot import: run this sweep in this process (jobs=1, no ray) or save "
            "the class in a file and pass methods=['FILE.py:ClassName']"
        )
    if local:
        jobs = 1
    if out is not None:
        problem = output.check_out(Path(out))
        if problem:
            raise ValueError(problem.replace("--out ", "out="))
    tasks = make_tasks(grid.cells(), grid.methods, grid.measure)
    jobs = jobs or os.cpu_count() or 1
    backend = make_backend(ray, jobs, len(tasks))  # ImportError / ConnectionError: one line
    started = datetime.now(UTC)
    t0 = time.perf_counter()
    try:
        desc = f"sweep {grid.measure} ({len(grid.cells())} cells x {len(grid.methods)} methods)"
        n_runs = run_tasks(tasks, backend, desc=desc)
    finally:
        backend.close()
    rows = output.rows_of(grid, tasks)
    columns = output.columns_of(grid, rows)
    if out is not None:
        folder = Path(out)
        files = output.write_table(folder, columns, rows)
        files.append(output.write_grid(folder, grid))
        files += output.plot_all(grid, rows, folder)
        call = ", ".join(
            [f"{k}={v!r}" for k, v in axes.items()]
            + [f"methods={list(grid.methods)!r}", f"measure={grid.measure!r}"]
        )
        output.write_readme(
            folder,
            command=f"pelvic_walk.sweep({call})",
            grid=grid,
            started=started,
            duration_s=time.perf_counter() - t0,
            n_runs=n_runs,
            backend=backend.name,
            files=files,
            n_errors=sum(1 for r in rows if r.get("error")),
        )
    return pd.DataFrame(rows, columns=columns)
