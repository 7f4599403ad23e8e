"""Section 8: where the paper's +0.10 m of pelvic rotation appears on our model.

The longest step that walks and the longest clean one (the core's limit search
(``pelvic_walk.core.measure``), the same
as ``pelvic-walk sweep --measure limit``), for the fixed pelvis and the MPC, over a grid of
two parameters (:class:`~app.experiments.definitions.Sensitivity`: k_pel x the DSP share) and
a few more cells (the authors' DSP and step width, the step time, the lateral distance's
readings). Each search brackets the clean limit at the default thresholds (landing within
2 cm, kappa(legs) below 1000) and with one threshold changed
(``pelvic_walk.core.measure.criteria``), from the same runs, and keeps every run's outcome.

A method does not read every parameter (:func:`effective`), so a run serves every cell that
differs only in parameters it does not read: the fixed pelvis runs once per value of the
others, its row serves every k_pel. Which parameters are whose is the strategy registry's
(``controller.strategy.own_fields``: the MPC owns its weights and limits, ``pelvis.alpha``,
``pelvis.beta``, ``pelvis.angle_limit_deg``, ``pelvis.acc_limit``; redundancy
``ik.redundancy_weight``; a user's strategy its ``Params``): a strategy reads its own and no
other strategy's. The rest of the Pelvic MPC group (k_pel, the lateral distance's reading, ...)
shapes the reference angle theta_ref of eq. (27)-(33), which a strategy reads only through
``s.theta_ref``: the paper's fixed pelvis and redundancy never do (:data:`IGNORE_REFERENCE`).
Every MPC row is compared with the fixed pelvis's row at the same parameters it reads
(:meth:`SensitivitySection.gain`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from app.experiments.definitions import Sensitivity, Study
from controller import strategy
from controller.params import ControllerParams, PelvisMpcParams
from controller.strategy import FIXED, MPC, REDUNDANCY
from pelvic_walk.core.grid import Cell
from pelvic_walk.core.measure import LimitSearch, LimitTask, criteria, outcome_of
from pelvic_walk.core.metrics import KAPPA_SINGULAR
from pelvic_walk.core.run_spec import Override, length

# the paper's strategies whose waist rate does not depend on the reference angle theta_ref
# (eq. 27-33): fixed pins 0, redundancy leaves the waist to the IK (controller/strategy.py)
IGNORE_REFERENCE = (FIXED, REDUNDANCY)
# what a row keeps of each run (besides its length and outcome)
RUN_KEYS = (
    "fell",
    "landing_error_max",
    "condition_number_legs_max",
    "waist_yaw_max_deg",
    "speed_limited_ticks",
    "servo_saturation_substeps",
    "solver_failures",
)


def owner(name: str) -> str | None:
    """The registered strategy that owns the parameter stored as ``name`` (the registry's
    ``own_fields``), or None: a parameter every strategy's walk reads."""
    for n in strategy.names():
        if name in strategy.own_fields(n).values():
            return n
    return None


def reference_params() -> tuple[str, ...]:
    """The parameters of the reference angle theta_ref (eq. 27-33): the Pelvic MPC group's
    that the MPC does not own (its weights and limits are its own, the rest is the
    reference's that the walker computes for every strategy)."""
    mine = set(strategy.own_fields(MPC).values())
    names = (f"pelvis.{f.name}" for f in dataclasses.fields(PelvisMpcParams))
    return tuple(n for n in names if n not in mine)


def reads_param(method: str, name: str) -> bool:
    """Whether a run of ``method`` reads the parameter stored as ``name``."""
    own = owner(name)
    if own is not None:
        return own == method
    return not (method in IGNORE_REFERENCE and name in reference_params())


def effective(method: str, overrides: tuple[Override, ...]) -> tuple[Override, ...]:
    """The overrides ``method`` reads (sorted by name)."""
    return tuple(sorted((n, v) for n, v in overrides if reads_param(method, n)))


def grid_cells(s: Sensitivity) -> list[tuple[Override, ...]]:
    """The grid's cells, rows slowest, each as its overrides (a default value stays)."""
    (rn, rv), (cn, cv) = s.rows, s.columns
    return [((rn, r), (cn, c)) for r in rv for c in cv]


