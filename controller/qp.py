"""Small QP containers and solvers shared by every layer.

Every layer *builds* its QP as a :class:`QP` (``min 1/2 x'Px + q'x  s.t.  l <= A x <= u``)
and *solves* it with a :class:`QpSolver`, so tests can check the matrices and the UI can
show what is active (pink's ``build_ik`` / ``solve_ik``).

Two back-ends:
- ``"osqp"``: OSQP (ADMM). Set up once for a sparsity pattern, then only vectors (and values)
  are updated each tick; warm-started from the previous solution; tight tolerances (1e-8)
  because the default 1e-3 leaves errors of tens of percent on our small QPs. Polishing is
  off by default: OSQP 1.1 prints "Polishing not needed" on stdout at every solve without an
  active constraint, even with verbose=False, which floods a 200 Hz loop's console.
- ``"daqp"``: DAQP, an exact dual active-set solver for small dense QPs.

A failed solve never raises: :meth:`QpSolver.solve` returns ``ok=False`` and the caller falls
back (holds its last command) and counts the failure.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import osqp
import scipy.sparse as sp

INF = 1e20  # OSQP's infinity; DAQP takes the same large bound


class QP(NamedTuple):
    """min 1/2 x' P x + q' x  s.t.  l <= A x <= u (dense arrays)."""

    P: np.ndarray  # (n, n) symmetric positive semidefinite
    q: np.ndarray  # (n,)
    A: np.ndarray  # (m, n)
    l: np.ndarray  # (m,)
    u: np.ndarray  # (m,)


class QpResult(NamedTuple):
    x: np.ndarray  # (n,) solution (the previous one when ok is False)
    ok: bool
    status: str


class QpSolver:
    """Solves a sequence of QPs of one fixed shape, warm-starting each from the last.

    The sparsity of P and A is fixed at the first solve; later calls update the values.
    Call :meth:`reset` when the problem's shape changes (e.g. a new horizon).
    """

    def __init__(
        self, backend: str = "daqp", eps: float = 1e-8, max_iter: int = 20000, polish: bool = False
    ):
        if backend not in ("osqp", "daqp"):
            raise ValueError(f"unknown QP backend {backend!r} (osqp or daqp)")
        self.backend = backend
        self.eps = eps
        self.max_iter = max_iter
        self.polish = polish
        self.reset()

    def reset(self) -> None:
        self._solver: osqp.OSQP | None = None
        self._shape: tuple[int, int] | None = None
        self._P_pattern: _Pattern | None = None
        self._A_pattern: _Pattern | None = None
        self._P_key: int | None = None
        self._A_key: int | None = None
        self.x_prev: np.ndarray | None = None
        self.failures = 0

    # -- OSQP ------------------------------------------------------------------------------
    def _setup_osqp(self, qp: QP) -> None:
        n = qp.P.shape[0]
        # Dense patterns (upper triangle of P, all of A): values may become non-zero later,
        # and OSQP's update() needs a fixed pattern. Our QPs are small, so this costs little.
        self._P_pattern = _Pattern(np.triu(np.ones((n, n), dtype=bool)))
        self._A_pattern = _Pattern(np.ones(qp.A.shape, dtype=bool))
        s = osqp.OSQP()
        s.setup(
            self._P_pattern.matrix(qp.P), qp.q, self._A_pattern.matrix(qp.A),
            np.maximum(qp.l, -INF), np.minimum(qp.u, INF),
            verbose=False, eps_abs=self.eps, eps_rel=self.eps, polishing=self.polish,
            max_iter=self.max_iter, warm_starting=True, adaptive_rho=True,
        )
        self._solver = s
        self._shape = qp.A.shape
        self._P_key = _key(qp.P)
        self._A_key = _key(qp.A)

    def _solve_osqp(self, qp: QP) -> tuple[np.ndarray | None, str]:
        if self._solver is None or self._shape != qp.A.shape:
            self._setup_osqp(qp)
            assert self._solver is not None
        else:
            kw: dict[str, np.ndarray] = {}
            pk, ak = _key(qp.P), _key(qp.A)
            if pk != self._P_key:
                kw["Px"] = self._P_pattern.values(qp.P)
                self._P_key = pk
            if ak != self._A_key:
                kw["Ax"] = self._A_pattern.values(qp.A)
                self._A_key = ak
            self._solver.update(
                q=qp.q, l=np.maximum(qp.l, -INF), u=np.minimum(qp.u, INF), **kw
            )
        res = self._solver.solve(raise_error=False)
        status = str(res.info.status)
        if res.info.status_val not in (1, 2) or res.x is None or not np.all(np.isfinite(res.x)):
            return None, status
        return np.asarray(res.x, dtype=float).copy(), status

    # -- DAQP ------------------------------------------------------------------------------
    def _solve_daqp(self, qp: QP) -> tuple[np.ndarray | None, str]:
        import daqp

        H = np.ascontiguousarray(qp.P, dtype=float)
        f = np.ascontiguousarray(qp.q, dtype=float)
        A = np.ascontiguousarray(qp.A, dtype=float)
        bu = np.ascontiguousarray(np.minimum(qp.u, INF), dtype=float)
        bl = np.ascontiguousarray(np.maximum(qp.l, -INF), dtype=float)
        sense = np.where(np.abs(bu - bl) < 1e-12, 5, 0).astype(np.int32)
        x, _fval, exitflag, _info = daqp.solve(H, f, A, bu, bl, sense)
        if exitflag < 1 or not np.all(np.isfinite(x)):
            return None, f"daqp exitflag {exitflag}"
        return np.asarray(x, dtype=float).copy(), "solved"

    def solve(self, qp: QP) -> QpResult:
        """Solve; on failure return the previous solution (or zeros) with ok=False."""
        try:
            if np.any(qp.l > qp.u + 1e-9) or not (
                np.isfinite(qp.P).all() and np.isfinite(qp.q).all() and np.isfinite(qp.A).all()
            ):
                x, status = None, "infeasible bounds or non-finite data"
            elif self.backend == "osqp":
                x, status = self._solve_osqp(qp)
            else:
                x, status = self._solve_daqp(qp)
        except Exception as exc:  # a solver error must never crash the control loop
            x, status = None, f"error: {exc}"
        if x is None:
            self.failures += 1
            fallback = self.x_prev if self.x_prev is not None else np.zeros(qp.q.shape[0])
            if self.backend == "osqp":
                self._solver = None  # re-setup next time: the workspace may be poisoned
            return QpResult(fallback, False, status)
        self.x_prev = x
        return QpResult(x, True, status)


class _Pattern:
    """A fixed CSC sparsity pattern and the (row, col) of each stored value, in CSC order."""

    def __init__(self, mask: np.ndarray):
        m = sp.csc_matrix(mask.astype(float))
        self.indices, self.indptr, self.shape = m.indices.copy(), m.indptr.copy(), m.shape
        self.rows = m.indices
        self.cols = np.repeat(np.arange(mask.shape[1]), np.diff(m.indptr))

    def values(self, dense: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(dense[self.rows, self.cols], dtype=float)

    def matrix(self, dense: np.ndarray) -> sp.csc_matrix:
        return sp.csc_matrix((self.values(dense), self.indices, self.indptr), shape=self.shape)


def _key(M: np.ndarray) -> int:
    """Cheap change detector for a matrix's values (identity of content)."""
    return hash(M.tobytes())


def solve_exact(qp: QP, active_tol: float = 1e-9) -> np.ndarray:
    """Reference solution by DAQP (exact active set); used by tests to check OSQP."""
    r = QpSolver("daqp").solve(qp)
    if not r.ok:
        raise RuntimeError(f"reference QP solve failed: {r.status}")
    return r.x
