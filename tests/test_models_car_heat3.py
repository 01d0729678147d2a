"""``car_heat3``: the cabin heated through the supply air (winter candidate of ``acid car
select``). Its balances close: in the steady state the heater's power leaves through the
fresh air the blower draws, the shell and the coolant loop's loss, and nothing reaches the
cabin before the ducts deliver it."""

import numpy as np

from acid.models import load


def _run(m, p, P_heater, H, x0=None):
    T_amb = 275.15
    x0 = np.array([T_amb] * m.nx) if x0 is None else x0
    u = np.full((H, m.nu), P_heater)
    d = np.tile([T_amb, 10.0], (H, 1))
    X, _ = m.simulate(x0, u, d, p)
    return X, T_amb


def test_car_heat3_is_a_winter_candidate_and_its_steady_state_balances():
    from acid.studies.car.select import CANDIDATES

    m = load("car_heat3")
    assert "car_heat3" in CANDIDATES["winter"]
    assert [s.name for s in m.states] == ["T_cool", "T_cab", "T_ain", "T_m"]
    v = dict(zip(m.parameter_names, m.values, strict=True))
    v["Q_occ"] = 0.0
    p = np.array([v[n] for n in m.parameter_names])
    from scipy.optimize import fsolve

    T_amb = 275.15
    x = fsolve(lambda x: m.step(x, [1500.0], [T_amb, 10.0], p)[0] - x,
               np.array([330.0, 295.0, 310.0, 285.0]), xtol=1e-12)
    assert np.allclose(m.step(x, [1500.0], [T_amb, 10.0], p)[0], x, atol=1e-9)
    T_cool, T_cab, T_ain, T_m = x
    w = v["W_lo"] + (v["W_hi"] - v["W_lo"]) * np.clip((T_cool - v["T_c0"]) / v["dT_w"], 0, 1)
    fresh = v["f_fresh"] * w * (T_cab - T_amb)
    shell = (v["UA_out"] + v["UA_out_v"] * 10.0) * (T_m - T_amb)
    coolant = v["UA_cool"] * (T_cool - T_amb)
    assert abs(v["eta_heater"] * 1500.0 - (fresh + shell + coolant)) < 1e-3
    assert T_ain > T_cab > T_m > T_amb


def test_the_cabin_warms_only_through_the_ducts():
    m = load("car_heat3")
    v = dict(zip(m.parameter_names, m.values, strict=True))
    v["Q_occ"] = 0.0
    v["tau_sup"] = 300.0                             # slow ducts: the cabin waits for them
    p = np.array([v[n] for n in m.parameter_names])
    X, T_amb = _run(m, p, 3000.0, 3)
    assert X[-1, 0] > T_amb + 1.0                    # the coolant is heated at once
    assert X[-1, 1] - T_amb < 0.05 * (X[-1, 2] - T_amb) + 1e-9   # cabin far behind the ducts
