"""What one cell of a sweep measures, for one method: a *task* that asks for runs one by one.

A run is :func:`run_one` (a :class:`~pelvic_walk.core.run_spec.RunSpec` in, a flat dict of plain
values
out, so it crosses process and Ray boundaries cheaply). A task gives its next job with
:meth:`next_job` (``(run, (spec,))`` for :func:`pelvic_walk.core.engine.run_tasks`), is told each
outcome with :meth:`record`, and gives its table row with :meth:`row`. Runs are deterministic
given their parameters, so a task's row does not depend on which backend ran it or in which
order the cells finished.

``summary`` (:class:`SummaryTask`): one walk of ``walk.n_steps`` steps at the cell's
parameters (step length from the grid, else the default); the row has the keys of
``simulate --json`` (``pelvic_walk.core.summary.SUMMARY_KEYS``), ``clean``, the derived ``walks``
and the summary's other scalar extras.

``limit`` (:class:`LimitTask`, logic in :class:`LimitSearch`): the longest step length that
*walks* (a success: no fall, the plan completed, every landing within ``LANDING_ERROR_CLEAN``
= 2 cm, QPs failing on at most 1 % of the ticks) and
the longest that is *clean* (:func:`clean`: walks, and no QP failure, no servo saturation, no
IK tick at the joint-speed limit, kappa(legs) below ``KAPPA_SINGULAR``). A search can bracket
more criteria from the same runs: :func:`criteria` gives the clean criterion at other
thresholds (the landing error and the kappa(legs) bound), named ``clean@<landing>cm`` and
``clean@kappa<K>``.

The search: step lengths on a grid from :data:`SEARCH_MIN` = 0.10 m to :data:`SEARCH_MAX` =
0.60 m at :data:`RESOLUTION` = 0.01 m (51 lengths). A bisection for each criterion in turn
(walks first, then clean, then the others) inside the bracket the runs so far leave (a
stricter criterion's failure bounds the others, so later criteria need few runs). Two
criteria take at most 11 runs per cell and method when the outcomes are monotonic in length
(6-11, mean 8.3, on the DSP-share sweep of fixed and mpc), sequential (each length depends on
the last outcome). A limit is *the longest length below the shortest failure found*:
``walks_limit`` walked and ``walks_first_fail`` = ``walks_limit`` + 0.01 m did not (None:
nothing failed up to 0.60 m, the limit is at least the range's top; ``walks_limit`` None: even
0.10 m failed). Bisection never tests above a known failure, so its runs are consistent by
construction; when a later run finds a failure below a length that passed, the bracket moves
below that failure and the search resumes there, and the lengths that passed above the
shortest failure are listed in ``<criterion>_above`` (failures that are not monotonic in length
show up there rather than being hidden). ``trace`` lists every run in order.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from functools import partial
from typing import Any

from pelvic_walk.core.grid import Cell, Grid, GridError
from pelvic_walk.core.metrics import KAPPA_SINGULAR, LANDING_ERROR_CLEAN
from pelvic_walk.core.run_spec import RunSpec, length
from pelvic_walk.core.summary import MISSED_FOOTHOLDS, SUMMARY_KEYS

SEARCH_MIN = 0.10  # [m] shortest step length the limit search tries
SEARCH_MAX = 0.60  # [m] longest (the step_length parameter's maximum)
RESOLUTION = 0.01  # [m]
OUTCOMES = ("clean", "walks", "fails", "error")  # of one run, best first
CRITERIA = ("walks", "clean")  # the limit measure's default criteria
TASK_COLUMNS = ("runs", "wall_s", "error")  # every row ends with these

Outcome = dict[str, Any]  # what run_one returns
Criterion = Callable[[Outcome], bool]
RunFunction = Callable[[RunSpec], Outcome]


def limit_columns(names: Sequence[str] = CRITERIA) -> tuple[str, ...]:
    """The limit columns of a row for the criteria ``names``."""
    return (
        *(f"{c}_{k}" for c in names for k in ("limit", "first_fail")),
        *(f"{c}_above" for c in names),
        "trace",
    )


LIMIT_COLUMNS = limit_columns()


def walks(summary: Mapping[str, Any], landing: float = LANDING_ERROR_CLEAN) -> bool:
    """A success but for the landings (no fall, the plan completed, QPs within their share of
    ticks: ``pelvic_walk.core.summary``), every landing within ``landing`` [m]; at the default, the
    summary's own success."""
    le = summary.get("landing_error_max")
    reasons = summary.get("unsuccessful")
    if reasons is None:  # a summary without its reasons: its success says it all
        landed = bool(summary.get("success"))
    else:
        landed = all(r == MISSED_FOOTHOLDS for r in reasons)
    return landed and le is not None and le < landing


