"""The ``pelvic-walk`` command line (docs/REFERENCE.md, "Command line").

Bad arguments exit with status 2 and one clear line on stderr, never a traceback.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

from app.cli.options import (
    MethodList,
    add_jobs_argument,
    add_param_options,
    add_ray_argument,
    add_set_argument,
    add_strategy_argument,
    load_strategy_options,
    method_name,
    params_from_args,
    positive_int,
    robot_spec,
    study_overrides,
)
from app.cli.sweep import add_sweep_arguments
from controller import strategy
from pelvic_walk.core.run_spec import DISTURBANCE, DISTURBANCE_PERIOD, SEED_PERTURBATION

if TYPE_CHECKING:
    from pelvic_walk.core.session import RunConfig


class _Parser(argparse.ArgumentParser):
    """argparse that reports errors on one line (no usage dump) and exits 2. No abbreviated
    options: ``--strategy`` is read before parsing (its files name the methods)."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {text!r}")
    return value


def _non_negative(text: str) -> float:
    value = _finite(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text!r}")
    return value


def _port(text: str) -> int:
    value = positive_int(text)
    if value > 65535:
        raise argparse.ArgumentTypeError(f"not a port number: {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="pelvic-walk", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("serve", help="the web teaching tool (FastAPI + viser)")
    p.add_argument(
        "--host",
        default=None,
        help="the address to listen on (default 127.0.0.1: this machine only; 0.0.0.0: a class)",
    )
    p.add_argument(
        "--port", type=_port, default=None, help="the page and the HTTP API (default 8000)"
    )
    p.add_argument(
        "--viser-port", type=_port, default=None, help="the 3-D scene (viser; default 8080)"
    )
    p.add_argument(
        "--report",
        "--report-dir",
        dest="report_dir",
        type=Path,
        default=None,
        help="the report /report shows (default: your latest `experiments --out` outside "
        "temporary folders, else the reference report)",
    )
    p.add_argument(
        "--methods",
        nargs="+",
        action=MethodList,
        default=None,
        help="the robots every session starts with, with commas or spaces (default: fixed "
        "redundancy mpc and every --strategy)",
    )
    p.add_argument(
        "--robot",
        dest="robots",
        action="append",
        type=robot_spec,
        default=None,
        metavar="NAME[,KEY=VALUE...][@LABEL]",
        help="a robot every session starts with: a strategy, its own settings over the shared "
        'parameters and a label, e.g. --robot mpc --robot "mpc,com.horizon=0.8@short '
        'horizon" (repeatable, at most 6; replaces --methods)',
    )
    add_strategy_argument(
        p,
        "FILE.py[:Class]: your own pelvis strategy (docs/STRATEGIES.md), one more robot "
        "beside the paper's three, in its own colour (repeatable); loaded once at start",
    )
    add_set_argument(p)
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        help="worker processes running the robots (default: one a core, holding the "
        "machine's capacity of 6 robots a core: 2 x 6 on 2 cores; 0: the same pool in "
        "threads of this process)",
    )
    p.add_argument(
        "--ray",
        nargs="?",
        const="",
        default=None,
        metavar="ADDRESS",
        help="run the robots of every live session on a Ray cluster at ADDRESS, or without one "
        "on a local Ray instance; the seats are what the cluster holds at start "
        "(docs/TEACHING.md, 'A class on a Ray cluster'; pip install 'pelvic-walk[cluster]')",
    )
    p.add_argument(
        "--sessions",
        choices=("shared", "private"),
        default=None,
        help="shared: every browser watches one session (default); private: each "
        "browser gets its own while the workers have room",
    )
    p.add_argument(
        "--robots-per-worker",
        type=positive_int,
        default=None,
        help="robots one worker runs at once (default: the capacity of 6 robots a core "
        "shared out over the workers; a worker's robots share one core)",
    )
    p.add_argument(
        "--display-hz",
        type=_finite,
        default=None,
        help="scene updates per second at most (default 20)",
    )
    p.add_argument(
        "--idle-timeout",
        type=_finite,
        default=None,
        help="[s] an API-opened private session without calls ends (default 300)",
    )
    p.add_argument(
        "--shared-demo",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="with --sessions private: run the shared demo beside the private sessions (the "
        "default; it holds its robots' worker slots) or not (--no-shared-demo: every slot "
        "for private sessions)",
    )
    p.add_argument(
        "--sessions-per-address",
        type=positive_int,
        default=None,
        metavar="N",
        help="with --sessions private: private sessions one client address holds at most, "
        "its browsers' and scripts' together (default 1; the server's own machine is not "
        "limited)",
    )
    p.add_argument(
        "--instructor-token",
        default=None,
        metavar="TOKEN",
        help="only the page opened with ?token=TOKEN (and API calls with 'Authorization: "
        "Bearer TOKEN') change the shared demo; students watch it (or drive their private "
        "sessions). PELVIC_WALK_INSTRUCTOR_TOKEN keeps it out of the process list",
    )
    p.add_argument(
        "--trusted-proxy",
        action="append",
        default=None,
        dest="trusted_proxies",
        metavar="ADDR",
        help="behind a reverse proxy: its address (or network, e.g. 10.0.0.0/24; repeat for "
        "more); from it, and only from it, X-Forwarded-For names the client, for the page, "
        "the API and the scene alike (docs/TEACHING.md, 'Behind a reverse proxy')",
    )

    p = sub.add_parser(
        "simulate",
        help="one headless closed-loop MuJoCo run",
        description="One headless closed-loop run. Every parameter of controller/params.py "
        "has an option (or use --set GROUP.NAME=VALUE).",
    )
    how = p.add_mutually_exclusive_group(required=True)
    how.add_argument(
        "--method",
        type=method_name,
        default=None,
        help=f"how the pelvis turns: {', '.join(strategy.BUILTINS)} (the paper's three), or "
        "the name of a strategy --strategy loads",
    )
    how.add_argument(
        "--strategy",
        dest="strategy_file",
        default=None,
        metavar="FILE.py[:Class]",
        help="your own pelvis strategy instead of --method (docs/STRATEGIES.md); the exit "
        "status is 1 if it raised or returned no rate (the message says where)",
    )
    add_param_options(p, required={"walk.step_length"})
    p.add_argument(
        "--seed",
        type=int,
        default=None,
        metavar="N",
        help=f"run the study's repeat N of this cell: a {SEED_PERTURBATION} rad start "
        "perturbation and seeded pushes on the torso through the whole run, as `experiments` "
        "runs it (e.g. --steps 20 --seed 3 reruns a Table 1 run)",
    )
    p.add_argument(
        "--disturbance",
        type=_non_negative,
        default=None,
        metavar="NEWTONS",
        help=f"[N] size of the seeded pushes: each axis N(0, NEWTONS), renewed every "
        f"{DISTURBANCE_PERIOD:g} s (default with --seed: the study's {DISTURBANCE:g} N; 0: the "
        "start perturbation alone; needs --seed)",
    )
    p.add_argument(
        "--backend",
        choices=("osqp", "daqp"),
        default="daqp",
        help="the QP solver of every layer (default daqp: exact active set; osqp: ADMM)",
    )
    p.add_argument("--json", type=Path, default=None, help="write the summary here")
    p.add_argument("--csv", type=Path, default=None, help="write the time series here")
    p.add_argument(
        "--record",
        type=Path,
        default=None,
        help="write a recording of the run that plays back without the server: "
        "PATH.zip, or else a folder (open its index.html in a browser)",
    )

    p = sub.add_parser("analyze", help="the kinematic analysis of eq. (1)-(5)")
    p.add_argument("--json", type=Path, default=None)

    p = sub.add_parser(
        "experiments",
        help="reproduce the paper's simulation results",
        description="The paper's simulation study on our model: every run on a local process "
        "pool (or Ray), then results.json, figures/ and report.md in --out.",
    )
    p.add_argument("--out", type=Path, required=True, metavar="DIR")
    p.add_argument("--quick", action="store_true", help="a small smoke set (about 2 min)")
    add_strategy_argument(
        p,
        "FILE.py[:Class]: your own pelvis strategy, studied beside the MPC in section 10 "
        "(its own row: longest step, waist, energy, kappa, push survival; repeatable)",
    )
    add_set_argument(p)
    add_jobs_argument(p)
    add_ray_argument(p)

    p = sub.add_parser("sweep", help="a parameter grid over methods (process pool or Ray)")
    add_sweep_arguments(p)

    p = sub.add_parser("loadtest", help="N scene viewers against a server (loopback only)")
    p.add_argument("--viewers", type=positive_int, default=20)
    p.add_argument("--robots", type=int, choices=(1, 2, 3), default=3)
    p.add_argument("--seconds", type=positive_int, default=120)
    p.add_argument(
        "--port",
        type=_port,
        default=None,
        help="a server already running on 127.0.0.1 (default: start one)",
    )
    p.add_argument("--viser-port", type=_port, default=None)
    p.add_argument("--json", type=Path, default=None)

    p = sub.add_parser("bench", help="performance figures")
    p.add_argument("--json", type=Path, default=None)
    p.add_argument("--ticks", type=positive_int, default=600)
    p.add_argument(
        "--peer-python",
        default=None,
        metavar="PATH",
        help="an interpreter with placo (its own venv: placo pins its own Pinocchio) to run "
        "placo's walk loop on our robot beside ours (default: $PELVIC_WALK_PEER_PYTHON, else "
        "this checkout's .venv-peers/bin/python, which `make peers` creates, else this "
        "interpreter if it has placo; without one the bench says so and runs the rest)",
    )

    p = sub.add_parser(
        "push-study",
        help="the largest sideways push each method survives (bisection, headless)",
        description="Push the torso for --duration s at mid-single-support of the third "
        "step; a run recovers when the robot has not fallen by the end of the plan.",
    )
    p.add_argument(
        "--methods",
        nargs="+",
        action=MethodList,
        default=list(strategy.BUILTINS),
        help="commas or spaces (default: fixed redundancy mpc)",
    )
    add_strategy_argument(p)
    p.add_argument("--step-length", type=_finite, default=0.3, help="[m] (default 0.3)")
    p.add_argument("--direction", choices=("left", "right", "forward", "back"), default="left")
    p.add_argument("--duration", type=_finite, default=0.1, help="[s] (default 0.1)")
    p.add_argument("--force", type=_finite, default=None, help="[N] one push, no bisection")
    add_jobs_argument(p, 1, "processes: one method's bisection each (default 1: in this process)")
    add_ray_argument(p)
    p.add_argument("--json", type=Path, default=None)
    return parser


