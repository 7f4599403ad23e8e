"""One run of the study in a worker process: :func:`execute` -> a small :class:`RunResult`.

A worker runs one :class:`RunSpec` headless and sends back only the summary plus the small
extracts its sections asked for (one mid-walk step at 200 Hz, the walking phase at 100 Hz):
the full ring buffer never crosses a process boundary.

The footstep plan is read through its tables (step timing) and, for the feet the plan has on
the ground, through :func:`_planned_feet` alone.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from app.experiments.definitions import DISTURBANCE_PERIOD, RunSpec
from app.experiments.results import (
    Extracts,
    RunResult,
    RunSummary,
    StepExtract,
    WalkExtract,
    ZmpExtract,
    samples,
)
from controller.kinematics import KAPPA_CAP
from models.dyros_jet import FOOT_SIZE

STEP_COLUMNS = ("waist_angle_cmd", "waist_angle", "waist_rate", "theta_ref")
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


def _event_peaks(t: np.ndarray, kappa: np.ndarray, events: np.ndarray) -> list[float | None]:
    """Max kappa within +/- LANDING_WINDOW of each event time (None if no sample there)."""
    out: list[float | None] = []
    for te in events:
        sel = (t >= te - LANDING_WINDOW) & (t <= te + LANDING_WINDOW) & np.isfinite(kappa)
        out.append(float(np.max(kappa[sel])) if np.any(sel) else None)
    return out


def _planned_feet(plan: Any, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The feet the plan has at ``t``: on the ground (N, 2) bool and positions (N, 2, 3) [m].

    The study's one query of the plan's feet ([left, right]; the swing foot stays where it
    lifted off until it lands).
    """
    sample = plan.sample(t)
    return sample.on_ground, np.stack([sample.p_left, sample.p_right], axis=1)


def _planned_support_ratio(plan: Any, t: np.ndarray, x: np.ndarray, y: np.ndarray) -> float:
    """Share of samples whose (x, y) lies in the convex hull of the feet the plan has down."""
    from app.sim.world import convex_hull, point_in_polygon

    hx, hy = FOOT_SIZE[0] / 2, FOOT_SIZE[1] / 2
    corners = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
    on_ground, feet = _planned_feet(plan, t)
    inside = n = 0
    for i in range(len(t)):
        if not (math.isfinite(x[i]) and math.isfinite(y[i])):
            continue
        pts = [corners + feet[i, s, :2] for s in range(2) if on_ground[i, s]]
        hull = convex_hull(np.vstack(pts))
        n += 1
        inside += int(point_in_polygon(np.array([x[i], y[i]]), hull))
    return inside / n if n else float("nan")


def _step_extract(
    series: Any,
    plan: Any,
    t: np.ndarray,
    kappa: np.ndarray,
    mid_step: int,
    summary: dict,
    lead: float,
) -> StepExtract:
    k = min(mid_step, plan.n - 1)
    t0, dur, dsp = float(plan.step_start[k]), float(plan.step_duration[k]), float(plan.step_dsp[k])
    sel = (t >= t0 - 1e-9) & (t <= t0 + dur + 1e-9)
    return StepExtract(
        t=samples(t[sel] - t0),
        **{c: samples(series.column(c)[sel]) for c in STEP_COLUMNS},
        kappa=samples(kappa[sel]),
        step_index=k,
        step_start=t0,
        duration=dur,
        dsp=dsp,
        theta_ref_lead=lead,
        swing_side=int(plan.swing_side[k]),
        complete=bool(
            np.any(sel)
            and t[sel][-1] >= t0 + dur - 0.01
            and not (summary["fell"] and summary["fall_time"] <= t0 + dur)
        ),
    )


def _zmp_extract(
    series: Any, plan: Any, t: np.ndarray, sub: np.ndarray, walking: np.ndarray
) -> ZmpExtract:
    lx, ly = series.column("lipm_zmp_x"), series.column("lipm_zmp_y")
    cx, cy = series.column("cop_x"), series.column("cop_y")
    return ZmpExtract(
        t=samples(t[sub]),
        **{c: samples(series.column(c)[sub]) for c in ZMP_COLUMNS},
        footholds=plan.footholds()[:, :2].tolist(),
        lipm_in_planned_support=_planned_support_ratio(plan, t[walking], lx[walking], ly[walking]),
        cop_in_planned_support=_planned_support_ratio(plan, t[walking], cx[walking], cy[walking]),
        cop_in_measured_support=float(np.nanmean(series.column("zmp_in_support")[walking])),
    )


def execute(spec: RunSpec, extracts: tuple[str, ...], mid_step: int) -> RunResult:
    """Run one spec headless; return its summary and the requested extracts (small)."""
    from app.runs import RunConfig, run

    start = time.perf_counter()
    params = spec.params()
    try:
        cfg = RunConfig(
            params=params,
            seed=spec.seed,
            perturbation=spec.perturbation,
            disturbance=spec.disturbance,
            disturbance_period=DISTURBANCE_PERIOD,
        )
        session = run(cfg)
    except Exception as exc:  # a crashed run is reported, never hides the others
        return RunResult(
            spec, None, error=f"{type(exc).__name__}: {exc}", wall_s=time.perf_counter() - start
        )
    summary = session.summary()
    plan = session.walker.plan
    series = session.series
    t = series.column("t")
    kappa, kappa_legs = (
        np.minimum(np.nan_to_num(series.column(c), nan=np.nan, posinf=KAPPA_CAP), KAPPA_CAP)
        for c in ("kappa_low", "kappa_legs")
    )
    n_walk = plan.n_walking_steps
    lift = plan.step_start[:n_walk] + plan.step_dsp[:n_walk]
    land = plan.landing_times()[:n_walk]
    walking = (t >= plan.t_start) & (t <= plan.walk_end)
    sub = np.flatnonzero(walking)[::DOWNSAMPLE]
    # theta_ref's first sample refers to one MPC sample after the tick (t + T_p); a row's time
    # is the tick's time + control_dt
    lead = params.com.sample_time - params.control_dt
    out = Extracts(
        step=(
            _step_extract(series, plan, t, kappa, mid_step, summary, lead)
            if "step" in extracts
            else None
        ),
        walk=(
            WalkExtract(
                t=samples(t[sub]),
                **{c: samples(series.column(c)[sub]) for c in WALK_COLUMNS},
                step_start=samples(plan.step_start),
            )
            if "walk" in extracts
            else None
        ),
        zmp=_zmp_extract(series, plan, t, sub, walking) if "zmp" in extracts else None,
    )
    return RunResult(
        spec,
        RunSummary.from_run(
            summary,
            kappa_liftoff=_event_peaks(t, kappa, lift),
            kappa_landing=_event_peaks(t, kappa, land),
            kappa_legs_liftoff=_event_peaks(t, kappa_legs, lift),
            kappa_legs_landing=_event_peaks(t, kappa_legs, land),
        ),
        out,
        wall_s=time.perf_counter() - start,
    )
