"""Run a validated sweep on an executor, streaming results to disk, resuming what is done.

:func:`run_sweep` holds the output folder (:func:`acid.outdir.claim`), skips every scenario
whose record is already ``"ok"`` (unless ``force``), sends the rest to the executor (a Dask
cluster by default: one task per scenario, plus one identification task per plant
configuration when ``params = "identify"``, which Dask runs once and hands to every scenario
that needs it), saves each record the moment it arrives, then writes the table, the figures
and ``summary.json``. An interrupted sweep keeps its finished records; the next run resumes.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from acid import __version__
from acid._io import save_figure, write_json
from acid.errors import AcidError, ConfigError
from acid.executor import (
    Executor,
    check_interrupt,
    dask_available,
    open_executor,
    start_worker_server,
)
from acid.outdir import claim
from acid.studies.sweep.results import (
    ResultStore,
    controller_summary,
    failure_record,
    prediction_roles,
    prediction_summary,
    results_table,
    write_table,
)
from acid.studies.sweep.scenario import (
    identify_params,
    one_line,
    run_scenario,
    scenario_tasks,
)
from acid.studies.sweep.spec import SweepSpec

#: exceptions of a task that never reported (run the scenario again next time)
LOST = ("KilledWorker", "CancelledError", "FutureCancelledError", "CommClosedError",
        "TimeoutError", "OSError")


@dataclass(frozen=True)
class SweepResult:
    """What a sweep produced.

    Attributes
    ----------
    spec : the sweep.
    out : output folder.
    table : pandas DataFrame, one row per scenario x controller.
    computed, reused, failed : scenarios run now, taken from earlier runs, failed now.
    elapsed_s : wall time, s.
    executor : where it ran (one line).
    files : name -> path of what was written.
    tampered : key -> why, of earlier records that were not valid (run again).
    """

    spec: SweepSpec
    out: Path
    table: object
    computed: int
    reused: int
    failed: int
    elapsed_s: float
    executor: str
    files: dict = field(default_factory=dict)
    tampered: dict = field(default_factory=dict)

    def failures(self) -> list[dict]:
        """``{scenario, label, controller, error}`` of every failed row."""
        df = self.table
        bad = df[df["status"] != "ok"]
        return [{"scenario": int(r.scenario), "label": r.label, "controller": r.controller,
                 "error": r.error} for r in bad.itertuples()]

    def to_json_dict(self) -> dict:
        from acid._io import json_safe

        return json_safe({
            "command": "sweep", "acid_version": __version__, "title": self.spec.title,
            "spec": str(self.spec.path) if self.spec.path else None, "out": str(self.out),
            "scenarios": len(self.spec.scenarios),
            "controllers": [c.label for c in self.spec.controllers],
            "baseline": self.spec.baseline, "rows": int(len(self.table)),
            "computed": self.computed, "reused": self.reused, "failed": self.failed,
            "executor": self.executor, "elapsed_s": self.elapsed_s,
            "per_controller": controller_summary(self.table, self.spec.baseline),
            "prediction": (prediction_summary(self.table) if len(self.table) else None),
            "failures": self.failures(), "tampered_records": dict(self.tampered),
            "files": {k: str(v) for k, v in self.files.items()}})


def run_sweep(spec: SweepSpec, out: str | Path, workers: int | None = None,
              scheduler: str | None = None, executor: Executor | None = None,
              force: bool = False, retry_failed: bool = False, figures: bool = True,
              on_progress: Callable[[int, int, str], None] | None = None,
              on_start: Callable[[int, int, str], None] | None = None) -> SweepResult:
    """Run ``spec`` into ``out``; see the module docstring.

    Parameters
    ----------
    workers : worker processes of a local Dask cluster (None: one per core).
    scheduler : address of an existing Dask scheduler instead.
    executor : an open executor to use instead (e.g. ``InlineExecutor()`` in tests).
    force : run every scenario again, ignoring earlier records.
    retry_failed : run scenarios again whose earlier record is an error.
    figures : write the summary figures.
    on_progress : ``on_progress(done, total, label)`` after each scenario that ran now;
        ``label`` names it as the spec gives it (``finished_label``).
    on_start : ``on_start(to_run, reused, where)`` once the executor is up.
    """
    t0 = time.perf_counter()
    out = Path(out)
    try:
        import pyarrow  # noqa: F401  (the Parquet table; checked before hours of work)
    except ImportError:
        raise AcidError("acid sweep writes Parquet with pyarrow: pip install "
                        "'acid[distributed]'") from None
    with claim(out, "acid sweep"):
        check_out_folder(spec, out, force)
        store = ResultStore(out, tuple(c.label for c in spec.controllers))
        tasks = scenario_tasks(spec)
        todo = [t for t in tasks if force or not store.finished(t.key, retry_failed)]
        tampered = dict(store.tampered)
        if spec.path is not None and spec.path.is_file():
            from acid._io import write_text  # marks the folder as this spec's at once

            write_text(out / "spec.toml", spec.path.read_text())
        computed = failed = 0
        where = "nothing to run"
        with contextlib.ExitStack() as stack:  # an executor opened here is closed at its end
            if todo:
                ex = executor
                if ex is None:
                    dask_available()  # Dask's own imports first, alone
                    if scheduler is None:
                        start_worker_server(WORKER_MODULES)
                    with prefetched(AFTER_RUN_MODULES):  # while the workers start
                        ex = stack.enter_context(open_executor(workers, scheduler,
                                                               inline_when_single=False))
                computed, failed, where = _execute(spec, todo, store, ex, on_progress,
                                                   on_start, len(tasks) - len(todo))
                if executor is None:
                    ex.close_soon()  # the workers end while the table is written
            elif on_start is not None:
                on_start(0, len(tasks), where)
            result = _finish(spec, out, tasks, store, figures, computed,
                             len(tasks) - len(todo), failed, where, tampered, t0)
    return result


#: what a worker needs to run a scenario: imported once, by the server the local cluster's
#: workers are forked from (:func:`acid.executor.start_worker_server`)
WORKER_MODULES = ("acid.studies.sweep.scenario",)

#: what :func:`run_sweep` needs once the scenarios are done (the table, its Parquet file and
#: the summary's paired tests); imported while a cluster's workers start, when this process
#: has nothing else to do (about 1 CPU-s it would otherwise add after the last scenario)
AFTER_RUN_MODULES = ("pandas", "pyarrow.parquet", "scipy.stats")


@contextlib.contextmanager
def prefetched(modules):
    """Import ``modules`` in a background thread while the block runs (the block must not
    import them itself); waits for the thread at the end. A module that fails to import is
    left to its first real use, which reports it."""
    import importlib
    import threading

    def load():
        for name in modules:
            with contextlib.suppress(Exception):
                importlib.import_module(name)

    thread = threading.Thread(target=load, name="acid-prefetch", daemon=True)
    thread.start()
    try:
        yield
    finally:
        thread.join()


def _finish(spec, out, tasks, store, figures, computed, reused, failed, where,
            tampered, t0):
    """The table, figures and summary of a sweep whose scenarios are done."""
    records = [store.load(t.key) for t in tasks]
    table = results_table([r for r in records if r is not None])
    files = write_table(table, out)
    if figures:
        from acid.report.sweep import energy_figure, saving_figure

        files["saving_figure"] = save_figure(saving_figure(table, spec.baseline),
                                             out / "saving_vs_ambient.png")
        files["energy_figure"] = save_figure(energy_figure(table),
                                             out / "energy_per_cycle.png")
        roles = prediction_roles(table) if len(table) else None
        if roles is not None:
            from acid.report.sweep import prediction_figure

            files["prediction_figure"] = save_figure(
                prediction_figure(table, **roles), out / "prediction.png")
    if spec.path is not None and spec.path.is_file():
        from acid._io import write_text

        files["spec"] = write_text(out / "spec.toml", spec.path.read_text())
    files["summary"] = out / "summary.json"
    result = SweepResult(spec=spec, out=out, table=table, computed=computed,
                         reused=reused, failed=failed,
                         elapsed_s=time.perf_counter() - t0, executor=where, files=files,
                         tampered=tampered)
    write_json(files["summary"], result.to_json_dict())
    return result


def check_out_folder(spec: SweepSpec, out: str | Path, force: bool = False) -> None:
    """Refuse (``ConfigError`` naming ``--out``) an output folder that holds the results of
    another specification: its ``spec.toml`` (written when a sweep starts) is not this
    spec's (compared as parsed TOML: comments and layout may differ), or it has results
    (tables, summary or scenario records) without one. The same specification resumes;
    ``force`` replaces them; a folder without results takes any specification."""
    from acid._readers import load_toml

    out = Path(out)
    if force or spec.path is None:
        return
    found = [n for n in ("summary.json", "results.parquet", "results.csv")
             if (out / n).exists()]
    if not found and (out / "scenarios").is_dir() and any((out / "scenarios").glob("*.json")):
        found = ["scenarios/"]
    if not found:  # nothing to lose (a run that never finished a scenario)
        return
    theirs = out / "spec.toml"
    hint = "choose another --out, or give --force to replace them"
    if not theirs.exists():
        raise ConfigError(f"--out {out}: holds sweep results ({found[0]}) of an unknown "
                          f"specification (no spec.toml); {hint}")
    try:
        same = load_toml(theirs, "spec.toml") == load_toml(spec.path, "sweep specification")
    except AcidError:
        same = False
    if not same:
        raise ConfigError(f"--out {out}: holds the results of another specification "
                          f"({theirs} is not {spec.path}); {hint}")


def _execute(spec, todo, store, ex: Executor, on_progress, on_start,
             reused) -> tuple[int, int, str]:
    """Submit ``todo``, save each record as it arrives; returns (computed, failed, where)."""
    if on_start is not None:
        on_start(len(todo), reused, ex.describe())
    ident = {}
    running = {}
    for t in todo:
        params = None
        if t.params_kind == "identify":
            k = repr(t.plant_config)
            if k not in ident:
                ident[k] = ex.submit(identify_params, t.plant_config, spec.identify,
                                     spec.allow_unstable)
            params = ident[k]
        running[ex.submit(run_scenario, t, params, check_interrupt)] = t
    done = failed = 0
    while running:
        for fut in ex.wait_any(running, timeout=0.5):
            t = running.pop(fut)
            try:
                record = ex.result(fut)
            except Exception as exc:  # the task did not report: lost, or identification
                lost = type(exc).__name__ in LOST
                record = failure_record(t.key, t.index, t.scenario.label, t.controllers,
                                        t.baseline, one_line(exc), "lost" if lost else "error")
            store.save(record)
            done += 1
            failed += record["status"] != "ok"
            if on_progress is not None:
                on_progress(done, len(todo), finished_label(t, record["status"]))
        ex.pump()
    return done, failed, ex.describe()


def finished_label(task, status: str) -> str:
    """What a progress line says of a scenario that just finished: where the spec gives it
    (``grid scenario #3 (ambient_C = 32.0, cycle = "udds")``, ``scenarios #2``; its conditions
    when it was built without a spec) and, unless it ran, ``failed`` (a controller raised) or
    ``lost`` (its worker ended; run again next time). User text: print it literally."""
    where = task.scenario.origin or f"scenario {task.index + 1} ({task.scenario.label})"
    return where + {"ok": "", "lost": ": lost (its worker ended)"}.get(status, ": failed")


__all__ = ["run_sweep", "SweepResult", "check_out_folder", "finished_label",
           "WORKER_MODULES"]
