"""``pelvic-walk serve``: FastAPI and the viser scene in this process, the robots in workers.

Processes and threads (the machine may have only two cores):

- **worker processes** (``--workers`` x ``--robots-per-worker``, by default one worker a core
  holding 6 robots: ``app.web.settings.worker_layout``; ``app.live.pool``, the one live mode)
  run the live sessions, each paced to real time, and send their frames back; with
  ``--workers 0`` the same pool runs its one worker in threads of this process instead (its
  in-process engine, ``app.live.engines``: one process to debug or profile; the robots then
  share this process's interpreter with the display); with ``--ray [ADDRESS]`` they are Ray
  actors on a cluster instead (``app.live.ray_engine``), as many as the cluster holds;
- the **display** thread (:class:`~app.web.view.Display`) draws each view's shown frame at
  most ``--display-hz`` times a second; viser's own thread sends the scene to the browsers;
- **uvicorn** serves the page and the HTTP API in the main thread.

With worker processes, this process's display and viser threads run ``display_nice``
steps below the workers (:func:`lower_priority`; the main thread (uvicorn, the API) and the
threads that receive the workers' frames keep their priority): on a machine whose cores are
short, the robots keep real time and the
scene is sent a little later, instead of every viewer slowing the robots down.

``--sessions shared`` (the default) shows one session to every browser; ``--sessions private``
gives each browser its own while the workers have room (``--robots-per-worker``), beside the
shared demo unless ``--no-shared-demo``, at most ``--sessions-per-address`` to one client
address (:mod:`app.live.registry`). ``--instructor-token`` puts one person in charge of
the shared demo (:mod:`app.web.auth`); the web server's access log stays off, so no URL (and no
``?token=``) is logged.

viser silently takes the next free port when its port is busy, so :func:`serve` checks
``get_port()`` and stops with one clear line (exit status 2); the FastAPI port is checked
before anything starts.
"""

from __future__ import annotations

import logging
import os
import socket
import sys
import threading
from pathlib import Path
from typing import Any

import viser
from pydantic import ValidationError

from app.live.engines import InProcessEngine
from app.live.intent import DEFAULT_METHODS
from app.live.loop import live_params
from app.live.pool import WorkerPool
from app.live.registry import SessionRegistry
from app.live.session import initial_intent
from app.web.addresses import ClientAddresses
from app.web.api import create_app
from app.web.auth import Instructor, redact_logs
from app.web.settings import MAX_DEFAULT_WORKERS, ROBOTS_PER_CORE, Settings, worker_layout
from app.web.view import Display
from controller import strategy
from pelvic_walk.core.params import parse_assignment
from pelvic_walk.core.robots import Robot

log = logging.getLogger(__name__)


