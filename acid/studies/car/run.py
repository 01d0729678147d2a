"""What ``acid car fit|validate|control`` do, as functions returning results (no printing).

* :func:`load_trips`: a folder of a car's logs through an import map, one dataset per trip.
* :func:`fit_car`: the power rows of ``car_ac`` fitted on the estimation trips (the cabin
  rows from a ``car_cabin`` parameter file or declared), scored on the held-out trips; the
  values as a ``car_ac`` parameter file's :class:`ParameterValues`.
* :func:`control_trip`: the economic NMPC on one trip's replay (its ambient and speed), the
  identified model as the plant, beside the car's own logged set-point replayed on it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from acid.control.car_ac import CarACConfig
from acid.data import ChannelMap, Dataset, import_logs
from acid.errors import DataError
from acid.models.car_ac import POWER_NAMES
from acid.models.car_ac import model as CAR_AC
from acid.models.values import ParameterValues
from acid.studies.car.power import split_trips
from acid.studies.car_study import ModelPlant, Trip, car_ac_values, fit_power, run_logged, run_nmpc

#: file names a folder of logs is read as
PATTERNS = ("*.csv.gz", "*.csv")


def load_trips(folder: Path, cmap: ChannelMap, names: Sequence[str] | None = None
               ) -> list[Dataset]:
    """The trips in ``folder`` (``*.csv.gz``/``*.csv``, sorted), one dataset each; ``names``:
    only those trips (file names without suffixes)."""
    files = sorted({p for pat in PATTERNS for p in Path(folder).glob(pat)})
    if not files:
        raise DataError(f"{folder}: no *.csv or *.csv.gz logs in it")
    trips = split_trips(import_logs(files, cmap))
    if names:
        have = {t.experiment_names()[0]: t for t in trips}
        missing = [n for n in names if n not in have]
        if missing:
            raise DataError(f"trip(s) {', '.join(missing)} not in {folder} (has "
                            f"{', '.join(sorted(have))})")
        trips = [have[n] for n in names]
    return trips


def cabin_values(cabin: ParameterValues | None) -> np.ndarray:
    """car_cabin's table from its parameter file, or its declared values (None)."""
    from acid.models import load

    m = load("car_cabin")
    if cabin is None:
        return m.values.copy()
    if cabin.declaration.name == "car_ac":
        return cabin.theta[:m.np].copy()
    if cabin.declaration.name != "car_cabin":
        raise DataError(f"{cabin.label}: a parameter file of model "
                        f"{cabin.declaration.name!r}; the car study needs one of 'car_cabin' "
                        "(acid fit --model car_cabin --method pem) or 'car_ac' (acid car fit)")
    return cabin.theta.copy()


@dataclass(frozen=True)
class CarFit:
    """The ``car_ac`` values (cabin rows given, power rows fitted on ``estimation``) and the
    fit's scores (:class:`acid.studies.car_study.PowerFit`)."""

    values: ParameterValues
    estimation: tuple[str, ...]
    held_out: tuple[str, ...]
    fit: object

    def summary(self) -> dict:
        return {"estimation_trips": list(self.estimation), "held_out_trips": list(self.held_out),
                "power_rows": self.fit.values, "status": self.fit.status,
                "estimation": _finite(self.fit.estimation.__dict__),
                "held_out": _finite(self.fit.held_out.__dict__)}


def _finite(d: dict) -> dict:
    """``d`` with a non-finite number (R^2 of trip means over one trip) as None."""
    return {k: (None if isinstance(v, float) and not np.isfinite(v) else v)
            for k, v in d.items()}


def fit_car(trips: Sequence[Dataset], cabin: np.ndarray, held_out: Sequence[int]) -> CarFit:
    """The power rows fitted on the trips not in ``held_out`` (indices), scored on those."""
    held = sorted(set(held_out))
    est = [t for i, t in enumerate(trips) if i not in held]
    if not est or not held:
        raise DataError("the car fit needs at least one estimation and one held-out trip")
    with np.errstate(divide="ignore", invalid="ignore"):   # trip-mean R^2 over one trip
        fit = fit_power(Dataset.concatenate(est),
                        Dataset.concatenate([trips[i] for i in held]), cabin, CAR_AC)
    values = car_ac_values(cabin, CAR_AC)
    for n in POWER_NAMES:
        values[CAR_AC.parameter_names.index(n)] = fit.values[n]
    name = lambda t: t.experiment_names()[0]   # noqa: E731
    ps = ParameterValues(values, model=CAR_AC, source="acid car fit",
                         provenance={"estimation_trips": [name(t) for t in est],
                                     "held_out_trips": [name(trips[i]) for i in held]})
    return CarFit(ps, tuple(name(t) for t in est), tuple(name(trips[i]) for i in held), fit)


def control_trip(trip_ds: Dataset, values: ParameterValues, config: CarACConfig | None = None,
                 progress: Callable[[int, int], None] | None = None) -> dict:
    """The NMPC and the logged set-point replayed on the identified model over one trip:
    their summaries, and the A/C energy and cabin air the car logged."""
    v = values.theta
    trip = Trip.of(trip_ds, int(trip_ds.experiment[0]), CAR_AC)
    cfg = config or CarACConfig()
    band = (cfg.T_cab_min, cfg.T_cab_max)
    plant = ModelPlant(CAR_AC, v, trip)
    n = len(trip.d)
    if progress is not None:   # one tick per sample the plant steps under the NMPC
        step, k = plant.step, [0]

        def ticking(T_evap, d):
            k[0] += 1
            progress(k[0], n)
            return step(T_evap, d)
        plant.step = ticking
    nm = run_nmpc(trip, v, plant, cfg, model=CAR_AC)
    logged = run_logged(trip, ModelPlant(CAR_AC, v, trip), band)
    return {"trip": trip.name, "samples": n, "Ts_s": trip.Ts,
            "band_C": [b - 273.15 for b in band], "nmpc": nm.summary(),
            "logged_replayed": logged.summary(),
            "logged": {"energy_kJ": float(trip.P_comp.sum() * trip.Ts / 1e3),
                       "mean_T_cab_C": float(trip.T_cab.mean() - 273.15)},
            "nmpc_vs_logged_replayed_energy_percent":
                100 * (nm.energy_J / logged.energy_J - 1) if logged.energy_J > 0 else None}