def defaults(s: Sensitivity) -> dict[str, Any]:
    """Every parameter the section varies -> its default."""
    p = ControllerParams()
    names = [s.rows[0], s.columns[0]] + [n for c in s.cells for n, _ in c.overrides]
    return {name: p.value(name) for name in names}


def _without_defaults(overrides: tuple[Override, ...]) -> tuple[Override, ...]:
    """Overrides that only restate a default are dropped, so equal runs share one key."""
    p = ControllerParams()
    return tuple((n, v) for n, v in overrides if p.value(n) != v)


def reads(method: str, overrides: tuple[Override, ...]) -> tuple[Override, ...]:
    """The overrides ``method`` reads that are off their defaults: equal for runs that are
    the same run."""
    return _without_defaults(effective(method, overrides))


def _key(method: str, overrides: tuple[Override, ...]) -> tuple[str, tuple[Override, ...]]:
    return method, reads(method, overrides)


@dataclass(frozen=True)
class SensitivityRow:
    """One method at one set of parameters: its limits for each criterion and its runs."""

    method: str
    overrides: list[list[Any]]  # [name, value] pairs it reads, off their defaults
    limits: dict[str, float | None]  # criterion -> longest length passing it [m]
    first_fails: dict[str, float | None]  # criterion -> shortest length failing it [m]
    runs: int
    wall_s: float
    error: str | None
    waist_at_first_deg: float | None  # peak |waist angle| of the run at Sensitivity.first
    runs_data: list[dict[str, Any]] = field(default_factory=list)  # every run, by length

    @property
    def walks_limit(self) -> float | None:
        return self.limits.get("walks")

    @property
    def clean_limit(self) -> float | None:
        return self.limits.get("clean")


@dataclass(frozen=True)
class SensitivitySection:
    n_steps: int
    resolution: float  # [m]
    search: tuple[float, float]  # [m] lengths the limit search covers
    first: float  # [m]
    defaults: dict[str, Any]  # parameter -> its default
    rows_axis: tuple[str, list[Any]]
    columns_axis: tuple[str, list[Any]]
    cells: list[tuple[str, list[list[Any]]]]  # (name, overrides) beside the grid
    criteria: list[str]  # walks, clean, then clean at other thresholds
    methods: list[str]
    rows: list[SensitivityRow] = field(default_factory=list)
    n_runs: int = 0
    duration_s: float = 0.0

    @property
    def clean_criteria(self) -> list[str]:
        """The clean criteria, by landing threshold, then by kappa(legs) bound."""
        from pelvic_walk.core.measure import threshold_of

        names = [c for c in self.criteria if c != "walks"]
        return sorted(names, key=lambda c: (threshold_of(c)[1] != KAPPA_SINGULAR, threshold_of(c)))

    def row(self, method: str, overrides: Any) -> SensitivityRow | None:
        """The row of ``method`` at ``overrides`` (pairs; those it does not read ignored)."""
        want = _key(method, tuple((str(n), v) for n, v in overrides))
        for r in self.rows:
            if _key(r.method, tuple((str(n), v) for n, v in r.overrides)) == want:
                return r
        return None

    def limit(self, method: str, overrides: Any, criterion: str = "clean") -> float | None:
        r = self.row(method, overrides)
        return r.limits.get(criterion) if r else None

    def gain(self, overrides: Any, criterion: str = "clean") -> float | None:
        """The MPC's limit minus the fixed pelvis's at the same parameters [m]."""
        m, f = self.limit(MPC, overrides, criterion), self.limit(FIXED, overrides, criterion)
        return None if m is None or f is None else round(m - f, 3)

    def grid(self) -> list[tuple[Any, Any, list[list[Any]]]]:
        """(row value, column value, overrides) of every grid cell, rows slowest."""
        (rn, rv), (cn, cv) = self.rows_axis, self.columns_axis
        return [(r, c, [[rn, r], [cn, c]]) for r in rv for c in cv]

    def all_cells(self) -> list[tuple[str, list[list[Any]]]]:
        """Every cell in words: the grid's, then the others (the defaults' cell first)."""
        (rn, _), (cn, _) = self.rows_axis, self.columns_axis
        out = [(f"{rn} = {r}, {cn} = {c}", ov) for r, c, ov in self.grid()]
        return out + list(self.cells)

    def best_gain(self, criterion: str = "clean") -> tuple[float, str] | None:
        """The largest MPC - fixed gain over every cell, and the cell's name."""
        gains = [
            (g, name)
            for name, ov in self.all_cells()
            if (g := self.gain(ov, criterion)) is not None
        ]
        return max(gains, key=lambda x: x[0]) if gains else None

    def cells_with_gain(self, at_least: float, criterion: str = "clean") -> list[str]:
        """The cells whose MPC - fixed gain is at least ``at_least`` [m]."""
        return [
            name
            for name, ov in self.all_cells()
            if (g := self.gain(ov, criterion)) is not None and g >= at_least - 1e-9
        ]


