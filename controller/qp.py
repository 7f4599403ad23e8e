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
- ``"daqp"``: DAQP, an exact dual active-set solver for small dense QPs. One DAQP workspace
  per solver: set up once (Cholesky factor of P, constraint matrix), then each tick only the
  vectors are updated and the last active set is the warm start; P or A are refactored only
  when they change. DAQP's C functions are called from a compiled kernel, or through
  ``daqp.Model`` when that binding cannot be made (:mod:`controller.compiled`), the same
  calls either way. (Answering with the unconstrained optimum -P^-1 q when it is feasible,
  which it is on most ticks, was tried: in numpy it costs more instructions than DAQP's warm
  start, 4.57 vs 4.32 M per closed-loop tick under callgrind.)

Constant matrices are tracked by *identity*, and only read-only ones: a layer that keeps P or
A constant freezes it once per parameter change (:func:`frozen`) and passes the same array
every tick, and the solver never re-factors it; any writable matrix is taken as new at every
solve. Modifying a frozen matrix in place raises (numpy refuses), so the identity shortcut
cannot go stale.

A failed solve never raises: :meth:`QpSolver.solve` returns ``ok=False`` and the caller falls
back (holds its last command) and counts the failure. A failed solve is the solver's verdict
on the data (infeasible, non-finite, not converged); a programming error (a wrong argument, a
kernel that does not compile) raises as any error does.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
import osqp
import scipy.sparse as sp

from controller.compiled import INF, UPDATE_A, UPDATE_H, DaqpWorkspace, daqp_binding

# numpy's reductions called directly (ndarray.sum / .min add a Python-level wrapper per call)
_sum = np.add.reduce
_fmin = np.fmin.reduce  # the smallest value, NaNs ignored
_INVALID = "infeasible bounds or non-finite data"
_SIZES = "the sizes of P, q, l and u do not match A"
__all__ = ["INF", "QP", "QpResult", "QpSolver", "frozen", "solve_exact"]


def frozen(a: np.ndarray) -> np.ndarray:
    """``a`` made read-only (in place) and returned: a constant QP matrix (module docstring)."""
    a.setflags(write=False)
    return a


def _same(new: np.ndarray, old: np.ndarray | None) -> bool:
    """True if ``new`` is the read-only matrix the solver already has."""
    return new is old and not new.flags.writeable


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
        # DAQP's C functions, bound and checked at the first DAQP solver (None: daqp.Model)
        self._binding = daqp_binding() if backend == "daqp" else None
        self.eps = eps
        self.max_iter = max_iter
        self.polish = polish
        self.reset()

    def reset(self) -> None:
        self._solver: osqp.OSQP | None = None
        self._daqp: DaqpWorkspace | None = None
        self._shape: tuple[int, int] | None = None
        self._P_pattern: _Pattern | None = None
        self._A_pattern: _Pattern | None = None
        self._P_obj: np.ndarray | None = None  # the P / A last handed to the solver
        self._A_obj: np.ndarray | None = None
        self.x_prev: np.ndarray | None = None
        self.failures = 0
        # the last QP solved and its result, held (not copied) for an explanation on demand
        # (controller.explain); a tick does nothing more for it
        self.last_qp: QP | None = None
        self.last_result: QpResult | None = None
        self._osqp_info: Any = None

    # -- OSQP ------------------------------------------------------------------------------
    def _setup_osqp(self, qp: QP) -> None:
        n = qp.P.shape[0]
        # Dense patterns (upper triangle of P, all of A): values may become non-zero later,
        # and OSQP's update() needs a fixed pattern. Our QPs are small, so this costs little.
        self._P_pattern = _Pattern(np.triu(np.ones((n, n), dtype=bool)))
        self._A_pattern = _Pattern(np.ones(qp.A.shape, dtype=bool))
        s = osqp.OSQP()
        s.setup(
            self._P_pattern.matrix(qp.P),
            qp.q,
            self._A_pattern.matrix(qp.A),
            np.maximum(qp.l, -INF),
            np.minimum(qp.u, INF),
            verbose=False,
            eps_abs=self.eps,
            eps_rel=self.eps,
            polishing=self.polish,
            max_iter=self.max_iter,
            warm_starting=True,
            adaptive_rho=True,
        )
        self._solver = s
        self._shape = qp.A.shape
        self._P_obj, self._A_obj = qp.P, qp.A

    def _solve_osqp(self, qp: QP) -> tuple[np.ndarray | None, str]:
        try:  # OSQP's verdict on the data (e.g. a non-convex P) is an exception of its own
            if self._solver is None or self._shape != qp.A.shape:
                self._setup_osqp(qp)
                assert self._solver is not None
            else:
                assert self._P_pattern is not None and self._A_pattern is not None
                kw: dict[str, np.ndarray] = {}
                if not _same(qp.P, self._P_obj):
                    kw["Px"] = self._P_pattern.values(qp.P)
                    self._P_obj = qp.P
                if not _same(qp.A, self._A_obj):
                    kw["Ax"] = self._A_pattern.values(qp.A)
                    self._A_obj = qp.A
                l, u = np.maximum(qp.l, -INF), np.minimum(qp.u, INF)
                self._solver.update(q=qp.q, l=l, u=u, **kw)
        except osqp.OSQPException as exc:
            return None, f"osqp: {exc}"
        res = self._solver.solve(raise_error=False)
        self._osqp_info = res.info  # for last_stats
        status = str(res.info.status)
        if res.info.status_val not in (1, 2) or res.x is None or not math.isfinite(res.x.sum()):
            return None, status
        return np.array(res.x, dtype=float), status

    # -- DAQP ------------------------------------------------------------------------------
    # False: every layer builds its QP and calls solve() (tests compare the two ways)
    compiled_steps = True

    def step_args(self, P: np.ndarray | None, A: np.ndarray) -> tuple | None:
        """What a layer's compiled step hands :func:`controller.compiled.daqp_call` for a QP
        with constraint matrix ``A`` and Hessian ``P``: ``(mask, setup, *workspace args)``,
        P and A copied into DAQP's workspace (and checked) only when new, as :meth:`solve`
        does; ``P`` None: the step writes the Hessian into :attr:`hessian` itself (and
        checks it).
        None when no compiled step runs (OSQP, ``daqp.Model``, ``compiled_steps`` off, a new
        P or A that is not finite): the layer then builds its QP and calls :meth:`solve`.
        :meth:`settle` records the step's solve."""
        binding, work = self._binding, self._daqp
        if binding is None or not self.compiled_steps:
            return None
        if (  # the steady state: the workspace of this A, and of this P unless the step writes it
            work is not None
            and A is self._A_obj
            and not A.flags.writeable
            and (P is None or (P is self._P_obj and not P.flags.writeable))
        ):
            return (UPDATE_H if P is None else 0, False, *work.args)
        m, n = A.shape
        setup = work is None or work.shape != (m, n)
        # _same inlined (this runs four times a tick)
        new_P = P is None or setup or P is not self._P_obj or P.flags.writeable
        new_A = setup or A is not self._A_obj or A.flags.writeable
        if (P is not None and new_P and not math.isfinite(_sum(P, None))) or (
            new_A and not math.isfinite(_sum(A, None))
        ):
            return None
        if setup:
            work = self._daqp = DaqpWorkspace(m, n, binding)
        assert work is not None
        if new_P:
            if P is not None:
                work.H[...] = P
            self._P_obj = P
        if new_A:
            work.A[...] = A
            self._A_obj = A
        mask = (UPDATE_H if new_P else 0) | (UPDATE_A if new_A else 0)
        return (mask, setup, *work.args)

    @property
    def hessian(self) -> np.ndarray:
        """DAQP's Hessian buffer, for a step that writes its own (after :meth:`step_args`)."""
        assert self._daqp is not None
        return self._daqp.H

    def settle(self, qp: QP, x: np.ndarray, status: int, flag: int, setup: bool) -> QpResult:
        """Record a compiled step's solve of ``qp`` (``x``, and ``status``, ``flag`` and
        ``setup`` as :func:`controller.compiled.daqp_call` and :meth:`step_args` gave them)
        as :meth:`solve` records its own; the same result, fallback and failure count."""
        if status == 0:  # as _finish's success
            self.x_prev = x
            self.last_qp, res = qp, QpResult(x, True, "solved")
            self.last_result = res
            return res
        if self._daqp is not None:
            self._daqp.failed(status, setup)
        return self._finish(qp, None, _daqp_status(status, flag, setup))

    def _solve_daqp(self, qp: QP) -> tuple[np.ndarray | None, str]:
        """DAQP on the QP (:class:`controller.compiled.DaqpWorkspace`): P and A copied to the
        workspace (and checked) only when new, the vectors every call."""
        P, q, A, l, u = qp
        work = self._daqp
        setup = work is None or work.shape != A.shape
        # _same inlined (this runs four times a tick)
        new_P = setup or P is not self._P_obj or P.flags.writeable
        new_A = setup or A is not self._A_obj or A.flags.writeable
        m, n = A.shape
        if q.shape != (n,) or l.shape != (m,) or u.shape != (m,) or P.shape != (n, n):
            return None, _SIZES  # the workspace's buffers have these sizes
        if (new_P and not math.isfinite(_sum(P, None))) or (
            new_A and not math.isfinite(_sum(A, None))
        ):
            return None, _INVALID
        if setup:
            work = self._daqp = DaqpWorkspace(m, n, self._binding)
        assert work is not None
        if new_P:
            work.H[...] = P
            self._P_obj = P
        if new_A:
            work.A[...] = A
            self._A_obj = A
        x = np.empty(n)
        status, flag = work.solve(q, l, u, x, new_P, new_A, setup)
        return (x if status == 0 else None), _daqp_status(status, flag, setup)

    def solve(self, qp: QP) -> QpResult:
        """Solve; on failure return the previous solution (or zeros) with ok=False.

        Invalid data fails without calling the solver: a non-finite value in q, P or A
        (P and A already checked, the same frozen objects as last time, are not checked
        again) or crossed bounds (l > u beyond 1e-9; NaN bounds are left to the solver).
        An error that is not the solver's verdict on the data raises (module docstring).
        """
        if self.backend == "daqp":
            x, status = self._solve_daqp(qp)
        elif _valid(qp, self._P_obj, self._A_obj):
            x, status = self._solve_osqp(qp)
        else:
            x, status = None, _INVALID
        return self._finish(qp, x, status)

    def _finish(self, qp: QP, x: np.ndarray | None, status: str) -> QpResult:
        """The result of a solve (``x`` None: failed), kept for an explanation on demand."""
        if x is None:
            self.failures += 1
            fallback = self.x_prev if self.x_prev is not None else np.zeros(qp.q.shape[0])
            # re-setup next time: the workspace may be poisoned
            self._solver = self._daqp = None
            self._P_obj = self._A_obj = None
            self.last_qp, res = qp, QpResult(fallback, False, status)
            self.last_result = res
            return res
        self.x_prev = x
        self.last_qp, res = qp, QpResult(x, True, status)
        self.last_result = res
        return res

    # -- what the last solve did (controller.explain; not called in a tick) ----------------
    def last_duals(self, qp: QP) -> np.ndarray | None:
        """DAQP's multipliers (m,) of the last solve if it was ``qp`` and it succeeded (a
        view of the workspace: the next solve overwrites it), else None."""
        res = self.last_result
        if self._daqp is None or self.last_qp is not qp or res is None or not res.ok:
            return None
        return self._daqp.lam

    def last_stats(self, qp: QP) -> tuple[int, float]:
        """(iterations, solve time [ms]) of the last solve if it was ``qp`` (-1, NaN unknown)."""
        if self.last_qp is not qp:
            return -1, math.nan
        if self._daqp is not None:
            return int(self._daqp.stats()[1]), self._daqp.solve_time() * 1e3
        info = self._osqp_info
        if info is not None:
            return int(info.iter), float(info.solve_time) * 1e3
        return -1, math.nan

    def active_count(self) -> float:
        """Constraints active at the last solution (DAQP: its non-zero duals; OSQP: rows at a
        bound), NaN before any solve or after a failed one. Cheap: the series reads it every
        tick."""
        res = self.last_result
        if res is None or not res.ok:
            return math.nan
        if self._daqp is not None:
            return float(np.count_nonzero(self._daqp.lam))
        qp = self.last_qp
        assert qp is not None
        ax = qp.A @ res.x
        tol = 1e-7 * (1.0 + np.abs(qp.u))
        return float(np.count_nonzero((np.abs(ax - qp.u) <= tol) | (np.abs(ax - qp.l) <= tol)))


def _daqp_status(status: int, flag: int, setup: bool) -> str:
    """The words for a DAQP solve's (status, flag) (:meth:`DaqpWorkspace.solve`)."""
    if status == 0:
        return "solved"
    if status == -1:
        return _INVALID
    if status == -2:
        return f"daqp {'setup' if setup else 'update'} flag {flag}"
    return f"daqp exitflag {flag}"


def _valid(qp: QP, P_known: np.ndarray | None, A_known: np.ndarray | None) -> bool:
    """Finite q, P, A (P and A unchecked when they are the frozen ones already checked;
    a sum is finite iff every term is, barring overflow near 1e308) and bounds not crossed."""
    P, q, A, l, u = qp
    gap = u - l
    return (
        math.isfinite(_sum(q))
        and (_same(P, P_known) or math.isfinite(_sum(P, None)))
        and (_same(A, A_known) or math.isfinite(_sum(A, None)))
        and not (len(gap) and _fmin(gap) < -1e-9)
    )


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


def solve_exact(qp: QP, active_tol: float = 1e-9) -> np.ndarray:
    """Reference solution by DAQP (exact active set); used by tests to check OSQP."""
    r = QpSolver("daqp").solve(qp)
    if not r.ok:
        raise RuntimeError(f"reference QP solve failed: {r.status}")
    return r.x
