"""Score winter structures on the folds of ``acid car select --season winter`` (T_cab held
out), from fold parameter files fitted apart (``fold_fit.py``), pooled and per trip.

    python benchmarks/winter_pem/score_cv.py LOGS OUT.npz [--warmup=S] NAME:WARM:F0.json:F1.json ...

Each NAME (a built-in structure) is validated with its fold files on the same folds and
starts (120 per fold, to the end of each trip, exogenous measured, warm-up S in seconds, default
0 as ``acid car select --season winter``: then no warm start acts and the latent states start
from their declared rule) by
``acid.ident.errmodel.validate_with_error_model``: the structure alone, the structure +
residual ARX, and persistence/ARX/subspace fitted on the same training trips. The first
NAME is "model" of the interval tables (its paired RMSE differences against every other).
"""
import sys
import time

import numpy as np

from acid.data import ChannelMap, Dataset
from acid.examples import resolve
from acid.ident.crossval import fold_groups, interval_tables
from acid.ident.errmodel import validate_with_error_model
from acid.models import load
from acid.models.values import ParameterValues
from acid.studies.car.run import load_trips

TIMES = (60.0, 300.0, 600.0, 1500.0)
STARTS = 120

logs, out = sys.argv[1], sys.argv[2]
args = sys.argv[3:]
WARMUP = float(args.pop(0).split("=")[1]) if args and args[0].startswith("--warmup=") else 0
specs = [a.split(":") for a in args]
parts = load_trips(logs, ChannelMap.from_file(resolve("example:bmw_i3_winter_map.toml")))
names = [p.experiment_names()[0] for p in parts]
groups = fold_groups(len(parts), 2)
errors: dict[str, list] = {}
exp_ref = None
for name, warm, *files in specs:
    m = load(name)
    exps = []
    for i, test in enumerate(groups):
        t0 = time.perf_counter()
        held = set(test.tolist())
        order = [j for j in range(len(parts)) if j not in held] + test.tolist()
        both = Dataset.concatenate([parts[j] for j in order])
        both.source = logs
        n_est = sum(len(parts[j]) for j in order[:len(order) - len(test)])
        p = ParameterValues.from_json(files[i])
        r = validate_with_error_model(m, both, p, n_estimation=n_est, channel="T_cab",
                                      starts=STARTS, fit_starts=STARTS, horizon=300,
                                      warmup=WARMUP, to_end=True, warm_start=warm, hold=(),
                                      n_resamples=10, seed=0)
        exps.append(np.asarray(order)[r.experiment])
        st = r.residual.settings
        print(f"{name} fold {i}: {len(r.experiment)} starts, residual ARX na={st['na']} "
              f"nb={st['nb']}, {time.perf_counter() - t0:.0f} s", flush=True)
        for k, e in r.errors.items():
            key = {"model": f"{name} + ARX", "greybox": name}.get(k, k)
            if k in ("model", "greybox") or exp_ref is None:
                errors.setdefault(key, []).append(e)
    e = np.concatenate(exps)
    if exp_ref is None:
        exp_ref = e
    elif not np.array_equal(e, exp_ref):
        raise SystemExit("the structures were not scored from the same starts")
E = {k: np.concatenate(v, axis=0) for k, v in errors.items()}
first = specs[0][0]
E = {"model": E.pop(first), **E}
np.savez(out, exp=exp_ref, names=np.array(names), **{k.replace(" ", "_"): v
                                                      for k, v in E.items()})
figs, verdicts = interval_tables(E, exp_ref, names, 5.0, TIMES, n_resamples=1000, seed=0)
print(f"T_cab held out; 'model' = {first}; RMSE [95 %] / p90 [95 %], K")
for f in figs:
    print(f"{f.scope:>8} {f.time_s:5g} s {f.predictor:>18}: {f.rmse:.2f} [{f.rmse_lo:.2f}, "
          f"{f.rmse_hi:.2f}] / {f.p90:.2f} [{f.p90_lo:.2f}, {f.p90_hi:.2f}] {f.n_starts} "
          f"starts / {f.n_experiments} trips" + ("" if f.resolved else " nr"))
for v in verdicts:
    print(f"{v.scope:>8} {v.time_s:5g} s {first} vs {v.yardstick}: {v.verdict}, "
          f"{v.difference:+.2f} [{v.lo:+.2f}, {v.hi:+.2f}]")
