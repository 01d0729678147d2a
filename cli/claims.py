"""``acid claims``: the registry of the paper's claims, or the headline table of a run."""

from __future__ import annotations

from pathlib import Path

import typer

from acid_cli._common import check_paths, handle_errors, print_table, say, warn, write_summary


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
