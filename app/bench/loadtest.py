"""``pelvic-walk loadtest``: N scene viewers against a server, the real-time factor it keeps.

It starts ``pelvic-walk serve`` on free loopback ports (or uses a server already running on
127.0.0.1 with ``--port`` and ``--viser-port``), sets the number of robots, connects
``--viewers`` websocket clients to the viser scene (each offers the subprotocol
``viser-v<version>``, reports a camera and reads every message, as a browser tab would), and
every second reads ``GET /api/sessions`` and the bytes each viewer received. It stops by
itself after ``--seconds`` and prints (and with ``--json`` writes) the real-time factor
(median, minimum, samples), bytes per viewer per second, and the server's memory (when it
started the server): once the warm-up is over (the first fifth of the run: the kept history
fills up and every viewer has its scene) and at the end. Traffic goes to 127.0.0.1 only.

The factor sampled is the lowest of the running sessions' (one session in shared mode, what
`GET /api/state` reports). Against a server with ``--sessions private`` every viewer, like a
browser, opens a private session while the workers have room and watches the shared demo
after that: the report says how many sessions ran at most and how many viewers were refused.
(viser counts a client as connected, and the server builds its view, once it has reported its
camera: in private mode a client that only read got nothing at all, 0.0 KB/s.)

When it started the server it also reads, once a second, the CPU [cores] of the serving
process and of each worker process (Linux ``/proc``) and the machine's idle cores, and
reports their means and their means over the 3-s windows of the samples below 0.9: whether
a dip came with the robots' workers short of CPU (the machine full) or not.

In a class the viewers run on the students' machines. Here they share the server's cores, so
they run in a thread ``VIEWER_NICE`` nice steps below the server: they take the CPU the server
leaves, as other machines would, instead of competing with the robots for it.
"""

from __future__ import annotations

import asyncio
import json
import os
import statistics
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import httpx

from app.bench.local_server import local_server, wait_healthy
from controller.strategy import FIXED, MPC, REDUNDANCY

if TYPE_CHECKING:
    from websockets.typing import Subprotocol

METHOD_SETS = {1: [MPC], 2: [FIXED, MPC], 3: [FIXED, REDUNDANCY, MPC]}
WARMUP_S = 5.0  # [s] after the viewers connect, before sampling
MEMORY_WARMUP_SHARE = 0.2  # the server's memory is compared from this share of the run on
VIEWER_NICE = 10  # nice steps of the viewers' thread (0: same priority as the server)
CLK_TCK = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100  # /proc time unit [1/s]


def rss_mb(pid: int) -> float | None:
    """Resident memory of a process and its children [MB] (Linux /proc)."""
    total, found = 0, False
    for p in [pid, *_children(pid)]:
        try:
            for line in Path(f"/proc/{p}/status").read_text().splitlines():
                if line.startswith("VmRSS:"):
                    total += int(line.split()[1])
                    found = True
        except OSError:
            continue
    return total / 1024 if found else None


