"""The declared heating model (``acid/models/heating.py``, issue 25): its declaration, its
step against an independent integration and an energy balance, its latent start after a
cold soak, and a short identification on real BMW i3 winter trips
(``../shared/real-data/bmw-i3-winter``; skipped, with the reason, where absent)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from acid.data import ChannelMap, import_logs
from acid.examples import resolve
from acid.ident.fit import fit_model
from acid.models import load

ROOT = Path(__file__).resolve().parents[1]
WINTER = ROOT.parent / "shared" / "real-data" / "bmw-i3-winter"
needs_logs = pytest.mark.skipif(not WINTER.is_dir(),
                                reason=f"BMW i3 winter logs absent ({WINTER})")


def _values(m, **changes):
    p = m.values.copy()
    for k, v in changes.items():
        p[m.parameter_names.index(k)] = v
    return p


def test_declaration_loads_by_name_with_measured_coolant_and_latent_interior_and_shell():
    m = load("heating")
    assert [(s.name, s.measured) for s in m.states] == [
        ("T_cool", True), ("T_cab", True), ("T_ain", True), ("T_int", False),
        ("T_shell", False)]
    assert [s.name for s in m.inputs] == ["P_heater"]
    assert {s.name for s in m.disturbances} == {"T_amb", "v_veh"}
    assert m.outputs == ()
    for p in m.parameters:
        assert p.min < p.max and p.min <= p.value <= p.max, p.name
    assert m.parameter("Q_occ").per_experiment and m.parameter("eta_heater").fixed
    assert m.parameter("G_cool").fixed
    # every cited key is a reference of one of the two source files
    doc = __import__("acid.models.heating", fromlist=["x"]).__doc__
    keys = set(re.findall(r"([A-Z][A-Za-z]+\d{4}|ASHRAE-F)", doc))
    text = ((ROOT / "acid/models/SOURCES.md").read_text(encoding="utf-8")
            + (ROOT / "datasets/plant/SOURCES.md").read_text(encoding="utf-8"))
    assert {"Steinstraeter2020", "ASHRAE-F", "Fayazbakhsh2013"} <= keys
    assert all(k in text for k in keys), [k for k in keys if k not in text]


def _rhs(p):
    """The heat balance of the module docstring, written again in numpy (K, W, kJ/K)."""
    def f(_t, x, P, Ta, v):
        T_cool, T_cab, T_ain, T_int, T_sh = x
        T_hc = T_cool + p["eta_heater"] * P / p["G_cool"]
        G = p["G_lo"] + (p["G_hi"] - p["G_lo"]) * min(max((T_cool - p["T_c0"]) / p["dT_w"],
                                                          0.0), 1.0)
        q_hc = G * (T_hc - T_cab)
        q_int = p["UA_int"] * (T_int - T_cab)
        q_sh = p["UA_shell"] * (T_sh - T_cab)
        q_out = (p["UA_out"] + p["UA_out_v"] * v) * (Ta - T_sh)
        q_vent = p["G_vent"] * (Ta - T_cab)
        return [(p["eta_heater"] * P - q_hc - p["UA_cool"] * (T_cool - Ta)) / (1e3 * p["C_cool"]),
                (q_hc + q_vent + q_int + q_sh + p["Q_occ"]) / (1e3 * p["C_cab"]),
                (T_cab + p["eps_sup"] * (T_hc - T_cab) - T_ain) / p["tau_sup"],
                -q_int / (1e3 * p["C_int"]),
                (q_out - q_sh) / (1e3 * p["C_shell"])]
    return f


@pytest.mark.parametrize("T_cool", [285.0, 300.0, 320.0])   # blower low, rising, high
def test_one_sample_matches_an_independent_integration(T_cool):
    m = load("heating")
    vals = _values(m, Q_occ=120.0)
    p = dict(zip(m.parameter_names, vals, strict=True))
    x0 = np.array([T_cool, 285.0, 300.0, 280.0, 278.0])
    u, d = np.array([3000.0]), np.array([276.0, 12.0])
    X, _ = m.simulate(x0, u[None, :], d[None, :], vals)
    ref = solve_ivp(_rhs(p), (0.0, m.Ts), x0, args=(3000.0, 276.0, 12.0), rtol=1e-11,
                    atol=1e-11).y[:, -1]
    np.testing.assert_allclose(X[1], ref, atol=2e-4)


def test_steady_state_closes_the_energy_balance():
    m = load("heating")
    vals = _values(m, Q_occ=100.0)
    p = dict(zip(m.parameter_names, vals, strict=True))
    n = 12 * 60 * 24  # 24 h: every node settles
    P, Ta, v = 1500.0, 275.0, 15.0
    X, _ = m.simulate(np.full(5, Ta), np.full((n, 1), P), np.tile([Ta, v], (n, 1)), vals)
    T_cool, T_cab, T_ain, T_int, T_sh = X[-1]
    assert T_int == pytest.approx(T_cab, abs=1e-6)  # no source in the interior
    out = (p["UA_cool"] * (T_cool - Ta) + p["G_vent"] * (T_cab - Ta)
           + (p["UA_out"] + p["UA_out_v"] * v) * (T_sh - Ta))
    assert out == pytest.approx(p["eta_heater"] * P + p["Q_occ"], rel=1e-6)
    assert T_cool > T_cab > T_sh > Ta
    # the outlets settle at the cabin air raised by eps_sup of the heater core's excess
    T_hc = T_cool + p["eta_heater"] * P / p["G_cool"]
    assert T_ain == pytest.approx(T_cab + p["eps_sup"] * (T_hc - T_cab), abs=1e-6)


def test_interior_starts_at_the_colder_of_cabin_sensor_and_outlets():
    from acid.data import Dataset
    from acid.ident.data import ModelData

    m = load("heating")
    n = 10
    ch = {"T_cool": np.full(n, 5.0), "T_cab": np.full(n, 10.0), "P_heater": np.zeros(n),
          "T_amb": np.full(n, 2.0), "v_veh": np.zeros(n), "T_ain": np.full(n, 4.0)}
    ch["T_ain"][5:] = 30.0
    units = {k: "degC" for k in ch} | {"P_heater": "W", "v_veh": "m/s"}
    data = ModelData.of(m, Dataset(np.arange(n) * 5.0, ch, units, 5.0))
    x0 = data.initial_states(m, np.array([0, 5]))
    # a cold soak with the cabin sensor at its 10 degC clip: the outlets' 4 degC
    np.testing.assert_allclose(x0[0, 3:], [277.15, 0.5 * (277.15 + 275.15)])
    # warm air at the outlets: the cabin sensor
    np.testing.assert_allclose(x0[1, 3:], [283.15, 0.5 * (283.15 + 275.15)])


@pytest.fixture(scope="module")
def two_trips():
    if not WINTER.is_dir():
        pytest.skip(f"BMW i3 winter logs absent ({WINTER})")
    cmap = ChannelMap.from_file(resolve("example:bmw_i3_winter_map.toml"))
    return import_logs([WINTER / "TripB13.csv.gz", WINTER / "TripB34.csv.gz"], cmap)


@needs_logs
def test_winter_map_reads_the_model_channels(two_trips):
    ds = two_trips
    assert {"T_cab", "T_cool", "P_heater", "T_amb", "v_veh", "T_ain"} <= set(ds.channels)
    names = ds.experiment_names()
    assert [n[:7] for n in names] == ["TripB13", "TripB34"] and ds.Ts == 5.0
    assert "T_ain" in ds.assumed  # the outlets' mean: equal shares are an assumption
    # the heater's power in W, the supply air warmer than the cabin while it heats
    P, T_ain, T_cab = ds.get("P_heater", "W"), ds.get("T_ain"), ds.get("T_cab")
    assert 500.0 < np.mean(P) < 4000.0
    assert np.mean(T_ain[P > 1000.0] - T_cab[P > 1000.0]) > 5.0


@needs_logs
def test_winter_map_marks_the_cabin_sensor_clip_and_drops_the_empty_tail():
    cmap = ChannelMap.from_file(resolve("example:bmw_i3_winter_map.toml"))
    ds = import_logs([WINTER / "TripB32.csv.gz"], cmap)  # cold soak; ends with empty rows
    mask = ds.get("T_cab_censored")
    assert mask[:12].all() and 0.1 < mask.mean() < 0.5
    assert np.all(ds.get("T_cab")[mask > 0] == pytest.approx(10.0))


@needs_logs
def test_short_fit_on_two_winter_trips_lowers_the_simulation_error(two_trips):
    m = load("heating")
    # the slow nodes held at their declared values: the coolant and cabin air identified
    fix = {n: m.parameter(n).value for n in ("C_int", "C_shell", "UA_out", "UA_out_v",
                                             "UA_shell", "UA_int", "G_vent")}
    res = fit_model(m, two_trips, "oe", fix=fix, oe_window=60, max_nfev=8)
    oe = res.output_error
    assert res.method == "oe", oe
    # simulation fit over the windows, each started from the log (latent from their rule)
    assert oe["channel_fit_percent"]["T_cab"] > 60.0, oe
    assert oe["channel_fit_percent"]["T_cool"] > 60.0, oe
    for name in ("C_cool", "G_lo", "G_hi", "T_c0", "eps_sup", "tau_sup", "UA_cool"):
        p = m.parameter(name)
        assert p.min <= res.value(name) <= p.max
    assert len(res.per_experiment["Q_occ"]) == 2
