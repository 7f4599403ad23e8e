"""The run engine of ``pelvic-walk sweep`` and ``pelvic-walk experiments``: jobs on a backend.

A *job* is a module-level function and its plain-data arguments (a
:class:`~pelvic_walk.core.run_spec.RunSpec`, numbers, strings): it crosses process and Ray
boundaries as
it is, and the worker builds its own MuJoCo and Pinocchio objects. A *task* asks for jobs one
at a time (a limit search's next length depends on the last outcome); a list of independent
jobs is a task per job (:class:`OneJob`). :func:`run_tasks` keeps one job in flight per task and
at most ``backend.slots`` in all, so the cells of a sweep and the runs of a study share the
workers; a progress bar (tqdm, stderr) counts the jobs.

Backends:

- :class:`LocalPool`: ``concurrent.futures.ProcessPoolExecutor`` with the ``spawn`` context
  (no inherited MuJoCo/Pinocchio state), ``jobs`` workers (the default);
- :class:`RayCluster`: Ray tasks (``--ray [ADDRESS]``; without an address a local Ray instance
  with ``jobs`` CPUs), one CPU each, ``OMP_NUM_THREADS=1`` in the workers' environment; Ray
  is imported only here, and :func:`import_ray` says how to install it when it is missing;
- :class:`InProcess`: runs in this process one at a time (``--jobs 1``, and tests).

Results do not depend on the backend: runs are deterministic given their arguments, and every
task is told its own jobs' results (the order jobs finish in does not matter).
"""

from __future__ import annotations

import multiprocessing
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any, Protocol

from tqdm import tqdm

RAY_INSTALL = "pip install 'pelvic-walk[cluster]'"
Job = tuple[Callable[..., Any], tuple[Any, ...]]  # (module-level function, its arguments)


class Backend(Protocol):
    """Where jobs run: submit one, then wait for any of those submitted."""

    name: str
    slots: int  # jobs worth keeping in flight (the workers, and one queued each)

    def submit(self, fn: Callable[..., Any], *args: Any) -> Any: ...

    def wait_any(self, handles: Sequence[Any]) -> list[tuple[Any, Any]]: ...

    def close(self) -> None: ...


class InProcess:
    """Runs in this process, in submission order (no parallelism)."""

    name = "in-process"
    slots = 1

    def __init__(self) -> None:
        self._queue: dict[int, Job] = {}
        self._next = 0

    def submit(self, fn: Callable[..., Any], *args: Any) -> int:
        self._next += 1
        self._queue[self._next] = (fn, args)
        return self._next

    def wait_any(self, handles: Sequence[int]) -> list[tuple[int, Any]]:
        h = min(handles)
        fn, args = self._queue.pop(h)
        return [(h, fn(*args))]

    def close(self) -> None:
        self._queue.clear()


class LocalPool:
    """A process pool (``spawn``) of ``jobs`` workers."""

    def __init__(self, jobs: int):
        self.name = f"local process pool, {jobs} jobs"
        self.slots = 2 * jobs
        ctx = multiprocessing.get_context("spawn")
        self.pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx)

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future:
        return self.pool.submit(fn, *args)

    def wait_any(self, handles: Sequence[Future]) -> list[tuple[Future, Any]]:
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

    def __init__(self, address: str | None, jobs: int):
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
        cpus = int(ray.cluster_resources().get("CPU", jobs)) if address else jobs
        self.slots = 2 * max(cpus, 1)
        self._remote: dict[Callable[..., Any], Any] = {}

    def submit(self, fn: Callable[..., Any], *args: Any) -> Any:
        remote = self._remote.get(fn)
        if remote is None:
            remote = self._remote[fn] = self.ray.remote(num_cpus=1, max_retries=0)(fn)
        return remote.remote(*args)

    def wait_any(self, handles: Sequence[Any]) -> list[tuple[Any, Any]]:
        ready, _ = self.ray.wait(list(handles), num_returns=1)
        return [(ref, self.ray.get(ref)) for ref in ready]

    def close(self) -> None:
        self.ray.shutdown()


def make_backend(ray: str | None, jobs: int, n_tasks: int) -> Backend:
    """Ray (``ray`` not None: "" for a local instance; ImportError / ConnectionError with one
    line), else a process pool of ``jobs`` workers (at most one per task), else in-process
    for one job."""
    if ray is not None:
        return RayCluster(ray or None, jobs)
    workers = max(1, min(jobs, n_tasks))
    return InProcess() if workers == 1 else LocalPool(workers)


class Task(Protocol):
    """Asks for jobs one at a time and is told each one's result."""

    def next_job(self) -> Job | None: ...

    def record(self, job: Job, result: Any) -> None: ...

    def jobs_left_estimate(self) -> int: ...

    def label(self, job: Job) -> str: ...


class OneJob:
    """A task of one job; its result in :attr:`result` once done."""

    def __init__(self, fn: Callable[..., Any], *args: Any, label: str = ""):
        self.job: Job = (fn, args)
        self.result: Any = None
        self.done = False
        self._label = label

    def next_job(self) -> Job | None:
        return None if self.done else self.job

    def record(self, job: Job, result: Any) -> None:
        self.result, self.done = result, True

    def jobs_left_estimate(self) -> int:
        return 0 if self.done else 1

    def label(self, job: Job) -> str:
        return self._label


def run_tasks(tasks: Sequence[Task], backend: Backend, desc: str = "runs") -> int:
    """Run every task to its end on ``backend``: at most one job in flight per task and
    ``backend.slots`` in all, the tasks served in their order. Returns the jobs made."""
    in_flight: dict[Any, tuple[int, Job]] = {}  # backend handle -> (task index, job)
    busy: set[int] = set()
    finished: set[int] = set()
    made = 0
    with tqdm(total=0, desc=desc, unit="run", file=sys.stderr, dynamic_ncols=True) as bar:

        def fill() -> None:
            for i, task in enumerate(tasks):
                if len(in_flight) >= backend.slots:
                    break
                if i in busy or i in finished:
                    continue
                job = task.next_job()
                if job is None:
                    finished.add(i)
                    continue
                in_flight[backend.submit(job[0], *job[1])] = (i, job)
                busy.add(i)
            # the bar's total: jobs made, in flight, and an estimate of those left
            left = sum(
                max(t.jobs_left_estimate() - (i in busy), 0)
                for i, t in enumerate(tasks)
                if i not in finished
            )
            bar.total = made + len(in_flight) + left
            bar.refresh()

        fill()
        while in_flight:
            for handle, result in backend.wait_any(list(in_flight)):
                i, job = in_flight.pop(handle)
                busy.discard(i)
                tasks[i].record(job, result)
                made += 1
                bar.set_postfix_str(tasks[i].label(job), refresh=False)
                bar.update(1)
            fill()
    return made