def simulate_config(args: argparse.Namespace) -> RunConfig:
    """The run ``simulate`` makes: the study's run of the same cell and seed
    (``pelvic_walk.core.run.spec_of``), with the pushes' size and the QP back-end the options ask
    for.
    ValueError on a bad value."""
    from pelvic_walk.core.run import spec_of

    if args.disturbance is not None and args.seed is None:
        raise ValueError("--disturbance needs --seed (the pushes are drawn from the seed)")
    params = params_from_args(args, method=simulate_method(args))
    cfg = spec_of(params, args.seed).config()
    if args.disturbance is not None:
        cfg = dataclasses.replace(cfg, disturbance=args.disturbance)
    return dataclasses.replace(cfg, backend=args.backend)


def simulate_method(args: argparse.Namespace) -> str:
    """The strategy ``simulate`` runs: ``--method``, or the one strategy of ``--strategy``
    (loaded before parsing); ValueError if that file holds several and names none."""
    if args.method is not None:
        return args.method
    file, cls = strategy.parse_source(args.strategy_file)
    loaded = strategy.load_file(args.strategy_file)  # already loaded: no work
    if len(loaded) > 1:
        raise ValueError(
            f"--strategy {file} defines {len(loaded)} strategies ({', '.join(loaded)}): name "
            f"one class, as {file}:ClassName"
        )
    return loaded[0]


