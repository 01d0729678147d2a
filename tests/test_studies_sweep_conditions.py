"""The one mapping of sweep conditions (degC, %, W/m2) onto the plant configuration."""

from __future__ import annotations

import pytest

from acid.errors import ConfigError
from acid.plant.config import PlantConfig
from acid.studies.sweep.conditions import G_REF, Conditions, plant_config_for
from acid.units import C2K


def test_default_conditions_reproduce_the_default_plant():
    """30 degC, 50 %, the reference irradiance, R134a and a 22 degC set-point are
    PlantConfig()'s own."""
    cfg = plant_config_for(Conditions(setpoint_C=22.0))
    assert cfg == PlantConfig()


def test_climate_maps_onto_the_plant():
    c = Conditions(ambient_C=40.0, humidity_pct=70.0, solar_W_m2=400.0,
                   refrigerant="R1234yf", setpoint_C=25.0)
    cfg, ref = plant_config_for(c), PlantConfig()
    assert cfg.T_amb == C2K(40.0) and cfg.RH_amb == pytest.approx(0.7)
    assert cfg.refrigerant == "R1234yf" and cfg.T_cab_set == C2K(25.0)
    assert cfg.Q_solar_shell == pytest.approx(ref.Q_solar_shell * 400.0 / G_REF)
    assert cfg.Q_solar_int == pytest.approx(ref.Q_solar_int * 400.0 / G_REF)
    # hot soak: walls at ambient, the cabin's excess over ambient halves with half the sun
    assert cfg.T_ew0 == cfg.T_cw0 == C2K(40.0)
    assert cfg.T_cab0 - cfg.T_amb == pytest.approx((ref.T_cab0 - ref.T_amb) * 400.0 / G_REF)


def test_no_sun_means_no_soak_and_no_solar_gain():
    cfg = plant_config_for(Conditions(solar_W_m2=0.0))
    assert cfg.Q_solar_int == cfg.Q_solar_shell == 0.0
    assert cfg.T_cab0 == cfg.T_int0 == cfg.T_shell0 == cfg.T_amb


def test_overrides_apply_but_may_not_contradict_the_conditions():
    assert plant_config_for(Conditions(), {"V_disp": 4.0e-5}).V_disp == 4.0e-5
    with pytest.raises(ConfigError, match="'RH_amb' is set by the scenario's humidity_pct"):
        plant_config_for(Conditions(), {"RH_amb": 0.3})


@pytest.mark.parametrize("kw, msg", [({"humidity_pct": -1.0}, "humidity_pct"),
                                     ({"ambient_C": 70.0}, "ambient_C"),
                                     ({"refrigerant": "CO2"}, "refrigerant"),
                                     ({"band_C": (25.0, 21.0)}, "band_C")])
def test_conditions_are_checked(kw, msg):
    with pytest.raises(ConfigError, match=msg):
        Conditions(**kw)
