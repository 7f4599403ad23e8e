"""From finished runs to :class:`~app.experiments.results.StudyResults`: every section's
numbers (each from its topic module), then the claims' verdicts (:mod:`claims`)."""

from __future__ import annotations

import dataclasses

from app.experiments import (
    ablation,
    balance,
    claims,
    energy,
    kappa,
    limits,
    reach,
    robustness,
    waist,
    yaw,
)
from app.experiments.definitions import Study
from app.experiments.outcomes import Results
from app.experiments.results import Meta, RunRecord, StudyResults
from app.experiments.robustness import PushCell
from app.experiments.sensitivity import SensitivitySection, lateral_limits
from pelvic_walk.core.run_spec import Override


def analyse(
    study: Study,
    results: Results,
    meta: Meta,
    sens: SensitivitySection | None = None,
    pushes: dict[str, PushCell | None] | None = None,
    cell_pushes: dict[tuple[str, tuple[Override, ...], str], PushCell | None] | None = None,
    reach_outcomes: dict[str, dict | None] | None = None,
    grid_pushes: dict[str, PushCell | None] | None = None,
) -> StudyResults:
    """Every section's numbers, the claims' verdicts, and every run's summary."""
    ms = limits.max_step(study, results)
    out = StudyResults(
        meta=meta,
        kinematics=limits.kinematics(),
        max_step=ms,
        equivalent_lengths=limits.equivalent_lengths(study, ms),
        waist=waist.waist(study, results),
        yaw_momentum=yaw.yaw_momentum(study, results),
        energy=energy.energy(study, results),
        kappa=kappa.kappa(study, results, ms),
        zmp=balance.zmp(study, results),
        lateral=waist.lateral(study, results, lateral_limits(sens)),
        balance=balance.balance(study, results),
        robustness=robustness.robustness(study, results, pushes, sens, cell_pushes, grid_pushes),
        sensitivity=sens,
        ablation=ablation.ablation(study, results, pushes),
        reach=reach.reach_section(reach_outcomes or {}),
        runs={
            s.key: RunRecord(
                s, r.wall_s, r.error, r.summary.as_dict() if r.summary else None, s.command()
            )
            for s, r in sorted(results.items(), key=lambda kv: kv[0].key)
        },
    )
    return dataclasses.replace(out, claims=claims.evaluate(study, out))
