"""The pool's workers as Ray actors: the live sessions' robots on a Ray cluster.

``pelvic-walk serve --ray [ADDRESS]`` keeps the page, the API and the scene in the web process
and runs the robots of every live session on a Ray cluster (a local instance without an
address, as ``sweep --ray``). :class:`RayEngine` is a third engine of the one worker pool
(``app.live.engines``): the pool places, merges, admits and restarts exactly as with worker
processes, and every live feature works the same. A worker is a :class:`LiveWorker` actor
running the same worker code (:func:`~app.live.worker.worker_main`, its ``_Hosted`` loops and
``Outbox``) in a thread of its own; its two "pipes" are Ray calls:

- commands in: ``command(bytes)``, one actor call per message (fire and forget, in order);
- frames out: ``frames(timeout)``, called by the pool's receiver thread with the next call
  already in flight, returns every message waiting (a batch of pickled messages, the plans
  stripped by :class:`~app.live.worker.FrameCodec` as over a pipe) and the actor's node and
  load. An actor that dies (its node lost, its process killed) fails the call with Ray's
  ``RayActorError``: to the pool, the pipe closed, and it restarts the worker's robots, all of
  each session's together, wherever the cluster has room.

Admission from the cluster: a robot holds ``robot_cpu`` of a CPU as a Ray resource (by default
1 / ROBOTS_PER_CORE, as a core of the local pool), an actor ``robots_per_worker`` of them, so
Ray places the actors (spread over the nodes) and the pool's seats are what the cluster holds
when ``serve`` starts (:meth:`RayEngine.workers_for`).

Time base: the robots of one session may run on different machines, so the sessions' clock is
``time.time`` (the hosts' clocks agree through NTP to a millisecond or so), not each host's own
monotonic clock.

Ray is imported only when this engine is made (``--ray``); ``import_ray`` says how to install
it when it is missing.
"""

from __future__ import annotations

import collections
import math
import os
import pickle
import queue
import socket
import threading
import time
from typing import Any

from app.live.engines import START_DELAY_S, QueueEnd
from app.live.loop import LiveLoop
from app.live.worker import worker_main
from pelvic_walk.core.engine import import_ray

ROBOT_CPU = 1 / 6  # a robot's share of a CPU (ROBOTS_PER_CORE robots a core, app.web.settings)
FRAMES_WAIT_S = 0.5  # [s] a frames() call returns empty after this (the receiver asks again)
LOAD_EVERY_S = 2.0  # [s] how often an actor reports its node's load
NODES_EVERY_S = 2.0  # [s] the cluster's nodes are asked for at most this often (health)


def _node_id() -> str:
    try:
        import ray

        return ray.get_runtime_context().get_node_id()
    except Exception:  # noqa: BLE001 - not in a Ray worker (a unit test)
        return ""


def _node_ip() -> str:
    try:
        import ray

        return ray.util.get_node_ip_address()
    except Exception:  # noqa: BLE001
        return ""


class _FrameBuffer:
    """The frames' end inside an actor: ``send_bytes`` (the worker's outbox thread) queues
    messages; ``take`` (an actor call) hands them all out, waiting up to ``timeout`` for one."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._items: collections.deque[bytes] = collections.deque()
        self.ended = False

    def send_bytes(self, data: bytes) -> None:
        with self._cond:
            self._items.append(data)
            self._cond.notify_all()

    def end(self) -> None:
        with self._cond:
            self.ended = True
            self._cond.notify_all()

    def take(self, timeout: float) -> tuple[list[bytes], bool]:
        with self._cond:
            if not self._items and not self.ended:
                self._cond.wait(timeout)
            items = list(self._items)
            self._items.clear()
            return items, self.ended and not items


class LiveWorker:
    """A worker of the pool as a Ray actor (module docstring): ``worker_main`` in a thread,
    commands in through :meth:`command`, frames out through :meth:`frames`."""

    def __init__(self, publish_hz: float, strategies: tuple[str, ...]) -> None:
        self._commands = QueueEnd(queue.SimpleQueue(), None)
        self._frames = _FrameBuffer()
        self._info = {"pid": os.getpid(), "node": _node_id(), "ip": _node_ip()}
        self._load_at = 0.0

        def run() -> None:
            try:
                # the sessions' clock is the hosts' shared one (module docstring); a thread of
                # the actor: the signals stay the actor's
                worker_main(
                    self._commands,
                    self._frames,
                    publish_hz,
                    strategies,
                    clock=time.time,
                    own_signals=False,
                )
            finally:
                self._frames.end()

        self._thread = threading.Thread(target=run, name="pelvic-walk-worker", daemon=True)
        self._thread.start()

    def command(self, data: bytes) -> None:
        self._commands.send_bytes(data)

    def frames(self, timeout: float = FRAMES_WAIT_S) -> tuple[list[bytes], bool, dict | None]:
        """(the messages waiting, whether the worker ended, the node's load now and then)."""
        items, ended = self._frames.take(timeout)
        now = time.monotonic()
        info = None
        if now - self._load_at >= LOAD_EVERY_S:
            self._load_at = now
            info = {**self._info, "load": os.getloadavg()[0], "cpus": os.cpu_count()}
        return items, ended, info

    def info(self) -> dict:
        return self._info


class _Commands:
    """The commands' sending end (``send(obj)``): one actor call per message."""

    def __init__(self, actor: Any) -> None:
        self._actor = actor

    def send(self, obj: Any) -> None:
        self._actor.command.remote(pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))


