"""The economic NMPC's compiled solver, end to end: compile CPU seconds and step time per
variant (solver x NLP form x optimisation level).

Run: ``python benchmarks/bench_compile.py [--variants sqp:stage fatrop:inlined ...]
[--levels auto] [--steps 120] [--params identified|truth] [--json out.json]``

What is measured
----------------
1. The econ model is identified as in ``benchmarks/bench_econ_nmpc.py`` (``--params truth``:
   the known parameter set of the tests instead, no identification) and controller E (24 x
   5 s horizon) drives the plant over the start of the drive cycle, inside CasADi (no
   compile); every measured state and preview is recorded.
2. For each variant (``SOLVER:FORM[:LEVEL]``: ``sqp`` or ``fatrop``; ``inlined`` (one
   expression for the whole horizon) or ``stage`` (one function per stage called over the
   horizon, ``stage_functions``); ``-O1``/``-O2``, default acid's rule: -O1 for sources of at
   least 1 MB), the solver is generated and compiled into an empty cache folder of its own:
   the compiler's CPU seconds (``RUSAGE_CHILDREN``: cc1, as and ld included), wall seconds,
   source and library size.
3. The recorded sequence is replayed, in order (warm starts as in closed loop), through one
   controller per variant, interleaved step by step (the same machine load for all); the
   whole ``make_step`` wall time is taken and the moves compared with the last variant's.

CPU seconds of a compile depend less on the machine's load than wall times (compare the
variants' ratios, measured in one run).
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

from acid.control.codegen import build as codegen  # noqa: E402
from acid.control.econ.nmpc import EconNMPC, EconNMPCConfig  # noqa: E402
from acid.studies.cav_study import default_plant_factory, identify_econ  # noqa: E402
from acid.units import C2K  # noqa: E402


def _truth():
    """The econ parameter set of the tests (``tests/conftest.py``'s ``econ_truth``)."""
    sys.path.insert(0, str(Path(__file__).parent.parent / "tests"))
    from conftest import ECON_MAP, ECON_TRUTH

    from acid.models.econ_params import EconParams, PowerMap

    domain = {"Q_e": (-500.0, 6000.0), "T_evap": (270.0, 290.0), "v_veh": (0.0, 35.0),
              "T_amb": (290.0, 320.0)}
    return EconParams(values=dict(ECON_TRUTH), C_ew=2000.0,
                      power_map=PowerMap(coef=ECON_MAP, domain=domain), name="truth")


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variants", nargs="+",
                    default=["sqp:stage", "fatrop:stage", "sqp:inlined", "fatrop:inlined"])
    ap.add_argument("--cycle", default="udds")
    ap.add_argument("--steps", type=int, default=120, help="recorded closed-loop steps")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--params", default="identified", choices=("identified", "truth"))
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    econ = _truth() if args.params == "truth" else identify_econ(default_plant_factory())[0]
    cfg = EconNMPCConfig(T_cab_max=C2K(24.0))
    steps = record(econ, args.cycle, cfg.replace(compiled=False))[: args.steps]
    builds, ctrls = {}, {}
    default_flags = codegen.OPT_FLAG, codegen.LARGE_OPT_FLAG
    for variant in args.variants:
        solver, form, *level = variant.split(":")
        codegen.OPT_FLAG, codegen.LARGE_OPT_FLAG = ((level[0], None) if level
                                                    else default_flags)
        with tempfile.TemporaryDirectory(prefix="acid-bench-cc-") as tmp:
            os.environ["ACID_CACHE_DIR"] = tmp
            t0 = time.perf_counter()
            mpc = EconNMPC(econ, cfg.replace(compiled=True, solver=solver,
                                             stage_functions=form == "stage"))
            wall = time.perf_counter() - t0
            # the SQP's whole step is one generated function when it compiles
            info = (mpc._step if mpc._step is not None else mpc._solver).build_info
            assert mpc.backend == "compiled", info
            builds[variant] = {"compile_cpu_s": info["compile_cpu_s"],
                               "compile_wall_s": info["compile_s"], "build_wall_s": wall,
                               "library_bytes": Path(info["path"]).stat().st_size}
            ctrls[variant] = mpc  # the library stays loaded after its folder is gone
        print(f"  built {variant}: {builds[variant]}", flush=True)
    codegen.OPT_FLAG, codegen.LARGE_OPT_FLAG = default_flags
    times = {v: [] for v in args.variants}
    moves = {v: [] for v in args.variants}
    for _ in range(args.repeats):
        for mpc in ctrls.values():
            mpc.reset()
        for x, vp, Ta, _m in steps:
            for v, mpc in ctrls.items():
                t0 = time.perf_counter()
                u = mpc.make_step(x, vp, Ta)
                times[v].append((time.perf_counter() - t0) * 1e3)
                moves[v].append(u)
    out = {"cycle": args.cycle, "steps": len(steps), "repeats": args.repeats,
           "params": args.params, "variants": {}}
    ref = args.variants[-1]
    span = cfg.u_max - cfg.u_min
    for v in args.variants:
        ms = np.asarray(times[v])
        out["variants"][v] = dict(
            builds[v], median_ms=float(np.median(ms)), p95_ms=float(np.percentile(ms, 95)),
            fallbacks=int(ctrls[v].fallbacks), solver_fallbacks=int(ctrls[v].solver_fallbacks),
            max_move_diff_vs_ref=float(np.max(np.abs(np.asarray(moves[v])
                                                     - np.asarray(moves[ref])) / span)))
    print(f"economic NMPC solver, {len(steps)} states x {args.repeats} replays "
          f"({args.cycle}), interleaved:")
    for v, r in out["variants"].items():
        print(f"  {v:16s} compile {r['compile_cpu_s']:6.1f} CPU s ({r['compile_wall_s']:6.1f} s "
              f"wall), library {r['library_bytes'] / 1e6:.2f} MB; step median "
              f"{r['median_ms']:.3f} ms, p95 {r['p95_ms']:.3f} ms; solver fallbacks "
              f"{r['solver_fallbacks']}; moves vs {ref} (share of range): "
              f"{r['max_move_diff_vs_ref']:.1e}")
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
