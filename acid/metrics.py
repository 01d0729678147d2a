"""Prediction-quality metrics, named by what they compute.

All take arrays of equal shape (truth ``y``, prediction ``y_hat``) and reduce over ``axis``.
"""

from __future__ import annotations

import numpy as np


def fit_percent(y, y_hat, axis=None):
    """MATLAB ``compare`` fit: 100 (1 - ||y - y_hat|| / ||y - mean(y)||), in (-inf, 100] %.

    100 % is a perfect fit; 0 % is no better than the mean of the data.
    """
    y, y_hat = np.asarray(y, float), np.asarray(y_hat, float)
    num = np.sqrt(np.sum((y - y_hat) ** 2, axis=axis))
    den = np.sqrt(np.sum((y - np.mean(y, axis=axis, keepdims=True)) ** 2, axis=axis))
    with np.errstate(divide="ignore", invalid="ignore"):
        return 100.0 * (1.0 - num / den)


def rmse(y, y_hat, axis=None):
    """Root-mean-square error, same unit as ``y``, in [0, inf)."""
    e = np.asarray(y, float) - np.asarray(y_hat, float)
    return np.sqrt(np.mean(e * e, axis=axis))


def max_abs_error(y, y_hat, axis=None):
    """Largest absolute error, same unit as ``y``, in [0, inf)."""
    return np.max(np.abs(np.asarray(y, float) - np.asarray(y_hat, float)), axis=axis)


def percentile_abs_error(y, y_hat, q: float, axis=None):
    """The q-th percentile (0-100) of the absolute error, same unit as ``y``."""
    return np.percentile(np.abs(np.asarray(y, float) - np.asarray(y_hat, float)), q, axis=axis)