def clean(
    summary: Mapping[str, Any],
    landing: float = LANDING_ERROR_CLEAN,
    kappa: float = KAPPA_SINGULAR,
) -> bool:
    """The clean criterion of a run's summary at other thresholds: walks (landings within
    ``landing``), no QP failure, no servo saturation, no IK tick at the joint-speed limit,
    kappa(legs) below ``kappa``. At the defaults it is the summary's own ``clean``
    (``pelvic_walk.core.summary``; a test checks that they agree)."""
    legs = summary.get("condition_number_legs_max")
    return (
        walks(summary, landing)
        and not summary.get("solver_failures")
        and not summary.get("servo_saturation_substeps")
        and not summary.get("speed_limited_ticks")
        and legs is not None
        and legs < kappa
    )


def _walked(outcome: Outcome) -> bool:
    """The run's own ``walks`` flag (:func:`run_one`)."""
    return bool(outcome.get("walks"))


def _was_clean(outcome: Outcome) -> bool:
    """The run's own ``clean`` flag (the summary's)."""
    return bool(outcome.get("clean"))


DEFAULT_TESTS: dict[str, Criterion] = {"walks": _walked, "clean": _was_clean}


def criteria(landings: Sequence[float] = (), kappas: Sequence[float] = ()) -> dict[str, Criterion]:
    """``walks`` and ``clean`` as the run says, then clean with one threshold changed: each
    landing error of ``landings`` [m] (``clean@1cm``) and each kappa(legs) bound of ``kappas``
    (``clean@kappa300``), from the run's fields (:func:`clean`)."""
    out: dict[str, Criterion] = dict(DEFAULT_TESTS)
    for le in landings:
        if abs(le - LANDING_ERROR_CLEAN) > 1e-12:
            out[f"clean@{le * 100:g}cm"] = partial(clean, landing=le)
    for k in kappas:
        if abs(k - KAPPA_SINGULAR) > 1e-9:
            out[f"clean@kappa{k:g}"] = partial(clean, kappa=k)
    return out


def threshold_of(name: str) -> tuple[float, float]:
    """(landing [m], kappa(legs) bound) of a criterion named by :func:`criteria`."""
    landing, kappa = LANDING_ERROR_CLEAN, KAPPA_SINGULAR
    if name.startswith("clean@kappa"):
        kappa = float(name[len("clean@kappa") :])
    elif name.startswith("clean@") and name.endswith("cm"):
        landing = float(name[len("clean@") : -2]) / 100
    return landing, kappa


