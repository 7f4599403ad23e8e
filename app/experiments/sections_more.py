"""The sections added for a fair reading (issue 13): lateral distance, balance, sensitivity.

Like :mod:`sections`, each function takes the :class:`Study` and the run results and returns
its dataclass (:mod:`app.experiments.results_more`). The sensitivity section runs its own
limit searches through ``app.sweep`` (:func:`sensitivity_tasks`, :func:`sensitivity`).

- *DSP share*: the waist angle's change from the step's start to its lift-off, as a share of
  its range over the step. A sine over the step (``-A cos(pi t / T)``) moves
  ``(1 - cos(pi r)) / 2`` of its range in a DSP of share ``r`` (9.5 % for r = 0.2): the
  yardstick of Fig. 8-9's "smoothly generated from the moment the step starts".
- *balance margin*: the measured CoP's distance to the edge of the support polygon of the
  feet in contact (``app.sim.world.polygon_margin``), over the walking ticks up to a fall;
  *tilt*: the largest angle of a foot in contact from the floor.
"""

from __future__ import annotations

import math
from typing import Any

from app.experiments.definitions import LATERAL, Study, length
from app.experiments.results import Results, case_key
from app.experiments.results_more import (
    BalanceCase,
    BalanceSection,
    LateralCase,
    LateralSection,
    SensitivityRow,
    SensitivitySection,
)
from app.experiments.sections import step_of, summary_of, waist_case
from controller.params import LATERAL_MODES, ControllerParams

BALANCE_LENGTHS = (0.15, 0.20, 0.25, 0.30, 0.35, 0.40)  # [m] Table 1's lengths


def sine_share(dsp_ratio: float) -> float:
    """Share of its range a sine over the step moves in a DSP of share ``dsp_ratio``."""
    return (1.0 - math.cos(math.pi * dsp_ratio)) / 2.0


# -- section 3: the lateral distance ----------------------------------------------------------
def lateral(study: Study, results: Results, sens: SensitivitySection | None) -> LateralSection:
    from app.sweep.measure import walks

    p = ControllerParams()
    default = p.pelvis.lateral_distance
    cases: dict[str, LateralCase | None] = {}
    for x in study.figure_lengths:
        for mode in LATERAL_MODES:
            spec = study.lateral_run(mode, x)
            s, ex = summary_of(results, spec), step_of(results, spec)
            if s is None or ex is None or len(ex.t) < 3:
                cases[case_key(mode, x)] = None
                continue
            w = waist_case("mpc", x, ex)
            turn = math.copysign(1.0, w.angle_end_deg - w.angle_start_deg)
            cases[case_key(mode, x)] = LateralCase(
                mode=mode,
                step_length=x,
                default=mode == default,
                clean=s.clean,
                walks=walks(s.as_dict()),
                range_deg=w.range_deg,
                dsp_change_deg=w.dsp_change_deg,
                dsp_share_of_range=w.dsp_share_of_range,
                toward_swing=w.dsp_change_deg * turn > 0,
                peak_abs_rate_deg_s=w.peak_abs_rate_deg_s,
                peak_abs_rate_change_deg_s2=w.peak_abs_rate_change_deg_s2,
                kappa_legs_max=s.other.get("condition_number_legs_max"),
            )
    limits: dict[str, dict[str, float | None]] = {}
    if sens is not None:
        for mode in LATERAL_MODES:
            name, value = ("", "") if mode == default else (LATERAL, mode)
            limits[mode] = {
                k: sens.limit(name, value, "mpc", k) for k in ("walks_limit", "clean_limit")
            }
    return LateralSection(
        dsp_ratio=p.walk.dsp_ratio,
        sine_share=sine_share(p.walk.dsp_ratio),
        default_mode=default,
        cases=cases,
        limits=limits,
    )


