"""How the declared model's fits scale with the data: least squares, output error (dense
and multiple-shooting) and prediction error on 1, 4, 16 h of ``acid excite`` data (the
paper's model), CPU seconds and each output-error optimum against the dense one.

Usage: python benchmarks/bench_fit_scaling.py [--hours 1 4 16] [--model paper]
       [--methods ls "oe dense" "oe ms" pem]
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--hours", type=float, nargs="+", default=[1.0, 4.0, 16.0])
    ap.add_argument("--model", default="paper")
    ap.add_argument("--methods", nargs="+", default=["ls", "oe dense", "oe ms", "pem"])
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    from acid.excite import ExcitationSpec, excite
    from acid.ident.fit import fit_model
    from acid.plant import make_plant

    print("hours samples  method      CPU-s  loss            ms: rel. param diff to dense OE; "
          "pem: converged?")
    for h in args.hours:
        ds = excite(make_plant("hifi"), ExcitationSpec(duration=3600.0 * h, seed=1))
        out = {}
        for label, kw in (("ls", {"method": "ls"}), ("oe dense", {"method": "oe"}),
                          ("oe ms", {"method": "oe", "oe_solver": "ms"}),
                          ("pem", {"method": "pem"})):
            if label not in args.methods:
                continue
            t = time.process_time()
            r = fit_model(args.model, ds, **kw)
            cpu = time.process_time() - t
            out[label] = r
            loss = r.output_error.get("loss", float("nan")) if r.output_error else float("nan")
            diff = ""
            if label == "oe ms" and "oe dense" in out:
                a = np.array([e.value for e in out["oe dense"].estimates])
                b = np.array([e.value for e in r.estimates])
                diff = f"{np.max(np.abs(a - b) / np.maximum(np.abs(a), 1e-12)):.2e}" + (
                    f", loss {abs(loss / out['oe dense'].output_error['loss'] - 1):.1e}")
            oe_ = r.output_error or {}
            if label == "pem":     # converged or not, and the evaluations and Hessians
                diff = oe_.get("status", "").split("; ")[-1].split(": ")[0]
                diff = ("converged, " if oe_.get("converged") else "NOT converged, ") + diff
            print(f"{h:5g} {len(ds):7d}  {label:9s} {cpu:7.2f}  {loss:<14.8g}  {diff}"
                  + ("" if oe_.get("converged", True) or label == "pem"
                     else f"  (not converged: {oe_.get('status')})"))


if __name__ == "__main__":
    main()
