"""``acid.ident.analysis``: k-step ``predict``, ``compare`` (MATLAB fit %) and ``resid`` tests."""

from __future__ import annotations

import matplotlib
import numpy as np
import pandas as pd
import pytest

from acid.errors import ConfigError, DataError
from acid.excite import ExcitationSpec, excite
from acid.ident.analysis import compare, predict, resid
from acid.metrics import fit_percent
from acid.models.params import paper
from acid.plant import make_plant

matplotlib.use("Agg")


def test_predictions_on_noise_free_model_data_are_exact(model_dataset):
    p = paper()
    for k in (1, 7, None):
        pr = predict(model_dataset, p, k)
        m = pr.valid
        assert m.sum() == len(model_dataset) - (0 if k is None else k)
        assert np.max(np.abs(pr.errors[m])) < 1e-8, k
        assert min(pr.fit_percent.values()) > 99.999999


def test_k_step_prediction_matches_a_hand_rolled_loop(model_dataset):
    p = paper().perturbed(0.02, np.random.default_rng(1))
    ds = model_dataset.window(0, 300)
    k, n = 12, 200
    pr = predict(ds, p, k)
    K = {c: ds.get(c, "K") for c in ("T_cab", "T_evap", "T_evap_set", "T_int", "T_shell")}
    W = ds["W_bl"]
    g, t = p.gamma, p.tau
    cab, evap = K["T_cab"][n - k], K["T_evap"][n - k]
    for j in range(n - k, n):   # eqs. 1-3 written out here
        ain = g[5] * evap + g[6] * W[j] + t[2]
        cab, evap = (cab + g[0] * (K["T_int"][j] - cab) + g[1] * (K["T_shell"][j] - cab)
                     + g[2] * (ain - cab) * W[j] + t[0],
                     g[3] * evap + g[4] * (evap - K["T_evap_set"][j]) + t[1])
    assert pr.predicted[n, 0] == pytest.approx(cab, abs=1e-9)
    assert pr.predicted[n, 1] == pytest.approx(evap, abs=1e-9)
    assert pr.predicted[n, 2] == pytest.approx(g[5] * evap + g[6] * W[n] + t[2], abs=1e-9)
    assert np.all(np.isnan(pr.predicted[:k]))


def test_predictions_never_cross_an_experiment_boundary(model_dataset):
    from acid.data import Dataset

    two = Dataset.concatenate([model_dataset.window(0, 100), model_dataset.window(500, 600)])
    pr = predict(two, paper(), 10)
    assert np.all(np.isnan(pr.predicted[100:110])) and np.all(np.isfinite(pr.predicted[110:]))


def test_compare_uses_matlabs_fit_definition_and_ranks_models(model_dataset):
    wrong = paper().perturbed(0.05, np.random.default_rng(3)).replace(name="wrong")
    res = compare(model_dataset, paper(), wrong)
    df = res.to_frame()
    assert list(df.index) == ["paper", "wrong"] and list(df.columns) == ["T_cab", "T_evap",
                                                                         "T_ain", "P_bl"]
    pr = res.predictions["wrong"]
    for i, c in enumerate(pr.channels):
        expected = fit_percent(pr.measured[:, i], pr.predicted[:, i])
        assert df.loc["wrong", c] == pytest.approx(expected)
        if c != "P_bl":   # perturbed() leaves beta (eq. 5) as it is
            assert df.loc["paper", c] > df.loc["wrong", c]
    fig = res.plot()
    assert isinstance(fig, matplotlib.figure.Figure) and len(fig.axes) == 4
    with pytest.raises(ConfigError, match="at least one model"):
        compare(model_dataset)


@pytest.fixture(scope="module")
def process_noise_dataset():
    spec = ExcitationSpec(seed=5)
    plant = make_plant("model", process_noise_std=0.05, rng=spec.rng("noise"))
    ds = excite(plant, spec)
    return ds.select([c for c in ds.channels if c != "P_bl"])   # eqs. 1-3: T_cab, T_evap, T_ain


