"""The compiled layer of the controller: numba for a tick's arithmetic, DAQP's C functions.

The one module of ``controller/`` that knows numba, ctypes or DAQP's C structures; the
paper's modules write their equations as plain Python functions over small arrays and mark
the ones a tick calls with :func:`kernel`.

Why compile: a control tick is a few hundred operations on arrays of 2 to 32 numbers. numpy
pays about a microsecond of Python and dispatch per operation whatever the size, so the
tick's time was that overhead, spread over every layer (docs/PERFORMANCE.md). A kernel is
one plain function, compiled once by numba; there is one code path, and no kernel has a
Python twin.

**Switched off**, with numba's own switch ``NUMBA_DISABLE_JIT=1`` (to step through a layer in
pdb) or without numba installed, :func:`kernel` returns the function itself: the same code
runs as plain Python and numpy, and DAQP's C functions are called through ctypes, the same
calls in the same order. A walk's summary is then the compiled one's (tests/test_compiled.py);
a headless tick takes about 7 times the CPU (docs/DESIGN.md, "The compiled layer").

- numba compiles a kernel to machine code at its first call and caches it in the module's
  ``__pycache__``: a fresh checkout compiles once, later processes load the cache.
- Numerics: IEEE double precision without fast-math (no reassociation, no fused
  multiply-add), so a kernel's loop rounds as it reads, compiled or not. Scalar
  transcendental functions are ``math``'s (the C library's, in both modes; numpy's own
  vectorised ``arctan`` differs from it in the last bit on some arguments).
- ``error_model="numpy"``: a division by zero gives inf or NaN as in numpy (the QP solver's
  finiteness checks then see it) instead of raising.
- A kernel may call kernels of other modules of ``controller/`` (a layer's compiled step
  calls :func:`daqp_call`): numba's cache notices a change of the kernel's own file only,
  so every kernel's cache is also keyed on every module of ``controller/`` (a change to
  any of them compiles the kernels again in the next process).

**DAQP.** :class:`DaqpWorkspace` solves QPs of one shape through DAQP's C functions, called
from the kernel :func:`daqp_call`: ``daqp.Model`` (DAQP's Python interface) wraps the same
three functions, but its per-call conversions (an info dict, two copies) cost 2-3 us a call,
more than DAQP's own work on these QPs. The binding is made at the first DAQP solver, not at
import, and checked before use (:func:`daqp_binding`): the installed DAQP is the release
whose headers the structures below copy, its functions resolve, and a check sequence of QPs
(set-up, vector, sense and matrix updates) gives ``daqp.Model``'s solutions bit for bit
without DAQP writing past the workspace's size. When any of that fails the solvers use
``daqp.Model``, with the same calls in the same order (so the same results), after one
warning that says why.
"""

from __future__ import annotations

import ctypes
import importlib.metadata
import math
import os
import warnings
import weakref
from collections.abc import Callable
from typing import Any, TypeVar, cast

import daqp
import numpy as np


def _numba() -> Any:
    """numba, or None: absent, or switched off by its own ``NUMBA_DISABLE_JIT`` (then not
    even imported: a run switched off starts sooner)."""
    try:
        if int(os.environ.get("NUMBA_DISABLE_JIT", "0")):
            return None
    except ValueError:  # numba ignores a value that is not a number
        pass
    try:
        import numba
    except ImportError:  # the plain Python of every kernel runs instead
        return None
    return None if numba.config.DISABLE_JIT else numba  # type: ignore[attr-defined]


numba = _numba()
JIT: bool = numba is not None  # kernels are compiled
F = TypeVar("F", bound=Callable[..., Any])


def kernel(fn: F) -> F:
    """``fn`` compiled by numba (nopython, cached, GIL released while it runs), or ``fn``
    itself when the compiled layer is switched off (module docstring)."""
    if not JIT:
        return fn
    compiled = numba.njit(cache=True, nogil=True, error_model="numpy")(fn)
    _key_on_controller(compiled)
    return cast(F, compiled)


