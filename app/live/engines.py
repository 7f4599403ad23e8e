"""How the worker pool reaches its workers: the engine is its transport, nothing more.

:class:`~app.live.pool.WorkerPool` places the robots of the live sessions on workers and
merges their frames (:class:`~app.live.pool.RemoteSession`); an engine starts a worker and
hands back its two ends, commands in and frames out. Both engines run the same worker code
(:func:`~app.live.worker.worker_main`: its ``_Hosted`` loops, the same messages, pickled):

- :class:`ProcessEngine` (the product's): each worker a process started with ``spawn``,
  talking over two pipes; robots keep real time whatever the web process does.
- :class:`InProcessEngine`: each worker a thread of this process, its pipes two queues
  (:class:`QueueEnd`). ``serve --workers 0`` uses it (one process to debug or profile), and
  tests do: nothing to spawn, and the loops (their robots) can be read. On a
  :class:`VirtualClock` the loops' wall clock moves only when every loop of the pool waits
  and no message is in flight, so frames relate exactly to simulated time however busy
  the machine is (the loops never fall behind, as on an idle machine).

- :class:`~app.live.ray_engine.RayEngine` (``serve --ray [ADDRESS]``): each worker a Ray
  actor on a cluster, its pipes Ray calls (``app.live.ray_engine``; Ray imported only there).

All three go behind the same calls: ``start``, ``loop`` and the ``clock`` and
``start_delay`` the sessions read.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import pickle
import queue
import threading
import time
from collections.abc import Callable
from typing import Any, Protocol

from app.live.loop import LiveLoop
from app.live.worker import InProcess, worker_main

START_DELAY_S = 1.0  # [s] rebuilt robots start this much later: processes build in parallel


class WorkerHandle(Protocol):
    """What the pool asks of a running worker (a process, or a thread of this one)."""

    @property
    def pid(self) -> int | None: ...

    @property
    def exitcode(self) -> int | None: ...

    def is_alive(self) -> bool: ...

    def join(self, timeout: float | None = None) -> None: ...

    def kill(self) -> None: ...


class Engine(Protocol):
    """A transport for the pool's workers."""

    @property
    def clock(self) -> Callable[[], float]:
        """The wall clock of the sessions' time base (monotonic) [s]."""
        ...

    @property
    def start_delay(self) -> float:
        """[s of wall time] rebuilt robots start this much later."""
        ...

    def start(
        self, index: int, publish_hz: float, strategies: tuple[str, ...]
    ) -> tuple[WorkerHandle, Any, Any]:
        """Start worker ``index``: (its handle, the commands' sending end, the frames'
        receiving end: ``send(obj)``, ``recv_bytes()``)."""
        ...

    def loop(self, worker: WorkerHandle, part: str) -> LiveLoop:
        """The loop running ``part`` (its robots), where the engine can reach it."""
        ...


