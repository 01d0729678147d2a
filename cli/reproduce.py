"""``acid reproduce``: every table and figure of the paper, in one command, with a report."""

from __future__ import annotations

import time
from pathlib import Path

import typer
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.text import Text

from acid.claims import Verdict, contradictions, counts, headline_rows, load_summary
from acid.errors import ConfigError
from acid.outdir import claim
from acid.pipeline import run_pipeline
from acid.studies.reproduce import ReproduceOptions, build_stages, is_quick, write_outputs
from acid_cli._common import (
    ProgressLines,
    check_paths,
    err_console,
    handle_errors,
    note,
    print_table,
    progress_is_plain,
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
                                              "(scheduler address; its workers need not see "
                                              "OUT: results come back through this "
                                              "process)."),
    force: bool = typer.Option(False, "--force", help="Ignore the cache and redo every stage."),
    json_path: Path | None = typer.Option(None, "--json",
                                          help="Also write the summary here (it is always "
                                               "written to OUT/summary.json)."),
) -> None:
    """Every stage of the paper and beyond it, cached, into one report and summary.json.

    Stages: {stages}.

    Stages are cached by their inputs under OUT/stages, so a second run redoes only what
    changed (one line names what it reused; a cached record that fails its integrity check
    is recomputed, with one line). Writes OUT/report.html (self-contained) and
    OUT/summary.json. A run into a folder another run is using stops with one line. Into a
    log (no terminal) each stage prints a line when it is queued, as it moves and when it ends.
    """
    check_paths(outputs={"--json": json_path},
                folders={"--out": (out, ("report.html", "summary.json"))})
    if jobs > 8:
        raise ConfigError(f"--jobs {jobs}: at most 8 local processes")
    if scheduler is not None:
        from acid.executor import check_scheduler_address

        check_scheduler_address(scheduler)
        _refuse_a_closed_port(scheduler)
    opts = ReproduceOptions.quick() if quick else ReproduceOptions()
    stages = build_stages(opts)
    with claim(out, "acid reproduce"):
        _reproduce(out, opts, stages, jobs, scheduler, force, json_path)


# --help lists the stages that run, as the pipeline declares them
reproduce.__doc__ = reproduce.__doc__.replace(
    "{stages}", "; ".join(s.title for s in build_stages(ReproduceOptions())))


def _refuse_a_closed_port(address: str) -> None:
    """One line at once for a TCP scheduler address where nothing listens (the connection is
    refused), before any work: Dask's client retries a refused address until its 10 s
    timeout. Other failures (no route, a slow host) are left to the client's own wait."""
    import socket
    from urllib.parse import urlsplit

    url = urlsplit(address if "://" in address else f"tcp://{address}")
    if url.scheme not in ("tcp", "tls", "ws", "wss") or not url.hostname:
        return
    try:
        with socket.create_connection((url.hostname, url.port or 8786), timeout=0.5):
            pass
    except ConnectionRefusedError:
        raise ConfigError(f"--scheduler {address}: cannot connect (connection refused: "
                          "nothing listens at that port)") from None
    except OSError:   # no route or no answer within 0.5 s: the client waits and says so
        pass


def _reproduce(out, opts, stages, jobs, scheduler, force, json_path) -> None:
    t0 = time.perf_counter()
    run = _run_with_lines if progress_is_plain() else _run_with_bars
    outcomes = run(stages, out, jobs, scheduler, force, _notice)
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


def _notice(message: str) -> None:
    """The pipeline's notices (a cache record recomputed) as literal lines on stderr."""
    err_console.print(Text(message), highlight=False, soft_wrap=True)


def _run_with_bars(stages, out, jobs, scheduler, force, notice):
    """The stages on a terminal: one rich bar per stage."""
    with Progress(TextColumn("[bold]{task.description:<48}"), BarColumn(),
                  TextColumn("{task.percentage:>3.0f}%"), TimeElapsedColumn(),
                  console=err_console) as prog:
        tasks = {s.name: prog.add_task(s.title, total=1, start=False) for s in stages}

        def on_start(name: str) -> None:
            prog.start_task(tasks[name])

        def on_progress(name: str, done: int, total: int) -> None:
            prog.update(tasks[name], completed=done, total=max(total, 1))

        def on_done(outcome) -> None:
            label = "cached" if outcome.cached else f"{outcome.seconds:.1f} s"
            prog.update(tasks[outcome.name], completed=1, total=1,
                        description=f"{outcome.title} ({label})")

        return run_pipeline(stages, out, jobs=jobs, on_start=on_start,
                            on_progress=on_progress, on_done=on_done, force=force,
                            scheduler=scheduler, notice=notice)


def _run_with_lines(stages, out, jobs, scheduler, force, notice):
    """The stages into a log (stderr not a terminal): a line when a stage is queued, its
    progress as plain lines (``ProgressLines``: each tenth, at least every 30 s), a line when
    it ends."""
    titles = {s.name: s.title for s in stages}
    lines: dict[str, ProgressLines] = {}

    def on_start(name: str) -> None:
        lines[name] = ProgressLines(f"stage {titles[name]}", None)
        lines[name].line("queued")   # submitted: it runs when a worker is free

    def on_progress(name: str, done: int, total: int) -> None:
        if name in lines:
            lines[name](done, max(total, 1))

    def on_done(outcome) -> None:
        _notice(f"stage {outcome.title}: "
                + ("cached" if outcome.cached else f"done in {outcome.seconds:.1f} s"))

    return run_pipeline(stages, out, jobs=jobs, on_start=on_start, on_progress=on_progress,
                        on_done=on_done, force=force, scheduler=scheduler, notice=notice)