def _key_on_controller(compiled: Any) -> None:
    """Key the kernel's cache on every module of ``controller/``: a kernel that calls
    another module's (a layer's step calls :func:`daqp_call`) holds its compiled code,
    which numba's cache, keyed on the kernel's own file only, would keep after that file
    changed. If numba's cache has no such key (another release), the kernel is not cached
    (compiled in every process: slower to start, never stale)."""
    cache_file = getattr(getattr(compiled, "_cache", None), "_cache_file", None)
    if cache_file is not None and hasattr(cache_file, "_source_stamp"):
        cache_file._source_stamp = (cache_file._source_stamp, _CONTROLLER_STAMP)
    else:
        compiled._cache = numba.core.caching.NullCache()


def _controller_stamp() -> tuple:
    """(name, mtime, size) of every module of ``controller/``."""
    folder = os.path.dirname(os.path.abspath(__file__))
    names = sorted(n for n in os.listdir(folder) if n.endswith(".py"))
    stats = [(n, os.stat(os.path.join(folder, n))) for n in names]
    return tuple((n, st.st_mtime, st.st_size) for n, st in stats)


_CONTROLLER_STAMP = _controller_stamp()


# -- eq. (45)'s eigenvalues -------------------------------------------------------------------
@kernel
def extreme_eigenvalues(A):
    """(smallest, largest) eigenvalue of the symmetric matrix A (n, n).

    A Householder reduction to a tridiagonal T, then implicit QR steps with the Wilkinson
    shift (Golub & Van Loan, Matrix Computations, 8.3), LAPACK's algorithm for all the
    eigenvalues of a small matrix, as accurate (a few eps ||A||) and several times cheaper at
    12 x 12, where dsyevd's cost is its per-call overhead (docs/PERFORMANCE.md); the same
    arithmetic compiled or not (LAPACK's would differ between numba's and numpy's builds).
    """
    n = A.shape[0]
    T = A.copy()
    v = np.empty(n)
    p = np.empty(n)
    for k in range(n - 2):
        # H = I - beta v v' zeroes column k below the subdiagonal: T <- H T H on the block
        lo = k + 1
        norm = 0.0
        for i in range(lo, n):
            norm += T[i, k] * T[i, k]
        norm = math.sqrt(norm)
        if norm == 0.0:
            continue
        alpha = -norm if T[lo, k] >= 0.0 else norm
        for i in range(lo, n):
            v[i] = T[i, k]
        v[lo] -= alpha
        vv = 0.0
        for i in range(lo, n):
            vv += v[i] * v[i]
        beta = 2.0 / vv
        pv = 0.0
        for i in range(lo, n):  # p = beta T v
            acc = 0.0
            for j in range(lo, n):
                acc += T[i, j] * v[j]
            p[i] = beta * acc
            pv += p[i] * v[i]
        half = 0.5 * beta * pv
        for i in range(lo, n):  # w = p - (beta / 2)(p'v) v, kept in p
            p[i] -= half * v[i]
        for i in range(lo, n):  # T - v w' - w v'
            for j in range(lo, n):
                T[i, j] -= v[i] * p[j] + p[i] * v[j]
        T[lo, k] = alpha
    # Implicit symmetric QR steps with the Wilkinson shift (Golub & Van Loan, 8.3.2-8.3.3) on
    # the diagonal d and subdiagonal e (e[i] between rows i and i + 1): each step chases a
    # Givens rotation G = [[c, s], [-s, c]] down the unreduced block [lo, hi] (T <- G' T G on
    # rows and columns k, k + 1, the bulge z moving from (k + 1, k - 1) to (k + 2, k)); a
    # subdiagonal below eps (|d_i| + |d_i+1|) is dropped and splits the problem.
    d = np.empty(n)
    e = np.zeros(n)
    for i in range(n):
        d[i] = T[i, i]
        if i + 1 < n:
            e[i] = T[i + 1, i]
    eps = np.finfo(np.float64).eps
    hi = n - 1
    for _ in range(30 * n):
        while hi > 0 and abs(e[hi - 1]) <= eps * (abs(d[hi - 1]) + abs(d[hi])):
            hi -= 1
        if hi == 0:
            break
        lo = hi - 1
        while lo > 0 and abs(e[lo - 1]) > eps * (abs(d[lo - 1]) + abs(d[lo])):
            lo -= 1
        half = 0.5 * (d[hi - 1] - d[hi])
        b = e[hi - 1]
        mu = d[hi] - b * b / (half + math.copysign(math.sqrt(half * half + b * b), half))
        x, z = d[lo] - mu, e[lo]
        for k in range(lo, hi):
            r = math.sqrt(x * x + z * z)
            c, sn = (x / r, -z / r) if r > 0.0 else (1.0, 0.0)  # G' [x; z] = [r; 0]
            if k > lo:
                e[k - 1] = r
            a0, a1, bk = d[k], d[k + 1], e[k]
            d[k] = c * c * a0 - 2.0 * c * sn * bk + sn * sn * a1
            d[k + 1] = sn * sn * a0 + 2.0 * c * sn * bk + c * c * a1
            e[k] = c * sn * (a0 - a1) + (c * c - sn * sn) * bk
            if k + 1 < hi:
                x, z = e[k], -sn * e[k + 1]
                e[k + 1] *= c
    return d.min(), d.max()


