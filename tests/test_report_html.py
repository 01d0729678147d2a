"""acid.report.html: the page reads summary first, figures next, every claim after."""

from __future__ import annotations

import base64
import re

from _claims import results

from acid.claims import Verdict, counts, evaluate
from acid.report.figures import FigureRecord
from acid.report.html import Report, ReportFigure, ReportSection, render_report

#: a 1x1 PNG
PNG = base64.b64decode("iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9Q"
                       "DwADhgGAWjR9awAAAABJRU5ErkJggg==")


def _page(tmp_path) -> tuple[str, list]:
    png = tmp_path / "fig.png"
    png.write_bytes(PNG)
    verdicts = evaluate(results())
    report = Report(title="t", verdicts=verdicts,
                    figures=[ReportFigure(png, FigureRecord("fig.png", "a caption", 2))],
                    sections=[ReportSection("Where the energy is", ("a study",))])
    return render_report(report), verdicts


def test_summary_then_figures_then_sections_then_every_claim(tmp_path):
    page, _ = _page(tmp_path)
    where = {name: page.index(marker) for name, marker in (
        ("summary", "<h2 id=summary>"), ("figures", "<h2 id=figures>"),
        ("section", "<h2 id=where-the-energy-is>Where the energy is</h2>"),
        ("claims", "<h2 id=claims>"),
        ("first claim row", "<tr data-claim="), ("stages", "<h2 id=stages>Stages</h2>"))}
    assert list(where) == sorted(where, key=where.get), where
    assert page.index("<figure") < where["claims"]


def test_the_summary_is_short_and_counts_each_section(tmp_path):
    page, verdicts = _page(tmp_path)
    summary = page[page.index("<h2 id=summary>"):page.index("<h2 id=figures>")]
    sections = list(dict.fromkeys(v.claim.section for v in verdicts if v.claim.paper))
    assert summary.count("<tr>") == len(sections) + 1     # one row per section of the paper
    for section in sections:
        row = summary[summary.index(f"<td>{section}</td>"):]
        row = row[:row.index("</tr>")]
        vs = [v for v in verdicts if v.claim.section == section and v.claim.paper]
        cells = [int(c) for c in re.findall(r"<td class=num>(\d+)</td>", row)]
        assert sum(cells) == len(vs), section
        assert cells[2] == sum(v.verdict is Verdict.DISAGREES for v in vs)
        for v in vs:
            assert (v.claim.quantity in row) == (v.verdict is Verdict.DISAGREES), v.claim.id
    n = counts(verdicts)
    agree = n[Verdict.AGREES.value]
    assert f'data-verdict="agrees" data-count="{agree}"' in summary
    # a summary, not the table: far fewer rows than the claims below
    paper_rows = sum(v.claim.paper is not None for v in verdicts)
    assert summary.count("<tr>") < paper_rows / 3
    assert f"({paper_rows} rows)" in summary and 'href="#claims"' in summary
    assert "data-claim=" not in summary   # the browser check counts the claim rows below


def test_a_table_of_contents_links_every_heading_and_long_tables_fold(tmp_path):
    """The page is navigable: a contents list links every heading's anchor (each anchor
    exists once), and the long claims table sits behind a summary line."""
    page, verdicts = _page(tmp_path)
    toc = page[page.index("<nav class=toc"):page.index("</nav>")]
    anchors = re.findall(r'href="#([a-z0-9-]+)"', toc)
    assert anchors[:2] == ["summary", "figures"] and "where-the-energy-is" in anchors
    for a in anchors:
        assert page.count(f"id={a}>") == 1, a
    claims = page[page.index("<h2 id=claims>"):]
    n_paper = sum(v.claim.paper is not None for v in verdicts)
    assert f"<details class=fold><summary>Show every claim with its rule ({n_paper} rows)" \
        in claims
