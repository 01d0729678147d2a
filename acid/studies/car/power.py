"""The A/C power on trips the fit has not seen: leave-trips-out over a car's logs.

Each fold fits the power rows of ``car_ac`` (:func:`acid.studies.car_study.fit_power`, the
declaration's own output through CasADi) on every trip but the held-out ones and predicts
those. Scores per held-out trip and pooled over all of them:

* R^2 per 5 s sample: ``1 - sum (P - P_hat)^2 / sum (P - mean P)^2`` (pooled: over all
  held-out samples, the mean being the pooled mean);
* the trip energy ratio ``sum P_hat / sum P`` (model / logged).

Intervals are percentile intervals over trips resampled with replacement (seeded
:class:`numpy.random.Generator`, ``n_boot`` draws), so they say how much the pooled number
rests on a few trips.

:func:`regressor_bound` runs the same folds with an unconstrained regressor on the same
logged channels (a full quadratic in ``T_cab, T_evap, T_amb, v_veh`` plus the evaporator
air's change over the last 5 s and 30 s, least squares): what the logged channels carry
about the power on unseen trips without any physical structure. When that bound is far
below R^2 0.5 the logs cannot support it, whatever the model.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from acid.data import Dataset
from acid.errors import DataError
from acid.models.car_ac import model as CAR_AC
from acid.models.declaration import Model
from acid.studies.car_study import car_ac_values, fit_power, power_function

#: W: a trip whose logged power varies less than this (standard deviation), or averages
#: less, is scored in the pooled numbers only (the A/C was off)
FLAT_W = 1.0


@dataclass(frozen=True)
class TripScore:
    """One held-out trip: samples, logged and predicted mean power (W), R^2 per sample,
    energy ratio predicted / logged."""

    trip: str
    n: int
    mean_logged_W: float
    mean_model_W: float
    r2: float
    energy_ratio: float


@dataclass(frozen=True)
class HeldOut:
    """Leave-trips-out scores of one predictor: per trip, pooled, and 90 % intervals of the
    pooled numbers over trips resampled (``*_ci``: (low, high))."""

    predictor: str
    folds: int
    trips: tuple[TripScore, ...]
    r2: float
    r2_ci: tuple[float, float]
    energy_ratio: float
    energy_ratio_ci: tuple[float, float]
    rmse_W: float
    fold_values: tuple[dict, ...] = ()

    def summary(self) -> dict:
        return {"predictor": self.predictor, "folds": self.folds, "r2_5s": self.r2,
                "r2_5s_ci90": list(self.r2_ci), "energy_ratio": self.energy_ratio,
                "energy_ratio_ci90": list(self.energy_ratio_ci), "rmse_W": self.rmse_W,
                "trips": [{k: (None if isinstance(v, float) and v != v else v)
                           for k, v in t.__dict__.items()} for t in self.trips],
                "fold_values": list(self.fold_values)}


def split_trips(ds: Dataset) -> list[Dataset]:
    """One dataset per experiment (trip), named as imported."""
    names = ds.experiment_names()
    out = []
    for (a, b), name in zip(ds.segments(), names, strict=True):
        w = ds.window(a, b)
        w.metadata["experiments"] = [{"name": name}]
        w.experiment = np.zeros(len(w), dtype=int)
        out.append(w)
    return out


def folds_of(n_trips: int, folds: int) -> list[np.ndarray]:
    """Trip indices held out per fold: trip i in fold ``i % folds`` (deterministic)."""
    if not 2 <= folds <= n_trips:
        raise DataError(f"--folds {folds}: needs 2 to {n_trips} (the number of trips)")
    idx = np.arange(n_trips)
    return [idx[idx % folds == f] for f in range(folds)]


def _pooled(P: list[np.ndarray], Ph: list[np.ndarray]) -> tuple[float, float, float]:
    p, ph = np.concatenate(P), np.concatenate(Ph)
    r = p - ph
    return (float(1 - np.sum(r ** 2) / np.sum((p - p.mean()) ** 2)),
            float(ph.sum() / p.sum()), float(np.sqrt(np.mean(r ** 2))))


def _score(name: str, predictor: str, folds: int, names, P, Ph, fold_values=(),
           n_boot: int = 2000, seed: int = 0) -> HeldOut:
    trips = []
    for nm, p, ph in zip(names, P, Ph, strict=True):
        ss = np.sum((p - p.mean()) ** 2)
        # a trip with the A/C off (logged power flat) has no R^2 and no energy ratio
        r2 = 1 - np.sum((p - ph) ** 2) / ss if ss > len(p) * FLAT_W ** 2 else float("nan")
        trips.append(TripScore(nm, len(p), float(p.mean()), float(ph.mean()), float(r2),
                               float(ph.sum() / p.sum()) if p.mean() > FLAT_W
                               else float("nan")))
    r2, er, rmse = _pooled(P, Ph)
    rng = np.random.default_rng(seed)
    boot = []
    for _ in range(n_boot):
        pick = rng.integers(0, len(P), len(P))
        boot.append(_pooled([P[i] for i in pick], [Ph[i] for i in pick])[:2])
    b = np.array(boot)
    lo, hi = np.percentile(b, [5, 95], axis=0)
    return HeldOut(predictor, folds, tuple(trips), r2, (float(lo[0]), float(hi[0])), er,
                   (float(lo[1]), float(hi[1])), rmse, tuple(fold_values))


def leave_trips_out(trips: Sequence[Dataset], cabin_values, folds: int | None = None, *,
                    model: Model = CAR_AC, seed: int = 0,
                    progress: Callable[[int, int], None] | None = None) -> HeldOut:
    """The declared power output, its rows fitted per fold on the other trips (``folds``
    default: one trip held out at a time)."""
    folds = folds or len(trips)
    parts = folds_of(len(trips), folds)
    fn = power_function(model)
    P, Ph, names, fold_values = [], [], [], []
    for f, held in enumerate(parts):
        est = Dataset.concatenate([t for i, t in enumerate(trips) if i not in set(held)])
        with np.errstate(divide="ignore", invalid="ignore"):   # a held-out trip A/C off
            fit = fit_power(est, trips[held[0]], cabin_values, model)
        fold_values.append(fit.values)
        values = car_ac_values(cabin_values, model)
        for k, v in fit.values.items():
            values[model.parameter_names.index(k)] = v
        for i in held:
            t = trips[i]
            X, U, D, p = _logged_power(t, model)
            P.append(p)
            Ph.append(np.asarray(fn.map(len(X))(X.T, U.T, D.T, values)).ravel())
            names.append(t.experiment_names()[0])
        if progress:
            progress(f + 1, folds)
    return _score("car_ac", "car_ac P_comp (declared, fitted per fold)", folds, names, P, Ph,
                  fold_values, seed=seed)


def declared_power(trips: Sequence[Dataset], cabin_values, *, model: Model = CAR_AC,
                   seed: int = 0) -> HeldOut:
    """The declared power output with its declared (literature) rows, not fitted, on every
    trip, scored as ``leave_trips_out``: what the per-fold fit buys over the cited values."""
    fn = power_function(model)
    values = car_ac_values(cabin_values, model)
    P, Ph, names = [], [], []
    for t in trips:
        X, U, D, p = _logged_power(t, model)
        P.append(p)
        Ph.append(np.asarray(fn.map(len(X))(X.T, U.T, D.T, values)).ravel())
        names.append(t.experiment_names()[0])
    return _score("car_ac", "car_ac P_comp (declared values, not fitted)", len(trips), names,
                  P, Ph, seed=seed)


def _logged_power(ds: Dataset, model: Model):
    """(X, U, D, P): the declaration's state (cabin air logged, the rest 0: the power reads
    no latent state), input, disturbances and the logged power, from one trip."""
    ds.require(["T_cab", "T_evap", "T_amb", "v_veh", "P_comp"])
    X = np.zeros((len(ds), model.nx))
    X[:, model.state_names.index("T_cab")] = ds.get("T_cab", "K")
    U = ds.get("T_evap", "K")[:, None]
    D = np.column_stack([ds.get(s.name, s.unit) for s in model.disturbances])
    return X, U, D, ds.get("P_comp", "W")


def _features(ds: Dataset) -> np.ndarray:
    """The regressor's columns: 1, the four logged channels (degC, m/s) and their squares
    and products, and the evaporator air's change over the last 1 and 6 samples."""
    ds.require(["T_cab", "T_evap", "T_amb", "v_veh"])
    c = [ds.get("T_cab", "degC"), ds.get("T_evap", "degC"), ds.get("T_amb", "degC"),
         ds.get("v_veh", "m/s")]
    cols = [np.ones(len(ds)), *c]
    cols += [c[i] * c[j] for i in range(4) for j in range(i, 4)]
    for lag in (1, 6):
        e = c[1]
        d = np.zeros_like(e)
        d[lag:] = e[lag:] - e[:-lag]
        cols.append(d)
    return np.column_stack(cols)


def regressor_bound(trips: Sequence[Dataset], folds: int | None = None, *, ridge: float = 1e-3,
                    seed: int = 0) -> HeldOut:
    """The same folds with the unconstrained quadratic regressor (:func:`_features`, ridge
    ``ridge`` on standardised columns): the bound on what the logged channels carry."""
    folds = folds or len(trips)
    parts = folds_of(len(trips), folds)
    F = [_features(t) for t in trips]
    Y = [t.get("P_comp", "W") for t in trips]
    P, Ph, names = [], [], []
    for held in parts:
        est = [i for i in range(len(trips)) if i not in set(held)]
        A, y = np.vstack([F[i] for i in est]), np.concatenate([Y[i] for i in est])
        s = A.std(axis=0)
        s[0] = 1.0
        s[s == 0] = 1.0
        As = A / s
        beta = np.linalg.solve(As.T @ As + ridge * len(y) * np.eye(A.shape[1]), As.T @ y) / s
        for i in held:
            P.append(Y[i])
            Ph.append(F[i] @ beta)
            names.append(trips[i].experiment_names()[0])
    return _score("bound", "quadratic regressor on the logged channels (no structure)",
                  folds, names, P, Ph, seed=seed)
