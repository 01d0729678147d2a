"""A dataset read for a declared model: the declared signals in the declared units, the
experiment structure, and the parameter vector of each sample (per-experiment values)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acid.data import Dataset
from acid.errors import DataError
from acid.models.declaration import Model


@dataclass(frozen=True)
class ModelData:
    """Arrays (N, n) in the declared order and units; NaN where a channel is absent (latent
    states, outputs the dataset does not record).

    Attributes
    ----------
    x, u, d, y : states, inputs, disturbances, outputs.
    experiment : (N,) index 0..E-1 of each sample's experiment (``experiment_ids`` order).
    experiment_ids : the dataset's experiment ids.
    segments : contiguous (start, stop) runs of one experiment.
    """

    x: np.ndarray
    u: np.ndarray
    d: np.ndarray
    y: np.ndarray
    experiment: np.ndarray
    experiment_ids: tuple[int, ...]
    segments: tuple[tuple[int, int], ...]
    Ts: float
    source: str
    #: (N, nx + ny) True where a measured channel is censored (its ``<name>_censored`` mask
    #: channel, written by ``acid import`` for a clipping sensor): not a measurement to fit
    #: or score, though its value (the sensor's limit) still starts a simulation.
    censored: np.ndarray | None = None

    @classmethod
    def of(cls, model: Model, ds: Dataset, min_samples: int = 8) -> ModelData:
        if len(ds) < min_samples:
            raise DataError(f"{ds.source}: {len(ds)} samples, model {model.name!r} needs at "
                            f"least {min_samples}")
        if abs(ds.Ts - model.Ts) > 1e-9 * model.Ts:
            raise DataError(f"{ds.source}: sample time {ds.Ts:g} s differs from model "
                            f"{model.name!r}'s Ts = {model.Ts:g} s; resample the data")
        n = len(ds)
        needed = [(r, w) for rows, w in ((model.states, "measured state"),
                                         (model.inputs, "input"),
                                         (model.disturbances, "disturbance"))
                  for r in rows if getattr(r, "measured", True)]
        missing = [f"{r.name!r} ({w}, {r.unit})" for r, w in needed if r.name not in ds]
        if len(missing) > 1:
            raise DataError(f"{ds.source}: model {model.name!r} needs channels "
                            f"{', '.join(missing)}")

        def column(row, required: bool, what: str):
            if row.name not in ds:
                if required:
                    raise DataError(f"{ds.source}: model {model.name!r} needs channel "
                                    f"{row.name!r} ({what}, {row.unit})")
                return np.full(n, np.nan)
            v = ds.get(row.name, row.unit)
            if required and not np.all(np.isfinite(v)):
                raise DataError(f"{ds.source}: channel {row.name!r} has non-finite values")
            return np.asarray(v, dtype=float)

        def stack(cols):
            return np.column_stack(cols) if cols else np.zeros((n, 0))

        x = stack([column(s, s.measured, "measured state") if s.measured
                   else np.full(n, np.nan) for s in model.states])
        u = stack([column(r, True, "input") for r in model.inputs])
        d = stack([column(r, True, "disturbance") for r in model.disturbances])
        y = stack([column(r, False, "output") for r in model.outputs])
        ids, exp = np.unique(ds.experiment, return_inverse=True)
        cens = np.column_stack([np.asarray(ds[f"{r.name}_censored"]) > 0.5
                                if f"{r.name}_censored" in ds else np.zeros(n, bool)
                                for r in (*model.states, *model.outputs)]) \
            if model.nx + model.ny else np.zeros((n, 0), bool)
        return cls(x=x, u=u, d=d, y=y, experiment=exp.astype(int),
                   experiment_ids=tuple(int(i) for i in ids), segments=tuple(ds.segments()),
                   Ts=float(ds.Ts), source=ds.source, censored=cens if cens.any() else None)

    def observed(self) -> np.ndarray:
        """(N, nx + ny) [x | y] with censored samples as NaN (what is fitted and scored)."""
        xy = np.concatenate([self.x, self.y], axis=1)
        if self.censored is not None:
            xy = np.where(self.censored, np.nan, xy)
        return xy

    def __len__(self) -> int:
        return self.x.shape[0]

    @property
    def n_experiments(self) -> int:
        return len(self.experiment_ids)

    @property
    def transition(self) -> np.ndarray:
        """(N-1,) True where samples k and k+1 are in one experiment."""
        return self.experiment[:-1] == self.experiment[1:]

    def measured_channels(self, model: Model) -> list[tuple[int, str]]:
        """(column in [x | y], name) of every channel this dataset measures."""
        out = [(i, s.name) for i, s in enumerate(model.states)
               if s.measured and np.isfinite(self.x[:, i]).any()]
        out += [(model.nx + j, o.name) for j, o in enumerate(model.outputs)
                if np.isfinite(self.y[:, j]).any()]
        return out

    def initial_states(self, model: Model, idx: np.ndarray) -> np.ndarray:
        """(len(idx), nx): measured states at ``idx``, latent ones from their ``initial``."""
        idx = np.asarray(idx, dtype=int)
        x0 = self.x[idx].copy()
        names = {}
        for group, arr in ((model.states, self.x), (model.inputs, self.u),
                           (model.disturbances, self.d), (model.outputs, self.y)):
            for i, row in enumerate(group):
                names[row.name] = arr[idx, i]
        ns = _Signals(names, model)
        for i, s in enumerate(model.states):
            if s.measured:
                continue
            rule = s.initial
            value = rule(ns) if callable(rule) else rule
            x0[:, i] = np.broadcast_to(np.asarray(value, dtype=float), idx.shape)
            if not np.all(np.isfinite(x0[:, i])):
                raise DataError(f"{self.source}: the initial rule of latent state {s.name!r} "
                                "gives a non-finite value (does it read an absent channel?)")
        return x0

    def parameter_matrix(self, model: Model, values: np.ndarray,
                         per_experiment: dict[str, np.ndarray] | None = None) -> np.ndarray:
        """(N, np) parameters of every sample: ``values``, per-experiment ones by experiment."""
        P = np.tile(np.asarray(values, dtype=float), (len(self), 1))
        names = model.parameter_names
        for name, vals in (per_experiment or {}).items():
            P[:, names.index(name)] = np.asarray(vals, dtype=float)[self.experiment]
        return P


class _Signals:
    def __init__(self, values: dict, model: Model):
        self._values = values
        self._model = model

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            return self._values[name]
        except KeyError:
            raise DataError(f"model {self._model.name!r}: an initial rule reads {name!r}, "
                            "not a signal of the model") from None

    __getitem__ = __getattr__