@kernel
def gram_extremes(J):
    """The extreme eigenvalues of J J' and of L L', L = J without its first column, as
    (min, max, min of L, max of L): the squared extreme singular values of a Jacobian and of
    its columns but the first (J J' = L L' + w w', w the first column, summed in that order)."""
    m, n = J.shape
    rest = np.empty((m, m))
    full = np.empty((m, m))
    for i in range(m):
        for j in range(i + 1):
            g = 0.0
            for c in range(1, n):
                g += J[i, c] * J[j, c]
            rest[i, j] = rest[j, i] = g
            full[i, j] = full[j, i] = g + J[i, 0] * J[j, 0]
    lo, hi = extreme_eigenvalues(full)
    lo_rest, hi_rest = extreme_eigenvalues(rest)
    return lo, hi, lo_rest, hi_rest


# -- DAQP's C API -----------------------------------------------------------------------------
# daqp.Model wraps three C functions: Model.setup calls setup_daqp(problem, work,
# &setup_time), Model.update daqp_update_ldp(mask, work, problem), Model.solve
# daqp_solve(result, work). The structures are DAQP's DAQPProblem, DAQPResult and
# DAQPWorkspace of the release DAQP_HEADERS (its include/types.h and api.h); only the
# workspace's size is used, and :func:`daqp_binding` checks it.
DAQP_HEADERS = "0.11"  # the DAQP release (major.minor) the structures copy
INF = 1e20  # bounds beyond this are infinite (DAQP's own infinity is larger)
EQUALITY = 5  # DAQP's sense of an equality row (l = u)
UPDATE_H, UPDATE_A, UPDATE_F, UPDATE_BOUNDS, UPDATE_SENSE = 1, 2, 4, 8, 16  # update masks
_P, _I, _D = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
_FUNCTIONS = {  # name: (argument types, result type)
    "setup_daqp": ((_P, _P, _P), _I),
    "daqp_update_ldp": ((_I, _P, _P), _I),
    "daqp_solve": ((_P, _P), None),
    "free_daqp_workspace": ((_P,), None),
    "free_daqp_ldp": ((_P,), None),
    "allocate_daqp_settings": ((_P,), None),
}


def _fields(*groups: tuple[Any, str]) -> list[tuple[str, Any]]:
    """ctypes fields from (type, "name name ...") groups, in order."""
    return [(name, ctype) for ctype, names in groups for name in names.split()]


class _DaqpProblem(ctypes.Structure):  # DAQPProblem
    _fields_ = _fields(
        (_I, "n m ms"),  # ms: simple bounds, none here (A holds every row)
        (_P, "H f A bupper blower sense break_points"),
        (_I, "nh problem_type"),
    )


class _DaqpResult(ctypes.Structure):  # DAQPResult
    _fields_ = _fields(
        (_P, "x lam"), (_D, "fval soft_slack"), (_I, "exitflag iter nodes"),
        (_D, "solve_time setup_time"),
    )  # fmt: skip


