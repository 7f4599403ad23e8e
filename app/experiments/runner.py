"""``pelvic-walk experiments``: run the study on the run engine and write the report.

The runs go to one backend of ``pelvic_walk.core.engine`` (the local process pool by default, or Ray
with ``--ray [ADDRESS]``), as jobs of plain data: :func:`worker.execute` on a
:class:`~pelvic_walk.core.run_spec.RunSpec` for the study's runs,
``pelvic_walk.core.measure.run_one`` for the
sensitivity section's limit searches, :func:`robustness.push_job` for the push survival.

Three phases, so the adaptive parts never wait at the end: first the push bisections and every
unseeded run known up front (:func:`definitions.planned_runs`: the coarse sweep, the figure
runs), longest first; then the sensitivity section's searches (each a chain of runs, served
first), the sweep's refinement between each method's last clean and first failed coarse length
(:func:`definitions.refinement_runs`), and Table 1's seeded repeats; then the push bisections
in the sensitivity cells whose gain the report states (:func:`robustness.trade_cells`, known
once the searches are done) beside the seeded walks under larger pushes. Then
:func:`analysis.analyse`, the figures, ``results.json`` and ``report.md``.
"""

from __future__ import annotations

import dataclasses
import os
import platform
import sys
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from app.experiments import limits, sensitivity
from app.experiments.analysis import analyse
from app.experiments.definitions import FULL, QUICK, Requests, Study, planned_runs, refinement_runs
from app.experiments.outcomes import Results, case_key
from app.experiments.reach import reach_cases, reach_job
from app.experiments.results import Meta, StudyResults, to_json
from app.experiments.robustness import (
    PushCell,
    grid_key,
    push_cell,
    push_job,
    push_key,
    trade_cells,
    trade_jobs,
)
from app.experiments.worker import execute
from controller import strategy
from pelvic_walk.core.engine import Backend, OneJob, Task, make_backend, run_tasks
from pelvic_walk.core.run_spec import Override, RunSpec

PROG = "pelvic-walk experiments"


def _run_jobs(requests: Requests, study: Study) -> list[tuple[RunSpec, OneJob]]:
    """One task per run, longest first."""
    specs = sorted(requests, key=lambda s: (-s.n_steps, -s.step_length, s.key))
    return [
        (s, OneJob(execute, s, tuple(sorted(requests[s])), study.mid_step, label=s.key))
        for s in specs
    ]


def _grid_push_jobs(study: Study) -> list[tuple[str, OneJob]]:
    """The stability claim's pushes at more phases of the step and on both feet
    (:attr:`Pushes.grid`), for the paper's methods."""
    p = study.pushes
    if p is None:
        return []
    return [
        (
            grid_key(m, p.grid_length, d, k, ph),
            OneJob(
                push_job,
                m,
                p.grid_length,
                d,
                p.duration,
                p.resolution,
                p.f_high,
                (),
                None,
                k,
                ph,
                label=f"push {m} {p.grid_length} {d} step {k} at {ph:g}",
            ),
        )
        for m in study.methods
        for k, ph in p.grid
        for d in p.directions
    ]


def _push_jobs(study: Study) -> list[tuple[str, OneJob]]:
    """The robustness section's push bisections, and section 10's at its push length."""
    p = study.pushes
    if p is None:
        return []
    cases = [(m, x) for x in p.lengths for m in study.methods]
    if study.ablations is not None:
        cases += [(m, study.ablations.push_length) for m in study.ablation_methods()]
    return [
        (
            push_key(m, x, d),
            OneJob(
                push_job,
                m,
                x,
                d,
                p.duration,
                p.resolution,
                p.f_high,
                (),
                strategy.info(m).source,
                label=f"push {m} {x} {d}",
            ),
        )
        for m, x in cases
        for d in p.directions
    ]


