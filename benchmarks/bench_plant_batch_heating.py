"""Speed of the batched heating plant: plant seconds per CPU second, single vs batched.

B winter scenarios (nominal mode: the production controllers, 600 s each from a cold soak)
differing in ambient (-20 to 15 degC), vehicle (acid's default and the paper's, alternating),
heat pump fitted or not (every third member heater only), and speed: piecewise-constant
random vehicle speed (0-25 m/s) held 2-12 samples (seed 0). For each B the same scenarios run
through ``HeatingPlant`` one after the other (at most ``--single-max`` of them: a single
plant's speed does not depend on B) and through one ``BatchHeatingPlant`` of B members,
interleaved ``--repeat`` times (best kept); the largest deviation of the batched trajectories
from the single plant's (K on temperatures, relative on the rest) is printed. CPU time is
``time.process_time``; the refrigerant table is built before timing.

Usage::

    python benchmarks/bench_plant_batch_heating.py [--sizes 16 256 1024] [--repeat 2]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from acid._io import write_json
from acid.plant.batch.heating import BatchHeatingPlant
from acid.plant.heating import HeatingPlant
from acid.plant.heating_config import HeatingConfig, winter_plant_config
from acid.plant.vehicles import vehicle_config
from acid.units import C2K

DURATION = 600.0


def scenarios(B: int, seed: int = 0):
    """B (HeatingConfig, PlantConfig) pairs and speed profiles (the module docstring)."""
    rng = np.random.default_rng(seed)
    bases = [vehicle_config("default"), vehicle_config("paper")]
    n = int(DURATION / bases[0].Ts)
    hcs, cfgs, speeds = [], [], []
    for b in range(B):
        hcs.append(HeatingConfig(heat_pump=b % 3 != 2))
        cfgs.append(winter_plant_config(C2K(rng.uniform(-20.0, 15.0)), base=bases[b % 2]))
        v = np.empty(n)
        k = 0
        while k < n:
            d = int(rng.integers(2, 13))
            v[k:k + d] = rng.uniform(0.0, 25.0)
            k += d
        speeds.append(v)
    return hcs, cfgs, speeds


def run_single(hcs, cfgs, speeds) -> tuple[float, list[dict]]:
    """CPU seconds of the single plants, one after the other, and their trajectories."""
    out = []
    t0 = time.process_time()
    for hc, cfg, v in zip(hcs, cfgs, speeds, strict=True):
        p = HeatingPlant(hc, cfg)
        p.reset()
        out.append([p.step(0.0, 0.0, float(x)) for x in v])
    cpu = time.process_time() - t0
    return cpu, [{k: np.array([r[k] for r in rows]) for k in rows[0]} for rows in out]


def run_batch(hcs, cfgs, speeds) -> tuple[float, list[dict]]:
    """CPU seconds of one ``BatchHeatingPlant`` run of all scenarios, and its trajectories."""
    t0 = time.process_time()
    out = BatchHeatingPlant(hcs, cfgs).run(speeds)
    return time.process_time() - t0, out


def deviation(ref: list[dict], got: list[dict]) -> float:
    """Largest |difference| / max(1, |value|) over every channel, sample and member."""
    return max(float(np.max(np.abs(a[k] - b[k]) / np.maximum(1.0, np.abs(a[k]))))
               for a, b in zip(ref, got, strict=False) for k in a)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[16, 256, 1024])
    parser.add_argument("--repeat", type=int, default=2, help="interleaved runs (best kept)")
    parser.add_argument("--single-max", type=int, default=32,
                        help="single-plant runs per size at most")
    parser.add_argument("--json", default=None, help="write the results as JSON here")
    args = parser.parse_args(argv)
    HeatingPlant()  # build the refrigerant table outside the timing
    rows = {}
    print(f"{'B':>6}{'single plant-s/CPU-s':>22}{'batched plant-s/CPU-s':>23}{'speed-up':>10}"
          f"{'max deviation':>15}")
    for B in args.sizes:
        hcs, cfgs, speeds = scenarios(B)
        m = min(B, args.single_max)
        best_s = best_b = float("inf")
        dev = 0.0
        for _ in range(max(1, args.repeat)):
            cpu_s, ref = run_single(hcs[:m], cfgs[:m], speeds[:m])
            cpu_b, got = run_batch(hcs, cfgs, speeds)
            best_s, best_b = min(best_s, cpu_s), min(best_b, cpu_b)
            dev = max(dev, deviation(ref, got[:m]))
        single = m * DURATION / best_s
        batched = B * DURATION / best_b
        rows[B] = {"single": single, "batched": batched, "speedup": batched / single,
                   "max_deviation": dev, "single_runs": m}
        print(f"{B:>6}{single:>22.0f}{batched:>23.0f}{batched / single:>10.2f}{dev:>15.1e}")
    summary = {"plant": "heating", "duration_s": DURATION,
               "plant_seconds_per_cpu_second": rows}
    if args.json:
        write_json(args.json, summary)
    return summary


if __name__ == "__main__":
    main()
