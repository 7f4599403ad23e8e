"""The compiler of a tick's arithmetic: numba's ``njit``, configured once (:func:`kernel`).

Why: a control tick is a few hundred operations on arrays of 2 to 32 numbers. numpy pays
about a microsecond of Python and dispatch per operation whatever the size, so the tick's
time was that overhead, spread over every layer (docs/PERFORMANCE.md). Each layer therefore
keeps its equations in its own module, written once in a plain function over small arrays
(building a QP's vectors, recovering a plan from a solution) decorated with :func:`kernel`,
and its Python code calls that function. There is one code path: the tests call the same
compiled functions the controller runs; nothing has a Python twin.

- numba compiles a kernel to machine code at its first call and caches it in the module's
  ``__pycache__``: a fresh checkout compiles once, later processes load the cache.
- Numerics: IEEE double precision without fast-math (no reassociation, no fused
  multiply-add), so a kernel's loop rounds as it reads. A loop's sums run in their written
  order, which is not always the order of the BLAS routines numpy called before; the last
  bits of a result can differ from numpy's, and the closed loop amplifies such differences
  (docs/PERFORMANCE.md, "Same results").
- ``error_model="numpy"``: a division by zero gives inf or NaN as in numpy (the QP solver's
  finiteness checks then see it) instead of raising.
- A kernel calls only kernels of its own module: numba's cache notices a change of the
  kernel's own file only, so a call into another module's kernel could keep running stale
  code after that module changed.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, cast

from numba import njit

F = TypeVar("F", bound=Callable[..., Any])


def kernel(fn: F) -> F:
    """``fn`` compiled by numba (nopython, cached, GIL released while it runs)."""
    return cast(F, njit(cache=True, nogil=True, error_model="numpy")(fn))