class _DaqpWorkspace(ctypes.Structure):  # DAQPWorkspace: its size only
    _fields_ = _fields(
        (_P, "qp"), (_I, "n m ms"),
        (_P, "M dupper dlower Rinv v sense scaling RinvD x xold lam lam_star u"),
        (_D, "fval"), (_P, "L D xldl zldl"), (_I, "reuse_ind"), (_P, "WS"),
        (_I, "n_active iterations sing_ind"), (_P, "prox_mask"), (_I, "n_prox"),
        (_D, "soft_slack"), (_P, "settings bnb"), (_I, "outer_iter"),
        (_P, "hierarchy avi eq timer Mu rho_ls rho_us w_ls w_us"), (_I, "state"),
    )  # fmt: skip


_EXITFLAG = _DaqpResult.exitflag.offset // 4  # as an index of the result's int32 view
_WORKSPACE_BYTES = ctypes.sizeof(_DaqpWorkspace)
_GUARD_BYTES = 4 * _WORKSPACE_BYTES  # zeroed room after it, checked untouched (daqp_binding)

# The C functions as :func:`daqp_call` calls them: compiled, numba's declarations of
# symbols resolved when the binding is made; switched off, the ctypes functions themselves.
if JIT:
    _c, _ptr = numba.types, numba.types.voidptr
    _setup_daqp: Any = _c.ExternalFunction("setup_daqp", _c.intc(_ptr, _ptr, _ptr))
    _daqp_update_ldp: Any = _c.ExternalFunction("daqp_update_ldp", _c.intc(_c.intc, _ptr, _ptr))
    _daqp_solve: Any = _c.ExternalFunction("daqp_solve", _c.void(_ptr, _ptr))
else:
    _setup_daqp = _daqp_update_ldp = _daqp_solve = None  # set by _bind


class DaqpBindingError(RuntimeError):
    """The installed DAQP's C functions cannot be called from here (the reason in words)."""


class DaqpBinding:
    """DAQP's C library with the functions the workspaces call (ctypes)."""

    def __init__(self, path: str):
        try:
            self.lib = ctypes.CDLL(path)  # DAQP's extension module exports its C functions
        except OSError as exc:
            raise DaqpBindingError(f"cannot load {path}: {exc}") from exc
        for name, (args, result) in _FUNCTIONS.items():
            try:
                fn = getattr(self.lib, name)
            except AttributeError:
                raise DaqpBindingError(f"{path} has no function {name}") from None
            fn.argtypes, fn.restype = args, result
        try:
            libc = ctypes.CDLL(None)  # the process's C library (POSIX)
            self.calloc, self.free = libc.calloc, libc.free
        except (OSError, TypeError, AttributeError) as exc:
            raise DaqpBindingError(f"no C library's calloc and free: {exc}") from exc
        self.calloc.restype, self.calloc.argtypes = _P, [ctypes.c_size_t, ctypes.c_size_t]
        self.free.argtypes = [_P]

    def address(self, name: str) -> int:
        return ctypes.cast(getattr(self.lib, name), _P).value or 0

    def release(self, work: int) -> None:
        """What Model's deallocation does: DAQP frees what it allocated, then the workspace."""
        self.lib.free_daqp_workspace(work)
        self.lib.free_daqp_ldp(work)
        self.free(work)


_binding: DaqpBinding | None = None
_binding_tried = False


def daqp_binding() -> DaqpBinding | None:
    """The checked binding of DAQP's C functions, made at the first call; None (after one
    warning saying why) when it cannot be made, and the solvers use ``daqp.Model``.

    A compile error of the kernel raises here, at the first solver, with numba's message."""
    global _binding, _binding_tried
    if not _binding_tried:
        _binding_tried = True
        try:
            _binding = _bind()
        except DaqpBindingError as exc:
            warnings.warn(
                f"DAQP's C functions are not called directly ({exc}); every DAQP solve goes "
                "through daqp.Model instead (the same results, about 2 us slower a solve)",
                RuntimeWarning,
                stacklevel=2,
            )
    return _binding