# -- section 7: balance margin ------------------------------------------------------------------
def balance(study: Study, results: Results) -> BalanceSection:
    """Margin and tilt of the unseeded figure runs at Table 1's lengths (where they ran)."""
    lengths = [x for x in BALANCE_LENGTHS if any(s.step_length == x for s in results)]
    cases: dict[str, BalanceCase | None] = {}
    for x in lengths:
        for m in study.methods:
            s = summary_of(results, study.figure_run(m, x))
            if s is None:
                cases[case_key(m, x)] = None
                continue
            o = s.other

            def mm(key: str, o: dict[str, Any] = o) -> float | None:
                return None if o.get(key) is None else 1000.0 * o[key]

            cases[case_key(m, x)] = BalanceCase(
                method=m,
                step_length=x,
                clean=s.clean,
                fell=s.fell,
                margin_min_mm=mm("balance_margin_min"),
                margin_p5_mm=mm("balance_margin_p5"),
                tilt_max_deg=o.get("sole_tilt_max_deg"),
            )
    return BalanceSection(lengths, cases)


# -- section 8: sensitivity ----------------------------------------------------------------------
def sensitivity_cells(study: Study) -> list[tuple[str, Any, str, Any]]:
    """(parameter, value, method, sweep Cell) of the baseline and every axis value."""
    from app.sweep.grid import Cell

    fixed = (("walk.n_steps", study.sensitivity_steps), *study.overrides)
    methods = sorted({m for _, _, ms in study.sensitivity for m in ms}, key=study.methods.index)
    out = [("", "", m, Cell(0, (), fixed)) for m in methods]
    for name, values, ms in study.sensitivity:
        for v in values:
            out += [(name, v, m, Cell(len(out), ((name, v),), fixed)) for m in ms]
    return out


def sensitivity_defaults(study: Study) -> dict[str, Any]:
    p = ControllerParams()
    return {
        name: getattr(getattr(p, name.split(".")[0]), name.split(".")[1])
        for name, _, _ in study.sensitivity
    }


def run_sensitivity(study: Study, jobs: int) -> SensitivitySection:
    """The limit search of every sensitivity cell on a local process pool (``app.sweep``)."""
    import time

    from app.sweep.measure import LimitSearch, LimitTask
    from app.sweep.run import InProcess, LocalPool, execute

    cells = sensitivity_cells(study)
    lo, hi, step = study.sensitivity_search
    section = SensitivitySection(
        n_steps=study.sensitivity_steps,
        resolution=step,
        search=(lo, hi),
        defaults=sensitivity_defaults(study),
    )
    if not cells:
        return section
    tasks = [LimitTask(cell, m, LimitSearch(lo, hi, step)) for _, _, m, cell in cells]
    t0 = time.perf_counter()
    backend = LocalPool(min(jobs, len(tasks))) if jobs > 1 else InProcess()
    try:
        n_runs = execute(tasks, backend, desc=f"sensitivity ({len(tasks)} cells)")
    finally:
        backend.close()
    rows = []
    for (name, value, m, _), task in zip(cells, tasks, strict=True):
        r = task.row()
        rows.append(
            SensitivityRow(
                parameter=name,
                value=value,
                method=m,
                walks_limit=r["walks_limit"],
                walks_first_fail=r["walks_first_fail"],
                clean_limit=r["clean_limit"],
                clean_first_fail=r["clean_first_fail"],
                runs=r["runs"],
                wall_s=r["wall_s"],
                error=r["error"],
            )
        )
    return SensitivitySection(
        n_steps=section.n_steps,
        resolution=section.resolution,
        search=section.search,
        defaults=section.defaults,
        rows=rows,
        n_runs=n_runs,
        duration_s=time.perf_counter() - t0,
    )


def gain_percent(fixed: float | None, mpc: float | None) -> float | None:
    """MPC's limit over the fixed pelvis's [%]."""
    if fixed is None or mpc is None or fixed <= 0:
        return None
    return 100.0 * (length(mpc) / length(fixed) - 1.0)
