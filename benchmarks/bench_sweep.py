"""Scaling of ``acid sweep`` on Dask: 16 short scenarios on 1 worker process vs 2.

The scenarios: UDDS (1370 s), ambient 26..40 degC in 8 steps x humidity 30 / 60 %, a 600 s
common warm-up, the paper NMPC on a constant bound and the ICM NMPC (about 1.3 s of work
each on one core). Two timings per worker count, in the same run (the ratio is what to
read; wall-clock numbers on a shared machine are noisy):

* ``end to end``: ``run_sweep`` as the command runs it -- start a LocalCluster, run, write
  the table and figures, shut down;
* ``compute``: on a cluster that is already up and whose workers have imported acid (a
  warm-up sweep of one scenario per worker first), the 16 scenarios alone.

Best of ``--repeat`` runs, 1 and 2 workers interleaved. Expect a 2-worker speed-up above 1.7
on an otherwise idle 2-core machine.

Usage::

    python benchmarks/bench_sweep.py [--repeat 3] [--json PATH]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from acid._io import write_json
from acid.executor import DaskExecutor, usable_cores
from acid.studies.sweep import run_sweep, spec_from_dict

SPEC = {
    "title": "bench",
    "defaults": {"cycle": "udds", "warmup_s": 600.0},
    "grid": {"ambient_C": [26.0, 28.0, 30.0, 32.0, 34.0, 36.0, 38.0, 40.0],
             "humidity_pct": [30.0, 60.0]},
    "controllers": {"nmpc": {}, "icm": {}},
}
WARM = {**SPEC, "grid": {"ambient_C": [27.0, 29.0]}}


def end_to_end(workers: int, root: Path) -> tuple[float, float]:
    """(total, start-up) s: start-up is until the cluster is up and the tasks are sent."""
    spec = spec_from_dict(SPEC, "bench")
    up = []
    t0 = time.perf_counter()
    res = run_sweep(spec, root / f"e2e{workers}", workers=workers, force=True,
                    on_start=lambda *a: up.append(time.perf_counter() - t0))
    dt = time.perf_counter() - t0
    assert res.computed == 16 and res.failed == 0, res.failures()
    return dt, up[0]


def compute_only(workers: int, root: Path) -> float:
    spec, warm = spec_from_dict(SPEC, "bench"), spec_from_dict(WARM, "warm-up")
    with DaskExecutor(workers=workers) as ex:
        run_sweep(warm, root / f"warm{workers}", executor=ex, force=True, figures=False)
        t0 = time.perf_counter()
        res = run_sweep(spec, root / f"c{workers}", executor=ex, force=True, figures=False)
        dt = time.perf_counter() - t0
    assert res.computed == 16 and res.failed == 0, res.failures()
    return dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    times: dict[str, dict[int, list[float]]] = {"end to end": {1: [], 2: []},
                                                "compute": {1: [], 2: []}}
    startup: dict[int, list[float]] = {1: [], 2: []}
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for _ in range(max(1, args.repeat)):
            for w in (1, 2):
                total, up = end_to_end(w, root)
                times["end to end"][w].append(total)
                startup[w].append(up)
                times["compute"][w].append(compute_only(w, root))
    print(f"16 scenarios (UDDS, nmpc + icm), {usable_cores()} usable cores, "
          f"best of {args.repeat}")
    print(f"{'timing':<12} {'1 worker s':>11} {'2 workers s':>12} {'speed-up':>9}")
    out = {"scenarios": 16, "cores": usable_cores(), "repeat": args.repeat, "timings": {}}
    for name, t in times.items():
        t1, t2 = min(t[1]), min(t[2])
        print(f"{name:<12} {t1:>11.2f} {t2:>12.2f} {t1 / t2:>9.2f}")
        out["timings"][name] = {"workers_1_s": t1, "workers_2_s": t2, "speedup": t1 / t2,
                                "all_1_s": t[1], "all_2_s": t[2]}
    print(f"cluster start-up (in end to end): 1 worker {min(startup[1]):.2f} s, 2 workers "
          f"{min(startup[2]):.2f} s")
    out["startup_s"] = {"workers_1": startup[1], "workers_2": startup[2]}
    if args.json is not None:
        write_json(args.json, out)


if __name__ == "__main__":
    main()
