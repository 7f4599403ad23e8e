"""``/report``'s Markdown rendering (markdown-it-py) and which report directory it shows."""

from __future__ import annotations

import re
from pathlib import Path

from app.web.report_page import markdown_to_html, render_report_page, report_url
from pelvic_walk.core.report_dir import (
    latest_report_dir,
    record_report_dir,
    reference_report_dir,
    state_file,
)

TABLE = """
| length [m] | method | peak \\|d rate/dt\\| [deg/s^2] | verdict |
|---|---|---|---|
| 0.4 | mpc | peak \\|d rate/dt\\| 178 | **holds** |
"""


def _rows(html: str) -> list[list[str]]:
    return [
        re.findall(r"<t[hd][^>]*>(.*?)</t[hd]>", row, re.S)
        for row in re.findall(r"<tr>(.*?)</tr>", html, re.S)
    ]


def test_an_escaped_bar_stays_inside_its_cell():
    rows = _rows(markdown_to_html(TABLE))
    assert [len(r) for r in rows] == [4, 4]
    assert rows[1][2] == "peak |d rate/dt| 178"
    assert rows[1][3] == "<strong>holds</strong>"


def test_image_and_link_urls_resolve_under_report():
    html = markdown_to_html(
        "![waist](figures/waist.png) [data](./results.json) [top](#claims) "
        "[paper](https://doi.org/10.1109/ACCESS.2022.3169886) [api](/docs)"
    )
    assert '<img src="/report/figures/waist.png" alt="waist"' in html
    assert 'href="/report/results.json"' in html
    assert 'href="#claims"' in html and 'href="/docs"' in html
    assert 'href="https://doi.org/10.1109/ACCESS.2022.3169886"' in html
    assert report_url("figures/x.png") == "/report/figures/x.png"


def test_details_blocks_and_their_markdown():
    html = markdown_to_html(
        "<details><summary>every sweep run</summary>\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n"
        "</details>\n"
    )
    assert "<details><summary>every sweep run</summary>" in html and "</details>" in html
    assert [len(r) for r in _rows(html)] == [2, 2]


def test_the_reference_report_renders_with_its_figures():
    page = render_report_page(reference_report_dir())
    assert page.startswith("<!doctype html>") and "<style>" in page
    assert page.count("<table>") >= 5
    for src in re.findall(r'<img src="([^"]+)"', page):
        assert src.startswith("/report/figures/")
        assert (reference_report_dir() / src.removeprefix("/report/")).is_file()


def test_no_report_yet(tmp_path):
    assert "No report yet" in render_report_page(tmp_path / "missing")


def _users_own(monkeypatch, home: Path) -> None:
    """Folders under ``home`` count as the user's own here (tmp_path is a temporary folder,
    whose reports are neither recorded nor shown)."""
    import pelvic_walk.core.report_dir

    monkeypatch.setattr(
        pelvic_walk.core.report_dir, "is_temporary", lambda p: home not in Path(p).parents
    )


def test_the_latest_written_report_is_remembered(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "state"))
    _users_own(monkeypatch, tmp_path)
    assert state_file() == tmp_path / "state" / "pelvic-walk" / "report-dirs"
    assert latest_report_dir() == reference_report_dir()
    older, newer = tmp_path / "older", tmp_path / "newer"
    for out in (older, newer):
        out.mkdir()
        (out / "report.md").write_text(f"# {out.name}\n")
        record_report_dir(out)
    assert latest_report_dir() == newer
    (newer / "report.md").unlink()  # gone: the one before it
    assert latest_report_dir() == older
    record_report_dir(older)  # written again: listed once, first
    assert state_file().read_text().splitlines() == [str(older), str(newer)]
    (older / "report.md").unlink()
    assert latest_report_dir() == reference_report_dir()


def test_an_unwritable_state_dir_is_only_a_warning(tmp_path, monkeypatch, capsys):
    (tmp_path / "file").write_text("")
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "file"))  # a file, not a directory
    _users_own(monkeypatch, tmp_path)
    (tmp_path / "mine").mkdir()
    record_report_dir(tmp_path / "mine")
    assert "warning" in capsys.readouterr().err
    assert latest_report_dir() == reference_report_dir()


def test_reports_in_temporary_folders_are_neither_recorded_nor_shown(tmp_path, monkeypatch):
    """A test's `experiments` run (pytest's or the system's temporary folder) never becomes
    what /report shows."""
    import tempfile

    from pelvic_walk.core.report_dir import choose_report, is_temporary

    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "state"))
    assert is_temporary(tmp_path) and is_temporary(Path(tempfile.gettempdir()) / "x")
    assert not is_temporary(Path.home() / "study")  # (a clone in /tmp has its reference there)
    (tmp_path / "report.md").write_text("# quick\n")
    record_report_dir(tmp_path)
    assert not state_file().exists()
    state_file().parent.mkdir(parents=True)
    state_file().write_text(f"{tmp_path}\n")  # recorded by an older version
    choice = choose_report()
    assert choice.path == reference_report_dir() and choice.kind == "reference"
    assert choice.about.startswith("The reference report shipped with pelvic-walk: made by")
