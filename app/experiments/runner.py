"""``pelvic-walk experiments``: run the study over a process pool and write the report.

Flow: :func:`definitions.planned_runs` (every run known up front) -> process pool ->
:func:`definitions.refinement_runs` (the 0.01 m sweep between each method's last clean and first
failed coarse length) -> process pool -> :mod:`sections` (numbers and verdicts) ->
``results.json``, ``figures/*.png``, ``report.md``.

Each worker runs one :class:`RunSpec` headless and sends back only the summary plus the small
extracts its sections asked for (one mid-walk step at 200 Hz, the walking phase at 100 Hz):
the full ring buffer never crosses a process boundary. Workers are started with ``spawn`` (no
inherited MuJoCo/Pinocchio state); the longest runs are submitted first.
"""

from __future__ import annotations

import json
import math
import multiprocessing
import os
import platform
import sys
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from app.experiments.definitions import (
    FULL,
    QUICK,
    Requests,
    RunSpec,
    Study,
    planned_runs,
    refinement_runs,
)

STEP_COLUMNS = ("waist_angle_cmd", "waist_angle", "waist_rate", "theta_ref", "kappa")
WALK_COLUMNS = ("yaw_momentum", "h_low", "h_up")
ZMP_COLUMNS = (
    "cop_x",
    "cop_y",
    "lipm_zmp_x",
    "lipm_zmp_y",
    "com_x",
    "com_y",
    "com_des_x",
    "com_des_y",
    "zmp_ref_x",
    "zmp_ref_y",
    "zmp_in_support",
)
DOWNSAMPLE = 2  # walking-phase extracts at 100 Hz
LANDING_WINDOW = 0.05  # [s] kappa "at landing / lift-off" = max within +/- this of the event
KAPPA_CAP = 1e8  # kappa(J) of a singular Jacobian (inf) is recorded as this


# -- worker side ------------------------------------------------------------------------------
def _clean_floats(values: np.ndarray) -> list[float | None]:
    """A float array as a JSON-safe list (NaN / inf -> None)."""
    return [float(v) if math.isfinite(v) else None for v in np.asarray(values, dtype=float)]


def _event_peaks(t: np.ndarray, kappa: np.ndarray, events: np.ndarray) -> list[float | None]:
    """Max kappa within +/- LANDING_WINDOW of each event time (None if no sample there)."""
    out: list[float | None] = []
    for te in events:
        sel = (t >= te - LANDING_WINDOW) & (t <= te + LANDING_WINDOW) & np.isfinite(kappa)
        out.append(float(np.max(kappa[sel])) if np.any(sel) else None)
    return out


def _planned_support_ratio(plan: Any, t: np.ndarray, x: np.ndarray, y: np.ndarray) -> float:
    """Share of samples whose (x, y) lies in the convex hull of the feet the plan has down."""
    from app.sim.world import convex_hull, point_in_polygon
    from controller.footsteps import FOOT_SIZE

    hx, hy = FOOT_SIZE[0] / 2, FOOT_SIZE[1] / 2
    corners = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
    on_ground = plan.feet_on_ground(t)
    idx = np.clip(plan.step_index(t), -1, plan.n)
    inside = n = 0
    for i in range(len(t)):
        if not (math.isfinite(x[i]) and math.isfinite(y[i])):
            continue
        k = int(idx[i])
        if k < 0:
            feet = plan.feet_init
        elif k >= plan.n:
            feet = plan.feet_final
        else:  # [left, right] now: the swing foot is at swing_from until it lands
            feet = np.empty((2, 3))
            side = int(plan.swing_side[k])
            feet[side] = plan.swing_from[k]
            feet[1 - side] = plan.support_pos[k]
        pts = [corners + feet[s, :2] for s in range(2) if on_ground[i, s]]
        hull = convex_hull(np.vstack(pts))
        n += 1
        inside += int(point_in_polygon(np.array([x[i], y[i]]), hull))
    return inside / n if n else float("nan")


