"""acid.units.parse_unit: compound units of declared models (factor to SI, dimensions)."""

from __future__ import annotations

import pytest

from acid.units import parse_unit

W = {"kg": 1, "m": 2, "s": -3}


@pytest.mark.parametrize("text, factor, dims", [
    ("W/K", 1.0, {**W, "K": -1}),
    ("kJ/K", 1e3, {"kg": 1, "m": 2, "s": -2, "K": -1}),
    ("K s/kg", 1.0, {"K": 1, "s": 1, "kg": -1}),
    ("J/(kg K)", 1.0, {"m": 2, "s": -2, "K": -1}),
    ("W s^2/kg^2", 1.0, {"kg": -1, "m": 2, "s": -1}),
    ("W/K/(m/s)^0.8", 1.0, {"kg": 1, "m": 1.2, "s": -2.2, "K": -1}),
    ("kg/kg", 1.0, {}), ("1", 1.0, {}), ("%", 0.01, {}), ("1/K", 1.0, {"K": -1}),
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
