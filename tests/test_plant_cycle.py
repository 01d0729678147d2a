"""The quasi-static cycle and its CoolProp tables, with an independent steady-state check.

Cross-check (PLANT.md): at fixed (T_e, T_c) the cycle's thermodynamic COP (Q_e over the
fluid power m_r (h2 - h1)) must equal

* a hand calculation with CoolProp ``PropsSI`` (always runs): suction state 1 at
  (p_sat(T_e), T_e + SH), h2s = h(p_sat(T_c), s1), h2 = h1 + (h2s - h1) / eta_is,
  liquid state 3 at (p_sat(T_c), T_c - SC), COP = (h1 - h3) / (h2 - h1);
* a TESPy network CycleCloser -> Compressor(eta_s) -> SimpleHeatExchanger -> Valve ->
  SimpleHeatExchanger (skipped when tespy is not installed).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from CoolProp.CoolProp import PropsSI

from acid.plant import refrigerant as rf
from acid.plant.config import PlantConfig
from acid.plant.cycle import cycle, cycle_at, make_solver

#: (T_e, T_c) in K, off the table grid: cool-down, mild and low-lift operating points.
OPERATING_POINTS = ((268.42, 328.67), (273.37, 318.81), (281.71, 308.43))


def hand_cop(T_e: float, T_c: float, eta_is: float, fluid: str = "R134a",
             SH: float = 5.0, SC: float = 5.0) -> float:
    """Thermodynamic COP from CoolProp PropsSI (documented hand calculation)."""
    p_e = PropsSI("P", "T", T_e, "Q", 1, fluid)
    p_c = PropsSI("P", "T", T_c, "Q", 0, fluid)
    h1 = PropsSI("H", "P", p_e, "T", T_e + SH, fluid)
    s1 = PropsSI("S", "P", p_e, "T", T_e + SH, fluid)
    h2s = PropsSI("H", "P", p_c, "S", s1, fluid)
    h2 = h1 + (h2s - h1) / eta_is
    h3 = PropsSI("H", "P", p_c, "T", T_c - SC, fluid)
    return (h1 - h3) / (h2 - h1)


@pytest.mark.parametrize("T_e, T_c", OPERATING_POINTS)
def test_cop_matches_propssi_hand_calculation(T_e, T_c):
    res = cycle_at(T_e, T_c)
    cop_thermo = res.Q_e / res.W_comp
    assert cop_thermo == pytest.approx(hand_cop(T_e, T_c, res.eta_is), rel=2e-3)
    assert res.COP == pytest.approx(cop_thermo * PlantConfig().eta_motor, rel=1e-12)


@pytest.mark.parametrize("T_e, T_c", OPERATING_POINTS)
def test_cop_matches_tespy(T_e, T_c):
    pytest.importorskip("tespy")
    from tespy.components import Compressor, CycleCloser, SimpleHeatExchanger, Valve
    from tespy.connections import Connection
    from tespy.networks import Network

    res = cycle_at(T_e, T_c)
    nw = Network(iterinfo=False)
    cc, comp = CycleCloser("closer"), Compressor("compressor")
    cond, valve, evap = SimpleHeatExchanger("condenser"), Valve("valve"), SimpleHeatExchanger(
        "evaporator")
    c1 = Connection(cc, "out1", comp, "in1", label="1")
    c2 = Connection(comp, "out1", cond, "in1", label="2")
    c3 = Connection(cond, "out1", valve, "in1", label="3")
    c4 = Connection(valve, "out1", evap, "in1", label="4")
    c5 = Connection(evap, "out1", cc, "in1", label="5")
    nw.add_conns(c1, c2, c3, c4, c5)
    comp.set_attr(eta_s=res.eta_is)
    cond.set_attr(pr=1)
    evap.set_attr(pr=1)
    c1.set_attr(fluid={"R134a": 1}, p=PropsSI("P", "T", T_e, "Q", 1, "R134a"), T=T_e + 5.0,
                m=res.m_r)
    c3.set_attr(p=PropsSI("P", "T", T_c, "Q", 0, "R134a"), T=T_c - 5.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        nw.solve("design")
    cop_tespy = evap.Q.val / comp.P.val
    assert res.Q_e / res.W_comp == pytest.approx(cop_tespy, rel=2e-3)
    assert res.Q_e == pytest.approx(evap.Q.val, rel=2e-3)


def test_tables_match_direct_heos_off_grid():
    tab = rf.table("R134a", 5.0, 5.0)
    for T_e, T_c in ((271.37, 322.81), (279.93, 307.26)):
        p_e = PropsSI("P", "T", T_e, "Q", 1, "R134a")
        p_c = PropsSI("P", "T", T_c, "Q", 0, "R134a")
        s1 = PropsSI("S", "P", p_e, "T", T_e + 5.0, "R134a")
        assert tab.interp1("p_sat", T_e) == pytest.approx(p_e, rel=5e-4)
        assert tab.interp1("rho1", T_e) == pytest.approx(
            PropsSI("D", "P", p_e, "T", T_e + 5.0, "R134a"), rel=1e-3)
        assert tab.interp1("h3", T_c) == pytest.approx(
            PropsSI("H", "P", p_c, "T", T_c - 5.0, "R134a"), rel=1e-4)
        assert tab.interp_h2s(T_e, T_c) == pytest.approx(
            PropsSI("H", "P", p_c, "S", s1, "R134a"), rel=1e-4)


def test_table_is_cached_per_fluid():
    assert rf.table("R134a", 5.0, 5.0) is rf.table("R134a", 5.0, 5.0)
    assert rf.table("R1234yf", 5.0, 5.0) is not rf.table("R134a", 5.0, 5.0)


def test_zero_speed_means_no_flow():
    res = cycle(0.0, 280.0, 310.0)
    assert (res.m_r, res.Q_e, res.Q_c, res.P_comp) == (0.0, 0.0, 0.0, 0.0)
    assert (res.T_e, res.T_c) == (280.0, 310.0)


@pytest.mark.parametrize("N, T_ew, T_cw", [(800, 285.0, 305.0), (4000, 278.15, 315.0),
                                            (8000, 303.15, 303.15), (8000, 272.0, 330.0)])
def test_solution_satisfies_balances_and_ordering(N, T_ew, T_cw):
    cfg = PlantConfig()
    res = cycle(N, T_ew, T_cw, cfg)
    assert res.T_e < T_ew and res.T_c > T_cw
    assert res.Q_e == pytest.approx(cfg.UA_er * (T_ew - res.T_e), rel=1e-6)
    assert res.Q_c == pytest.approx(cfg.UA_cr * (res.T_c - T_cw), rel=1e-6)
    # first law of the cycle: Q_c = Q_e + compressor fluid power
    assert res.Q_c == pytest.approx(res.Q_e + res.W_comp, rel=1e-9)
    assert res.P_comp == pytest.approx(res.W_comp / cfg.eta_motor)
    assert 0.3 <= res.eta_is <= cfg.eta_is_max and 0.05 <= res.eta_v <= cfg.eta_v0


def test_warm_start_converges_in_few_iterations():
    solve, _ = make_solver(PlantConfig())
    T_e, T_c, *_ = solve(5000.0, 278.15, 315.0, 270.0, 320.0)
    out = solve(5050.0, 278.2, 315.05, T_e, T_c)
    assert out[-1] <= 3
    cold = cycle(5000.0, 278.15, 315.0)
    assert cold.T_e == pytest.approx(T_e, abs=1e-4) and cold.T_c == pytest.approx(T_c, abs=1e-4)


def test_cycle_is_smooth_in_speed():
    """No jumps from table interpolation: Q_e(N) is monotone with bounded slope changes."""
    N = np.linspace(800, 8000, 73)
    Q = np.array([cycle(n, 280.0, 315.0).Q_e for n in N])
    dQ = np.diff(Q)
    assert np.all(dQ > 0)
    assert np.max(np.abs(np.diff(dQ))) < 0.05 * np.mean(dQ)
    assert all(math.isfinite(q) for q in Q)
