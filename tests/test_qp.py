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
