"""``acid fit --model econ``: the econ model's branch of ``acid fit`` (table, files), over
acid.ident's staged fit of the econ declaration (``acid.ident.econ.identify``)."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

from acid import __version__
from acid.data import Dataset
from acid.ident.econ import REQUIRED, identify
from acid.ident.envelope import Envelope
from acid_cli._common import note, print_table, say, warn, write_summary


def _num(v: float, digits: int = 5) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.{digits}g}"


def fit_econ(data: Path, out: Path, estimation_fraction: float, covariance: str,
             bandwidth, json_path: Path | None) -> None:
    """Identify the econ model from ``data``, print the estimation report, write ``out``."""
    ds = Dataset.from_hdf5(data, require=REQUIRED, min_samples=20)
    est = ds if estimation_fraction == 1.0 else ds.split(estimation_fraction)[0]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # printed below, once
        result = identify(est, covariance=covariance, hac_bandwidth=bandwidth)
    params = result.params.replace(provenance={**result.params.provenance,
                                               "estimation_fraction": estimation_fraction})
    report = result.to_json_dict()
    params.to_json(out, extra={"fit": report})

    fit = result.fit
    say(f"{data}: {len(est)} of {len(ds)} samples ({est.duration:g} s), model econ, staged "
        f"fit (acid.ident), covariance {covariance} ({fit.elapsed_s:.1f} s)")
    rows = [[e.name, e.unit, _num(e.value), _num(e.stderr, 2), "-" if not math.isfinite(
        e.ci95[0]) else f"[{_num(e.ci95[0])}, {_num(e.ci95[1])}]", e.status]
        for e in fit.estimates]
    print_table("Econ model parameters (SI, kelvin)", ["name", "unit", "estimate", "stderr",
                                                        "95 % interval", "status"], rows)
    print_table("Equations: stage method, one-step fit %, residual std",
                ["equation", "fit", "fit %", "resid"],
                [[q.name, q.method, _num(q.fit_percent, 4), _num(q.residual_std, 3)]
                 for q in fit.equations])
    q = result.power_map_quality
    steady = (f"; near-steady samples ({q['n_steady']}): RMS {q['steady_rms_pct']:.2f} %, "
              f"max {q['steady_max_pct']:.1f} %" if "steady_rms_pct" in q else "")
    say(f"power map P_comp = Q_e f(Q_e, T_evap, v, T_amb): RMS error {q['rms_W']:.1f} W "
        f"({q['rms_pct']:.2f} % of the mean power), R^2 {q['r2']:.4f}, n = {q['n']}{steady}")
    say(f"envelope (the ranges of the data it was identified on; a controller planning "
        f"outside them extrapolates): {Envelope.of(params).describe()}")
    for line in fit.notes:
        note(line)
    for line in [*map(str, (w.message for w in caught)), *fit.warnings]:
        warn(line)
    say(f"parameters written to {out}")
    write_summary(json_path, {"command": "fit", "acid_version": __version__, "model": "econ",
                              "inputs": {"data": str(data)},
                              "estimation_fraction": estimation_fraction, "out": str(out),
                              "params": params.to_json_dict(), **report})
