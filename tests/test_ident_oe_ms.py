"""acid.ident.ms.shooting: output error as one sparse multiple-shooting NLP (IPOPT) reaches the
dense output error's optimum, and its size grows linearly with the data."""

from __future__ import annotations

import numpy as np
import pytest

from acid.data import Dataset
from acid.errors import ConfigError
from acid.ident import linear, oe
from acid.ident.data import ModelData
from acid.ident.fit import _window_base, fit_model
from acid.ident.ms import shooting as oe_ms
from acid.models import load

TRUTH = np.array([8.0, 80.0, 120.0, 70.0, 15.0, 0.5, 0.15, 0.8, 0.0])


def _cabin3(n: int, seed: int = 0, noise: float = 0.05) -> Dataset:
    """Two experiments of the cabin3 declaration (one Q_sol each), measured with noise."""
    rng = np.random.default_rng(seed)
    m = load("cabin3")
    parts = []
    for q in (300.0, 900.0):
        W = np.repeat(rng.uniform(0.04, 0.16, n // 20 + 1), 20)[:n]
        Ts = np.repeat(rng.uniform(275.0, 284.0, n // 20 + 1), 20)[:n]
        Ta = 305.0 + 3.0 * np.sin(np.arange(n) / 60.0)
        p = TRUTH.copy()
        p[m.parameter_names.index("Q_sol")] = q
        X, Y = m.simulate(np.array([308.0, 312.0, 281.0]), np.c_[W, Ts], Ta[:, None], p)
        e = noise * rng.standard_normal((3, n))
        ch = {"T_cab": X[:-1, 0] - 273.15 + e[0], "T_evap": X[:-1, 2] - 273.15 + e[1],
              "T_ain": Y[:, 0] - 273.15 + e[2], "W_bl": W, "T_evap_set": Ts - 273.15,
              "T_amb": Ta - 273.15}
        parts.append(Dataset(np.arange(n) * 5.0, ch, {k: "kg/s" if k == "W_bl" else "degC"
                                                    for k in ch}, 5.0))
    return Dataset.concatenate(parts)


def test_multiple_shooting_reaches_the_dense_output_errors_optimum():
    ds = _cabin3(120)
    m = load("cabin3")
    dense = fit_model(m, ds, method="oe", oe_window=60)
    ms = fit_model(m, ds, method="oe", oe_window=60, oe_solver="ms")
    assert ms.output_error["converged"], ms.output_error["status"]
    assert "IPOPT" in ms.output_error["status"]
    assert ms.output_error["loss"] == pytest.approx(dense.output_error["loss"], rel=1e-6)
    for a, b in zip(dense.estimates, ms.estimates, strict=True):
        assert b.value == pytest.approx(a.value, rel=1e-6, abs=1e-9), a.name
        if np.isfinite(a.stderr):     # the same covariance (summarise) at the same optimum
            assert b.stderr == pytest.approx(a.stderr, rel=1e-4), a.name


def test_the_nlp_grows_linearly_with_the_data():
    m = load("cabin3")
    sizes = []
    for n in (100, 400):
        data = ModelData.of(m, _cabin3(n))
        cols = tuple(linear.Column(i, m.parameter_names[i])
                     for i, p in enumerate(m.parameters) if not p.fixed)
        w = oe.Windows.of(data.segments, 50)
        prob = oe.OEProblem(m, data, cols, _window_base(
            data.parameter_matrix(m, m.values), cols, w), 50)
        sizes.append(oe_ms.nlp_size(prob))
    for key in ("variables", "constraints", "jacobian_nnz", "hessian_nnz"):
        # 4 times the samples: 4 times the size (the parameters' own entries aside)
        assert sizes[1][key] <= 4.05 * sizes[0][key], (key, sizes)
    # the dense formulation's Jacobian has (samples x channels) x (parameters + 3 x0 per
    # window) entries: its parameter block alone is 4 x, its x0 block 16 x
    assert sizes[1]["jacobian_nnz"] >= 3.9 * sizes[0]["jacobian_nnz"]


def test_multiple_shooting_refuses_the_huber_loss():
    with pytest.raises(ConfigError, match="squared loss only"):
        fit_model("cabin3", _cabin3(60), method="oe", oe_solver="ms", loss="huber")
