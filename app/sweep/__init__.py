"""``pelvic-walk sweep``: a parameter grid over walking methods, run headless in parallel.

Where each thing is:

- what one run is: :class:`~app.run_spec.RunSpec` (``app/run_spec.py``), plain data that the
  sweep, the study (``app.experiments``) and ``simulate --seed`` share.
- ``engine``: the run engine both use: jobs of plain data on a backend (local ``spawn``
  process pool, Ray, in-process), one job in flight per task, with a progress bar.
- ``grid``: the grid from ``--set GROUP.NAME=V1,V2,...`` options or a YAML / JSON file, any
  field of ``controller/params.py``, checked by ``app.params_cli``; cells = cartesian product.
- ``measure``: what one (cell, method) computes: ``summary`` (one walk, its summary keys) or
  ``limit`` (the longest step that walks and the longest that is clean, by bisection, at one or
  several clean thresholds); and :func:`~app.sweep.measure.run_one`, one headless run.
- ``output``: the tidy table (``sweep.csv``, ``sweep.jsonl``), heatmaps / line plots,
  ``grid.json`` and ``README.md`` in ``--out``.
- ``cli``: :func:`add_sweep_arguments` and :func:`sweep_main` for ``app.cli``, and
  :func:`main` for ``python -m app.sweep``.

Importing this package is light (no MuJoCo, matplotlib or Ray until a sweep runs).
"""

from app.sweep.cli import add_sweep_arguments, main, sweep_main

__all__ = ["add_sweep_arguments", "main", "sweep_main"]
