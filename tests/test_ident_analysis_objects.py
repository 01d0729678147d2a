"""predict / compare / resid results as objects: a readable repr (their summary, not the
arrays), summary() and a JSON round trip (NaN where no prediction exists included)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import acid
from acid.ident.analysis import CompareResult, PredictionResult, ResidualResult
from acid.models import Model, Parameter, Signal, State
from acid.models.values import ParameterValues


@pytest.fixture(scope="module")
def room():
    model = Model("room", states=[State("T", "K")], inputs=[Signal("u", "W", "heater")],
                  parameters=[Parameter("C", "J/K", 6e5, 1e4, 1e7),
                              Parameter("UA", "W/K", 45.0, 1.0, 500.0)],
                  Ts=60.0, ode=lambda s: {"T": (s.UA * (280.0 - s.T) + s.u) / s.C})
    rng = np.random.default_rng(0)
    n = 300
    u = np.repeat(rng.uniform(0.0, 1500.0, n // 30), 30)
    T = np.empty(n)
    T[0] = 285.0
    for k in range(n - 1):
        T[k + 1] = T[k] + 60.0 * (45.0 * (280.0 - T[k]) + u[k]) / 6e5
    ds = acid.Dataset(time=np.arange(n) * 60.0, Ts=60.0,
                      channels={"T": T + rng.normal(0, 0.05, n), "u": u},
                      units={"T": "K", "u": "W"})
    return model, ds


@pytest.mark.parametrize("kind", ["predict", "compare", "resid"])
def test_results_print_their_summary_and_round_trip_through_json(room, kind):
    model, ds = room
    model = ParameterValues(model.values, model=model)      # the declared values
    res = {"predict": lambda: acid.predict(ds, model, 5),
           "compare": lambda: acid.compare(ds, model),
           "resid": lambda: acid.resid(ds, model)}[kind]()
    cls = {"predict": PredictionResult, "compare": CompareResult,
           "resid": ResidualResult}[kind]
    text = repr(res)
    assert text.splitlines()[0] == f"{cls.__name__}(" and len(text.splitlines()) < 12
    assert "array(" not in text and res.summary() in text
    back = cls.from_json_dict(json.loads(json.dumps(res.to_json_dict(), allow_nan=False)))
    assert back == res and back is not res
    pr = {"predict": lambda r: r, "compare": lambda r: next(iter(r.predictions.values())),
          "resid": lambda r: r.prediction}[kind]
    a, b = pr(res), pr(back)
    np.testing.assert_array_equal(a.predicted, b.predicted)     # NaN where none exists
    assert a.channels == b.channels and a.horizon == b.horizon
    if kind == "predict":
        assert np.isnan(b.predicted[:5]).all() and "5-step prediction" in res.summary()
    if kind == "resid":
        assert back.white == res.white and back.interpretation == res.interpretation
