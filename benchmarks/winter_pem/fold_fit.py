"""Fit one fold of ``acid car select --season winter``'s cross-validation (the same folds:
``fold_groups(22, 2)``, fold 0 holds out the 1st, 3rd... trip) and write its parameter file.

    python benchmarks/winter_pem/fold_fit.py LOGS MODEL FOLD METHOD MAX_EVALS OUT.json

LOGS: a copy of the winter logs (never the shared folder itself). Fold 1 trains on the
README's winter estimation split (TripB02, B06, ... B34), fold 0 on the other 11 trips.
"""
import sys
import time

from acid.data import ChannelMap, Dataset
from acid.examples import resolve
from acid.ident.crossval import fold_groups
from acid.ident.fit import fit_model
from acid.models import load
from acid.studies.car.run import load_trips

logs, name, fold, method, evals, out = (sys.argv[1], sys.argv[2], int(sys.argv[3]),
                                        sys.argv[4], int(sys.argv[5]), sys.argv[6])
parts = load_trips(logs, ChannelMap.from_file(resolve("example:bmw_i3_winter_map.toml")))
names = [p.experiment_names()[0] for p in parts]
test = set(fold_groups(len(parts), 2)[fold].tolist()) if fold >= 0 else set()
train = [j for j in range(len(parts)) if j not in test]
tr = Dataset.concatenate([parts[j] for j in train])
tr.source = f"winter fold {fold} training trips"
tr.metadata["experiments"] = [{"name": names[j]} for j in train]
t0, c0 = time.perf_counter(), time.process_time()
m = load(name)
opts = {"oe_window": 240} if method == "oe" else {}
res = fit_model(m, tr, method=method, max_nfev=evals,
                progress=lambda d, t, lab: print(f"{time.perf_counter() - t0:.0f} s {lab}",
                                                 flush=True), **opts)
print(f"wall {time.perf_counter() - t0:.0f} s, CPU {time.process_time() - c0:.0f} s",
      flush=True)
print("on bounds", getattr(res, "on_bounds", None), flush=True)
for k in ("status", "loss", "message"):
    print(k, getattr(res, k, None), flush=True)
res.write(out, m, {"fold": fold, "held_out": [names[j] for j in sorted(test)],
                   "trained_on": [names[j] for j in train], "method": method,
                   "max_evals": evals})
print("done")
