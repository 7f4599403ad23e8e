"""A sweep's results: one tidy table (CSV and JSON lines), figures and a README in ``--out``.

The table has one row per (cell, method): the grid's parameters (axes, then the fixed ones) by
their dotted names, ``method``, the measure's columns (``limit``: :data:`LIMIT_COLUMNS`;
``summary``: the run's summary keys), then ``runs``, ``wall_s`` (seconds of run time, summed
over the cell's runs) and ``error``. Rows are in grid order (first axis slowest), methods in
the order asked, whatever order the runs finished in. In the CSV a list is written as its
items separated by spaces, a missing value as an empty field; the JSON lines keep lists and
use null. :data:`TIMING_COLUMNS` are the only ones that differ between two sweeps of the same
grid (on any backend).

Figures (matplotlib, Agg), in ``figures/``: for a grid of two axes, one heatmap per method
and quantity (``heatmap_<quantity>_<method>.png``, the same colour scale for every method of
a quantity); for one axis, one line plot per quantity with a line per method
(``line_<quantity>.png``; for a limit, a thin bar up to the first failed length); for no axis
or three and more, the table only.
"""

from __future__ import annotations

import csv
import json
import math
import os
import platform
from collections.abc import Sequence
from datetime import datetime
from pathlib import Path
from typing import Any

from pelvic_walk.core.grid import Grid
from pelvic_walk.core.measure import (
    LIMIT_COLUMNS,
    RESOLUTION,
    SEARCH_MAX,
    SEARCH_MIN,
    TASK_COLUMNS,
    Task,
)
from pelvic_walk.core.methods import METHOD_INFO
from pelvic_walk.core.summary import TIMING_KEYS

TABLE_CSV = "sweep.csv"
TABLE_JSONL = "sweep.jsonl"
GRID_JSON = "grid.json"
FIGURES = "figures"
# Columns that measure time, not the robot: they differ from one sweep to the next.
TIMING_COLUMNS = ("wall_s", *TIMING_KEYS)
# quantity -> (label, unit, log colour scale)
QUANTITIES: dict[str, dict[str, tuple[str, str, bool]]] = {
    "limit": {
        "walks_limit": ("longest step that walks", "m", False),
        "clean_limit": ("longest clean step", "m", False),
    },
    "summary": {
        "clean": ("clean (1) or not (0)", "", False),
        "steps_completed": ("steps completed", "", False),
        "landing_error_max": ("landing error max", "m", False),
        "waist_yaw_max_deg": ("waist yaw max", "deg", False),
        "yaw_momentum_peak": ("peak yaw momentum", "kg m^2/s", False),
        "energy_two_step_mean": ("energy per two steps (eq. 44)", "J", False),
        "condition_number_max": ("kappa(J_low) max", "", True),
        "condition_number_legs_max": ("kappa(legs) max", "", True),
    },
}


def rows_of(grid: Grid, tasks: Sequence[Task]) -> list[dict[str, Any]]:
    """The table's rows, one per task, in the tasks' (grid) order."""
    rows = []
    for task in tasks:
        row: dict[str, Any] = dict(task.cell.values) | dict(task.cell.fixed)
        row["method"] = task.method
        row.update(task.row())
        rows.append(row)
    return rows


def columns_of(grid: Grid, rows: Sequence[dict[str, Any]]) -> list[str]:
    """Parameters, ``method``, the measure's columns, then :data:`TASK_COLUMNS`."""
    head = [*grid.names, "method"]
    if grid.measure == "limit":
        middle = list(LIMIT_COLUMNS)
    else:
        middle = []
        skip = set(head) | set(TASK_COLUMNS)
        for row in rows:
            middle += [k for k in row if k not in skip and k not in middle]
    return head + middle + list(TASK_COLUMNS)


def _json_value(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, (list, tuple)):
        return [_json_value(v) for v in value]
    return value


def _csv_value(value: Any) -> str:
    value = _json_value(value)
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list):
        return " ".join(_csv_value(v) for v in value)
    return str(value)


def write_table(out: Path, columns: Sequence[str], rows: Sequence[dict[str, Any]]) -> list[Path]:
    """``sweep.csv`` and ``sweep.jsonl``; returns their paths."""
    csv_path, jsonl_path = out / TABLE_CSV, out / TABLE_JSONL
    with csv_path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(columns)
        for row in rows:
            writer.writerow([_csv_value(row.get(c)) for c in columns])
    with jsonl_path.open("w") as f:
        for row in rows:
            f.write(json.dumps({c: _json_value(row.get(c)) for c in columns}, allow_nan=False))
            f.write("\n")
    return [csv_path, jsonl_path]


def read_table(path: Path) -> list[dict[str, Any]]:
    """The rows of a ``sweep.jsonl``."""
    return [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]


# -- figures ----------------------------------------------------------------------------------
def _number(value: Any) -> float:
    if value is None or isinstance(value, (str, list)):
        return math.nan
    return float(value)


