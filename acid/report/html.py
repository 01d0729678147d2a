"""A self-contained HTML report: a short summary and the figures first, then the studies'
sections and the paper's claims with acid's verdicts.

The page needs no server and no network: figures are embedded as base64 PNG data URIs.
Every verdict comes from :mod:`acid.claims` (the report does not judge anything itself);
each claim row carries ``data-claim``, ``data-verdict`` and ``data-implies`` and each figure
``data-lines`` / ``data-hidden``, so that a browser check (``benchmarks/render_report.py``)
can re-check consistency and visibility on the rendered page.
"""

from __future__ import annotations

import base64
import html
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from acid._io import write_text
from acid.claims import ClaimVerdict, Verdict, contradictions, counts
from acid.report.figures import FigureRecord


@dataclass(frozen=True)
class ReportSection:
    """An extra section of the report (e.g. a study beyond the paper): a title, paragraphs
    of text and an optional table (``header`` and ``rows`` of strings)."""

    title: str
    paragraphs: tuple[str, ...] = ()
    header: tuple[str, ...] = ()
    rows: tuple[tuple[str, ...], ...] = ()
    #: shown right after the summary, before the figures (the energy answer)
    lead: bool = False


@dataclass(frozen=True)
class ReportFigure:
    """A PNG to embed with its record (caption, audit) from the stage's ``figures.json``."""

    path: Path
    record: FigureRecord


@dataclass(frozen=True)
class StageTime:
    """One stage line of the report: title, wall time (s), whether it came from the cache."""

    title: str
    seconds: float
    cached: bool


@dataclass(frozen=True)
class Report:
    """Everything the page shows."""

    title: str
    verdicts: Sequence[ClaimVerdict]
    figures: Sequence[ReportFigure] = ()
    sections: Sequence[ReportSection] = ()
    stages: Sequence[StageTime] = ()
    meta: dict[str, str] = field(default_factory=dict)


