"""acid.models.econ: the econ model declared once steps as the hand-written model it replaced
(values recorded from ``acid/econ/model.py`` before its deletion, in
``tests/references/econ_model_steps.json``), for the declared 5 s step, longer intervals
with several RK4 sub-steps and additive disturbances, and a 40-step simulation; and the
physics it declares (air side, RK4 convergence, disturbance hooks)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from acid.models import econ, load
from acid.psychro import humidity_ratio
from acid.units import C2K

REF = json.loads((Path(__file__).parent / "references" / "econ_model_steps.json").read_text())


@pytest.fixture(scope="module")
def theta():
    p = REF["params"]
    return np.array([p["values"][n] for n in econ.THERMAL_NAMES] + [p["C_ew"]] + p["map"]
                    + p["beta"])


def test_declared_step_is_the_recorded_step(theta):
    m = load("econ")
    x, u, d = (np.array(REF[k]) for k in ("x", "u", "d"))
    xn, y = m.step(x, u, d, theta)
    case = REF["step"]
    np.testing.assert_allclose(xn, case["x_next"], rtol=1e-10)
    for j, name in enumerate(m.output_names):
        np.testing.assert_allclose(y[:, j], case[name], rtol=1e-10, atol=1e-9, err_msg=name)


@pytest.mark.parametrize("case", REF["cases"], ids=lambda c: f"dt{c['dt']:g}")
def test_intervals_with_disturbances_are_the_recorded_ones(theta, case):
    x, u, d, w = (np.array(REF[k]) for k in ("x", "u", "d", "dist"))
    F = econ.casadi_interval(case["dt"], case["n_sub"]).map(len(x))
    out = F(x.T, u.T, d.T, np.tile(theta, (len(x), 1)).T, w.T)
    np.testing.assert_allclose(np.asarray(out[0]).T, case["x_next"], rtol=1e-10)
    for k, name in enumerate(("T_ain", "Q_e", "P_comp", "P_bl"), start=1):
        np.testing.assert_allclose(np.asarray(out[k]).ravel(), case[name], rtol=1e-10,
                                   atol=1e-9, err_msg=name)


def test_simulation_and_heat_content_are_the_recorded_ones(theta):
    m = load("econ")
    sim = REF["simulate"]
    u = np.c_[sim["W_bl"], sim["T_evap_set"]]
    d = np.c_[sim["v_veh"], sim["T_amb"]]
    X, Y = m.simulate(np.array(sim["x0"]), u, d, theta)
    np.testing.assert_allclose(X, sim["x"], rtol=1e-10)
    np.testing.assert_allclose(Y[:, 0], sim["T_ain"], rtol=1e-10)
    np.testing.assert_allclose(np.maximum(Y[:, 1], 0.0), sim["P_comp"], rtol=1e-9)
    np.testing.assert_allclose(Y[:, 2], sim["P_bl"], rtol=1e-10)
    x = np.array(REF["x"])
    H = econ.heat_content(econ.parameters(theta), tuple(x.T), np.array(REF["d"])[:, 0])
    np.testing.assert_allclose(H, REF["heat_content"], rtol=1e-12)


def test_air_side_is_the_recorded_one(theta):
    x, u, d = (np.array(REF[k]) for k in ("x", "u", "d"))
    air = econ.air_side(econ.parameters(theta), x[:, 0], x[:, 3], x[:, 4], u[:, 0], d[:, 1])
    for name, ref in REF["air_side"].items():
        np.testing.assert_allclose(getattr(air, name), ref, rtol=1e-12, atol=1e-15,
                                   err_msg=name)


# ------------------------------------------------------------------ the physics it declares
X0 = (C2K(25.0), C2K(27.0), C2K(35.0), C2K(8.0), 0.008)


def _interval(p, x, u, d, dt=5.0, n_sub=None, dist=(0.0,) * 5):
    out = econ.casadi_interval(dt, n_sub)(x, u, d, p.theta_all, dist)
    return [np.asarray(v).ravel() for v in out]


def test_rk4_sub_steps_converge(econ_truth):
    u, d = (0.1, C2K(5.0)), (10.0, C2K(32.0))
    ref = _interval(econ_truth, X0, u, d, n_sub=16)
    one = _interval(econ_truth, X0, u, d)            # the declared step (1 x 5 s)
    assert np.max(np.abs(one[0][:4] - ref[0][:4])) < 0.01
    assert one[2][0] == pytest.approx(ref[2][0], rel=2e-3)


def test_air_side_physics(econ_truth):
    s = econ.parameters(econ_truth.theta_all)
    T_amb = C2K(30.0)
    # recirculation: proportional to T_amb - T_cab, saturated at r_max, none when warmer inside
    r = econ.air_side(s, np.array([C2K(34.0), C2K(27.0), C2K(10.0)]), C2K(5.0), 0.008, 0.1,
                      T_amb).r
    assert r[0] < 0.01 and r[1] == pytest.approx(0.3, abs=0.01)
    assert r[2] == pytest.approx(s.r_max, abs=0.01)
    # more blower flow: less effectiveness, warmer supply air
    lo = econ.air_side(s, C2K(24.0), C2K(5.0), 0.008, 0.05, T_amb)
    hi = econ.air_side(s, C2K(24.0), C2K(5.0), 0.008, 0.15, T_amb)
    assert hi.eps < lo.eps < 1 and hi.T_ain > lo.T_ain
    # dry air over a warm coil: no condensation (beyond the smooth switch's few watts)
    dry = econ.air_side(econ._ByName(s, RH_amb=0.1), C2K(24.0), C2K(12.0),
                        humidity_ratio(C2K(5.0), 0.5), 0.1, T_amb)
    assert abs(float(dry.Q_lat)) < 10.0
    wet = econ.air_side(s, C2K(24.0), C2K(3.0), 0.010, 0.1, T_amb)
    assert wet.Q_lat > 300.0 and wet.w_ain < wet.w_mix


def test_disturbance_terms_shift_the_states(econ_truth):
    u, d = (0.1, C2K(5.0)), (10.0, C2K(32.0))
    base = _interval(econ_truth, X0, u, d)[0]
    moved = _interval(econ_truth, X0, u, d, dist=(0.01, 0.0, 0.0, 0.0, 0.0))[0]  # K/s, cabin
    assert 0.0 < moved[0] - base[0] < 0.05
    assert abs(moved[1] - base[1]) < 0.02 * (moved[0] - base[0])  # only via coupling


def test_simulate_vectorises_and_reaches_the_wall_set_point(econ_truth):
    H = 40
    u = np.broadcast_to([0.1, C2K(6.0)], (2, H, 2))
    d = np.broadcast_to([15.0, C2K(30.0)], (2, H, 2))
    X, Y = load("econ").simulate(np.array([X0, X0]), u, d, econ_truth.theta_all)
    assert X.shape == (2, H + 1, 5) and Y.shape == (2, H, 3)
    np.testing.assert_allclose(X[0], X[1])
    assert np.all(Y[..., 1] > 0) and np.all(Y[..., 2] > 0)
    assert X[0, -1, 3] == pytest.approx(C2K(6.0) + econ_truth.dT_ew, abs=0.05)
