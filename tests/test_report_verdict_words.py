"""Energy statements carry their interval or no verdict word (README, generated reports)."""

from pathlib import Path

import pytest

from acid.report.verdict_words import unjudged_statements

ROOT = Path(__file__).resolve().parents[1]


def test_scanner_flags_a_point_only_verdict_and_passes_a_judged_one():
    assert unjudged_statements("E saves 0.2 % against F on UDDS.") == [
        "E saves 0.2 % against F on UDDS."]
    assert unjudged_statements("E beats F by 0.21 points on SC03.")
    # the interval, or the engine's undecided words, make it a judged statement
    assert not unjudged_statements("E saves 0.2 % [+0.1, +0.4] against F (held out).")
    assert not unjudged_statements("E vs F +0.2 %: no resolvable difference.")
    # a measured figure without a verdict word, and verdict words about no energy
    assert not unjudged_statements("E used 0.2 % less than F on UDDS (one run).")
    assert not unjudged_statements("A stage saves each figure as PNG.")
    assert not unjudged_statements("the heater costs 58 % of the range at -10 C.")


def test_readme_has_no_point_only_energy_verdict():
    bad = unjudged_statements((ROOT / "README.md").read_text(encoding="utf-8"))
    assert not bad, "\n".join(bad)


def test_generated_reports_have_no_point_only_energy_verdict():
    texts = [p for p in (ROOT / "reports").rglob("*") if p.suffix in (".md", ".txt", ".html")
             and p.name != "README.md"]
    if not texts:
        pytest.skip("no generated report in reports/ (run acid reproduce)")
    bad = [s for p in texts for s in unjudged_statements(p.read_text(encoding="utf-8"))]
    assert not bad, "\n".join(bad)