def execute(spec: RunSpec, extracts: tuple[str, ...], mid_step: int) -> dict[str, Any]:
    """Run one spec headless; return its summary and the requested extracts (small)."""
    from app.runs import RunConfig, run
    from controller.params import ControllerParams

    start = time.perf_counter()
    params = ControllerParams().replace(
        method=spec.method,
        walk={"step_length": spec.step_length, "n_steps": spec.n_steps},
        arms={"enabled": spec.arms},
    )
    try:
        session = run(RunConfig(params=params, seed=spec.seed, perturbation=spec.perturbation))
    except Exception as exc:  # a crashed run is reported, never hides the others
        return {
            "spec": spec,
            "error": f"{type(exc).__name__}: {exc}",
            "summary": None,
            "extracts": {},
            "wall_s": time.perf_counter() - start,
        }
    summary = session.summary()
    plan = session.walker.plan
    series = session.series
    t = series.column("t")
    kappa = np.minimum(
        np.nan_to_num(series.column("kappa"), nan=np.nan, posinf=KAPPA_CAP), KAPPA_CAP
    )
    n_walk = plan.n_walking_steps
    lift = plan.step_start[:n_walk] + plan.step_dsp[:n_walk]
    land = plan.step_start[:n_walk] + plan.step_duration[:n_walk]
    summary["kappa_liftoff"] = _event_peaks(t, kappa, lift)
    summary["kappa_landing"] = _event_peaks(t, kappa, land)
    out: dict[str, Any] = {}
    if "step" in extracts:
        k = min(mid_step, plan.n - 1)
        t0, dur, dsp = (
            float(plan.step_start[k]),
            float(plan.step_duration[k]),
            float(plan.step_dsp[k]),
        )
        sel = (t >= t0 - 1e-9) & (t <= t0 + dur + 1e-9)
        step = {c: _clean_floats(series.column(c)[sel]) for c in STEP_COLUMNS}
        step["kappa"] = _clean_floats(kappa[sel])
        step.update(
            t=_clean_floats(t[sel] - t0),
            step_index=k,
            step_start=t0,
            duration=dur,
            dsp=dsp,
            # theta_ref's first sample refers to one MPC sample after the tick (t + T_p);
            # a row's time is the tick's time + control_dt
            theta_ref_lead=params.com.sample_time - params.control_dt,
            swing_side=int(plan.swing_side[k]),
            complete=bool(
                np.any(sel)
                and t[sel][-1] >= t0 + dur - 0.01
                and not (summary["fell"] and summary["fall_time"] <= t0 + dur)
            ),
        )
        out["step"] = step
    walking = (t >= plan.t_start) & (t <= plan.walk_end)
    sub = np.flatnonzero(walking)[::DOWNSAMPLE]
    if "walk" in extracts:
        walk = {c: _clean_floats(series.column(c)[sub]) for c in WALK_COLUMNS}
        walk.update(t=_clean_floats(t[sub]), step_start=_clean_floats(plan.step_start))
        out["walk"] = walk
    if "zmp" in extracts:
        zmp = {c: _clean_floats(series.column(c)[sub]) for c in ZMP_COLUMNS}
        lx, ly = series.column("lipm_zmp_x"), series.column("lipm_zmp_y")
        cx, cy = series.column("cop_x"), series.column("cop_y")
        zmp.update(
            t=_clean_floats(t[sub]),
            footholds=plan.footholds()[:, :2].tolist(),
            lipm_in_planned_support=_planned_support_ratio(
                plan, t[walking], lx[walking], ly[walking]
            ),
            cop_in_planned_support=_planned_support_ratio(
                plan, t[walking], cx[walking], cy[walking]
            ),
            cop_in_measured_support=float(np.nanmean(series.column("zmp_in_support")[walking])),
        )
        out["zmp"] = zmp
    return {
        "spec": spec,
        "error": None,
        "summary": summary,
        "extracts": out,
        "wall_s": time.perf_counter() - start,
    }