def _param_label(name: str) -> str:
    from pelvic_walk.core.params import fields

    for group, field_name, meta in fields():
        if f"{group}.{field_name}" == name:
            unit = f" [{meta['unit']}]" if meta.get("unit") else ""
            return f"{meta.get('label', field_name)} ({name}){unit}"
    return name


def _tick(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    return str(value).lower() if isinstance(value, bool) else str(value)


def _fmt(value: float, unit: str) -> str:
    if not math.isfinite(value):
        return "-"
    if unit == "m":
        return f"{value:.2f}"
    return f"{value:.3g}"


def plot_all(grid: Grid, rows: Sequence[dict[str, Any]], out: Path) -> list[Path]:
    """The figures the grid's shape allows (see the module docstring); returns their paths."""
    if len(grid.axes) not in (1, 2):
        return []
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder = out / FIGURES
    folder.mkdir(exist_ok=True)
    paths: list[Path] = []
    quantities = {k: v for k, v in QUANTITIES[grid.measure].items() if any(k in r for r in rows)}
    try:
        for key, (label, unit, log) in quantities.items():
            if len(grid.axes) == 2:
                paths += _heatmaps(plt, grid, rows, key, label, unit, log, folder)
            else:
                paths.append(_lines(plt, grid, rows, key, label, unit, log, folder))
    finally:
        plt.close("all")
    return paths


def _cell_text(row: dict[str, Any], key: str, unit: str) -> str:
    """A heatmap cell's label; a limit reads "0.60+" when nothing failed up to the range's
    top and "<0.10" when even the shortest length failed."""
    v = _number(row.get(key))
    if key.endswith("_limit") and not row.get("error"):
        fail = row.get(key.replace("_limit", "_first_fail"))
        if math.isfinite(v) and fail is None:
            return _fmt(v, unit) + "+"
        if not math.isfinite(v) and fail is not None:
            return f"<{fail:.2f}"
    return _fmt(v, unit)


def _heatmaps(
    plt: Any,
    grid: Grid,
    rows: Sequence[dict[str, Any]],
    key: str,
    label: str,
    unit: str,
    log: bool,
    folder: Path,
) -> list[Path]:
    import numpy as np
    from matplotlib.colors import LogNorm, Normalize

    ay, ax_ = grid.axes
    tables, texts = {}, {}
    for m in grid.methods:
        z = np.full((len(ay.values), len(ax_.values)), np.nan)
        text = np.full(z.shape, "-", dtype=object)
        for r in rows:
            if r["method"] == m:
                i, j = ay.values.index(r[ay.name]), ax_.values.index(r[ax_.name])
                z[i, j] = _number(r.get(key))
                text[i, j] = _cell_text(r, key, unit)
        tables[m], texts[m] = z, text
    finite = np.concatenate([z[np.isfinite(z)] for z in tables.values()])
    if log:
        finite = finite[finite > 0]
    lo, hi = (float(finite.min()), float(finite.max())) if len(finite) else (0.0, 1.0)
    if hi <= lo:
        lo, hi = (lo / 2, lo * 2) if log and lo > 0 else (lo - 0.5, hi + 0.5)
    norm = LogNorm(lo, hi) if log else Normalize(lo, hi)
    cmap = plt.get_cmap("viridis").with_extremes(bad="#d9d9d9")
    unit_text = f" [{unit}]" if unit else ""
    paths = []
    for m, z in tables.items():
        ny, nx = z.shape
        fig, ax = plt.subplots(figsize=(min(2.8 + 0.9 * nx, 16.0), min(1.8 + 0.55 * ny, 12.0)))
        shown = np.ma.masked_invalid(np.where(z > 0, z, np.nan) if log else z)
        im = ax.imshow(shown, origin="lower", aspect="auto", cmap=cmap, norm=norm)
        ax.set_xticks(range(nx), [_tick(v) for v in ax_.values])
        ax.set_yticks(range(ny), [_tick(v) for v in ay.values])
        ax.set_xlabel(_param_label(ax_.name))
        ax.set_ylabel(_param_label(ay.name))
        if nx * ny <= 400:
            for i in range(ny):
                for j in range(nx):
                    v = z[i, j]
                    dark = math.isfinite(v) and (not log or v > 0) and norm(v) < 0.5
                    ax.text(
                        j,
                        i,
                        texts[m][i, j],
                        ha="center",
                        va="center",
                        fontsize=8,
                        color="white" if dark else "black",
                    )
        ax.grid(False)
        fig.colorbar(im, ax=ax, label=f"{label}{unit_text}")
        ax.set_title(f"{METHOD_INFO[m].label}: {label}", fontsize=10)
        fig.tight_layout()
        path = folder / f"heatmap_{key}_{m}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


def _lines(
    plt: Any,
    grid: Grid,
    rows: Sequence[dict[str, Any]],
    key: str,
    label: str,
    unit: str,
    log: bool,
    folder: Path,
) -> Path:
    from pelvic_walk.core.methods import method_hex

    (axis,) = grid.axes
    numeric = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in axis.values)
    xs = [float(v) for v in axis.values] if numeric else list(range(len(axis.values)))
    fig, ax = plt.subplots(figsize=(6.4, 3.8))
    bracket = key.endswith("_limit")
    for m in grid.methods:
        by_value = {r[axis.name]: r for r in rows if r["method"] == m}
        ys = [_number(by_value[v].get(key)) if v in by_value else math.nan for v in axis.values]
        ax.plot(xs, ys, marker="o", color=method_hex(m), label=METHOD_INFO[m].label)
        if bracket:
            fails = [
                _number(by_value[v].get(key.replace("_limit", "_first_fail")))
                if v in by_value
                else math.nan
                for v in axis.values
            ]
            for x, y, f in zip(xs, ys, fails, strict=True):
                if math.isfinite(y) and math.isfinite(f):
                    ax.plot([x, x], [y, f], color=method_hex(m), alpha=0.35, lw=4)
    if log:
        ax.set_yscale("log")
    if not numeric:
        ax.set_xticks(xs, [_tick(v) for v in axis.values])
    ax.set_xlabel(_param_label(axis.name))
    ax.set_ylabel(f"{label}" + (f" [{unit}]" if unit else ""))
    title = label + (" (bar: up to the first failed length)" if bracket else "")
    ax.set_title(title, fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = folder / f"line_{key}.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# -- README -----------------------------------------------------------------------------------
def write_readme(
    out: Path,
    *,
    command: str,
    grid: Grid,
    started: datetime,
    duration_s: float,
    n_runs: int,
    backend: str,
    files: Sequence[Path],
    n_errors: int,
) -> Path:
    """``README.md``: the command, date, machine, what was measured and the files."""
    cells = len(grid.cells())
    axes = ", ".join(f"`{a.name}` = {', '.join(map(_tick, a.values))}" for a in grid.axes)
    fixed = ", ".join(f"`{n}` = {_tick(v)}" for n, v in grid.fixed)
    raised = f"; {n_errors} run(s) raised" if n_errors else ""
    lines = [
        "# Parameter sweep",
        "",
        f"- command: `{command}`",
        f"- date: {started.strftime('%Y-%m-%d %H:%M UTC')}",
        f"- machine: {platform.node() or '?'}, {platform.machine()}, {os.cpu_count()} CPUs, "
        f"{platform.system()} {platform.release()}, Python {platform.python_version()}",
        f"- backend: {backend}",
        f"- grid: {cells} cell(s) x {len(grid.methods)} method(s) ({', '.join(grid.methods)}); "
        + (f"axes: {axes}" if axes else "no axis")
        + (f"; fixed: {fixed}" if fixed else ""),
        f"- measure: `{grid.measure}`",
        f"- {n_runs} runs in {duration_s:.0f} s{raised}",
        "",
    ]
    if grid.measure == "limit":
        lines += [
            "For each cell and method: the longest step length that *walks* (no fall, the plan "
            "completed, every landing within 2 cm) and the longest that is *clean* (also no QP "
            "failure, no servo saturation, no IK tick at the joint-speed limit, kappa(legs) below "
            f"the singular bound), searched from {SEARCH_MIN:.2f} to {SEARCH_MAX:.2f} m at "
            f"{RESOLUTION:.2f} m by bisection (walks first, then clean inside the bracket left). "
            "A limit is the longest length below the shortest failed one found; `*_first_fail` "
            "is that failure (empty: nothing failed up to the range's top); `*_above` lists "
            "lengths that passed above it (failures not monotonic in length); `trace` lists "
            "every run in order (see `pelvic_walk/core/measure.py`).",
            "",
        ]
    else:
        lines += [
            "One run per cell and method; the columns are the run's summary (the keys of "
            "`pelvic-walk simulate --json`, plus `clean`, `walks` = no fall, the plan completed, "
            "every landing within 2 cm, and the summary's other scalar keys).",
            "",
        ]
    lines += [
        "Timing columns (`" + "`, `".join(TIMING_COLUMNS) + "`) are the only ones that change "
        "from one sweep of the same grid to the next.",
        "",
        "## Files",
        "",
    ]
    for path in files:
        rel = path.relative_to(out).as_posix()
        lines.append(f"- [`{rel}`]({rel})")
    path = out / "README.md"
    path.write_text("\n".join(lines) + "\n")
    return path


def write_grid(out: Path, grid: Grid) -> Path:
    """``grid.json``: the grid as a file ``--grid`` reads back."""
    path = out / GRID_JSON
    path.write_text(json.dumps(grid.as_dict(), indent=2) + "\n")
    return path


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
