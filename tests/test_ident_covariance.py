"""White vs Newey-West (HAC) standard errors of ``acid.ident.fit_model`` (``covariance=...``)
on the paper's declaration; the HC0 sandwich checked against one computed here."""

from __future__ import annotations

import json

import numpy as np
import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid import hac
from acid.data import Dataset
from acid.errors import ConfigError
from acid.excite import ExcitationSpec, excite
from acid.ident.fit import DEFAULT_COVARIANCE, fit_model
from acid.models.params import PARAMETER_TABLE, paper
from acid.plant import make_plant
from acid_cli.main import app

TRUE = paper().theta
PARAM_NAMES = tuple(row[0] for row in PARAMETER_TABLE)
EQ3 = [PARAM_NAMES.index(n) for n in ("gamma6", "gamma7", "tau3")]


def fit(ds, method="ls", **opts):
    return fit_model("paper", ds, method, **opts)


def _se(res) -> np.ndarray:
    """Standard errors in ``PARAMETER_TABLE`` order."""
    rows = {e.name: e.stderr for e in res.estimates if e.experiment is None}
    return np.array([rows[n] for n in PARAM_NAMES])


def _ci(res) -> np.ndarray:
    rows = {e.name: e.ci95 for e in res.estimates if e.experiment is None}
    return np.array([rows[n] for n in PARAM_NAMES])


def _block(res, names) -> np.ndarray:
    """The covariance of ``names`` from the result's matrix over its free columns."""
    i = [res.covariance_names.index(n) for n in names]
    return res.covariance[np.ix_(i, i)]


def _data(seed: int, duration: float = 3600.0, meas: float = 0.0, proc: float = 0.0):
    spec = ExcitationSpec(seed=seed, duration=duration, noise=meas)
    plant = make_plant("model", meas_noise_std=meas, process_noise_std=proc,
                       rng=spec.rng("noise"))
    return excite(plant, spec)


# ------------------------------------------------------------------ the estimator itself
def test_hac_meat_is_the_bartlett_sum_within_experiments_only(rng):
    h = rng.standard_normal((60, 3))
    g = np.repeat([0, 1, 2], [25, 5, 30])
    L = 4
    S = np.zeros((3, 3))
    for t in range(60):
        for s in range(60):
            if g[t] == g[s] and abs(t - s) <= L:
                S += (1 - abs(t - s) / (L + 1)) * np.outer(h[t], h[s])
    assert np.allclose(hac.hac_meat(h, g, L), S)
    assert np.allclose(hac.hac_meat(h, g, 0), h.T @ h)  # bandwidth 0: White's HC0
    assert np.linalg.eigvalsh(hac.hac_meat(h, g, 20)).min() > -1e-12  # PSD


def test_automatic_bandwidth_grows_with_autocorrelation(rng):
    n = 2000
    g = np.zeros(n, dtype=int)
    white = rng.standard_normal((n, 2))
    ar = np.zeros((n, 2))
    for t in range(1, n):
        ar[t] = 0.9 * ar[t - 1] + white[t]
    b_white = hac.nw_bandwidth(white, g)
    b_ar = hac.nw_bandwidth(ar, g)
    # the NW94 rule is noisy on white scores (~n^(1/3)) but clearly larger under AR(0.9)
    assert b_white <= 15 and b_ar > 20 and b_ar > 2 * b_white, (b_white, b_ar)
    assert hac.resolve_bandwidth("nw", white, g) == int(4 * (n / 100) ** (2 / 9))


def test_bandwidth_zero_is_the_hc0_sandwich_exactly():
    ds = _data(seed=1, proc=0.05)
    res = fit(ds, method="ls", covariance="hac", hac_bandwidth=0)
    X = np.column_stack([ds.get("T_evap", "K"), ds.get("W_bl", "kg/s"), np.ones(len(ds))])
    e = ds.get("T_ain", "K") - X @ res.values[EQ3]
    bread = np.linalg.inv(X.T @ X)
    n, p = X.shape
    hc0 = n / (n - p) * bread @ ((X * e[:, None]).T @ (X * e[:, None])) @ bread
    assert np.allclose(_block(res, ("gamma6", "gamma7", "tau3")), hc0, rtol=1e-6)
    assert res.hac_bandwidth["T_ain"] == 0


def test_hac_matches_white_when_the_residuals_are_white():
    """Process noise on the model plant: eqs. 1-2 residuals are white, both agree."""
    ds = _data(seed=2, duration=7200.0, proc=0.05)
    w = fit(ds, method="ls", covariance="white")
    h = fit(ds, method="ls", covariance="hac")
    idx = [PARAM_NAMES.index(n) for n in ("gamma1", "gamma2", "gamma3", "gamma4", "gamma5")]
    ratio = _se(h)[idx] / _se(w)[idx]
    assert np.all((ratio > 0.75) & (ratio < 1.33)), ratio
    assert np.array_equal(h.values, w.values)