def _simulate(args: argparse.Namespace) -> int:
    from pelvic_walk.core.run import run, summarize
    from pelvic_walk.core.summary import outcome, unsuccessful_text

    try:
        cfg = simulate_config(args)
    except ValueError as exc:  # bad parameter values: one line, exit 2, nothing started
        print(f"pelvic-walk simulate: error: {exc}", file=sys.stderr)
        return 2
    params = cfg.params
    recorder = None
    if args.record:
        from pelvic_walk.core.capture import Capture

        recorder = Capture(params.method)
    session = run(cfg, on_tick=recorder.capture if recorder else None)
    summary = summarize(session)
    ok = outcome(summary, clean=False)
    le = summary["landing_error_max"]
    landing = f"{le * 100:.1f} cm" if le is not None else "-"
    print(
        f"{summary['method']} step {summary['step_length']:.3f} m x {summary['steps_planned']}: "
        f"{ok}, {summary['steps_completed']}/{summary['steps_planned']} steps, "
        f"landing error max {landing}, "
        f"ZMP in support {summary['zmp_in_support_ratio'] * 100:.1f} %, "
        f"waist max {summary['waist_yaw_max_deg']:.1f} deg, "
        f"kappa max {summary['condition_number_max']:.1f}, "
        f"solver failures {summary['solver_failures']}, "
        f"RTF {summary['realtime_factor'] or 0:.1f}"
    )
    if cfg.seed is not None:
        print(
            f"seed {cfg.seed}: start perturbation {cfg.perturbation:g} rad, pushes "
            f"N(0, {cfg.disturbance:g} N) per axis every {cfg.disturbance_period:g} s"
        )
    if summary["fell"]:
        print(f"fell at {summary['fall_time']:.2f} s: {summary['fall_reason']}")
    if summary["unsuccessful"]:
        why = unsuccessful_text(summary["unsuccessful"], le, summary["solver_failure_share"])
        print(f"not a success: {why}")
    if summary["strategy_error"]:
        step = summary.get("strategy_error_step")
        where = f" in step {step} (s.step)" if step is not None and step >= 0 else ""
        print(
            f"stopped at t = {summary['strategy_error_time']:.3f} s{where}: "
            f"{summary['strategy_error']}"
        )
    tick_ms = params.control_dt * 1e3
    if summary["strategy_ms_median"] > tick_ms:
        print(
            f"warning: the strategy takes {summary['strategy_ms_median']:.1f} ms a tick "
            f"(median; max {summary['strategy_ms_max']:.1f} ms), more than the {tick_ms:g} ms "
            "control period: it cannot run in real time live"
        )
    if args.json:
        args.json.write_text(json.dumps(summary, indent=2))
    if args.csv:
        session.series.to_csv(str(args.csv))
    if recorder is not None:
        _write_recording(recorder, args)
    # a walk the strategy stopped did not run as asked: a script can tell (a fall is a result)
    return 1 if summary["strategy_error"] else 0