class ActorWorker:
    """A worker actor as the pool sees it: its handle (``pid``, ``exitcode``, ``is_alive``,
    ``join``, ``kill``) and its frames' receiving end (``recv_bytes``: EOFError once the
    worker ended or the actor died)."""

    def __init__(self, ray: Any, actor: Any, index: int) -> None:
        self._ray = ray
        self.actor = actor
        self.index = index
        self.commands = _Commands(actor)
        self._pending: collections.deque[bytes] = collections.deque()
        self._next: Any = None  # the frames() call in flight
        self._ended = threading.Event()
        self._killed = False
        self.info: dict = {}  # pid, node, ip, load, cpus (the latest the actor told)
        self.died: str | None = None  # why, when the actor died
        self.bytes_received = 0  # the messages' bytes so far (what crossed from the actor)

    # -- the handle ------------------------------------------------------------------------
    @property
    def pid(self) -> int | None:
        return self.info.get("pid")

    @property
    def exitcode(self) -> int | None:
        return None

    @property
    def node(self) -> str | None:
        return self.info.get("node")

    @property
    def where(self) -> str:
        """Where it ran, for the page: ``on node <ip> (<id>)``."""
        node, ip = self.info.get("node"), self.info.get("ip")
        return f" on node {ip or '?'} ({(node or '?')[:8]})" if node or ip else ""

    def is_alive(self) -> bool:
        return not self._ended.is_set() and not self._killed

    def join(self, timeout: float | None = None) -> None:
        self._ended.wait(timeout)

    def kill(self) -> None:
        self._killed = True
        try:
            self._ray.kill(self.actor, no_restart=True)
        except Exception:  # noqa: BLE001 - gone already
            pass

    # -- the frames' end -------------------------------------------------------------------
    def recv_bytes(self) -> bytes:
        while not self._pending:
            if self._ended.is_set():
                raise EOFError
            ref = self._next if self._next is not None else self.actor.frames.remote()
            self._next = None
            try:
                items, ended, info = self._ray.get(ref)
            except Exception as exc:  # noqa: BLE001 - RayActorError and the like: it died
                self.died = f"{type(exc).__name__}"
                self._ended.set()
                raise EOFError from None
            if ended:
                self._ended.set()
                self.kill()  # its resources back to the cluster
                raise EOFError
            self._next = self.actor.frames.remote()  # the next batch on its way meanwhile
            if info is not None:
                self.info = {**self.info, **info}
            self._pending.extend(items)
            self.bytes_received += sum(len(x) for x in items)
        return self._pending.popleft()


