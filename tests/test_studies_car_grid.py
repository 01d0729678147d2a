"""The start grid of the error-model cross-validation: every start of a held-out trip that has
the whole horizon after it, so the longest horizon is scored from every start reaching it."""

from __future__ import annotations

import numpy as np
import pytest

from acid.data import Dataset
from acid.errors import DataError
from acid.models import Model, Parameter, Signal, State
from acid.studies.car.errcv import error_model_cv, start_grid

TS = 5.0


def _model():
    return Model("one", states=[State("T_cab", "K", description="cabin air")],
                 inputs=[Signal("T_evap", "K", "supply air")],
                 parameters=[Parameter("C", "kJ/K", 20.0, 1.0, 200.0),
                             Parameter("G", "W/K", 50.0, 1.0, 500.0)], Ts=TS,
                 ode=lambda s: {"T_cab": s.G * (s.T_evap - s.T_cab) / (1e3 * s.C)})


def _trips(lengths, seed=0):
    rng = np.random.default_rng(seed)
    m = _model()
    parts = []
    for n in lengths:
        evap = np.repeat(rng.uniform(278.0, 300.0, n // 12 + 1), 12)[:n]
        X, _ = m.simulate(np.array([300.0]), evap[:, None], np.zeros((n, 0)), m.values)
        ch = {"T_cab": X[:-1, 0] - 273.15 + 0.05 * rng.standard_normal(n),
              "T_evap": evap - 273.15}
        parts.append(Dataset(np.arange(n) * TS, ch, dict.fromkeys(ch, "degC"), TS))
    return Dataset.concatenate(parts)


def test_the_grid_keeps_only_starts_with_the_whole_horizon_after_them():
    ds = _trips([100, 50, 80])            # segments [0,100), [100,150), [150,230)
    k = start_grid(ds, 100, horizon=60, warmup=10, every=7)
    # trip 2 (50 samples) cannot hold 10 + 60; trip 3: 160, 167 (167 + 60 = 227 < 230)
    assert k.tolist() == [160, 167]
    assert start_grid(ds, 0, 60, 0, 20).tolist() == [0, 20, 150]
    with pytest.raises(DataError, match="every"):
        start_grid(ds, 0, 60, 0, 0)


def test_every_grid_start_is_scored_at_the_longest_horizon():
    """Four trips of 200 samples and two of 40, taken in turn (3 per fold, 2 long ones
    each); horizon 60 steps (300 s): with the grid, every scored start reaches 300 s, and
    only the long trips hold one."""
    ds = _trips([200, 200, 40, 40, 200, 200], seed=1)
    m = _model()
    v = dict(zip(m.parameter_names, map(float, m.values), strict=True))
    cv = error_model_cv(m, ds, [v, v], folds=2, starts=24, horizon=60, warmup=0,
                        to_end=True, n_resamples=50, every=10)
    fig = {(f.predictor, f.time_s): f for f in cv.figures if f.scope == "pooled"}
    n300 = fig[("greybox", 300.0)]
    assert n300.n_starts == fig[("greybox", 60.0)].n_starts == 4 * 14   # 0..130 every 10
    assert n300.n_experiments == 4 and fig[("greybox", 60.0)].n_experiments == 4
    even = error_model_cv(m, ds, [v, v], folds=2, starts=24, horizon=60, warmup=0,
                          to_end=True, n_resamples=50)
    fe = {(f.predictor, f.time_s): f for f in even.figures if f.scope == "pooled"}
    assert fe[("greybox", 60.0)].n_experiments == 6       # even starts: the short trips too
    assert fe[("greybox", 300.0)].n_starts < fe[("greybox", 60.0)].n_starts
    assert cv.settings["start_every"] == 10
