"""What one cell of a sweep measures, for one method: a *task* that asks for runs one by one.

A run is :func:`run_one` (a :class:`~app.experiments.definitions.RunSpec` in, a flat dict of
plain values out, so it crosses process and Ray boundaries cheaply). A task asks for its next
run with :meth:`Task.next_spec`, is told each outcome with :meth:`Task.record`, and gives its
table row with :meth:`Task.row`. Runs are deterministic given their parameters, so a task's
row does not depend on which backend ran it or in which order the cells finished.

``summary`` (:class:`SummaryTask`): one walk of ``walk.n_steps`` steps at the cell's
parameters (step length from the grid, else the default); the row has the keys of
``simulate --json`` (``app.sim.summary.SUMMARY_KEYS``), ``clean``, the derived ``walks``
and the summary's other scalar extras.

``limit`` (:class:`LimitTask`, logic in :class:`LimitSearch`): the longest step length that
*walks* (no fall, the plan completed, every landing within ``LANDING_ERROR_CLEAN`` = 2 cm) and
the longest that is *clean* (the summary's ``clean`` flag: walks, and no QP failure, no servo
saturation, no IK tick at the joint-speed limit, kappa(J) below the singular bound).

The search: step lengths on a grid from :data:`SEARCH_MIN` = 0.10 m to :data:`SEARCH_MAX` =
0.60 m at :data:`RESOLUTION` = 0.01 m (51 lengths). First a bisection for *walks* (6 runs: the
first at 0.35 m); then a bisection for *clean* inside the bracket the runs so far leave (a
clean run walks, so the walks runs already narrow it: 0-5 more runs). At most 11 runs per
cell and method when the outcomes are monotonic in length (6-11, mean 8.3, on the DSP-share
sweep of fixed and mpc), sequential (each length depends on the last outcome). A limit is
*the longest length below the shortest failure found*: ``walks_limit`` walked and
``walks_first_fail`` = ``walks_limit`` + 0.01 m did not (None: nothing failed up to 0.60 m, the
limit is at least the range's top; ``walks_limit`` None: even 0.10 m failed). Bisection never
tests above a known failure, so its runs are consistent by construction; when a later run
(the clean phase) finds a failure below a length that walked, the bracket moves below that
failure and the search resumes there, and the lengths that passed above the shortest failure
are listed in ``walks_above`` / ``clean_above`` (failures that are not monotonic in length
show up there rather than being hidden). ``trace`` lists every run in order.
"""

from __future__ import annotations

import math
import time
from typing import Any, Protocol

from app.experiments.definitions import RunSpec, length
from app.sim.metrics import LANDING_ERROR_CLEAN
from app.sim.summary import SUMMARY_KEYS
from app.sweep.grid import Cell

SEARCH_MIN = 0.10  # [m] shortest step length the limit search tries
SEARCH_MAX = 0.60  # [m] longest (the step_length parameter's maximum)
RESOLUTION = 0.01  # [m]
OUTCOMES = ("clean", "walks", "fails", "error")  # of one run, best first
LIMIT_COLUMNS = (
    "walks_limit",
    "walks_first_fail",
    "clean_limit",
    "clean_first_fail",
    "walks_above",
    "clean_above",
    "trace",
)
TASK_COLUMNS = ("runs", "wall_s", "error")  # every row ends with these

Outcome = dict[str, Any]  # what run_one returns


def walks(summary: dict[str, Any]) -> bool:
    """No fall, the plan completed, every landing within ``LANDING_ERROR_CLEAN``."""
    le = summary.get("landing_error_max")
    return bool(summary.get("success")) and le is not None and le < LANDING_ERROR_CLEAN


