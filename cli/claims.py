"""``acid claims``: the registry of the paper's claims, or the headline table of a run."""

from __future__ import annotations

from pathlib import Path

import typer

from acid.errors import DataError
from acid_cli._common import check_paths, handle_errors, print_table, say, warn, write_summary

#: texts of each entry of ``claims.items`` the headline table prints
ITEM_TEXTS = ("id", "verdict", "rule_text", "paper_text", "acid_text")


def check_summary(path: Path) -> dict:
    """The ``summary.json`` at ``path`` if its ``claims`` block has what the headline table
    reads (``items``: objects with texts ``ITEM_TEXTS``, a known verdict and, when not
    comparable or not measured, a ``reason``; ``counts``: a count per verdict), else a
    ``DataError`` naming the file and the key."""
    from acid._readers import load_json
    from acid.claims.core import Verdict

    d = load_json(path, "summary")
    block = d.get("claims")
    if not isinstance(block, dict):
        raise DataError(f"{path}: no 'claims' block (not a summary.json of acid reproduce)")
    items = block.get("items")
    if not isinstance(items, list):
        raise DataError(f"{path}: claims.items must be a list of claims")
    verdicts = [v.value for v in Verdict]
    for i, item in enumerate(items):
        where = f"claims.items[{i}]"
        if not isinstance(item, dict):
            raise DataError(f"{path}: {where} must be an object")
        for key in ITEM_TEXTS:
            if not isinstance(item.get(key), str):
                raise DataError(f"{path}: {where}.{key} must be a text")
        if item["verdict"] not in verdicts:
            raise DataError(f"{path}: {where}.verdict {item['verdict'][:40]!r} is not a "
                            f"verdict ({', '.join(verdicts)})")
        needs_reason = item["verdict"] in (Verdict.NOT_COMPARABLE.value,
                                           Verdict.NOT_MEASURED.value)
        if needs_reason and not isinstance(item.get("reason"), str):
            raise DataError(f"{path}: {where}.reason must be a text")
    counts = block.get("counts")
    if not isinstance(counts, dict):
        raise DataError(f"{path}: claims.counts must be an object")
    for v in verdicts:
        n = counts.get(v)
        if isinstance(n, bool) or not isinstance(n, int) or n < 0:
            raise DataError(f"{path}: claims.counts.{v!r} must be a count")
    return d


@handle_errors
def claims(
    summary: Path | None = typer.Argument(
        None, help="summary.json of `acid reproduce`: print its headline table (markdown, "
                   "as pasted into the README)."),
    json_path: Path | None = typer.Option(None, "--json",
                                          help="Also write the rows shown as JSON here."),
) -> None:
    """The paper's claims: each result's value, where acid measures it and the verdict rule.

    With a SUMMARY, the README's headline table (paper, acid, verdict per row) of that run:
    every verdict judged again by the registry (acid.claims) from the values the summary
    stores (a stored verdict that differs is corrected, with one line saying so).
    """
    from acid.claims import headline_markdown, headline_rows, load_summary, registry_rows
    from acid.claims.headline import correction_note, rejudge

    check_paths(inputs={"SUMMARY": summary}, outputs={"--json": json_path})
    if summary is not None:
        check_summary(summary)  # size, depth and every entry the table reads: one line
        s, changed = rejudge(load_summary(summary), summary)
        if changed:
            warn(correction_note(summary, changed))
        typer.echo(headline_markdown(s), nl=False)
        write_summary(json_path, {"summary": str(summary), "corrected": changed, "headline": [
            dict(zip(("result", "paper", "acid", "verdict"), r, strict=True))
            for r in headline_rows(s)]})
        return
    rows = registry_rows()
    print_table("Claims of the paper (acid.claims)",
                ["_id", "_paper", "_where acid measures it", "_rule", "_note"],
                [list(r) for r in rows])
    say(f"{len(rows)} claims; `acid claims reports/paper/summary.json` prints the headline "
        "table of a run")
    write_summary(json_path, {"claims": [
        dict(zip(("id", "paper", "measured_at", "rule", "note"), r, strict=True))
        for r in rows]})