class ProcessEngine:
    """Workers in processes (``spawn``), over two pipes each."""

    clock = staticmethod(time.monotonic)
    start_delay = START_DELAY_S

    def __init__(self) -> None:
        self._ctx = multiprocessing.get_context("spawn")

    def start(self, index: int, publish_hz: float, strategies: tuple[str, ...]):
        cmd_recv, cmd_send = self._ctx.Pipe(duplex=False)
        frm_recv, frm_send = self._ctx.Pipe(duplex=False)
        # One BLAS thread per worker: the matrices are small and the cores are for workers.
        env = {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")}
        os.environ.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
        try:
            proc = self._ctx.Process(
                target=worker_main,
                # a user's strategies (serve --strategy): the worker loads the same files
                args=(cmd_recv, frm_send, publish_hz, strategies),
                name=f"pelvic-walk-worker-{index}",
                daemon=True,
            )
            proc.start()
        finally:
            for k, v in env.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v
        cmd_recv.close()
        frm_send.close()
        return proc, cmd_send, frm_recv

    def loop(self, worker: WorkerHandle, part: str) -> LiveLoop:
        raise TypeError("the robots run in worker processes: their loops are not here")


class VirtualClock:
    """A wall clock for deterministic runs: its loops take turns, one at a time (the latest
    started first), and it moves only when every loop waits and no message is in flight
    (sent, not yet handled), to the earliest wake-up asked for. Loops on it never fall behind
    their time base and publish a frame every display interval of simulated time, in the same
    order on any machine."""

    def __init__(self, now: float = 0.0) -> None:
        self._cond = threading.Condition()
        self._now = now
        self._loops = 0  # loops running on it
        self._entered = 0
        self._busy = 0  # messages in flight
        self._waiting: dict[int, tuple[float, threading.Event]] = {}  # token -> wait

    def __call__(self) -> float:
        with self._cond:
            return self._now

    def enter(self) -> int:
        """A loop starts on this clock: its token (its turn comes before earlier ones')."""
        with self._cond:
            self._loops += 1
            self._entered += 1
            return self._entered

    def leave(self, _token: int) -> None:
        with self._cond:
            self._loops -= 1
            self._cond.notify_all()

    def busy(self, delta: int) -> None:
        with self._cond:
            self._busy += delta
            self._cond.notify_all()

    def wait(self, seconds: float, wake: threading.Event, token: int) -> None:
        """Wait ``seconds`` of this clock, or until ``wake`` is set (a new intent, a stop);
        ``math.inf``: only for ``wake`` (a paused loop). Then wait for the loop's turn."""
        with self._cond:
            self._waiting[token] = (self._now + seconds, wake)
            self._cond.notify_all()
            try:
                while self._turn() != token:
                    self._cond.wait(0.005)  # (a wake is an Event: polled)
            finally:
                del self._waiting[token]
                self._cond.notify_all()

    def _turn(self) -> int | None:
        """The loop that runs next, moving the clock if none is ready (under the lock)."""
        if self._busy or len(self._waiting) < self._loops:
            return None  # a loop runs, or a message is on its way
        ready = [t for t, (d, w) in self._waiting.items() if w.is_set() or d <= self._now + 1e-12]
        if not ready:
            wake_up = min(d for d, _w in self._waiting.values())
            if not math.isfinite(wake_up):
                return None  # all paused: the clock stands
            self._now = wake_up
            ready = [t for t, (d, _w) in self._waiting.items() if d <= self._now + 1e-12]
        return max(ready)


class QueueEnd:
    """One end of a one-way queue standing in for a pipe end (``send``/``recv``,
    ``send_bytes``/``recv_bytes``); messages are pickled as a pipe would. A message counts as
    in flight on the clock until the reader asks for the next one (it has handled it)."""

    _CLOSED = b""

    def __init__(self, q: queue.SimpleQueue, clock: VirtualClock | None) -> None:
        self._q = q
        self._clock = clock
        self._holding = False  # the reader handles a message (counted in flight)

    def send_bytes(self, data: bytes) -> None:
        if self._clock is not None:
            self._clock.busy(+1)
        self._q.put(data)

    def send(self, obj: Any) -> None:
        self.send_bytes(pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))

    def recv_bytes(self) -> bytes:
        if self._holding and self._clock is not None:
            self._clock.busy(-1)
        self._holding = False
        data = self._q.get()
        if data is self._CLOSED:
            self._q.put(data)  # (for any other reader)
            raise EOFError
        self._holding = True
        return data

    def recv(self) -> Any:
        return pickle.loads(self.recv_bytes())

    def close(self) -> None:
        self._q.put(self._CLOSED)


class _Thread:
    """A worker run by a thread of this process (its handle for the pool)."""

    def __init__(self, index: int, target: Callable[[], None], host: InProcess) -> None:
        self.host = host
        self.thread = threading.Thread(target=target, name=f"pelvic-walk-worker-{index}")
        self.thread.daemon = True
        self.commands: QueueEnd | None = None

    @property
    def pid(self) -> int | None:
        return os.getpid()

    @property
    def exitcode(self) -> int | None:
        return None

    def is_alive(self) -> bool:
        return self.thread.is_alive()

    def join(self, timeout: float | None = None) -> None:
        self.thread.join(timeout)

    def kill(self) -> None:
        if self.commands is not None:
            self.commands.close()  # the worker's loops stop, its frames end


class InProcessEngine:
    """Workers in threads of this process, over two queues each (module docstring).

    Args:
        clock: the wall clock of the loops and the sessions: ``time.monotonic`` (default),
            or a :class:`VirtualClock` (deterministic tests).
        start_delay: [s of wall time] rebuilt robots start this much later (default: two
            display intervals on a virtual clock, where building takes no time; else a
            fraction of a second, to build them in this process).
    """

    def __init__(
        self, clock: Callable[[], float] | None = None, start_delay: float | None = None
    ) -> None:
        self.clock = clock or time.monotonic
        self.virtual = clock if isinstance(clock, VirtualClock) else None
        self._start_delay = start_delay

    @property
    def start_delay(self) -> float:
        if self._start_delay is not None:
            return self._start_delay
        return 0.0 if self.virtual is not None else 0.3  # (virtual: see start())

    def start(self, index: int, publish_hz: float, strategies: tuple[str, ...]):
        commands = QueueEnd(queue.SimpleQueue(), self.virtual)
        frames = QueueEnd(queue.SimpleQueue(), self.virtual)
        host = InProcess(clock=self.clock, virtual=self.virtual)
        if self._start_delay is None and self.virtual is not None:
            # a loop runs up to a display interval (plus a tick) ahead of the time base
            self._start_delay = 2.0 / publish_hz

        def run() -> None:
            try:
                worker_main(commands, frames, publish_hz, strategies, host=host)
            finally:
                frames.close()

        handle = _Thread(index, run, host)
        handle.commands = commands
        handle.thread.start()
        return handle, commands, frames

    def loop(self, worker: WorkerHandle, part: str) -> LiveLoop:
        if not isinstance(worker, _Thread):
            raise TypeError("not a worker of this engine")
        return worker.host.hosted[part].loop
