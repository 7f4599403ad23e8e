"""Running a sweep's tasks on a backend, with a progress bar (tqdm, stderr).

:func:`execute` keeps one run in flight per task (a limit search is sequential within its
cell: each length depends on the last outcome), so the cells run in parallel with each other;
the bar counts runs, its total being the runs made plus an estimate of those left.

Backends run :func:`app.sweep.measure.run_one` on a :class:`RunSpec` (plain data) and return
its plain-dict outcome; MuJoCo and Pinocchio objects never cross a process boundary:

- :class:`LocalPool`: ``concurrent.futures.ProcessPoolExecutor`` with the ``spawn`` context
  (no inherited MuJoCo/Pinocchio state), ``--jobs`` workers;
- :class:`RayCluster`: Ray tasks (``--ray [ADDRESS]``; without an address a local Ray instance
  with ``--jobs`` CPUs), one CPU each, ``OMP_NUM_THREADS=1`` in the workers' environment; Ray
  is imported only here, and :func:`import_ray` says how to install it when it is missing;
- :class:`InProcess`: runs in this process one at a time (``--jobs 1``, and tests with a fake
  run function).

Results do not depend on the backend: runs are deterministic given their parameters and every
row is built from its own task's outcomes.
"""

from __future__ import annotations

import multiprocessing
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any, Protocol

from tqdm import tqdm

from app.experiments.definitions import RunSpec
from app.sweep.measure import Outcome, Task, run_one

RunFunction = Callable[[RunSpec], Outcome]
RAY_INSTALL = "pip install 'pelvic-walk[cluster]'"


class Backend(Protocol):
    """Where runs execute: submit a spec, then wait for any of the submitted runs."""

    name: str

    def submit(self, spec: RunSpec) -> Any: ...

    def wait_any(self, handles: Sequence[Any]) -> list[tuple[Any, Outcome]]: ...

    def close(self) -> None: ...


class InProcess:
    """Runs in this process, in submission order (no parallelism)."""

    name = "in-process"

    def __init__(self, fn: RunFunction = run_one):
        self.fn = fn
        self._queue: dict[int, RunSpec] = {}
        self._next = 0

    def submit(self, spec: RunSpec) -> int:
        self._next += 1
        self._queue[self._next] = spec
        return self._next

    def wait_any(self, handles: Sequence[int]) -> list[tuple[int, Outcome]]:
        h = min(handles)
        return [(h, self.fn(self._queue.pop(h)))]

    def close(self) -> None:
        self._queue.clear()


class LocalPool:
    """A process pool (``spawn``) of ``jobs`` workers."""

    def __init__(self, jobs: int, fn: RunFunction = run_one):
        self.name = f"local process pool, {jobs} jobs"
        self.fn = fn
        ctx = multiprocessing.get_context("spawn")
        self.pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx)

    def submit(self, spec: RunSpec) -> Future:
        return self.pool.submit(self.fn, spec)

    def wait_any(self, handles: Sequence[Future]) -> list[tuple[Future, Outcome]]:
        done, _ = wait(handles, return_when=FIRST_COMPLETED)
        return [(f, f.result()) for f in done]

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


def import_ray() -> Any:
    """The ``ray`` module, or ImportError with a one-line message saying how to install it."""
    try:
        import ray
    except ImportError:
        raise ImportError(f"--ray needs Ray, which is not installed: {RAY_INSTALL}") from None
    return ray


class RayCluster:
    """Ray tasks on a cluster at ``address``, or on a local instance with ``jobs`` CPUs.

    Connecting (or starting the local instance) happens here; :meth:`close` always calls
    ``ray.shutdown()``, which stops a local instance and disconnects from a cluster.
    Raises ImportError (Ray missing) or ConnectionError (cannot reach the cluster).
    """

    def __init__(self, address: str | None, jobs: int, fn: RunFunction = run_one):
        ray = import_ray()
        self.ray = ray
        kwargs: dict[str, Any] = {
            "runtime_env": {"env_vars": {"OMP_NUM_THREADS": "1"}},
            "include_dashboard": False,
            "log_to_driver": False,
            "logging_level": "ERROR",
        }
        if address:
            kwargs["address"] = address
            where = f"Ray cluster at {address}"
        else:
            kwargs["num_cpus"] = jobs
            where = f"local Ray instance, {jobs} CPUs"
        try:
            ray.init(**kwargs)
        except Exception as exc:
            ray.shutdown()
            reason = " ".join(str(exc).split()) or type(exc).__name__
            raise ConnectionError(f"--ray: cannot start or reach Ray ({where}): {reason}") from None
        self.name = where
        self.remote = ray.remote(num_cpus=1, max_retries=0)(fn)

    def submit(self, spec: RunSpec) -> Any:
        return self.remote.remote(spec)

    def wait_any(self, handles: Sequence[Any]) -> list[tuple[Any, Outcome]]:
        ready, _ = self.ray.wait(list(handles), num_returns=1)
        return [(ref, self.ray.get(ref)) for ref in ready]

    def close(self) -> None:
        self.ray.shutdown()


def _label(task: Task) -> str:
    return f"{task.cell.label} {task.method}"


def execute(tasks: Sequence[Task], backend: Backend, desc: str = "sweep") -> int:
    """Run every task to its end on ``backend`` (one run in flight per task); returns the
    number of runs made. The tasks hold the outcomes (:meth:`Task.row`)."""
    in_flight: dict[Any, tuple[int, RunSpec]] = {}  # backend handle -> (task index, spec)
    made = 0
    with tqdm(total=0, desc=desc, unit="run", file=sys.stderr, dynamic_ncols=True) as bar:

        def fill() -> None:
            busy = {i for i, _ in in_flight.values()}
            for i, task in enumerate(tasks):
                spec = None if i in busy else task.next_spec()
                if spec is not None:
                    in_flight[backend.submit(spec)] = (i, spec)
                    busy.add(i)
            # the bar's total: runs made, in flight, and an estimate of those left
            left = sum(max(t.runs_left_estimate() - (i in busy), 0) for i, t in enumerate(tasks))
            bar.total = made + len(in_flight) + left
            bar.refresh()

        fill()
        while in_flight:
            for handle, result in backend.wait_any(list(in_flight)):
                i, spec = in_flight.pop(handle)
                tasks[i].record(spec, result)
                made += 1
                bar.set_postfix_str(f"{_label(tasks[i])} L={spec.step_length:.2f}", refresh=False)
                bar.update(1)
            fill()
    return made
