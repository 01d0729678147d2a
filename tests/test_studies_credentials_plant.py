"""acid.studies.credentials.plant: the plant's credentials (issue 9 checks a-g) through the plant
protocol."""

from __future__ import annotations

import json

import numpy as np
import pytest

from acid.errors import ConfigError
from acid.plant import make_plant
from acid.studies.credentials.plant import CYCLE_CHECKS, SERVICE_CHART, build_plant, plant_check


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
            assert r.passed or (r.info and r.passed is None), (r.name, r.value, r.reference)
    a = {r.name: r for r in rows_of(hifi_check, "a")}
    assert a["Table I: E(0 m/s), 600 s"].passed
    assert a["Table I: smallest decrement (strictly decreasing)"].passed
    assert 2.5 <= hifi_check.cop_steady_30C_standstill <= 3.8
    assert hifi_check.cop_gain_25_vs_0_equal_load_pct >= 10.0


HOT_PULLDOWN = "pull-down: 60 degC soak at 43 degC, 1000 W/m2, to 25 degC"


def test_hot_pulldown_row_measures_the_time_to_25_degC(hifi_check):
    """(e) beside PLANT.md's 20-30 min from a 60 degC soak at 43 degC and 1000 W/m^2: a
    design target, not a published test, so information without a verdict (issue 21)."""
    (row,) = [r for r in rows_of(hifi_check, "e") if r.name == HOT_PULLDOWN]
    assert row.reference.startswith("20-30 min") and row.unit == "min"
    assert row.info and row.passed is None and "not a published test" in row.reference
    assert row.to_json_dict()["info"] is True
    T = np.asarray(hifi_check.pulldown["hot43"]["T_cab_C"])
    assert T[0] == pytest.approx(60.0)
    below = np.nonzero(T <= 25.0)[0]
    assert row.value == pytest.approx(below[0] * 5.0 / 60.0)
    assert T[24] > 30.0  # still above 30 degC after 2 min


def test_the_paper_vehicle_passes_every_check_and_the_hot_pulldown_is_information():
    """The paper vehicle (datasets/plant/table_i_20cc.toml, by name): every row with a verdict
    passes; the hot pull-down it does not meet is information (issue 21), and the result
    says the search behind it was not exhaustive."""
    res = plant_check(build_plant("hifi", config_path="paper"))
    assert [r.name for r in res.rows if r.passed is False] == []
    assert res.passed
    assert 0.77 <= res.table_i["ratio"] <= 0.83
    assert res.pulldown["hot43"]["T_cab_C"][360] > 30.0  # still above 30 degC after 30 min
    (row,) = [r for r in res.rows if r.name == HOT_PULLDOWN]
    assert row.info and row.passed is None and "outside the target" in row.note
    d = res.to_json_dict()
    assert "not exhaustive" in d["search_note"] and "1,000" in d["search_note"]


def test_the_refrigerant_balance_is_replaced_by_the_coolprop_cycle(hifi_check):
    """(b): no tautological 'balance: refrigerant' row; four CoolProp comparisons at three
    operating points, within their tolerances on the plant."""
    names = [r.name for r in rows_of(hifi_check, "b")]
    assert not any("refrigerant (" in n for n in names)
    cyc = [r for r in rows_of(hifi_check, "b") if r.name.startswith("cycle vs CoolProp")]
    assert len(cyc) == len(CYCLE_CHECKS) and all(r.passed for r in cyc)
    pts = hifi_check.cycle_check["points"]
    assert len(pts) == 3
    for p in pts:  # the plant's own numbers beside CoolProp's, physically sensible
        assert 2.0 < p["coolprop"]["COP"] < 8.0 and 30.0 < p["coolprop"]["T_c_C"] < 70.0
        assert p["coolprop"]["m_r_kg_s"] == pytest.approx(p["plant"]["m_r_kg_s"], rel=5e-3)


def test_coolprop_cycle_catches_a_plant_that_misreports_its_cycle(monkeypatch):
    """The check can fail: a cycle whose shaft power is 2 % high (COP 2 % low) or whose
    condensing temperature is 0.3 K off fails its row."""
    import dataclasses

    from acid.plant import check
    from acid.plant.cycle import cycle
    from acid.plant.vehicles import vehicle_config

    cfg = vehicle_config("default")
    r = cycle(6000.0, 278.15, 318.15, cfg)
    devs, _ = check.cycle_deviations(cfg, r)
    assert max(abs(d) for d in devs.values()) < 0.05  # acid's cycle agrees with CoolProp
    devs, _ = check.cycle_deviations(cfg, dataclasses.replace(r, W_comp=1.02 * r.W_comp))
    assert devs[CYCLE_CHECKS[0]] == pytest.approx(100 * (1 / 1.02 - 1), abs=0.05)
    plant = build_plant("hifi")
    bad = [("hot", dataclasses.replace(r, T_c=r.T_c + 0.3)),
           ("weak", dataclasses.replace(r, W_comp=1.02 * r.W_comp))]
    monkeypatch.setattr(check, "_operating_points", lambda p, p0: (bad, plant))
    rows, data = check.check_refrigerant_cycle(plant, plant)
    verdicts = {n: row.passed for n, row in zip(CYCLE_CHECKS, rows, strict=True)}
    assert all(n in row.name for n, row in zip(CYCLE_CHECKS, rows, strict=True))
    assert verdicts == {CYCLE_CHECKS[0]: False, CYCLE_CHECKS[1]: False,
                        CYCLE_CHECKS[2]: True, CYCLE_CHECKS[3]: True}
    assert len(data["points"]) == 2


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


def test_the_paper_vehicle_is_a_name_wherever_a_plant_configuration_is_accepted(tmp_path):
    from acid.plant.config import PlantConfig
    from acid.plant.vehicles import resolve_config, vehicle_config, vehicle_file

    paper_file = vehicle_file("paper")
    assert paper_file.name == "table_i_20cc.toml" and paper_file.is_file()
    assert make_plant("hifi", config_path="paper").cfg == PlantConfig.from_toml(paper_file)
    assert make_plant("hifi", config_path="default").cfg == PlantConfig()
    assert vehicle_config(None) == PlantConfig() and resolve_config("default") is None
    own = tmp_path / "mine.toml"
    own.write_text('refrigerant = "R1234yf"\n')
    assert resolve_config(own) == own and vehicle_config(own).refrigerant == "R1234yf"
    with pytest.raises(ConfigError, match="unknown vehicle"):
        vehicle_file("sedan")