def _write_recording(recorder, args: argparse.Namespace) -> None:
    """``simulate --record``: the whole run as a zip or a folder (by the path's extension)."""
    from app.web import recording

    how = f"--strategy {args.strategy_file}" if args.strategy_file else f"--method {args.method}"
    source = f"headless run (pelvic-walk simulate {how})"
    try:
        path = recording.write(recording.of_capture(recorder, source), args.record)
    finally:
        recording.shutdown()
    size = sum(f.stat().st_size for f in [path, *path.rglob("*")] if f.is_file())
    print(f"recording: {path} ({size / 1e6:.1f} MB); open index.html in a browser")


def _analyze(args: argparse.Namespace) -> int:
    from controller.analysis import kinematic_analysis

    paper = kinematic_analysis()
    for k, v in paper.items():
        print(f"{k:32s} {v:.4f}" if isinstance(v, float) else f"{k:32s} {v}")
    if args.json:
        args.json.write_text(json.dumps(paper, indent=2))
    return 0


def _check_output_paths(args: argparse.Namespace) -> str | None:
    """A one-line complaint if an output file cannot be written (checked before any run)."""
    for flag in ("json", "csv", "record"):
        path = getattr(args, flag, None)
        if path is None:
            continue
        if flag == "record" and path.suffix.lower() != ".zip":  # a folder, made if need be
            if path.exists() and not path.is_dir():
                return f"--record {path}: is a file, not a folder (or name it .zip)"
            if path.is_dir():
                path = path / "index.html"
        parent = path.resolve().parent
        if not parent.is_dir():
            return f"--{flag} {path}: folder {parent} does not exist"
        if not os.access(parent, os.W_OK) or (path.exists() and not os.access(path, os.W_OK)):
            return f"--{flag} {path}: not writable"
        if path.is_dir():
            return f"--{flag} {path}: is a folder, not a file"
    return None


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    # a user's strategies first: their names are methods the options below may name
    problem = load_strategy_options(argv)
    if problem:
        command = next((a for a in argv if not a.startswith("-")), "")
        print(f"pelvic-walk {command}: error: {problem}".replace("  ", " "), file=sys.stderr)
        return 2
    parser = build_parser()
    args = parser.parse_args(argv)
    problem = _check_output_paths(args)
    if problem:
        print(f"pelvic-walk {args.command}: error: {problem}", file=sys.stderr)
        return 2
    try:
        if args.command == "simulate":
            return _simulate(args)
        if args.command == "analyze":
            return _analyze(args)
        if args.command == "serve":
            from app.web.server import serve

            return serve(
                args.host,
                args.port,
                args.viser_port,
                args.report_dir,
                args.workers,
                args.sessions,
                args.robots_per_worker,
                args.display_hz,
                args.idle_timeout,
                args.methods,
                args.shared_demo,
                args.instructor_token,
                args.strategies,
                sessions_per_address=args.sessions_per_address,
                trusted_proxies=args.trusted_proxies,
                robots=args.robots,
                param_set=args.param_set,
                ray=args.ray,
            )
        if args.command == "experiments":
            from app.experiments.runner import main as experiments_main

            try:
                overrides = study_overrides(args.param_set)
            except ValueError as exc:
                print(f"pelvic-walk experiments: error: {exc}", file=sys.stderr)
                return 2
            return experiments_main(
                args.out,
                quick=args.quick,
                jobs=args.jobs,
                ray=args.ray,
                strategies=tuple(args.strategies),
                overrides=overrides,
            )
        if args.command == "sweep":
            from app.cli.sweep import sweep_main

            return sweep_main(args)
        if args.command == "loadtest":
            from app.bench.loadtest import main as loadtest_main

            return loadtest_main(
                args.viewers, args.robots, args.seconds, args.port, args.viser_port, args.json
            )
        if args.command == "bench":
            from app.bench.timings import main as bench_main

            return bench_main(args.json, ticks=args.ticks, peer_python_path=args.peer_python)
        if args.command == "push-study":
            from app.cli.push_study import push_study_main

            return push_study_main(args)
    except KeyboardInterrupt:
        return 130
    return 2


if __name__ == "__main__":
    sys.exit(main())