def _bind() -> DaqpBinding:
    """Load, declare and check the binding (:func:`daqp_binding`)."""
    global _setup_daqp, _daqp_update_ldp, _daqp_solve
    try:
        version = importlib.metadata.version("daqp")
    except importlib.metadata.PackageNotFoundError:
        version = "of unknown version"
    if version.split(".")[:2] != DAQP_HEADERS.split("."):
        raise DaqpBindingError(
            f"daqp {version} is installed; the binding copies the structures of daqp {DAQP_HEADERS}"
        )
    binding = DaqpBinding(str(daqp.__file__))
    if JIT:  # cached kernels resolve the functions by name
        import llvmlite.binding

        for name in ("setup_daqp", "daqp_update_ldp", "daqp_solve"):
            llvmlite.binding.add_symbol(name, binding.address(name))
    else:
        lib = binding.lib
        _setup_daqp, _daqp_update_ldp, _daqp_solve = (
            lib.setup_daqp,
            lib.daqp_update_ldp,
            lib.daqp_solve,
        )
    _check(binding)
    return binding


def _check(binding: DaqpBinding) -> None:
    """A sequence of small QPs through the binding and through ``daqp.Model``: a set-up, new
    vectors, a row that becomes an equality, new matrices; every solution, objective, exit
    flag and iteration count equal, and nothing written past the workspace's size."""
    rng = np.random.default_rng(0)
    m, n = 4, 3
    ours, model = DaqpWorkspace(m, n, binding), DaqpWorkspace(m, n, None)
    for k in range(5):
        P = np.eye(n) * 2.0 + 0.1 * np.ones((n, n)) if k in (0, 4) else None
        A = rng.normal(size=(m, n)) if k in (0, 4) else None
        q = rng.normal(size=n)
        l, u = -rng.uniform(0.1, 1.0, m), rng.uniform(0.1, 1.0, m)
        if k >= 2:  # an equality row
            l[1] = u[1] = 0.05
        outs = []
        for work in (ours, model):
            if P is not None:
                work.H[...] = P
            if A is not None:
                work.A[...] = A
            x = np.full(n, np.nan)
            status, flag = work.solve(q, l, u, x, P is not None, A is not None, k == 0)
            outs.append((status, flag, x, *work.stats()))
        (s1, f1, x1, v1, i1), (s2, f2, x2, v2, i2) = outs
        if (s1, f1, v1, i1) != (s2, f2, v2, i2) or not np.array_equal(x1, x2) or s1 != 0:
            raise DaqpBindingError(
                f"check QP {k}: status {s1}, exit flag {f1}, x {x1} differ from daqp.Model's "
                f"(status {s2}, exit flag {f2}, x {x2})"
            )
    written = ctypes.string_at(ours.work + _WORKSPACE_BYTES, _GUARD_BYTES)
    if any(written):
        raise DaqpBindingError(
            f"DAQP wrote past the {_WORKSPACE_BYTES} bytes of DAQPWorkspace in daqp "
            f"{DAQP_HEADERS}'s header: the structure differs"
        )


@kernel
def daqp_vectors(q, l, u, f, bu, bl, eq, sense, setup):
    """DAQP's vectors of min 1/2 x'Hx + q'x, l <= Ax <= u: checks them (q finite, no bound
    pair crossed beyond 1e-9), writes f = q, bu = min(u, INF), bl = max(l, -INF) (NaN passes
    to the solver) and marks the equality rows ``eq`` and their ``sense`` (5; a row is one
    when |u - l| < 1e-12). Returns (valid, the senses changed, or ``setup``)."""
    for i in range(q.shape[0]):
        if not math.isfinite(q[i]):
            return False, False
    changed = setup
    for i in range(l.shape[0]):
        gap = u[i] - l[i]
        if gap < -1e-9:
            return False, False
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
            sense[i] = EQUALITY if eq[i] else 0
    return True, changed