class RayEngine:
    """Workers as Ray actors (module docstring), on a cluster at ``address`` or on a local
    instance of ``cpus`` CPUs (default: this machine's); joins the Ray this process is
    already connected to, if any (tests' clusters), and leaves it connected.

    Raises ImportError (Ray missing) or ConnectionError (cannot start or reach Ray), one line.
    """

    clock = staticmethod(time.time)
    # rebuilt robots start this much later: an actor's parts build in its threads, on a node
    # whose cores other actors share, and their intents cross the network first
    start_delay = 2 * START_DELAY_S

    def __init__(
        self,
        address: str | None = None,
        robots_per_worker: int = 6,
        robot_cpu: float = ROBOT_CPU,
        cpus: int | None = None,
    ) -> None:
        ray = import_ray()
        self.ray = ray
        self.robots_per_worker = robots_per_worker
        self.robot_cpu = robot_cpu
        before = _thread_ids()
        self._own = not ray.is_initialized()
        if self._own:
            kwargs: dict[str, Any] = {
                "runtime_env": {"env_vars": {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}},
                "include_dashboard": False,
                "log_to_driver": False,
                "logging_level": "ERROR",
            }
            if address:
                kwargs["address"] = address
                self.where = f"Ray cluster at {address}"
                _reachable(address, self.where)  # (Ray itself waits minutes for a wrong one)
            else:
                cpus = cpus or os.cpu_count() or 1
                kwargs["num_cpus"] = cpus
                self.where = f"local Ray instance, {cpus} CPUs"
            try:
                ray.init(**kwargs)
            except Exception as exc:
                ray.shutdown()
                reason = " ".join(str(exc).split()) or type(exc).__name__
                raise ConnectionError(
                    f"--ray: cannot start or reach Ray ({self.where}): {reason}"
                ) from None
        else:
            self.where = "Ray cluster (already connected)"
        self._ray_threads = _thread_ids() - before  # Ray's own threads in this process
        self._actor_class = ray.remote(LiveWorker)
        self._workers: list[ActorWorker] = []
        self._nodes: list[dict] = []
        self._nodes_at = -math.inf

    @property
    def worker_cpu(self) -> float:
        """The CPU one actor asks Ray for: its robots' shares."""
        return round(self.robots_per_worker * self.robot_cpu, 4)

    def workers_for(self) -> int:
        """Workers the cluster holds now (its free CPUs over an actor's share), at least 0."""
        free = float(self.ray.available_resources().get("CPU", 0.0))
        return int(free / self.worker_cpu + 1e-9)

    def start(self, index: int, publish_hz: float, strategies: tuple[str, ...]):
        actor = self._actor_class.options(
            num_cpus=self.worker_cpu,
            max_concurrency=8,  # command() and frames() at once
            max_restarts=0,  # the pool restarts a lost worker (all of its sessions' robots)
            scheduling_strategy="SPREAD",  # a class over every node
            name=None,
        ).remote(publish_hz, strategies)
        handle = ActorWorker(self.ray, actor, index)
        self._workers.append(handle)
        return handle, handle.commands, handle

    def loop(self, worker: Any, part: str) -> LiveLoop:
        raise TypeError("the robots run in Ray actors: their loops are not here")

    def keep_threads(self) -> set[int]:
        """Native ids of Ray's threads in this process (they carry the frames: their priority
        stays the workers')."""
        return set(self._ray_threads)

    def nodes(self, workers: list[dict]) -> list[dict]:
        """The cluster's nodes for /api/health: address, alive, CPUs, the pool's workers and
        robots on each, and the node's load (1-minute load average, as its actors report)."""
        now = time.monotonic()
        if now - self._nodes_at > NODES_EVERY_S:  # (a call to Ray's control plane)
            self._nodes, self._nodes_at = self.ray.nodes(), now
        out = []
        for n in self._nodes:
            nid = n.get("NodeID", "")[:8]
            mine = [w for w in workers if w.get("node") == nid]
            loads = [w["load"] for w in mine if w.get("load") is not None]
            out.append(
                {
                    "node": nid,
                    "address": n.get("NodeManagerAddress"),
                    "alive": bool(n.get("Alive")),
                    "cpus": n.get("Resources", {}).get("CPU", 0.0),
                    "workers": [w["index"] for w in mine],
                    "robots": sum(len(w["robots"]) for w in mine),
                    "load": max(loads) if loads else None,
                }
            )
        return out

    def close(self) -> None:
        for w in self._workers:
            w.kill()
        if self._own:
            self.ray.shutdown()


def _thread_ids() -> set[int]:
    try:
        return {int(t) for t in os.listdir("/proc/self/task")}
    except OSError:
        return set()


def _reachable(address: str, where: str, timeout: float = 5.0) -> None:
    """ConnectionError (one line) unless ``HOST:PORT`` accepts a TCP connection; other forms
    (``auto``, ``ray://...``) are left to Ray."""
    host, sep, port = address.rpartition(":")
    if not sep or "://" in address or not port.isdigit():
        return
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except OSError as exc:
        raise ConnectionError(
            f"--ray: cannot reach Ray ({where}): {exc.strerror or exc}; is `ray start --head` "
            "running there?"
        ) from None
