"""``pelvic-walk push-study``: one push per method (``--force``) or the largest survived.

The walks run through the core's one run path (``pelvic_walk.core.pushes`` on
``pelvic_walk.core.run``) and its engine (``--jobs``, ``--ray``), so a student's strategy that
raises is contained as everywhere: its row says it stopped, one line names the file and line,
the other methods' rows stand, and the exit status is 1.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from controller.params import ControllerParams, spec
from pelvic_walk.core.pushes import PushOutcome, Survival, as_json, run_push, study, table

PROG = "pelvic-walk push-study"


def _check(args: argparse.Namespace) -> str | None:
    meta = spec(ControllerParams().walk)["step_length"]
    if not meta["min"] <= args.step_length <= meta["max"]:
        return f"--step-length must be in {meta['min']}..{meta['max']} m"
    if not 0.0 < args.duration <= 1.0:
        return "--duration must be in (0, 1] s"
    if args.force is not None and args.force < 0.0:
        return "--force must be >= 0 N"
    return None


def push_study_main(args: argparse.Namespace) -> int:
    problem = _check(args)
    if problem:
        print(f"{PROG}: error: {problem}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    singles: list[PushOutcome] = []
    rows: list[Survival] = []
    stopped: list[tuple[str, str]] = []  # (method, the strategy's error)
    if args.force is not None:
        for m in args.methods:
            o = run_push(m, args.step_length, args.force, args.direction, args.duration)
            singles.append(o)
            if o.error is not None:
                stopped.append((m, o.error))
                result = "STOPPED by its strategy"
            elif o.recovered:
                result = "recovered"
            else:
                result = f"FELL at {o.fall_time:.2f} s ({o.fall_reason})"
            print(
                f"{m}: {o.force:.0f} N {o.direction} for {o.duration:.2f} s at t = "
                f"{o.push_time:.2f} s (mid-SSP, on the {o.support} foot), step "
                f"{o.step_length:.2f} m: {result}"
            )
    else:
        try:
            rows = study(
                args.methods,
                args.step_length,
                args.direction,
                args.duration,
                jobs=args.jobs,
                ray=args.ray,
            )
        except (ImportError, ConnectionError) as exc:
            print(f"{PROG}: error: {exc}", file=sys.stderr)
            return 2
        stopped = [(s.method, s.error) for s in rows if s.error is not None]
        print(table(rows))
    print(f"({time.perf_counter() - start:.0f} s)")
    if args.json:
        args.json.write_text(json.dumps(as_json(rows, singles), indent=2))
    for method, error in stopped:  # one line each: the file and line the strategy failed at
        print(f"{PROG}: {method} stopped by its strategy: {error}", file=sys.stderr)
    return 1 if stopped else 0
