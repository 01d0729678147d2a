"""Does ``acid sweep`` scale? 8 and 64 short CPU-bound scenarios, in one process and at
``--jobs 1`` / ``--jobs 2``: speed-up, overhead per scenario, CPU time, processes left.

The scenarios: UDDS (1370 s) after a 600 s warm-up, ambient 26..40 degC x humidity (8 x 1
or 8 x 8), the paper NMPC and the ICM NMPC (about half a CPU second each). Each run is a
fresh command, as a user starts it (imports, cluster start-up and shut-down included):

* ``inline``: ``run_sweep`` with ``InlineExecutor`` (``python -c``): no cluster, no
  serialisation; the reference for the overhead;
* ``jobs 1``, ``jobs 2``: ``acid sweep SPEC --jobs J --no-figures --force``.

Printed per scenario count: wall time of each; ``speed-up`` = jobs 1 / jobs 2; ``overhead``
= (jobs 1 - inline) / scenarios (s per scenario; it contains the fixed cluster start-up, so
the slope between 8 and 64 scenarios, printed last, is the per-scenario part); the sum of
the scenarios' own CPU time (``cpu_s`` of their records) and the CPU time of the whole
command's process tree (``getrusage`` of the command and what it reaped, plus the last
look at each process it did not reap, such as workers forked by a fork server);
``CPU speed-up`` = sum of the scenarios' CPU / wall (how many cores the scenarios kept
busy: the speed-up without the other processes' load); whether every run's table equals
the inline one but for its timing columns; ``left``: processes of the command's process
group alive 10 s after it ended (psutil; must be 0). The load average is printed with each
run: on a shared machine the wall-clock speed-up is bounded by the free cores, the CPU
speed-up less so.

Usage::

    python benchmarks/bench_sweep_scale.py [--counts 8 64] [--repeat 1] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import psutil

SPEC = """title = "scale"
[defaults]
cycle = "udds"
warmup_s = 600.0
[grid]
ambient_C = [26.0, 28.0, 30.0, 32.0, 34.0, 36.0, 38.0, 40.0]
humidity_pct = {humidity}
[controllers.nmpc]
[controllers.icm]
"""
HUMIDITY = {8: "[40.0]", 64: "[20.0, 30.0, 40.0, 50.0, 55.0, 60.0, 65.0, 70.0]"}
INLINE = ("import sys; from acid.executor import InlineExecutor; "
          "from acid.studies.sweep import load_spec, run_sweep; "
          "r = run_sweep(load_spec(sys.argv[1]), sys.argv[2], executor=InlineExecutor(), "
          "force=True, figures=False); sys.exit(r.failed > 0)")


def _group(pgid: int) -> list[psutil.Process]:
    out = []
    for p in psutil.process_iter():
        try:
            if os.getpgid(p.pid) == pgid and p.status() != psutil.STATUS_ZOMBIE:
                out.append(p)
        except (psutil.Error, ProcessLookupError, PermissionError):
            pass
    return out


def run(cmd: list[str], out: Path) -> dict:
    """Run ``cmd`` in its own session; wall, tree CPU, most processes seen, left after."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                         start_new_session=True)
    most = 0
    seen: dict[int, tuple[int, float]] = {}   # pid -> (parent pid, CPU s at the last look)
    while p.poll() is None:
        try:
            kids = psutil.Process(p.pid).children(recursive=True)
            most = max(most, len(kids))
            for k in kids:
                with open(f"/proc/{k.pid}/stat") as f:   # psutil's cpu_times, one read
                    fields = f.read().rsplit(")", 1)[1].split()
                tick = os.sysconf("SC_CLK_TCK")
                seen[k.pid] = (int(fields[1]), (int(fields[11]) + int(fields[12])) / tick)
        except (psutil.Error, OSError, IndexError):
            pass
        time.sleep(0.2)
    wall = time.perf_counter() - t0
    # the command's own CPU and its reaped children's come from getrusage below; processes
    # it did not reap (workers forked by a fork server, services that outlive it) from
    # their last look (up to 0.2 s of each missed)
    alive = {q.pid for q in psutil.process_iter()}
    unreaped = sum(c for pid, (ppid, c) in seen.items() if ppid != p.pid or pid in alive)
    text = p.stdout.read()
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({p.returncode}):\n{text[-2000:]}")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    deadline = time.monotonic() + 10.0
    while _group(p.pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    left = _group(p.pid)
    for q in left:   # do not leave them to the next run
        try:
            q.send_signal(signal.SIGKILL)
        except psutil.Error:
            pass
    records = [json.loads(f.read_text()) for f in (out / "scenarios").glob("*.json")]
    return {"wall_s": wall, "tree_cpu_s": (after.ru_utime + after.ru_stime)
            - (before.ru_utime + before.ru_stime) + unreaped,
            "task_cpu_s": sum(r.get("cpu_s") or 0.0 for r in records),
            "task_wall_s": sum(r.get("elapsed_s") or 0.0 for r in records),
            "records": len(records), "most_children": most, "left": len(left),
            "load": [load0, os.getloadavg()[0]]}


#: columns that say where and how long a scenario ran (they differ from run to run)
TIMING = ["solve_ms_median", "solve_ms_p95", "solve_ms_max", "scenario_elapsed_s", "worker"]


def same_table(out: Path):
    """The run's table without its timing columns, in scenario order."""
    import pandas as pd

    t = pd.read_parquet(out / "results.parquet").drop(columns=TIMING)
    return t.sort_values(["scenario", "controller"]).reset_index(drop=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--counts", type=int, nargs="+", default=[8, 64], choices=[8, 64])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    acid = str(Path(sys.executable).with_name("acid"))
    results: dict = {"cores": len(os.sched_getaffinity(0)), "runs": {}}
    tables: dict = {}
    with tempfile.TemporaryDirectory(prefix="acid-scale-") as tmp:
        root = Path(tmp)
        # untimed: the imports' files in the page cache
        subprocess.run([sys.executable, "-c", "import acid.studies.sweep, distributed"],
                       check=True)
        for n in args.counts:
            spec = root / f"s{n}.toml"
            spec.write_text(SPEC.format(humidity=HUMIDITY[n]))
            for rep in range(args.repeat):
                for mode in ("inline", "jobs 1", "jobs 2"):
                    out = root / f"o{n}-{mode.replace(' ', '')}-{rep}"
                    cmd = ([sys.executable, "-c", INLINE, str(spec), str(out)]
                           if mode == "inline" else
                           [acid, "sweep", str(spec), "--out", str(out), "--jobs",
                            mode.split()[1], "--no-figures", "--force"])
                    r = run(cmd, out)
                    assert r["records"] == n, r
                    tables.setdefault(n, []).append((mode, same_table(out)))
                    results["runs"].setdefault(str(n), {}).setdefault(mode, []).append(r)
                    print(f"{n:>3} scenarios {mode:<7} wall {r['wall_s']:7.2f} s  task CPU "
                          f"{r['task_cpu_s']:7.2f} s  tree CPU {r['tree_cpu_s']:7.2f} s  "
                          f"processes seen {r['most_children']:>2} left {r['left']}  load "
                          f"{r['load'][0]:.1f}-{r['load'][1]:.1f}", flush=True)
    for n, found in tables.items():   # every run's table against the first (inline)
        ref = found[0][1]
        differ = sorted({f"{mode}: {c}" for mode, t in found[1:] for c in ref.columns
                         if not ref[c].equals(t[c])})
        results.setdefault("same_table", {})[str(n)] = not differ
        print(f"{n:>3} scenarios: tables (but timings) of every run equal to inline: "
              f"{'yes' if not differ else 'NO: ' + ', '.join(differ)}")
    print("\nbest of", args.repeat)
    summary = {}
    for n, modes in results["runs"].items():
        best = {m: min(rs, key=lambda r: r["wall_s"]) for m, rs in modes.items()}
        w_in, w1, w2 = (best[m]["wall_s"] for m in ("inline", "jobs 1", "jobs 2"))
        s = {"inline_s": w_in, "jobs1_s": w1, "jobs2_s": w2, "speedup": w1 / w2,
             "overhead_per_scenario_s": (w1 - w_in) / int(n),
             "cpu_speedup_jobs2": best["jobs 2"]["task_cpu_s"] / w2,
             "cpu_speedup_jobs1": best["jobs 1"]["task_cpu_s"] / w1,
             "task_cpu_inline_s": best["inline"]["task_cpu_s"],
             "task_cpu_jobs2_s": best["jobs 2"]["task_cpu_s"],
             "left": max(r["left"] for rs in modes.values() for r in rs)}
        summary[n] = s
        print(f"{n:>3} scenarios: inline {w_in:.2f} s, jobs 1 {w1:.2f} s, jobs 2 {w2:.2f} s; "
              f"speed-up {s['speedup']:.2f}x (CPU speed-up {s['cpu_speedup_jobs2']:.2f} at "
              f"jobs 2, {s['cpu_speedup_jobs1']:.2f} at jobs 1); overhead "
              f"{s['overhead_per_scenario_s']:.3f} s per scenario; processes left {s['left']}")
    if "8" in summary and "64" in summary:
        a, b = summary["8"], summary["64"]
        slope = ((b["jobs1_s"] - b["inline_s"]) - (a["jobs1_s"] - a["inline_s"])) / 56
        summary["overhead_slope_s"] = slope
        print(f"per-scenario overhead of a worker (slope 8 -> 64, jobs 1 - inline): "
              f"{slope:.3f} s")
    results["summary"] = summary
    if args.json is not None:
        args.json.write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
