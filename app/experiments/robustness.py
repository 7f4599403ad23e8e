"""The robustness section: how often each method falls or misses its foothold under the
study's small disturbance, and the largest sideways push it survives.

- *Repeats*: Table 1's seeded runs (each pushed through the whole run by a horizontal force
  on the torso, N(0, 5 N) per axis renewed every 0.1 s; ``app.run_spec``). Per method and
  length: the runs that fell, the runs that did not fall but landed a foot more than 2 cm off
  its planned foothold (``LANDING_ERROR_CLEAN``), the worst landing, and the seeds of each
  (``pelvic-walk simulate --seed N`` reruns repeat N).
- *Push survival*: ``app.pushes.largest_survived``, the same bisection as ``pelvic-walk
  push-study``: a push on the torso for 0.1 s at the middle of the third step's single
  support; the largest force after which the robot still completes its plan. Run by the study
  (:func:`push_job`), so it is measured on the same code as every other section.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from app.experiments.definitions import Pushes, Study
from app.experiments.runs import Results, case_key, summary_of
from app.sim.metrics import LANDING_ERROR_CLEAN


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
class PushCell:
    """The largest push one method survives at one length (``app.pushes.Survival``)."""

    method: str
    step_length: float  # [m]
    direction: str
    duration: float  # [s]
    survived: float | None  # [N] largest force survived (None: falls unpushed)
    failed: float | None  # [N] smallest force that made it fall (None: survived the highest)
    fall_reason: str | None
    runs: int


@dataclass(frozen=True)
class RobustnessSection:
    repeats: int
    steps: int
    lengths: list[float]
    cells: dict[str, RepeatsCell | None]  # "<method>@<length>"
    pushes: dict[str, PushCell | None] = field(default_factory=dict)
    push_setup: Pushes | None = None


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


def push_job(
    method: str, step_length: float, direction: str, duration: float, resolution: float
) -> dict[str, Any]:
    """One method's push survival at one length (a job of the run engine: plain data in and
    out)."""
    from app.pushes import largest_survived

    s = largest_survived(
        method, step_length, direction=direction, duration=duration, resolution=resolution
    )
    return dataclasses.asdict(s)


def push_cell(outcome: dict[str, Any]) -> PushCell:
    names = {f.name for f in dataclasses.fields(PushCell)}
    return PushCell(**{k: v for k, v in outcome.items() if k in names})


def robustness(
    study: Study, results: Results, pushes: dict[str, PushCell | None] | None = None
) -> RobustnessSection:
    return RobustnessSection(
        repeats=study.energy_repeats,
        steps=study.energy_steps,
        lengths=list(study.energy_lengths),
        cells=repeats(study, results),
        pushes=pushes or {},
        push_setup=study.pushes,
    )
