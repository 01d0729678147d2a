"""acid.studies.car.errcv: grey box plus residual ARX cross-validated over trips.

Synthetic trips from a cabin that loses to the ambient (``TRUE`` of the structure-selection
test); the grey box lacks that path (``SMALL`` at the true C and G), so its held-out error
grows with the horizon in a way the ambient explains: the residual ARX, fitted on the
training trips of each fold only, must repair it on the held-out trips, pooled over both
folds (every trip held out once)."""

from __future__ import annotations

import numpy as np
import pytest

from acid.data import Dataset
from acid.errors import DataError
from acid.models import Model, Parameter, Signal, State
from acid.studies.car.errcv import error_model_cv

TS = 5.0


def _declared(name, uses_amb):
    def ode(s):
        q = s.G * (s.T_evap - s.T_cab) + (s.UA * (s.T_amb - s.T_cab) if uses_amb else 0.0)
        return {"T_cab": q / (1e3 * s.C)}
    pars = [Parameter("C", "kJ/K", 20.0, 1.0, 200.0), Parameter("G", "W/K", 50.0, 1.0, 500.0)]
    pars += [Parameter("UA", "W/K", 60.0, 0.0, 500.0)] if uses_amb else []
    return Model(name, states=[State("T_cab", "K", description="cabin air")],
                 inputs=[Signal("T_evap", "K", "supply air")],
                 disturbances=[Signal("T_amb", "K", "ambient")], parameters=pars, Ts=TS,
                 ode=ode)


TRUE, SMALL = _declared("true", True), _declared("small", False)


def _trips(n_trips, n, seed):
    rng = np.random.default_rng(seed)
    parts = []
    for _ in range(n_trips):
        evap = np.repeat(rng.uniform(278.0, 300.0, n // 24 + 1), 24)[:n]
        amb = np.full(n, rng.uniform(290.0, 310.0)) + np.linspace(0.0, 3.0, n)
        X, _ = TRUE.simulate(np.array([amb[0]]), evap[:, None], amb[:, None], TRUE.values)
        ch = {"T_cab": X[:-1, 0] - 273.15 + 0.02 * rng.standard_normal(n),
              "T_evap": evap - 273.15, "T_amb": amb - 273.15}
        parts.append(Dataset(np.arange(n) * TS, ch, dict.fromkeys(ch, "degC"), TS))
    return Dataset.concatenate(parts)


def _cv(values, **kw):
    ds = _trips(n_trips=6, n=160, seed=3)
    return error_model_cv(SMALL, ds, values, folds=2, starts=24, horizon=61, warmup=0,
                          to_end=False, n_resamples=100, **kw)


def test_the_residual_arx_repairs_a_missing_path_on_held_out_trips():
    v = dict(zip(SMALL.parameter_names, map(float, SMALL.values), strict=True))
    cv = _cv([v, v])
    t = 300.0
    fig = {f.predictor: f for f in cv.figures if f.scope == "pooled" and f.time_s == t}
    assert fig["model"].n_experiments == 6          # both folds pooled: every trip once
    assert fig["model"].resolved
    # grey box + ARX resolvably better than the grey box alone, by a fifth at least
    verdict = next(d for d in cv.verdicts if d.scope == "pooled" and d.time_s == t
                   and d.yardstick == "greybox")
    assert verdict.verdict == "beats", cv.summary()
    assert fig["model"].rmse < 0.8 * fig["greybox"].rmse
    assert [len(f["held_out"]) for f in cv.folds] == [3, 3]
    assert "grey box + ARX vs greybox" in cv.summary()


def test_one_parameter_set_per_fold():
    with pytest.raises(DataError, match="2 folds"):
        _cv([dict(zip(SMALL.parameter_names, np.asarray(SMALL.values), strict=True))])


def test_cli_refuses_an_unknown_error_model(tmp_path):
    from typer.testing import CliRunner

    from acid_cli.main import app

    r = CliRunner().invoke(app, ["car", "select", str(tmp_path), "--error-model", "ann"])
    assert r.exit_code == 2 and "--error-model" in r.output and "'arx'" in r.output
