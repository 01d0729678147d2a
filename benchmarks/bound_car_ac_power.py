"""How much of the BMW i3's logged A/C power any model of the logged channels can predict on
trips it was not fitted on: an upper-bound check for a declared power model.

The summer trips (``../shared/real-data/bmw-i3``, imported through the bundled map at 5 s)
are split as the README's car study does (alternate trips in name order). A ridge regression
of ``P_comp`` on every logged channel that could carry the A/C load (cabin air, ambient,
evaporator air, speed, their differences and products, up to 2 minutes of lags, the cabin's
and the evaporator's backward differences) is fitted on one half and scored on the other,
both ways: R^2 per 5 s sample and of 60 s means, and each held-out trip's energy ratio.
A physical power model of these channels can do better than this flexible regression only
by luck; where the regression cannot reach R^2 0.5, the logs cannot support it.

    python benchmarks/bound_car_ac_power.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from acid.data import ChannelMap, import_logs
from acid.signals import datasets_dir

ROOT = Path(__file__).resolve().parents[1]
REAL = next((p for p in (ROOT.parent / "shared" / "real-data" / "bmw-i3",
                         ROOT.parent.parent / "shared" / "real-data" / "bmw-i3") if p.is_dir()),
            ROOT.parent / "shared" / "real-data" / "bmw-i3")
FEATURES = ("T_cab", "T_amb", "T_evap", "v_veh")


def design(ds, lags: int) -> np.ndarray:
    """Regressors per sample, lags inside each trip only (the first sample repeated)."""
    rows = []
    for e in np.unique(ds.experiment):
        m = ds.experiment == e
        c = {k: np.asarray(ds[k], float)[m] for k in FEATURES}
        base = [c["T_cab"], c["T_amb"], c["T_evap"], c["v_veh"], c["T_cab"] - c["T_evap"],
                c["T_amb"] - c["T_evap"]]
        cols = [np.ones(m.sum())]
        for b in base:
            cols += [b] + [np.concatenate([np.full(k, b[0]), b[:-k]]) for k in range(1, lags + 1)]
        cols += [base[i] * base[j] for i in range(len(base)) for j in range(i, len(base))]
        cols += [np.diff(c[k], prepend=c[k][0]) for k in ("T_evap", "T_cab")]
        rows.append(np.column_stack(cols))
    return np.vstack(rows)


def r2(y: np.ndarray, p: np.ndarray) -> float:
    return float(1.0 - np.sum((y - p) ** 2) / np.sum((y - y.mean()) ** 2))


def main() -> int:
    if not REAL.is_dir():
        print(f"skipped: {REAL} is absent (../shared/real-data beside the repository)")
        return 0
    cmap = ChannelMap.from_file(datasets_dir() / "examples" / "bmw_i3_map.toml")
    ds = import_logs(sorted(REAL.glob("TripA*.csv.gz")), cmap)
    P = np.asarray(ds["P_comp"], float)
    ids = np.unique(ds.experiment)
    half = np.isin(ds.experiment, ids[1::2]).astype(int)      # alternate trips
    print(f"{ids.size} trips, {P.size} samples at 5 s; P_comp mean {np.nanmean(P):.0f} W, "
          f"std {np.nanstd(P):.0f} W")
    for lags in (0, 6, 24):
        X = design(ds, lags)
        ok = np.isfinite(X).all(axis=1) & np.isfinite(P)
        fits, means, ratios = [], [], []
        for k in (0, 1):
            tr, te = ok & (half != k), ok & (half == k)
            A = X[tr].T @ X[tr]
            theta = np.linalg.solve(A + 1e-3 * np.trace(A) / A.shape[0] * np.eye(A.shape[0]),
                                    X[tr].T @ P[tr])
            pred = X @ theta
            fits.append(r2(P[te], pred[te]))
            a, b = [], []
            for e in ids[(np.arange(ids.size) % 2) == k]:
                idx = np.flatnonzero(te & (ds.experiment == e))
                if P[idx].sum() > 0:
                    ratios.append(pred[idx].sum() / P[idx].sum())
                for i in range(0, idx.size - 11, 12):
                    a.append(P[idx[i:i + 12]].mean())
                    b.append(pred[idx[i:i + 12]].mean())
            means.append(r2(np.array(a), np.array(b)))
        ratios = np.array(ratios)
        print(f"lags {lags:2d} ({X.shape[1]:3d} regressors): held-out R^2 per 5 s "
              f"{fits[0]:+.2f} / {fits[1]:+.2f}, of 60 s means {means[0]:+.2f} / "
              f"{means[1]:+.2f}; trip energy within 15 % on {np.sum(abs(ratios - 1) <= 0.15)}"
              f" of {ratios.size} trips (median ratio {np.median(ratios):.2f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
