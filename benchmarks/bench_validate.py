"""Time the validation's latent-state warm start against the number of starts.

The cabin3 example (latent interior) on 2 h of acid's hifi plant (seed 1),
validated on the last half as ``acid validate --model cabin3`` does (300-step windows, a
300 s warm-up, T_amb held), with ``--warm-start fit`` (least squares over the warm-up,
one small problem per start) and ``--warm-start ekf``. Only the warm-start step is timed:
from the progress callback before it to the one after it, CPU seconds of this process and
wall seconds (inflated by load; compare ratios from one run). The fit's cost should grow
linearly with the starts (issue 19's warm5 stop: it was cubic).

Usage: python benchmarks/bench_validate.py [--starts 60 120 240 360] [--params FILE]
"""

from __future__ import annotations

import argparse
import time
import warnings


def warm_start_times(starts: list[int], params: str | None) -> list[dict]:
    from acid.excite import ExcitationSpec, excite
    from acid.ident.validate import (
        declared_parameters,
        held_out_start,
        read_parameters,
        validate_model,
    )
    from acid.models.loader import load
    from acid.plant import make_plant

    model = load("cabin3")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = excite(make_plant("hifi"), ExcitationSpec(duration=7200.0, seed=1))
    values = read_parameters(model, params) if params else declared_parameters(model)
    lo = held_out_start(len(ds), 0.5)
    rows = []
    for n in starts:
        for how in ("fit", "ekf"):
            marks = []

            def progress(done, total, label, marks=marks):
                marks.append((label, time.process_time(), time.perf_counter()))

            res = validate_model(model, ds, values, starts=n, horizon=300, warmup=60 * ds.Ts,
                                 hold=("T_amb",), start_range=(lo, len(ds)),
                                 warm_start=how, progress=progress, yardsticks=False)
            at = next(i for i, m in enumerate(marks) if m[0].startswith("latent states"))
            rows.append({"starts": int(res.starts.size), "warm_start": how,
                         "cpu_s": marks[at][1] - marks[at - 1][1],
                         "wall_s": marks[at][2] - marks[at - 1][2]})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--starts", type=int, nargs="+", default=[60, 120, 240, 360])
    ap.add_argument("--params", default=None, help="a cabin3 parameter file (default: "
                    "the declared values)")
    args = ap.parse_args()
    rows = warm_start_times(args.starts, args.params)
    print(f"{'starts':>6} {'warm start':>10} {'CPU s':>8} {'wall s':>8}")
    for r in rows:
        print(f"{r['starts']:>6} {r['warm_start']:>10} {r['cpu_s']:>8.3f} {r['wall_s']:>8.3f}")


if __name__ == "__main__":
    main()
