"""The one unit table (``acid.units.UNIT_SCALES``) that import maps and FMU maps share; the
compound units of declared models (``acid.units.parse_unit``)."""

from __future__ import annotations

import numpy as np
import pytest

from acid.data import ChannelMap
from acid.plant.fmi.plant import FmuMap, fmi_unit_definition
from acid.units import (
    BASE_DIMENSIONS,
    KNOWN_UNITS,
    UNIT_SCALES,
    base_unit,
    convert,
    from_base,
    parse_unit,
    storage_unit,
    temperature_unit_consistent,
    to_base,
)


@pytest.mark.parametrize("unit", list(UNIT_SCALES))
def test_every_unit_round_trips_and_has_dimensions(unit):
    x = np.array([0.0, 1.5, -2.25, 300.0])
    assert np.allclose(from_base(to_base(x, unit), unit), x)
    assert base_unit(unit) in BASE_DIMENSIONS          # an exported FMU can declare it
    assert storage_unit(unit) in KNOWN_UNITS          # a dataset can store it
    exps, factor, offset = fmi_unit_definition(unit)
    assert exps == BASE_DIMENSIONS[base_unit(unit)] and factor > 0


@pytest.mark.parametrize(("value", "unit", "to", "expected"), [
    (36.0, "km/h", "m/s", 10.0), (2.5, "kW", "W", 2500.0), (360.0, "kg/h", "kg/s", 0.1),
    (100.0, "g/s", "kg/s", 0.1), (212.0, "degF", "degC", 100.0), (20.0, "°C", "K", 293.15),
    (2.0, "bar", "kPa", 200.0), (1013.0, "mbar", "Pa", 101300.0), (50.0, "%RH", "1", 0.5),
    (1.0, "kWh", "J", 3.6e6), (60.0, "mph", "km/h", 96.56064), (1.5, "min", "s", 90.0),
    (250.0, "ms", "s", 0.25), (800.0, "W/m^2", "W/m2", 800.0), (3.0, "kJ/K", "J/K", 3000.0),
    (60.0, "l/min", "m3/s", 1e-3), (60.0, "rpm", "rad/s", 2 * np.pi),
])
def test_conversions(value, unit, to, expected):
    assert convert(value, unit, to) == pytest.approx(expected)


def test_storage_units_are_degC_for_temperatures_and_base_units_otherwise():
    assert storage_unit("K") == storage_unit("degF") == storage_unit("°C") == "degC"
    assert (storage_unit("km/h"), storage_unit("kW"), storage_unit("kg/h"),
            storage_unit("%RH")) == ("m/s", "W", "kg/s", "1")


def test_different_quantities_and_unknown_units_are_refused():
    with pytest.raises(ValueError, match="km/h"):
        convert(1.0, "km/h", "W")
    with pytest.raises(ValueError, match="furlong"):
        base_unit("furlong")


def test_temperature_plausibility_in_any_temperature_unit():
    assert temperature_unit_consistent([70.0, 100.0], "degF")
    assert not temperature_unit_consistent([300.0], "degC")
    assert not temperature_unit_consistent([25.0], "K")
    assert not temperature_unit_consistent([600.0], "degF")


@pytest.mark.parametrize("unit", ["km/h", "kW", "kg/h", "g/s", "degF", "bar", "kPa", "W/m2",
                                  "%RH"])
def test_import_maps_and_fmu_maps_accept_the_same_units(unit):
    ChannelMap.from_dict({"time": "t", "channels": {"x": {"column": "X", "unit": unit}}})
    FmuMap.from_dict({"inputs": {"W_bl": {"name": "a"}, "T_evap_set": {"name": "b"}},
                      "states": {"T_cab": {"name": "c"}, "T_evap": {"name": "d"},
                                 "T_int": {"name": "e"}, "T_shell": {"name": "f"}},
                      "outputs": {"T_ain": {"name": "g"}, "extra": {"name": "h",
                                                                     "unit": unit}}})


