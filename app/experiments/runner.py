"""``pelvic-walk experiments``: run the study over a process pool and write the report.

Flow: :func:`definitions.planned_runs` (every run known up front) -> process pool of
:func:`worker.execute` -> :func:`definitions.refinement_runs` (the 0.01 m sweep between each
method's last clean and first failed coarse length) -> process pool -> :func:`analyse`
(:mod:`sections`' numbers, :mod:`claims`' verdicts) -> ``results.json``, ``figures/*.png``,
``report.md``.

Workers are started with ``spawn`` (no inherited MuJoCo/Pinocchio state); the longest runs are
submitted first.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import os
import platform
import sys
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from datetime import UTC, datetime
from pathlib import Path
from typing import cast

from tqdm import tqdm

from app.experiments import claims, sections, sections_more
from app.experiments.definitions import (
    FULL,
    QUICK,
    STUDIES,
    Requests,
    Study,
    planned_runs,
    refinement_runs,
)
from app.experiments.results import Meta, Results, RunRecord, RunSummary, StudyResults, to_json
from app.experiments.results_more import SensitivitySection
from app.experiments.worker import execute


def _run_all(
    requests: Requests, pool: ProcessPoolExecutor, bar: tqdm, mid_step: int, results: Results
) -> None:
    """Run every request not yet in ``results`` (longest runs first); fill ``results``."""
    todo = [s for s in requests if s not in results]
    todo.sort(key=lambda s: (-s.n_steps, -s.step_length, s.key))
    bar.total = (bar.total or 0) + len(todo)
    bar.refresh()
    futures = {pool.submit(execute, s, tuple(sorted(requests[s])), mid_step): s for s in todo}
    pending = set(futures)
    while pending:
        done, pending = wait(pending, return_when=FIRST_COMPLETED)
        for fut in done:
            results[futures[fut]] = fut.result()
            bar.set_postfix_str(futures[fut].key, refresh=False)
            bar.update(1)


def run_study(study: Study, jobs: int, results: Results | None = None) -> tuple[Results, Requests]:
    """Run the whole study; returns every run's result and the merged requests."""
    results = {} if results is None else results
    requests = planned_runs(study)
    ctx = multiprocessing.get_context("spawn")
    with (
        ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool,
        tqdm(
            total=0,
            desc=f"experiments ({study.name}, {jobs} jobs)",
            unit="run",
            file=sys.stderr,
            dynamic_ncols=True,
        ) as bar,
    ):
        _run_all(requests, pool, bar, study.mid_step, results)
        clean = {
            m: {x: results[study.figure_run(m, x)].clean for x in study.sweep_grid}
            for m in study.methods
        }
        refine = refinement_runs(study, clean)
        for spec, ex in refine.items():
            requests.setdefault(spec, set()).update(ex)
        _run_all(refine, pool, bar, study.mid_step, results)
    return results, requests


def estimate_full_seconds(results: Results, jobs: int) -> float | None:
    """Wall time of the full study on ``jobs`` processes, from these runs' cost per sim second.

    Counts the full study's planned runs plus about 20 refinement runs of 10 steps; a run that
    falls ends early, so this is an upper estimate.
    """
    done = [r for r in results.values() if r.summary and r.summary.sim_time > 0]
    if not done:
        return None
    rate = sum(r.wall_s for r in done) / sum(cast(RunSummary, r.summary).sim_time for r in done)
    overhead = 0.8 + 1.2 * 0.2 + 1.0 + 1.2  # [s] stand, final DSP, final stand, closing step
    sim = sum(s.n_steps * 1.2 + overhead for s in planned_runs(FULL))
    sim += 20 * (FULL.n_steps * 1.2 + overhead)
    return rate * sim / max(jobs, 1)


