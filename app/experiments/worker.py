"""One run of the study in a worker process: :func:`execute` -> a small :class:`RunResult`.

A worker runs one :class:`RunSpec` headless and sends back only the summary plus the small
extracts its sections asked for (one mid-walk step at 200 Hz, the walking phase at 100 Hz):
the full ring buffer never crosses a process boundary.

The footstep plan is read through its tables (step timing) and, for the feet the plan has on
the ground, through :func:`_planned_feet` alone. While the run goes, :class:`EdgeCounter`
notes where the centre of pressure sits when it is on a sole's edge (section 7).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from app.experiments.balance import EDGE_MARGIN, EDGES
from app.experiments.outcomes import (
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
from pelvic_walk.core.run_spec import RunSpec

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
    "balance_margin",
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


def _planned_support(
    plan: Any, t: np.ndarray, x: np.ndarray, y: np.ndarray
) -> tuple[float, float | None]:
    """(share of samples whose (x, y) lies in the convex hull of the feet the plan has down,
    the farthest a sample lay outside it [mm] (None: none outside))."""
    from pelvic_walk.core.world import convex_hull, point_in_polygon, polygon_margin

    hx, hy = FOOT_SIZE[0] / 2, FOOT_SIZE[1] / 2
    corners = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
    on_ground, feet = _planned_feet(plan, t)
    inside = n = 0
    outside = 0.0
    for i in range(len(t)):
        if not (math.isfinite(x[i]) and math.isfinite(y[i])):
            continue
        pts = [corners + feet[i, s, :2] for s in range(2) if on_ground[i, s]]
        hull = convex_hull(np.vstack(pts))
        p = np.array([x[i], y[i]])
        n += 1
        if point_in_polygon(p, hull):
            inside += 1
        else:
            outside = max(outside, -polygon_margin(p, hull))
    share = inside / n if n else float("nan")
    return share, (1000.0 * outside if outside > 0 else None)


class EdgeCounter:
    """Counts the walking ticks, and those with the CoP on the support polygon's edge by edge
    (:data:`~app.experiments.balance.EDGES`): a run's ``on_tick`` hook."""

    def __init__(self) -> None:
        self.counts = dict.fromkeys(("walking", *EDGES), 0)
        hx, hy = FOOT_SIZE[0] / 2, FOOT_SIZE[1] / 2
        self.half = (hx, hy)

    def __call__(self, session: Any) -> None:
        plan, m = session.plan, session.measured
        if m is None or not plan.t_start <= m.t <= plan.walk_end or session.fell:
            return
        self.counts["walking"] += 1
        if m.contacts.cop is None or not abs(m.balance_margin) < EDGE_MARGIN:
            return
        feet = np.flatnonzero(m.contacts.in_contact)
        if len(feet) != 1:
            self.counts["two feet"] += 1
            return
        side = int(feet[0])  # 0 left, 1 right (pelvic_walk.core.world's order)
        d, site = session.world.data, int(session.world.sole_site_ids[side])
        mat = d.site_xmat[site].reshape(3, 3)
        u, v = mat[:2, :2].T @ (m.contacts.cop - d.site_xpos[site, :2])  # sole frame
        hx, hy = self.half
        gaps = {"toe": hx - u, "heel": u + hx, "left": hy - v, "right": v + hy}
        edge = min(gaps, key=lambda k: gaps[k])
        if edge in ("left", "right"):  # the outer edge is away from the other foot
            edge = "outer" if (edge == "left") == (side == 0) else "inner"
        self.counts[edge] += 1


def _step_extract(
    series: Any,
    plan: Any,
    t: np.ndarray,
    kappa: np.ndarray,
    kappa_legs: np.ndarray,
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
        kappa_legs=samples(kappa_legs[sel]),
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
    lipm, lipm_out = _planned_support(plan, t[walking], lx[walking], ly[walking])
    cop, _ = _planned_support(plan, t[walking], cx[walking], cy[walking])
    return ZmpExtract(
        t=samples(t[sub]),
        **{c: samples(series.column(c)[sub]) for c in ZMP_COLUMNS},
        footholds=plan.footholds()[:, :2].tolist(),
        lipm_in_planned_support=lipm,
        cop_in_planned_support=cop,
        cop_in_measured_support=float(np.nanmean(series.column("zmp_in_support")[walking])),
        lipm_outside_max_mm=lipm_out,
    )


def execute(spec: RunSpec, extracts: tuple[str, ...], mid_step: int) -> RunResult:
    """Run one spec headless; return its summary and the requested extracts (small)."""
    from pelvic_walk.core.run import run, summarize

    start = time.perf_counter()
    params = spec.params()
    edges = EdgeCounter()
    try:
        session = run(spec.config(), on_tick=edges)
    except Exception as exc:  # a crashed run is reported, never hides the others
        return RunResult(
            spec, None, error=f"{type(exc).__name__}: {exc}", wall_s=time.perf_counter() - start
        )
    summary = summarize(session)
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
            _step_extract(series, plan, t, kappa, kappa_legs, mid_step, summary, lead)
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
            cop_edge_ticks=edges.counts,
        ),
        out,
        wall_s=time.perf_counter() - start,
    )
