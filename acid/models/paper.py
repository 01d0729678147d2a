"""The paper's control-oriented model (Wang et al., ACC 2018, eqs. 1-5) as a declaration.

Kelvin, kg/s, W; Ts = 5 s; values from the claims registry (``acid.claims.MODEL``, the one
place the paper's numbers are written). Eq. 1 reads the output T_ain: simulating, eq. 3 is
substituted; fitting by equation error, the measured T_ain is (as the paper does). Eq. 4
(compressor power from a fixed COP) is the controller's cost, not an identified equation:
``compressor_power`` below, and ``estimate_eta_cop`` reads its COP off P_comp.
"""

from __future__ import annotations

import math

import numpy as np

from acid.models.declaration import Constant, Constraint, Model, Parameter, Signal, State
from acid.paper import MODEL as _PAPER
from acid.paper import TABLE_II as _TABLE_II

#: (name, unit, meaning) of every parameter, in the order of the table.
PARAMETER_TABLE: tuple[tuple[str, str, str], ...] = (
    ("gamma1", "1", "cabin air <- interior conductance per step (eq. 1)"),
    ("gamma2", "1", "cabin air <- shell conductance per step (eq. 1)"),
    ("gamma3", "s/kg", "cabin air <- inlet air, per unit blower flow (eq. 1)"),
    ("gamma4", "1", "evaporator wall memory (eq. 2)"),
    ("gamma5", "1", "evaporator wall <- set-point error gain (eq. 2)"),
    ("gamma6", "1", "inlet air <- evaporator wall (eq. 3)"),
    ("gamma7", "K s/kg", "inlet air <- blower flow (eq. 3)"),
    ("tau1", "K", "cabin air offset (eq. 1)"),
    ("tau2", "K", "evaporator wall offset (eq. 2)"),
    ("tau3", "K", "inlet air offset (eq. 3)"),
    ("beta1", "W s^2/kg^2", "blower power, quadratic (eq. 5)"),
    ("beta2", "W s/kg", "blower power, linear (eq. 5)"),
    ("beta3", "W", "blower power, constant (eq. 5)"),
)
# physical signs (heat flows from warm to cold, a higher set-point warms the wall) that
# --method cvx imposes; the rest are unbounded
_BOUNDS = {"gamma1": (0.0, math.inf), "gamma2": (0.0, math.inf), "gamma3": (0.0, math.inf),
           "gamma5": (-math.inf, 0.0), "gamma6": (0.0, math.inf), "gamma7": (0.0, math.inf),
           "beta1": (0.0, math.inf)}
_VALUES = (*_PAPER.gamma, *_PAPER.tau, *_PAPER.beta)
#: Table II's range of the blower flow W_bl (kg/s) over which the cabin pole is checked.
W_BL_RANGE = (_TABLE_II.W_bl_min, _TABLE_II.W_bl_max)
#: Operating point at which steady temperatures are checked for plausibility (K, kg/s).
CHECK_T_EVAP_SET, CHECK_W_BL = 278.15, 0.1
#: A steady temperature outside this range (K) means parameters in another convention.
PLAUSIBLE_STEADY_K = (200.0, 400.0)
#: --method cvx keeps the evaporator pole in [0, 1 - margin]: stable, not oscillating.
EVAP_POLE_MARGIN = 1e-3


def step(s):
    T_ain = s.T_ain  # eq. 3 below when simulating, the measured T_ain when fitting
    return {
        # eq. 1: cabin air
        "T_cab": (s.T_cab + s.gamma1 * (s.T_int - s.T_cab) + s.gamma2 * (s.T_shell - s.T_cab)
                  + s.gamma3 * (T_ain - s.T_cab) * s.W_bl + s.tau1),
        # eq. 2: evaporator wall
        "T_evap": s.gamma4 * s.T_evap + s.gamma5 * (s.T_evap - s.T_evap_set) + s.tau2,
    }


def output(s):
    return {
        # eq. 3: inlet (supply) air
        "T_ain": s.gamma6 * s.T_evap + s.gamma7 * s.W_bl + s.tau3,
        # eq. 5: blower power
        "P_bl": s.beta1 * s.W_bl * s.W_bl + s.beta2 * s.W_bl + s.beta3,
    }