def plan(study: Study) -> list[tuple[str, tuple[Override, ...], LimitTask]]:
    """One limit task per (method, parameters it reads), shared by the cells that need it."""
    s = study.sensitivity
    if s is None:
        return []
    lo, hi, res = s.search
    tests = criteria(s.landings, s.kappas)
    wanted = [(m, ov) for ov in grid_cells(s) for m in s.methods]
    wanted += [(m, c.overrides) for c in s.cells for m in c.methods]
    out: list[tuple[str, tuple[Override, ...], LimitTask]] = []
    seen: set[tuple[str, tuple[Override, ...]]] = set()
    for m, ov in wanted:
        key = _key(m, ov)
        if key in seen:
            continue
        seen.add(key)
        search = LimitSearch(lo, hi, res, names=tuple(tests), first=s.first)
        fixed = (("walk.n_steps", s.steps), *study.overrides_for(m))
        task = LimitTask(Cell(len(out), key[1], fixed), m, search, tests)
        out.append((m, key[1], task))
    return out


def _run_data(x: float, outcome: dict[str, Any]) -> dict[str, Any]:
    return {"step_length": x, "outcome": outcome_of(outcome)} | {
        k: outcome.get(k) for k in RUN_KEYS
    }


def section(
    study: Study,
    planned: list[tuple[str, tuple[Override, ...], LimitTask]],
    n_runs: int,
    duration_s: float,
) -> SensitivitySection | None:
    """The section from the finished tasks of :func:`plan`."""
    s = study.sensitivity
    if s is None:
        return None
    lo, hi, res = s.search
    names = list(criteria(s.landings, s.kappas))
    rows = []
    for m, ov, task in planned:
        r = task.row()
        at_first = task.outcomes.get(length(s.first))
        rows.append(
            SensitivityRow(
                method=m,
                overrides=[[n, v] for n, v in ov],
                limits={c: r[f"{c}_limit"] for c in names},
                first_fails={c: r[f"{c}_first_fail"] for c in names},
                runs=r["runs"],
                wall_s=r["wall_s"],
                error=r["error"],
                waist_at_first_deg=at_first.get("waist_yaw_max_deg") if at_first else None,
                runs_data=[_run_data(x, o) for x, o in sorted(task.outcomes.items())],
            )
        )
    return SensitivitySection(
        n_steps=s.steps,
        resolution=res,
        search=(lo, hi),
        first=s.first,
        defaults=defaults(s),
        rows_axis=(s.rows[0], list(s.rows[1])),
        columns_axis=(s.columns[0], list(s.columns[1])),
        cells=[(c.name, [[n, v] for n, v in c.overrides]) for c in s.cells],
        criteria=names,
        methods=list(s.methods),
        rows=rows,
        n_runs=n_runs,
        duration_s=duration_s,
    )


def lateral_limits(sens: SensitivitySection | None) -> dict[str, dict[str, float | None]]:
    """Each reading of the lateral distance -> the MPC's walks and clean limits."""
    from app.experiments.definitions import LATERAL
    from controller.params import LATERAL_MODES

    if sens is None:
        return {}
    out = {}
    for mode in LATERAL_MODES:
        r = sens.row(MPC, [[LATERAL, mode]])
        if r is not None:
            out[mode] = {"walks_limit": r.walks_limit, "clean_limit": r.clean_limit}
    return out
