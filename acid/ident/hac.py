"""Newey-West (HAC) covariance of least-squares scores, shared by the fits of both model
families (:mod:`acid.ident`: the least-squares, staged and output-error fits).

Scores ``h`` (n, p) are time-ordered rows labelled by experiment ``g`` (n,); lag products
never cross an experiment (a dataset's segments are independent records).
"""

from __future__ import annotations

import numpy as np


def segment_ids(sample_idx: np.ndarray, segments) -> np.ndarray:
    """Experiment number of each sample index (``segments`` as ``Dataset.segments()``)."""
    starts = np.array([a for a, _ in segments])
    return np.searchsorted(starts, sample_idx, side="right") - 1


def _lag_products(h: np.ndarray, g: np.ndarray, lag: int) -> np.ndarray:
    """sum_t h_t h_{t-lag}^T over the pairs in one experiment (rows ordered in time)."""
    same = (g[lag:] == g[:-lag]).astype(float)
    return (h[lag:] * same[:, None]).T @ h[:-lag]


def nw_bandwidth(h: np.ndarray, g: np.ndarray) -> int:
    """Automatic Bartlett truncation lag of Newey & West (1994).

    ``h`` (n, p) are time-ordered scores with the experiment labels ``g`` (lag products
    never cross an experiment). The scores are standardised column by column and summed
    (NW94's weight vector, equal weights); from the autocovariances ``sigma_j`` of that sum
    up to the preliminary lag ``m = floor(4 (n/100)^(2/9))``,
    ``s0 = sigma_0 + 2 sum sigma_j``, ``s1 = 2 sum j sigma_j``, and the lag is
    ``floor(1.1447 (s1/s0)^(2/3) n^(1/3))``, capped below the longest experiment.
    """
    n = h.shape[0]
    sd = h.std(axis=0)
    keep = sd > 0
    if not keep.any():
        return 0
    u = (h[:, keep] / sd[keep]).sum(axis=1, keepdims=True)
    longest = int(np.max(np.bincount(g - g.min()))) if n else 0
    m = min(int(4 * (n / 100.0) ** (2.0 / 9.0)), max(longest - 1, 0))
    sig = [float(u[:, 0] @ u[:, 0]) / n]
    sig += [float(_lag_products(u, g, j)[0, 0]) / n for j in range(1, m + 1)]
    sig = np.array(sig)
    j = np.arange(m + 1)
    s0 = sig[0] + 2.0 * sig[1:].sum()
    s1 = 2.0 * (j[1:] * sig[1:]).sum()
    if s0 <= 0:
        return m
    lag = int(1.1447 * (abs(s1) / s0) ** (2.0 / 3.0) * n ** (1.0 / 3.0))
    return int(min(lag, max(longest - 1, 0)))


def hac_meat(h: np.ndarray, g: np.ndarray, bandwidth: int) -> np.ndarray:
    """Newey-West (1987) long-run covariance of the score sum, Bartlett weights.

    ``S = G_0 + sum_{l=1..L} (1 - l/(L+1)) (G_l + G_l^T)`` with ``G_l`` the sum of
    ``h_t h_{t-l}^T`` over pairs inside one experiment (``g`` labels; rows in time order).
    Positive semi-definite by construction; ``L = 0`` is White's (1980) HC0 meat.
    """
    S = h.T @ h
    for lag in range(1, min(int(bandwidth), h.shape[0] - 1) + 1):
        G = _lag_products(h, g, lag)
        S += (1.0 - lag / (bandwidth + 1.0)) * (G + G.T)
    return S


def resolve_bandwidth(spec, h: np.ndarray, g: np.ndarray) -> int:
    """The truncation lag: ``"auto"`` (Newey-West 1994), ``"nw"`` (floor(4 (n/100)^(2/9)))
    or a non-negative integer."""
    if spec == "auto":
        return nw_bandwidth(h, g)
    if spec == "nw":
        return int(4 * (h.shape[0] / 100.0) ** (2.0 / 9.0))
    return int(spec)


def warnings_as_note(fit):
    """``fit`` (returning a result with ``notes``) with numpy's floating-point warnings
    raised in this module (scores so large that their products overflow) turned into one
    note of the result instead of lines on the terminal; other warnings pass through."""
    import dataclasses
    import functools
    import warnings

    @functools.wraps(fit)
    def wrapped(*args, **kwargs):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = fit(*args, **kwargs)
        ours = [w for w in caught if issubclass(w.category, RuntimeWarning)
                and w.filename == __file__]
        for w in caught:
            if w not in ours:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        if not ours:
            return result
        what = sorted({str(w.message) for w in ours})
        return dataclasses.replace(result, notes=(*result.notes, (
            "standard errors: the Newey-West covariance of the scores met "
            f"{'; '.join(what)} (scores too large for float64): the standard errors and "
            "intervals may be inf or NaN; declare the parameters in units that keep them "
            "near 1")))

    return wrapped
