"""``pelvic-walk loadtest``: N scene viewers against a server, the real-time factor it keeps.

It starts ``pelvic-walk serve`` on free loopback ports (or uses a server already running on
127.0.0.1 with ``--port`` and ``--viser-port``), sets the number of robots, connects
``--viewers`` websocket clients to the viser scene (each offers the subprotocol
``viser-v<version>`` and reads every message, as a browser tab would), and every second reads
``GET /api/state`` and the bytes each viewer received. It stops by itself after
``--seconds`` and prints (and with ``--json`` writes) the real-time factor (median, minimum,
samples), bytes per viewer per second, and the server's memory at the start and end (when
it started the server). Traffic goes to 127.0.0.1 only.
"""

from __future__ import annotations

import asyncio
import json
import os
import signal
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import httpx

METHOD_SETS = {1: ["mpc"], 2: ["fixed", "mpc"], 3: ["fixed", "redundancy", "mpc"]}
WARMUP_S = 5.0  # [s] after the viewers connect, before sampling


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


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


def _children(pid: int) -> list[int]:
    out = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            out += [int(c) for c in (task / "children").read_text().split()]
        except OSError:
            pass
    return out + [g for c in out for g in _children(c)]


async def _viewer(url: str, subprotocol: str, counter: list[int], stop: asyncio.Event) -> None:
    import websockets

    async with websockets.connect(
        url, subprotocols=[subprotocol], max_size=None, open_timeout=60
    ) as ws:
        while not stop.is_set():
            try:
                msg = await asyncio.wait_for(ws.recv(), timeout=0.5)
            except TimeoutError:
                continue
            counter[0] += len(msg)


async def _run(base: str, viser_url: str, viewers: int, seconds: float) -> dict[str, Any]:
    import viser

    subprotocol = f"viser-v{viser.__version__}"
    counters = [[0] for _ in range(viewers)]
    stop = asyncio.Event()
    tasks = [asyncio.create_task(_viewer(viser_url, subprotocol, c, stop)) for c in counters]
    rtf: list[float] = []
    rates: list[float] = []
    async with httpx.AsyncClient(timeout=10) as client:
        await asyncio.sleep(WARMUP_S)
        t0, b0 = time.monotonic(), sum(c[0] for c in counters)
        last_t, last_b = t0, b0
        while time.monotonic() - t0 < seconds:
            await asyncio.sleep(1.0)
            for task in tasks:
                if task.done() and task.exception() is not None:
                    raise RuntimeError(f"a viewer failed: {task.exception()!r}")
            state = (await client.get(f"{base}/api/state")).json()
            if state.get("realtime_factor") is not None:
                rtf.append(float(state["realtime_factor"]))
            now, b = time.monotonic(), sum(c[0] for c in counters)
            rates.append((b - last_b) / (now - last_t) / max(viewers, 1))
            last_t, last_b = now, b
        elapsed = time.monotonic() - t0
        total = sum(c[0] for c in counters) - b0
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
    }


def run_loadtest(
    viewers: int,
    robots: int,
    seconds: float,
    port: int | None = None,
    viser_port: int | None = None,
    serve_args: list[str] | None = None,
) -> dict[str, Any]:
    """Start (or use) a server, load it, and return the figures (see the module docstring)."""
    if robots not in METHOD_SETS:
        raise ValueError(f"robots must be 1, 2 or 3, got {robots}")
    proc = None
    if port is None:
        port, viser_port = free_port(), free_port()
        exe = Path(sys.executable).with_name("pelvic-walk")
        proc = subprocess.Popen(
            [
                str(exe),
                "serve",
                "--port",
                str(port),
                "--viser-port",
                str(viser_port),
                *(serve_args or []),
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
    elif viser_port is None:
        raise ValueError("--viser-port is needed with --port")
    base = f"http://127.0.0.1:{port}"
    try:
        _wait_healthy(base, proc)
        r = httpx.put(f"{base}/api/params", json={"methods": METHOD_SETS[robots]}, timeout=30)
        r.raise_for_status()
        mem0 = rss_mb(proc.pid) if proc else None
        out = asyncio.run(_run(base, f"ws://127.0.0.1:{viser_port}", viewers, seconds))
        out.update(
            robots=robots,
            memory_mb_start=mem0,
            memory_mb_end=rss_mb(proc.pid) if proc else None,
            health=httpx.get(f"{base}/api/health", timeout=10).json(),
        )
        if mem0 and out["memory_mb_end"]:
            out["memory_growth_percent"] = 100 * (out["memory_mb_end"] / mem0 - 1)
        return out
    finally:
        if proc is not None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(20)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(5)


def _wait_healthy(base: str, proc: subprocess.Popen | None, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc is not None and proc.poll() is not None:
            err = proc.stderr.read() if proc.stderr else ""
            raise RuntimeError(f"serve exited with {proc.returncode}: {err[-1000:]}")
        try:
            if httpx.get(f"{base}/api/health", timeout=2).status_code == 200:
                return
        except httpx.HTTPError:
            pass
        time.sleep(0.5)
    raise RuntimeError(f"no server answered at {base} within {timeout:.0f} s")


def format_report(r: dict[str, Any]) -> str:
    med, lo = r["realtime_factor_median"], r["realtime_factor_min"]
    lines = [
        f"loadtest: {r['viewers']} viewers, {r['robots']} robots, {r['seconds']:.0f} s",
        f"real-time factor   median {med:.3f}   min {lo:.3f}   "
        f"({len(r['realtime_factor_samples'])} samples, 1 s apart)"
        if med is not None
        else "real-time factor   no samples",
        f"sent per viewer    {r['bytes_per_viewer_per_s'] / 1e3:.1f} KB/s (max "
        f"{(r['bytes_per_viewer_per_s_max'] or 0) / 1e3:.1f} KB/s over 1 s)",
    ]
    if r.get("memory_mb_start"):
        lines.append(
            f"server memory      {r['memory_mb_start']:.0f} -> "
            f"{r['memory_mb_end']:.0f} MB ({r['memory_growth_percent']:+.1f} %)"
        )
    return "\n".join(lines)


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