def test_resid_of_the_true_model_is_white_and_independent(process_noise_dataset):
    r = resid(process_noise_dataset, paper(), max_lag=20)
    assert r.band99 == pytest.approx(2.5758 / np.sqrt(r.n), rel=1e-4)
    assert np.allclose(r.autocorrelation[0], 1.0)
    outside = np.sum(np.abs(r.autocorrelation[1:]) > r.band99)
    assert outside <= 1, r.autocorrelation
    # the slow APRBS input makes neighbouring lags' estimates correlated: a single chance
    # excursion spans several lags, so bound the size, not the count, of exceedances
    assert np.max(np.abs(r.cross_correlation)) < 1.5 * r.band99
    assert np.mean(np.abs(r.cross_correlation) > r.band99) < 0.1
    assert all(v["p_value"] > 0.01 for v in r.ljung_box.values()), r.ljung_box
    df = r.to_frame()
    assert df.shape == (41, 3 + 6) and df.attrs["band99"] == r.band99
    assert isinstance(r.plot(), matplotlib.figure.Figure)


def test_resid_of_a_wrong_model_fails_whiteness(process_noise_dataset):
    wrong = paper().replace(gamma=(0.2, 0.0867, 1.2999, 1.0047, -0.5176, 0.4553, 34.9579))
    r = resid(process_noise_dataset, wrong, max_lag=20)
    assert not r.white["T_cab"] and r.ljung_box["T_cab"]["p_value"] < 1e-6
    assert not r.independent["W_bl"]["T_cab"]
    assert np.max(np.abs(r.cross_correlation[:, 0, 0])) > 2 * r.band99


def test_fit_result_is_accepted_wherever_parameters_are(model_dataset):
    from acid.control.nmpc import NMPC
    from acid.ident.fit import fit
    from acid.ident.validate import validate
    from acid.models.params import fitted

    est, val = model_dataset.split(0.5)
    result = fit(est)
    a = validate(model_dataset, result, starts=5, horizon=50, held_out_fraction=0.5)
    b = validate(model_dataset, fitted(result), starts=5, horizon=50, held_out_fraction=0.5)
    np.testing.assert_array_equal(a.predicted, b.predicted)
    assert predict(val, result).model == "paper (fit-ls)"
    assert NMPC(result).params == fitted(result)
    assert make_plant("model", params=result).params == fitted(result)
    with pytest.raises(DataError, match="expected model parameters"):
        validate(model_dataset, 3.5)


def test_frames_are_degc_and_labelled(model_dataset):
    pr = predict(model_dataset.window(0, 50), paper(), 3)
    df = pr.to_frame()
    assert isinstance(df, pd.DataFrame)
    assert df.attrs["units"] == {"T_cab": "degC", "T_evap": "degC", "T_ain": "degC", "P_bl": "W"}
    assert list(df.columns) == ["T_cab", "T_cab_pred", "T_evap", "T_evap_pred", "T_ain",
                                "T_ain_pred", "P_bl", "P_bl_pred"]
    np.testing.assert_allclose(df["T_cab"], model_dataset["T_cab"][:50])
    with pytest.raises(ConfigError, match="horizon k"):
        predict(model_dataset, paper(), 0)


def test_resid_interpretation_tells_noise_from_missed_dynamics(process_noise_dataset,
                                                               model_dataset,
                                                               noisy_model_dataset):
    true = resid(process_noise_dataset, paper(), max_lag=20)
    for c in true.channels:
        if true.white[c]:
            assert true.interpretation[c].startswith("white at one step")
    wrong = paper().replace(gamma=(0.2, 0.0867, 1.2999, 1.0047, -0.5176, 0.4553, 34.9579))
    bad = resid(process_noise_dataset, wrong, max_lag=20).interpretation["T_cab"]
    assert bad.startswith("not white") and "add up in one direction" in bad
    assert "misses part of W_bl's effect" in bad
    # measurement noise on the state each one-step prediction starts from: lag 1, negative
    noisy = resid(noisy_model_dataset, paper(), max_lag=20)
    assert not noisy.white["T_cab"] and noisy.autocorrelation[1, 0] < -0.2
    assert "noise on the measured state" in noisy.interpretation["T_cab"]
    exact = resid(model_dataset, paper(), max_lag=20)
    assert exact.interpretation["T_cab"].startswith("no test: the one-step residuals are zero")
    assert set(noisy.to_json_dict()["interpretation"]) == set(noisy.channels)