@kernel
def daqp_call(q, l, u, out, mask, setup, buf, sense, eq, result, ptrs):
    """One DAQP solve on a workspace (:meth:`DaqpWorkspace.solve`; a layer's compiled step
    calls it with :attr:`DaqpWorkspace.args`): the vectors (:func:`daqp_vectors`), then
    setup_daqp (``setup``, on H and A as they are) or daqp_update_ldp with ``mask`` (H, A)
    plus the vectors, plus the senses if an equality row changed (else DAQP keeps its
    working set: the warm start); then daqp_solve and the solution copied to ``out``.
    ``buf`` holds f, x, bu, bl, the duals and the set-up time (:class:`DaqpWorkspace`),
    ``ptrs`` the workspace's and the problem's addresses. Returns (status, flag) as
    :meth:`DaqpWorkspace.solve`."""
    n, m = q.shape[0], l.shape[0]
    f, x = buf[:n], buf[n : 2 * n]
    bu, bl = buf[2 * n : 2 * n + m], buf[2 * n + m : 2 * n + 2 * m]
    valid, changed = daqp_vectors(q, l, u, f, bu, bl, eq, sense, setup)
    if not valid:
        return -1, 0
    work, problem = int(ptrs[0]), int(ptrs[1])  # Python ints for ctypes (switched off)
    if setup:
        flag = _setup_daqp(problem, work, buf[2 * n + 3 * m :].ctypes.data)
    else:
        mask |= UPDATE_F | UPDATE_BOUNDS
        if changed:
            mask |= UPDATE_SENSE
        flag = _daqp_update_ldp(mask, work, problem)
    if flag < 0:
        return -2, flag
    _daqp_solve(result.ctypes.data, work)
    exitflag = result[_EXITFLAG]
    if exitflag < 1:
        return -3, exitflag
    for i in range(n):
        if not math.isfinite(x[i]):
            return -3, exitflag
        out[i] = x[i]
    return 0, exitflag


@kernel
def daqp_call_new_hessian(P, c, lo, hi, H, qp_vectors, x, mask, setup, buf, sense, eq, res, ptrs):
    """:func:`daqp_call` for a step whose Hessian changes every tick (the IK's, the arm
    swing's): P written into DAQP's ``H``, the vectors (c, lo, hi) into ``qp_vectors`` (the QP
    the solver keeps for an explanation), P checked finite as :class:`controller.qp.QpSolver`
    checks a new P (status -1 if not), then the solve into ``x``."""
    H[:] = P
    qp_vectors[0], qp_vectors[1], qp_vectors[2] = c, lo, hi
    for v in H.ravel():
        if not math.isfinite(v):
            return -1, 0
    return daqp_call(c, lo, hi, x, mask, setup, buf, sense, eq, res, ptrs)


