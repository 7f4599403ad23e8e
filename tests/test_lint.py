"""`make lint` as a test, so CI checks it too: ruff (rules, formatting), mypy (app, controller),
the import contracts between the layers (import-linter, pyproject.toml), no module importing
another's private names, and no citation of a file a clone of the repository does not have."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
PATHS = ["app", "controller", "models", "tests"]


# [s] a guard against a hung tool, not a speed target: mypy without its cache (a fresh clone)
# on a busy 2-core machine took more than 300 s (load average 25-35)
RUN_TIMEOUT_S = 1800


def _run(*cmd: str) -> subprocess.CompletedProcess:
    return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=RUN_TIMEOUT_S)


def test_ruff_rules_and_formatting():
    check = _run(str(BIN / "ruff"), "check", *PATHS)
    assert check.returncode == 0, check.stdout[-3000:]
    fmt = _run(str(BIN / "ruff"), "format", "--check", *PATHS)
    assert fmt.returncode == 0, fmt.stdout[-3000:]


def test_mypy_is_clean():
    result = _run(str(BIN / "mypy"))
    assert result.returncode == 0, result.stdout[-3000:]


def test_the_layers_import_only_downwards_and_no_package_has_an_import_circle():
    result = _run(str(BIN / "lint-imports"), "--no-cache")
    assert result.returncode == 0, result.stdout[-3000:]
    assert "0 broken" in result.stdout


def _sources() -> list[Path]:
    return [p for d in ("app", "controller", "models", "tests") for p in (ROOT / d).rglob("*.py")]


def test_no_module_imports_another_modules_private_names():
    found = []
    for path in _sources():
        if path.is_relative_to(ROOT / "tests"):
            continue  # a test may check a module's helper directly
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                ours = node.module.split(".")[0] in ("app", "controller", "models")
                private = [a.name for a in node.names if a.name.startswith("_")]
                if ours and private and node.module != "__future__":
                    found.append(f"{path.relative_to(ROOT)}: {node.module} {private}")
    assert found == []


def test_nothing_cites_a_file_outside_the_repository():
    """The design lives in docs/: no path to the design inputs outside the repository, none of
    their file names, no issue numbers (the patterns are written so that this file does not
    match them itself)."""
    outside = re.compile(r"\.\./share[d]|shar[e]d/design|\b(SPEC|STYLE|ROBOT)\.md|[Ii]ssue #?\d")
    folders = ("app", "controller", "models", "tests", "static", "report", "docs")
    found = [
        f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
        for folder in folders
        for path in (ROOT / folder).rglob("*")
        if path.is_file() and path.suffix in (".py", ".md", ".j2", ".html", ".json", ".txt")
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1)
        if outside.search(line)
    ]
    found += [
        f"README.md: {ln}"
        for ln in (ROOT / "README.md").read_text().splitlines()
        if outside.search(ln)
    ]
    assert found == []
