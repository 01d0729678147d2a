"""acid.control.econ.terminal: the optimal steady state and its multipliers (terminal prices)."""

from __future__ import annotations

import numpy as np
import pytest

from acid.control.econ.terminal import SteadyStatePrice
from acid.models import econ
from acid.units import C2K

U_MIN, U_MAX = [0.05, C2K(3.0)], [0.15, C2K(10.0)]
BAND = (C2K(22.0), C2K(24.0))
NX = econ.model.nx


def _next_state(p, x, u, d, dist) -> np.ndarray:
    """The econ declaration one sample on (``casadi_interval``) at the numbers of ``p``."""
    F = econ.casadi_interval(p.Ts)
    return np.asarray(F(x, u, d, p.theta_all, dist)[0]).ravel()


def test_the_steady_state_is_a_fixed_point_on_the_band_at_least_power(econ_truth):
    sp = SteadyStatePrice(econ_truth, U_MIN, U_MAX)
    ss = sp.steady_state(12.0, C2K(30.0), *BAND)
    assert ss.success
    xn = _next_state(econ_truth, ss.x, ss.u, [12.0, C2K(30.0)], np.zeros(NX))
    np.testing.assert_allclose(xn, ss.x, atol=1e-7)
    assert ss.x[0] == pytest.approx(BAND[1], abs=1e-5)   # cooling costs: the upper edge
    # a nearby admissible input held to its own steady state costs more
    m = econ.model
    _, y = m.simulate(ss.x, np.tile(ss.u + [0.01, -0.5], (2000, 1)),
                      np.tile([12.0, C2K(30.0)], (2000, 1)), econ_truth.theta_all)
    power = y[-1, m.output_names.index("P_comp")] + y[-1, m.output_names.index("P_bl")]
    assert power > ss.power_W


def test_multipliers_are_the_optimal_cost_sensitivity(econ_truth):
    """lam_j = -d(l*)/d(b_j) for the steady-state equation F(x, u) - x = b; a constant
    disturbance e on the derivative j moves that equation to F - x = -(dF/de) e, so
    d(l*)/de = lam . dF/de (central differences): lam prices the heat a state gains."""
    sp = SteadyStatePrice(econ_truth, U_MIN, U_MAX)
    d = [12.0, C2K(30.0)]
    ss = sp.steady_state(*d, *BAND)
    assert np.all(ss.lam[:3] > 0) and ss.lam[4] > 0   # more heat or moisture costs energy
    for j, eps in ((0, 1e-4), (1, 1e-5), (4, 1e-9)):
        e = np.zeros(NX)
        e[j] = eps
        dFde = (_next_state(econ_truth, ss.x, ss.u, d, e)
                - _next_state(econ_truth, ss.x, ss.u, d, -e)) / (2 * eps)
        hi = sp.steady_state(*d, *BAND, guess=ss, dist=e)
        lo = sp.steady_state(*d, *BAND, guess=ss, dist=-e)
        fd = econ_truth.Ts * (hi.power_W - lo.power_W) / (2 * eps)
        assert fd == pytest.approx(ss.lam @ dFde, rel=1e-4), j


def test_prices_interpolate_the_speed_grid(econ_truth):
    sp = SteadyStatePrice(econ_truth, U_MIN, U_MAX)
    lam = sp.grid(C2K(30.0), *BAND)
    assert lam.shape == (sp.v_grid.size, NX) and sp.failures == 0
    v = 0.5 * (sp.v_grid[3] + sp.v_grid[4])
    np.testing.assert_allclose(sp(v, C2K(30.0), *BAND), 0.5 * (lam[3] + lam[4]))
    np.testing.assert_allclose(sp(sp.v_grid[2], C2K(30.0), *BAND),
                               sp.steady_state(sp.v_grid[2], C2K(30.0), *BAND).lam, rtol=1e-5)


def test_with_a_comfort_price_the_steady_cabin_sits_between_reference_and_edge(econ_truth):
    # energy + w (T_cab - ref)^2 at steady state: the cabin settles above the reference
    # (cooling costs) and below the band's upper edge (the price grows with the distance);
    # a lower reference or a dearer price pulls it down
    band = (C2K(22.0), C2K(26.0))
    t = {}
    for w, ref in ((30.0, 23.0), (30.0, 22.5), (300.0, 23.0)):
        ss = SteadyStatePrice(econ_truth, U_MIN, U_MAX, comfort_weight=w).steady_state(
            12.0, C2K(30.0), *band, T_cab_ref=C2K(ref))
        assert ss.success
        xn = _next_state(econ_truth, ss.x, ss.u, [12.0, C2K(30.0)], np.zeros(NX))
        np.testing.assert_allclose(xn, ss.x, atol=1e-7)
        assert C2K(ref) < ss.x[0] < band[1]
        t[(w, ref)] = ss.x[0]
    assert t[(30.0, 22.5)] < t[(30.0, 23.0)] and t[(300.0, 23.0)] < t[(30.0, 23.0)]
