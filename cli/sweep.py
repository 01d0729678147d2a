"""``acid sweep``: many closed-loop scenarios (cycles, climates, cabins, controllers) on Dask."""

from __future__ import annotations

import math
from pathlib import Path

import typer
from rich.text import Text

from acid.errors import ConfigError
from acid_cli._common import (
    check_paths,
    err_console,
    handle_errors,
    print_table,
    progress_bar,
    say,
)

#: files acid sweep writes into its output folder
OUTPUTS = ("results.parquet", "results.csv", "summary.json", "saving_vs_ambient.png",
           "energy_per_cycle.png", "prediction.png", "spec.toml", ".acid.lock")


def _fmt(v, digits: int = 3) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.{digits}f}"


def _mean(d: dict, key: str, digits: int) -> str:
    return _fmt((d.get(key) or {}).get("mean"), digits) if d.get(key) else ""


def _range(d: dict, key: str, digits: int) -> str:
    s = d.get(key)
    return f"{_fmt(s['min'], digits)}..{_fmt(s['max'], digits)}" if s else ""


@handle_errors
def sweep(
    spec_path: Path = typer.Argument(..., metavar="SPEC.toml",
                                     help="Sweep specification (TOML)."),
    out: Path | None = typer.Option(None, "--out",
                                    help="Output folder (default: reports/sweep/NAME for "
                                         "NAME.toml)."),
    workers: int | None = typer.Option(None, "--jobs",
                                       help="Worker processes of the local Dask cluster "
                                            "(default: one per core)."),
    scheduler: str | None = typer.Option(None, "--scheduler",
                                         help="Address of an existing Dask scheduler to run "
                                              "on instead (e.g. tcp://10.0.0.5:8786)."),
    force: bool = typer.Option(False, "--force",
                               help="Run every scenario again (default: resume, skipping "
                                    "scenarios already finished in OUT)."),
    retry_failed: bool = typer.Option(False, "--retry-failed",
                                      help="Also run again the scenarios that failed in an "
                                           "earlier run (lost ones always run again)."),
    dry_run: bool = typer.Option(False, "--dry-run",
                                 help="Check the specification and list the scenarios; run "
                                      "nothing."),
    figures: bool = typer.Option(True, "--figures/--no-figures",
                                 help="Write the summary figures."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
    allow_unstable: bool = typer.Option(
        False, "--allow-unstable",
        help="Use parameter files of the spec even if eqs. 1-3 are unstable or not in kelvin."),
) -> None:
    """Run every scenario x controller of SPEC.toml and tabulate energy, savings and comfort.

    Scenarios are a grid (cartesian product) and/or a list of drive cycles or constant
    speeds, ambient temperature, humidity, solar irradiance, refrigerant, cabin set-point
    and comfort band, plant overrides and model parameters (paper, a file, or identified
    per climate); controllers come from a registry (nmpc, icm, nominal, ...). Runs on a
    local Dask cluster (or `--scheduler`); each finished scenario is saved at once, so an
    interrupted sweep resumes. Writes OUT/results.parquet, OUT/results.csv, two figures and
    OUT/summary.json.
    """
    from acid.executor import check_scheduler_address, start_worker_server, workers_skip_main
    from acid.outdir import claim
    from acid.studies.sweep import load_spec
    from acid.studies.sweep.runner import check_out_folder

    if out is None:
        if not spec_path.stem.strip("." + "/\\"):
            raise ConfigError(f"SPEC.toml {spec_path}: a name made only of dots cannot name "
                              "its output folder (rename it, or give --out)")
        out = Path("reports/sweep") / spec_path.stem
    check_paths(inputs={"SPEC.toml": spec_path}, outputs={"--json": json_path},
                folders={"--out": (out, OUTPUTS)})
    if json_path is not None and (out / "scenarios").resolve() in json_path.resolve().parents:
        raise ConfigError(f"--json {json_path}: inside {out / 'scenarios'}, where acid sweep "
                          "keeps its records")
    if workers is not None and scheduler is not None:
        raise ConfigError("--jobs and --scheduler: give one (the cluster has its workers)")
    if workers is not None and not 1 <= workers <= 256:
        raise ConfigError(f"--jobs {workers}: must lie in 1..256")
    if scheduler is not None:
        check_scheduler_address(scheduler)
    spec = load_spec(spec_path, allow_unstable=allow_unstable)
    check_out_folder(spec, out, force)  # another spec's results: one line, nothing lost
    n, m = len(spec.scenarios), len(spec.controllers)
    header = (f"{spec_path}: {spec.title!r}: {n} scenario{'s' * (n != 1)} x {m} "
              f"controller{'s' * (m != 1)} ({', '.join(c.label for c in spec.controllers)}; "
              f"baseline {spec.baseline})")
    if dry_run:
        say(header)
        rows = [[i, s.label, s.duration_s or "cycle", s.warmup_s, s.tail_s, s.params,
                 ", ".join(f"{k}={v}" for k, v in s.plant) or "-"]
                for i, s in enumerate(spec.scenarios[:20])]
        print_table("Scenarios" + (f" (first 20 of {n})" if n > 20 else ""),
                    ["#", "_scenario", "duration s", "warm-up s", "tail s", "_params",
                     "_plant"], rows)
        say("specification OK; nothing run (--dry-run)")
        return
    workers_skip_main()  # the workers need acid, not this command-line interface
    if scheduler is None:  # the workers' imports begin now, beside this process's own
        from acid.studies.sweep.runner import WORKER_MODULES

        start_worker_server(WORKER_MODULES)
    with claim(out, "acid sweep"):  # before anything is printed: a busy folder is one line
        _run(spec, out, workers, scheduler, force, retry_failed, figures, json_path, header)


def _run(spec, out, workers, scheduler, force, retry_failed, figures, json_path,
         header) -> None:
    from acid.studies.sweep import run_sweep

    n = len(spec.scenarios)
    with progress_bar(f"sweep {spec.title}", total=n) as update:
        def on_start(to_run: int, reused: int, where: str) -> None:
            say(header)  # once the workers are up: a cluster that fails is one line alone
            update(0, max(to_run, 1))
            done = f"{reused} scenario{'s' * (reused != 1)} finished earlier"
            err_console.print(Text(f"{done}; running {to_run} on {where}" if to_run else
                                   f"{done}: nothing to run"), highlight=False)

        result = run_sweep(spec, out, workers=workers, scheduler=scheduler, force=force,
                           retry_failed=retry_failed, figures=figures, on_progress=update,
                           on_start=on_start)

    d = result.to_json_dict()
    rows = []
    for label, s in d["per_controller"].items():
        rows.append([label + (" *" if label == spec.baseline else ""), s["scenarios_ok"],
                     s["scenarios_failed"], _mean(s, "energy_MJ", 3), _mean(s, "saving_pct", 2),
                     _range(s, "saving_pct", 1), _mean(s, "saving_tail_corrected_pct", 2),
                     _mean(s, "mean_T_cab_C", 2), _mean(s, "comfort_violation_Ks", 1),
                     _fmt(s.get("solve_ms_median"), 2)])
    print_table(f"{spec.title}: means over the scenarios (* baseline)",
                ["_controller", "ok", "fail", "E MJ", "saving %", "range %", "tail-corr %",
                 "T_cab C", "viol Ks", "ms"], rows)
    for key, why in list(result.tampered.items())[:10]:
        say(f"ignored and ran again: scenario record {key} ({why})")
    for f in d["failures"][:10]:
        say(f"failed: scenario {f['scenario']} ({f['label']}), {f['controller']}: "
            f"{f['error']}")
    if len(d["failures"]) > 10:
        say(f"... {len(d['failures']) - 10} more failures in the table")
    say(f"{d['computed']} computed ({d['failed']} failed), {d['reused']} reused, "
        f"{result.executor}, {result.elapsed_s:.1f} s")
    for key in ("parquet", "csv", "saving_figure", "energy_figure", "prediction_figure",
                "summary"):
        if key in result.files:
            say(f"{key.replace('_', ' ')}: {result.files[key]}")
    if json_path is not None:
        from acid_cli._common import write_summary

        write_summary(json_path, d)
