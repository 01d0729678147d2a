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


NO_SUCTION_DROP = PlantConfig(dT_suc0=0.0)


def hand_cop(T_e: float, T_c: float, eta_is: float, fluid: str = "R134a",
             SH: float = 5.0, SC: float = 5.0, T_s: float | None = None) -> float:
    """Thermodynamic COP from CoolProp PropsSI (documented hand calculation).

    Evaporator outlet 1 at (p_sat(T_e), T_e + SH); with a suction drop the compressor starts
    from (p_sat(T_s), h1) (isenthalpic suction line) and lifts isentropically to p_sat(T_c).
    """
    p_e = PropsSI("P", "T", T_e, "Q", 1, fluid)
    p_c = PropsSI("P", "T", T_c, "Q", 0, fluid)
    h1 = PropsSI("H", "P", p_e, "T", T_e + SH, fluid)
    p_s = p_e if T_s is None else PropsSI("P", "T", T_s, "Q", 1, fluid)
    s1 = PropsSI("S", "P", p_s, "H", h1, fluid)
    h2s = PropsSI("H", "P", p_c, "S", s1, fluid)
    h2 = h1 + (h2s - h1) / eta_is
    h3 = PropsSI("H", "P", p_c, "T", T_c - SC, fluid)
    return (h1 - h3) / (h2 - h1)


@pytest.mark.parametrize("T_e, T_c", OPERATING_POINTS)
def test_cop_matches_propssi_hand_calculation(T_e, T_c):
    """Like with like: without a suction drop the cycle is the textbook one."""
    res = cycle_at(T_e, T_c, NO_SUCTION_DROP)
    cop_thermo = res.Q_e / res.W_comp
    assert cop_thermo == pytest.approx(hand_cop(T_e, T_c, res.eta_is), rel=2e-3)
    assert res.COP == pytest.approx(cop_thermo * res.eta_motor, rel=1e-12)
    assert 0.75 < res.eta_motor < 0.95


@pytest.mark.parametrize("T_e, T_c", OPERATING_POINTS)
def test_cop_with_suction_drop_matches_hand_calculation(T_e, T_c):
    """With the suction-line drop the compressor lifts from (p_s, h1): the tables approximate
    that state by (p_s, T_s + SH), so agreement is to 1 %, and the drop costs COP."""
    res = cycle_at(T_e, T_c)
    assert res.T_s < T_e and res.p_s < res.p_e
    cop_thermo = res.Q_e / res.W_comp
    assert cop_thermo == pytest.approx(hand_cop(T_e, T_c, res.eta_is, T_s=res.T_s), rel=0.01)
    ref = cycle_at(T_e, T_c, NO_SUCTION_DROP)
    assert cop_thermo < ref.Q_e / ref.W_comp


@pytest.mark.parametrize("T_e, T_c", OPERATING_POINTS)
def test_cop_matches_tespy(T_e, T_c):
    pytest.importorskip("tespy")
    from tespy.components import Compressor, CycleCloser, SimpleHeatExchanger, Valve
    from tespy.connections import Connection
    from tespy.networks import Network

    res = cycle_at(T_e, T_c, NO_SUCTION_DROP)
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
    g = (res.m_r / cfg.m_r0) ** cfg.n_r  # refrigerant-side UA scales with the flow
    assert res.Q_e == pytest.approx(cfg.UA_er0 * g * (T_ew - res.T_e), rel=1e-4)
    assert res.Q_c == pytest.approx(cfg.UA_cr0 * g * (res.T_c - T_cw), rel=1e-4)
    # first law of the cycle: Q_c = Q_e + compressor fluid power
    assert res.Q_c == pytest.approx(res.Q_e + res.W_comp, rel=1e-9)
    assert res.P_comp > res.W_comp  # inverter + motor losses
    assert res.T_s == pytest.approx(res.T_e - cfg.dT_suc0 * (res.m_r / cfg.m_r0) ** 2, abs=1e-3)
    assert 0.2 <= res.eta_is <= cfg.eta_is_max and 0.05 <= res.eta_v <= cfg.eta_v0


def test_warm_start_converges_in_few_iterations():
    solve, _ = make_solver(PlantConfig())
    T_e, T_c, *_ = solve(5000.0, 278.15, 315.0, 270.0, 320.0)
    out = solve(5050.0, 278.2, 315.05, T_e, T_c)
    assert out[-1] <= 4
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


def test_compressor_map_part_load_and_speed():
    """Issue 9 item 2: leakage lowers eta_v at low speed; eta_is is lowest at low speed and
    falls a little at N_max; the inverter + motor is least efficient at light load."""
    cfg = PlantConfig()
    lo, mid, hi = (cycle_at(275.15, 318.15, cfg, N=N) for N in (1000.0, 4000.0, 8000.0))
    assert lo.eta_v < mid.eta_v < hi.eta_v
    assert lo.eta_is < hi.eta_is < mid.eta_is
    assert mid.eta_is - lo.eta_is > 0.08  # 10-20 points lower below 1500 rpm (PLANT.md)
    assert 0.02 < mid.eta_is - hi.eta_is < 0.08
    assert lo.eta_motor < 0.86 and hi.eta_motor > 0.9