def _plain(value: Any) -> Any:
    """A JSON-safe scalar (non-finite floats -> None)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def run_one(spec: RunSpec) -> Outcome:
    """One closed-loop headless run (``app.runs.run``) -> its summary as plain values.

    The keys of ``simulate --json``, then ``clean``, ``walks``, the summary's other scalar
    keys, and ``wall_s`` (this run's wall time). A run that raises returns ``{"error": ...}``
    (a crash is an outcome of the parameters, never hides the other cells).
    """
    from app.runs import RunConfig, run

    start = time.perf_counter()
    try:
        summary = run(RunConfig(params=spec.params())).summary()
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


def _passes(criterion: str, outcome: str) -> bool:
    return outcome == "clean" or (criterion == "walks" and outcome == "walks")


class LimitSearch:
    """Bisection for the longest step length that walks, then the longest that is clean.

    Pure logic, no runs: :meth:`next_length` says which length to run next (None when done),
    :meth:`record` takes its outcome (one of :data:`OUTCOMES`).
    """

    CRITERIA = ("walks", "clean")

    def __init__(
        self, lo: float = SEARCH_MIN, hi: float = SEARCH_MAX, resolution: float = RESOLUTION
    ):
        if not 0 < lo < hi or resolution <= 0:
            raise ValueError(f"bad search range {lo}..{hi} at {resolution}")
        n = int(round((hi - lo) / resolution)) + 1
        self.lengths = [length(lo + i * resolution) for i in range(n)]
        self.outcomes: dict[int, str] = {}  # index into lengths -> outcome
        self.order: list[int] = []  # the runs in the order they were made

    def bracket(self, criterion: str) -> tuple[int, int]:
        """(longest passing index below the shortest failure, shortest failure); -1 / n
        where there is none."""
        n = len(self.lengths)
        failed = [i for i, o in self.outcomes.items() if not _passes(criterion, o)]
        hi = min(failed, default=n)
        passed = [i for i, o in self.outcomes.items() if _passes(criterion, o) and i < hi]
        return max(passed, default=-1), hi

    def next_length(self) -> float | None:
        for criterion in self.CRITERIA:
            lo, hi = self.bracket(criterion)
            if hi - lo > 1:
                return self.lengths[(lo + hi) // 2]
        return None

    def record(self, step_length: float, outcome: str) -> None:
        if outcome not in OUTCOMES:
            raise ValueError(f"unknown outcome {outcome!r}")
        i = self.lengths.index(length(step_length))
        self.outcomes[i] = outcome
        self.order.append(i)

    def runs_left_estimate(self) -> int:
        """Runs still to make if the outcomes stay monotonic (for a progress bar)."""
        total = 0
        for criterion in self.CRITERIA:
            lo, hi = self.bracket(criterion)
            total += math.ceil(math.log2(hi - lo)) if hi - lo > 1 else 0
        return total

    def result(self) -> dict[str, Any]:
        """The limit columns of the row (:data:`LIMIT_COLUMNS`)."""
        out: dict[str, Any] = {}
        n = len(self.lengths)
        for criterion in self.CRITERIA:
            lo, hi = self.bracket(criterion)
            out[f"{criterion}_limit"] = self.lengths[lo] if lo >= 0 else None
            out[f"{criterion}_first_fail"] = self.lengths[hi] if hi < n else None
        for criterion in self.CRITERIA:
            _, hi = self.bracket(criterion)
            out[f"{criterion}_above"] = sorted(
                self.lengths[i]
                for i, o in self.outcomes.items()
                if i > hi and _passes(criterion, o)
            )
        out["trace"] = " ".join(f"{self.lengths[i]:.2f}={self.outcomes[i]}" for i in self.order)
        return out


class Task(Protocol):
    """One (cell, method) of a sweep: asks for runs one at a time, then gives its row."""

    cell: Cell
    method: str

    def next_spec(self) -> RunSpec | None: ...

    def record(self, spec: RunSpec, result: Outcome) -> None: ...

    def runs_left_estimate(self) -> int: ...

    def row(self) -> dict[str, Any]: ...


class _TaskBase:
    def __init__(self, cell: Cell, method: str):
        self.cell = cell
        self.method = method
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


class SummaryTask(_TaskBase):
    """One run at the cell's parameters; the row is its summary."""

    def __init__(self, cell: Cell, method: str):
        super().__init__(cell, method)
        self.spec = cell.spec(method)
        self.result: Outcome | None = None

    def next_spec(self) -> RunSpec | None:
        return self.spec if self.runs == 0 else None

    def record(self, spec: RunSpec, result: Outcome) -> None:
        self._count(spec, result)
        self.result = result

    def runs_left_estimate(self) -> int:
        return 0 if self.runs else 1

    def row(self) -> dict[str, Any]:
        summary = {
            k: v for k, v in (self.result or {}).items() if k not in ("method", "wall_s", "error")
        }
        return summary | self._tail()


class LimitTask(_TaskBase):
    """The walks and clean limits of one cell and method (:class:`LimitSearch`)."""

    def __init__(self, cell: Cell, method: str, search: LimitSearch | None = None):
        super().__init__(cell, method)
        self.search = search or LimitSearch()

    def next_spec(self) -> RunSpec | None:
        x = self.search.next_length()
        return None if x is None else self.cell.spec(self.method, x)

    def record(self, spec: RunSpec, result: Outcome) -> None:
        self._count(spec, result)
        self.search.record(spec.step_length, outcome_of(result))

    def runs_left_estimate(self) -> int:
        return self.search.runs_left_estimate()

    def row(self) -> dict[str, Any]:
        return self.search.result() | self._tail()


def make_tasks(cells: list[Cell], methods: tuple[str, ...], measure: str) -> list[Task]:
    """One task per (cell, method), cells in grid order, methods in the given order."""
    kind = {"limit": LimitTask, "summary": SummaryTask}[measure]
    return [kind(cell, m) for cell in cells for m in methods]
