"""The headless core (``pelvic_walk/core``): every face runs walks through it, and it loads no
face. A walk through the core, the public package's walk and a sweep leave no web, live,
scene or command-line module in ``sys.modules``; ``push-study`` contains a student's fault as
``simulate`` does (one run path)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from app.cli import main
from controller import strategy

FACES = ("fastapi", "uvicorn", "viser", "mjviser", "app")

WALK_THROUGH_THE_CORE = """
import json, pkgutil, sys, importlib
import pelvic_walk.core as core
for m in pkgutil.iter_modules(core.__path__):
    importlib.import_module(f"pelvic_walk.core.{m.name}")
from pelvic_walk.core.capture import Capture
from pelvic_walk.core.pushes import run_push
from pelvic_walk.core.run import run, spec_of, summarize
from controller.params import ControllerParams
import pelvic_walk as pw

p = ControllerParams().replace(method="mpc", walk={"step_length": 0.2, "n_steps": 1})
cap = Capture("mpc")
summarize(run(spec_of(p).config(), on_tick=cap.capture))
run_push("fixed", 0.2, 10.0, n_steps=2, step=1)
r = pw.simulate("mpc", step_length=0.2, steps=1)
r.horizon(1.0)
pw.compare([r])
faces = ("fastapi", "uvicorn", "viser", "mjviser", "app")
print(json.dumps(sorted(m for m in sys.modules if m.split(".")[0] in faces)))
"""


def test_a_walk_through_the_core_loads_no_face():
    """Every core module, a walk with its frame sink, a push, and pelvic_walk's simulate,
    horizon and compare: no web server, scene, viewer, live or command-line module loaded."""
    proc = subprocess.run(
        [sys.executable, "-c", WALK_THROUGH_THE_CORE],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout.strip().splitlines()[-1]) == []


def test_the_import_contracts_name_the_core():
    """The contracts that keep the core headless are in pyproject.toml (make lint checks them)."""
    text = (Path(__file__).resolve().parents[1] / "pyproject.toml").read_text()
    assert 'source_modules = ["pelvic_walk.core"]' in text
    assert 'forbidden_modules = ["app", "fastapi", "uvicorn", "viser", "mjviser"]' in text


BROKEN = """
import pelvic_walk as pw


class Broken(pw.PelvisStrategy):
    name = "broken"

    def waist_rate(self, s):
        if s.step == 2:
            raise RuntimeError("a student's bug")
        return 0.0
"""


@pytest.fixture
def broken(tmp_path, monkeypatch):
    path = tmp_path / "broken.py"
    path.write_text(textwrap.dedent(BROKEN).lstrip())
    monkeypatch.chdir(tmp_path)
    yield path
    strategy.unregister("broken")


def test_push_study_contains_a_strategys_fault_with_one_line(broken, capsys, tmp_path):
    """One push each: the broken strategy's row says it stopped, the MPC's row stands, one line
    on stderr names the file and line, exit 1 (as simulate)."""
    out = tmp_path / "p.json"
    argv = ["push-study", "--strategy", str(broken), "--methods", "broken", "mpc"]
    assert main([*argv, "--force", "40", "--json", str(out)]) == 1
    std = capsys.readouterr()
    lines = std.err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in std.err
    assert "broken.py:9" in lines[0] and "a student's bug" in lines[0]
    assert "broken: 40 N" in std.out and "STOPPED by its strategy" in std.out
    assert "mpc: 40 N" in std.out and "recovered" in std.out
    pushes = json.loads(out.read_text())["pushes"]
    assert [p["method"] for p in pushes] == ["broken", "mpc"]
    assert pushes[0]["error"] and pushes[1]["error"] is None and pushes[1]["recovered"]


def test_push_study_bisection_stops_at_a_strategys_fault(broken, capsys):
    """The bisection gives no figure for a strategy that raised: its row says so, exit 1."""
    assert main(["push-study", "--strategy", str(broken), "--methods", "broken"]) == 1
    std = capsys.readouterr()
    assert "| broken | 0.30 | left, 0.10 s | - | - | stopped by its strategy |" in std.out
    said = [line for line in std.err.splitlines() if line.startswith("pelvic-walk")]
    assert len(said) == 1 and "broken.py:9" in said[0] and "Traceback" not in std.err
