"""``predict``, ``compare`` and ``resid`` for any declared model (``acid.models``), through
the result objects of :mod:`acid.analysis` (``PredictionResult``, ``CompareResult``,
``ResidualResult``), so their tables and plots serve every model.

k-step prediction: sample n is predicted from the state at n - k and the measured inputs and
disturbances in between. Measured states are taken as measured; latent states come from a
forced run of the model along each experiment (the measured states reset to their
measurements at every sample, the latent ones propagated by the model's equations), started
from their declared ``initial`` rule or, with ``warmup`` W > 0, from the state fitted to the
first W samples (``acid.ident.validate``'s warm start). ``k=None`` simulates each experiment
from its first predicted sample. Channels: every state and output the dataset measures, in
their declared units. ``acid.analysis.predict/compare/resid`` route here when given a
``DeclaredFitResult``, ``ParameterValues`` or a declared parameter file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from acid.analysis import (
    CompareResult,
    PredictionResult,
    ResidualResult,
    compare_predictions,
    residual_tests,
)
from acid.data import Dataset
from acid.errors import ConfigError
from acid.ident.data import ModelData
from acid.ident.fit import DeclaredFitResult
from acid.ident.oe import simulate_windows
from acid.ident.validate import (
    _parameters_at,
    _warm_start,
    declared_parameters,
    fitted_parameters,
    read_parameters,
)
from acid.models.declaration import Model
from acid.models.loader import load
from acid.models.values import ParameterValues

__all__ = ["compare_models", "predict_model", "resid_model", "resolve"]


def resolve(params, model: Model | str | None = None) -> tuple[Model, ParameterValues, str]:
    """(model, values, label) of ``params``: ``ParameterValues`` of any declaration
    (``ModelParams``, ``EconParams``...), a ``DeclaredFitResult``, a parameter file or
    ``(model, values)``; ``model`` (a ``Model``, built-in name or file) overrides the one the
    parameters name. ``params=None``: the model's declared values, or the paper's preset
    without a model (as ``"paper"``)."""
    from acid.params import paper

    if isinstance(params, tuple):
        model, params = params
    if (params is None and model is None) or (isinstance(params, str) and params == "paper"):
        params = paper()
    if isinstance(getattr(params, "params", None), ParameterValues):
        params = params.params   # a stage's fit (EconFit)
    if isinstance(params, DeclaredFitResult):
        pv = fitted_parameters(params)
        m = pv.declaration if model is None else load(model)
        return m, pv, f"{m.name} (fit-{params.method})"
    if isinstance(params, (str, Path)):
        pv = read_parameters(None if model is None else load(model), params)
        return pv.declaration, pv, f"{pv.declaration.name} ({Path(params).name})"
    if params is None:
        params = declared_parameters(load(model))
    if not isinstance(params, ParameterValues):
        raise ConfigError(f"expected a fit result, a parameter file or ParameterValues, got "
                          f"{type(params).__name__}")
    m = params.declaration if model is None else load(model)
    return m, params, params.name if params.source is None else f"{m.name} ({params.source})"


def _state_track(model: Model, data: ModelData, P: np.ndarray, first: np.ndarray,
                 warmup: int) -> np.ndarray:
    """(N, nx) the state at every sample: measured states as measured; latent ones from a
    forced run of each experiment from its sample ``first[e]`` (NaN before it)."""
    X = data.x.copy()
    latent = [i for i, s in enumerate(model.states) if not s.measured]
    if not latent:
        return X
    X[:, latent] = np.nan
    for (_a, b), s in zip(data.segments, first, strict=True):
        if s >= b:
            continue
        x0 = data.initial_states(model, np.array([s]))
        if warmup > 0:
            x0 = _warm_start(model, data, P[[s]], np.array([s]), warmup, x0, latent)
        x = x0[0]
        for n in range(s, b):
            X[n, latent] = x[latent]
            if n + 1 == b:
                break
            x = np.where(np.isfinite(data.x[n]), data.x[n], x)
            x, _ = model.step(x, data.u[n], data.d[n], P[n])
            x = np.asarray(x, dtype=float).ravel()
    return X


def predict_model(ds: Dataset, params=None, k: int | None = 1, *, model=None,
                  warmup: int = 0) -> PredictionResult:
    """k-step-ahead predictions of every measured channel of a declared model along ``ds``
    (module docstring). ``params`` as :func:`resolve`; ``k`` >= 1 or None (simulation);
    ``warmup`` samples at the start of each experiment that fit the latent states (none are
    predicted there). Returns a ``PredictionResult`` in the declared units."""
    if k is not None and (isinstance(k, bool) or int(k) != k or int(k) < 1):
        raise ConfigError(f"predict: horizon k must be a whole number of samples >= 1 or None, "
                          f"got {k!r}")
    if isinstance(warmup, bool) or int(warmup) < 0:
        raise ConfigError(f"predict: warmup must be a whole number of samples >= 0, got "
                          f"{warmup!r}")
    m, ps, label = resolve(params, model)
    data = ModelData.of(m, ds, min_samples=2)
    latent = any(not s.measured for s in m.states)
    W = int(warmup) if latent else 0
    n = len(data)
    notes: list[str] = []
    P = _parameters_at(m, data, ps, np.arange(n), notes)
    first = np.array([a + W for a, _ in data.segments])
    X = _state_track(m, data, P, first, W)
    chans = data.measured_channels(m)
    cols = [c for c, _ in chans]
    meas = np.concatenate([data.x, data.y], axis=1)[:, cols]
    pred = np.full(meas.shape, np.nan)
    for (_a, b), s in zip(data.segments, first, strict=True):
        steps = (b - s - 1) if k is None else int(k)
        if steps < 1 or b - s <= steps:
            continue
        starts = np.array([s]) if k is None else np.arange(s, b - steps)
        idx = starts[:, None] + np.arange(steps + 1)[None, :]
        Y = simulate_windows(m, data, idx, X[starts], P[starts])[..., cols]
        if k is None:
            pred[s:b] = Y[0]
        else:
            pred[starts + steps] = Y[:, -1]
    unit_of = {r.name: r.unit for r in m.states + m.outputs}
    names = tuple(nm for _, nm in chans)
    return PredictionResult(time=np.asarray(ds.time, dtype=float).copy(), measured=meas,
                            predicted=pred, horizon=None if k is None else int(k), Ts=m.Ts,
                            model=label, source=ds.source, channels=names,
                            units=tuple(unit_of[c] for c in names))


def compare_models(ds: Dataset, *params, k: int | None = None, labels=None, model=None,
                   warmup: int = 0) -> CompareResult:
    """Fit % per channel of one or more declared parameter sets on ``ds`` (MATLAB
    ``compare``; ``k`` None: simulation)."""
    return compare_predictions(
        params, lambda p: predict_model(ds, p, k, model=model, warmup=warmup), k, labels)

def resid_model(ds: Dataset, params=None, max_lag: int = 25, k: int = 1, *, model=None,
                warmup: int = 0) -> ResidualResult:
    """Residual tests of a declared model on ``ds`` (MATLAB ``resid``): autocorrelation of
    every channel's k-step errors and their cross-correlation with every declared input."""
    if int(max_lag) < 1:
        raise ConfigError(f"resid: max_lag must be >= 1, got {max_lag}")
    pr = predict_model(ds, params, k, model=model, warmup=warmup)
    m, _, _ = resolve(params, model)
    data = ModelData.of(m, ds, min_samples=2)
    return residual_tests(pr, data.u, tuple(r.name for r in m.inputs), ds.experiment,
                          int(max_lag), {"max_lag": int(max_lag), "k": k, "warmup": warmup},
                          ds.source)
