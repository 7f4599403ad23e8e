"""Which report ``/report`` serves, and what it says about it (:func:`choose_report`).

In order: the directory given to ``serve --report DIR``; else the latest report this user's
own ``pelvic-walk experiments --out DIR`` wrote outside temporary folders; else the reference
report shipped with the package (the repository's ``report/``, installed as
``app.reference_report``). Whatever it shows, the page says which run it is.

``experiments --out DIR`` records DIR in a small state file
(``$XDG_STATE_HOME/pelvic-walk/report-dirs``, by default ``~/.local/state/pelvic-walk/``),
newest first, so the web tool finds the report wherever it was written and whatever the
server's working directory. A report written under a temporary folder (the system's, or a
test's) is neither recorded nor served: a test run must never replace the reference report.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

STATE_NAME = "report-dirs"
KEEP = 10  # remembered directories: a deleted newest one falls back to the one before


def state_file() -> Path:
    """The file listing the report directories written, newest first."""
    base = os.environ.get("XDG_STATE_HOME") or ""
    root = Path(base) if os.path.isabs(base) else Path.home() / ".local" / "state"
    return root / "pelvic-walk" / STATE_NAME


def package_dir(package: str) -> Path:
    """The directory of an installed package's files (wheels and editable installs unpack)."""
    files = resources.files(package)
    if not isinstance(files, Path):
        raise RuntimeError(f"{package} is not installed as plain files ({files!r})")
    return files


def reference_report_dir() -> Path:
    """The committed reference report, installed as package data."""
    return package_dir("app.reference_report")


def is_temporary(path: Path) -> bool:
    """True for a folder under a temporary directory: the system's (``tempfile``'s, /tmp,
    /var/tmp) or pytest's (``pytest-of-<user>``)."""
    p = Path(path).resolve()
    roots = {Path(tempfile.gettempdir()).resolve(), Path("/tmp").resolve(), Path("/var/tmp")}
    if any(r == p or r in p.parents for r in roots):
        return True
    return any(part.startswith("pytest-of-") for part in p.parts)


def record_report_dir(out: Path) -> None:
    """Remember that a report was written to ``out`` (not under a temporary folder); a state
    file we cannot write is only a warning (the report itself is written)."""
    if is_temporary(out):
        return
    path = state_file()
    entry = str(Path(out).resolve())
    try:
        kept = [d for d in _recorded(path) if d != entry]
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp")
        tmp.write_text("\n".join([entry, *kept][:KEEP]) + "\n", encoding="utf-8")
        tmp.replace(path)
    except OSError as exc:
        print(
            f"pelvic-walk: warning: could not record the report directory in {path}: {exc}",
            file=sys.stderr,
        )


def latest_report_dir() -> Path:
    """The newest recorded directory outside temporary folders that still holds a
    ``report.md``, else the reference."""
    for entry in _recorded(state_file()):
        if (Path(entry) / "report.md").is_file() and not is_temporary(Path(entry)):
            return Path(entry)
    return reference_report_dir()


@dataclass(frozen=True)
class ReportChoice:
    """The report ``/report`` shows and one line saying which run it is."""

    path: Path
    kind: str  # "chosen" (serve --report), "latest" (this user's experiments), "reference"
    about: str  # e.g. "Reference report shipped with pelvic-walk: ..." (plain text)


def choose_report(explicit: Path | None = None) -> ReportChoice:
    """``explicit`` (``serve --report DIR``), else this user's latest ``experiments`` run
    outside temporary folders, else the reference report; with a line saying which."""
    if explicit is not None:
        path, kind, head = Path(explicit), "chosen", "The report chosen with serve --report"
    else:
        path = latest_report_dir()
        if path == reference_report_dir():
            kind, head = "reference", "The reference report shipped with pelvic-walk"
        else:
            kind, head = "latest", "Your latest pelvic-walk experiments run"
    where = "" if kind == "reference" else f" ({path})"
    return ReportChoice(path, kind, f"{head}{where}: {describe_run(path)}.")


def describe_run(path: Path) -> str:
    """What run made the report in ``path``, from its ``results.json`` (command, full or
    quick study, date), or what is known without it."""
    try:
        meta = json.loads((Path(path) / "results.json").read_text(encoding="utf-8"))["meta"]
    except (OSError, ValueError, KeyError, TypeError):
        meta = None
    if not isinstance(meta, dict):
        return "no results.json beside it, so the run is not known"
    parts = []
    if meta.get("command"):
        parts.append(f"made by `{meta['command']}`")
    if meta.get("study"):
        parts.append(f"{meta['study']} study")
    if meta.get("date_utc"):
        parts.append(f"on {meta['date_utc']}")
    if meta.get("n_runs"):
        parts.append(f"{meta['n_runs']} runs")
    return ", ".join(parts) or "its results.json does not say how it was made"


def _recorded(path: Path) -> list[str]:
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return []
    return [line for line in (x.strip() for x in lines) if os.path.isabs(line)]
