"""Energy verdict words that come without their interval.

An energy statement may say "saves", "beats", "costs", "gains", "loses", "is cheaper" or
"stays ahead" only when it carries the interval it was read from (``[lo, hi]``, as
:func:`acid.studies.verdict.paired_verdict` and ``acid compare`` print it) or the engine's
own words for an interval that decides nothing ("no resolvable difference", "not resolved",
"not at equal comfort"). Otherwise it is a measured figure and must be worded as one
("E used 0.2 % less than F on UDDS, one run"). :func:`unjudged_statements` finds the
sentences that break this rule in a text (a generated report, a claims summary, README.md).
"""

from __future__ import annotations

import re

#: words that state a verdict
VERDICT = re.compile(r"\b(saves?|saving more|beats?|costs|gains?|loses|stays? ahead|"
                     r"is cheaper|are cheaper|outperforms?)\b", re.IGNORECASE)
#: an energy quantity in the same sentence (per cent, points, energy units)
ENERGY = re.compile(r"(\d\s*%|\bpoints?\b|\bk?Wh\b|\bMJ\b|\bkJ\b|\benergy\b)", re.IGNORECASE)
#: what makes it a judged statement: an interval or the engine's undecided words
JUDGED = re.compile(r"(\[\s*[-+]?\d[\d.]*\s*,\s*[-+]?\d[\d.]*\s*\]|no resolvable difference|"
                    r"not resolved|not at equal comfort)", re.IGNORECASE)
#: verdict words that are not about a comparison of energy
_BENIGN = re.compile(r"(share of range (the climate|it) costs?|COP gain|efficiency gain|"
                     r"cost, USD|can save|costs? \d+ % of the range|"
                     r"saves? (it|each|the figure|a figure|them)\b)", re.IGNORECASE)


def sentences(text: str) -> list[str]:
    """The text cut into sentences (paragraph breaks, table rows and '. ' end one)."""
    out = []
    for block in re.split(r"\n\s*\n|\n(?=\s*[|#>-])|\n(?=```)", text):
        flat = " ".join(block.split())
        out += [s for s in re.split(r"(?<=[.;:!?])\s+(?=[A-Z*(`])", flat) if s]
    return out


def unjudged_statements(text: str) -> list[str]:
    """Sentences of ``text`` that state an energy verdict without its interval."""
    bad = []
    for s in sentences(text):
        if "```" in s:
            continue
        cleaned = _BENIGN.sub("", s)
        if VERDICT.search(cleaned) and ENERGY.search(cleaned) and not JUDGED.search(s):
            bad.append(s)
    return bad


__all__ = ["unjudged_statements", "sentences"]
