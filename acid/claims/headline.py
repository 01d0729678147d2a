"""The README's headline table, rendered from a ``summary.json`` alone, and the command
line of ``python -m acid.claims``."""

from __future__ import annotations

import json
import math
import sys
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path

from acid.claims.core import NO_VERDICT, Claim, Verdict, unit_suffix
from acid.claims.registry import CLAIMS, HEADLINE, HeadlineRow


def _combined_verdict(items: Sequence[Mapping]) -> str:
    verdicts = [i["verdict"] for i in items]
    kinds = Counter(verdicts)
    if len(kinds) == 1:
        v = verdicts[0]
        rule = items[0]["rule_text"]
        if v == Verdict.BEYOND.value:
            return "—"
        if v in {x.value for x in NO_VERDICT}:
            reasons = {i["reason"] for i in items}
            return f"{v}: {reasons.pop()}" if len(reasons) == 1 else v
        same_rule = all(i["rule_text"] == rule for i in items)
        scope = ("each " if len(items) > 1 else "") + rule if same_rule else ""
        if not scope or v == Verdict.DIRECTION.value:
            return v
        return f"{v} ({scope})" if v == Verdict.AGREES.value else f"{v} (rule: {scope})"
    return "mixed: " + ", ".join(f"{n} {_plural(k) if n > 1 else k}" for k, n in kinds.items())


def _plural(verdict: str) -> str:
    """'agrees' -> 'agree', 'agrees in direction' -> 'agree in direction'."""
    return verdict.replace("agrees", "agree").replace("disagrees", "disagree")


def headline_rows(summary: Mapping, headline: Sequence[HeadlineRow] = HEADLINE
                  ) -> list[tuple[str, str, str, str]]:
    """(result, paper, acid, verdict) per headline row, from a ``summary.json`` dict."""
    items = {i["id"]: i for i in summary["claims"]["items"]}
    rows = []
    for row in headline:
        its = [items[j] for j in row.claims if j in items]
        if not its:
            continue
        paper = " / ".join(i["paper_text"] for i in its)
        if len({i["paper_text"] for i in its}) == 1 and len(its) > 1:
            paper = its[0]["paper_text"]
        acid = " / ".join(_compact(i["acid_text"]) for i in its)
        rows.append((row.label, paper, acid, _combined_verdict(its)))
    return rows


def _compact(text: str) -> str:
    """An estimate without its interval when it has a standard error (the headline keeps
    value ± stderr); an interval that is the estimate's only uncertainty is kept."""
    return text.split(" [", 1)[0] if " ± " in text else text


def headline_markdown(summary: Mapping, headline: Sequence[HeadlineRow] = HEADLINE) -> str:
    """The README's headline table as markdown, from a ``summary.json`` dict."""
    c = summary["claims"]["counts"]
    lines = ["| result | paper | acid | verdict |", "|---|---|---|---|"]
    for r in headline_rows(summary, headline):
        lines.append("| " + " | ".join(x.replace("|", "\\|") for x in r) + " |")
    lines.append("")
    lines.append(f"{c['agrees']} claims agree, {c['agrees in direction']} agree in direction "
                 f"only, {c['disagrees']} disagree, {c['not comparable']} are not comparable"
                 + (f", {c['not measured']} not measured" if c["not measured"] else "")
                 + (f", {c[Verdict.NOT_JUDGED.value]} not judged (quick run)"
                    if c.get(Verdict.NOT_JUDGED.value) else "")
                 + f" ({len(summary['claims']['items'])} registry entries, "
                 f"{c['beyond the paper']} beyond the paper).")
    return "\n".join(lines) + "\n"


def registry_rows(claims: Sequence[Claim] = CLAIMS) -> list[tuple[str, str, str, str, str]]:
    """(id, paper value, where acid measures it, rule, note) for listing the registry."""
    rows = []
    for c in claims:
        paper = "—" if c.paper is None else (
            c.paper.display() + unit_suffix(c.paper.unit) if c.paper.value is not None
            else c.paper.display())
        rows.append((c.id, paper, c.measured.where() if c.measured else "—",
                     c.rule_text, c.note or getattr(c.rule, "reason", "")))
    return rows


