"""acid.plant.check: the plant's credentials (issue 9 checks a-g) through the plant protocol."""

from __future__ import annotations

import json

import numpy as np
import pytest

from acid.errors import ConfigError
from acid.plant import make_plant
from acid.plant.check import SERVICE_CHART, build_plant, plant_check


@pytest.fixture(scope="module")
def hifi_check():
    return plant_check(build_plant("hifi"))


def rows_of(result, group):
    return [r for r in result.rows if r.group == group]


def test_json_contract(hifi_check):
    d = json.loads(json.dumps(hifi_check.to_json_dict(), allow_nan=False))
    assert isinstance(d["passed"], bool)
    assert {"cop_steady_30C_standstill", "cop_gain_25_vs_0_equal_load_pct"} <= set(d)
    for c in d["checks"]:
        assert {"name", "value", "reference", "unit", "passed"} <= set(c)
    assert {c["group"] for c in d["checks"]} == set("abcdefg")


def test_physics_credentials_pass(hifi_check):
    """(b)-(g) pass on the default plant; Table I's shape and E(0) hold (a)."""
    for group in "bcdefg":
        for r in rows_of(hifi_check, group):
            assert r.passed, (r.name, r.value, r.reference)
    a = {r.name: r for r in rows_of(hifi_check, "a")}
    assert a["Table I: E(0 m/s), 600 s"].passed
    assert a["Table I: smallest decrement (strictly decreasing)"].passed
    assert 2.5 <= hifi_check.cop_steady_30C_standstill <= 3.8
    assert hifi_check.cop_gain_25_vs_0_equal_load_pct >= 10.0


HOT_PULLDOWN = "pull-down: 60 degC soak at 43 degC, 1000 W/m2, to 25 degC"


def test_hot_pulldown_row_measures_the_time_to_25_degC(hifi_check):
    """(e) against PLANT.md's 20-30 min from a 60 degC soak at 43 degC and 1000 W/m^2."""
    (row,) = [r for r in rows_of(hifi_check, "e") if r.name == HOT_PULLDOWN]
    assert row.reference.startswith("20-30 min") and row.unit == "min"
    T = np.asarray(hifi_check.pulldown["hot43"]["T_cab_C"])
    assert T[0] == pytest.approx(60.0)
    below = np.nonzero(T <= 25.0)[0]
    assert row.value == pytest.approx(below[0] * 5.0 / 60.0)
    assert T[24] > 30.0  # still above 30 degC after 2 min


def test_the_table_i_calibration_meets_table_i_and_the_chart_but_not_the_hot_pulldown():
    """datasets/plant/table_i_20cc.toml (issue 9): every row passes but the hot pull-down,
    which the 20 cc compressor and its evaporator cannot meet (notes/i9-plant.md)."""
    from pathlib import Path

    toml = Path(__file__).parents[1] / "datasets" / "plant" / "table_i_20cc.toml"
    res = plant_check(build_plant("hifi", config_path=toml))
    failed = [r.name for r in res.rows if r.passed is False]
    assert failed == [HOT_PULLDOWN]
    assert 0.77 <= res.table_i["ratio"] <= 0.83
    assert res.pulldown["hot43"]["T_cab_C"][360] > 30.0  # still above 30 degC after 30 min


def test_service_chart_rows_compare_gauge_pressures_with_the_chart(hifi_check):
    s = hifi_check.service
    assert s["ambient_C"] == list(SERVICE_CHART)
    hi, lo = np.array(s["high_kPa"]), np.array(s["low_kPa"])
    assert np.all(np.diff(hi) > 0) and np.all(hi > 5 * lo)  # head pressure rises with ambient


def test_table_i_with_and_without_the_fan(hifi_check):
    t = hifi_check.table_i
    E, Ef = np.array(t["energy_MJ"]), np.array(t["energy_with_fan_MJ"])
    assert np.all(Ef >= E) and Ef[0] > E[0] and Ef[-1] == pytest.approx(E[-1])
    assert t["ratio_with_fan"] < t["ratio"]


def test_a_plant_without_pressures_degrades_gracefully():
    res = plant_check(make_plant("model"))
    by = {r.group: [] for r in res.rows}
    for r in res.rows:
        by[r.group].append(r)
    for group in "bcdfg":
        assert all(r.passed is None and "not available" in r.note for r in by[group]), group
    assert all(r.passed is not None for r in by["a"])  # Table I ran through the protocol
    assert res.cop_steady_30C_standstill is None


def test_ambient_outside_the_property_tables_is_refused():
    with pytest.raises(ConfigError, match="outside the refrigerant property tables"):
        build_plant("hifi", T_amb=400.0)
