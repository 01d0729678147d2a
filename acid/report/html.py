"""A self-contained HTML report: comparison table (paper vs acid) and embedded figures.

The page needs no server and no network: figures are embedded as base64 PNG data URIs.
"""

from __future__ import annotations

import base64
import html
from dataclasses import dataclass
from pathlib import Path

from acid._io import write_text


@dataclass(frozen=True)
class ComparisonRow:
    """One paper result: what the paper reports, what acid measured, and whether they agree."""

    section: str
    quantity: str
    paper: str
    acid: str
    agrees: bool | None
    note: str = ""


@dataclass(frozen=True)
class FigureRef:
    """A PNG to embed, with a caption that names the paper figure it reproduces."""

    path: Path
    caption: str


_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:2em auto;
max-width:1100px;color:#1b1f23;line-height:1.45;padding:0 1em}
h1{font-size:1.6em;margin-bottom:.2em} h2{margin-top:1.6em;border-bottom:1px solid #ddd}
table{border-collapse:collapse;width:100%;font-size:.92em;margin:.6em 0}
th,td{border:1px solid #d0d7de;padding:.35em .55em;text-align:left;vertical-align:top}
th{background:#f6f8fa} td.num{text-align:right;font-variant-numeric:tabular-nums}
.ok{color:#116329;font-weight:600} .no{color:#a40e26;font-weight:600} .na{color:#6e7781}
figure{margin:1.2em 0;text-align:center} figure img{max-width:100%;border:1px solid #eee}
figcaption{font-size:.9em;color:#57606a;margin-top:.3em} .meta{color:#57606a;font-size:.88em}
"""


def _img_tag(path: Path) -> str:
    data = base64.b64encode(Path(path).read_bytes()).decode()
    return f'<img src="data:image/png;base64,{data}" alt="{html.escape(Path(path).name)}">'


def render_report(title: str, rows: list[ComparisonRow], figures: list[FigureRef],
                  stage_times: list[tuple[str, float, bool]], meta: dict[str, str]) -> str:
    """Build the HTML text of the report."""
    e = html.escape
    out = [f"<!doctype html><html lang=en><head><meta charset=utf-8><title>{e(title)}</title>"
           f"<style>{_CSS}</style></head><body>", f"<h1>{e(title)}</h1>"]
    out.append("<p class=meta>" + " &middot; ".join(f"{e(k)}: {e(str(v))}"
                                                     for k, v in meta.items()) + "</p>")
    out.append("<h2>Paper vs acid</h2><table><tr><th>result</th><th>quantity</th>"
               "<th>paper</th><th>acid (measured)</th><th>agrees</th><th>note</th></tr>")
    for r in rows:
        cls, word = {True: ("ok", "yes"), False: ("no", "no"), None: ("na", "n/a")}[r.agrees]
        out.append(f"<tr><td>{e(r.section)}</td><td>{e(r.quantity)}</td>"
                   f"<td class=num>{e(r.paper)}</td><td class=num>{e(r.acid)}</td>"
                   f"<td class={cls}>{word}</td><td>{e(r.note)}</td></tr>")
    out.append("</table>")
    out.append("<h2>Figures</h2>")
    for f in figures:
        out.append(f"<figure>{_img_tag(f.path)}<figcaption>{e(f.caption)}</figcaption></figure>")
    out.append("<h2>Stages</h2><table><tr><th>stage</th><th>time (s)</th><th>cache</th></tr>")
    for name, seconds, cached in stage_times:
        out.append(f"<tr><td>{e(name)}</td><td class=num>{seconds:.1f}</td>"
                   f"<td>{'reused' if cached else 'computed'}</td></tr>")
    out.append("</table></body></html>")
    return "\n".join(out)


def write_report(path: Path, *args, **kwargs) -> Path:
    """Render and write the report atomically."""
    return write_text(path, render_report(*args, **kwargs))