@dataclasses.dataclass
class StudyRuns:
    """Everything the runs gave: each run's result, the sensitivity section, the pushes (and
    those in the sensitivity cells of the trade)."""

    results: Results
    sensitivity: sensitivity.SensitivitySection | None
    pushes: dict[str, PushCell | None]
    n_jobs: int
    seconds: float
    cell_pushes: dict[tuple[str, tuple[Override, ...], str], PushCell | None] = dataclasses.field(
        default_factory=dict
    )
    reach: dict[str, dict | None] = dataclasses.field(default_factory=dict)  # reach_job's
    grid_pushes: dict[str, PushCell | None] = dataclasses.field(default_factory=dict)


def run_study(study: Study, backend: Backend) -> StudyRuns:
    """Every run of the study on ``backend`` (see the module docstring for the order)."""
    t0 = time.perf_counter()
    requests = planned_runs(study)
    seeded = {s for s in requests if s.seed is not None}
    table1 = {s for s in seeded if s.push_std is None}
    first = _run_jobs({s: e for s, e in requests.items() if s not in seeded}, study)
    pushes = _push_jobs(study)
    grid = _grid_push_jobs(study)
    tasks: list[Task] = []
    tasks.extend(t for _, t in pushes)
    tasks.extend(t for _, t in grid)
    tasks.extend(t for _, t in first)
    n = run_tasks(tasks, backend, desc=f"experiments ({study.name}, 1/3: {backend.name})")
    results: Results = {s: t.result for s, t in first}

    clean = {
        m: {x: results[study.figure_run(m, x)].clean for x in study.sweep_grid}
        for m in (*study.methods, *study.ablation_methods())
    }
    refine = refinement_runs(study, clean)
    second = _run_jobs(
        {
            **{s: e for s, e in refine.items() if s not in results},
            **{s: requests[s] for s in table1},
        },
        study,
    )
    sens_plan = sensitivity.plan(study)
    tasks = []
    tasks.extend(t for _, _, t in sens_plan)
    tasks.extend(t for _, t in second)
    n += run_tasks(tasks, backend, desc=f"experiments ({study.name}, 2/3: {backend.name})")
    results.update({s: t.result for s, t in second})
    sens_runs = sum(t.runs for _, _, t in sens_plan)
    sens_s = sum(t.wall_s for _, _, t in sens_plan)
    sens = sensitivity.section(study, sens_plan, sens_runs, sens_s)

    # the push margin in the sensitivity cells whose gain the report states (known now), and
    # the walks under larger pushes
    cell_jobs = {
        key: OneJob(push_job, *args, label=f"push {' '.join(map(str, key))}")
        for key, args in trade_jobs(study, trade_cells(study, sens)).items()
    }
    third = _run_jobs({s: requests[s] for s in seeded - table1}, study)
    reach_jobs = {
        case_key(m, x): OneJob(reach_job, m, x, label=f"reach {m} {x:g}")
        for m, x in reach_cases(study, limits.max_step(study, results))
    }
    tasks = [*cell_jobs.values(), *reach_jobs.values(), *(t for _, t in third)]
    n += run_tasks(tasks, backend, desc=f"experiments ({study.name}, 3/3: {backend.name})")
    results.update({s: t.result for s, t in third})
    return StudyRuns(
        results=results,
        sensitivity=sens,
        pushes={k: push_cell(t.result) for k, t in pushes},
        n_jobs=n,
        seconds=time.perf_counter() - t0,
        cell_pushes={k: push_cell(t.result) for k, t in cell_jobs.items()},
        reach={k: t.result for k, t in reach_jobs.items()},
        grid_pushes={k: push_cell(t.result) for k, t in grid},
    )


def command_of(
    quick: bool,
    jobs: int | None,
    ray: str | None,
    out: Path,
    strategies: tuple[str, ...] = (),
    overrides: tuple[tuple[str, Any], ...] = (),
) -> str:
    """The command line that reruns this study."""
    parts = [PROG, "--out", str(out)]
    if quick:
        parts.append("--quick")
    parts += [f"--strategy {s}" for s in strategies]
    parts += [f"--set {name}={value}" for name, value in overrides]
    if jobs:
        parts += ["--jobs", str(jobs)]
    if ray is not None:
        parts += ["--ray", *([ray] if ray else [])]
    return " ".join(parts)


