"""Speed of the high-fidelity plant: plant seconds simulated per CPU second.

Two cases (target: >= 10,000 plant-s per CPU-s on one core, issue 9):

* ``nominal-600s``: the nominal controller at a constant 10 m/s for 600 s (one Table I run);
* ``direct-4000s``: direct mode, 4000 s of random steps of W_bl (0.05-0.15 kg/s),
  T_evap_set (3-10 degC) and vehicle speed (0-25 m/s), held 10-60 s each (seed 0).

The refrigerant table is built (and CoolProp imported) before timing; CPU time is
``time.process_time`` (best of ``--repeat`` runs). A fixed pure-Python peer (one million
multiply-adds, the kind of work the plant's inner loop does) is timed in the same run, so the
``vs peer`` column (plant seconds per peer run) compares machines and busy periods fairly.

Usage::

    python benchmarks/bench_plant.py [--repeat 3] [--json PATH]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from acid._io import write_json
from acid.plant.config import PlantConfig
from acid.plant.cycle import make_solver
from acid.plant.hifi import HifiPlant
from acid.units import C2K


def _random_inputs(n: int, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """Piecewise-constant random W_bl, T_evap_set (K) and speed, dwell 2-12 samples."""
    W, Tset, v = np.empty(n), np.empty(n), np.empty(n)
    k = 0
    while k < n:
        d = int(rng.integers(2, 13))
        W[k:k + d] = rng.uniform(0.05, 0.15)
        Tset[k:k + d] = C2K(rng.uniform(3.0, 10.0))
        v[k:k + d] = rng.uniform(0.0, 25.0)
        k += d
    return W, Tset, v


def run_case(name: str, config: PlantConfig) -> float:
    """Simulated plant seconds per CPU second of one run of case ``name``."""
    if name == "nominal-600s":
        plant = HifiPlant(config, mode="nominal")
        n = int(600 / plant.Ts)
        t0 = time.process_time()
        plant.reset()
        for _ in range(n):
            plant.step(0.0, config.T_ew_set, 10.0)
    elif name == "direct-4000s":
        plant = HifiPlant(config, mode="direct")
        n = int(4000 / plant.Ts)
        W, Tset, v = _random_inputs(n, np.random.default_rng(0))
        t0 = time.process_time()
        plant.reset()
        for k in range(n):
            plant.step(W[k], Tset[k], v[k])
    else:
        raise ValueError(f"unknown case {name!r}")
    cpu = time.process_time() - t0
    return n * plant.Ts / cpu


def peer_seconds() -> float:
    """CPU seconds of the pure-Python peer: 10^6 float multiply-adds in a loop."""
    t0 = time.process_time()
    x, a = 0.0, 1.0000001
    for _ in range(1_000_000):
        x = x * a + 1e-9
    return time.process_time() - t0


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs per case (best is kept)")
    parser.add_argument("--json", default=None, help="write the results as JSON here")
    args = parser.parse_args(argv)
    config = PlantConfig()
    make_solver(config)  # build the CoolProp table outside the timing
    results = {}
    for case in ("nominal-600s", "direct-4000s"):
        results[case] = max(run_case(case, config) for _ in range(max(1, args.repeat)))
    peer = min(peer_seconds() for _ in range(max(1, args.repeat)))
    print(f"{'case':<16}{'plant-s / CPU-s':>18}{'CPU s per 600 s':>18}{'vs peer':>12}")
    for case, speed in results.items():
        print(f"{case:<16}{speed:>18.0f}{600.0 / speed:>18.4f}{speed * peer:>12.0f}")
    print(f"peer: {peer:.4f} CPU s; target >= 10000 plant-s / CPU-s (issue 9)")
    summary = {"plant_seconds_per_cpu_second": results, "dt_int_s": config.dt_int,
               "peer_cpu_s": peer,
               "plant_seconds_per_peer": {k: v * peer for k, v in results.items()},
               "target": 10000.0}
    if args.json:
        write_json(args.json, summary)
    return summary


if __name__ == "__main__":
    main()
