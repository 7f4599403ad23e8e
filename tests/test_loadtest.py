"""`pelvic-walk loadtest` runs end to end on loopback and reports what it measured (no timing
assertions: the figures themselves are for the README, measured on a quiet machine), and the
server lowers its own threads' priority below the workers'."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

from app.loadtest import format_report, run_loadtest


def test_a_short_load_reports_real_time_bytes_and_memory():
    r = run_loadtest(viewers=2, robots=1, seconds=5, serve_args=["--workers", "0"])
    assert r["viewers"] == 2 and r["robots"] == 1 and r["seconds"] >= 5
    assert len(r["realtime_factor_samples"]) >= 1  # one a second once the factor is known
    assert 0 < r["realtime_factor_min"] <= r["realtime_factor_median"]
    assert r["bytes_per_viewer_per_s"] > 1000  # the scene did reach the viewers
    assert r["memory_mb_start"] > 0 and r["memory_mb_after_warmup"] > 0
    assert r["memory_mb_peak"] >= r["memory_mb_after_warmup"]
    assert r["health"]["status"] == "ok"
    text = format_report(r)
    assert "real-time factor" in text and "KB/s" in text and "after warm-up" in text
    below = sum(x < 0.9 for x in r["realtime_factor_samples"])
    assert f"; {below} below 0.9)" in text


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
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    changed, kept, lowered, main = map(int, out.stdout.split())
    base = os.getpriority(os.PRIO_PROCESS, 0)
    assert changed >= 2  # the main thread and "lowered"
    assert kept == base and lowered == min(19, base + 4) and main == min(19, base + 4)
