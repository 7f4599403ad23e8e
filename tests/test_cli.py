"""The pelvic-walk command line: good runs and bad arguments (exit 2, one line)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from app.cli import main
from app.runs import SUMMARY_KEYS

BAD = [
    ["simulate", "--method", "fixed", "--step-length", "0"],
    ["simulate", "--method", "fixed", "--step-length", "-0.1"],
    ["simulate", "--method", "fixed", "--step-length", "0.7"],
    ["simulate", "--method", "fixed", "--step-length", "nan"],
    ["simulate", "--method", "fixed", "--step-length", "abc"],
    ["simulate", "--method", "sideways", "--step-length", "0.2"],
    ["simulate", "--method", "mpc", "--step-length", "0.2", "--horizon", "0.01"],
    ["simulate", "--method", "mpc", "--step-length", "0.2", "--steps", "0"],
    ["simulate", "--method", "mpc", "--step-length", "0.2", "--step-time", "inf"],
    ["simulate", "--step-length", "0.2"],
    ["fly"],
    ["simulate", "--method", "fixed", "--step-length", "0.2", "--json", "/nonexistent/x.json"],
    ["simulate", "--method", "fixed", "--step-length", "0.2", "--csv", "/"],
    ["bench", "--json", "/nonexistent/b.json"],
]


@pytest.mark.parametrize("argv", BAD, ids=lambda a: " ".join(a))
def test_bad_arguments_exit_2_with_one_line(argv):
    proc = subprocess.run(
        [sys.executable, "-m", "app.cli", *argv], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 2
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stderr
    assert "error" in lines[0]
    assert "Traceback" not in proc.stderr
    assert proc.stdout == ""  # nothing started


def test_simulate_writes_every_json_key_and_csv(tmp_path, capsys):
    out, csv = tmp_path / "out.json", tmp_path / "series.csv"
    code = main(
        [
            "simulate",
            "--method",
            "mpc",
            "--step-length",
            "0.15",
            "--steps",
            "2",
            "--json",
            str(out),
            "--csv",
            str(csv),
        ]
    )
    assert code == 0
    summary = json.loads(out.read_text())
    assert set(SUMMARY_KEYS) <= set(summary)
    assert summary["success"] is True
    assert summary["steps_planned"] == 2
    header = csv.read_text().splitlines()[0].split(",")
    assert {"t", "waist_angle", "yaw_momentum", "kappa_low"} <= set(header)
    assert "success" in capsys.readouterr().out


def test_analyze_reproduces_the_paper_numbers(tmp_path):
    out = tmp_path / "a.json"
    assert main(["analyze", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["step_max_fixed_static"] == pytest.approx(0.31, abs=0.01)
    assert data["step_max_rotation_static"] == pytest.approx(0.42, abs=0.01)