def main(
    out: Path,
    quick: bool = False,
    jobs: int | None = None,
    ray: str | None = None,
    strategies: tuple[str, ...] = (),
    overrides: tuple[tuple[str, Any], ...] = (),
) -> int:
    """Run the study (``quick``: the smoke set) on the local pool or Ray and write
    results.json, figures/ and report.md into ``out``; ``strategies`` (``FILE.py[:Class]``,
    loaded already) are studied beside the MPC in section 10; ``overrides`` (``("group.name",
    value)``, checked) set parameters of every run (a strategy's own: its runs only). Exit 0;
    1 if a run crashed; 2 (one line) if Ray is missing or cannot be reached."""
    study = dataclasses.replace(
        QUICK if quick else FULL, strategies=tuple(strategies), overrides=tuple(overrides)
    )
    n_jobs = jobs or os.cpu_count() or 1
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    started = datetime.now(UTC)
    t0 = time.perf_counter()
    cpu0 = cpu_seconds()
    load_start = os.getloadavg()[0]
    try:
        backend = make_backend(ray, n_jobs, n_tasks=n_jobs)
    except (ImportError, ConnectionError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    try:
        runs = run_study(study, backend)
    finally:
        backend.close()
    meta = Meta(
        command=command_of(quick, jobs, ray, out, tuple(strategies), tuple(overrides)),
        study=study.name,
        date_utc=started.strftime("%Y-%m-%d %H:%M UTC"),
        duration_s=time.perf_counter() - t0,
        run_seconds_total=sum(r.wall_s for r in runs.results.values())
        + (runs.sensitivity.duration_s if runs.sensitivity else 0.0),
        n_runs=len(runs.results)
        + (runs.sensitivity.n_runs if runs.sensitivity else 0)
        + sum(
            p.runs
            for p in [
                *runs.pushes.values(),
                *runs.cell_pushes.values(),
                *runs.grid_pushes.values(),
            ]
            if p
        )
        + len(runs.reach),
        jobs=n_jobs,
        cpu_count=os.cpu_count(),
        machine=f"{platform.machine()}, {platform.python_implementation()} "
        f"{platform.python_version()}",
        errors={s.key: r.error for s, r in runs.results.items() if r.error},
        backend=backend.name,
        load_average_start=load_start,
        cpu_s=cpu_seconds() - cpu0 if ray is None else None,
    )
    return finish(out, study, runs, meta, t0)


def cpu_seconds() -> float:
    """CPU time of this process and of its finished children (the local pool's workers once
    it is shut down; Ray's workers are not children) [s]."""
    import resource

    own, kids = (resource.getrusage(w) for w in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def finish(out: Path, study: Study, runs: StudyRuns, meta: Meta, t0: float) -> int:
    """Analyse finished runs, draw the figures, write results.json and report.md."""
    from app.experiments import figures
    from pelvic_walk.core.report_dir import record_report_dir

    data = analyse(
        study,
        runs.results,
        meta,
        runs.sensitivity,
        runs.pushes,
        runs.cell_pushes,
        runs.reach,
        runs.grid_pushes,
    )
    data = dataclasses.replace(
        data, figures=figures.make_all(study, runs.results, data, out / "figures")
    )
    # the duration includes the figures
    end = dataclasses.replace(
        data.meta, duration_s=time.perf_counter() - t0, load_average=os.getloadavg()[0]
    )
    data = dataclasses.replace(data, meta=end)
    write(out, study, data)
    record_report_dir(out)  # what `pelvic-walk serve` shows at /report
    print(f"wrote {out / 'report.md'} ({meta.n_runs} runs, {data.meta.duration_s:.0f} s)")
    return 0 if not meta.errors else 1


def write(out: Path, study: Study, data: StudyResults) -> None:
    """``results.json`` and ``report.md`` into ``out``."""
    from app.experiments import report

    (out / "results.json").write_text(to_json(data))
    (out / "report.md").write_text(report.render(study, data))
