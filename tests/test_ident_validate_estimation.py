"""The API's validation of a two-record per-experiment fit on the first half of each record:
the estimation samples given as the fitted ``Dataset`` or as ranges, the in-sample windows left
out, the yardsticks fitted on exactly those samples; the API's defaults are the CLI's."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

import acid
from acid.errors import ConfigError
from acid.models import Model, Parameter, Signal, State

N, TS = 400, 60.0          # samples per record, s
Q_TRUE = (150.0, 600.0)    # W, each record's own solar load


def _room() -> Model:
    return Model(
        "room", states=[State("T", "K")], inputs=[Signal("u", "W", "heater")],
        disturbances=[Signal("T_out", "K", "outdoor")],
        parameters=[Parameter("C", "J/K", 6e5, 1e4, 1e7),
                    Parameter("UA", "W/K", 45.0, 1.0, 500.0),
                    Parameter("Q", "W", 300.0, -2000.0, 2000.0, per_experiment=True)],
        Ts=TS, ode=lambda s: {"T": (s.UA * (s.T_out - s.T) + s.u + s.Q) / s.C})


def _record(q: float, rng) -> acid.Dataset:
    u = np.repeat(rng.uniform(0.0, 1500.0, N // 40), 40)
    t_out = 278.15 + 5.0 * np.sin(np.arange(N) * TS / 86400.0 * 2 * np.pi)
    T = np.empty(N)
    T[0] = 290.0
    for k in range(N - 1):
        x = T[k]
        for _ in range(10):
            x += TS / 10 * (45.0 * (t_out[k] - x) + u[k] + q) / 6e5
        T[k + 1] = x
    return acid.Dataset(time=np.arange(N) * TS, Ts=TS,
                        channels={"T": T + rng.normal(0, 0.05, N), "u": u, "T_out": t_out},
                        units={"T": "K", "u": "W", "T_out": "K"})


@pytest.fixture(scope="module")
def two_records():
    """(model, whole records joined, the first halves joined, the fit on them)."""
    rng = np.random.default_rng(3)
    recs = [_record(q, rng) for q in Q_TRUE]
    est = acid.Dataset.concatenate([r.window(0, N // 2) for r in recs])
    model = _room()
    fit = acid.fit_model(model, est, method="oe")
    return model, acid.Dataset.concatenate(recs), est, fit


def test_the_fitted_dataset_marks_the_in_sample_windows_and_fits_the_yardsticks(two_records):
    model, whole, est, fit = two_records
    res = acid.validate_model(model, whole, fit, starts=8, horizon=30, warmup=0,
                              estimation=est)
    # no window scores a fitted sample: every scored step lies in a second half
    scored = res.starts[:, None] + np.arange(1, 31)[None, :]
    assert np.all(scored % N >= N // 2)
    assert any("left out (in-sample)" in n for n in res.notes)
    assert res.settings["yardsticks_fitted_on"] == {"estimation_data_samples": N}
    assert {"persistence", "arx", "subspace"} <= set(res.yardsticks)
    # each record with its own solar load: the model beats holding the temperature
    assert res.metrics["T"]["rmse"] < 0.2
    # the same samples given as ranges of the whole record: the same yardsticks
    ranges = [(0, N // 2), (N, N + N // 2)]
    alt = acid.validate_model(model, whole, fit, starts=8, horizon=30, warmup=0,
                              estimation=ranges, start_range=[(N // 2, N), (N + N // 2, 2 * N)])
    assert alt.settings["yardsticks_fitted_on"] == [list(r) for r in ranges]
    np.testing.assert_array_equal(alt.starts, res.starts)
    for name in ("arx", "subspace"):
        assert alt.yardsticks[name]["description"] == res.yardsticks[name]["description"]
        np.testing.assert_allclose(alt.yardsticks[name]["errors"]["T"],
                                   res.yardsticks[name]["errors"]["T"], rtol=1e-9, atol=1e-12)


def test_yardsticks_on_both_halves_differ_from_the_whole_record(two_records):
    model, whole, est, fit = two_records
    kw = {"starts": 8, "horizon": 30, "warmup": 0, "start_range": [(N // 2, N),
                                                                     (N + N // 2, 2 * N)]}
    halves = acid.validate_model(model, whole, fit, estimation=est, **kw)
    full = acid.validate_model(model, whole, fit, **kw)       # in-sample, with a note
    assert any("in-sample" in n for n in full.notes)
    assert not np.allclose(halves.yardsticks["arx"]["errors"]["T"],
                           full.yardsticks["arx"]["errors"]["T"])


def test_bad_estimation_ranges_are_one_line_errors(two_records):
    model, whole, _, fit = two_records
    with pytest.raises(ConfigError, match="estimation"):
        acid.validate_model(model, whole, fit, starts=4, horizon=10, warmup=0,
                            estimation=[(5 * N, 6 * N)])


def test_the_api_defaults_are_the_cli_s(two_records):
    from acid_cli.validate import validate as cli

    api = inspect.signature(acid.validate_model).parameters
    opt = inspect.signature(cli).parameters
    assert api["yardsticks"].default is opt["yardsticks"].default.default is True
    assert opt["exogenous"].default.default == "hold"
    assert api["starts"].default == opt["starts"].default.default
    assert api["horizon"].default == opt["horizon"].default.default
    model, whole, est, fit = two_records
    res = acid.validate_model(model, whole, fit, starts=4, horizon=10, warmup=0)
    assert res.settings["hold"] == ("T_out",) and res.yardsticks
