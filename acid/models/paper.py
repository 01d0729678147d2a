"""The paper's control-oriented model (Wang et al., ACC 2018, eqs. 1-3 and 5) as a declaration.

Kelvin, kg/s, W; Ts = 5 s; values from ``acid.params.paper()`` (``acid.claims``). Eq. 1 reads
the output T_ain: simulating, eq. 3 is substituted; fitting by equation error, the measured
T_ain is (as the paper does). Eq. 4 (compressor power from a fixed COP) is the controller's
cost, not an identified equation; it stays in ``acid.model.compressor_power``.
"""

from __future__ import annotations

import math

from acid.models.declaration import Model, Parameter, Signal, State
from acid.params import PARAMETER_TABLE, paper

_P = paper()
# physical signs (heat flows from warm to cold, a higher set-point warms the wall), the
# ones the constrained fit of acid.fit imposes; the rest are unbounded
_BOUNDS = {"gamma1": (0.0, math.inf), "gamma2": (0.0, math.inf), "gamma3": (0.0, math.inf),
           "gamma5": (-math.inf, 0.0), "gamma6": (0.0, math.inf), "gamma7": (0.0, math.inf),
           "beta1": (0.0, math.inf)}


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
                for (name, unit, meaning), value in zip(PARAMETER_TABLE, _P.theta,
                                                        strict=True)],
    Ts=_P.Ts, step=step, output=output,
    description="Wang et al., ACC 2018, eqs. 1-3 and 5 (kelvin convention)",
)
