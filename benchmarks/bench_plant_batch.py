"""Speed of the batched high-fidelity plant: plant seconds per CPU second, single vs batched.

B scenarios (direct mode, 600 s each) differing in ambient (20-40 degC), sun (0-1000 W/m^2)
and inputs: piecewise-constant random W_bl (0.05-0.15 kg/s), T_evap_set (3-10 degC) and
vehicle speed (0-25 m/s), held 2-12 samples (seed 0). For each B the same scenarios run
through ``HifiPlant`` one after the other (at most ``--single-max`` of them: a single plant's
speed does not depend on B) and through one ``BatchPlant`` of B members, interleaved
``--repeat`` times (best kept); the largest deviation of the batched trajectories from the
single plant's (K on temperatures, relative on the rest) is printed. CPU time is
``time.process_time``; the refrigerant table is built before timing.

Usage::

    python benchmarks/bench_plant_batch.py [--sizes 1 16 256 1024] [--repeat 2] [--json PATH]
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from acid._io import write_json
from acid.plant.base import InputSchedule
from acid.plant.batch import BatchPlant
from acid.plant.config import PlantConfig
from acid.plant.cycle import make_solver
from acid.plant.hifi import HifiPlant
from acid.units import C2K

DURATION = 600.0


def scenarios(B: int, seed: int = 0) -> tuple[list[PlantConfig], list[InputSchedule]]:
    """B configurations and input schedules (see the module docstring)."""
    rng = np.random.default_rng(seed)
    base = PlantConfig()
    n = int(DURATION / base.Ts)
    cfgs, scheds = [], []
    for _ in range(B):
        cfgs.append(dataclasses.replace(base, T_amb=C2K(rng.uniform(20.0, 40.0)),
                                        G_solar=rng.uniform(0.0, 1000.0)))
        W, Tset, v = np.empty(n), np.empty(n), np.empty(n)
        k = 0
        while k < n:
            d = int(rng.integers(2, 13))
            W[k:k + d] = rng.uniform(0.05, 0.15)
            Tset[k:k + d] = C2K(rng.uniform(3.0, 10.0))
            v[k:k + d] = rng.uniform(0.0, 25.0)
            k += d
        scheds.append(InputSchedule(W, Tset, v))
    return cfgs, scheds


def run_single(cfgs, scheds) -> tuple[float, list[dict]]:
    """CPU seconds of the single plants, one after the other, and their trajectories."""
    out = []
    t0 = time.process_time()
    for cfg, s in zip(cfgs, scheds, strict=True):
        p = HifiPlant(cfg)
        p.reset()
        rows = [p.step(s.W_bl[k], s.T_evap_set[k], s.v_veh[k]) for k in range(len(s))]
        out.append(rows)
    cpu = time.process_time() - t0
    return cpu, [{k: np.array([r[k] for r in rows]) for k in rows[0]} for rows in out]


def run_batch(cfgs, scheds) -> tuple[float, list[dict]]:
    """CPU seconds of one ``BatchPlant`` run of all scenarios, and its trajectories."""
    t0 = time.process_time()
    out = BatchPlant(cfgs).run(scheds)
    return time.process_time() - t0, out


def deviation(ref: list[dict], got: list[dict]) -> float:
    """Largest |difference| / max(1, |value|) over every channel, sample and member."""
    return max(float(np.max(np.abs(a[k] - b[k]) / np.maximum(1.0, np.abs(a[k]))))
               for a, b in zip(ref, got, strict=False) for k in a)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 16, 256, 1024])
    parser.add_argument("--repeat", type=int, default=2, help="interleaved runs (best kept)")
    parser.add_argument("--single-max", type=int, default=32,
                        help="single-plant runs per size at most")
    parser.add_argument("--json", default=None, help="write the results as JSON here")
    args = parser.parse_args(argv)
    make_solver(PlantConfig())  # build the refrigerant table outside the timing
    rows = {}
    print(f"{'B':>6}{'single plant-s/CPU-s':>22}{'batched plant-s/CPU-s':>23}{'speed-up':>10}"
          f"{'max deviation':>15}")
    for B in args.sizes:
        cfgs, scheds = scenarios(B)
        m = min(B, args.single_max)
        best_s = best_b = float("inf")
        dev = 0.0
        for _ in range(max(1, args.repeat)):
            cpu_s, ref = run_single(cfgs[:m], scheds[:m])
            cpu_b, got = run_batch(cfgs, scheds)
            best_s, best_b = min(best_s, cpu_s), min(best_b, cpu_b)
            dev = max(dev, deviation(ref, got[:m]))
        single = m * DURATION / best_s
        batched = B * DURATION / best_b
        rows[B] = {"single": single, "batched": batched, "speedup": batched / single,
                   "max_deviation": dev, "single_runs": m}
        print(f"{B:>6}{single:>22.0f}{batched:>23.0f}{batched / single:>10.2f}{dev:>15.1e}")
    summary = {"duration_s": DURATION, "plant_seconds_per_cpu_second": rows,
               "target_batched_B256": 100000.0}
    if args.json:
        write_json(args.json, summary)
    return summary


if __name__ == "__main__":
    main()
