"""schemathesis against the app's ``/openapi.json``: no request may get a 5xx, and the live
simulation still advances afterwards.

The app (around a real live session, tests/conftest.py, short plans) is served by uvicorn on a free
localhost port in a thread of this process; schemathesis's command line runs in a subprocess
with the phases examples, coverage and fuzzing, only the ``not_a_server_error`` check and a
``MAX_TIME_S`` budget. The headless runs that ``POST /api/runs`` starts are real but stopped
after ``RUN_WALL_S`` of wall time each, and the server refuses more than two pending ones of one
client (429), so the fuzzing cannot exhaust the machine.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import httpx
import pytest

from app.web.api import RunManager, create_app

MAX_TIME_S = 60
RUN_WALL_S = 2.0


@pytest.fixture(scope="module")
def base_url(live, serve_app):
    app = create_app(live, viser_port=18766, runs=RunManager(max_wall_s=RUN_WALL_S))
    with serve_app(app) as url:
        yield url


def test_no_request_gets_a_server_error(base_url, live, tmp_path):
    exe = Path(sys.executable).with_name("schemathesis")
    cmd = [
        str(exe),
        "run",
        f"{base_url}/openapi.json",
        "--phases",
        "examples,coverage,fuzzing",
        "--checks",
        "not_a_server_error",
        "--max-time",
        str(MAX_TIME_S),
        "--workers",
        "1",
        "--seed",
        "20261201",
        "--request-timeout",
        "30",
        "--no-color",
    ]
    try:  # cwd: its Hypothesis database and any report stay out of the checkout
        proc = subprocess.run(
            cmd, cwd=tmp_path, capture_output=True, text=True, timeout=MAX_TIME_S + 180
        )
    except subprocess.TimeoutExpired as exc:
        pytest.fail(f"schemathesis did not finish: {str(exc.stdout)[-3000:]}")
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-6000:]
    assert "✅ Coverage" in out and "✅ Fuzzing" in out, out[-3000:]  # both ran, no failure

    # The live simulation survived: resumed, its clock moves on.
    with httpx.Client(base_url=base_url, timeout=30) as client:
        assert client.post("/api/sim/resume").status_code == 200
        clock = client.get("/api/state").json()["clock"]
        frame = live.frame()
        for _ in range(5):
            frame = live.wait_frame(frame.seq, timeout=30)
            assert frame is not None
        state = client.get("/api/state").json()
        assert state["clock"] > clock and state["paused"] is False
        assert client.get("/api/health").json()["status"] == "ok"
    assert live.running and live.error is None
