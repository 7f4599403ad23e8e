"""Sections 1 and 2: the kinematic limits of eq. (1)-(5) and the longest step each method
walks (the sweep of step lengths, and the paper's lengths at the same share of each limit).

- *clean* run: ``summary.clean`` (completed, no QP failure, no servo saturation, no
  speed-limited IK tick, every step within 2 cm of its planned foothold, kappa(legs) bounded);
- *walks*: no fall, the plan completed, every landing within 2 cm (``pelvic_walk.core.measure``);
- *longest clean step*: the longest length below the method's shortest failing length.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from app.experiments import paper
from app.experiments.definitions import Study, sweep_bracket
from app.experiments.outcomes import Results, RunSummary, failure_reasons, summary_of
from app.experiments.paper import KinematicLimits
from pelvic_walk.core.measure import walks
from pelvic_walk.core.run_spec import length


@dataclass(frozen=True)
class KinematicsSection:
    """Section 1: eq. (1)-(5) (``controller.analysis.kinematic_analysis``'s keys)."""

    paper_reported: KinematicLimits
    paper_inputs: dict[str, float]
    paper_inputs_literal: dict[str, float]
    ours: dict[str, float]
    ours_literal: dict[str, float]


@dataclass(frozen=True)
class SweepPoint:
    """Section 2: one run of the sweep (None where the run crashed)."""

    step_length: float
    clean: bool
    fell: bool | None
    fall_reason: str | None
    steps_completed: int | None
    steps_planned: int | None
    landing_error_max: float | None
    speed_limited_ticks: int | None
    servo_saturation_substeps: int | None
    solver_failures: int | None
    condition_number_max: float | None  # kappa(J_low)
    waist_yaw_max_deg: float | None
    reasons: list[str]
    condition_number_legs_max: float | None = None  # kappa(legs)


@dataclass(frozen=True)
class MaxStep:
    """Section 2: one method's longest clean step."""

    paper: float
    longest_clean: float | None
    first_failed: float | None
    resolution: float | None  # the sweep's resolution where the bracket was refined to it
    clean_again_above_first_failure: list[float]
    binding_at_first_failure: SweepPoint | None
    points: list[SweepPoint]
    # the longest step that *walks* (no fall, every landing within 2 cm) and the first that
    # does not, from the same runs
    walks_limit: float | None = None
    walks_first_failed: float | None = None


@dataclass(frozen=True)
class ShareOfLimit:
    share_of_limit: float
    ours: float | None  # [m]


@dataclass(frozen=True)
class EquivalentRow:
    paper_length: float
    methods: dict[str, ShareOfLimit]


@dataclass(frozen=True)
class EquivalentLengths:
    """The paper's lengths as a share of each method's paper limit, and ours at that share."""

    paper_limits: dict[str, float]
    our_limits: dict[str, float | None]
    rows: list[EquivalentRow]


def kinematics() -> KinematicsSection:
    """Eq. (1)-(5) with the paper's numbers and with our model's (same theta)."""
    from controller.analysis import kinematic_analysis
    from models.dyros_jet import HIP_HEIGHT_Z0, HIP_OFFSET, LEG_LENGTH, W_STEP

    theirs = vars(paper.ROBOT)
    ours: dict[str, Any] = dict(
        l_leg=LEG_LENGTH,
        z0=HIP_HEIGHT_Z0,
        l_pel=2 * HIP_OFFSET[1],
        w_step=W_STEP,
        theta_pel_deg=paper.ROBOT.theta_pel_deg,
    )
    return KinematicsSection(
        paper_reported=paper.KINEMATICS,
        paper_inputs=kinematic_analysis(**theirs),
        paper_inputs_literal=kinematic_analysis(**theirs, rule="literal"),
        ours=kinematic_analysis(**ours),
        ours_literal=kinematic_analysis(**ours, rule="literal"),
    )


def _point(x: float, s: RunSummary | None) -> SweepPoint:
    return SweepPoint(
        step_length=x,
        clean=bool(s and s.clean),
        fell=s.fell if s else None,
        fall_reason=s.fall_reason if s else None,
        steps_completed=s.steps_completed if s else None,
        steps_planned=s.steps_planned if s else None,
        landing_error_max=s.landing_error_max if s else None,
        speed_limited_ticks=s.speed_limited_ticks if s else None,
        servo_saturation_substeps=s.servo_saturation_substeps if s else None,
        solver_failures=s.solver_failures if s else None,
        condition_number_max=s.condition_number_max if s else None,
        waist_yaw_max_deg=s.waist_yaw_max_deg if s else None,
        reasons=failure_reasons(s),
        condition_number_legs_max=s.condition_number_legs_max if s else None,
    )


def figure_lengths_run(study: Study, results: Results, method: str) -> list[float]:
    """Every length of ``method``'s figure runs (sweep, refinement, figures), sorted."""
    return sorted({s.step_length for s in results if s.method == method and study.is_figure_run(s)})


def max_step(study: Study, results: Results) -> dict[str, MaxStep]:
    """Longest clean step per method from every unseeded arms-on run of ``n_steps`` steps."""
    out = {}
    for m in study.methods:
        points = [
            _point(x, summary_of(results, study.figure_run(m, x)))
            for x in figure_lengths_run(study, results, m)
        ]
        longest, first_failed = sweep_bracket({p.step_length: p.clean for p in points})
        sums = {
            x: summary_of(results, study.figure_run(m, x))
            for x in figure_lengths_run(study, results, m)
        }
        walks_limit, walks_failed = sweep_bracket(
            {x: bool(s and walks(s.as_dict())) for x, s in sums.items()}
        )
        out[m] = MaxStep(
            paper=paper.MAX_STEP[m],
            longest_clean=longest,
            first_failed=first_failed,
            resolution=(
                study.sweep_resolution
                if longest is not None
                and first_failed is not None
                and first_failed - longest <= study.sweep_resolution + 1e-9
                else None
            ),
            clean_again_above_first_failure=[
                p.step_length
                for p in points
                if p.clean and first_failed is not None and p.step_length > first_failed
            ],
            binding_at_first_failure=next(
                (p for p in points if p.step_length == first_failed), None
            ),
            points=points,
            walks_limit=walks_limit,
            walks_first_failed=walks_failed,
        )
    return out


def equivalent_lengths(study: Study, ms: dict[str, MaxStep]) -> EquivalentLengths:
    """The paper's lengths as a share of each method's paper limit, and ours at that share."""
    rows = []
    for x in paper.TABLE1_LENGTHS:
        methods = {}
        for m in study.methods:
            share = x / paper.MAX_STEP[m]
            ours = ms[m].longest_clean
            methods[m] = ShareOfLimit(share, length(share * ours) if ours is not None else None)
        rows.append(EquivalentRow(x, methods))
    return EquivalentLengths(
        paper_limits=dict(paper.MAX_STEP),
        our_limits={m: ms[m].longest_clean for m in study.methods},
        rows=rows,
    )
