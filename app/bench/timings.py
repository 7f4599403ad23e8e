"""Performance figures: ``pelvic-walk bench [--json PATH] [--ticks N]``
(docs/REFERENCE.md, "bench JSON").

Everything comes from one invocation, on one robot, headless:

1. **Closed loop** (the measured figures): one :class:`pelvic_walk.core.run.Session`, method
   ``mpc``, arms
   on, step 0.3 m, QP back-end ``daqp`` (the default), stepped exactly as
   :func:`pelvic_walk.core.run.run`
   steps it (controller tick, MuJoCo substeps, measurement). The initial stand before the first
   step (``t_start``, 0.8 s = 160 ticks) is the warm-up and is not measured; the next
   ``ticks`` ticks are. ``tick_ms_*`` time ``Walker.tick`` alone (all layers); ``layer_ms``
   are the per-layer medians the walker reports with its injected clock; ``realtime_factor``
   is simulated time / wall time of the whole loop over the measured ticks.
   **Unrecorded** (``*_unrecorded``): the same loop as a live worker steps it
   (``Session(record=False)``: no time series and no per-tick measurement, which only headless
   runs need; :func:`unrecorded_loop`), i.e. a classroom robot's tick before its frames.
2. **MuJoCo alone** (``bare_step_realtime_factor``): a second world of the same model and
   timestep, servo targets held at the walk-ready keyframe, only ``mj_step``, as many
   substeps as the closed loop ran. Half is run before and half after the closed loops so a
   change of machine load during the run biases the figures alike.
3. **QP back-ends** (``qp_backends``): every QP the four layers built during a real walk (a
   separate session, same parameters, same ticks) is recorded, then the sequence is re-solved by
   a fresh :class:`controller.qp.QpSolver` per back-end (warm starts as in the loop). Reported
   per layer and back-end: median / p99 time of ``QpSolver.solve`` (what the controller pays,
   wrapper included) and the max deviation from the exact solution, i.e. a cold one-shot
   DAQP solve of the same QP (an exact active-set solution: its KKT system is solved directly).
4. **Peer** (``peer``): placo's walk loop (its walk pattern generator and whole-body
   kinematics QP, no physics) on our robot, in the same run, with our step timing and length,
   re-planning over a fixed horizon of a few steps as placo's walk example does, so its
   re-planning tick does not grow with ``ticks`` (``app/bench/peer.py``, in an interpreter
   that has placo: ``--peer-python``, ``$PELVIC_WALK_PEER_PYTHON`` or the checkout's
   ``.venv-peers`` of ``make peers``; placo pins Pinocchio 3.8, so it lives in its own
   venv). The URDF it loads is written from our MJCF at run time (:func:`urdf_from_mjcf`).
   Without placo the bench says so and runs the rest.
5. **CPU time**: the ``*_cpu`` extras repeat the figures in CPU time of this process
   (``tick_ms_cpu_*`` from a second session), which other jobs on the machine disturb less.
6. **Paced at 1x** (``paced_core_share``): one robot in a live loop with real sleeps, as a
   worker runs it (frames at the default display rate), for ``ticks`` x 5 ms of wall time after
   it has caught up with its time base: the CPU time of its thread per simulated second, i.e.
   the share of a core a robot takes at real time, sleeps and wake-ups included (what limits how
   many robots a core holds: ``robots_per_core_paced``).

Timings are wall-clock and depend on the machine and its load: ``machine`` records the CPU
count and the load averages at the start and the end of the run.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

import daqp
import mujoco
import numpy as np

from controller import strategy
from controller.params import ControllerParams
from controller.qp import INF, QP, QpSolver, frozen
from pelvic_walk.core.run import RunConfig, Session
from pelvic_walk.core.world import JOINTS, World

STEP_LENGTH = 0.3  # [m]
METHOD = strategy.MPC
BACKENDS = ("daqp", "osqp")
QP_LAYERS = ("ik", "arm_swing", "pelvis_mpc", "com_mpc")


def bench_params(n_ticks: int, control_dt: float = 0.005) -> ControllerParams:
    """mpc, arms on, step 0.3 m, with enough steps for the warm-up and ``n_ticks`` ticks."""
    base = ControllerParams()
    steps = max(10, math.ceil(n_ticks * control_dt / base.walk.step_time) + 2)
    return base.replace(method=METHOD, walk={"step_length": STEP_LENGTH, "n_steps": steps})


def _warmup_ticks(session: Session) -> int:
    """Ticks of the initial stand (before the first step): run but not measured."""
    return int(round(session.walker.plan.t_start / session.params.control_dt))


def closed_loop(ticks: int) -> dict[str, Any]:
    """Tick times and the real-time factor of one closed-loop robot, as a run steps it (the
    walker's per-layer clock off: :func:`layer_split` reads the layers in a second session)."""
    session = Session(RunConfig(params=bench_params(ticks)))
    warm = _warmup_ticks(session)
    for _ in range(warm):
        session.tick()
    split0 = dict(session.time_split)
    cpu0 = time.process_time()
    start = time.perf_counter()
    for _ in range(ticks):  # what run() does per tick
        session.tick()
    wall = time.perf_counter() - start
    cpu = time.process_time() - cpu0
    tick = session.series.column("tick_ms", last=ticks)
    sim_time = ticks * session.params.control_dt
    return {
        "tick_ms_median": float(np.median(tick)),
        "tick_ms_p99": float(np.percentile(tick, 99)),
        "tick_ms_max": float(np.max(tick)),
        "tick_ms_mean": float(np.mean(tick)),
        # mean per tick: the controller, MuJoCo (the substeps and their copies) and the
        # measurement (contacts, CoP, support polygon, series row, bookkeeping)
        "time_split_ms": {k: (v - split0[k]) / ticks * 1e3 for k, v in session.time_split.items()},
        "sim_time": sim_time,
        "wall_time": wall,
        "cpu_time": cpu,
        "realtime_factor": sim_time / wall,
        "warmup_ticks": warm,
        "fell": bool(session.fell),
        "substeps": ticks * session.world.n_substeps,
        "sim_dt": session.world.sim_dt,
        "control_dt": session.params.control_dt,
    }


def layer_split(ticks: int) -> dict[str, Any]:
    """Per layer, in a closed-loop session of its own with the walker's per-layer clock on
    (``Walker.layer_times``): the median and mean time, and for the four QP layers the split
    into DAQP's solve (its own clock: the active-set iterations on the factored problem) and
    the rest (the problem's build, DAQP's update of its factors, the data's way in and out
    between Python, the compiled step and C; ``pelvis_mpc``'s also holds eq. (19)'s pelvis,
    the reference of eq. (27)-(33) and the strategy's inputs, as ``layer_ms`` does)."""
    session = Session(RunConfig(params=bench_params(ticks)))
    walker = session.walker
    walker.layer_times = True
    for _ in range(_warmup_ticks(session)):
        session.tick()
    layer_s: list[dict[str, float]] = []
    solve_s: dict[str, list[float]] = {name: [] for name in QP_LAYERS}
    for _ in range(ticks):
        layer_s.append(session.tick().layer_s)
        for name, solver in _layer_solvers(walker).items():
            qp = solver.last_qp
            ms = solver.last_stats(qp)[1] if qp is not None else math.nan
            solve_s[name].append(ms * 1e-3)
    names = list(layer_s[0])
    mean = {n: float(np.mean([d[n] for d in layer_s])) * 1e3 for n in names}
    solve = {n: float(np.nanmean(v)) * 1e3 for n, v in solve_s.items() if np.isfinite(v).any()}
    return {
        "layer_ms": {n: float(np.median([d[n] for d in layer_s])) * 1e3 for n in names},
        # means too: the plan's table is filled again every 100 ticks, which no median shows
        "layer_ms_mean": mean,
        "layer_solve_ms_mean": solve,
        "layer_build_ms_mean": {n: mean[n] - solve[n] for n in solve},
    }


def _layer_solvers(walker: Any) -> dict[str, QpSolver]:
    """The QP solvers of the walker's four layers (the pelvic MPC's: the paper's strategy)."""
    mpc = getattr(walker.strategy.strategy, "mpc", None)
    solvers = {"com_mpc": walker.com_mpc.solver, "ik": walker.ik_solver}
    if mpc is not None:
        solvers["pelvis_mpc"] = mpc.solver
    if walker.params.arms.enabled:
        solvers["arm_swing"] = walker.arm_solver
    return solvers


def open_loop(ticks: int) -> dict[str, Any]:
    """The controller tick in a walk loop without physics, as the peer's loop runs: the walker
    reads back its own commanded joints as measured, tick after tick (the same parameters and
    warm-up as :func:`closed_loop`; no simulation step between two ticks)."""
    session = Session(RunConfig(params=bench_params(ticks)), record=False)
    walker = session.walker
    for _ in range(_warmup_ticks(session)):
        walker.tick(walker.q_cmd)
    clock, out = time.perf_counter, np.empty(ticks)
    for i in range(ticks):
        t0 = clock()
        walker.tick(walker.q_cmd)
        out[i] = clock() - t0
    ms = out * 1e3
    return {
        "tick_ms_median": float(np.median(ms)),
        "tick_ms_mean": float(np.mean(ms)),
        "tick_ms_p99": float(np.percentile(ms, 99)),
        "tick_ms_max": float(np.max(ms)),
    }


def unrecorded_loop(ticks: int) -> dict[str, Any]:
    """The closed loop as a live worker steps it: ``Session(record=False)`` (controller, MuJoCo,
    the energy at step starts and the fall test; no time series, no per-tick measurement, no
    frames), after the same warm-up. What one classroom robot costs per tick before its
    display (the frames are in :func:`live_loop`)."""
    session = Session(RunConfig(params=bench_params(ticks)), record=False)
    for _ in range(_warmup_ticks(session)):
        session.tick()
    cpu0 = time.process_time()
    start = time.perf_counter()
    for _ in range(ticks):
        session.tick()
    wall = time.perf_counter() - start
    cpu = time.process_time() - cpu0
    sim_time = ticks * session.params.control_dt
    return {"sim_time": sim_time, "wall_time": wall, "cpu_time": cpu}


def live_loop(ticks: int) -> dict[str, Any]:
    """One robot in a live loop, unpaced, its frames pickled at the display rate as a worker
    sends them: how many robots one worker process holds at 1.0x real time."""
    import pickle

    from app.live.loop import LiveLoop
    from app.live.session import initial_intent

    intent = initial_intent(bench_params(ticks), [METHOD])
    sent = [0]

    def publish(frame: Any) -> None:
        sent[0] += len(pickle.dumps(frame, protocol=pickle.HIGHEST_PROTOCOL))

    loop = LiveLoop(lambda: intent, publish, sleep=lambda _s: None)
    loop.iterate()  # build the robot
    warm = int(round(1.0 / intent.params.control_dt))
    for _ in range(warm):
        loop.iterate()
    start, clock0 = time.perf_counter(), loop.clock
    for _ in range(ticks):
        loop.iterate()
    rtf = (loop.clock - clock0) / (time.perf_counter() - start)
    return {
        "live_loop_realtime_factor": rtf,
        # headroom kept for frames, plot rows and the scheduler of a busy machine
        "robots_per_worker": max(1, int(np.floor(0.8 * rtf))),
        "frame_bytes_per_s": sent[0] / (time.perf_counter() - start),
    }


def paced_loop(ticks: int) -> dict[str, Any]:
    """One robot in a live loop paced to the wall clock at 1x (module docstring, item 6)."""
    from app.live.loop import LiveLoop
    from app.live.session import initial_intent
    from app.web.settings import Settings

    params = bench_params(ticks + 600)
    display_hz = Settings.model_fields["display_hz"].default  # what `serve` sends workers
    # the time base starts now, so the robot is built on time and walks at once
    intent = dataclasses.replace(initial_intent(params, [METHOD]), anchor=(time.monotonic(), 0.0))
    loop = LiveLoop(lambda: intent, lambda _frame: None, publish_hz=display_hz)
    loop.iterate()  # build the robot
    walking = loop.robots[METHOD].session.plan.t_start + 0.2  # [s] past the initial stand
    deadline = time.monotonic() + 20.0
    while loop.clock < walking or loop.ahead(intent) < -0.01:  # then caught up
        loop.iterate()
        if time.monotonic() > deadline:  # a machine too busy to catch up: measure anyway
            break
    cpu0, clock0, wall0 = time.thread_time(), loop.clock, time.monotonic()
    seconds = ticks * intent.params.control_dt
    while time.monotonic() - wall0 < seconds:
        loop.iterate()
    share = (time.thread_time() - cpu0) / max(loop.clock - clock0, 1e-9)
    return {
        "paced_core_share": share,
        "paced_realtime_factor": (loop.clock - clock0) / (time.monotonic() - wall0),
        "robots_per_core_paced": max(1, int(np.floor(1.0 / share))),
    }


def tick_cpu_ms(ticks: int) -> np.ndarray:
    """Per-tick CPU time [ms] of ``Walker.tick`` in a second closed-loop session.

    CPU time of this process, so time spent waiting for a core while other jobs run is not
    counted (the wall-clock figures above include it). A separate session keeps the measured
    loop free of the extra clock calls.
    """
    session = Session(RunConfig(params=bench_params(ticks)))
    walker = session.walker
    for _ in range(_warmup_ticks(session)):
        session.tick()
    tick, out = walker.tick, []
    clock = time.process_time

    def timed(q_meas: np.ndarray):
        t0 = clock()
        result = tick(q_meas)
        out.append(clock() - t0)
        return result

    walker.tick = timed  # type: ignore[method-assign]
    for _ in range(ticks):
        session.tick()
    return np.array(out) * 1e3


def bare_steps(n_substeps: int, sim_dt: float, control_dt: float) -> tuple[float, float, float]:
    """(simulated, wall, CPU time) of ``n_substeps`` mj_step calls, targets at the keyframe."""
    world = World(sim_dt, control_dt)
    world.data.ctrl[world.act_idx] = world.keyframe_joints()
    m, d = world.model, world.data
    for _ in range(200):  # warm-up (caches, contacts settle)
        mujoco.mj_step(m, d)
    cpu0 = time.process_time()
    start = time.perf_counter()
    for _ in range(n_substeps):
        mujoco.mj_step(m, d)
    wall = time.perf_counter() - start
    return n_substeps * sim_dt, wall, time.process_time() - cpu0


def record_qps(ticks: int) -> dict[str, list[QP]]:
    """The QPs each layer built during ``ticks`` walking ticks (after the warm-up).

    Matrices the layer kept (the same object as on the previous tick) stay shared in the
    record, so a re-solve sees the same identity pattern as the loop (see controller.qp).
    """
    session = Session(RunConfig(params=bench_params(ticks)))
    w = session.walker
    record: dict[str, list[QP]] = {name: [] for name in QP_LAYERS}
    recording = [False]
    for _ in range(_warmup_ticks(session)):
        session.tick()
    solvers = _layer_solvers(w)  # the paper's method, arms on (bench_params): all four
    assert set(solvers) == set(QP_LAYERS)
    for name, solver in solvers.items():
        solver.compiled_steps = False  # each layer builds its QP and calls solve (the same QPs)
        _wrap(solver, record[name], recording)
    recording[0] = True
    for _ in range(ticks):
        session.tick()
    return record


def _wrap(solver: QpSolver, out: list[QP], recording: list[bool]) -> None:
    original = solver.solve
    last: dict[str, Any] = {}

    def solve(qp: QP):
        if recording[0]:
            P = last["P"] if qp.P is last.get("P_obj") else _copy(qp.P)
            A = last["A"] if qp.A is last.get("A_obj") else _copy(qp.A)
            last.update(P=P, A=A, P_obj=qp.P, A_obj=qp.A)
            out.append(QP(P, qp.q.copy(), A, qp.l.copy(), qp.u.copy()))
        return original(qp)

    solver.solve = solve  # type: ignore[method-assign]


def _copy(a: np.ndarray) -> np.ndarray:
    """A copy that is read-only if the original was (the solver's identity shortcut)."""
    return a.copy() if a.flags.writeable else frozen(a.copy())


def exact_solution(qp: QP) -> np.ndarray:
    """Cold one-shot DAQP solve (no warm start): the exact active-set solution."""
    bu = np.minimum(qp.u, INF)
    bl = np.maximum(qp.l, -INF)
    sense = np.where(np.abs(bu - bl) < 1e-12, 5, 0).astype(np.intc)
    x, _, flag, _ = daqp.solve(
        np.require(qp.P, dtype=float, requirements=("C", "W")),
        np.ascontiguousarray(qp.q),
        np.require(qp.A, dtype=float, requirements=("C", "W")),
        bu,
        bl,
        sense,
    )
    if flag < 1:
        raise RuntimeError(f"reference QP solve failed (daqp exitflag {flag})")
    return np.asarray(x)


def compare_backends(record: dict[str, list[QP]]) -> dict[str, Any]:
    """Per layer: size, and per back-end median / p99 solve time [us], max deviation, failures."""
    out: dict[str, Any] = {}
    for name in QP_LAYERS:
        qps = record[name]
        if not qps:
            continue
        exact = [exact_solution(qp) for qp in qps]
        row: dict[str, Any] = {
            "n_qps": len(qps),
            "n_vars": int(qps[0].P.shape[0]),
            "n_constraints": int(qps[0].A.shape[0]),
        }
        for backend in BACKENDS:
            solver = QpSolver(backend)
            times, dev, fails = [], 0.0, 0
            for qp, x_ref in zip(qps, exact, strict=True):
                t0 = time.perf_counter()
                res = solver.solve(qp)
                times.append(time.perf_counter() - t0)
                fails += int(not res.ok)
                dev = max(dev, float(np.max(np.abs(res.x - x_ref))))
            us = np.array(times) * 1e6
            row[backend] = {
                "solve_us_median": float(np.median(us)),
                "solve_us_p99": float(np.percentile(us, 99)),
                "max_abs_dev": dev,
                "failures": fails,
            }
        out[name] = row
    return out


# -- the peer (placo) ---------------------------------------------------------------------
PEER_PYTHON_ENV = "PELVIC_WALK_PEER_PYTHON"  # an interpreter with placo (its own venv)
PEER_FRAMES = {"pelvis": "trunk", "L_sole": "left_foot", "R_sole": "right_foot"}


def urdf_from_mjcf(xml: str | Path) -> str:
    """A URDF of the robot in ``xml`` (our MJCF), written from MuJoCo's compiled model.

    Links are the bodies (the root body is named ``trunk``, as placo's humanoid expects),
    with their mass and principal inertia; each hinge becomes a revolute joint with its axis
    and range, a body without one a fixed joint; the sole sites become fixed frames
    ``left_foot`` / ``right_foot``. No geometry: the peer runs kinematics only.
    """
    m = mujoco.MjModel.from_xml_path(str(xml))

    def name(obj_type: int, i: int) -> str:
        n = mujoco.mj_id2name(m, obj_type, i)
        return PEER_FRAMES.get(n, n)

    def origin(pos: np.ndarray, quat: np.ndarray) -> str:
        w, x, y, z = quat  # rpy of R = Rz(yaw) Ry(pitch) Rx(roll) (URDF's fixed axes)
        roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
        yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        return (
            f'<origin xyz="{pos[0]:.9g} {pos[1]:.9g} {pos[2]:.9g}" '
            f'rpy="{roll:.9g} {pitch:.9g} {yaw:.9g}"/>'
        )

    body = int(mujoco.mjtObj.mjOBJ_BODY)
    lines = ['<?xml version="1.0"?>', f'<robot name="{m.names[: m.names.index(0)].decode()}">']
    for b in range(1, m.nbody):
        ixx, iyy, izz = m.body_inertia[b]
        lines += [
            f'  <link name="{name(body, b)}"><inertial>{origin(m.body_ipos[b], m.body_iquat[b])}'
            f'<mass value="{m.body_mass[b]:.9g}"/><inertia ixx="{ixx:.9g}" iyy="{iyy:.9g}" '
            f'izz="{izz:.9g}" ixy="0" ixz="0" iyz="0"/></inertial></link>'
        ]
        parent = int(m.body_parentid[b])
        if parent == 0:
            continue  # the root: placo adds the floating base
        hinges = [
            j
            for j in range(m.body_jntadr[b], m.body_jntadr[b] + m.body_jntnum[b])
            if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE
        ]
        joint = origin(m.body_pos[b], m.body_quat[b])
        link = f'<parent link="{name(body, parent)}"/><child link="{name(body, b)}"/>'
        if hinges:
            j = hinges[0]
            lo, hi = m.jnt_range[j]
            ax = m.jnt_axis[j]
            lines.append(
                f'  <joint name="{name(int(mujoco.mjtObj.mjOBJ_JOINT), j)}" type="revolute">'
                f'{joint}{link}<axis xyz="{ax[0]:.9g} {ax[1]:.9g} {ax[2]:.9g}"/>'
                f'<limit lower="{lo:.9g}" upper="{hi:.9g}" effort="300" velocity="10"/></joint>'
            )
        else:
            lines.append(
                f'  <joint name="{name(body, b)}_fixed" type="fixed">{joint}{link}</joint>'
            )
    site = int(mujoco.mjtObj.mjOBJ_SITE)
    for s in range(m.nsite):
        frame = name(site, s)
        if frame in ("left_foot", "right_foot"):
            lines += [
                f'  <link name="{frame}"/>',
                f'  <joint name="{frame}_fixed" type="fixed">'
                f"{origin(m.site_pos[s], m.site_quat[s])}"
                f'<parent link="{name(body, int(m.site_bodyid[s]))}"/><child link="{frame}"/>'
                "</joint>",
            ]
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def peer_python() -> str | None:
    """The interpreter that runs placo: $PELVIC_WALK_PEER_PYTHON, else the one ``make peers``
    made in the checkout (``.venv-peers``), else this one if it has placo, else None (placo is
    not installed)."""
    import importlib.util

    env = os.environ.get(PEER_PYTHON_ENV)
    if env:
        return env
    made = Path(__file__).resolve().parents[2] / ".venv-peers" / "bin" / "python"
    if made.exists():
        return str(made)
    return sys.executable if importlib.util.find_spec("placo") is not None else None


def peer_loop(ticks: int, python: str | None = None) -> dict[str, Any]:
    """placo's walk loop on our robot (``app/bench/peer.py``) in ``python``; our walking
    timing, sizes and step length; {"installed": False} without placo."""
    import subprocess
    import tempfile

    from models.dyros_jet import FOOT_SIZE, ROBOT_XML

    python = python or peer_python()
    if python is None:
        return {"installed": False, "reason": "placo is not installed"}
    session = Session(RunConfig(params=bench_params(ticks)))
    p, w = session.params, session.walker
    q0 = session.world.keyframe_joints()
    held = {n: float(q) for n, q in zip(JOINTS, q0, strict=True) if not n.startswith(("L_", "R_"))}
    held.update(
        {n: float(q) for n, q in zip(JOINTS, q0, strict=True) if "shoulder" in n or "elbow" in n}
    )
    with tempfile.TemporaryDirectory() as tmp:
        urdf = Path(tmp) / "robot.urdf"
        urdf.write_text(urdf_from_mjcf(ROBOT_XML))
        cfg = {
            "urdf": str(urdf),
            "dt": p.control_dt,
            "step_length": p.walk.step_length,
            "step_time": p.walk.step_time,
            "dsp_ratio": p.walk.dsp_ratio,
            "foot_height": p.walk.foot_height,
            "step_width": p.walk.step_width,
            "foot_size": list(FOOT_SIZE),
            "zmp_margin": p.com.zmp_margin,
            "com_height": w.com_height,
            "held_joints": held,
            "ssp_timesteps": 10,
            "planned_timesteps": 48,
            "replan_timesteps": 10,
            "warmup_ticks": _warmup_ticks(session),
            "ticks": ticks,
        }
        script = Path(__file__).with_name("peer.py")
        done = subprocess.run(
            [python, str(script), json.dumps(cfg)], capture_output=True, text=True, timeout=600
        )
    if done.returncode != 0:
        tail = (done.stderr or done.stdout).strip().splitlines()[-1:] or ["no output"]
        return {"installed": True, "error": f"{python}: {tail[0]}"}
    return {"installed": True, "python": python, **json.loads(done.stdout.strip().splitlines()[-1])}


def run_bench(ticks: int = 600, peer_python_path: str | None = None) -> dict[str, Any]:
    """All the figures of one bench run (see the module docstring)."""
    load0 = os.getloadavg()
    probe = World()
    sim_dt, control_dt, n_sub = probe.sim_dt, probe.control_dt, probe.n_substeps
    half = ticks * n_sub // 2
    bare_sim, bare_wall, bare_cpu = bare_steps(half, sim_dt, control_dt)
    loop = closed_loop(ticks)
    unrecorded = unrecorded_loop(ticks)
    layers = layer_split(ticks)
    kinematic = open_loop(ticks)
    s2, w2, c2 = bare_steps(ticks * n_sub - half, sim_dt, control_dt)
    bare_sim, bare_wall, bare_cpu = bare_sim + s2, bare_wall + w2, bare_cpu + c2
    bare_rtf = bare_sim / bare_wall
    # The same figures in CPU time of this process: less sensitive to other jobs on the
    # machine (time spent waiting for a core is not counted).
    loop_rtf_cpu = loop["sim_time"] / loop["cpu_time"]
    bare_rtf_cpu = bare_sim / bare_cpu
    unrec_rtf = unrecorded["sim_time"] / unrecorded["wall_time"]
    unrec_rtf_cpu = unrecorded["sim_time"] / unrecorded["cpu_time"]
    tick_cpu = tick_cpu_ms(ticks)
    live = live_loop(ticks)
    paced = paced_loop(ticks)
    qp = compare_backends(record_qps(ticks))
    peer = peer_loop(ticks, peer_python_path)
    return {
        "tick_ms_median": loop["tick_ms_median"],
        "tick_ms_p99": loop["tick_ms_p99"],
        "layer_ms": layers["layer_ms"],
        "layer_ms_mean": layers["layer_ms_mean"],
        "layer_solve_ms_mean": layers["layer_solve_ms_mean"],
        "layer_build_ms_mean": layers["layer_build_ms_mean"],
        "open_loop": kinematic,
        "realtime_factor": loop["realtime_factor"],
        "bare_step_realtime_factor": bare_rtf,
        "overhead_ratio": bare_rtf / loop["realtime_factor"],
        "robots_per_worker": live["robots_per_worker"],
        "live_loop_realtime_factor": live["live_loop_realtime_factor"],
        "time_split_ms": loop["time_split_ms"],
        **paced,
        # extras
        "tick_ms_max": loop["tick_ms_max"],
        "tick_ms_mean": loop["tick_ms_mean"],
        "tick_ms_cpu_median": float(np.median(tick_cpu)),
        "tick_ms_cpu_p99": float(np.percentile(tick_cpu, 99)),
        "ticks": ticks,
        "warmup_ticks": loop["warmup_ticks"],
        "method": METHOD,
        "arms": True,
        "step_length": STEP_LENGTH,
        "backend": RunConfig().backend,
        "sim_dt": sim_dt,
        "control_dt": control_dt,
        "closed_loop_wall_s": loop["wall_time"],
        "bare_step_wall_s": bare_wall,
        "realtime_factor_cpu": loop_rtf_cpu,
        "bare_step_realtime_factor_cpu": bare_rtf_cpu,
        "overhead_ratio_cpu": bare_rtf_cpu / loop_rtf_cpu,
        "realtime_factor_unrecorded": unrec_rtf,
        "overhead_ratio_unrecorded": bare_rtf / unrec_rtf,
        "realtime_factor_unrecorded_cpu": unrec_rtf_cpu,
        "overhead_ratio_unrecorded_cpu": bare_rtf_cpu / unrec_rtf_cpu,
        "fell": loop["fell"],
        "qp_backends": qp,
        "peer": peer,
        "machine": {
            "cpu_count": os.cpu_count(),
            "loadavg_start": list(load0),
            "loadavg_end": list(os.getloadavg()),
            "python": sys.version.split()[0],
            "platform": platform.platform(),
            "numpy": np.__version__,
            "mujoco": mujoco.__version__,
        },
    }


def format_report(r: dict[str, Any]) -> str:
    """A short human-readable summary of :func:`run_bench`'s figures."""
    lines = [
        f"bench: method {r['method']}, arms on, step {r['step_length']} m, back-end "
        f"{r['backend']}, {r['ticks']} ticks after a {r['warmup_ticks']}-tick warm-up",
        f"controller tick      median {r['tick_ms_median']:.3f} ms   p99 "
        f"{r['tick_ms_p99']:.3f} ms   max {r['tick_ms_max']:.3f} ms   (budget 5 ms at 200 Hz)",
        f"  in CPU time        median {r['tick_ms_cpu_median']:.3f} ms   p99 "
        f"{r['tick_ms_cpu_p99']:.3f} ms",
        "per layer (median)   "
        + "   ".join(f"{k} {v:.3f}" for k, v in r["layer_ms"].items())
        + "  [ms]",
        "per layer (mean)     "
        + "   ".join(f"{k} {v:.3f}" for k, v in r["layer_ms_mean"].items())
        + "  [ms]",
        "  QP layers (mean)   "
        + "   ".join(
            f"{k} {1e3 * r['layer_build_ms_mean'][k]:.1f} + {1e3 * v:.1f}"
            for k, v in r["layer_solve_ms_mean"].items()
        )
        + "  [us]: build, update and data + DAQP's solve (its own clock)",
        "time per tick        "
        + "   ".join(f"{k} {v:.3f}" for k, v in r["time_split_ms"].items())
        + "  [ms]",
        f"live loop            real-time factor {r['live_loop_realtime_factor']:.1f} (one "
        f"robot, frames included): a worker holds {r['robots_per_worker']} robots at 1.0x",
        f"paced at 1x          {r['paced_core_share']:.2f} of a core per robot (CPU per "
        f"simulated second, sleeps included; factor {r['paced_realtime_factor']:.2f}): a core "
        f"holds {r['robots_per_core_paced']} robots at 1.0x",
        f"real-time factor     closed loop {r['realtime_factor']:.1f}   MuJoCo alone "
        f"{r['bare_step_realtime_factor']:.1f}   overhead ratio {r['overhead_ratio']:.2f}   "
        f"(CPU time: {r['realtime_factor_cpu']:.1f} / {r['bare_step_realtime_factor_cpu']:.1f}"
        f" / {r['overhead_ratio_cpu']:.2f})",
        f"  unrecorded (live)  closed loop {r['realtime_factor_unrecorded']:.1f}   overhead "
        f"ratio {r['overhead_ratio_unrecorded']:.2f}   (CPU time: "
        f"{r['realtime_factor_unrecorded_cpu']:.1f} / {r['overhead_ratio_unrecorded_cpu']:.2f}):"
        " a live robot's tick, no series, frames aside",
        "QP back-ends (QpSolver.solve on the QPs of a real walk; deviation from the exact "
        "solution):",
        f"  {'layer':11s} {'size':>8s}   {'daqp med/p99 [us]':>18s} {'max dev':>9s}   "
        f"{'osqp med/p99 [us]':>18s} {'max dev':>9s}",
    ]
    for name, row in r["qp_backends"].items():
        size = f"{row['n_vars']}x{row['n_constraints']}"
        cells = []
        for b in BACKENDS:
            c = row[b]
            cells.append(
                f"{c['solve_us_median']:8.1f}/{c['solve_us_p99']:<9.1f} {c['max_abs_dev']:9.1e}"
            )
        lines.append(f"  {name:11s} {size:>8s}   " + "   ".join(cells))
    peer = r["peer"]
    if not peer.get("installed"):
        lines.append(
            f"peer: placo's walk loop not run: {peer.get('reason', 'placo is not installed')} "
            f"(an interpreter with placo: --peer-python PATH or ${PEER_PYTHON_ENV})"
        )
    elif "error" in peer:
        lines.append(f"peer: placo's walk loop failed: {peer['error']}")
    else:
        o = r["open_loop"]
        lines += [
            f"peer: {peer['name']}, our timing and step length, same ticks, re-planning "
            f"over {peer['steps_ahead']} steps ({peer['horizon_s']:.1f} s) ahead",
            f"  {'tick [ms]':26s} {'median':>8s} {'mean':>8s} {'p99':>8s} {'max':>8s}"
            "   mean / placo's",
            f"  {'ours, closed loop':26s} {r['tick_ms_median']:8.3f} {r['tick_ms_mean']:8.3f} "
            f"{r['tick_ms_p99']:8.3f} {r['tick_ms_max']:8.3f}   "
            f"{r['tick_ms_mean'] / peer['tick_ms_mean']:.2f}x  (MuJoCo steps between ticks)",
            f"  {'ours, no physics':26s} {o['tick_ms_median']:8.3f} {o['tick_ms_mean']:8.3f} "
            f"{o['tick_ms_p99']:8.3f} {o['tick_ms_max']:8.3f}   "
            f"{o['tick_ms_mean'] / peer['tick_ms_mean']:.2f}x  (tick after tick, as placo's)",
            f"  {'placo':26s} {peer['tick_ms_median']:8.3f} {peer['tick_ms_mean']:8.3f} "
            f"{peer['tick_ms_p99']:8.3f} {peer['tick_ms_max']:8.3f}   (re-planning ticks "
            f"{100 * peer['replan_tick_share']:.1f} % ({peer['replans']}), median "
            f"{peer['replan_tick_ms_median'] or math.nan:.1f} ms, in CPU time "
            f"{peer['replan_tick_ms_cpu_median'] or math.nan:.1f} ms)",
        ]
    m = r["machine"]
    lines.append(
        f"machine: {m['cpu_count']} CPUs, load average {m['loadavg_start'][0]:.2f} at start, "
        f"{m['loadavg_end'][0]:.2f} at end"
    )
    return "\n".join(lines)


def main(json_path: Path | None, ticks: int = 600, peer_python_path: str | None = None) -> int:
    """Run the bench, print the summary, write the figures to ``json_path`` if given."""
    if ticks < 1:
        print("pelvic-walk bench: error: --ticks must be at least 1", file=sys.stderr)
        return 2
    report = run_bench(ticks, peer_python_path)
    print(format_report(report))
    if json_path is not None:
        Path(json_path).write_text(json.dumps(report, indent=2))
    return 0
