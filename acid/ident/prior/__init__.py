"""Declared priors in least squares: the prior as weighted rows beside the data's, the
prior weight (how much every prior counts against the data), and the fit's note on how far
each estimate moved from its prior."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np

from acid.errors import ConfigError
from acid.models.declaration import Model


def check_weight(weight) -> float:
    """The prior weight as a float: finite and >= 0, else one ``ConfigError``."""
    try:
        w = float(weight)
    except (TypeError, ValueError):
        w = float("nan")
    if not (np.isfinite(w) and w >= 0.0) or isinstance(weight, bool):
        raise ConfigError(f"prior weight must be a finite number >= 0, got {weight!r}")
    return w


def weighted(model: Model, weight: float) -> Model:
    """``model`` with every declared prior's information (1/sd^2) scaled by ``weight``:
    the standard deviation divided by sqrt(weight); 0 drops every prior (the unregularised
    fit), 1 keeps the declared priors. A weight below 1 says the data count for more than
    their prior does at face value (e.g. correlated errors counted as independent samples
    make the data rows too heavy; a weight above 1 compensates for that)."""
    w = check_weight(weight)
    if w == 1.0 or all(p.prior is None for p in model.parameters):
        return model
    if w == 0.0:
        return _without_priors(model)
    return model.with_priors({p.name: (p.prior[0], p.prior[1] / np.sqrt(w))
                              for p in model.parameters if p.prior is not None})


def _without_priors(model: Model) -> Model:
    other = copy.copy(model)
    other.parameters = tuple(dataclasses.replace(p, prior=None) for p in model.parameters)
    return other


def prior_rows(Z: np.ndarray, y: np.ndarray, scale: np.ndarray, rank: int,
               prior: tuple[np.ndarray, np.ndarray] | None):
    """``Z`` (n, k) the column-scaled regressors (theta = phi / ``scale``), ``y`` (n,):
    the regression with a row sigma (theta_j - mean_j) / sd_j under it for each column with
    a prior (sd finite), sigma the residual standard deviation of the fit without priors
    (the equation errors' noise scale): least squares on it is the maximum a posteriori
    estimate. Returns (Z, y, prior rows (m, k), sigma); unchanged, (0, k) and 0 without."""
    n, k = Z.shape
    if prior is None or not np.any(np.isfinite(prior[1])):
        return Z, y, np.zeros((0, k)), 0.0
    mean, sd = (np.asarray(a, dtype=float) for a in prior)
    r_free = y - Z @ np.linalg.lstsq(Z, y, rcond=None)[0]
    sig = max(float(np.sqrt(r_free @ r_free / max(n - rank, 1))),
              1e-12 * (1.0 + float(np.abs(y).max())))
    has = np.flatnonzero(np.isfinite(sd))
    Rp = np.zeros((has.size, k))
    Rp[np.arange(has.size), has] = sig / (sd[has] * scale[has])
    return np.vstack([Z, Rp]), np.concatenate([y, sig * mean[has] / sd[has]]), Rp, sig


def prior_arrays(model: Model, columns) -> tuple[np.ndarray, np.ndarray] | None:
    """The declared priors of ``columns`` as (mean, sd) arrays (sd inf: no prior; a
    per-experiment parameter's prior on each experiment's column); None without any."""
    prs = [model.parameters[c.index].prior for c in columns]
    if all(p is None for p in prs):
        return None
    return (np.array([p[0] if p else 0.0 for p in prs]),
            np.array([p[1] if p else np.inf for p in prs]))


def prior_note(model: Model, columns, theta) -> str:
    """One note line for the fitted ``columns`` that carry a declared prior: each estimate
    beside its prior and how far it moved, in the prior's standard deviations ("" without
    priors)."""
    parts = []
    for c, t in zip(columns, theta, strict=True):
        pr = model.parameters[c.index].prior
        if pr is not None:
            parts.append(f"{c.label} {t:.4g} (prior {pr[0]:g} +- {pr[1]:g} "
                         f"{model.parameters[c.index].unit}, {(t - pr[0]) / pr[1]:+.1f} sd)")
    return ("maximum a posteriori with declared priors: " + "; ".join(parts)) if parts else ""
