"""The shared QP solvers: constant matrices are frozen, and a changed matrix is never missed."""

from __future__ import annotations

import numpy as np
import pytest

from controller.ik import BOUND_ROWS
from controller.qp import QP, QpSolver, frozen, solve_exact


def _qp(P: np.ndarray, A: np.ndarray) -> QP:
    return QP(P, np.array([1.0, -2.0]), A, np.full(2, -10.0), np.full(2, 10.0))


@pytest.mark.parametrize("backend", ["daqp", "osqp"])
def test_a_matrix_changed_in_place_is_not_missed(backend):
    """A writable P edited in place between solves: the solver sees the new values."""
    P, A = np.eye(2), frozen(np.eye(2))
    solver = QpSolver(backend)
    first = solver.solve(_qp(P, A))
    assert first.ok
    np.testing.assert_allclose(first.x, [-1.0, 2.0], atol=1e-6)
    P *= 4.0  # in place, same object
    second = solver.solve(_qp(P, A))
    np.testing.assert_allclose(second.x, solve_exact(_qp(P, A)), atol=1e-6)
    np.testing.assert_allclose(second.x, [-0.25, 0.5], atol=1e-6)


def test_constant_matrices_are_read_only():
    with pytest.raises(ValueError, match="read-only"):
        BOUND_ROWS[0, 0] = 2.0
    P = frozen(np.eye(2))
    with pytest.raises(ValueError, match="read-only"):
        P *= 2.0


def _model_replay(qps: list[QP]) -> list[np.ndarray]:
    """The same QPs through DAQP's own Python interface (``daqp.Model``), called as the
    solver calls DAQP's C functions: set up once, then the vectors every solve, P or A when
    they are not the frozen objects of the solve before, the senses when an equality row
    changed (else DAQP keeps its working set)."""
    import daqp

    model, out, eq, P_obj, A_obj = daqp.Model(), [], None, None, None
    for P, q, A, l, u in qps:
        bu, bl = np.minimum(u, 1e20), np.maximum(l, -1e20)
        new_eq = np.abs(u - l) < 1e-12
        sense = new_eq.astype(np.intc) * 5
        if eq is None:
            model.setup(np.array(P, order="C"), q.copy(), np.array(A, order="C"), bu, bl, sense)
        else:
            kw = {}
            if not (P is P_obj and not P.flags.writeable):
                kw["H"] = np.array(P, order="C")
            if not (A is A_obj and not A.flags.writeable):
                kw["A"] = np.array(A, order="C")
            if not np.array_equal(new_eq, eq):
                kw["sense"] = sense
            model.update(f=q.copy(), bupper=bu, blower=bl, **kw)
        eq, P_obj, A_obj = new_eq, P, A
        x, _fval, exitflag, _info = model.solve()
        assert exitflag >= 1
        out.append(x)
    return out


def test_daqp_from_compiled_code_equals_daqps_own_interface():
    """The solver calls DAQP's C functions from a kernel, on its own structures (the layouts
    of DAQP's headers): over a walk's QPs of every layer, warm starts, matrix and sense
    updates included, its solutions equal daqp.Model's bit for bit."""
    from app.bench.timings import record_qps

    for layer, qps in record_qps(300).items():
        solver = QpSolver("daqp")
        ours = [solver.solve(qp) for qp in qps]
        assert all(r.ok for r in ours), layer
        for k, (r, x) in enumerate(zip(ours, _model_replay(qps), strict=True)):
            assert np.array_equal(r.x, x), (layer, k)


def test_daqp_equality_rows_that_come_and_go_equal_daqps_own_interface():
    """Rows that turn into equalities and back (the IK's waist row between methods) and a
    matrix that changes: the senses and the factors are updated as daqp.Model updates them."""
    rng = np.random.default_rng(3)
    A = frozen(rng.normal(size=(3, 4)))  # full row rank: every box of Ax is feasible
    qps = []
    for k in range(60):
        M = rng.normal(size=(4, 4))
        P = M @ M.T + np.eye(4) if k % 7 == 0 or not qps else qps[-1].P
        l, u = -rng.uniform(0.05, 0.5, 3), rng.uniform(0.05, 0.5, 3)
        rows = rng.random(3) < 0.4  # some rows pinned at a value
        l[rows] = u[rows] = rng.uniform(-0.2, 0.2, rows.sum())
        qps.append(QP(frozen(P) if k % 7 else P, rng.normal(size=4), A, l, u))
    solver = QpSolver("daqp")
    for k, (qp, x) in enumerate(zip(qps, _model_replay(qps), strict=True)):
        r = solver.solve(qp)
        assert r.ok and np.array_equal(r.x, x), k


def test_daqp_failures_fall_back_and_the_next_solve_recovers():
    """Crossed bounds, a non-finite vector and an infeasible QP each fail without raising,
    return the last solution, are counted, and the solver sets up anew for the next QP."""
    A = frozen(np.eye(2))
    solver = QpSolver("daqp")
    good = _qp(np.eye(2), A)
    first = solver.solve(good)
    assert first.ok
    crossed = good._replace(l=np.array([1.0, -10.0]), u=np.array([0.0, 10.0]))
    nan_q = good._replace(q=np.array([np.nan, 0.0]))
    infeasible = QP(np.eye(2), np.zeros(2), frozen(np.array([[1.0, 0.0], [1.0, 0.0]])),
                    np.array([1.0, -10.0]), np.array([10.0, 0.0]))  # fmt: skip
    for bad, status in ((crossed, "infeasible bounds"), (nan_q, "non-finite"),
                        (infeasible, "daqp exitflag")):  # fmt: skip
        r = solver.solve(bad)
        assert not r.ok and status in r.status and np.array_equal(r.x, first.x)
        again = solver.solve(good)
        assert again.ok and np.array_equal(again.x, first.x)
    assert solver.failures == 3


def test_daqp_refuses_vectors_of_the_wrong_size():
    """A q, l or u whose size does not match A fails cleanly (the kernel writes DAQP's
    buffers by these sizes: it is never called with them)."""
    A = frozen(np.eye(2))
    solver = QpSolver("daqp")
    good = _qp(np.eye(2), A)
    assert solver.solve(good).ok
    for bad in (good._replace(q=np.ones(5)), good._replace(l=np.zeros(1)),
                good._replace(u=np.ones(3)), good._replace(P=np.eye(3))):  # fmt: skip
        r = solver.solve(bad)
        assert not r.ok and "do not match" in r.status
    assert solver.solve(good).ok and solver.failures == 4
