"""acid.mpc.econ_terminal: the optimal steady state and its multipliers (terminal prices)."""

from __future__ import annotations

import numpy as np
import pytest

from acid.econ import model
from acid.mpc.econ_terminal import SteadyStatePrice
from acid.units import C2K

U_MIN, U_MAX = [0.05, C2K(3.0)], [0.15, C2K(10.0)]
BAND = (C2K(22.0), C2K(24.0))


def test_the_steady_state_is_a_fixed_point_on_the_band_at_least_power(econ_truth):
    sp = SteadyStatePrice(econ_truth, U_MIN, U_MAX)
    ss = sp.steady_state(12.0, C2K(30.0), *BAND)
    assert ss.success
    xn = np.asarray(model.casadi_step(econ_truth, econ_truth.Ts)(
        ss.x, ss.u, [12.0, C2K(30.0)], np.zeros(model.NX))[0]).ravel()
    np.testing.assert_allclose(xn, ss.x, atol=1e-7)
    assert ss.x[0] == pytest.approx(BAND[1], abs=1e-5)   # cooling costs: the upper edge
    # a nearby admissible input held to its own steady state costs more
    tr = model.simulate(ss.x, np.full(2000, ss.u[0] + 0.01), np.full(2000, ss.u[1] - 0.5),
                        12.0, C2K(30.0), econ_truth)
    assert tr.P_comp[-1] + tr.P_bl[-1] > ss.power_W


def test_multipliers_are_the_optimal_cost_sensitivity(econ_truth):
    """lam_j = -d(l*)/d(b_j) for the steady-state equation F(x, u) - x = b; a constant
    disturbance e on the derivative j moves that equation to F - x = -(dF/de) e, so
    d(l*)/de = lam . dF/de (central differences): lam prices the heat a state gains."""
    sp = SteadyStatePrice(econ_truth, U_MIN, U_MAX)
    d = [12.0, C2K(30.0)]
    ss = sp.steady_state(*d, *BAND)
    F = model.casadi_step(econ_truth, econ_truth.Ts)
    assert np.all(ss.lam[:3] > 0) and ss.lam[4] > 0   # more heat or moisture costs energy
    for j, eps in ((0, 1e-4), (1, 1e-5), (4, 1e-9)):
        e = np.zeros(model.NX)
        e[j] = eps
        dFde = (np.asarray(F(ss.x, ss.u, d, e)[0]).ravel()
                - np.asarray(F(ss.x, ss.u, d, -e)[0]).ravel()) / (2 * eps)
        hi = sp.steady_state(*d, *BAND, guess=ss, dist=e)
        lo = sp.steady_state(*d, *BAND, guess=ss, dist=-e)
        fd = econ_truth.Ts * (hi.power_W - lo.power_W) / (2 * eps)
        assert fd == pytest.approx(ss.lam @ dFde, rel=1e-4), j


def test_prices_interpolate_the_speed_grid(econ_truth):
    sp = SteadyStatePrice(econ_truth, U_MIN, U_MAX)
    lam = sp.grid(C2K(30.0), *BAND)
    assert lam.shape == (sp.v_grid.size, model.NX) and sp.failures == 0
    v = 0.5 * (sp.v_grid[3] + sp.v_grid[4])
    np.testing.assert_allclose(sp(v, C2K(30.0), *BAND), 0.5 * (lam[3] + lam[4]))
    np.testing.assert_allclose(sp(sp.v_grid[2], C2K(30.0), *BAND),
                               sp.steady_state(sp.v_grid[2], C2K(30.0), *BAND).lam, rtol=1e-5)