def analyse(
    study: Study, results: Results, meta: Meta, sens: SensitivitySection | None = None
) -> StudyResults:
    """Every section's numbers, the claims' verdicts, and every run's summary."""
    ms = sections.max_step(study, results)
    out = StudyResults(
        meta=dataclasses.replace(meta, full_estimate_s=estimate_full_seconds(results, meta.jobs)),
        kinematics=sections.kinematics(),
        max_step=ms,
        equivalent_lengths=sections.equivalent_lengths(study, ms),
        waist=sections.waist(study, results),
        yaw_momentum=sections.yaw_momentum(study, results),
        energy=sections.energy(study, results),
        kappa=sections.kappa(study, results, ms),
        zmp=sections.zmp(study, results),
        lateral=sections_more.lateral(study, results, sens),
        balance=sections_more.balance(study, results),
        sensitivity=sens,
        runs={
            s.key: RunRecord(s, r.wall_s, r.error, r.summary.as_dict() if r.summary else None)
            for s, r in sorted(results.items(), key=lambda kv: kv[0].key)
        },
    )
    return dataclasses.replace(out, claims=claims.evaluate(study, out))


def main(
    out: Path, quick: bool = False, jobs: int | None = None, study_name: str | None = None
) -> int:
    """Run the study (``quick``: the smoke set; ``study_name``: one of
    :data:`definitions.STUDIES`) and write results.json, figures/ and report.md."""
    study = STUDIES[study_name] if study_name else (QUICK if quick else FULL)
    jobs = jobs or os.cpu_count() or 1
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    started = datetime.now(UTC)
    t0 = time.perf_counter()
    load_start = os.getloadavg()[0]
    results, _ = run_study(study, jobs)
    study_s = time.perf_counter() - t0
    sens = sections_more.run_sensitivity(study, jobs)
    if study_name:
        command = f"python -m app.experiments.runner --out {out} --study {study.name} --jobs {jobs}"
    else:
        command = "pelvic-walk experiments --out {} {}--jobs {}".format(
            out, "--quick " if quick else "", jobs
        )
    return finish(out, study, results, sens, command, started, t0, study_s, jobs, load_start)


def finish(
    out: Path,
    study: Study,
    results: Results,
    sens: SensitivitySection,
    command: str,
    started: datetime,
    t0: float,
    study_s: float,
    jobs: int,
    load_start: float | None = None,
) -> int:
    """Analyse finished runs, draw the figures, write results.json and report.md."""
    from app.experiments import figures
    from app.report_dir import record_report_dir

    meta = Meta(
        command=command,
        study=study.name,
        date_utc=started.strftime("%Y-%m-%d %H:%M UTC"),
        duration_s=time.perf_counter() - t0,
        run_seconds_total=sum(r.wall_s for r in results.values()),
        n_runs=len(results),
        study_s=study_s,
        jobs=jobs,
        cpu_count=os.cpu_count(),
        machine=f"{platform.machine()}, {platform.python_implementation()} "
        f"{platform.python_version()}",
        errors={s.key: r.error for s, r in results.items() if r.error},
        load_average=os.getloadavg()[0],
        load_average_start=load_start,
    )
    data = analyse(study, results, meta, sens)
    data = dataclasses.replace(
        data, figures=figures.make_all(study, results, data, out / "figures")
    )
    # the duration includes the figures
    data = dataclasses.replace(
        data, meta=dataclasses.replace(data.meta, duration_s=time.perf_counter() - t0)
    )
    write(out, study, data)
    record_report_dir(out)  # what `pelvic-walk serve` shows at /report
    print(
        f"wrote {out / 'report.md'} ({len(results)} runs + {sens.n_runs} sensitivity runs, "
        f"{data.meta.duration_s:.0f} s)"
    )
    return 0 if not meta.errors else 1


def write(out: Path, study: Study, data: StudyResults) -> None:
    """``results.json`` and ``report.md`` into ``out``."""
    from app.experiments import report

    (out / "results.json").write_text(to_json(data))
    (out / "report.md").write_text(report.render(study, data))


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m app.experiments.runner",
        description="the study, as `pelvic-walk experiments`, with a choice of study",
    )
    parser.add_argument("--out", type=Path, default=Path("report"))
    parser.add_argument("--study", choices=sorted(STUDIES), default="full")
    parser.add_argument("--jobs", type=int, default=None)
    args = parser.parse_args()
    sys.exit(main(args.out, jobs=args.jobs, study_name=args.study))
