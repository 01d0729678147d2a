"""acid.econ.model: the econ model family's functions (numpy and CasADi alike)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from acid.econ import model
from acid.econ.params import EconParams
from acid.errors import DataError
from acid.psychro import humidity_ratio
from acid.units import C2K

X0 = (C2K(25.0), C2K(27.0), C2K(35.0), C2K(8.0), 0.008)


def test_numpy_and_casadi_give_the_same_interval(econ_truth):
    rng = np.random.default_rng(0)
    F = model.casadi_step(econ_truth, 5.0)
    for _ in range(5):
        x = np.array(X0) + rng.normal(0, [2, 2, 2, 2, 1e-3])
        u = (rng.uniform(0.05, 0.15), C2K(rng.uniform(3, 10)))
        d = (rng.uniform(0, 30), C2K(rng.uniform(25, 40)))
        r = model.step(tuple(x), u, d, econ_truth, 5.0)
        xn, T_ain, Q_e, P_c, P_bl = (np.asarray(v).ravel() for v in F(x, u, d, np.zeros(5)))
        np.testing.assert_allclose(xn, np.array(r.x), rtol=1e-12)
        assert T_ain[0] == pytest.approx(r.T_ain, rel=1e-12)
        q = model.refrigerant_heat(r.Q_coil, x[3], r.x[3], 5.0, econ_truth)
        assert Q_e[0] == pytest.approx(q, rel=1e-10)
        assert P_c[0] == pytest.approx(model.compressor_power(q, r.T_evap, d[0], d[1],
                                                               econ_truth.power_map), rel=1e-10)


def test_rk4_sub_steps_converge(econ_truth):
    u, d = (0.1, C2K(5.0)), (10.0, C2K(32.0))
    ref = model.step(X0, u, d, econ_truth, 5.0, n_sub=16)
    one = model.step(X0, u, d, econ_truth, 5.0)      # the model's own step (1 x 5 s)
    assert np.max(np.abs(np.array(one.x[:4]) - np.array(ref.x[:4]))) < 0.01
    assert one.Q_coil == pytest.approx(ref.Q_coil, rel=2e-3)


def test_air_side_physics(econ_truth):
    p = econ_truth
    T_cab, T_amb = np.array([C2K(24.0)]), C2K(30.0)
    # recirculation: proportional to T_amb - T_cab, saturated at r_max, none when warmer inside
    r = model.recirculation(np.array([C2K(34.0), C2K(27.0), C2K(10.0)]), T_amb, p)
    assert r[0] < 0.01 and r[1] == pytest.approx(0.3, abs=0.01)
    assert r[2] == pytest.approx(p.r_max, abs=0.01)
    # more blower flow: less effectiveness, warmer supply air
    lo = model.air_side(T_cab, C2K(5.0), 0.008, 0.05, T_amb, p)
    hi = model.air_side(T_cab, C2K(5.0), 0.008, 0.15, T_amb, p)
    assert hi.eps < lo.eps < 1 and hi.T_ain > lo.T_ain
    # dry air over a warm coil: no condensation (beyond the smooth switch's few watts)
    w_dry = humidity_ratio(C2K(5.0), 0.5)
    dry = model.air_side(T_cab, C2K(12.0), w_dry, 0.1, T_amb, p.replace(RH_amb=0.1))
    assert abs(float(dry.Q_lat[0])) < 10.0
    wet = model.air_side(T_cab, C2K(3.0), 0.010, 0.1, T_amb, p)
    assert wet.Q_lat > 300.0 and wet.w_ain < wet.w_mix


def test_disturbance_terms_shift_the_states(econ_truth):
    u, d = (0.1, C2K(5.0)), (10.0, C2K(32.0))
    base = model.step(X0, u, d, econ_truth, 5.0)
    dist = (0.01, 0.0, 0.0, 0.0, 0.0)   # K/s on the cabin air
    moved = model.step(X0, u, d, econ_truth, 5.0, dist=dist)
    assert 0.0 < moved.x[0] - base.x[0] < 0.05
    assert abs(moved.x[1] - base.x[1]) < 0.02 * (moved.x[0] - base.x[0])  # only via coupling


def test_simulate_vectorises_and_conserves_steady_state(econ_truth):
    H = 40
    x0 = np.array([X0, X0])
    tr = model.simulate(x0, np.full((2, H), 0.1), np.full((2, H), C2K(6.0)),
                        np.full((2, H), 15.0), np.full((2, H), C2K(30.0)), econ_truth)
    assert tr.x.shape == (2, H + 1, 5) and tr.P_comp.shape == (2, H)
    np.testing.assert_allclose(tr.x[0], tr.x[1])
    assert np.all(tr.P_comp >= 0) and np.all(tr.power > 0)
    assert tr.state("T_evap")[0, -1] == pytest.approx(C2K(6.0) + econ_truth.dT_ew, abs=0.05)


def test_params_json_round_trip_and_family(econ_truth, tmp_path):
    from acid.econ.params import load_any_params, model_family
    from acid.params import paper

    path = econ_truth.to_json(tmp_path / "econ.json")
    back = EconParams.from_json(path)
    assert back.values == econ_truth.values and back.C_ew == econ_truth.C_ew
    assert back.power_map.coef == econ_truth.power_map.coef
    assert model_family(path) == "econ" and isinstance(load_any_params(path), EconParams)
    paper_file = paper().to_json(tmp_path / "paper.json")
    assert model_family(paper_file) == "paper" and model_family("paper") == "paper"
    with pytest.raises(DataError, match="not an econ parameter file"):
        EconParams.from_json(paper_file)
    with pytest.raises(DataError, match="C_cab must be positive"):
        econ_truth.replace(C_cab=-1.0)


def test_power_map_names_what_it_extrapolates(econ_truth):
    pm = econ_truth.power_map
    assert pm.outside(v_veh=np.array([0.0, 20.0]), T_amb=np.array([C2K(30.0)])) == []
    msg = pm.outside(v_veh=np.array([40.0]))
    assert len(msg) == 1 and "v_veh up to 40" in msg[0]
    hot = pm.outside(T_amb=np.array([C2K(70.0)]))   # what the user reads is in degC
    assert len(hot) == 1 and re.search(r"T_amb up to 70 degC \(data [\d.]+-[\d.]+\)", hot[0])
