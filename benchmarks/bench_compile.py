"""The compiled solver's optimisation level, end to end: compile CPU seconds and solve time.

Run: ``python benchmarks/bench_compile.py [--levels -O1 -O2] [--steps 120] [--json out.json]``

What is measured
----------------
1. The econ model is identified as in ``benchmarks/bench_econ_nmpc.py`` and controller E
   (the economic NMPC, 24 x 5 s horizon, fatrop) drives the plant over the start of the
   drive cycle, inside CasADi (no compile); every measured state and preview is recorded.
2. For each optimisation level, the economic NMPC's solver is generated and compiled into an
   empty cache folder of its own: the compiler's CPU seconds (``RUSAGE_CHILDREN``: cc1, as
   and ld included) and wall seconds are taken.
3. The recorded sequence is replayed, in order (warm starts as in closed loop), through one
   controller per level, interleaved step by step (the same machine load for all); the
   whole ``make_step`` wall time is taken and the moves of the levels compared.

CPU seconds of a compile barely depend on the machine's load; wall times do (compare the
levels' ratio, measured in one run).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from bench_econ_nmpc import record  # noqa: E402

from acid.mpc import codegen  # noqa: E402
from acid.mpc.cav_study import default_plant_factory, identify_econ  # noqa: E402
from acid.mpc.econ_nmpc import EconNMPC, EconNMPCConfig  # noqa: E402
from acid.units import C2K  # noqa: E402


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", nargs="+", default=["-O1", "-O2"])
    ap.add_argument("--cycle", default="udds")
    ap.add_argument("--steps", type=int, default=120, help="recorded closed-loop steps")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    econ, _ = identify_econ(default_plant_factory())
    cfg = EconNMPCConfig(T_cab_max=C2K(24.0))
    steps = record(econ, args.cycle, cfg.replace(compiled=False))[: args.steps]
    builds, ctrls = {}, {}
    for level in args.levels:
        codegen.OPT_FLAG, codegen.LARGE_OPT_FLAG = level, None
        with tempfile.TemporaryDirectory(prefix="acid-bench-cc-") as tmp:
            os.environ["ACID_CACHE_DIR"] = tmp
            t0 = time.perf_counter()
            mpc = EconNMPC(econ, cfg.replace(compiled=True))
            wall = time.perf_counter() - t0
            info = mpc._solver.build_info
            assert mpc.backend == "compiled", info
            builds[level] = {"compile_cpu_s": info["compile_cpu_s"],
                             "compile_wall_s": info["compile_s"], "build_wall_s": wall,
                             "library_bytes": Path(info["path"]).stat().st_size}
            ctrls[level] = mpc  # the library stays loaded after its folder is gone
    times = {lv: [] for lv in args.levels}
    moves = {lv: [] for lv in args.levels}
    for _ in range(args.repeats):
        for mpc in ctrls.values():
            mpc.reset()
        for x, vp, Ta, _m in steps:
            for lv, mpc in ctrls.items():
                t0 = time.perf_counter()
                u = mpc.make_step(x, vp, Ta)
                times[lv].append((time.perf_counter() - t0) * 1e3)
                moves[lv].append(u)
    out = {"cycle": args.cycle, "steps": len(steps), "repeats": args.repeats, "levels": {}}
    ref = args.levels[-1]
    for lv in args.levels:
        ms = np.asarray(times[lv])
        out["levels"][lv] = dict(builds[lv], median_ms=float(np.median(ms)),
                                 p95_ms=float(np.percentile(ms, 95)),
                                 max_move_diff_vs_ref=float(np.max(np.abs(
                                     np.asarray(moves[lv]) - np.asarray(moves[ref])))))
    print(f"economic NMPC solver, {len(steps)} states x {args.repeats} replays "
          f"({args.cycle}), interleaved:")
    for lv, r in out["levels"].items():
        print(f"  {lv}: compile {r['compile_cpu_s']:6.1f} CPU s ({r['compile_wall_s']:6.1f} s "
              f"wall), library {r['library_bytes'] / 1e6:.2f} MB; step median "
              f"{r['median_ms']:.3f} ms, p95 {r['p95_ms']:.3f} ms; moves vs {ref}: "
              f"{r['max_move_diff_vs_ref']:.1e}")
    if len(args.levels) == 2:
        a, b = (out["levels"][lv] for lv in args.levels)
        print(f"  {args.levels[0]} / {args.levels[1]}: compile CPU "
              f"{a['compile_cpu_s'] / b['compile_cpu_s']:.2f}x, step median "
              f"{a['median_ms'] / b['median_ms']:.3f}x")
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
