"""Speed-aware eq. 4 (acid.control.speed_model): identification and the speed-aware NMPC."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from acid.control.nmpc import NMPC, NMPCConfig
from acid.control.speed_model import (
    SpeedAwareNMPC,
    SpeedEfficiency,
    fit_speed_efficiency,
    identify_from_plant,
)
from acid.errors import ConfigError, DataError
from acid.models.params import paper
from acid.units import C2K


def _synthetic(form, eta0, eta1, n=800, noise=5.0, seed=3):
    rng = np.random.default_rng(seed)
    v = rng.uniform(0.0, 30.0, n)
    W = rng.uniform(0.05, 0.15, n)
    T_ain = C2K(rng.uniform(3.0, 15.0, n))
    eff = SpeedEfficiency(eta0=eta0, eta1=eta1, form=form, v_sat=15.0)
    P = 1008.0 * W * (C2K(30.0) - T_ain) / eff.eta_cop(v) + noise * rng.standard_normal(n)
    return P, W, T_ain, v


@pytest.mark.parametrize("form,eta1", [("linear", 0.02), ("saturating", 0.015)])
def test_fit_recovers_synthetic_parameters(form, eta1):
    P, W, T_ain, v = _synthetic(form, 4.0, eta1)
    f = fit_speed_efficiency(P, W, T_ain, v, C2K(30.0), form=form, v_sat=15.0)
    assert f.eta0 == pytest.approx(4.0, abs=4 * f.stderr[0] + 1e-3)
    assert f.eta1 == pytest.approx(eta1, abs=4 * f.stderr[1] + 1e-4)
    assert f.quality["r2"] > 0.95 and f.quality["r2"] >= f.quality["const_r2"]


def test_eta_cop_accepts_floats_arrays_and_casadi_symbols():
    for form in ("linear", "saturating"):
        eff = SpeedEfficiency(eta0=4.0, eta1=0.02, form=form)
        v = ca.SX.sym("v")
        f = ca.Function("f", [v], [eff.eta_cop(v)])
        assert float(f(12.0)) == pytest.approx(eff.eta_cop(12.0))
        assert np.allclose(eff.eta_cop(np.array([0.0, 12.0])), [4.0, eff.eta_cop(12.0)])
        assert eff.eta_cop(0.0) == pytest.approx(4.0)
    assert SpeedEfficiency.constant(3.5).ratio(25.0) == 1.0


def test_identified_eta_cop_rises_with_speed_on_plant_data():
    f = identify_from_plant(duration_s=3600.0, skip_s=600.0)
    assert f.eta1 > 0 and f.eta1 > 3 * f.stderr[1]
    assert f.eta_cop(25.0) > f.eta_cop(0.0)
    assert 2.0 < f.eta0 < 8.0
    assert f.quality["r2"] > f.quality["const_r2"]
    d = f.to_json_dict()
    assert d["source"]["cycle"] == "udds" and d["stderr"]["eta1"] == f.stderr[1]


def test_too_few_samples_and_bad_options_are_one_line_errors():
    with pytest.raises(DataError, match="usable samples"):
        fit_speed_efficiency(np.zeros(20), np.full(20, 0.1), np.full(20, 280.0),
                             np.zeros(20), 303.15)
    with pytest.raises(ConfigError):
        SpeedEfficiency(eta0=4.0, form="cubic")


X0 = np.array([C2K(26.0), C2K(8.0)])


def test_speed_aware_nmpc_reduces_to_the_paper_nmpc_when_eta1_is_zero():
    p, cfg = paper(), NMPCConfig()
    ref = NMPC(p, cfg).solve(X0, C2K(24.0), C2K(30.0), C2K(33.0))
    aware = SpeedAwareNMPC(p, SpeedEfficiency(eta0=4.9, eta1=0.0), cfg)
    aware.set_speed_profile(np.linspace(0.0, 25.0, 40))
    assert np.allclose(aware.eta_preview(0), p.eta_cop)
    u = aware.make_step(X0, C2K(24.0), C2K(30.0), C2K(33.0))
    assert np.allclose(u, ref.u, atol=1e-7)
    assert aware.log.solutions[-1].objective == pytest.approx(ref.objective, rel=1e-8)


def test_speed_aware_preview_uses_the_relative_sensitivity_and_pads_the_end():
    p = paper()
    eff = SpeedEfficiency(eta0=5.0, eta1=0.05)
    aware = SpeedAwareNMPC(p, eff, NMPCConfig(N=6))
    aware.set_speed_profile([0.0, 10.0, 20.0])
    eta = aware.eta_preview(0)
    assert eta.shape == (7,)
    assert eta[0] == pytest.approx(p.eta_cop)
    assert eta[1] == pytest.approx(p.eta_cop * 1.1)
    assert np.allclose(eta[2:], p.eta_cop * 1.2)
    aware.make_step(X0, C2K(24.0), C2K(30.0), C2K(33.0))
    sol = aware.log.solutions[-1]
    W = np.append(sol.W_bl, sol.W_bl[-1])
    assert np.allclose(sol.P_comp, p.c_p / eta * W * (C2K(30.0) - sol.T_ain))
    aware.reset()
    assert aware._k == 0
    with pytest.raises(ConfigError):
        aware.set_speed_profile([-1.0])


def test_nmpc_eta_preview_is_validated():
    mpc = NMPC(paper(), NMPCConfig())
    with pytest.raises(ConfigError, match="eta_cop"):
        mpc.solve(X0, C2K(24.0), C2K(30.0), C2K(33.0), eta_cop=[3.5, 3.5])
    with pytest.raises(ConfigError, match="positive"):
        mpc.solve(X0, C2K(24.0), C2K(30.0), C2K(33.0), eta_cop=0.0)
