"""Which report ``/report`` serves: the latest one ``pelvic-walk experiments`` wrote.

``experiments --out DIR`` records DIR in a small state file
(``$XDG_STATE_HOME/pelvic-walk/report-dirs``, by default ``~/.local/state/pelvic-walk/``),
newest first, so the web tool finds the report wherever it was written and whatever the
server's working directory. Without one that still exists, the reference report shipped with
the package (the repository's ``report/``, installed as ``app.reference_report``) is served.
"""

from __future__ import annotations

import os
import sys
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


def record_report_dir(out: Path) -> None:
    """Remember that a report was written to ``out``; a state file we cannot write is only
    a warning (the report itself is written)."""
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
    """The newest recorded directory that still holds a ``report.md``, else the reference."""
    for entry in _recorded(state_file()):
        if (Path(entry) / "report.md").is_file():
            return Path(entry)
    return reference_report_dir()


def _recorded(path: Path) -> list[str]:
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return []
    return [line for line in (x.strip() for x in lines) if os.path.isabs(line)]