def load_summary(path: str | Path) -> dict:
    """A ``summary.json`` of ``acid reproduce`` (``DataError`` naming the file if it is not)."""
    from acid.errors import DataError

    path = Path(path)
    try:
        summary = json.loads(path.read_text())
    except FileNotFoundError:
        raise DataError(f"{path}: file not found") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DataError(f"{path}: not a JSON file ({exc.__class__.__name__})") from None
    if not isinstance(summary, dict) or not isinstance(summary.get("claims"), dict):
        raise DataError(f"{path}: no 'claims' block (not a summary.json of acid reproduce)")
    return summary


def _non_finite(obj, where: str):
    """The first key path under ``obj`` holding a non-finite number (JSON NaN/Infinity)."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return where
    items = obj.items() if isinstance(obj, Mapping) else (
        enumerate(obj) if isinstance(obj, list) else ())
    for k, v in items:
        bad = _non_finite(v, f"{where}[{k}]" if isinstance(k, int) else f"{where}.{k}")
        if bad:
            return bad
    return None


def rejudge(summary: Mapping, path: str | Path = "summary.json") -> tuple[dict, list[str]]:
    """The verdicts of a ``summary.json`` recomputed from its stage values by the registry.

    The stored verdicts are never trusted: every claim is judged again from the typed stage
    results in ``stages.*.summary`` (and the run's ``options``: a run with other sizes than
    the study's is a quick run). Returns the summary with its ``claims`` block replaced, and
    the ids whose stored verdict differed (corrected). A malformed or tampered value is a
    ``DataError`` naming the file and the key.
    """
    from acid.claims.options import run_mode
    from acid.claims.registry import evaluate, summary_claims
    from acid.claims.results import StudyResults
    from acid.errors import DataError

    stages = summary.get("stages")
    if not isinstance(stages, Mapping) or not stages:
        raise DataError(f"{path}: no 'stages' block: the verdicts cannot be judged again")
    bodies = {}
    for name, st in stages.items():
        body = st.get("summary") if isinstance(st, Mapping) else None
        if not isinstance(body, Mapping):
            raise DataError(f"{path}: stages.{name}.summary is missing or not an object")
        bad = _non_finite(body, f"stages.{name}.summary")
        if bad:
            raise DataError(f"{path}: {bad} is not a finite number")
        bodies[name] = body
    options = summary.get("options")
    if not isinstance(options, Mapping):
        raise DataError(f"{path}: 'options' is missing or not an object (the run's sizes)")
    try:
        results = StudyResults.from_summaries(bodies)
    except DataError as exc:
        raise DataError(f"{path}: {exc}") from None
    except (TypeError, ValueError) as exc:  # a value the stage result class refuses
        raise DataError(f"{path}: a stage summary does not fit its result class "
                        f"({exc})") from None
    verdicts = evaluate(results, quick=run_mode(dict(options)) != "full")
    stored = summary["claims"].get("items")
    stored = {i.get("id"): i.get("verdict") for i in stored if isinstance(i, Mapping)} \
        if isinstance(stored, list) else {}
    changed = [f"{v.claim.id} ({stored.get(v.claim.id)} -> {v.verdict.value})"
               for v in verdicts if stored.get(v.claim.id) != v.verdict.value]
    out = dict(summary)
    out["claims"] = summary_claims(verdicts)
    return out, changed


def correction_note(path: str | Path, changed: Sequence[str]) -> str:
    """One line saying which stored verdicts the registry corrected."""
    shown = "; ".join(changed[:4]) + (f"; and {len(changed) - 4} more" if len(changed) > 4
                                      else "")
    return (f"{path}: {len(changed)} stored verdict{'s' if len(changed) != 1 else ''} "
            f"differ from the registry's judgement of the stored values and were corrected: "
            f"{shown}")


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m acid.claims [summary.json]``: the registry, or the headline table (its
    verdicts judged again from the stored values, :func:`rejudge`)."""
    from acid.errors import AcidError

    argv = list(sys.argv[1:] if argv is None else argv)
    if argv:
        try:
            summary, changed = rejudge(load_summary(argv[0]), argv[0])
        except AcidError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        if changed:
            print(f"note: {correction_note(argv[0], changed)}", file=sys.stderr)
        sys.stdout.write(headline_markdown(summary))
        return 0
    for row in registry_rows():
        print(" | ".join(row))
    return 0
