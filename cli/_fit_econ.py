"""``acid fit --model econ``: the econ model family's branch of ``acid fit`` (table, files)."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

from acid import __version__
from acid.data import Dataset
from acid.econ.fit import REQUIRED, EconFitter
from acid_cli._common import note, print_table, say, warn, write_summary


def _num(v: float, digits: int = 5) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.{digits}g}"


def fit_econ(data: Path, out: Path, estimation_fraction: float, covariance: str,
             bandwidth, json_path: Path | None) -> None:
    """Identify the econ model from ``data``, print the estimation report, write ``out``."""
    ds = Dataset.from_hdf5(data, require=REQUIRED, min_samples=20)
    est = ds if estimation_fraction == 1.0 else ds.split(estimation_fraction)[0]
    fitter = EconFitter(covariance=covariance, hac_bandwidth=bandwidth)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the result carries them; printed below, once
        result = fitter.fit(est)
    params = result.params.replace(provenance={**result.params.provenance,
                                               "estimation_fraction": estimation_fraction})
    report = result.to_json_dict()
    params.to_json(out, extra={"fit": report})

    say(f"{data}: {len(est)} of {len(ds)} samples ({est.duration:g} s), model econ, "
        f"{result.n_rows} one-step rows, covariance {covariance} ({result.elapsed_s:.1f} s)")
    rows = [[n, u, _num(v), _num(s, 2), "-" if not math.isfinite(lo) else
             f"[{_num(lo)}, {_num(hi)}]"] for n, u, v, s, lo, hi in result.table()]
    print_table("Econ model parameters (SI, kelvin)", ["name", "unit", "estimate", "stderr",
                                                        "95 % interval"], rows)
    fits = [[ch, f"{result.fit_percent_one_step.get(ch, math.nan):.2f}",
             f"{result.fit_percent_simulation.get(ch, math.nan):.2f}"]
            for ch in result.fit_percent_one_step]
    print_table(f"Fit % (one step / {fitter.sim_window}-step simulation from measured states)",
                ["channel", "one step", "simulation"], fits)
    q = result.power_map_quality
    steady = (f"; near-steady samples ({q['n_steady']}): RMS {q['steady_rms_pct']:.2f} %, "
              f"max {q['steady_max_pct']:.1f} %" if "steady_rms_pct" in q else "")
    say(f"power map P_comp = Q_e f(Q_e, T_evap, v, T_amb): RMS error {q['rms_W']:.1f} W "
        f"({q['rms_pct']:.2f} % of the mean power), R^2 {q['r2']:.4f}, n = {q['n']}{steady}")
    for line in result.notes:
        note(line)
    for line in result.warnings:
        warn(line)
    say(f"parameters written to {out}")
    write_summary(json_path, {"command": "fit", "acid_version": __version__, "model": "econ",
                              "inputs": {"data": str(data)},
                              "estimation_fraction": estimation_fraction, "out": str(out),
                              "params": params.to_json_dict(), **report})
