"""acid.ident.stages: staged fitting over any declaration (one-step prediction error, the
groups before a stage held), checked against independent least-squares answers."""

from __future__ import annotations

import numpy as np
import pytest

from acid.data import Dataset
from acid.errors import DataError
from acid.ident.hac import hac_meat, segment_ids
from acid.ident.stages import Stage, fit_stages
from acid.models import Model, Parameter, Signal, State


def _model():
    # T' = T + a (T_amb - T) + b W;  P = c W^2 + e W;  Y = exp(g) T  (nonlinear in g)
    return Model("stages", states=[State("T", "K")], inputs=[Signal("W", "kg/s")],
                 disturbances=[Signal("T_amb", "K")],
                 outputs=[Signal("P", "W"), Signal("Y", "K")],
                 parameters=[Parameter("a", "1", 0.05, 0.0, 1.0), Parameter("b", "K s/kg", 1.0),
                             Parameter("c", "W s^2/kg^2", 1.0), Parameter("e", "W s/kg", 1.0),
                             Parameter("g", "1", 0.0, -1.0, 1.0)],
                 Ts=5.0, step=lambda s: {"T": s.T + s.a * (s.T_amb - s.T) + s.b * s.W},
                 output=lambda s: {"P": s.c * s.W * s.W + s.e * s.W,
                                   "Y": 2.718281828459045 ** s.g * s.T},
                 source="stages.py")


@pytest.fixture(scope="module")
def data():
    rng = np.random.default_rng(7)
    n = 400
    W = rng.uniform(0.05, 0.2, n)
    Ta = 300.0 + rng.normal(0, 2, n)
    T = np.empty(n)
    T[0] = 295.0
    for k in range(n - 1):
        T[k + 1] = T[k] + 0.1 * (Ta[k] - T[k]) - 20.0 * W[k] + 0.05 * rng.standard_normal()
    P = 300.0 * W * W + 40.0 * W + rng.normal(0, 0.1, n)
    Y = np.exp(0.02) * T + rng.normal(0, 0.05, n)
    ch = {"T": T - 273.15, "W": W, "T_amb": Ta - 273.15, "P": P, "Y": Y - 273.15}
    return Dataset(np.arange(n) * 5.0, ch, {"T": "degC", "W": "kg/s", "T_amb": "degC",
                                            "P": "W", "Y": "degC"}, 5.0,
                   experiment=np.repeat([0, 1], n // 2))


def test_each_stage_equals_an_independent_least_squares(data):
    skip = 3
    res = fit_stages(_model(), data, [Stage(("c", "e"), ("P",), "ls"),
                                      Stage(("a", "b"), ("T",), "ee"),
                                      Stage(("g",), ("Y",), "ee")],
                     covariance="white", skip_s=skip * 5.0)
    assert [q.method for q in res.equations] == ["ls", "ee", "ee"]
    T, W, Ta, P, Y = (data.get(n, u) for n, u in (("T", "K"), ("W", "kg/s"), ("T_amb", "K"),
                                                  ("P", "W"), ("Y", "K")))
    c, e = np.linalg.lstsq(np.c_[W * W, W], P, rcond=None)[0]
    k = np.r_[np.arange(skip, 199), np.arange(200 + skip, 399)]       # inside experiments
    X = np.c_[Ta[k] - T[k], W[k]]
    (a, b), rss = np.linalg.lstsq(X, T[k + 1] - T[k], rcond=None)[:2]
    g = np.log(np.sum(Y[k] * T[k]) / np.sum(T[k] ** 2))               # y = exp(g) T
    for name, v in dict(a=a, b=b, c=c, e=e, g=g).items():
        assert res.value(name) == pytest.approx(v, rel=1e-6), name
    # the white standard errors of the ee stage are least squares' own
    se = np.sqrt(np.diag(float(rss[0]) / (k.size - 2) * np.linalg.inv(X.T @ X)))
    est = {x.name: x for x in res.estimates}
    assert est["a"].stderr == pytest.approx(se[0], rel=1e-5)
    assert est["a"].status == "estimated (ee)" and est["c"].status == "estimated (ls)"
    assert list(res.covariance_names) == ["c", "e", "a", "b", "g"]


def test_hac_standard_errors_sum_an_instants_equations(data):
    res = fit_stages(_model(), data, [Stage(("a", "b"), ("T",), "ee")], covariance="hac",
                     hac_bandwidth=3)
    T, W, Ta = (data.get(n, u) for n, u in (("T", "K"), ("W", "kg/s"), ("T_amb", "K")))
    k = np.r_[np.arange(0, 199), np.arange(200, 399)]
    X = np.c_[Ta[k] - T[k], W[k]]
    r = T[k + 1] - T[k] - X @ np.array([res.value("a"), res.value("b")])
    w = r.std()                                    # the residual weight at the optimum
    Jw, rw = X / w, r / w
    bread = np.linalg.inv(Jw.T @ Jw)
    meat = hac_meat(Jw * rw[:, None], segment_ids(k, data.segments()), 3)
    cov = k.size / (k.size - 2) * bread @ meat @ bread
    est = {x.name: x for x in res.estimates}
    assert est["b"].stderr == pytest.approx(np.sqrt(cov[1, 1]), rel=1e-4)
    assert est["c"].status == "fixed" and est["c"].value == 1.0


def test_too_few_samples_is_one_line(data):
    with pytest.raises(DataError, match="usable samples for 2 parameters of T"):
        fit_stages(_model(), data, [Stage(("a", "b"), ("T",), "ee")], skip_s=5.0 * 199)