def plausibility(s) -> list[str]:
    """Why eqs. 1-3 with the values ``s`` are unstable or not in kelvin (empty if fine).

    * eq. 2: T_evap(k+1) = (gamma4 + gamma5) T_evap(k) + ...: needs |gamma4 + gamma5| < 1;
    * eq. 1: the cabin pole 1 - gamma1 - gamma2 - gamma3 W_bl must lie inside the unit
      circle over Table II's W_bl range (linear in W_bl, so both ends suffice);
    * the steady T_evap at a 5 degC set-point and eq. 3's T_ain there at 0.1 kg/s must be
      temperatures in kelvin (200-400 K): parameters fitted in degC fail this.
    """
    a_evap = s.gamma4 + s.gamma5
    if not abs(a_evap) < 1.0:
        return [f"eq. 2 is unstable: gamma4 + gamma5 = {a_evap:.6g}, needs "
                "|gamma4 + gamma5| < 1"]
    for W in W_BL_RANGE:
        pole = 1.0 - s.gamma1 - s.gamma2 - s.gamma3 * W
        if not abs(pole) < 1.0:
            return [f"eq. 1 is unstable: the cabin pole 1 - gamma1 - gamma2 - gamma3 W_bl = "
                    f"{pole:.6g} at W_bl = {W:g} kg/s lies outside the unit circle (gamma1, "
                    "gamma2, gamma3)"]
    lo, hi = PLAUSIBLE_STEADY_K
    T_evap = (s.tau2 - s.gamma5 * CHECK_T_EVAP_SET) / (1.0 - a_evap)
    T_ain = s.gamma6 * T_evap + s.gamma7 * CHECK_W_BL + s.tau3
    for name, value, keys in (("steady T_evap", T_evap, "gamma4, gamma5, tau2"),
                              ("eq. 3 T_ain", T_ain, "gamma6, gamma7, tau3")):
        if not (math.isfinite(value) and lo <= value <= hi):
            return [f"{name} = {value:.6g} K at a 5 degC set-point and W_bl = {CHECK_W_BL:g} "
                    f"kg/s is not a plausible temperature in kelvin ({keys})"]
    return []


model = Model(
    "paper",
    states=[State("T_cab", "K", description="cabin air"),
            State("T_evap", "K", description="evaporator wall")],
    inputs=[Signal("W_bl", "kg/s", "blower air flow"),
            Signal("T_evap_set", "K", "evaporator wall set-point")],
    disturbances=[Signal("T_int", "K", "interior"), Signal("T_shell", "K", "shell")],
    outputs=[Signal("T_ain", "K", "inlet air"), Signal("P_bl", "W", "blower power")],
    parameters=[Parameter(name, unit, value, *_BOUNDS.get(name, (-math.inf, math.inf)),
                          description=meaning)
                for (name, unit, meaning), value in zip(PARAMETER_TABLE, _VALUES, strict=True)],
    # eq. 4 (the controller's cost): a parameter file may give the COP read off P_comp
    constants=[Constant("c_p", _TABLE_II.c_p, "J/(kg K)", "specific heat of air (Table II)",
                        900.0, 1100.0),
               Constant("eta_cop", _TABLE_II.eta_cop, "1", "COP of eq. 4 (Table II)",
                        0.1, 50.0)],
    constraints=[Constraint(lambda s: s.gamma4 + s.gamma5, 0.0, 1.0 - EVAP_POLE_MARGIN,
                            "stable, non-oscillating evaporator pole"),
                 Constraint(lambda s: s.beta1 * s.W_bl**2 + s.beta2 * s.W_bl + s.beta3, 0.0,
                            description="P_bl >= 0 over the measured W_bl range")],
    Ts=_TABLE_II.Ts, step=step, output=output, checks=plausibility,
    description="Wang et al., ACC 2018, eqs. 1-3 and 5 (kelvin convention)",
)


def compressor_power(W_bl, T_ain, T_amb, c_p, eta_cop):
    """Eq. 4: P_c = c_p / eta_cop * W_bl * (T_amb - T_ain), W (numpy or CasADi alike;
    ``eta_cop`` a scalar, an array per stage or a symbol; c_p in J/(kg K))."""
    return c_p * W_bl * (T_amb - T_ain) / eta_cop


def estimate_eta_cop(W_bl, T_ain, T_amb, P_comp, c_p: float) -> tuple[float, float]:
    """eta_cop and its standard error from P_comp = c_p / eta_cop W_bl (T_amb - T_ain)
    (eq. 4), a regression through the origin over the samples with the compressor running
    and warm ambient air (kg/s, K, W); NaN when fewer than 10 samples qualify."""
    x = compressor_power(np.asarray(W_bl), np.asarray(T_ain), np.asarray(T_amb), c_p, 1.0)
    y = np.asarray(P_comp)
    use = (y > 1.0) & (x > 1.0)
    if use.sum() < 10:
        return math.nan, math.nan
    x, y = x[use], y[use]
    slope = float(x @ y / (x @ x))
    if slope <= 0:
        return math.nan, math.nan
    r = y - slope * x
    se_slope = math.sqrt(float(r @ r) / (x.size - 1) / float(x @ x))
    return 1.0 / slope, se_slope / slope**2


#: Where the paper's model plant starts (K): a hot-soaked cabin, the disturbances held.
PLANT_INITIAL = {"T_cab": 308.15, "T_evap": 281.15, "T_int": 308.15, "T_shell": 311.15}