def test_a_map_unit_that_measures_another_quantity_than_the_channel_is_refused():
    from acid.errors import DataError

    with pytest.raises(DataError, match="v_veh.*kW"):
        ChannelMap.from_dict({"time": "t", "channels": {"v_veh": {"column": "V",
                                                                   "unit": "kW"}}})


# ------------------------------------------------------------ compound units (declared models)
W = {"kg": 1, "m": 2, "s": -3}


@pytest.mark.parametrize("text, factor, dims", [
    ("W/K", 1.0, {**W, "K": -1}),
    ("kJ/K", 1e3, {"kg": 1, "m": 2, "s": -2, "K": -1}),
    ("K s/kg", 1.0, {"K": 1, "s": 1, "kg": -1}),
    ("J/(kg K)", 1.0, {"m": 2, "s": -2, "K": -1}),
    ("W s^2/kg^2", 1.0, {"kg": -1, "m": 2, "s": -1}),
    ("W/K/(m/s)^0.8", 1.0, {"kg": 1, "m": 1.2, "s": -2.2, "K": -1}),
    ("kg/kg", 1.0, {}), ("1", 1.0, {}), ("-", 1.0, {}), ("%", 0.01, {}),
    ("1/K", 1.0, {"K": -1}),
    ("kg m^-3", 1.0, {"kg": 1, "m": -3}), ("g/s", 1e-3, {"kg": 1, "s": -1}),
    ("degC", 1.0, {"K": 1}),
])
def test_compound_units(text, factor, dims):
    f, d = parse_unit(text)
    assert f == pytest.approx(factor)
    assert d.keys() == dims.keys() and all(d[k] == pytest.approx(v) for k, v in dims.items())


@pytest.mark.parametrize("text, fragment", [
    ("furlong", "unknown unit 'furlong'"), ("W/", "incomplete"), ("(K", "parenthesis"),
    ("", "empty unit"), ("K^", "'^' needs a number"), ("degC/s", "unknown unit 'degC'"),
])
def test_unreadable_units_say_why(text, fragment):
    with pytest.raises(ValueError, match=fragment.replace("^", "\\^").replace("(", "\\(")):
        parse_unit(text)


def test_an_unknown_unit_lists_the_known_ones_in_the_message():
    # a user reads the list in the error, not in acid's source
    with pytest.raises(ValueError) as err:
        parse_unit("furlong/s")
    assert "kW" in str(err.value) and "km/h" in str(err.value) and "'-'" in str(err.value)
    assert "UNIT_SCALES" not in str(err.value)


def test_json_in_degC_converts_absolute_temperatures_and_keeps_differences():
    from acid.units import json_in_degC

    d = {"T_amb_K": 303.15, "nmpc": {"T_cab_min_K": 293.15, "bounds_K": [276.15, 283.15]},
         "max_violation_K": 0.3, "rmse_K": 1.2, "slack_penalty_W_per_K": 1e5,
         "final_T_cab_K": float("nan"), "runs": [{"T_int_K": 315.15, "T_cab_floor_K": None}],
         "flag_K": True, "T_cab": 22.0, "UA_W_per_K": 300.0, "hA_W_K": 250.0}
    out = json_in_degC(d)
    assert out["T_amb_C"] == pytest.approx(30.0) and "T_amb_K" not in out
    assert out["nmpc"] == {"T_cab_min_C": pytest.approx(20.0),
                           "bounds_C": [pytest.approx(3.0), pytest.approx(10.0)]}
    assert out["runs"][0]["T_int_C"] == pytest.approx(42.0)
    # differences (a degC and a kelvin of difference are one), derived units, no number
    for key in ("max_violation_K", "rmse_K", "slack_penalty_W_per_K", "T_cab_floor_K",
                "flag_K", "T_cab", "UA_W_per_K", "hA_W_K"):   # W/K in 150-450: not a temperature
        assert key in out or key in out["runs"][0], key
    assert out["final_T_cab_K"] != out["final_T_cab_K"]  # a lone NaN says nothing: kept
    assert d["T_amb_K"] == 303.15  # the input is not changed
