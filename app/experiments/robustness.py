"""The robustness section: how often each method falls or misses its foothold under random
pushes, the largest sideways push it survives, and what the gains of the sensitivity section
cost in push margin.

- *Repeats*: Table 1's seeded runs (each pushed through the whole run by a horizontal force
  on the torso, N(0, 5 N) per axis renewed every 0.1 s; ``pelvic_walk.core.run_spec``). Per method
  and
  length: the runs that fell, the runs that did not fall but landed a foot more than 2 cm off
  its planned foothold (``LANDING_ERROR_CLEAN``), the worst landing, and the seeds of each
  (``pelvic-walk simulate --seed N`` reruns repeat N).
- *Falls*: the runs that fell at the study's push size (the repeats, every length) and under
  larger pushes (:class:`~app.experiments.definitions.Falls`: the same seeded walks with each
  axis N(0, 15 N)). Two methods' counts differ when Fisher's exact test says so
  (:func:`falls_p`, p < :data:`~app.experiments.energy.SIGNIFICANCE`).
- *Push survival*: ``pelvic_walk.core.pushes.largest_survived``, the same bisection as ``pelvic-walk
  push-study``: a push on the torso for 0.1 s at the middle of the third step's single
  support, to the left and to the right; the largest force after which the robot still
  completes its plan, bracketed to 2 N. Two methods differ when their brackets do not overlap.
  Run by the study (:func:`push_job`), so it is measured on the same code as every other
  section.
- *Trade*: the same push survival at one length in the sensitivity cells whose gain the
  report states (:func:`trade_cells`), beside the cell's k_pel, the MPC's waist amplitude and
  its gain in the longest clean step (:class:`TradeRow`).

:func:`stability` compares two methods on all of these (the paper's conclusion that the
MPC's rotation is "more stable" than redundancy's is judged on it).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from app.experiments.definitions import Falls, Pushes, Study
from app.experiments.energy import SIGNIFICANCE
from app.experiments.outcomes import Results, case_key, summary_of
from app.experiments.sensitivity import SensitivitySection, reads
from controller.strategy import FIXED, MPC
from pelvic_walk.core.metrics import LANDING_ERROR_CLEAN
from pelvic_walk.core.run_spec import DISTURBANCE, Override


@dataclass(frozen=True)
class RepeatsCell:
    """One method and length over the seeded repeats."""

    method: str
    step_length: float  # [m]
    runs: int
    fell: int
    off_foothold: int  # runs that did not fall with a landing beyond LANDING_ERROR_CLEAN
    landings: int  # landings made, all runs
    landings_off: int  # of those, beyond LANDING_ERROR_CLEAN
    worst_landing_cm: float | None
    seeds_fell: list[int] = field(default_factory=list)
    seeds_off: list[int] = field(default_factory=list)

    @property
    def walked(self) -> int:
        """Runs with no fall and every landing within LANDING_ERROR_CLEAN."""
        return self.runs - self.fell - self.off_foothold


@dataclass(frozen=True)
class FallsCell:
    """One method's seeded walks at one push size: how many fell."""

    method: str
    force: float  # [N] std of each axis of the pushes
    lengths: list[float]  # [m]
    runs: int
    fell: int
    seeds_fell: list[int] = field(default_factory=list)


@dataclass(frozen=True)
class PushCell:
    """The largest push one method survives at one length and direction
    (``pelvic_walk.core.pushes.Survival``)."""

    method: str
    step_length: float  # [m]
    direction: str
    duration: float  # [s]
    survived: float | None  # [N] largest force survived (None: falls unpushed)
    failed: float | None  # [N] smallest force that made it fall (None: survived the highest)
    fall_reason: str | None
    runs: int
    support: str | None = None  # the foot it stood on when pushed
    overrides: list[list[Any]] = field(default_factory=list)  # parameters off their defaults
    step: int = 2  # the pushed step (0-based)
    phase: float = 0.5  # when in its single support (0: lift-off, 1: touch-down)


@dataclass(frozen=True)
class TradeRow:
    """A sensitivity cell whose gain the report states, and what the gain costs."""

    name: str
    overrides: list[list[Any]]
    k_pel: float
    gain: float | None  # [m] MPC - fixed, longest clean step (the sensitivity section)
    waist_deg: float | None  # the MPC's peak |waist angle| at ``waist_length``
    pushes: dict[str, dict[str, PushCell | None]]  # direction -> method -> push survival
    waist_length: float = 0.0  # [m] the sensitivity's first length
    push_length: float = 0.0  # [m] where the pushes are measured

    def margin(self, direction: str) -> float | None:
        """[N] the MPC's largest push survived minus the fixed pelvis's (None: missing)."""
        m, f = (self.pushes.get(direction, {}).get(k) for k in (MPC, FIXED))
        if m is None or f is None or m.survived is None or f.survived is None:
            return None
        return m.survived - f.survived


