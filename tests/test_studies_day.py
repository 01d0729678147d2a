"""A connected car's day (``acid.studies.day``, ``acid.plant.battery``): inputs, physics of
parked pre-conditioning, accounting, the tuned timer against an independent scan, intervals."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from acid.errors import ConfigError
from acid.plant.battery import J_PER_KWH, Battery, Charger
from acid.studies import day as D
from acid.units import K2C


def test_climate_follows_the_normals_and_the_sun_sets():
    c = D.load_climate("summer")
    assert K2C(c.T_amb_K(15 * 3600.0)) == pytest.approx(c.T_max_C)
    assert K2C(c.T_amb_K(5 * 3600.0)) == pytest.approx(c.T_min_C)
    assert K2C(c.T_amb_K(15 * 3600.0, 2.0)) == pytest.approx(c.T_max_C + 2.0)
    assert c.G_solar(0.0) == 0.0 and c.G_solar(23 * 3600.0) == 0.0
    noon = c.G_solar(12 * 3600.0)
    assert 850.0 < noon < 1100.0  # a July noon at 33 N, clear sky
    assert c.G_solar(12 * 3600.0, 0.5) == pytest.approx(0.5 * noon)
    w = D.load_climate("winter")
    assert 300.0 < w.G_solar(12 * 3600.0) < noon  # a January noon at 45 N
    with pytest.raises(ConfigError):
        D.load_climate("spring")


def test_tariff_periods():
    t = D.load_tariff()
    assert t.price(17 * 3600.0) > t.price(15.5 * 3600.0) > t.price(7 * 3600.0)
    assert t.price(22 * 3600.0) == t.price(15.5 * 3600.0)
    assert t.off_peak == t.price(3 * 3600.0)


def test_battery_and_charger():
    b = Battery()
    assert (b.usable_kWh, b.gross_kWh) == (37.9, 42.2)
    half = Battery(soc=0.5).drawn(0.25 * 37.9 * J_PER_KWH)
    assert half.soc == pytest.approx(0.25)
    assert Battery(soc=0.1).drawn(10 * J_PER_KWH).soc == 0.0
    assert Battery(soc=0.1).exhausted(10 * J_PER_KWH)
    ch = Charger()
    assert ch.grid_J(ch.efficiency) == pytest.approx(1.0)
    assert ch.covers(5000.0) and not ch.covers(7400.0)
    with pytest.raises(ConfigError):
        Battery(usable_kWh=50.0)
    with pytest.raises(ConfigError):
        Charger(efficiency=1.2)


def test_days_are_seeded_and_forecast_errors_leave_the_days_alone():
    a = D.make_days("summer", 3, 7)
    assert a == D.make_days("summer", 3, 7)
    b = D.make_days("summer", 3, 7, forecast_sd_min=15.0)
    for x, y in zip(a, b, strict=True):
        assert [t.depart_s for t in x.trips] == [t.depart_s for t in y.trips]
        assert (x.dT_max, x.clouds) == (y.dT_max, y.clouds)
    assert any(t.forecast_s != t.depart_s for d in b for t in d.trips)
    assert all(t.depart_s % 60.0 == 0.0 for d in a for t in d.trips)


@pytest.fixture(scope="module")
def summer():
    d = D.make_days("summer", 1, 0)[0]
    return d, D.run_day(d, D.NoPreconditioning()), D.run_day(d, D.Timer(20.0))


@pytest.fixture(scope="module")
def winter():
    d = D.make_days("winter", 1, 0)[0]
    return d, D.run_day(d, D.NoPreconditioning()), D.run_day(d, D.Timer(20.0))


@pytest.mark.parametrize("which", ["summer", "winter"])
def test_preconditioning_moves_climate_energy_off_the_battery(which, request):
    d, none, timer = request.getfixturevalue(which)
    assert none.E_pre_grid_kWh == 0.0
    assert all(t.lead_s == 0.0 for t in none.trips)
    assert timer.trips[0].lead_s == 20 * 60.0  # plugged at home, forecast exact
    # the hot (cold) start removed, the drive's climate energy lower, the total higher
    assert none.Kmin_window > 5.0 and timer.Kmin_window < 0.5
    assert timer.time_to_comfort_s < none.time_to_comfort_s
    assert timer.E_climate_battery_kWh < 0.9 * none.E_climate_battery_kWh
    assert timer.range_lost_km < none.range_lost_km
    assert timer.E_pre_grid_kWh > 0.3
    assert timer.E_grid_kWh > none.E_grid_kWh
    # traction and base load do not depend on the climate controller
    for a, b in zip(none.trips, timer.trips, strict=True):
        assert a.E_traction_kWh == pytest.approx(b.E_traction_kWh, rel=1e-3)
        assert a.distance_km == pytest.approx(b.distance_km, rel=1e-9) and a.distance_km > 10.0
    # the accounting adds up
    for o in (none, timer):
        assert o.E_battery_kWh == pytest.approx(sum(
            t.E_pre_battery_kWh + t.E_climate_kWh + t.E_traction_kWh + t.E_base_kWh
            for t in o.trips))
        assert o.E_recharge_grid_kWh == pytest.approx(o.E_battery_kWh / Charger().efficiency)
        assert 0.0 < o.soc_end < D.SOC_START
        assert o.to_dict()["controller"] == o.controller and json.dumps(o.to_dict())
        assert o.summary().startswith(d.label)


def test_the_charger_caps_what_the_grid_supplies(winter):
    # heater and heat pump together draw more than the charger's 6.4 kW DC: the rest comes
    # from the battery, and a charger of twice the power takes all of it
    d, _, timer = winter
    t0 = timer.trips[0]
    assert t0.E_pre_battery_kWh > 0.0
    big = D.run_day(d, D.Timer(20.0), charger=Charger(P_ac_W=14800.0))
    assert big.trips[0].E_pre_battery_kWh == 0.0
    assert big.trips[0].E_pre_grid_kWh > t0.E_pre_grid_kWh
    assert big.E_battery_kWh == pytest.approx(timer.E_battery_kWh - t0.E_pre_battery_kWh
                                              - timer.trips[1].E_pre_battery_kWh, rel=1e-9)


def test_a_range_limited_day_is_driven_with_preconditioning_and_not_without(winter):
    # the battery at a start between what the day takes without and with pre-conditioning
    # (no charging between trips): without, the car is short of range; with, it arrives
    import dataclasses

    d, none, timer = winter
    assert none.short_kWh == 0.0 and timer.short_kWh == 0.0        # the usual 90 % start
    assert timer.charger_limited_kWh > 0.0           # the charger's power binds in winter
    assert timer.charger_limited_kWh == pytest.approx(sum(t.E_pre_battery_kWh
                                                          for t in timer.trips))
    soc = 0.5 * (none.E_battery_kWh + timer.E_battery_kWh) / Battery().usable_kWh
    low = dataclasses.replace(d, soc_start=soc)
    n, t = D.run_day(low, D.NoPreconditioning()), D.run_day(low, D.Timer(20.0))
    assert n.short_kWh > 0.0
    assert n.short_kWh == pytest.approx(n.E_battery_kWh - soc * Battery().usable_kWh)
    assert t.short_kWh == 0.0 and "short of range" in n.summary()
    assert n.soc_end == 0.0 and t.soc_end > 0.0
    with pytest.raises(ConfigError, match="soc-start"):
        D.make_days("winter", 1, 0, soc_start=0.0)


def test_winter_fog_margin_is_reported_and_summer_has_none(summer, winter):
    assert math.isnan(summer[1].fog_margin_min_K)
    assert winter[2].fog_margin_min_K > winter[1].fog_margin_min_K


def test_a_timer_of_no_lead_is_no_preconditioning(summer):
    d, none, _ = summer
    zero = D.run_day(d, D.Timer(0.0))
    assert zero.E_battery_kWh == none.E_battery_kWh and zero.Kmin_window == none.Kmin_window


def test_day_verdicts_are_the_engines_reading():
    from acid.studies.verdict import paired_verdict

    same = D.day_verdict([0.0] * 10)
    assert same["verdict"] == "no resolvable difference" and same["low"] == same["high"] == 0.0
    rng = np.random.default_rng(1)
    less = -1.0 + 0.1 * rng.standard_normal(10)
    v = D.day_verdict(less)
    assert v["verdict"] == "saves" and v["high"] < 0.0 < -v["low"]
    # the engine's t interval on the saving, in the difference's sign
    ref = paired_verdict(-less, min_count=D.MIN_DAYS_RESOLVED)
    assert (v["low"], v["high"], v["mean"]) == (-ref.hi, -ref.lo, -ref.mean)
    assert D.day_verdict(1.0 + 0.1 * rng.standard_normal(10))["verdict"] == "costs"
    few = D.day_verdict([-1.0] * (D.MIN_DAYS_RESOLVED - 1))
    assert few["verdict"] == "not resolved" and math.isnan(few["low"])


@pytest.mark.slow
def test_the_tuned_timer_is_as_good_as_the_best_lead_of_an_independent_scan():
    """The study tunes on a 10-minute scan (then to the minute); an independent scan of
    fixed leads on the plant, every minute up to 3 past the tuned lead and every 5 beyond,
    finds no cheaper lead that meets the comfort target."""
    leads = (0.0, 10.0, 20.0, 30.0)
    study = D.day_study(("summer",), n_train=2, n_test=1, seed=3, leads_min=leads,
                        forecast_errors_min=(0.0,), planners=())
    tuned = study.tuned_lead_min["summer"]
    train = D.make_days("summer", 2, 3)
    scan = {}
    for L in sorted({*range(0, int(tuned) + 4), *range(0, 31, 5)}):
        outs = [D.run_day(d, D.Timer(float(L))) for d in train]
        plugged = [t for o in outs for t in o.trips if t.plugged]
        scan[L] = (np.mean([o.cost_USD for o in outs]),
                   sum(t.Kmin_window for t in plugged) / len(plugged))
    ok = {L: c for L, (c, k) in scan.items() if k <= D.COMFORT_TARGET_KMIN}
    assert ok, "no lead of the scan met the comfort target"
    assert scan[tuned][1] <= D.COMFORT_TARGET_KMIN
    assert scan[tuned][0] <= min(ok.values()) + 1e-9
    assert {c["verdict"] for c in study.comparisons} <= {"not resolved"}


def test_the_plant_search_meets_the_comfort_target_at_no_more_cost_than_a_long_timer(summer):
    d, none, _ = summer
    plan = D.run_day(d, D.Planner(40.0))
    long = D.run_day(d, D.Timer(40.0))
    assert all(t.Kmin_window <= D.COMFORT_TARGET_KMIN for t in plan.trips)
    assert plan.cost_USD <= long.cost_USD + 1e-9
    assert plan.Kmin_window < none.Kmin_window
