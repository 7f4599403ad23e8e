"""`make lint` as a test, so CI checks it too: ruff (rules, formatting), mypy (app, controller)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
PATHS = ["app", "controller", "models", "tests"]


def _run(*cmd: str) -> subprocess.CompletedProcess:
    return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)


def test_ruff_rules_and_formatting():
    check = _run(str(BIN / "ruff"), "check", *PATHS)
    assert check.returncode == 0, check.stdout[-3000:]
    fmt = _run(str(BIN / "ruff"), "format", "--check", *PATHS)
    assert fmt.returncode == 0, fmt.stdout[-3000:]


def test_mypy_is_clean():
    result = _run(str(BIN / "mypy"))
    assert result.returncode == 0, result.stdout[-3000:]
