"""``acid reproduce``: every table and figure of the paper, in one command, with a report."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import typer
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.text import Text

from acid.claims import Verdict, contradictions, counts, headline_rows, load_summary
from acid.errors import ConfigError
from acid.outdir import claim
from acid.pipeline import run_pipeline
from acid.reproduce import ReproduceOptions, build_stages, is_quick, write_outputs
from acid_cli._common import (
    check_paths,
    err_console,
    handle_errors,
    note,
    print_table,
    say,
    warn,
    write_summary,
)


@handle_errors
def reproduce(
    out: Path = typer.Option(Path("reports/paper"), "--out",
                             help="Folder for the report, its figures and the stage cache."),
    quick: bool = typer.Option(False, "--quick",
                               help="A smaller study (shorter records, 12 starts) for tests "
                                    "and first looks."),
    jobs: int = typer.Option(2, "--jobs", min=1,
                             help="Independent stages run side by side in this many worker "
                                  "processes (a local Dask cluster; 1: in this process)."),
    scheduler: str | None = typer.Option(None, "--scheduler",
                                         help="Run the stages on this existing Dask cluster "
                                              "(scheduler address; its workers must see OUT)."),
    force: bool = typer.Option(False, "--force", help="Ignore the cache and redo every stage."),
    json_path: Path | None = typer.Option(None, "--json",
                                          help="Also write the summary here (it is always "
                                               "written to OUT/summary.json)."),
) -> None:
    """Sweep (Table I), excite, fit, validate (Figs. 5-6) and NMPC checks (Figs. 7-10).

    Stages are cached by their inputs under OUT/stages, so a second run redoes only what
    changed (one line names what it reused; a cached record that fails its integrity check
    is recomputed, with one line). Writes OUT/report.html (self-contained) and
    OUT/summary.json. A run into a folder another run is using stops with one line.
    """
    check_paths(outputs={"--json": json_path},
                folders={"--out": (out, ("report.html", "summary.json"))})
    if jobs > 8:
        raise ConfigError(f"--jobs {jobs}: at most 8 local processes")
    if scheduler is not None:
        from acid.executor import check_scheduler_address

        check_scheduler_address(scheduler)
    opts = ReproduceOptions.quick() if quick else ReproduceOptions()
    stages = build_stages(opts)
    with claim(out, "acid reproduce"):
        _reproduce(out, opts, stages, jobs, scheduler, force, json_path)


def _reproduce(out, opts, stages, jobs, scheduler, force, json_path) -> None:
    t0 = time.perf_counter()
    with Progress(TextColumn("[bold]{task.description:<48}"), BarColumn(),
                  TextColumn("{task.percentage:>3.0f}%"), TimeElapsedColumn(),
                  console=err_console, disable=not sys.stderr.isatty()) as prog:
        tasks = {s.name: prog.add_task(s.title, total=1, start=False) for s in stages}

        def on_start(name: str) -> None:
            prog.start_task(tasks[name])

        def on_progress(name: str, done: int, total: int) -> None:
            prog.update(tasks[name], completed=done, total=max(total, 1))

        def on_done(outcome) -> None:
            label = "cached" if outcome.cached else f"{outcome.seconds:.1f} s"
            prog.update(tasks[outcome.name], completed=1, total=1,
                        description=f"{outcome.title} ({label})")

        outcomes = run_pipeline(stages, out, jobs=jobs, on_start=on_start,
                                on_progress=on_progress, on_done=on_done, force=force,
                                scheduler=scheduler,
                                notice=lambda msg: err_console.print(Text(msg), highlight=False,
                                                                    soft_wrap=True))
    elapsed = time.perf_counter() - t0
    reused = [o.name for o in outcomes.values() if o.cached]
    if reused:
        note(f"reused {len(reused)} of {len(outcomes)} stages cached in {out / 'stages'} "
            f"({', '.join(reused)}: same settings, inputs and code); the report is written "
            "again from them; --force recomputes every stage")
    html, summary_path, verdicts = write_outputs(out, outcomes, opts, elapsed)

    print_table("Stages", ["stage", "time (s)", "cache"],
                [[o.title, f"{o.seconds:.1f}", "reused" if o.cached else "computed"]
                 for o in outcomes.values()])
    summary = load_summary(summary_path)
    print_table("Paper vs acid (headline; every claim in the report)",
                ["_result", "_paper", "_acid", "_verdict"],
                [[r[0].replace("*", ""), *r[1:]] for r in headline_rows(summary)])
    n = counts(verdicts)
    say(", ".join(f"{c} {k}" for k, c in n.items()))
    if is_quick(opts):
        say(f"quick run: {n[Verdict.NOT_JUDGED.value]} claims not judged (the stages it "
            "shortens); only the NMPC checks are judged. Run without --quick for the study.")
    bad = contradictions(verdicts)
    if bad:
        warn("contradictory verdicts: " + "; ".join(bad))
    say(f"report: {html}\nsummary: {summary_path}\ntotal {elapsed:.1f} s")
    if json_path is not None:
        write_summary(json_path, summary)
