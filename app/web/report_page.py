"""``GET /report``: the experiments' ``report.md`` as a simple HTML page.

Rendered with markdown-it-py (CommonMark plus GitHub's pipe tables, where ``\\|`` is a ``|``
inside a cell, and raw HTML for the report's ``<details>`` blocks). Relative image and link
URLs resolve under ``/report/`` (e.g. ``figures/x.png`` -> ``/report/figures/x.png``), where
the report's directory is served.
"""

from __future__ import annotations

import re
from pathlib import Path

from markdown_it import MarkdownIt
from markdown_it.rules_core import StateCore

_STYLE = """
body { font: 15px/1.5 system-ui, sans-serif; max-width: 980px; margin: 2em auto; padding: 0 1em;
       color: #1d2330; }
table { border-collapse: collapse; margin: 1em 0; font-size: 14px; }
th, td { border: 1px solid #ccd; padding: 4px 8px; text-align: right; }
th { background: #eef1f6; }
td:first-child, th:first-child { text-align: left; }
img { max-width: 100%; }
pre { background: #f3f4f7; padding: 0.8em; overflow-x: auto; }
code { background: #f3f4f7; padding: 0 3px; }
nav a { margin-right: 1em; }
.which { background: #eef4ff; border: 1px solid #c9d8f5; border-radius: 6px; padding: 6px 10px;
         margin: 1em 0; font-size: 14px; }
"""
_ABSOLUTE = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:|^/|^#")  # scheme, absolute path, anchor
_URL_ATTRS = {"image": "src", "link_open": "href"}


def report_url(target: str) -> str:
    """A URL of the report resolved under ``/report/``; absolute ones and anchors unchanged."""
    if _ABSOLUTE.match(target):
        return target
    return "/report/" + target.removeprefix("./")


def _rewrite_urls(state: StateCore) -> None:
    """Core rule: point relative image and link URLs of the document under ``/report/``."""
    for block in state.tokens:
        for token in block.children or ():
            attr = _URL_ATTRS.get(token.type)
            value = token.attrGet(attr) if attr else None
            if isinstance(value, str):
                assert attr is not None  # value is None without one
                token.attrSet(attr, report_url(value))


def _parser() -> MarkdownIt:
    md = MarkdownIt("commonmark", {"html": True}).enable("table")
    md.core.ruler.after("inline", "report_urls", _rewrite_urls)
    return md


_MD = _parser()
_INLINE = MarkdownIt("commonmark", {"html": False})  # a line about the report: no raw HTML


def markdown_to_html(md: str) -> str:
    """Render the report's Markdown (see the module docstring)."""
    return _MD.render(md)


def render_report_page(report_dir: Path, about: str | None = None) -> str:
    """The report as HTML, or a page saying how to generate it; ``about`` (which run it is,
    :func:`pelvic_walk.core.report_dir.choose_report`) heads the page."""
    md_path = report_dir / "report.md"
    nav = '<nav><a href="/">Live tool</a><a href="/docs">API docs</a></nav>'
    which = f'<p class="which"><b>Which report:</b> {markdown_inline(about)}</p>' if about else ""
    try:
        body = markdown_to_html(md_path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError):
        body = (
            "<h1>No report yet</h1><p>Generate it with</p>"
            "<pre><code>pelvic-walk experiments --out report</code></pre>"
            "<p>(add <code>--quick</code> for a short version), then reload this page.</p>"
        )
    return (
        "<!doctype html><html><head><meta charset='utf-8'><title>pelvic-walk report"
        f"</title><style>{_STYLE}</style></head><body>{nav}{which}{body}</body></html>"
    )


def markdown_inline(text: str) -> str:
    """One line of Markdown (code spans) as HTML; raw HTML in it is escaped."""
    return _INLINE.renderInline(text)