@dataclass(frozen=True)
class Comparison:
    """One measure of stability, method ``a`` against ``b``: ``order`` -1 when ``a`` is the
    more stable (the measure separates them), +1 when ``b`` is, 0 a tie."""

    what: str  # in words
    a: str  # a's value in words
    b: str
    order: int


@dataclass(frozen=True)
class RobustnessSection:
    repeats: int
    steps: int
    lengths: list[float]
    cells: dict[str, RepeatsCell | None]  # "<method>@<length>"
    pushes: dict[str, PushCell | None] = field(default_factory=dict)  # push_key
    push_setup: Pushes | None = None
    falls: dict[str, dict[str, FallsCell]] = field(default_factory=dict)  # force_key -> method
    falls_setup: Falls | None = None
    trade: list[TradeRow] = field(default_factory=list)
    # more push conditions for the stability claim: grid_key -> survival (Pushes.grid)
    grid_pushes: dict[str, PushCell | None] = field(default_factory=dict)

    def push(self, method: str, x: float, direction: str) -> PushCell | None:
        return self.pushes.get(push_key(method, x, direction))

    def grid_push(
        self, method: str, x: float, direction: str, step: int, phase: float
    ) -> PushCell | None:
        return self.grid_pushes.get(grid_key(method, x, direction, step, phase))

    @property
    def push_lengths(self) -> list[float]:
        return sorted({p.step_length for p in self.pushes.values() if p})

    @property
    def directions(self) -> list[str]:
        return list(self.push_setup.directions) if self.push_setup else []


def push_key(method: str, x: float, direction: str) -> str:
    return f"{case_key(method, x)}@{direction}"


def grid_key(method: str, x: float, direction: str, step: int, phase: float) -> str:
    return f"{push_key(method, x, direction)}@step{step}@{phase:g}"


def force_key(force: float) -> str:
    return f"{force:g} N"


def repeats(study: Study, results: Results) -> dict[str, RepeatsCell | None]:
    """Falls and missed footholds of Table 1's seeded repeats, per method and length."""
    cells: dict[str, RepeatsCell | None] = {}
    for x in study.energy_lengths:
        for m in study.methods:
            specs = study.energy_runs(m, x)
            sums = [(spec.seed, summary_of(results, spec)) for spec in specs]
            done = [(seed, s) for seed, s in sums if s is not None]
            if not done:
                cells[case_key(m, x)] = None
                continue
            landed = [le for _, s in done for le in s.landing_errors]
            fell = [seed for seed, s in done if s.fell]
            off = [
                seed
                for seed, s in done
                if not s.fell
                and s.landing_error_max is not None
                and s.landing_error_max >= LANDING_ERROR_CLEAN
            ]
            cells[case_key(m, x)] = RepeatsCell(
                method=m,
                step_length=x,
                runs=len(done),
                fell=len(fell),
                off_foothold=len(off),
                landings=len(landed),
                landings_off=int(np.sum(np.asarray(landed) >= LANDING_ERROR_CLEAN)),
                worst_landing_cm=100.0 * max(landed) if landed else None,
                seeds_fell=[int(s) for s in fell if s is not None],
                seeds_off=[int(s) for s in off if s is not None],
            )
    return cells


def falls(
    study: Study, results: Results, cells: dict[str, RepeatsCell | None]
) -> dict[str, dict[str, FallsCell]]:
    """Runs that fell at the study's push size (the repeats, every length) and at the larger
    size of :attr:`Study.falls`, per method."""
    out: dict[str, dict[str, FallsCell]] = {}
    small: dict[str, FallsCell] = {}
    for m in study.methods:
        mine = [c for c in (cells.get(case_key(m, x)) for x in study.energy_lengths) if c]
        if mine:
            small[m] = FallsCell(
                m,
                DISTURBANCE,
                [c.step_length for c in mine],
                sum(c.runs for c in mine),
                sum(c.fell for c in mine),
                [s for c in mine for s in c.seeds_fell],
            )
    if small:
        out[force_key(DISTURBANCE)] = small
    f = study.falls
    if f is not None:
        large: dict[str, FallsCell] = {}
        for m in study.methods:
            done = [(s.seed, r) for s in study.falls_runs(m) if (r := summary_of(results, s))]
            if done:
                fell = [int(seed) for seed, r in done if r.fell and seed is not None]
                large[m] = FallsCell(m, f.force, [f.step_length], len(done), len(fell), fell)
        if large:
            out[force_key(f.force)] = large
    return out