def test_hac_widens_the_intervals_of_an_equation_with_ar1_residuals(rng):
    """AR(1) (rho 0.95) errors on T_ain: eq. 3's white standard errors are too small."""
    ds = _data(seed=3, duration=7200.0)
    e = np.zeros(len(ds))
    z = 0.05 * rng.standard_normal(len(ds))
    for t in range(1, len(ds)):
        e[t] = 0.95 * e[t - 1] + z[t]
    ds.channels["T_ain"] = ds.channels["T_ain"] + e
    w = fit(ds, method="ls", covariance="white")
    h = fit(ds, method="ls", covariance="hac")
    assert np.all(_se(h)[EQ3] > 2.0 * _se(w)[EQ3]), _se(h)[EQ3] / _se(w)[EQ3]
    assert h.hac_bandwidth["T_ain"] > 10


@pytest.mark.parametrize(("method", "noise", "covariance"), [
    ("oe", {"meas": 0.05}, None), ("oe", {"meas": 0.05}, "white"),
    ("ls", {"proc": 0.05}, None), ("ls", {"proc": 0.05}, "white"), ("ls", {"proc": 0.05}, "hac")])
def test_intervals_cover_the_truth_on_model_data(method, noise, covariance):
    """White-noise model-plant data: both kinds (and the default, HAC) are near 95 %."""
    covered = []
    idx = list(range(10)) if method == "oe" else [0, 1, 2, 3, 4, 7, 8]
    opts = {} if covariance is None else {"covariance": covariance}
    for seed in range(10, 18 if method == "oe" else 20):
        res = fit(_data(seed=seed, **noise), method=method, **opts)
        assert res.covariance_kind == (covariance or DEFAULT_COVARIANCE)
        lo, hi = _ci(res)[idx].T
        covered.append((lo <= TRUE[idx]) & (TRUE[idx] <= hi))
    assert np.mean(covered) >= 0.85, np.mean(covered, axis=0)


def test_output_error_hac_reports_its_lag_and_is_json_safe(noisy_model_dataset):
    res = fit(noisy_model_dataset, method="oe", covariance="hac")
    assert res.covariance_kind == "hac" and res.hac_bandwidth["oe"] >= 0
    assert np.all(np.isfinite(_se(res)[:10])) and np.all(_se(res)[:10] > 0)
    d = res.to_json_dict()
    json.dumps(d, allow_nan=False)
    assert d["covariance_kind"] == "hac" and set(d["hac_bandwidth"]) >= {"T_cab", "oe"}


def test_two_experiments_hac_never_crosses_the_boundary():
    a, b = _data(seed=4, duration=1800.0, proc=0.05), _data(seed=5, duration=1800.0, proc=0.05)
    res = fit(Dataset.concatenate([a, b]), method="ls", covariance="hac", hac_bandwidth=5)
    assert np.all(np.isfinite(_se(res))) and res.hac_bandwidth["T_cab"] == 5


def test_invalid_covariance_options_are_refused(model_dataset):
    with pytest.raises(ConfigError, match="covariance"):
        fit(model_dataset, covariance="robust")
    for bad in (-1, "big", 2.5, True):
        with pytest.raises(ConfigError, match="hac_bandwidth"):
            fit(model_dataset, covariance="hac", hac_bandwidth=bad)


# --------------------------------------------------------------------------------- CLI
runner = CliRunner()


def test_cli_covariance_option(model_dataset, tmp_path):
    data = model_dataset.to_hdf5(tmp_path / "m.h5")
    out = tmp_path / "p.json"
    res = runner.invoke(app, ["fit", str(data), "--out", str(out), "--covariance", "hac",
                              "--hac-bandwidth", "3"])
    assert res.exit_code == 0, res.output
    d = json.loads(out.read_text())["fit"]
    assert d["covariance_kind"] == "hac" and d["hac_bandwidth"]["T_cab"] == 3
    assert "covariance hac" in " ".join(res.output.split())
    bad = runner.invoke(app, ["fit", str(data), "--out", str(out), "--covariance", "robust"])
    assert_one_line_error(bad, "--covariance", "robust")
    bad = runner.invoke(app, ["fit", str(data), "--out", str(out), "--hac-bandwidth", "x"])
    assert_one_line_error(bad, "--hac-bandwidth")
