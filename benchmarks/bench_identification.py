"""Time the identification pipeline: ``acid excite`` (2 h) + ``acid fit`` + ``acid validate``.

Issue 3 asks for the three together "in well under 30 s" on this machine. Measured twice:
the whole commands as a user runs them (subprocesses, Python start-up and imports included)
and the library calls alone.

Usage: python benchmarks/bench_identification.py [--plant hifi|model] [--method ls|oe]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path


def run_cli(plant: str, method: str) -> dict[str, float]:
    times = {}
    with tempfile.TemporaryDirectory() as tmp:
        data, params = Path(tmp) / "data.h5", Path(tmp) / "params.json"
        cmds = {
            "excite": ["excite", "--plant", plant, "--duration", "7200", "--out", str(data)],
            "fit": ["fit", str(data), "--method", method, "--estimation-fraction", "0.5",
                    "--out", str(params)],
            "validate": ["validate", str(data), "--params", str(params), "--starts", "60",
                         "--horizon", "300", "--out", str(Path(tmp) / "val")],
        }
        for name, args in cmds.items():
            t0 = time.perf_counter()
            subprocess.run(["acid", *args], check=True, capture_output=True)
            times[name] = time.perf_counter() - t0
    return times


def run_library(plant: str, method: str) -> dict[str, float]:
    from acid.excite import ExcitationSpec, excite
    from acid.ident.fit import fit_model
    from acid.ident.validate import validate
    from acid.models.params import fitted
    from acid.plant import make_plant

    times = {}
    t0 = time.perf_counter()
    ds = excite(make_plant(plant), ExcitationSpec(duration=7200.0, seed=0))
    times["excite"] = time.perf_counter() - t0
    est, held = ds.split(0.5)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        params = fitted(fit_model("paper", est, method))
    times["fit"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    validate(held, params, starts=60, horizon=300, yardsticks=False)
    times["validate"] = time.perf_counter() - t0
    return times


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plant", default="hifi", choices=("hifi", "model"))
    ap.add_argument("--method", default="oe", choices=("ls", "cvx", "oe"))
    args = ap.parse_args()
    cli = run_cli(args.plant, args.method)
    lib = run_library(args.plant, args.method)
    print(f"identification pipeline, plant {args.plant}, fit {args.method}, 2 h of data "
          "(fit on the first hour; validate: 60 starts x 300 steps on the held-out hour)")
    print(f"{'stage':<10}{'CLI (s)':>10}{'library (s)':>14}")
    for k in cli:
        print(f"{k:<10}{cli[k]:>10.2f}{lib[k]:>14.2f}")
    print(f"{'total':<10}{sum(cli.values()):>10.2f}{sum(lib.values()):>14.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