def falls_p(a: FallsCell, b: FallsCell) -> float:
    """Two-sided p-value of Fisher's exact test that ``a`` and ``b`` fall as often."""
    from scipy import stats

    table = [[a.fell, a.runs - a.fell], [b.fell, b.runs - b.fell]]
    return float(stats.fisher_exact(table).pvalue)


def _push_words(p: PushCell | None) -> str:
    if p is None:
        return "-"
    if p.survived is None:
        return "falls unpushed"
    if p.failed is None:
        return f">= {p.survived:.0f} N"
    return f"{p.survived:.0f}-{p.failed:.0f} N"


def push_order(a: PushCell | None, b: PushCell | None) -> int | None:
    """-1 when ``a`` survives a push ``b`` topples at with a gap between the brackets (the
    difference is more than the bisection's resolution: adjacent brackets, e.g. 92-94 against
    94-96 N, are within it and tie), +1 the reverse, 0 a tie; None when either is missing."""
    if a is None or b is None:
        return None

    def bracket(p: PushCell) -> tuple[float, float]:
        lo = -math.inf if p.survived is None else p.survived
        hi = math.inf if p.failed is None else p.failed
        return lo, hi

    (a_lo, a_hi), (b_lo, b_hi) = bracket(a), bracket(b)
    if a_lo > b_hi:
        return -1
    if b_lo > a_hi:
        return 1
    return 0


def sign_p(wins: int, losses: int) -> float:
    """Two-sided sign test that ``wins`` and ``losses`` (ties left out) are equally likely."""
    from scipy import stats

    n = wins + losses
    return 1.0 if n == 0 else float(stats.binomtest(wins, n, 0.5).pvalue)


def stability(rob: RobustnessSection, a: str, b: str) -> list[Comparison]:
    """Method ``a`` against ``b`` on every measure of the section: the largest push survived
    at each length and direction, and the falls at each push size."""
    out = []
    for x in rob.push_lengths:
        for d in rob.directions:
            pa, pb = rob.push(a, x, d), rob.push(b, x, d)
            order = push_order(pa, pb)
            if order is not None:
                out.append(
                    Comparison(f"push {d} at {x:.2f} m", _push_words(pa), _push_words(pb), order)
                )
    setup = rob.push_setup
    for k, ph in setup.grid if setup else ():
        for d in rob.directions:
            assert setup is not None
            x = setup.grid_length
            pa, pb = rob.grid_push(a, x, d, k, ph), rob.grid_push(b, x, d, k, ph)
            order = push_order(pa, pb)
            if order is not None:
                on = pa.support if pa and pa.support else "?"
                out.append(
                    Comparison(
                        f"push {d} at {x:.2f} m, step {k + 1} (on the {on} foot), "
                        f"{ph:.0%} into its single support",
                        _push_words(pa),
                        _push_words(pb),
                        order,
                    )
                )
    for size, cells in rob.falls.items():
        ca, cb = cells.get(a), cells.get(b)
        if ca is None or cb is None:
            continue
        p = falls_p(ca, cb)
        order = 0 if p >= SIGNIFICANCE else (-1 if ca.fell / ca.runs < cb.fell / cb.runs else 1)
        where = (
            f"{ca.lengths[0]:.2f} m"
            if len(ca.lengths) == 1
            else f"{min(ca.lengths):.2f}-{max(ca.lengths):.2f} m"
        )
        p_text = "p < 0.001" if p < 0.001 else f"p = {p:.2g}"
        out.append(
            Comparison(
                f"falls at {size} ({where}; {p_text})",
                f"{ca.fell}/{ca.runs}",
                f"{cb.fell}/{cb.runs}",
                order,
            )
        )
    return out


def push_job(
    method: str,
    step_length: float,
    direction: str,
    duration: float,
    resolution: float,
    f_high: float,
    overrides: tuple[Override, ...] = (),
    strategy_file: str | None = None,
    step: int | None = None,
    phase: float = 0.5,
) -> dict[str, Any]:
    """One method's push survival at one length and direction (a job of the run engine: plain
    data in and out), with ``overrides`` of any other parameter; ``strategy_file`` is a
    user's strategy this worker loads first."""
    from controller import strategy
    from pelvic_walk.core.pushes import largest_survived
    from pelvic_walk.core.run_spec import RunSpec

    if strategy_file is not None:
        strategy.load_file(strategy_file)

    from pelvic_walk.core.pushes import N_STEPS, PUSH_STEP

    params = RunSpec(method, step_length, 1, overrides=overrides).params() if overrides else None
    k = PUSH_STEP if step is None else step
    s = largest_survived(
        method,
        step_length,
        direction=direction,
        duration=duration,
        f_high=f_high,
        resolution=resolution,
        params=params,
        step=k,
        n_steps=max(N_STEPS, k + 3),  # two steps after the pushed one
        phase=phase,
    )
    return dataclasses.asdict(s) | {
        "overrides": [list(o) for o in overrides],
        "step": k,
        "phase": phase,
    }


