"""A small cached, parallel stage runner (used by ``acid reproduce``).

A stage is a module-level function ``func(workdir, inputs, config, progress) -> summary``
that writes its files into ``workdir`` and returns a JSON-serialisable summary. Its cache key
hashes the stage's name and configuration, the keys of the stages it depends on and a
fingerprint of acid's source code and shipped data, so a second run redoes only what changed.
A stage's outputs appear atomically: it runs in a hidden temporary folder
(``stages/.NAME.XXXX.tmp``) that is renamed into place only when it succeeded.

A cached record (``stages/NAME/stage.json``) is reused only if it matches its inputs: its
cache key (the stage's configuration, its dependencies' keys, the code fingerprint) and acid's
version, its own content hash and the SHA-256 of every file it lists. A record written for
these inputs that fails the check (tampered or damaged) is recomputed, with one ``notice``
line saying so. (An integrity check against accidents and casual edits, not a signature.)

Stages run on :mod:`acid.executor` -- in this process (``jobs=1``) or on Dask (a local
cluster of ``jobs`` worker processes, or an existing cluster): the same mechanism as
``acid sweep``. On an existing cluster no shared disk is assumed: a stage's input folders
travel with its task and its files come back through the client. The output folder is held
for the whole run (:func:`acid.outdir.claim`: a concurrent second run into it stops with a
one-line message; a later run reuses what is cached) and temporaries of a killed run are
removed when the next one starts.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from acid import __version__
from acid._io import file_sha256, json_safe, write_json
from acid.errors import AcidError
from acid.executor import Executor, ProgressReporter, open_executor
from acid.outdir import TMP_DIR_SUFFIX, claim, clean_stale

STAGE_RECORD = "stage.json"

ProgressFn = Callable[[int, int], None]


@dataclass(frozen=True)
class Stage:
    """One step of a pipeline: what to run, on what configuration, after which stages."""

    name: str
    title: str
    func: Callable[[Path, dict[str, Path], dict, ProgressFn], dict]
    config: dict = field(default_factory=dict)
    depends: tuple[str, ...] = ()
    #: estimated CPU seconds of a cold run: orders the work only (never part of the cache
    #: key); the stage on the longest remaining chain of estimates starts first
    cost: float = 1.0


@dataclass(frozen=True)
class StageOutcome:
    """What a stage produced: its folder, summary, wall time and whether it came from cache."""

    name: str
    title: str
    workdir: Path
    summary: dict
    seconds: float
    cached: bool
    key: str
    #: CPU seconds of the process that ran the stage and of the programs it ran (NaN when
    #: not recorded)
    cpu_seconds: float = math.nan


def source_fingerprint() -> str:
    """Hash of acid's source files and shipped datasets (invalidates caches on any change)."""
    import acid
    from acid.signals import datasets_dir

    pkg = Path(acid.__file__).resolve().parent
    h = hashlib.sha256(__version__.encode())
    files = [(str(p.relative_to(pkg.parent)), p) for p in sorted(pkg.rglob("*.py"))]
    data = datasets_dir().resolve()  # the shipped data, as importlib.resources finds it
    files += [(f"datasets/{p.relative_to(data)}", p) for p in sorted(data.rglob("*"))
              if p.is_file() and p.suffix in (".csv", ".toml")]
    for name, p in files:
        h.update(name.encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def _stage_key(stage: Stage, dep_keys: dict[str, str], fingerprint: str) -> str:
    blob = json.dumps({"stage": stage.name, "config": stage.config, "deps": dep_keys,
                       "code": fingerprint}, sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


def _content_hash(record: dict) -> str:
    """SHA-256 of a stage record's content (every key but ``content_sha256``), canonical."""
    body = {k: v for k, v in record.items() if k != "content_sha256"}
    return hashlib.sha256(json.dumps(body, sort_keys=True, allow_nan=False,
                                     default=str).encode()).hexdigest()


def _check_record(workdir: Path, key: str) -> tuple[dict | None, str]:
    """The cached record of a stage if it may be reused, else (None, why).

    ``why`` is empty when there is simply nothing to reuse (no record, or one for other
    inputs or another code version: the cache key differs); otherwise it says what is wrong
    with a record written for exactly these inputs: unreadable, its content hash or a
    file's hash does not match (tampered or damaged), a file is missing.
    """
    rec = workdir / STAGE_RECORD
    if not rec.is_file():
        return None, ""
    try:
        d = json.loads(rec.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return None, f"{STAGE_RECORD} is not readable JSON"
    if not isinstance(d, dict) or d.get("key") != key or d.get("acid_version") != __version__:
        return None, ""  # other inputs or code: recomputed as any change is
    try:
        ok = d.get("content_sha256") == _content_hash(d)
    except (TypeError, ValueError):
        ok = False
    if not ok or not isinstance(d.get("summary"), dict):
        return None, f"{STAGE_RECORD} does not match its content hash"
    files = d.get("file_sha256")
    if not isinstance(files, dict):
        return None, f"{STAGE_RECORD} lists no file hashes"
    for name, digest in files.items():
        f = workdir / str(name)
        if not f.is_file():
            return None, f"its file {name} is missing"
        if file_sha256(f) != digest:
            return None, f"its file {name} does not match its hash"
    return d, ""


def _seal(stage: Stage, key: str, tmp: Path, summary: dict, seconds: float,
          cpu_seconds: float = math.nan) -> None:
    """Write the record of a stage's finished folder ``tmp`` and move it into place."""
    final = tmp.parent / stage.name
    files = sorted(str(p.relative_to(tmp)) for p in tmp.rglob("*") if p.is_file())
    record = {"stage": stage.name, "key": key, "summary": summary, "seconds": seconds,
              "cpu_seconds": cpu_seconds,
              "files": files, "file_sha256": {f: file_sha256(tmp / f) for f in files},
              "acid_version": __version__}
    record = json_safe(record)  # as write_json writes it, so that the hash reads back
    record["content_sha256"] = _content_hash(record)
    write_json(tmp / STAGE_RECORD, record)
    if final.exists():
        # move the old result aside first: the swap leaves either the old or the new
        # folder in place, never a mixture
        old = Path(tempfile.mkdtemp(prefix=f".{stage.name}.old.", suffix=TMP_DIR_SUFFIX,
                                    dir=final.parent))
        os.replace(final, old / "x")
        os.replace(tmp, final)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(tmp, final)


def _cpu_now() -> float:
    """CPU seconds of this process and of the child processes it has waited for (the C
    compiler of a generated solver runs as one)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def _stage_tmp(root: Path, stage: Stage) -> Path:
    final = root / "stages" / stage.name
    final.parent.mkdir(parents=True, exist_ok=True)
    return Path(tempfile.mkdtemp(prefix=f".{stage.name}.", suffix=TMP_DIR_SUFFIX,
                                 dir=final.parent))


def _progress(stage: Stage, report: ProgressReporter) -> ProgressFn:
    def progress(done: int, total: int) -> None:
        report(stage.name, int(done), int(total), final=done >= total)

    return progress


def _run_stage(stage: Stage, root: Path, inputs: dict[str, Path], key: str,
               report: ProgressReporter) -> tuple[dict, float, float]:
    """Run one stage into a temporary folder, then move it into place (task side, on a
    worker that sees ``root``: this process, or a local cluster)."""
    tmp = _stage_tmp(root, stage)
    t0, c0 = time.perf_counter(), _cpu_now()
    try:
        summary = stage.func(tmp, inputs, stage.config, _progress(stage, report))
        seconds, cpu = time.perf_counter() - t0, _cpu_now() - c0
        _seal(stage, key, tmp, summary, seconds, cpu)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return summary, seconds, cpu


def folder_files(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder``: relative path -> content (what travels to a worker)."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def _scratch_dir() -> str | None:
    """The worker's own directory when on a Dask worker (else the system's temporaries)."""
    try:
        from distributed import get_worker

        return get_worker().local_directory
    except (ImportError, ValueError):
        return None


def _run_stage_detached(stage: Stage, inputs: dict[str, dict[str, bytes]],
                        report: ProgressReporter) -> tuple[dict, float, float, dict[str, bytes]]:
    """Run one stage on a worker that does not see the output folder (task side): its
    inputs' files arrive with the task and are written into a scratch folder of the worker,
    the stage runs there, and its files go back to the client with the summary."""
    base = Path(tempfile.mkdtemp(prefix=f"acid-{stage.name}-", dir=_scratch_dir()))
    try:
        paths = {}
        for dep, files in inputs.items():
            paths[dep] = base / "inputs" / dep
            for rel, data in files.items():
                (paths[dep] / rel).parent.mkdir(parents=True, exist_ok=True)
                (paths[dep] / rel).write_bytes(data)
        work = base / "work"
        work.mkdir()
        t0, c0 = time.perf_counter(), _cpu_now()
        summary = stage.func(work, paths, stage.config, _progress(stage, report))
        seconds, cpu = time.perf_counter() - t0, _cpu_now() - c0
        return summary, seconds, cpu, folder_files(work)
    finally:
        shutil.rmtree(base, ignore_errors=True)


def _install(stage: Stage, root: Path, key: str, summary: dict, seconds: float,
             cpu_seconds: float, files: dict[str, bytes]) -> None:
    """Write what a detached stage sent back into its folder under ``root`` (client side)."""
    tmp = _stage_tmp(root, stage)
    try:
        for rel, data in files.items():
            target = (tmp / rel).resolve()
            if tmp.resolve() not in target.parents:
                raise AcidError(f"stage {stage.name}: a worker sent back a file outside its "
                                f"folder ({rel!r})")
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
        _seal(stage, key, tmp, summary, seconds, cpu_seconds)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def chain_costs(stages: list[Stage]) -> dict[str, float]:
    """Each stage's cost plus the costliest chain of stages that wait for it (its "bottom
    level"): the order in which ready stages start (largest first), so that the long chains
    and the long tasks never run last while the other workers idle."""
    after: dict[str, list[str]] = {s.name: [] for s in stages}
    for s in stages:
        for d in s.depends:
            after[d].append(s.name)
    by_name = {s.name: s for s in stages}
    out: dict[str, float] = {}

    def level(name: str, seen: tuple = ()) -> float:
        if name not in out:
            if name in seen:
                raise AcidError("pipeline has a dependency cycle: " + ", ".join(seen))
            out[name] = float(by_name[name].cost) + max(
                (level(a, (*seen, name)) for a in after[name]), default=0.0)
        return out[name]

    for s in stages:
        level(s.name)
    return out


def run_pipeline(stages: list[Stage], root: Path, jobs: int = 1,
                 on_start: Callable[[str], None] | None = None,
                 on_progress: Callable[[str, int, int], None] | None = None,
                 on_done: Callable[[StageOutcome], None] | None = None,
                 force: bool = False, scheduler: str | None = None,
                 executor: Executor | None = None,
                 notice: Callable[[str], None] | None = None) -> dict[str, StageOutcome]:
    """Run ``stages`` in dependency order, up to ``jobs`` at once.

    Stages whose cache key matches the record in their folder, and whose record passes its
    integrity check, are not run again (unless ``force``); a record that fails it is
    recomputed with one ``notice`` line. Callbacks report start, progress and completion to
    the caller (the CLI).

    Parameters
    ----------
    jobs : 1 runs in this process; more starts a local Dask cluster of that many worker
        processes (in this process, with a ``notice``, when Dask is not installed).
    scheduler : address of an existing Dask cluster instead. Its workers need not see
        ``root``: each stage's inputs travel with its task and its files come back to this
        process (:func:`folder_files`), which writes them.
    executor : an open executor to use instead of starting one.
    """
    root = Path(root)
    by_name = {s.name: s for s in stages}
    for s in stages:
        for d in s.depends:
            if d not in by_name:
                raise AcidError(f"stage {s.name!r} depends on unknown stage {d!r}")
    with claim(root, "acid reproduce"):
        if executor is not None:
            return _run(stages, root, executor, on_start, on_progress, on_done, force, notice)
        try:
            with open_executor(jobs, scheduler, notice=notice) as ex:
                return _run(stages, root, ex, on_start, on_progress, on_done, force, notice)
        finally:  # the workers are gone: a stage folder still under construction is stale
            clean_stale(root / "stages")


def _run(stages, root, ex: Executor, on_start, on_progress, on_done, force, notice=None):
    fingerprint = source_fingerprint()
    keys: dict[str, str] = {}
    outcomes: dict[str, StageOutcome] = {}
    pending = list(stages)
    running: dict = {}
    report = ex.reporter(on_progress or (lambda name, done, total: None), "stages")
    detached = ex.kind == "cluster"  # an existing cluster: no shared disk assumed

    def finish(stage: Stage, summary: dict, seconds: float, cached: bool,
               cpu: float = math.nan) -> None:
        out = StageOutcome(stage.name, stage.title, root / "stages" / stage.name, summary,
                           seconds, cached, keys[stage.name], cpu)
        outcomes[stage.name] = out
        if on_done:
            on_done(out)

    rank = chain_costs(stages)
    queued: list[Stage] = []   # ready, not cached, waiting for a free worker
    slots = max(1, int(getattr(ex, "workers", 1)))
    while pending or running or queued:
        ready = [s for s in pending if all(d in outcomes for d in s.depends)]
        for s in ready:
            pending.remove(s)
            keys[s.name] = _stage_key(s, {d: keys[d] for d in s.depends}, fingerprint)
            workdir = root / "stages" / s.name
            rec, why = (None, "") if force else _check_record(workdir, keys[s.name])
            if rec is not None:
                cpu = rec.get("cpu_seconds")   # absent in older records, None for NaN
                finish(s, rec["summary"], float(rec.get("seconds", 0.0)), True,
                       math.nan if cpu is None else float(cpu))
                continue
            if why and notice is not None:
                notice(f"stage {s.name}: the cached record in {workdir} was not reused ({why}: "
                       "tampered or damaged); recomputing it")
            queued.append(s)
        # one stage per free worker, the longest remaining chain first (the scheduler's own
        # queue would start them in submission order); one worker: the order of ``stages``
        # (no order shortens a serial run)
        if slots > 1:
            queued.sort(key=lambda q: -rank[q.name])
        while queued and len(running) < slots:
            s = queued.pop(0)
            inputs = {d: outcomes[d].workdir for d in s.depends}
            if on_start:
                on_start(s.name)
            if detached:
                shipped = {d: folder_files(p) for d, p in inputs.items()}
                running[ex.submit(_run_stage_detached, s, shipped, report)] = s
            else:
                running[ex.submit(_run_stage, s, root, inputs, keys[s.name], report)] = s
        if not running:
            if pending and not ready:
                raise AcidError("pipeline has a dependency cycle: "
                                + ", ".join(s.name for s in pending))
            continue
        done = ex.wait_any(running, timeout=0.2)
        ex.pump()
        for fut in done:
            s = running.pop(fut)
            if detached:
                summary, seconds, cpu, files = ex.result(fut)
                _install(s, root, keys[s.name], summary, seconds, cpu, files)
            else:
                summary, seconds, cpu = ex.result(fut)
            finish(s, summary, seconds, False, cpu)
    return outcomes
