"""The real car's A/C under economic NMPC (``acid/models/car_ac.py``,
``acid/control/car_ac.py``, ``acid/car_study.py``; issue 20, item 5): the power output's
least squares recovers known values, and in closed loop on the declared model the NMPC holds
the comfort band for less energy than the best PI that holds it too."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from acid import car_study as cs
from acid.control.car_ac import CarACConfig
from acid.data import Dataset
from acid.models import load
from acid.models.car_ac import POWER_NAMES
from acid.units import C2K


def _synthetic_logs(model, values, seed: int, n_trips: int = 4, n: int = 200) -> Dataset:
    """Trips whose power is the declaration's output at ``values`` plus 20 W of noise."""
    rng = np.random.default_rng(seed)
    T_cab = rng.uniform(20.0, 35.0, n * n_trips)
    T_amb = rng.uniform(15.0, 35.0, n * n_trips)
    T_evap = rng.uniform(5.0, 25.0, n * n_trips)
    v = rng.uniform(0.0, 30.0, n * n_trips)
    fn = cs.power_function(model)
    X = np.zeros((n * n_trips, model.nx))
    X[:, 0] = C2K(T_cab)
    D = np.column_stack([C2K(T_amb), v])
    P = np.asarray(fn.map(len(X))(X.T, C2K(T_evap)[None, :], D.T, values)).ravel()
    P = P + rng.normal(0.0, 20.0, P.size)
    return Dataset(np.arange(n * n_trips) * 5.0,
                   {"T_cab": T_cab, "T_amb": T_amb, "T_evap": T_evap, "v_veh": v,
                    "P_comp": P},
                   {"T_cab": "degC", "T_amb": "degC", "T_evap": "degC", "v_veh": "m/s",
                    "P_comp": "W"}, 5.0, np.repeat(np.arange(n_trips), n))


def test_power_least_squares_recovers_known_values_and_scores_held_out_trips():
    m = load("car_ac")
    truth = m.values.copy()
    names = m.parameter_names
    truth[names.index("k_ac")], truth[names.index("f_fresh")] = 60.0, 0.2
    truth[names.index("k_cop")] = 0.05
    cabin = truth[:len(load("car_cabin").parameters)]
    # the fit starts from the declared values (38.7 W/K, 0.38, 0.11), not from the truth
    est, held = _synthetic_logs(m, truth, 1), _synthetic_logs(m, truth, 2)
    fit = cs.fit_power(est, held, cabin, m)
    for n in POWER_NAMES:
        assert fit.values[n] == pytest.approx(truth[names.index(n)], rel=0.03), n
    assert fit.held_out.rmse_W == pytest.approx(20.0, rel=0.15)   # the noise, no more
    assert fit.held_out.r2 > 0.99 and abs(fit.held_out.energy_ratio - 1) < 0.01


def test_nmpc_holds_the_band_for_no_more_energy_than_the_best_pi_holding_it():
    """Five minutes at 32 degC and 15 m/s from 24.5 degC, band 21-25 degC, on the declared
    model. The NMPC minimises this energy with the band as a constraint over its horizon
    (and a filter that sees only the cabin air); a PI holding the band must keep a margin
    below its top, so it cools more. Equal is allowed (0.5 %): both may end on the
    band's edge."""
    m = load("car_ac")
    values = m.values
    n = 60
    d = np.column_stack([np.full(n, C2K(32.0)), np.full(n, 15.0)])
    trip = cs.Trip("synthetic", d, np.full(n, C2K(24.5)), np.full(n, C2K(12.0)),
                   np.zeros(n), 5.0)
    cfg = CarACConfig(N=24)
    band = (cfg.T_cab_min, cfg.T_cab_max)

    def plant():
        return cs.ModelPlant(m, values, trip)

    nm = cs.run_nmpc(trip, values, plant(), cfg, model=m)
    assert nm.fallbacks == 0
    assert nm.max_violation_K < 0.02, nm.summary()
    pi, runs = cs.tune_pi(trip, plant, band, max_violation_K=0.02)
    assert all(r.max_violation_K <= 0.02 + 1e-9 for r in runs)
    assert nm.energy_J <= 1.005 * pi.energy_J, (nm.summary(), pi.summary())
    # the economics, not an idle controller: it cools (the cabin would pass 25 degC)
    assert nm.energy_J > 0.2 * pi.energy_J and nm.T_cab.max() > C2K(24.9)


REAL = Path(__file__).resolve().parents[1].parent / "shared" / "real-data" / "bmw-i3"


@pytest.mark.skipif(not REAL.is_dir(), reason=f"real vehicle data not found at {REAL} "
                    "(the BMW i3 trips, doi:10.21227/6jr9-5235; acid does not ship them)")
def test_real_trips_power_rises_with_the_ambient_in_both_splits_but_its_level_is_loose():
    """What the i3 logs support (notes/i20-real-logs.md, deliverable 5): fitted on either
    half of 8 trips, the power per K of air cooled rises with the ambient (the COP falls);
    on the other half the energy is right only to a factor of about two."""
    from acid.data import ChannelMap, import_logs
    from acid.examples import resolve

    cmap = ChannelMap.from_file(resolve("example:bmw_i3_map.toml"))
    a = import_logs([REAL / f"TripA{n}.csv.gz" for n in ("01", "04", "07", "09")], cmap)
    b = import_logs([REAL / f"TripA{n}.csv.gz" for n in ("03", "05", "08", "11")], cmap)
    m = load("car_ac")
    cabin = load("car_cabin").values
    for est, held in ((a, b), (b, a)):
        fit = cs.fit_power(est, held, cabin, m)
        assert fit.values["k_cop"] > 0.03, fit.values
        assert 1.0 < fit.values["k_ac"] < 399.0, fit.values
        assert fit.estimation.r2 > 0.3, fit.estimation
        assert 0.33 < fit.held_out.energy_ratio < 3.0, fit.held_out