def push_cell(outcome: dict[str, Any] | None) -> PushCell | None:
    if outcome is None:
        return None
    names = {f.name for f in dataclasses.fields(PushCell)}
    return PushCell(**{k: v for k, v in outcome.items() if k in names})


def trade_cells(
    study: Study, s: SensitivitySection | None
) -> list[tuple[str, tuple[Override, ...]]]:
    """The sensitivity cells whose gain the report states besides the defaults' (whose push
    margin is the section's own): the cell of the largest gain, every cell reaching the
    paper's gain, and the authors' DSP and step width; each as (name, overrides)."""
    from app.experiments import paper
    from app.experiments.definitions import AUTHORS

    if s is None or study.pushes is None:
        return []
    gain = paper.MAX_STEP[MPC] - paper.MAX_STEP[FIXED]
    cells = dict(s.all_cells())
    names = []
    best = s.best_gain()
    if best:
        names.append(best[1])
    names += s.cells_with_gain(gain)
    names += [n for n, ov in cells.items() if sorted(map(tuple, ov)) == sorted(AUTHORS)]
    out, seen = [], set()
    for n in names:
        ov = tuple((str(k), v) for k, v in cells[n])
        if n not in seen and ov:
            seen.add(n)
            out.append((n, ov))
    return out


def trade_jobs(
    study: Study, cells: list[tuple[str, tuple[Override, ...]]]
) -> dict[tuple[str, tuple[Override, ...], str], tuple]:
    """The push bisections of the trade cells: (method, overrides it reads, direction) -> the
    arguments of :func:`push_job`, one per distinct run (the fixed pelvis reads no ``pelvis``
    parameter, so cells that differ only there share its bisection; a run at the defaults
    is the section's own push when it measures ``trade_length``)."""
    p = study.pushes
    if p is None:
        return {}
    own = any(abs(x - p.trade_length) < 1e-9 for x in p.lengths)
    out = {}
    for _, ov in [("the defaults", ()), *cells]:
        for m in (FIXED, MPC):
            eff = reads(m, ov)
            for d in p.directions:
                key = (m, eff, d)
                if key not in out and not (own and not eff):
                    out[key] = (m, p.trade_length, d, p.duration, p.resolution, p.f_high, eff)
    return out


def trade(
    study: Study,
    s: SensitivitySection | None,
    rob_pushes: dict[str, PushCell | None],
    cell_pushes: dict[tuple[str, tuple[Override, ...], str], PushCell | None],
) -> list[TradeRow]:
    """The trade of each gain the report states: the defaults' cell and :func:`trade_cells`."""
    from controller.params import ControllerParams

    p = study.pushes
    if s is None or p is None:
        return []
    k_default = ControllerParams().pelvis.k_pel
    rows = []
    for name, ov in [("the defaults", ()), *trade_cells(study, s)]:
        pushes: dict[str, dict[str, PushCell | None]] = {}
        for d in p.directions:
            pushes[d] = {}
            for m in (FIXED, MPC):
                key = (m, reads(m, ov), d)
                own = rob_pushes.get(push_key(m, p.trade_length, d)) if not key[1] else None
                pushes[d][m] = own or cell_pushes.get(key)
        mpc_row = s.row(MPC, [list(o) for o in ov])
        rows.append(
            TradeRow(
                name=name,
                overrides=[list(o) for o in ov],
                k_pel=float(dict(ov).get("pelvis.k_pel", k_default)),
                gain=s.gain([list(o) for o in ov]),
                waist_deg=mpc_row.waist_at_first_deg if mpc_row else None,
                pushes=pushes,
                waist_length=s.first,
                push_length=p.trade_length,
            )
        )
    return rows


def robustness(
    study: Study,
    results: Results,
    pushes: dict[str, PushCell | None] | None = None,
    sens: SensitivitySection | None = None,
    cell_pushes: dict[tuple[str, tuple[Override, ...], str], PushCell | None] | None = None,
    grid_pushes: dict[str, PushCell | None] | None = None,
) -> RobustnessSection:
    cells = repeats(study, results)
    # the paper's methods' (section 10's other strategies keep theirs in their rows)
    pushes = {k: v for k, v in (pushes or {}).items() if k.split("@")[0] in study.methods}
    return RobustnessSection(
        repeats=study.energy_repeats,
        steps=study.energy_steps,
        lengths=list(study.energy_lengths),
        cells=cells,
        pushes=pushes,
        push_setup=study.pushes,
        falls=falls(study, results, cells),
        falls_setup=study.falls,
        trade=trade(study, sens, pushes, cell_pushes or {}),
        grid_pushes=dict(grid_pushes or {}),
    )
