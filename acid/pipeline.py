"""A small cached, parallel stage runner (used by ``acid reproduce``).

A stage is a module-level function ``func(workdir, inputs, config, progress) -> summary``
that writes its files into ``workdir`` and returns a JSON-serialisable summary. Its cache key
hashes the stage's name and configuration, the keys of the stages it depends on and a
fingerprint of acid's source code and shipped data, so a second run redoes only what changed.
A stage's outputs appear atomically: it runs in a temporary folder that is renamed into place
only when it succeeded.
"""

from __future__ import annotations

import hashlib
import json
import multiprocessing as mp
import os
import queue as queue_mod
import shutil
import tempfile
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path

from acid import __version__
from acid._io import write_json
from acid.errors import AcidError

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


def _cached(workdir: Path, key: str) -> dict | None:
    rec = workdir / STAGE_RECORD
    if not rec.is_file():
        return None
    try:
        d = json.loads(rec.read_text())
    except json.JSONDecodeError:
        return None
    if d.get("key") != key:
        return None
    if not all((workdir / f).is_file() for f in d.get("files", [])):
        return None
    return d


def _run_stage(stage: Stage, root: Path, inputs: dict[str, Path], key: str,
               progress_queue) -> tuple[dict, float]:
    """Run one stage into a temporary folder, then move it into place (worker side)."""
    final = root / "stages" / stage.name
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{stage.name}.", dir=final.parent))

    def progress(done: int, total: int) -> None:
        if progress_queue is not None:
            progress_queue.put((stage.name, int(done), int(total)))

    t0 = time.perf_counter()
    try:
        summary = stage.func(tmp, inputs, stage.config, progress)
        seconds = time.perf_counter() - t0
        files = sorted(str(p.relative_to(tmp)) for p in tmp.rglob("*") if p.is_file())
        write_json(tmp / STAGE_RECORD, {"stage": stage.name, "key": key, "summary": summary,
                                        "seconds": seconds, "files": files,
                                        "acid_version": __version__})
        if final.exists():
            shutil.rmtree(final)
        os.replace(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return summary, seconds


def run_pipeline(stages: list[Stage], root: Path, jobs: int = 1,
                 on_start: Callable[[str], None] | None = None,
                 on_progress: Callable[[str, int, int], None] | None = None,
                 on_done: Callable[[StageOutcome], None] | None = None,
                 force: bool = False) -> dict[str, StageOutcome]:
    """Run ``stages`` in dependency order, up to ``jobs`` at once in local processes.

    Stages whose cache key matches the record in their folder are not run again (unless
    ``force``). Callbacks report start, progress and completion to the caller (the CLI).
    """
    root = Path(root)
    by_name = {s.name: s for s in stages}
    for s in stages:
        for d in s.depends:
            if d not in by_name:
                raise AcidError(f"stage {s.name!r} depends on unknown stage {d!r}")
    fingerprint = source_fingerprint()
    keys: dict[str, str] = {}
    outcomes: dict[str, StageOutcome] = {}
    pending = list(stages)
    running: dict[Future, Stage] = {}
    ctx = mp.get_context("spawn") if jobs > 1 else None
    manager = ctx.Manager() if ctx is not None else None
    pq = manager.Queue() if manager is not None else None
    local_q: queue_mod.SimpleQueue = queue_mod.SimpleQueue()
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) if jobs > 1 else None

    def drain() -> None:
        for q in (pq, local_q):
            if q is None:
                continue
            while True:
                try:
                    name, done, total = q.get_nowait()
                except (queue_mod.Empty, EOFError):
                    break
                if on_progress:
                    on_progress(name, done, total)

    def finish(stage: Stage, summary: dict, seconds: float, cached: bool) -> None:
        out = StageOutcome(stage.name, stage.title, root / "stages" / stage.name, summary,
                           seconds, cached, keys[stage.name])
        outcomes[stage.name] = out
        if on_done:
            on_done(out)

    try:
        while pending or running:
            ready = [s for s in pending if all(d in outcomes for d in s.depends)]
            for s in ready:
                pending.remove(s)
                keys[s.name] = _stage_key(s, {d: keys[d] for d in s.depends}, fingerprint)
                workdir = root / "stages" / s.name
                rec = None if force else _cached(workdir, keys[s.name])
                if rec is not None:
                    finish(s, rec["summary"], float(rec.get("seconds", 0.0)), True)
                    continue
                inputs = {d: outcomes[d].workdir for d in s.depends}
                if on_start:
                    on_start(s.name)
                if pool is None:
                    summary, seconds = _run_stage(s, root, inputs, keys[s.name], local_q)
                    drain()
                    finish(s, summary, seconds, False)
                else:
                    running[pool.submit(_run_stage, s, root, inputs, keys[s.name], pq)] = s
            if ready and pool is None:
                continue
            if not running:
                if pending and not ready:
                    raise AcidError("pipeline has a dependency cycle: "
                                    + ", ".join(s.name for s in pending))
                continue
            done, _ = wait(list(running), timeout=0.2, return_when=FIRST_COMPLETED)
            drain()
            for fut in done:
                s = running.pop(fut)
                summary, seconds = fut.result()
                finish(s, summary, seconds, False)
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
        if manager is not None:
            manager.shutdown()
    return outcomes
