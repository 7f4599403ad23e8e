"""The study's and the sweep's modules are named by concept and import each other in one
direction: no ``*_more.py``, no module importing another's private names, no import circle
among ``app/experiments`` and the core's (``pelvic_walk/core``) modules, and the core never
imports the study (``experiments`` runs on the core's engine, not the other way round)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("app/experiments", "pelvic_walk/core")


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).glob("*.py")):
            name = ".".join(path.relative_to(ROOT).with_suffix("").parts)
            out[name.removesuffix(".__init__")] = path
    return out


def _imports(path: Path) -> list[tuple[str, list[str]]]:
    """(module, names) of every ``import`` / ``from ... import`` in a file, at any depth."""
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            out.append((node.module, [a.name for a in node.names]))
        elif isinstance(node, ast.Import):
            out += [(a.name, []) for a in node.names]
    return out


def _graph() -> dict[str, set[str]]:
    mods = _modules()
    graph: dict[str, set[str]] = {m: set() for m in mods}
    for m, path in mods.items():
        for target, names in _imports(path):
            subs = [f"{target}.{n}" for n in names if f"{target}.{n}" in mods]
            if subs:  # "from app.experiments import claims" imports the module claims
                graph[m].update(subs)
            elif target in mods:
                graph[m].add(target)
    return graph


def test_modules_are_named_by_concept():
    names = [p.name for p in _modules().values()]
    assert not [n for n in names if n.endswith("_more.py")], names


def test_no_module_imports_another_modules_private_names():
    mods = _modules()
    bad = [
        (m, target, n)
        for m, path in mods.items()
        for target, names in _imports(path)
        if target.startswith(("app.", "pelvic_walk.core"))
        for n in names
        if n.startswith("_") and not n.startswith("__")
    ]
    assert not bad, bad


def test_no_import_circle():
    graph = _graph()
    done: set[str] = set()

    def visit(m: str, stack: list[str]) -> None:
        if m in stack:
            raise AssertionError("import circle: " + " -> ".join([*stack[stack.index(m) :], m]))
        if m in done:
            return
        for n in sorted(graph[m]):
            visit(n, [*stack, m])
        done.add(m)

    for m in sorted(graph):
        visit(m, [])


def test_the_core_never_imports_the_study():
    graph = _graph()
    sweep = [m for m in graph if m.startswith("pelvic_walk.core")]
    assert not [(m, n) for m in sweep for n in graph[m] if n.startswith("app.experiments")]