def port_free(host: str, port: int) -> bool:
    """True if a TCP server could bind ``host:port`` now."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host, port))
        except OSError:
            return False
    return True


def lower_priority(steps: int, keep: set[int]) -> int:
    """Lower the priority of this process's threads, but ``keep`` (native ids), by ``steps``
    nice steps; threads they start later inherit it. Returns how many threads changed (0
    where Linux's per-thread /proc/self/task is missing). Lowering needs no privilege."""
    changed = 0
    task_dir = Path("/proc/self/task")
    if steps <= 0 or not task_dir.is_dir():
        return 0
    for task in task_dir.iterdir():
        tid = int(task.name)
        if tid in keep:
            continue
        try:
            nice = min(19, os.getpriority(os.PRIO_PROCESS, tid) + steps)
            os.setpriority(os.PRIO_PROCESS, tid, nice)
            changed += 1
        except OSError:  # the thread ended meanwhile
            continue
    return changed


def _fail(message: str) -> int:
    print(f"pelvic-walk serve: error: {message}", file=sys.stderr)
    return 2


def ray_layout(
    address: str, workers: int | None, robots_per_worker: int | None
) -> tuple[Any, int, int]:
    """(the Ray engine, its workers, robots each) for ``serve --ray [ADDRESS]``: an actor
    holds ``robots_per_worker`` robots (default ROBOTS_PER_CORE: a CPU's worth), as many
    actors as the cluster's free CPUs hold (at most ``workers`` if given). ImportError or
    ConnectionError (Ray missing or unreachable), ValueError (the cluster holds no actor),
    one line each."""
    from app.live.ray_engine import RayEngine

    if workers == 0:
        raise ValueError("--workers 0 runs the robots in this process; --ray needs at least 1")
    per = robots_per_worker or ROBOTS_PER_CORE
    engine = RayEngine(address or None, robots_per_worker=per)
    held = engine.workers_for()
    n = min(held, workers) if workers else min(held, 4 * MAX_DEFAULT_WORKERS)
    if n < 1:
        engine.close()
        raise ValueError(
            f"--ray: the cluster ({engine.where}) has no room for one worker of {per} robots"
            f" ({engine.worker_cpu:g} CPU); give fewer --robots-per-worker or add nodes"
        )
    return engine, n, per


def cluster_line(engine: Any, workers: int, robots_per_worker: int) -> str:
    """The start-up line of ``serve --ray``: the cluster, its nodes and the seats."""
    nodes = [n for n in engine.nodes([]) if n["alive"]]
    cpus = sum(n["cpus"] for n in nodes)
    share = engine.robot_cpu
    return (
        f"pelvic-walk: Ray: {len(nodes)} node{'s' if len(nodes) != 1 else ''}, {cpus:g} CPUs;"
        f" {workers} worker(s) x {robots_per_worker} robot(s) = {workers * robots_per_worker}"
        f" robot seats ({share:.3g} CPU a robot, {engine.worker_cpu:g} a worker)"
    )


def private_room_line(workers: int, robots_per_worker: int, robots: int, shared_demo: bool) -> str:
    """The start-up line of ``--sessions private``: how many private sessions of ``robots``
    robots the workers hold beside the shared demo (a session takes a slot per robot, the demo
    holds its own all the time), and what to do when that is none."""
    slots = workers * robots_per_worker
    n = max(slots - (robots if shared_demo else 0), 0) // robots
    line = (
        f"pelvic-walk: {n} private session{'s' if n != 1 else ''} of {robots} robot"
        f"{'s' if robots != 1 else ''} {'fits' if n == 1 else 'fit'}"
        f"{' beside the shared demo' if shared_demo else ''} ({workers} worker(s) x"
        f" {robots_per_worker} robot(s) = {slots} robot slots"
        f"{f', {robots} of them for the demo' if shared_demo else ''})"
    )
    if n:
        beyond = "watches the shared demo" if shared_demo else "is told they are full"
        return f"{line}; a browser beyond that {beyond}"
    fixes = ["--no-shared-demo (every slot for the students)"] if shared_demo else []
    fixes.append("more --workers or --robots-per-worker (if the cores keep up: pelvic-walk bench)")
    if robots > 1:
        fixes.append("fewer robots per session (--methods mpc)")
    what = fixes[0] if len(fixes) == 1 else f"{', '.join(fixes[:-1])} or {fixes[-1]}"
    whom = "every student watches the shared demo" if shared_demo else "no browser gets robots"
    return f"{line}: {whom}. For private sessions start with {what}."


def serve(
    host: str | None = None,
    port: int | None = None,
    viser_port: int | None = None,
    report_dir: Path | None = None,
    workers: int | None = None,
    sessions: str | None = None,
    robots_per_worker: int | None = None,
    display_hz: float | None = None,
    idle_timeout: float | None = None,
    methods: list[str] | None = None,
    shared_demo: bool | None = None,
    instructor_token: str | None = None,
    strategies: list[str] | None = None,
    sessions_per_address: int | None = None,
    trusted_proxies: list[str] | None = None,
    robots: list[Robot] | None = None,
    param_set: list[str] | None = None,
    ray: str | None = None,
) -> int:
    """Run the web tool until Ctrl-C; returns the exit status (2 on a busy port).

    Unset arguments come from :class:`~app.web.settings.Settings` (environment
    ``PELVIC_WALK_*``). ``report_dir``: what ``/report`` shows (default: the latest
    ``pelvic-walk experiments`` output, else the packaged reference report).
    ``strategies``: a user's strategy files (``--strategy``), already loaded by the command
    line (else loaded here); each adds a robot to the default ``methods``. ``robots``
    (``--robot``): the robots every session starts with, strategies with their own settings
    (instead of ``methods``); ``param_set`` (``--set GROUP.NAME=VALUE``): the shared
    parameters' values, a strategy's own (``gain.k=12``) included. ``ray`` (``--ray
    [ADDRESS]``): the robots on a Ray cluster ("" for a local instance; ``workers``: at most
    that many actors, else as many as the cluster holds).
    """
    import uvicorn

    given: dict[str, Any] = {
        "host": host,
        "port": port,
        "viser_port": viser_port,
        "report_dir": report_dir,
        "workers": workers,
        "sessions": sessions,
        "robots_per_worker": robots_per_worker,
        "display_hz": display_hz,
        "idle_timeout": idle_timeout,
        "shared_demo": shared_demo,
        "instructor_token": instructor_token,
        "sessions_per_address": sessions_per_address,
        "trusted_proxies": trusted_proxies,
    }
    try:  # the command line over the environment over the defaults, checked in one place
        settings = Settings(**{k: v for k, v in given.items() if v is not None})
    except ValidationError as exc:
        err = exc.errors()[0]  # (its "input", which may be a token, is never printed)
        return _fail(f"--{'-'.join(map(str, err['loc'])).replace('_', '-')}: {err['msg']}")
    host, port, viser_port = settings.host, settings.port, settings.viser_port
    report_dir, sessions = settings.report_dir, settings.sessions
    workers, robots_per_worker = worker_layout(settings.workers, settings.robots_per_worker)
    display_hz = settings.display_hz
    idle_timeout = settings.idle_timeout
    if port == viser_port:
        return _fail(f"--port and --viser-port must differ (both {port})")
    if not settings.shared_demo and sessions != "private":
        return _fail("--no-shared-demo needs --sessions private (else nothing would run)")
    secret = settings.instructor_token
    instructor = Instructor(secret.get_secret_value() if secret is not None else None)
    try:
        loaded = strategy.load_files(strategies or [])
    except strategy.StrategyLoadError as exc:
        return _fail(f"--strategy {exc}")
    if robots and methods:
        return _fail("--robot and --methods both name the robots: give one")
    shared: dict[str, dict[str, Any]] = {}
    try:
        for text in param_set or []:
            group, name, value = parse_assignment(text)
            shared.setdefault(group, {})[name] = value
        params = live_params().replace(**shared)
    except ValueError as exc:
        return _fail(f"--set: {exc}")
    try:
        intent = initial_intent(
            params, methods=methods or (*DEFAULT_METHODS, *loaded), robots=robots or None
        )
    except ValueError as exc:
        return _fail(f"--robot: {exc}" if robots else str(exc))
    engine: Any = None if workers else InProcessEngine()  # --workers 0: threads of this one
    if ray is not None:
        try:
            engine, workers, robots_per_worker = ray_layout(
                ray, settings.workers, settings.robots_per_worker
            )
        except (ImportError, ConnectionError, ValueError) as exc:
            return _fail(str(exc))
    if settings.shared_demo and len(intent.methods) > max(workers, 1) * robots_per_worker:
        if ray is not None:
            engine.close()
        return _fail(
            f"{workers} worker(s) x {robots_per_worker} robot(s) cannot hold the"
            f" {len(intent.methods)} robots of the demo; give more --workers or"
            " --robots-per-worker"
        )
    problem = None
    if not port_free(host, port):
        problem = f"port {port} on {host} is in use; choose another with --port"
    elif not port_free(host, viser_port):
        problem = f"port {viser_port} on {host} is in use; choose another with --viser-port"
    if problem is None:
        viser_server = viser.ViserServer(host=host, port=viser_port, verbose=False)
        if viser_server.get_port() != viser_port:
            viser_server.stop()
            problem = f"port {viser_port} on {host} is in use; choose another with --viser-port"
    if problem is not None:
        if ray is not None:
            engine.close()
        return _fail(problem)

    # --workers 0: the same pool, its one worker in threads of this process
    pool = WorkerPool(max(workers, 1), robots_per_worker, display_hz, engine).start()
    registry = SessionRegistry.start(
        sessions,
        intent,
        pool,
        idle_timeout,
        shared_demo=settings.shared_demo,
        per_address=settings.sessions_per_address,
    )
    addresses = ClientAddresses(settings.trusted_proxies)  # one source: page, API, scene
    display = Display(viser_server, registry, display_hz, instructor, addresses).start()
    app = create_app(
        registry,
        viser_port=viser_port,
        report_dir=report_dir,
        health_extra=display.health,
        instructor=instructor,
        addresses=addresses,
    )
    if not pool.in_process:
        # the main thread (uvicorn, and the API's worker threads it starts) keeps its
        # priority: the HTTP API is light and must answer promptly
        keep = pool.receiver_thread_ids() | {threading.get_native_id()}
        keep |= engine.keep_threads() if ray is not None else set()  # (Ray's: the frames')
        lower_priority(settings.display_nice, keep=keep)
    redact_logs()  # a URL with ?token= never reaches a log (the access log is off anyway)
    # proxy_headers off: forwarded headers are read by app.web.addresses alone, from the
    # trusted proxies only, for the API and the scene alike
    config = uvicorn.Config(
        app, host=host, port=port, log_level="warning", access_log=False, proxy_headers=False
    )
    server = uvicorn.Server(config)
    shown = f"[{host}]" if ":" in host else host
    demo = "" if settings.shared_demo else ", no shared demo"
    teacher = "; instructor: open the page with ?token=<your token>" if instructor.enabled else ""
    print(
        f"pelvic-walk: open http://{shown}:{port}/  (3-D scene: http://{shown}:{viser_port}/,"
        f" API docs: http://{shown}:{port}/docs); "
        + (
            f"{workers} Ray actor{'s' if workers != 1 else ''} on {engine.where}"
            if ray is not None
            else f"{workers} worker process{'es' if workers != 1 else ''}"
            if workers
            else "the robots in this process (--workers 0)"
        )
        + f", {sessions} sessions{demo}{teacher}; Ctrl-C to stop",
        flush=True,
    )
    if ray is not None:
        print(cluster_line(engine, workers, robots_per_worker), flush=True)
    if sessions == "private":
        print(
            private_room_line(
                max(workers, 1), robots_per_worker, len(intent.methods), settings.shared_demo
            ),
            flush=True,
        )
    status = 0
    try:
        server.run()
    except SystemExit as exc:  # uvicorn exits when it cannot bind (a race with another server)
        status = 2 if exc.code else 0
    except KeyboardInterrupt:
        status = 0
    finally:
        display.stop()
        registry.shutdown()
        pool.stop()
        app.state.runs.shutdown()
        viser_server.stop()
    if not server.started and status == 0:
        return _fail(f"the web server could not start on {host}:{port}")
    print("pelvic-walk: stopped", flush=True)
    return status
