"""The i3's road load (``acid.plant.road_load``): traction energy against closed-form answers
and against the car's EPA label."""

from __future__ import annotations

import math

import numpy as np
import pytest

from acid.errors import ConfigError
from acid.plant.road_load import G_N, RoadLoad, cycle_traction, epa_label_check


def test_constant_speed_costs_rolling_plus_aerodynamic_power_over_the_drivetrain():
    road = RoadLoad()
    v, n, T = 20.0, 600, 288.15
    t = road.traction(np.full(n + 1, v), 1.0, T)
    rho = 101325.0 / (287.05 * T)
    P_wheel = road.m * G_N * road.C_rr * v + 0.5 * rho * road.C_d * road.A_f * v ** 3
    assert t.wheel_J == pytest.approx(P_wheel * n, rel=1e-12)
    assert t.regen_J == 0.0
    assert t.battery_J == pytest.approx(P_wheel * n / road.eta_drive, rel=1e-12)
    assert t.aux_J == pytest.approx(road.P_aux * n)
    assert t.distance_m == pytest.approx(v * n)


def test_braking_returns_part_of_the_kinetic_energy_and_nothing_is_free():
    road = RoadLoad(C_rr=1e-9, C_d=1e-9, P_aux=1e-9)  # inertia alone
    v = np.concatenate([np.linspace(0, 20, 21), np.linspace(20, 0, 21)[1:]])
    t = road.traction(v, 1.0, 293.15)
    kinetic = 0.5 * road.f_rot * road.m * 20.0 ** 2
    assert t.wheel_J == pytest.approx(kinetic, rel=1e-6)
    assert t.regen_J == pytest.approx(kinetic * road.f_regen * road.eta_drive, rel=1e-6)
    assert 0.0 < t.battery_J < t.wheel_J / road.eta_drive


def test_cold_air_is_denser_and_costs_more_on_the_highway():
    road = RoadLoad()
    cold, hot = (cycle_traction(road, "hwfet", C) for C in (263.15, 313.15))
    assert cold.rho_air / hot.rho_air == pytest.approx(313.15 / 263.15)
    assert cold.battery_J > hot.battery_J
    assert cold.distance_m == hot.distance_m == pytest.approx(16506.55, rel=1e-4)


def test_the_i3_road_load_sits_near_its_epa_label():
    """UDDS inside the label's band (unadjusted, net of charging 0.85-0.92); HWFET within
    2 % of its lower edge (measured: 0.4 % below: the road load is reported, not tuned)."""
    checks = {c.cycle: c for c in epa_label_check()}
    assert checks["udds"].passed
    h = checks["hwfet"]
    assert h.model_Wh_per_km > 0.98 * h.label_low_Wh_per_km
    assert h.model_Wh_per_km < h.label_high_Wh_per_km
    assert checks["hwfet"].model_Wh_per_km > checks["udds"].model_Wh_per_km


@pytest.mark.parametrize("change", [{"m": 0.0}, {"eta_drive": 1.2}, {"f_rot": 0.9},
                                    {"C_d": math.nan}])
def test_bad_values_are_refused(change):
    with pytest.raises(ConfigError, match=next(iter(change))):
        RoadLoad(**change)


def test_every_road_load_value_cites_a_source():
    import dataclasses
    import re
    from pathlib import Path

    sources = (Path(__file__).parents[1] / "datasets/plant/SOURCES.md").read_text()
    for f in dataclasses.fields(RoadLoad):
        source = f.metadata["source"]
        assert f.metadata["unit"] and source, f.name
        keys = re.findall(r"\[([A-Za-z0-9.\-]+)\]", source)
        assert keys or "assumption" in source or "standard" in source, f.name
        for key in keys:
            assert f"[{key}]" in sources, (f.name, key)
