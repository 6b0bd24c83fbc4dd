"""The demo report: Markdown (and a self-contained-looking HTML twin) with tables and figures.

Only formatting lives here: every number comes from the tables it is given.
"""

from __future__ import annotations

import functools
import html
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd


@dataclass
class Section:
    title: str
    text: list[str] = field(default_factory=list)  # Markdown paragraphs / tables / images


def fmt(value, digits: int = 3) -> str:
    """A table cell: floats to ``digits`` significant figures, whole floats as integers, nan as a dash."""
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isnan(v):
            return "–"
        if v.is_integer() and abs(v) < 1e6:
            return str(int(v))
        if abs(v) >= 10 ** digits:
            return f"{v:.0f}"
        return f"{v:.{digits}g}"
    return str(value)


def markdown_table(table: pd.DataFrame, digits: int = 3) -> str:
    """A GitHub-flavoured Markdown table of ``table`` (no index)."""
    header = "| " + " | ".join(str(c) for c in table.columns) + " |"
    rule = "|" + "|".join("---" for _ in table.columns) + "|"
    rows = ["| " + " | ".join(fmt(v, digits) for v in row) + " |" for row in table.itertuples(index=False)]
    return "\n".join([header, rule, *rows])


def figure(path: str, caption: str) -> str:
    return f"![{caption}]({path})\n\n*{caption}*"


def write_report(folder: Path, title: str, sections: list[Section]) -> tuple[Path, Path]:
    """Write ``report.md`` and ``report.html`` into ``folder``; image paths are relative to it."""
    md = [f"# {title}", ""]
    for sec in sections:
        md += [f"## {sec.title}", ""]
        for block in sec.text:
            md += [block, ""]
    from experiments.provenance import write_record

    md_path = write_record(folder / "report.md", "\n".join(md))  # whole: it tells a demo's folder (DEMO_OWNER)
    html_path = write_record(folder / "report.html", markdown_to_html("\n".join(md), title, images=folder))
    return md_path, html_path


_CSS = """body{font-family:system-ui,sans-serif;max-width:60rem;margin:2rem auto;padding:0 1rem;color:#222}
table{border-collapse:collapse;margin:0.5rem 0;font-size:0.9rem}th,td{border:1px solid #ccc;padding:0.2rem 0.5rem;
text-align:right}th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}img{max-width:100%;height:auto}
code,pre{background:#f6f6f6}pre{padding:0.5rem;overflow-x:auto}em{color:#555}.wide{overflow-x:auto;max-width:100%}
p,li{overflow-wrap:anywhere}"""


def markdown_to_html(text: str, title: str, images: Path | None = None) -> str:
    """The small Markdown subset the report uses (headings, tables, images, lists, code, emphasis).
    With ``images`` (the folder image paths are relative to), PNG / SVG / JPEG images are embedded
    as data URIs, so the page is one self-contained file; wide tables scroll inside the page."""
    inline = functools.partial(_inline, images=images)
    out = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
           f"<style>{_CSS}</style></head><body>"]
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("```"):
            j = i + 1
            while j < len(lines) and not lines[j].startswith("```"):
                j += 1
            out.append("<pre><code>" + html.escape("\n".join(lines[i + 1:j])) + "</code></pre>")
            i = j + 1
            continue
        if line.startswith("|"):
            rows = []
            while i < len(lines) and lines[i].startswith("|"):
                rows.append([c.strip() for c in lines[i].strip().strip("|").split("|")])
                i += 1
            head, body = rows[0], [r for r in rows[2:]]
            out.append("<div class='wide'><table><tr>" + "".join(f"<th>{inline(c)}</th>" for c in head) + "</tr>"
                       + "".join("<tr>" + "".join(f"<td>{inline(c)}</td>" for c in r) + "</tr>" for r in body)
                       + "</table></div>")
            continue
        m = re.match(r"^(#{1,4}) (.*)$", line)
        if m:
            n = len(m.group(1))
            out.append(f"<h{n}>{inline(m.group(2))}</h{n}>")
        elif line.startswith("- "):
            items = []
            while i < len(lines) and lines[i].startswith("- "):
                items.append(f"<li>{inline(lines[i][2:])}</li>")
                i += 1
            out.append("<ul>" + "".join(items) + "</ul>")
            continue
        elif line.strip():
            out.append(f"<p>{inline(line)}</p>")
        i += 1
    out.append("</body></html>")
    return "\n".join(out)


_MIME = {".png": "image/png", ".svg": "image/svg+xml", ".jpg": "image/jpeg", ".jpeg": "image/jpeg"}


def _src(path: str, images: Path | None) -> str:
    """A data URI of an image file below the report's folder ``images``, else the path as given."""
    import base64

    from experiments.options import real_path

    if images is None:
        return path
    file = real_path(images / html.unescape(path))  # Path.resolve: RuntimeError on a loop of links
    mime = _MIME.get(file.suffix.lower())
    if mime is None or not file.is_file():
        return path
    return f"data:{mime};base64," + base64.b64encode(file.read_bytes()).decode("ascii")


def _inline(text: str, images: Path | None = None) -> str:
    text = html.escape(text, quote=False)
    text = re.sub(r"!\[([^\]]*)\]\(([^)]+)\)", lambda m: f"<img src='{_src(m.group(2), images)}' alt='{m.group(1)}'>", text)
    text = re.sub(r"\[([^\]]+)\]\(([^)]+)\)", r"<a href='\2'>\1</a>", text)
    text = re.sub(r"`([^`]+)`", r"<code>\1</code>", text)
    text = re.sub(r"\*\*([^*]+)\*\*", r"<b>\1</b>", text)
    text = re.sub(r"(?<![\w*])\*([^*]+)\*(?![\w*])", r"<em>\1</em>", text)
    return text
