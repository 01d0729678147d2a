"""The registry of the paper's claims: its numbers, where acid measures them, how they are judged.

The paper's numbers are written in :mod:`acid.paper` and nowhere else (Wang,
Kolmanovsky, Amini & Sun, "Model Predictive Climate Control of Connected and Automated
Vehicles for Improved Energy Efficiency", ACC 2018). Everything else reads them from there:
the parameter preset (:func:`acid.models.params.paper`), the speed sweep's Table I, the CAV
scenario's window, the report, ``summary.json`` and the README's headline table.

Modules: :mod:`~acid.paper` (the numbers), :mod:`~acid.claims.core` (claims, rules,
verdicts), :mod:`~acid.claims.registry` (``CLAIMS``, ``HEADLINE``),
:mod:`~acid.claims.headline` (the README table from a ``summary.json``).

A :class:`Claim` is one result of the paper:

* ``paper``: its value, unit, where in the paper it is and, for qualitative or approximate
  statements, the paper's words (:class:`PaperValue`);
* ``measured``: where acid measures it, as a stage result class of
  :mod:`acid.claims.results` and a path to one of its fields (checked against the declared
  fields when the registry is built), plus the conditions under which the two are comparable
  (e.g. a 600 s sweep) (:class:`Measured`, :class:`Requires`);
* ``rule``: how the verdict is reached: :class:`Within` a tolerance, :class:`AtMost` a
  limit (a stated reading of a qualitative claim), :class:`SameSign` (agrees in direction
  only), :class:`NotComparable` (with its reason) or :class:`BeyondThePaper` (acid's own
  measurement, no paper value);
* ``implies``: claims that must not disagree when this one agrees (the consistency check
  that keeps the report from contradicting itself).

:func:`evaluate` turns the registry and the typed stage results into :class:`ClaimVerdict`
objects; :func:`contradictions` lists violated implications; :func:`headline_markdown`
renders the README's headline table from a ``summary.json``.

Adding a claim (for a new stage or study): give the stage a result class in
:mod:`acid.claims.results`, then add a ``Claim`` in :mod:`acid.claims.registry` (and, if it
belongs in the README, its id to a :class:`HeadlineRow` in ``HEADLINE``). ``python -m acid.claims``
lists the registry; ``python -m acid.claims summary.json`` prints the headline table.
"""

from __future__ import annotations

from acid.claims.core import (
    NO_VERDICT,
    AtMost,
    BeyondThePaper,
    Claim,
    ClaimVerdict,
    Measured,
    NotComparable,
    PaperValue,
    Requires,
    Rule,
    SameSign,
    Verdict,
    Within,
    check_path,
    contradictions,
    counts,
    judge,
    not_judged,
    resolve,
)
from acid.claims.headline import (
    headline_markdown,
    headline_rows,
    load_summary,
    main,
    registry_rows,
)
from acid.claims.registry import (
    CLAIMS,
    HEADLINE,
    HeadlineRow,
    claim,
    evaluate,
    judge_value,
    summary_claims,
    validate_registry,
)
from acid.paper import MODEL, PAPER_CITATION, STUDIES, TABLE_I, TABLE_II

__all__ = ["CLAIMS", "HEADLINE", "MODEL", "NO_VERDICT", "PAPER_CITATION", "STUDIES", "TABLE_I",
           "TABLE_II",
           "AtMost", "BeyondThePaper", "Claim", "ClaimVerdict", "HeadlineRow", "Measured",
           "NotComparable", "PaperValue", "Requires", "Rule", "SameSign", "Verdict", "Within",
           "check_path", "claim", "contradictions", "counts", "evaluate", "headline_markdown",
           "headline_rows", "judge", "judge_value", "load_summary", "main", "not_judged",
           "registry_rows", "resolve", "summary_claims", "validate_registry"]
