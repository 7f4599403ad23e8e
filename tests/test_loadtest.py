"""`pelvic-walk loadtest` runs end to end on loopback and reports what it measured (no timing
assertions: the figures themselves are for the README, measured on a quiet machine), and the
server lowers its own threads' priority below the workers'."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time

import pytest

from app.bench.loadtest import CpuMeter, cpu_summary, format_report, run_loadtest


def test_a_short_load_reports_real_time_bytes_and_memory():
    r = run_loadtest(viewers=2, robots=1, seconds=5, serve_args=["--workers", "0"])
    assert r["viewers"] == 2 and r["robots"] == 1 and r["seconds"] >= 5
    assert len(r["realtime_factor_samples"]) >= 1  # one a second once the factor is known
    assert 0 < r["realtime_factor_min"] <= r["realtime_factor_median"]
    # the scene did reach the viewers. (Not a rate: the viewers read in a thread VIEWER_NICE
    # steps below the server, so on a busy machine they read what the CPU left them, and the
    # display thread is itself niced: 401 B/s at load average 25-35 with two busy loops.)
    assert r["bytes_per_viewer_per_s"] > 0
    assert r["memory_mb_start"] > 0 and r["memory_mb_after_warmup"] > 0
    assert r["memory_mb_peak"] >= r["memory_mb_after_warmup"]
    assert r["health"]["status"] == "ok"
    text = format_report(r)
    assert "real-time factor" in text and "KB/s" in text and "after warm-up" in text
    below = sum(x < 0.9 for x in r["realtime_factor_samples"])
    assert f"; {below} below 0.9)" in text
    # the CPU read with each factor sample (Linux /proc): the serving process did work
    assert len(r["cpu_samples"]) == len(r["realtime_factor_samples"])
    assert r["cpu"]["run"]["server"] > 0 and r["cpu"]["run"]["idle"] >= 0
    assert "CPU [cores]        serving process" in text and "child processes" in text


def test_in_private_mode_each_viewer_opens_a_session_or_is_told_they_are_full():
    """The viewers report a camera as browsers do, so a private-mode server gives each its own
    session while the worker has room (4 robots: the shared demo's 1 and the 3 a private session
    opens with) and tells the rest; every viewer gets a scene either way."""
    r = run_loadtest(
        viewers=3,
        robots=1,
        seconds=5,
        serve_args=["--sessions", "private", "--workers", "1", "--robots-per-worker", "4"],
    )
    refused = r["health"]["viewers_refused"]
    assert r["private_sessions_max"] >= 1 and refused >= 1
    assert r["private_sessions_max"] + refused == 3
    assert r["bytes_per_viewer_per_s"] > 0  # a scene for each (not a rate: see above)
    assert len(r["realtime_factor_samples"]) >= 1
    assert f"{refused} viewers told the workers were full" in format_report(r)


def _cpu(server, workers, idle):
    return {"server": server, "workers": workers, "idle": idle}


def _same(a, b) -> bool:
    return (
        a["server"] == pytest.approx(b["server"])
        and a["workers"] == pytest.approx(b["workers"])
        and a["idle"] == pytest.approx(b["idle"])
    )


def test_cpu_summary_averages_the_run_and_the_windows_of_the_dips():
    calm = _cpu(0.3, [0.5, 0.4], 0.2)
    busy = [_cpu(0.1, [0.6, 0.6], 0.1), _cpu(0.1, [0.7, 0.6], 0.0), _cpu(0.4, [0.8, 0.6], 0.2)]
    samples = [calm] * 5 + busy + [calm] * 2
    rtf = [1.0] * 7 + [0.85] + [1.0] * 2  # the dip's 3-s window: samples 5-7
    c = cpu_summary(samples, rtf)
    assert c["run"]["server"] == pytest.approx((7 * 0.3 + 0.6) / 10)
    assert c["run"]["workers"] == pytest.approx([(7 * 0.5 + 2.1) / 10, (7 * 0.4 + 1.8) / 10])
    assert _same(c["below"], _cpu(0.2, [0.7, 0.6], 0.1))
    # no dip, no "below"; a dip in the first second has a window of one; gaps are skipped
    assert cpu_summary(samples, [1.0] * 10)["below"] is None
    early = cpu_summary([_cpu(0.2, [0.9], 0.0), None, _cpu(0.3, [0.1], 1.0)], [0.5, 1, 1])
    assert _same(early["below"], _cpu(0.2, [0.9], 0.0))
    assert early["run"]["idle"] == pytest.approx(0.5)
    assert cpu_summary([None, None], [0.5, 0.5]) is None
    # workers that came and went: the missing ones count as idle in the mean
    uneven = cpu_summary([_cpu(0, [0.8, 0.4], 0), _cpu(0, [0.6], 0)], [1, 1])
    assert uneven["run"]["workers"] == pytest.approx([0.7, 0.2])


def test_cpu_meter_reads_this_process_and_its_children():
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        meter = CpuMeter(os.getpid())
        spent = time.process_time() + 0.2
        while time.process_time() < spent:  # 0.2 s of CPU, however long it takes
            pass
        c = meter.sample()
        assert c is not None and c["server"] > 0 and c["idle"] >= 0
        assert len(c["workers"]) >= 1  # the child
    finally:
        child.kill()
        child.wait()


def test_lower_priority_spares_the_kept_threads():
    # in a child process: the priority of pytest's own threads must not change
    code = textwrap.dedent(
        """
        import os, threading
        from app.web.server import lower_priority
        ids, stop = {}, threading.Event()
        def idle(name):
            ids[name] = threading.get_native_id()
            stop.wait()
        for name in ("kept", "lowered"):
            threading.Thread(target=idle, args=(name,), daemon=True).start()
        while len(ids) < 2:
            pass
        changed = lower_priority(4, keep={ids["kept"]})
        nice = {n: os.getpriority(os.PRIO_PROCESS, t) for n, t in ids.items()}
        main = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
        print(changed, nice["kept"], nice["lowered"], main)
        """
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    changed, kept, lowered, main = map(int, out.stdout.split())
    base = os.getpriority(os.PRIO_PROCESS, 0)
    assert changed >= 2  # the main thread and "lowered"
    assert kept == base and lowered == min(19, base + 4) and main == min(19, base + 4)
