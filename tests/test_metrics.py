"""Prediction-quality metrics (acid/metrics.py): values, formulas, ranges, axes."""

from __future__ import annotations

import numpy as np
import pytest

from acid.metrics import fit_percent, max_abs_error, percentile_abs_error, rmse


@pytest.fixture
def signal(rng):
    return 20.0 + np.cumsum(rng.standard_normal(200))


def test_fit_percent_is_100_for_a_perfect_prediction(signal):
    assert fit_percent(signal, signal) == pytest.approx(100.0)


def test_fit_percent_is_0_for_the_mean(signal):
    assert fit_percent(signal, np.full_like(signal, signal.mean())) == pytest.approx(0.0)


def test_fit_percent_formula_and_negative_range(signal, rng):
    y_hat = signal + rng.normal(0.0, 2.0, signal.size)
    expected = 100.0 * (1.0 - np.linalg.norm(signal - y_hat)
                        / np.linalg.norm(signal - signal.mean()))
    assert fit_percent(signal, y_hat) == pytest.approx(expected)
    assert fit_percent(signal, signal + 100.0) < 0.0  # worse than the mean: negative


def test_fit_percent_reduces_along_an_axis(signal):
    y = np.stack([signal, 2.0 * signal])
    f = fit_percent(y, y + np.array([[0.0], [1.0]]), axis=1)
    assert f.shape == (2,) and f[0] == pytest.approx(100.0) and f[1] < 100.0


def test_rmse_values():
    assert rmse([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]) == 0.0
    assert rmse([0.0, 0.0], [3.0, -4.0]) == pytest.approx(np.sqrt(12.5))
    np.testing.assert_allclose(rmse([[0.0, 0.0], [1.0, 1.0]], [[1.0, 1.0], [1.0, 3.0]], axis=1),
                               [1.0, np.sqrt(2.0)])


def test_max_abs_error_and_percentile():
    y, y_hat = np.zeros(5), np.array([-3.0, 1.0, 0.5, 2.0, 0.0])
    assert max_abs_error(y, y_hat) == 3.0
    assert percentile_abs_error(y, y_hat, 50) == 1.0
    assert percentile_abs_error(y, y_hat, 100) == max_abs_error(y, y_hat)
    np.testing.assert_allclose(max_abs_error(np.zeros((2, 3)), [[1, -2, 0], [0, 0, 5]], axis=1),
                               [2.0, 5.0])
