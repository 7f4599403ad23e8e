"""The compiled layer (controller/compiled.py): switched off it runs the same walk as plain
Python; a DAQP binding that cannot be made falls back to daqp.Model with one warning and the
same results; errors that are not a solver's verdict raise; a run whose QPs all fail is no
success."""

from __future__ import annotations

import ast
import json
import math
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from controller import compiled
from controller.params import ControllerParams
from controller.qp import QP, QpSolver, frozen
from pelvic_walk.core.run import RunConfig, Session, run, summarize
from pelvic_walk.core.summary import MISSED_FOOTHOLDS, SOLVER_FAILURES, TIMING_KEYS

ROOT = Path(__file__).resolve().parents[1]
TIMING = set(TIMING_KEYS)


def _params(method: str = "mpc", length: float = 0.3, steps: int = 4) -> ControllerParams:
    return ControllerParams().replace(method=method, walk=dict(step_length=length, n_steps=steps))


def _simulate_json(tmp_path: Path, name: str, env: dict[str, str], *argv: str) -> dict:
    """``pelvic-walk simulate ... --json`` in a fresh process with ``env`` added."""
    out = tmp_path / f"{name}.json"
    proc = subprocess.run(
        [sys.executable, *argv, "--json", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=ROOT,
        env={**os.environ, **env},
    )
    assert proc.returncode == 0, proc.stderr
    return json.loads(out.read_text())


def _assert_same_summary(ours: dict, theirs: dict, rel: float = 1e-9) -> None:
    """Every key equal (floats within ``rel``, lists element by element), timing aside."""
    assert set(ours) == set(theirs)
    for key in set(ours) - TIMING:
        a, b = ours[key], theirs[key]
        if isinstance(a, list) and a and isinstance(a[0], float):
            np.testing.assert_allclose(a, b, rtol=rel, atol=0, err_msg=key)
        elif isinstance(a, float) and isinstance(b, float):
            assert a == pytest.approx(b, rel=rel, abs=0) or (math.isnan(a) and math.isnan(b)), key
        else:
            assert a == b, key


@pytest.mark.slow
def test_switched_off_the_walk_is_the_compiled_one(tmp_path):
    """NUMBA_DISABLE_JIT=1 (numba's switch to step through kernels in pdb): the same code as
    plain Python, DAQP through ctypes; the summary equals the compiled run's, no QP fails."""
    argv = ("-m", "app.cli", "simulate", "--method", "mpc", "--step-length", "0.3")
    plain = _simulate_json(tmp_path, "plain", {"NUMBA_DISABLE_JIT": "1"}, *argv, "--steps", "4")
    compiled_run = summarize(run(RunConfig(params=_params())))
    assert plain["solver_failures"] == 0 and plain["success"], plain["unsuccessful"]
    _assert_same_summary(plain, json.loads(json.dumps(compiled_run)))


@pytest.mark.slow
def test_without_numba_the_walk_is_the_compiled_one(tmp_path):
    """numba not installed (its import fails): kernels are the plain functions, same walk."""
    script = (
        "import sys; sys.modules['numba'] = None\n"  # `import numba` raises ImportError
        "from controller import compiled\n"
        "assert not compiled.JIT and compiled.kernel(len) is len\n"
        "from app.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    argv = ("simulate", "--method", "redundancy", "--step-length", "0.3", "--steps", "1")
    plain = _simulate_json(tmp_path, "no_numba", {}, "-c", script, *argv)
    _assert_same_summary(plain, json.loads(json.dumps(summarize(run(RunConfig(
        params=_params("redundancy", 0.3, 1)))))))  # fmt: skip


def _daqp_fails(monkeypatch) -> None:
    """DAQP reports every QP infeasible (exit flag -1), on both ways a layer solves: its
    compiled step (the status it hands QpSolver.settle) and QpSolver.solve."""
    settle = QpSolver.settle
    monkeypatch.setattr(
        QpSolver,
        "settle",
        lambda self, qp, x, status, flag, setup: settle(self, qp, x, -3, -1, setup),
    )
    monkeypatch.setattr(compiled.DaqpWorkspace, "solve", lambda self, *args: (-3, -1))


@pytest.fixture
def unbound(monkeypatch):
    """The binding not made yet in this process (made again at the next DAQP solver)."""
    monkeypatch.setattr(compiled, "_binding", None)
    monkeypatch.setattr(compiled, "_binding_tried", False)
    return monkeypatch


BREAKS = {
    "another DAQP version": lambda mp: mp.setattr(
        compiled.importlib.metadata, "version", lambda name: "0.12.0"
    ),
    "a missing symbol": lambda mp: mp.setitem(
        compiled._FUNCTIONS, "daqp_no_such_function", ((), None)
    ),
    "a workspace larger than the header's": lambda mp: mp.setattr(
        compiled, "_WORKSPACE_BYTES", 64
    ),  # DAQP writes past it, into the checked guard
}


@pytest.mark.parametrize("why", BREAKS)
def test_a_binding_that_cannot_be_made_falls_back_to_daqp_model(unbound, why):
    """The binding cannot be made or fails its check: one warning that says why, then
    daqp.Model for every solver, with the direct binding's results (a walk, bit for bit)."""
    direct = summarize(run(RunConfig(params=_params("mpc", 0.3, 1))))
    BREAKS[why](unbound)
    unbound.setattr(compiled, "_binding", None)
    unbound.setattr(compiled, "_binding_tried", False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fallback = summarize(run(RunConfig(params=_params("mpc", 0.3, 1))))
        QpSolver("daqp")  # later solvers: no second warning
    daqp_warnings = [w for w in caught if "daqp.Model" in str(w.message)]
    assert len(daqp_warnings) == 1, [str(w.message) for w in caught]
    assert compiled.daqp_binding() is None
    assert fallback["solver_failures"] == 0
    _assert_same_summary(fallback, direct, rel=0.0)


def test_importing_the_solvers_binds_nothing():
    """Importing controller.qp (the OSQP back-end included) loads no DAQP library: the
    binding is made at the first DAQP solver."""
    script = (
        "import controller.qp, controller.compiled as c\n"
        "assert not c._binding_tried\n"
        "controller.qp.QpSolver('osqp')\n"
        "assert not c._binding_tried\n"
        "controller.qp.QpSolver('daqp')\n"
        "assert c._binding_tried and c._binding is not None\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=300, cwd=ROOT
    )
    assert proc.returncode == 0, proc.stderr


def test_a_compile_error_raises_at_the_first_solver_not_per_tick(unbound):
    """An error in the DAQP kernel is no solver verdict: it raises where the binding is
    checked (the first DAQP solver, at a run's start) with its message."""

    def broken(*args):
        raise TypeError("the kernel does not compile: boom")

    unbound.setattr(compiled, "daqp_call", broken)
    with pytest.raises(TypeError, match="boom"):
        QpSolver("daqp")


@pytest.mark.parametrize("backend", ["daqp", "osqp"])
def test_a_programming_error_is_not_counted_as_a_failed_qp(backend):
    """A wrong argument raises from solve() instead of becoming a counted QP failure."""
    solver = QpSolver(backend)
    A = frozen(np.eye(2))
    assert solver.solve(QP(np.eye(2), np.ones(2), A, -np.ones(2), np.ones(2))).ok
    with pytest.raises((AttributeError, TypeError)):
        solver.solve(QP(np.eye(2), np.ones(2), A, -np.ones(2), "not bounds"))  # type: ignore[arg-type]
    assert solver.failures == 0


def test_a_run_whose_qps_all_fail_is_no_success(unbound, capsys):
    """DAQP reports every QP infeasible: every layer falls back (the robot holds still), and
    the run is no success, with the reasons in the summary and on the command line."""
    from app.cli import main

    compiled.daqp_binding()  # made (and checked) before DAQP turns bad
    _daqp_fails(unbound)
    s = summarize(run(RunConfig(params=_params("mpc", 0.3, 1))))
    assert not s["fell"] and s["solver_failure_share"] == 1.0
    assert not s["success"] and SOLVER_FAILURES in s["unsuccessful"]
    assert MISSED_FOOTHOLDS in s["unsuccessful"]  # it never stepped
    argv = ["simulate", "--method", "fixed", "--step-length", "0.2", "--steps", "1"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "NO SUCCESS" in out and "QPs failed on 100 % of the ticks" in out


def test_numba_and_ctypes_stay_behind_the_compiled_layer():
    """Only controller/compiled.py imports numba, llvmlite or ctypes (app/ included)."""
    banned = {"numba", "llvmlite", "ctypes"}
    for path in [*(ROOT / "controller").glob("*.py"), *(ROOT / "app").rglob("*.py")]:
        if path.name == "compiled.py" and path.parent.name == "controller":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names = {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                names = {(node.module or "").split(".")[0]}
            else:
                continue
            assert not banned & names, f"{path.relative_to(ROOT)} imports {names}"


def test_a_live_walk_whose_qps_all_fail_finishes_with_no_success(unbound):
    """The live tool: a robot whose QPs all fail finishes its plan standing; its walk is no
    success, and its label says so and why."""
    import dataclasses

    from app.live.loop import LiveLoop
    from app.live.session import initial_intent
    from app.web.scene import label_text

    compiled.daqp_binding()
    _daqp_fails(unbound)
    params = ControllerParams().replace(walk={"n_steps": 1})
    intent = dataclasses.replace(initial_intent(params, ["fixed"]), anchor=(0.0, 0.0))
    frames: list = []
    wall = [0.0]

    def sleep(seconds: float) -> None:
        wall[0] += seconds

    loop = LiveLoop(
        lambda: intent, frames.append, clock=lambda: wall[0], sleep=sleep, publish_hz=1e6
    )
    while not frames or not frames[-1].robots[0].finished:
        loop.iterate()
    robot = frames[-1].robots[0]
    assert robot.walks_completed == 1 and robot.last_walk_success is False
    assert "QPs failed on 100 % of the ticks" in robot.unsuccessful
    assert "NO SUCCESS" in label_text(robot, frames[-1])


def _walk(monkeypatch, compiled_steps: bool, method: str) -> list[tuple]:
    """Per tick: the targets, the CoM and pelvic plans, and each layer's last QP."""
    monkeypatch.setattr(QpSolver, "compiled_steps", compiled_steps)
    params = _params(method, 0.3, 2).replace(arms={"enabled": method != "redundancy"})
    session = Session(RunConfig(params=params))
    w, out = session.walker, []
    for i in range(520):
        if i == 300:  # a replan and new gains mid-walk: the steps' constants follow
            w.replace_params(walk={"step_length": 0.25}, ik={"foot_gain": 25.0})
        o = session.tick()
        qps = [s.last_qp for s in (w.com_mpc.solver, w.ik_solver, w.arm_solver)]
        mpc = getattr(w.strategy.strategy, "mpc", None)
        if mpc is not None:
            qps.append(mpc.solver.last_qp)
        pelvis = o.pelvis_plan
        out.append(
            (
                o.q_target, o.q_dot, o.com_plan.com, o.com_plan.jerk, o.com_plan.next_state,
                o.theta_ref, o.lateral, (o.h_low, o.h_up, o.waist_rate, o.speed_limited),
                None if pelvis is None else (pelvis.angles, pelvis.rates, pelvis.acc,
                                             pelvis.reference, pelvis.next_rate),
                [None if qp is None else tuple(np.array(a, copy=True) for a in qp) for qp in qps],
            )
        )  # fmt: skip
    assert sum(w.failure_counts.values()) == 0
    return out


@pytest.mark.parametrize("method", ["mpc", "fixed", "redundancy"])
def test_the_compiled_steps_are_the_layers_calls_bit_for_bit(monkeypatch, method):
    """Each QP layer's compiled step (build, DAQP, outputs in one call) gives what its
    separate calls give (build the QP, QpSolver.solve, the outputs), bit for bit: the same
    targets, plans and QPs at every tick, through a replan and a change of gains."""
    steps = _walk(monkeypatch, True, method)
    calls = _walk(monkeypatch, False, method)
    assert len(steps) == len(calls)
    for i, (a, b) in enumerate(zip(steps, calls, strict=True)):
        np.testing.assert_equal(a, b, err_msg=f"tick {i}")


def test_every_kernel_cache_is_keyed_on_every_controller_module():
    """A kernel's compiled code holds the other modules' kernels it calls (a layer's step
    calls daqp_call): its cache is stale when any module of controller/ changes."""
    if not compiled.JIT:
        pytest.skip("numba switched off: nothing is cached")
    from controller import com_mpc, ik

    stamp = compiled._controller_stamp()
    assert {name for name, *_ in stamp} >= {"compiled.py", "com_mpc.py", "ik.py", "walker.py"}
    for kernel in (com_mpc._step, ik._step, compiled.daqp_call):
        assert kernel._cache._cache_file._source_stamp[1] == stamp