class DaqpWorkspace:
    """DAQP set up for QPs of one shape (m rows, n variables): its buffers, and the calls.

    The caller writes a new P or A into :attr:`H` / :attr:`A` and says so
    (:meth:`solve`'s ``new_H``, ``new_A``); the vectors are written by :meth:`solve`.
    ``binding``: DAQP's C functions (:func:`daqp_binding`), or None for ``daqp.Model``.
    """

    def __init__(self, m: int, n: int, binding: DaqpBinding | None):
        self.shape = (m, n)
        self.H, self.A = np.zeros((n, n)), np.zeros((m, n))
        # the vectors in one buffer (a kernel takes one argument for them): f, x (n), bu,
        # bl, the duals (m) and DAQP's set-up time (1)
        self.buf = np.zeros(2 * n + 3 * m + 1)
        self.f, self.x = self.buf[:n], self.buf[n : 2 * n]
        self.bu, self.bl = self.buf[2 * n : 2 * n + m], self.buf[2 * n + m : 2 * n + 2 * m]
        self.lam = self.buf[2 * n + 2 * m : 2 * n + 3 * m]
        self.sense = np.zeros(m, dtype=np.intc)
        self.eq = np.zeros(m, dtype=np.bool_)  # which rows are equalities
        self.args: tuple = ()  # daqp_call's workspace arguments (buf, sense, eq, result, ptrs)
        self._binding = binding
        if binding is None:
            self._model = daqp.Model()
            self._stats = (math.nan, -1)  # the last solve's objective and iterations
            self._solve_time = math.nan  # [s] the last solve's, as DAQP measured it
            return
        ptr = ctypes.c_void_p
        self._problem = _DaqpProblem(
            n, m, 0, *(ptr(a.ctypes.data) for a in (self.H, self.f, self.A, self.bu, self.bl)),
            ptr(self.sense.ctypes.data), None, 0, 0,
        )  # fmt: skip
        self.problem = ctypes.addressof(self._problem)
        # the result's memory as int32s (the kernel reads the exit flag), the structure on it
        self.result = np.zeros(ctypes.sizeof(_DaqpResult) // 4, dtype=np.int32)
        self._result = _DaqpResult.from_address(self.result.ctypes.data)  # result keeps it
        self._result.x, self._result.lam = self.x.ctypes.data, self.lam.ctypes.data
        self.work = binding.calloc(1, _WORKSPACE_BYTES + _GUARD_BYTES) or 0  # zeroed
        if not self.work:
            raise MemoryError("DAQP workspace")
        self._finalizer = weakref.finalize(self, binding.release, self.work)
        ptrs = np.array([self.work, self.problem], dtype=np.int64)
        self.args = (self.buf, self.sense, self.eq, self.result, ptrs)

    def solve(
        self,
        q: np.ndarray,
        l: np.ndarray,
        u: np.ndarray,
        out: np.ndarray,
        new_H: bool,
        new_A: bool,
        setup: bool,
    ) -> tuple[int, int]:
        """min 1/2 x'Hx + q'x, l <= Ax <= u into ``out``, from DAQP's set-up (``setup``, the
        first solve) or as an update of the last (H, A when new, the vectors, the senses when
        an equality row changed).

        Returns (status, flag): 0 solved (flag: the exit flag); -1 invalid vectors (checked
        before any call); -2 setup or update failed (its flag); -3 an exit flag below 1 or a
        non-finite solution (the exit flag).
        """
        if self._binding is None:
            return self._solve_model(q, l, u, out, new_H, new_A, setup)
        mask = (UPDATE_H if new_H else 0) | (UPDATE_A if new_A else 0)
        status, flag = daqp_call(q, l, u, out, mask, setup, *self.args)
        self.failed(status, setup)
        return status, flag

    def failed(self, status: int, setup: bool) -> None:
        """After a solve's (status, setup): a failed set-up freed DAQP's own settings;
        restore them as ``daqp.Model`` does (so the workspace can be released)."""
        if status == -2 and setup and self._binding is not None:
            self._binding.lib.allocate_daqp_settings(self.work)

    def _solve_model(self, q, l, u, out, new_H, new_A, setup) -> tuple[int, int]:
        """:meth:`solve` through ``daqp.Model``: the same C calls with the same arguments."""
        valid, changed = daqp_vectors(q, l, u, self.f, self.bu, self.bl, self.eq, self.sense, setup)
        if not valid:
            return -1, 0
        model = self._model
        if setup:
            flag, _ = model.setup(self.H, self.f, self.A, self.bu, self.bl, self.sense)
        else:
            kw: dict[str, np.ndarray] = {"H": self.H} if new_H else {}
            if new_A:
                kw["A"] = self.A
            if changed:
                kw["sense"] = self.sense
            flag = model.update(f=self.f, bupper=self.bu, blower=self.bl, **kw)
        if flag < 0:
            return -2, flag
        x, fval, exitflag, info = model.solve()
        self._stats = (fval, info["iterations"])
        self._solve_time = float(info.get("solve_time", math.nan))
        lam = info.get("lam")
        if lam is not None and len(lam) == len(self.lam):  # the duals, as the binding has them
            self.lam[:] = lam
        if exitflag < 1 or not np.isfinite(x).all():
            return -3, exitflag
        out[:] = x
        return 0, exitflag

    def stats(self) -> tuple[float, int]:
        """The last solve's objective and iteration count (as DAQP's result has them)."""
        if self._binding is None:
            return self._stats
        return self._result.fval, self._result.iter

    def solve_time(self) -> float:
        """[s] the last solve's time as DAQP measured it (NaN unknown)."""
        if self._binding is None:
            return self._solve_time
        t = float(self._result.solve_time)
        return t if t > 0.0 else math.nan
