"""``acid heating-check``: the heating plant's credentials, each beside a reference."""

from __future__ import annotations

import os
from pathlib import Path

import typer

from acid import __version__
from acid_cli._common import (
    check_paths,
    handle_errors,
    print_table,
    progress_bar,
    say,
    write_summary,
)
from acid_cli.plant_check import format_value, verdict_text

#: Where the real winter logs live in the project's shared folder (acid never ships them).
DEFAULT_LOGS = Path("../shared/real-data/bmw-i3-winter")


@handle_errors
def heating_check(
    logs: Path | None = typer.Option(
        None, "--logs",
        help="Folder of the BMW i3 winter trips (TripBnn.csv.gz) for the warm-up rows "
             f"(default: $ACID_WINTER_LOGS, else {DEFAULT_LOGS} when present)."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
) -> None:
    """Check the heating plant: heat-pump COP against ambient, frost and defrost, balances,
    fogging, warm-up and heater power against the real i3 winter logs. Exits 1 on any FAIL.

    Sources of every reference: datasets/plant/SOURCES.md.
    """
    from acid.errors import DataError
    from acid.studies.credentials.heating import heating_check as run_check

    check_paths(outputs={"--json": json_path}, read_folders={"--logs": logs})
    if logs is not None:
        if not logs.is_dir():
            raise DataError(f"--logs {logs}: not a folder of winter trips")
        if not any(logs.glob("Trip*.csv.gz")):
            raise DataError(f"--logs {logs}: no Trip*.csv.gz files in it")
    else:
        env = os.environ.get("ACID_WINTER_LOGS")
        cand = Path(env) if env else DEFAULT_LOGS
        logs = cand if cand.is_dir() else None
        if logs is None:
            say(f"winter logs not found ({cand}): the warm-up rows are skipped")
    done = [0]
    with progress_bar("heating check", total=14) as update:
        def tick():
            done[0] += 1
            update(done[0], 14)

        result = run_check(logs, progress=tick)
    rows = [[r.group, r.name, format_value(r.value), r.unit, r.reference, verdict_text(r), r.note]
            for r in result.rows]
    print_table("acid heating-check", ["_", "_check", "value", "_unit", "_reference",
                                       "_verdict", "_note"], rows)
    summary = result.to_json_dict()
    summary.update(acid_version=__version__, logs=str(logs) if logs is not None else None)
    write_summary(json_path, summary)
    say("PASS" if result.passed else "FAIL")
    if not result.passed:
        raise typer.Exit(code=1)
