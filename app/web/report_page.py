"""``GET /report``: the experiments' ``report.md`` as a simple HTML page.

A small Markdown subset (headings, paragraphs, lists, pipe tables, fenced code, images,
links, bold, italics, inline code) is enough for the generated report; no extra dependency.
Images and links resolve under ``/report/`` (e.g. ``figures/x.png`` -> ``/report/figures/x.png``).
"""

from __future__ import annotations

import html
import re
from pathlib import Path

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
"""


def _inline(text: str) -> str:
    t = html.escape(text, quote=False)
    t = re.sub(r"`([^`]+)`", r"<code>\1</code>", t)
    t = re.sub(r"!\[([^\]]*)\]\(([^)\s]+)\)",
               lambda m: f'<img alt="{m[1]}" src="{_url(m[2])}">', t)
    t = re.sub(r"\[([^\]]+)\]\(([^)\s]+)\)", lambda m: f'<a href="{_url(m[2])}">{m[1]}</a>', t)
    t = re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", t)
    t = re.sub(r"(?<![*\w])\*([^*]+)\*(?![*\w])", r"<em>\1</em>", t)
    return t


def _url(target: str) -> str:
    if re.match(r"^[a-z]+:|^/|^#", target):
        return target
    return "/report/" + target.removeprefix("./")


def markdown_to_html(md: str) -> str:
    """Render the Markdown subset described in the module docstring."""
    out: list[str] = []
    lines = md.splitlines()
    i = 0
    para: list[str] = []

    def flush() -> None:
        if para:
            out.append(f"<p>{_inline(' '.join(para))}</p>")
            para.clear()

    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        if stripped.startswith("```"):
            flush()
            j = i + 1
            while j < len(lines) and not lines[j].strip().startswith("```"):
                j += 1
            out.append(f"<pre><code>{html.escape(chr(10).join(lines[i + 1:j]))}</code></pre>")
            i = j + 1
            continue
        m = re.match(r"^(#{1,6})\s+(.*)$", stripped)
        if m:
            flush()
            n = len(m[1])
            out.append(f"<h{n}>{_inline(m[2])}</h{n}>")
        elif stripped.startswith("|"):
            flush()
            rows = []
            while i < len(lines) and lines[i].strip().startswith("|"):
                rows.append([c.strip() for c in lines[i].strip().strip("|").split("|")])
                i += 1
            body = [r for r in rows if not all(re.fullmatch(r":?-{2,}:?", c) for c in r)]
            head, rest = body[0], body[1:]
            out.append("<table><tr>" + "".join(f"<th>{_inline(c)}</th>" for c in head) + "</tr>")
            for r in rest:
                out.append("<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in r) + "</tr>")
            out.append("</table>")
            continue
        elif re.match(r"^([-*]|\d+\.)\s+", stripped):
            flush()
            tag = "ol" if stripped[0].isdigit() else "ul"
            out.append(f"<{tag}>")
            while i < len(lines) and re.match(r"^\s*([-*]|\d+\.)\s+", lines[i]):
                item = re.sub(r"^\s*([-*]|\d+\.)\s+", "", lines[i])
                out.append(f"<li>{_inline(item)}</li>")
                i += 1
            out.append(f"</{tag}>")
            continue
        elif not stripped:
            flush()
        else:
            para.append(stripped)
        i += 1
    flush()
    return "\n".join(out)


def render_report_page(report_dir: Path) -> str:
    """The report as HTML, or a page saying how to generate it."""
    md_path = report_dir / "report.md"
    nav = '<nav><a href="/">Live tool</a><a href="/docs">API docs</a></nav>'
    if md_path.is_file():
        body = markdown_to_html(md_path.read_text(encoding="utf-8"))
    else:
        body = (
            "<h1>No report yet</h1><p>Generate it with</p>"
            "<pre><code>pelvic-walk experiments --out report</code></pre>"
            "<p>(add <code>--quick</code> for a short version), then reload this page.</p>"
        )
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>pelvic-walk report"
            f"</title><style>{_STYLE}</style></head><body>{nav}{body}</body></html>")
