"""car_ac's A/C power: positive at every ambient (its COP never turns negative), and on the
26 BMW i3 summer trips held out one at a time it carries over (``../shared/real-data``;
skipped where absent)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from acid.models import load
from acid.studies.car.power import (
    declared_power,
    folds_of,
    leave_trips_out,
    regressor_bound,
    split_trips,
)
from acid.studies.car_study import power_function

ROOT = Path(__file__).resolve().parents[1]
REAL = next((p for p in (ROOT.parent / "shared" / "real-data" / "bmw-i3",
                         ROOT.parent.parent / "shared" / "real-data" / "bmw-i3") if p.is_dir()),
            ROOT.parent / "shared" / "real-data" / "bmw-i3")


def test_power_is_positive_and_rises_with_the_ambient_from_winter_to_heat_wave():
    m = load("car_ac")
    fn = power_function(m)
    T_amb = np.linspace(273.15, 318.15, 10)         # 0-45 degC
    X = np.zeros((10, m.nx))
    X[:, m.state_names.index("T_cab")] = 298.15
    U = np.full((10, 1), 283.15)                    # 10 K of air cooled at least
    D = np.column_stack([T_amb, np.full(10, 10.0)])
    P = np.asarray(fn.map(10)(X.T, U.T, D.T, m.values)).ravel()
    assert np.all(P > 0), P
    assert np.all(np.diff(P) > 0), P


def test_folds_hold_each_trip_out_once():
    f = folds_of(7, 3)
    assert sorted(np.concatenate(f).tolist()) == list(range(7))
    with pytest.raises(Exception, match="--folds"):
        folds_of(3, 4)


@pytest.mark.slow
@pytest.mark.skipif(not REAL.is_dir(), reason=f"real vehicle data not found at {REAL} "
                    "(the BMW i3 trips, doi:10.21227/6jr9-5235; acid does not ship them)")
def test_power_carries_over_to_trips_held_out_one_at_a_time():
    """Leave-one-trip-out over the 26 summer trips: pooled R^2 per 5 s above 0.5 and the
    energy within 15 %, and better than an unconstrained quadratic regressor on the same
    channels (measured: 0.56 [0.31, 0.68], 0.91 [0.74, 1.08]; regressor 0.42)."""
    from acid.data import ChannelMap, import_logs
    from acid.examples import resolve

    ds = import_logs(sorted(REAL.glob("TripA*.csv.gz")),
                     ChannelMap.from_file(resolve("example:bmw_i3_map.toml")))
    trips = split_trips(ds)
    assert len(trips) >= 20
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        h = leave_trips_out(trips, load("car_cabin").values)
        b = regressor_bound(trips)
        d = declared_power(trips, load("car_cabin").values)
    assert h.r2 > 0.5 and 0.85 < h.energy_ratio < 1.15, h.summary()
    # the fit is what carries over, not the cited values alone (measured R^2 0.56 against
    # 0.52 with the declared rows), and every fold moved them
    assert h.r2 > d.r2 + 0.02, (h.r2, d.r2)
    declared = dict(zip(load("car_ac").parameter_names, load("car_ac").values, strict=True))
    for fold in h.fold_values:
        assert any(abs(v - declared[k]) > 0.01 * abs(declared[k]) for k, v in fold.items())
    assert h.r2_ci[0] < h.r2 < h.r2_ci[1]
    assert h.r2 > b.r2, (h.r2, b.r2)
    assert all(t.mean_model_W >= 0 for t in h.trips)