# -- parent side ------------------------------------------------------------------------------
def is_clean(result: dict[str, Any]) -> bool:
    """The run's ``clean`` flag (False for a crashed run)."""
    return bool(result["summary"] and result["summary"]["clean"])


def _run_all(
    requests: Requests,
    pool: ProcessPoolExecutor,
    bar: tqdm,
    mid_step: int,
    results: dict[RunSpec, dict[str, Any]],
) -> None:
    """Run every request not yet in ``results`` (longest runs first); fill ``results``."""
    todo = [s for s in requests if s not in results]
    todo.sort(key=lambda s: (-s.n_steps, -s.step_length, s.key))
    bar.total = (bar.total or 0) + len(todo)
    bar.refresh()
    futures = {pool.submit(execute, s, tuple(sorted(requests[s])), mid_step): s for s in todo}
    pending = set(futures)
    while pending:
        done, pending = wait(pending, return_when=FIRST_COMPLETED)
        for fut in done:
            res = fut.result()
            results[futures[fut]] = res
            bar.set_postfix_str(futures[fut].key, refresh=False)
            bar.update(1)


def run_study(
    study: Study, jobs: int, results: dict[RunSpec, dict[str, Any]] | None = None
) -> tuple[dict[RunSpec, dict[str, Any]], Requests]:
    """Run the whole study; returns every run's result and the merged requests."""
    results = {} if results is None else results
    requests = planned_runs(study)
    ctx = multiprocessing.get_context("spawn")
    with (
        ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool,
        tqdm(
            total=0,
            desc=f"experiments ({study.name}, {jobs} jobs)",
            unit="run",
            file=sys.stderr,
            dynamic_ncols=True,
        ) as bar,
    ):
        _run_all(requests, pool, bar, study.mid_step, results)
        clean = {
            m: {x: is_clean(results[study.figure_run(m, x)]) for x in study.sweep_grid}
            for m in study.methods
        }
        refine = refinement_runs(study, clean)
        for spec, ex in refine.items():
            requests.setdefault(spec, set()).update(ex)
        _run_all(refine, pool, bar, study.mid_step, results)
    return results, requests


def main(out: Path, quick: bool = False, jobs: int | None = None) -> int:
    """Run the study (``quick``: reduced) and write results.json, figures/ and report.md."""
    from app.experiments import figures, report, sections

    study = QUICK if quick else FULL
    jobs = jobs or os.cpu_count() or 1
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    started = datetime.now(UTC)
    t0 = time.perf_counter()
    results, requests = run_study(study, jobs)
    duration = time.perf_counter() - t0
    cpu_s = sum(r["wall_s"] for r in results.values())
    meta = {
        "command": "pelvic-walk experiments --out {} {}--jobs {}".format(
            out, "--quick " if quick else "", jobs
        ),
        "study": study.name,
        "date_utc": started.strftime("%Y-%m-%d %H:%M UTC"),
        "duration_s": duration,
        "run_seconds_total": cpu_s,
        "n_runs": len(results),
        "jobs": jobs,
        "cpu_count": os.cpu_count(),
        "machine": f"{platform.machine()}, {platform.python_implementation()} "
        f"{platform.python_version()}",
        "errors": {s.key: r["error"] for s, r in results.items() if r["error"]},
    }
    data = sections.analyse(study, results, meta)
    figs = figures.make_all(study, results, data, out / "figures")
    data["figures"] = figs
    data["meta"]["duration_s"] = time.perf_counter() - t0  # include figures
    (out / "results.json").write_text(json.dumps(_json_safe(data), indent=1, allow_nan=False))
    (out / "report.md").write_text(report.render(study, data))
    print(f"wrote {out / 'report.md'} ({len(results)} runs, {data['meta']['duration_s']:.0f} s)")
    return 0 if not meta["errors"] else 1


def _json_safe(obj: Any) -> Any:
    """Replace NaN / inf by None and numpy scalars by Python numbers, recursively."""
    if isinstance(obj, dict):
        return {str(k): _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj
