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
  when they change. DAQP's C functions are called from a compiled kernel (the section "DAQP's
  C API" below), the same calls in the same order as the ``daqp.Model`` of its Python
  package, whose per-call conversions cost more than DAQP's own work on these QPs.
  (Answering with the unconstrained optimum -P^-1 q when it is feasible, which it is on most
  ticks, was tried: in numpy it costs more instructions than DAQP's warm start, 4.57 vs
  4.32 M per closed-loop tick under callgrind.)

Constant matrices are tracked by *identity*, and only read-only ones: a layer that keeps P or
A constant freezes it once per parameter change (:func:`frozen`) and passes the same array
every tick, and the solver never re-factors it; any writable matrix is taken as new at every
solve. Modifying a frozen matrix in place raises (numpy refuses), so the identity shortcut
cannot go stale.

A failed solve never raises: :meth:`QpSolver.solve` returns ``ok=False`` and the caller falls
back (holds its last command) and counts the failure.
"""

from __future__ import annotations

import ctypes
import math
import weakref
from typing import NamedTuple

import daqp
import llvmlite.binding
import numpy as np
import osqp
import scipy.sparse as sp
from numba import types

from controller.jit import kernel

INF = 1e20  # OSQP's infinity; DAQP takes the same large bound
# numpy's reductions called directly (ndarray.sum / .min add a Python-level wrapper per call)
_sum = np.add.reduce
_fmin = np.fmin.reduce  # the smallest value, NaNs ignored
_INVALID = "infeasible bounds or non-finite data"
_SIZES = "the sizes of P, q, l and u do not match A"
_EQUALITY = 5  # DAQP's sense of an equality row (l = u)


# -- DAQP's C API ---------------------------------------------------------------------------
# daqp.Model (DAQP's Python package) wraps three C functions: Model.setup calls
# setup_daqp(problem, work, &setup_time), Model.update daqp_update_ldp(mask, work, problem),
# Model.solve daqp_solve(result, work). Its Python side (argument conversion, an info dict and
# two copies per solve) cost 2-3 us a call, more than DAQP's own work on most of our QPs. The
# kernel below makes the same calls in the same order, on buffers a _DaqpWork owns, so its
# solutions equal Model's bit for bit (tests/test_qp.py replays a walk's QPs through both).
# The structures are DAQP's DAQPProblem and DAQPResult (its types.h and api.h; pyproject.toml
# admits the minor version this was tested with); the workspace is DAQP's own, zeroed here
# and freed by DAQP's free functions, as Model does.
_DAQP = ctypes.CDLL(daqp.__file__)  # the extension module exports DAQP's C functions
for _name in ("setup_daqp", "daqp_update_ldp", "daqp_solve"):  # resolvable by cached kernels
    llvmlite.binding.add_symbol(_name, ctypes.cast(getattr(_DAQP, _name), ctypes.c_void_p).value)
_setup_daqp = types.ExternalFunction(
    "setup_daqp", types.intc(types.voidptr, types.voidptr, types.voidptr)
)
_daqp_update_ldp = types.ExternalFunction(
    "daqp_update_ldp", types.intc(types.intc, types.voidptr, types.voidptr)
)
_daqp_solve = types.ExternalFunction("daqp_solve", types.void(types.voidptr, types.voidptr))
_UPDATE_H, _UPDATE_A, _UPDATE_F, _UPDATE_BOUNDS, _UPDATE_SENSE = 1, 2, 4, 8, 16  # Model's mask


class _DaqpProblem(ctypes.Structure):  # DAQP's DAQPProblem
    _fields_ = [
        ("n", ctypes.c_int),
        ("m", ctypes.c_int),
        ("ms", ctypes.c_int),  # simple bounds: none here (A holds every row)
        ("H", ctypes.c_void_p),
        ("f", ctypes.c_void_p),
        ("A", ctypes.c_void_p),
        ("bupper", ctypes.c_void_p),
        ("blower", ctypes.c_void_p),
        ("sense", ctypes.c_void_p),
        ("break_points", ctypes.c_void_p),
        ("nh", ctypes.c_int),
        ("problem_type", ctypes.c_int),
    ]


class _DaqpResult(ctypes.Structure):  # DAQP's DAQPResult
    _fields_ = [
        ("x", ctypes.c_void_p),
        ("lam", ctypes.c_void_p),
        ("fval", ctypes.c_double),
        ("soft_slack", ctypes.c_double),
        ("exitflag", ctypes.c_int),
        ("iter", ctypes.c_int),
        ("nodes", ctypes.c_int),
        ("solve_time", ctypes.c_double),
        ("setup_time", ctypes.c_double),
    ]


_EXITFLAG = _DaqpResult.exitflag.offset // 4  # as an index of the result's int32 view
_WORKSPACE_BYTES = 4096  # zeroed room for DAQPWorkspace (a few hundred bytes)
_libc = ctypes.CDLL(None)
_libc.calloc.restype = ctypes.c_void_p
_libc.calloc.argtypes = [ctypes.c_size_t, ctypes.c_size_t]
_libc.free.argtypes = [ctypes.c_void_p]
for _name in ("free_daqp_workspace", "free_daqp_ldp", "allocate_daqp_settings"):
    getattr(_DAQP, _name).argtypes = [ctypes.c_void_p]


def _free_workspace(work: int) -> None:
    """What Model's deallocation does: DAQP frees what it allocated, then the workspace."""
    _DAQP.free_daqp_workspace(work)
    _DAQP.free_daqp_ldp(work)
    _libc.free(work)


class _DaqpWork:
    """A DAQP workspace for QPs of one shape and the buffers its problem points into."""

    def __init__(self, m: int, n: int):
        self.shape = (m, n)
        self.H, self.A = np.zeros((n, n)), np.zeros((m, n))
        self.f, self.x = np.zeros(n), np.zeros(n)
        self.bu, self.bl, self.lam = np.zeros(m), np.zeros(m), np.zeros(m)
        self.sense = np.zeros(m, dtype=np.intc)
        self.eq = np.zeros(m, dtype=np.bool_)  # which rows are equalities (|u - l| < 1e-12)
        self.setup_time = np.zeros(1)
        ptr = ctypes.c_void_p
        self._problem = _DaqpProblem(
            n, m, 0, *(ptr(a.ctypes.data) for a in (self.H, self.f, self.A, self.bu, self.bl)),
            ptr(self.sense.ctypes.data), None, 0, 0,
        )  # fmt: skip
        self.problem = ctypes.addressof(self._problem)
        # the result's memory as int32s (the kernel reads the exitflag), the structure on it
        self.result = np.zeros(ctypes.sizeof(_DaqpResult) // 4, dtype=np.int32)
        result = _DaqpResult.from_address(self.result.ctypes.data)  # self.result keeps it
        result.x, result.lam = self.x.ctypes.data, self.lam.ctypes.data
        self.work = _libc.calloc(1, _WORKSPACE_BYTES)
        if not self.work:
            raise MemoryError("DAQP workspace")
        self._finalizer = weakref.finalize(self, _free_workspace, self.work)

    def failed_setup(self) -> None:
        """After a failed setup_daqp: settings as Model restores them (DAQP freed its own)."""
        _DAQP.allocate_daqp_settings(self.work)


@kernel
def _daqp_call(q, l, u, eq, f, bu, bl, sense, x, out, mask, setup, work, problem, result, t):
    """One DAQP solve of min 1/2 x'Hx + q'x, l <= Ax <= u on the workspace ``work``.

    Checks the vectors (q finite, no bound pair crossed beyond 1e-9), writes DAQP's bounds
    (min(u, INF), max(l, -INF); NaN passes to the solver) and f = q, marks the equality rows
    ``eq`` (DAQP's sense 5), then: with ``setup``, setup_daqp on H and A as they are;
    otherwise daqp_update_ldp with ``mask`` (H, A) plus the vectors, plus the senses if an
    equality row changed (else DAQP keeps its working set: the warm start). Then daqp_solve
    and the solution copied to ``out``.

    Returns (status, flag): 0 solved; -1 invalid vectors; -2 setup or update failed (its
    flag); -3 exitflag < 1 or a non-finite solution (the exitflag).
    """
    for i in range(q.shape[0]):
        if not math.isfinite(q[i]):
            return -1, 0
    changed = setup
    for i in range(l.shape[0]):
        gap = u[i] - l[i]
        if gap < -1e-9:
            return -1, 0
        bu[i] = INF if u[i] > INF else u[i]
        bl[i] = -INF if l[i] < -INF else l[i]
        is_eq = abs(gap) < 1e-12
        if eq[i] != is_eq:
            eq[i] = is_eq
            changed = True
    for i in range(q.shape[0]):
        f[i] = q[i]
    if changed:
        for i in range(eq.shape[0]):
            sense[i] = _EQUALITY if eq[i] else 0
    if setup:
        flag = _setup_daqp(problem, work, t.ctypes.data)
    else:
        mask |= _UPDATE_F | _UPDATE_BOUNDS
        if changed:
            mask |= _UPDATE_SENSE
        flag = _daqp_update_ldp(mask, work, problem)
    if flag < 0:
        return -2, flag
    _daqp_solve(result.ctypes.data, work)
    exitflag = result[_EXITFLAG]
    if exitflag < 1:
        return -3, exitflag
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            return -3, exitflag
        out[i] = x[i]
    return 0, exitflag


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
        self.eps = eps
        self.max_iter = max_iter
        self.polish = polish
        self.reset()

    def reset(self) -> None:
        self._solver: osqp.OSQP | None = None
        self._daqp: _DaqpWork | None = None
        self._shape: tuple[int, int] | None = None
        self._P_pattern: _Pattern | None = None
        self._A_pattern: _Pattern | None = None
        self._P_obj: np.ndarray | None = None  # the P / A last handed to the solver
        self._A_obj: np.ndarray | None = None
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
            self._solver.update(q=qp.q, l=np.maximum(qp.l, -INF), u=np.minimum(qp.u, INF), **kw)
        res = self._solver.solve(raise_error=False)
        status = str(res.info.status)
        if res.info.status_val not in (1, 2) or res.x is None or not math.isfinite(res.x.sum()):
            return None, status
        return np.array(res.x, dtype=float), status

    # -- DAQP ------------------------------------------------------------------------------
    def _solve_daqp(self, qp: QP) -> tuple[np.ndarray | None, str]:
        """DAQP on the QP through :func:`_daqp_call`: P and A copied to the workspace (and
        checked) only when new, the vectors every call."""
        P, q, A, l, u = qp
        work = self._daqp
        setup = work is None or work.shape != A.shape
        # _same inlined (this runs four times a tick)
        new_P = setup or P is not self._P_obj or P.flags.writeable
        new_A = setup or A is not self._A_obj or A.flags.writeable
        m, n = A.shape
        if q.shape != (n,) or l.shape != (m,) or u.shape != (m,) or P.shape != (n, n):
            return None, _SIZES  # the kernel writes the workspace's buffers by these sizes
        if (new_P and not math.isfinite(_sum(P, None))) or (
            new_A and not math.isfinite(_sum(A, None))
        ):
            return None, _INVALID
        if setup:
            work = self._daqp = _DaqpWork(*A.shape)
        assert work is not None
        mask = 0
        if new_P:
            work.H[...] = P
            self._P_obj, mask = P, mask | _UPDATE_H
        if new_A:
            work.A[...] = A
            self._A_obj, mask = A, mask | _UPDATE_A
        x = np.empty(n)
        status, flag = _daqp_call(
            q, l, u, work.eq, work.f, work.bu, work.bl, work.sense, work.x, x, mask, setup,
            work.work, work.problem, work.result, work.setup_time,
        )  # fmt: skip
        if status == -1:
            return None, _INVALID
        if status == -2:
            if setup:
                work.failed_setup()
            return None, f"daqp {'setup' if setup else 'update'} flag {flag}"
        if status == -3:
            return None, f"daqp exitflag {flag}"
        return x, "solved"

    def solve(self, qp: QP) -> QpResult:
        """Solve; on failure return the previous solution (or zeros) with ok=False.

        Invalid data fails without calling the solver: a non-finite value in q, P or A
        (P and A already checked, the same frozen objects as last time, are not checked
        again) or crossed bounds (l > u beyond 1e-9; NaN bounds are left to the solver).
        """
        try:
            if self.backend == "daqp":
                x, status = self._solve_daqp(qp)
            elif _valid(qp, self._P_obj, self._A_obj):
                x, status = self._solve_osqp(qp)
            else:
                x, status = None, _INVALID
        except Exception as exc:  # a solver error must never crash the control loop
            x, status = None, f"error: {exc}"
        if x is None:
            self.failures += 1
            fallback = self.x_prev if self.x_prev is not None else np.zeros(qp.q.shape[0])
            # re-setup next time: the workspace may be poisoned
            self._solver = self._daqp = None
            self._P_obj = self._A_obj = None
            return QpResult(fallback, False, status)
        self.x_prev = x
        return QpResult(x, True, status)


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