def _plain(value: Any) -> Any:
    """A JSON-safe scalar (non-finite floats -> None)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def run_one(spec: RunSpec) -> Outcome:
    """One closed-loop headless run (``pelvic_walk.core.run.run``) -> its summary as plain values.

    The keys of ``simulate --json``, then ``clean``, ``walks``, the summary's other scalar
    keys, and ``wall_s`` (this run's wall time). A run that raises returns ``{"error": ...}``
    (a crash is an outcome of the parameters, never hides the other cells).
    """
    from pelvic_walk.core.run import run, summarize

    start = time.perf_counter()
    try:
        summary = summarize(run(spec.config()))
    except Exception as exc:
        return {"error": f"{type(exc).__name__}: {exc}", "wall_s": time.perf_counter() - start}
    out: Outcome = {k: _plain(summary[k]) for k in SUMMARY_KEYS}
    out["clean"] = bool(summary["clean"])
    out["walks"] = walks(summary)
    for key, value in summary.items():
        if key not in out and (value is None or isinstance(value, (bool, int, float, str))):
            out[key] = _plain(value)
    out["wall_s"] = time.perf_counter() - start
    return out


def outcome_of(result: Outcome) -> str:
    """One of :data:`OUTCOMES`."""
    if result.get("error"):
        return "error"
    if result.get("clean"):
        return "clean"
    return "walks" if result.get("walks") else "fails"


def _passes_label(criterion: str, outcome: str) -> bool:
    """Whether a run labelled ``outcome`` passes ``criterion`` (the labels know walks and
    clean; a clean run passes every clean criterion, as a run's label says no more)."""
    if criterion == "walks":
        return outcome in ("clean", "walks")
    return outcome == "clean"


class LimitSearch:
    """Bisection for the longest step length passing each criterion in turn.

    Pure logic, no runs: :meth:`next_length` says which length to run next (None when done),
    :meth:`record` takes whether the run passed each criterion (or an outcome label of
    :data:`OUTCOMES`). ``first``: the length to try first (e.g. one a report shows).
    """

    def __init__(
        self,
        lo: float = SEARCH_MIN,
        hi: float = SEARCH_MAX,
        resolution: float = RESOLUTION,
        names: Sequence[str] = CRITERIA,
        first: float | None = None,
    ):
        if not 0 < lo < hi or resolution <= 0:
            raise ValueError(f"bad search range {lo}..{hi} at {resolution}")
        n = int(round((hi - lo) / resolution)) + 1
        self.lengths = [length(lo + i * resolution) for i in range(n)]
        self.names = tuple(names)
        if first is not None and length(first) not in self.lengths:
            raise ValueError(f"first length {first} is not on the search grid")
        self.first = None if first is None else length(first)
        self.passed: dict[int, dict[str, bool]] = {}  # index into lengths -> criterion -> ok
        self.labels: dict[int, str] = {}  # index -> outcome label (for the trace)
        self.order: list[int] = []  # the runs in the order they were made

    @property
    def outcomes(self) -> dict[int, str]:
        """Index -> outcome label of every run made."""
        return dict(self.labels)

    def bracket(self, criterion: str) -> tuple[int, int]:
        """(longest passing index below the shortest failure, shortest failure); -1 / n
        where there is none."""
        n = len(self.lengths)
        failed = [i for i, ok in self.passed.items() if not ok[criterion]]
        hi = min(failed, default=n)
        good = [i for i, ok in self.passed.items() if ok[criterion] and i < hi]
        return max(good, default=-1), hi

    def next_length(self) -> float | None:
        if not self.passed and self.first is not None:
            return self.first
        for criterion in self.names:
            lo, hi = self.bracket(criterion)
            if hi - lo > 1:
                return self.lengths[(lo + hi) // 2]
        return None

    def record(self, step_length: float, passed: Mapping[str, bool] | str) -> None:
        i = self.lengths.index(length(step_length))
        if isinstance(passed, str):
            if passed not in OUTCOMES:
                raise ValueError(f"unknown outcome {passed!r}")
            label = passed
            ok = {c: _passes_label(c, passed) for c in self.names}
        else:
            ok = {c: bool(passed[c]) for c in self.names}
            label = "clean" if ok.get("clean") else ("walks" if ok.get("walks") else "fails")
        self.passed[i] = ok
        self.labels[i] = label
        self.order.append(i)

    def runs_left_estimate(self) -> int:
        """Runs still to make if the outcomes stay monotonic (for a progress bar)."""
        total = 0
        for criterion in self.names:
            lo, hi = self.bracket(criterion)
            total += math.ceil(math.log2(hi - lo)) if hi - lo > 1 else 0
        return total

    def result(self) -> dict[str, Any]:
        """The limit columns of the row (:func:`limit_columns` of the criteria)."""
        out: dict[str, Any] = {}
        n = len(self.lengths)
        for criterion in self.names:
            lo, hi = self.bracket(criterion)
            out[f"{criterion}_limit"] = self.lengths[lo] if lo >= 0 else None
            out[f"{criterion}_first_fail"] = self.lengths[hi] if hi < n else None
        for criterion in self.names:
            _, hi = self.bracket(criterion)
            out[f"{criterion}_above"] = sorted(
                self.lengths[i] for i, ok in self.passed.items() if i > hi and ok[criterion]
            )
        out["trace"] = " ".join(f"{self.lengths[i]:.2f}={self.labels[i]}" for i in self.order)
        return out


class _TaskBase:
    def __init__(self, cell: Cell, method: str, run: RunFunction = run_one):
        self.cell = cell
        self.method = method
        self.run = run
        self.runs = 0
        self.wall_s = 0.0
        self.errors: list[str] = []

    def _count(self, spec: RunSpec, result: Outcome) -> None:
        self.runs += 1
        self.wall_s += float(result.get("wall_s") or 0.0)
        if result.get("error"):
            self.errors.append(f"L={spec.step_length:.2f}: {result['error']}")

    def _tail(self) -> dict[str, Any]:
        return {
            "runs": self.runs,
            "wall_s": round(self.wall_s, 3),
            "error": "; ".join(self.errors) or None,
        }

    def label(self, job: tuple[Any, tuple[Any, ...]]) -> str:
        spec = job[1][0]
        return f"{self.cell.label} {self.method} L={spec.step_length:.2f}"


class SummaryTask(_TaskBase):
    """One run at the cell's parameters; the row is its summary."""

    def __init__(self, cell: Cell, method: str, run: RunFunction = run_one):
        super().__init__(cell, method, run)
        self.spec = cell.spec(method)
        self.result: Outcome | None = None

    def next_job(self) -> tuple[RunFunction, tuple[RunSpec]] | None:
        return (self.run, (self.spec,)) if self.runs == 0 else None

    def record(self, job: tuple[Any, tuple[Any, ...]], result: Outcome) -> None:
        self._count(job[1][0], result)
        self.result = result

    def jobs_left_estimate(self) -> int:
        return 0 if self.runs else 1

    def row(self) -> dict[str, Any]:
        summary = {
            k: v for k, v in (self.result or {}).items() if k not in ("method", "wall_s", "error")
        }
        return summary | self._tail()


class LimitTask(_TaskBase):
    """The limits of one cell and method for each criterion (:class:`LimitSearch`); keeps
    every run's outcome (:attr:`outcomes`, by length) so other figures can read them."""

    def __init__(
        self,
        cell: Cell,
        method: str,
        search: LimitSearch | None = None,
        tests: Mapping[str, Criterion] | None = None,
        run: RunFunction = run_one,
    ):
        super().__init__(cell, method, run)
        self.tests = dict(tests or DEFAULT_TESTS)
        self.search = search or LimitSearch(names=tuple(self.tests))
        if tuple(self.tests) != self.search.names:
            raise ValueError("the search's criteria and the tests differ")
        self.outcomes: dict[float, Outcome] = {}

    def next_job(self) -> tuple[RunFunction, tuple[RunSpec]] | None:
        x = self.search.next_length()
        return None if x is None else (self.run, (self.cell.spec(self.method, x),))

    def record(self, job: tuple[Any, tuple[Any, ...]], result: Outcome) -> None:
        spec = job[1][0]
        self._count(spec, result)
        self.outcomes[length(spec.step_length)] = result
        if result.get("error"):
            self.search.record(spec.step_length, "error")
        else:
            self.search.record(spec.step_length, {c: t(result) for c, t in self.tests.items()})

    def jobs_left_estimate(self) -> int:
        return self.search.runs_left_estimate()

    def row(self) -> dict[str, Any]:
        return self.search.result() | self._tail()


class SameRuns(_TaskBase):
    """A (cell, method) whose runs are another task's (the same specs): no run of its own;
    its row is that task's limits or summary, with ``runs`` 0 (counted once, there)."""

    def __init__(self, cell: Cell, method: str, same: Any):
        super().__init__(cell, method)
        self.same = same

    def next_job(self) -> None:
        return None

    def record(self, job: tuple[Any, tuple[Any, ...]], result: Outcome) -> None:
        raise RuntimeError("a task sharing another's runs makes none")

    def jobs_left_estimate(self) -> int:
        return 0

    def row(self) -> dict[str, Any]:
        return self.same.row() | {"runs": 0, "wall_s": 0.0}


Task = SummaryTask | LimitTask | SameRuns


def make_tasks(
    cells: list[Cell], methods: tuple[str, ...], measure: str, run: RunFunction = run_one
) -> list[Task]:
    """One task per (cell, method), cells in grid order, methods in the given order. A cell
    whose run of a method is an earlier cell's (they differ only in another strategy's own
    parameter, ``gain.k`` for the MPC) shares that cell's runs (:class:`SameRuns`)."""
    if measure not in ("limit", "summary"):
        raise ValueError(f"unknown measure {measure!r}")
    make = LimitTask if measure == "limit" else SummaryTask
    out: list[Task] = []
    first: dict[tuple[str, RunSpec], Any] = {}
    for cell in cells:
        for m in methods:
            key = (m, cell.spec(m))
            if key in first:
                out.append(SameRuns(cell, m, first[key]))
            else:
                first[key] = task = make(cell, m, run=run)
                out.append(task)
    return out


def check_runs(grid: Grid) -> None:
    """Every cell's parameters are valid together for every method at every length it may
    run (e.g. a horizon shorter than the MPC sample); GridError naming the cell otherwise."""
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