_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:2em auto;
max-width:1150px;color:#1b1f23;line-height:1.45;padding:0 1em}
h1{font-size:1.6em;margin-bottom:.2em} h2{margin-top:1.6em;border-bottom:1px solid #ddd}
table{border-collapse:collapse;width:100%;font-size:.9em;margin:.6em 0}
th,td{border:1px solid #d0d7de;padding:.35em .55em;text-align:left;vertical-align:top}
th{background:#f6f8fa} td.num{text-align:right;font-variant-numeric:tabular-nums}
td.section{background:#f6f8fa;font-weight:600}
.v-agrees{color:#116329;font-weight:600} .v-agrees-in-direction{color:#7d4e00;font-weight:600}
.v-disagrees{color:#a40e26;font-weight:600} .v-not-comparable,.v-not-measured,
.v-not-judged-quick-run,
.v-beyond-the-paper{color:#6e7781}
.counts span{margin-right:1.2em} .alert{background:#ffebe9;border:1px solid #a40e26;
padding:.6em;color:#a40e26} .small{font-size:.85em;color:#57606a}
figure{margin:1.2em 0;text-align:center} figure img{max-width:100%;border:1px solid #eee}
figcaption{font-size:.9em;color:#57606a;margin-top:.3em} .meta{color:#57606a;font-size:.88em}
nav.toc{background:#f6f8fa;border:1px solid #d0d7de;padding:.4em 1em;font-size:.9em}
nav.toc ol{margin:.3em 0;padding-left:1.4em} details.fold>summary{cursor:pointer;color:#0969da}
"""

#: a table with more rows than this is folded (``<details>``): the page stays navigable
FOLD_ROWS = 12


def _img_tag(path: Path) -> str:
    data = base64.b64encode(Path(path).read_bytes()).decode()
    return f'<img src="data:image/png;base64,{data}" alt="{html.escape(Path(path).name)}">'


def _css_class(v: Verdict) -> str:
    import re

    return "v-" + re.sub(r"[^a-z]+", "-", v.value).strip("-")


def _claims_table(verdicts: Sequence[ClaimVerdict]) -> list[str]:
    e = html.escape
    out = ["<table class=claims><tr><th>quantity</th><th>paper</th><th>acid (measured)</th>"
           "<th>verdict</th><th>rule</th><th>why / note</th></tr>"]
    section = None
    for v in verdicts:
        c = v.claim
        if c.section != section:
            section = c.section
            out.append(f"<tr><td class=section colspan=6>{e(section)}</td></tr>")
        src = f"<div class=small>{e(c.paper.source)}</div>" if c.paper is not None else ""
        quote = (f"<div class=small>&ldquo;{e(c.paper.text)}&rdquo;</div>"
                 if c.paper is not None and c.paper.text and c.paper.value is not None else "")
        note = e(v.reason) + (f"<div class=small>{e(c.note)}</div>" if c.note else "")
        where = f"<div class=small>{e(c.measured.where())}</div>" if c.measured else ""
        out.append(
            f'<tr data-claim="{e(c.id)}" data-verdict="{e(v.verdict.value)}" '
            f'data-implies="{e(" ".join(c.implies))}"><td>{e(c.quantity)}{where}</td>'
            f"<td class=num>{e(v.paper_text)}{quote}{src}</td>"
            f"<td class=num>{e(v.acid_text)}</td>"
            f"<td class={_css_class(v.verdict)}>{e(v.verdict.value)}</td>"
            f"<td>{e(c.rule_text)}</td><td>{note}</td></tr>")
    out.append("</table>")
    return out


#: the columns of the summary: verdicts counted per section of the paper
_SUMMARY_COLUMNS = (Verdict.AGREES, Verdict.DIRECTION, Verdict.DISAGREES)


def _summary(report: Report) -> list[str]:
    """The short summary that opens the page: the verdict counts, any contradiction, and one
    row per section of the paper (how many of its claims agree, agree in direction only,
    disagree or have no verdict (not comparable, not measured, not judged), which ones
    disagree); the full table of claims is further down."""
    e = html.escape
    n = counts(report.verdicts)
    out = ["<h2 id=summary>Summary</h2><p class=counts id=counts>" + "".join(
        f'<span data-verdict="{e(k)}" data-count="{c}"><b>{c}</b> {e(k)}</span>'
        for k, c in n.items() if k != Verdict.BEYOND.value) + "</p>"]
    bad = contradictions(report.verdicts)
    if bad:
        out.append("<p class=alert id=contradictions>Contradictory verdicts: "
                   + "; ".join(e(b) for b in bad) + "</p>")
    by_section: dict[str, list[ClaimVerdict]] = {}
    for v in report.verdicts:
        if v.claim.paper is not None:
            by_section.setdefault(v.claim.section, []).append(v)
    out.append("<table class=summary><tr><th>section of the paper</th>"
               + "".join(f"<th>{e(c.value)}</th>" for c in _SUMMARY_COLUMNS)
               + "<th>no verdict</th><th>what disagrees</th></tr>")
    for section, vs in by_section.items():
        tally = [sum(v.verdict is c for v in vs) for c in _SUMMARY_COLUMNS]
        other = len(vs) - sum(tally)
        worst = "; ".join(e(v.claim.quantity) for v in vs if v.verdict is Verdict.DISAGREES)
        out.append(f"<tr><td>{e(section)}</td>"
                   + "".join(f"<td class=num>{t}</td>" for t in tally)
                   + f"<td class=num>{other}</td><td>{worst}</td></tr>")
    out.append("</table>")
    n_paper = sum(len(vs) for vs in by_section.values())
    out.append(f"<p class=small>The figures follow; then the studies' own sections, and "
               f'<a href="#claims">every claim of the paper</a> ({n_paper} rows) with its '
               "value, acid's measurement and the rule of its verdict.</p>")
    return out


def _figures(report: Report) -> list[str]:
    e = html.escape
    out = ["<h2 id=figures>Figures</h2>"]
    for f in report.figures:
        r = f.record
        warn = (f"<div class=alert>hidden lines: {e('; '.join(r.hidden))}</div>"
                if r.hidden else "")
        out.append(f'<figure data-lines="{r.labelled_lines}" data-hidden="{len(r.hidden)}">'
                   f"{_img_tag(f.path)}<figcaption>{e(r.caption)}</figcaption>{warn}</figure>")
    return out


def _anchors(report: Report) -> list[str]:
    """One unique anchor per study section, from its title."""
    used, out = {"summary", "figures", "claims", "beyond", "stages", "contents"}, []
    for s in report.sections:
        base = re.sub(r"[^a-z0-9]+", "-", s.title.lower()).strip("-") or "section"
        slug, i = base, 2
        while slug in used:
            slug, i = f"{base}-{i}", i + 1
        used.add(slug)
        out.append(slug)
    return out


def _contents(report: Report) -> list[str]:
    """The table of contents: every heading of the page, linked."""
    e = html.escape
    sections = list(zip(_anchors(report), report.sections, strict=True))
    items = [("summary", "Summary")]
    items += [(a, s.title) for a, s in sections if s.lead]
    items += [("figures", "Figures")]
    items += [(a, s.title) for a, s in sections if not s.lead]
    items += [("claims", "Paper vs acid: every claim")]
    if any(v.claim.paper is None for v in report.verdicts):
        items.append(("beyond", "Beyond the paper"))
    items.append(("stages", "Stages"))
    return ["<nav class=toc id=contents><b>Contents</b><ol>"
            + "".join(f'<li><a href="#{a}">{e(t)}</a></li>' for a, t in items)
            + "</ol></nav>"]


def _fold(rows: list[str], n: int, what: str) -> list[str]:
    """``rows`` (a table's HTML) folded behind a summary line when it has more than
    ``FOLD_ROWS`` rows."""
    if n <= FOLD_ROWS:
        return rows
    return [f"<details class=fold><summary>{html.escape(what)} ({n} rows)</summary>", *rows,
            "</details>"]


def _sections(report: Report, lead: bool = False) -> list[str]:
    """The studies' sections: those marked ``lead`` when ``lead``, else the others."""
    e = html.escape
    out = []
    for s, anchor in zip(report.sections, _anchors(report), strict=True):
        if s.lead != lead:
            continue
        out.append(f"<h2 id={anchor}>{e(s.title)}</h2>")
        out += [f"<p>{e(p)}</p>" for p in s.paragraphs]
        if s.header:
            table = ["<table><tr>" + "".join(f"<th>{e(h)}</th>" for h in s.header) + "</tr>"]
            table += ["<tr>" + "".join(f"<td>{e(c)}</td>" for c in r) + "</tr>" for r in s.rows]
            table.append("</table>")
            out += _fold(table, len(s.rows), "Show the table")
    return out


def _claims(report: Report) -> list[str]:
    e = html.escape
    paper = [v for v in report.verdicts if v.claim.paper is not None]
    beyond = [v for v in report.verdicts if v.claim.paper is None]
    out = ["<h2 id=claims>Paper vs acid: every claim</h2>",
           "<p class=small>Every verdict below is computed from the claims registry "
           "(<code>acid.claims</code>): the paper's value, where acid measures it, and the "
           "rule named in each row.</p>"]
    out += _fold(_claims_table(paper), len(paper), "Show every claim with its rule")
    if beyond:
        out.append("<h2 id=beyond>Beyond the paper</h2>")
        table = ["<table class=claims><tr><th>quantity</th>"
                 "<th>acid (measured)</th><th>note</th></tr>"]
        for v in beyond:
            c = v.claim
            where = f"<div class=small>{e(c.measured.where())}</div>" if c.measured else ""
            judged = "" if v.verdict is Verdict.BEYOND else \
                f"<div class={_css_class(v.verdict)}>{e(v.verdict.value)}: {e(v.reason)}</div>"
            table.append(f'<tr data-claim="{e(c.id)}" data-verdict="{e(v.verdict.value)}" '
                         f'data-implies=""><td>{e(c.quantity)}{where}</td>'
                         f"<td class=num>{e(v.acid_text)}</td><td>{judged}{e(c.note)}</td>"
                         "</tr>")
        table.append("</table>")
        out += _fold(table, len(beyond), "Show acid's measurements beyond the paper")
    return out


def render_report(report: Report) -> str:
    """The HTML text of the report, in reading order: a short summary (verdict counts and
    the headline rows), the figures, the studies' sections, then every claim with its rule,
    and the stages' times."""
    e = html.escape
    out = [f"<!doctype html><html lang=en><head><meta charset=utf-8><title>{e(report.title)}"
           f"</title><style>{_CSS}</style></head><body>", f"<h1>{e(report.title)}</h1>"]
    out.append("<p class=meta>" + " &middot; ".join(f"{e(k)}: {e(str(v))}"
                                                     for k, v in report.meta.items()) + "</p>")
    out += (_contents(report) + _summary(report) + _sections(report, lead=True)
            + _figures(report) + _sections(report) + _claims(report))
    out.append("<h2 id=stages>Stages</h2><table><tr><th>stage</th><th>time (s)</th>"
               "<th>cache</th></tr>")
    for s in report.stages:
        out.append(f"<tr><td>{e(s.title)}</td><td class=num>{s.seconds:.1f}</td>"
                   f"<td>{'reused' if s.cached else 'computed'}</td></tr>")
    out.append("</table></body></html>")
    return "\n".join(out)


def write_report(path: Path, report: Report) -> Path:
    """Render and write the report atomically."""
    return write_text(path, render_report(report))