def _cpu_seconds(pid: int) -> float | None:
    """User + system CPU time of one process [s] (Linux /proc), None when it is gone."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return (int(fields[11]) + int(fields[12])) / CLK_TCK  # utime, stime (man 5 proc)


def _idle_seconds() -> float | None:
    """Idle + iowait time of all CPUs since boot [s] (Linux /proc/stat)."""
    try:
        fields = Path("/proc/stat").read_text().split("\n", 1)[0].split()
    except OSError:
        return None
    return (int(fields[4]) + int(fields[5])) / CLK_TCK


class CpuMeter:
    """CPU [cores] of a server and its worker processes, and the machine's idle cores, over
    the time between two :meth:`sample` calls (Linux; elsewhere every sample is None)."""

    def __init__(self, pid: int):
        self.pid = pid
        self._last = self._read()

    def _read(self) -> tuple[float, dict[int, float], float | None]:
        procs = {p: _cpu_seconds(p) for p in [self.pid, *_children(self.pid)]}
        return time.monotonic(), {p: c for p, c in procs.items() if c is not None}, _idle_seconds()

    def sample(self) -> dict[str, Any] | None:
        """{"server": cores, "workers": [cores, ...] (busiest first), "idle": cores}."""
        (t0, p0, i0), (t1, p1, i1) = self._last, self._read()
        self._last = (t1, p1, i1)
        dt = t1 - t0
        if dt <= 0 or self.pid not in p1 or self.pid not in p0 or i0 is None or i1 is None:
            return None
        workers = [(p1[p] - p0[p]) / dt for p in p1 if p != self.pid and p in p0]
        return {
            "server": (p1[self.pid] - p0[self.pid]) / dt,
            "workers": sorted(workers, reverse=True),
            "idle": (i1 - i0) / dt,
        }


def cpu_summary(
    samples: list[dict[str, Any] | None], rtf: list[float], level: float = 0.9, window: int = 3
) -> dict[str, Any] | None:
    """Mean CPU of ``samples`` (one a second, as :meth:`CpuMeter.sample` returns them) over
    the run and over the ``window`` samples ending at each real-time factor below ``level``
    (the factor is measured over the last 3 s). ``rtf[i]`` and ``samples[i]`` are read at the
    same second; None when there is no CPU sample."""

    def mean(rows: list[dict[str, Any]]) -> dict[str, Any] | None:
        if not rows:
            return None
        n = max(len(r["workers"]) for r in rows)
        return {
            "server": statistics.fmean(r["server"] for r in rows),
            "workers": [
                statistics.fmean(r["workers"][k] if k < len(r["workers"]) else 0.0 for r in rows)
                for k in range(n)
            ],
            "idle": statistics.fmean(r["idle"] for r in rows),
        }

    rows = [r for r in samples if r is not None]
    if not rows:
        return None
    dips = sorted(
        {
            j
            for i, x in enumerate(rtf)
            if x < level
            for j in range(max(0, i - window + 1), i + 1)
            if j < len(samples) and samples[j] is not None
        }
    )
    return {
        "run": mean(rows),
        "below": mean([cast(dict[str, Any], samples[j]) for j in dips]),  # dips skip the Nones
        "level": level,
    }


def _children(pid: int) -> list[int]:
    out = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            out += [int(c) for c in (task / "children").read_text().split()]
        except OSError:
            pass
    return out + [g for c in out for g in _children(c)]


def _camera_message() -> bytes:
    """What a browser sends first: its camera (here a 1280 x 720 canvas looking at the robots)."""
    import msgspec
    from viser import _messages  # the wire format of the viser version installed

    msg = _messages.ViewerCameraMessage(
        wxyz=(1.0, 0.0, 0.0, 0.0),
        position=(3.0, -3.0, 2.0),
        fov=0.87,
        near=0.01,
        far=1000.0,
        image_height=720,
        image_width=1280,
        look_at=(0.0, 0.0, 1.0),
        up_direction=(0.0, 0.0, 1.0),
    )
    return msgspec.msgpack.encode(msg.as_serializable_dict())


async def _viewer(url: str, subprotocol: str, counter: list[int], stop: asyncio.Event) -> None:
    import websockets

    async with websockets.connect(
        url, subprotocols=[cast("Subprotocol", subprotocol)], max_size=None, open_timeout=60
    ) as ws:
        await ws.send(_camera_message())
        while not stop.is_set():
            try:
                msg = await asyncio.wait_for(ws.recv(), timeout=0.5)
            except TimeoutError:
                continue
            counter[0] += len(msg)
            counter[1] += 1


async def _run(
    base: str,
    viser_url: str,
    viewers: int,
    seconds: float,
    memory=lambda: None,
    cpu=lambda: None,
) -> dict[str, Any]:
    import viser

    subprotocol = f"viser-v{viser.__version__}"
    counters = [[0, 0] for _ in range(viewers)]  # bytes, messages
    stop = asyncio.Event()
    tasks = [asyncio.create_task(_viewer(viser_url, subprotocol, c, stop)) for c in counters]
    rtf: list[float] = []
    cpu_samples: list[dict[str, Any] | None] = []  # read with each factor sample
    rates: list[float] = []
    private_max = 0  # private sessions running at once, at most
    async with httpx.AsyncClient(timeout=10) as client:
        await asyncio.sleep(WARMUP_S)
        t0, b0 = time.monotonic(), sum(c[0] for c in counters)
        m0 = sum(c[1] for c in counters)
        last_t, last_b = t0, b0
        mem_warm, mem_peak = None, None
        cpu()  # the meter's first interval starts here
        while time.monotonic() - t0 < seconds:
            await asyncio.sleep(1.0)
            mem, used = memory(), cpu()
            if mem is not None and time.monotonic() - t0 >= MEMORY_WARMUP_SHARE * seconds:
                mem_warm = mem if mem_warm is None else mem_warm
                mem_peak = max(mem, mem_peak or mem)
            for task in tasks:
                if task.done() and task.exception() is not None:
                    raise RuntimeError(f"a viewer failed: {task.exception()!r}")
            sessions = (await client.get(f"{base}/api/sessions")).json()
            private_max = max(private_max, int(sessions.get("private_sessions", 0)))
            # the session that keeps real time least (private ones are not listed to a
            # stranger, but counted in this figure)
            least = sessions.get("realtime_factor_min")
            if least is not None:
                rtf.append(float(least))
                cpu_samples.append(used)
            now, b = time.monotonic(), sum(c[0] for c in counters)
            rates.append((b - last_b) / (now - last_t) / max(viewers, 1))
            last_t, last_b = now, b
        elapsed = time.monotonic() - t0
        total = sum(c[0] for c in counters) - b0
        messages = sum(c[1] for c in counters) - m0
    stop.set()
    await asyncio.gather(*tasks, return_exceptions=True)
    return {
        "viewers": viewers,
        "seconds": elapsed,
        "realtime_factor_median": statistics.median(rtf) if rtf else None,
        "realtime_factor_min": min(rtf) if rtf else None,
        "realtime_factor_samples": rtf,
        "bytes_per_viewer_per_s": total / elapsed / max(viewers, 1),
        "bytes_per_viewer_per_s_max": max(rates) if rates else None,
        "messages_per_viewer_per_s": messages / elapsed / max(viewers, 1),
        "memory_mb_after_warmup": mem_warm,
        "memory_mb_peak": mem_peak,
        "cpu_samples": cpu_samples,
        "cpu": cpu_summary(cpu_samples, rtf),
        "private_sessions_max": private_max,
    }


def run_loadtest(
    viewers: int,
    robots: int,
    seconds: float,
    port: int | None = None,
    viser_port: int | None = None,
    serve_args: list[str] | None = None,
    viewer_nice: int = VIEWER_NICE,
) -> dict[str, Any]:
    """Start (or use) a server, load it, and return the figures (see the module docstring)."""
    if robots not in METHOD_SETS:
        raise ValueError(f"robots must be 1, 2 or 3, got {robots}")
    if port is not None:
        if viser_port is None:
            raise ValueError("--viser-port is needed with --port")
        base = f"http://127.0.0.1:{port}"
        wait_healthy(base)
        return _load(base, viser_port, None, viewers, robots, seconds, viewer_nice)
    with local_server(serve_args or []) as server:
        return _load(
            server.base, server.viser_port, server.proc.pid, viewers, robots, seconds, viewer_nice
        )


def _load(
    base: str,
    viser_port: int,
    pid: int | None,
    viewers: int,
    robots: int,
    seconds: float,
    viewer_nice: int,
) -> dict[str, Any]:
    """The load itself against a healthy server; ``pid``: the server's process when this
    process started it (its memory and CPU are then read too)."""
    r = httpx.put(f"{base}/api/params", json={"methods": METHOD_SETS[robots]}, timeout=30)
    r.raise_for_status()
    memory = (lambda: rss_mb(pid)) if pid else (lambda: None)
    mem0 = memory()
    meter = CpuMeter(pid) if pid else None
    out = _in_viewer_thread(
        _run(
            base,
            f"ws://127.0.0.1:{viser_port}",
            viewers,
            seconds,
            memory,
            meter.sample if meter else (lambda: None),
        ),
        viewer_nice,
    )
    out.update(
        robots=robots,
        viewer_nice=viewer_nice,
        memory_mb_start=mem0,
        memory_mb_end=memory(),
        health=httpx.get(f"{base}/api/health", timeout=10).json(),
    )
    warm, end = out["memory_mb_after_warmup"], out["memory_mb_end"]
    if warm and end:
        out["memory_growth_percent"] = 100 * (end / warm - 1)
    return out


def _in_viewer_thread(coro, nice: int) -> dict[str, Any]:
    """Run the viewers' event loop in a thread ``nice`` steps below this one (Linux nice is
    per thread; elsewhere it runs at the same priority)."""
    result: dict[str, Any] = {}

    def main() -> None:
        try:
            tid = threading.get_native_id()
            os.setpriority(
                os.PRIO_PROCESS, tid, min(19, os.getpriority(os.PRIO_PROCESS, tid) + nice)
            )
        except (OSError, AttributeError):
            pass
        try:
            result["out"] = asyncio.run(coro)
        except BaseException as exc:  # re-raised in the caller's thread
            result["error"] = exc

    t = threading.Thread(target=main, name="loadtest-viewers")
    t.start()
    t.join()
    if "error" in result:
        raise result["error"]
    return result["out"]


def _below(r: dict[str, Any], level: float) -> int:
    return sum(1 for x in r["realtime_factor_samples"] if x < level)


def format_report(r: dict[str, Any]) -> str:
    med, lo = r["realtime_factor_median"], r["realtime_factor_min"]
    lines = [
        f"loadtest: {r['viewers']} viewers, {r['robots']} robots, {r['seconds']:.0f} s",
        f"real-time factor   median {med:.3f}   min {lo:.3f}   "
        f"({len(r['realtime_factor_samples'])} samples, 1 s apart; {_below(r, 0.9)} below 0.9)"
        if med is not None
        else "real-time factor   no samples",
        f"sent per viewer    {r['bytes_per_viewer_per_s'] / 1e3:.1f} KB/s (max "
        f"{(r['bytes_per_viewer_per_s_max'] or 0) / 1e3:.1f} KB/s over 1 s; "
        f"{r.get('messages_per_viewer_per_s', 0):.1f} scene messages/s)",
    ]
    health = r.get("health") or {}
    if health.get("sessions_mode") == "private":
        lines.append(
            f"private sessions   {r['private_sessions_max']} at most at once, "
            f"{health.get('viewers_refused', 0)} viewers told the workers were full "
            "(they watch the shared demo); the factor is the lowest session's"
        )
    if r.get("memory_growth_percent") is not None:
        lines.append(
            f"server memory      {r['memory_mb_start']:.0f} MB at start, "
            f"{r['memory_mb_after_warmup']:.0f} MB after warm-up, {r['memory_mb_end']:.0f} MB "
            f"at the end ({r['memory_growth_percent']:+.1f} % since warm-up, peak "
            f"{r['memory_mb_peak']:.0f} MB)"
        )
    cpu = r.get("cpu")
    if cpu is not None:
        lines.append(f"CPU [cores]        {_cpu_text(cpu['run'])} (mean over the run)")
        if cpu["below"] is not None:
            lines.append(
                f"                   {_cpu_text(cpu['below'])} (mean over the 3-s windows "
                f"below {cpu['level']})"
            )
    return "\n".join(lines)


def _cpu_text(c: dict[str, Any]) -> str:
    workers = " ".join(f"{w:.2f}" for w in c["workers"]) or "none"
    return (
        f"serving process {c['server']:.2f}, its child processes (the workers) {workers}, "
        f"machine idle {c['idle']:.2f}"
    )


def main(
    viewers: int,
    robots: int,
    seconds: float,
    port: int | None,
    viser_port: int | None,
    json_path: Path | None,
    serve_args: list[str] | None = None,
) -> int:
    try:
        report = run_loadtest(viewers, robots, seconds, port, viser_port, serve_args)
    except (RuntimeError, ValueError, httpx.HTTPError) as exc:
        print(f"pelvic-walk loadtest: error: {exc}", file=sys.stderr)
        return 2
    print(format_report(report))
    if json_path is not None:
        json_path.write_text(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":  # pragma: no cover
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main(int(sys.argv[1]), 3, float(sys.argv[2]), None, None, None))
