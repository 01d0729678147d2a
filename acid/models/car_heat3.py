"""Cabin heating through the air the outlets deliver: ``--model car_heat3`` (a
structure-selection candidate, ``acid car select --season winter``).

``heating`` and ``car_heat2`` heat the cabin air straight from the heater core
(``G_hc (T_hc - T_cab)``) and read the outlets' air as a separate output lagging the core:
the cabin warms before the air that warms it has left the ducts, and the fresh air the unit
draws is a separate path (``G_vent``) or none. Here the heat follows the air as an
automatic unit moves it: the blower draws a mix of cabin and outside air, the heater core
heats it, the ducts deliver it at the outlets (logged, ``T_ain``) with their lag, and it
leaves the cabin at the cabin's temperature:

    T_mix  = T_cab + f_fresh (T_amb - T_cab)                air at the heater core's inlet
    T_hc   = T_cool + eta_heater P_heater / G_cool          coolant at the heater core
    W      = W_lo + (W_hi - W_lo) sat((T_cool - T_c0) / dT_w)    blower air x c_p (W/K)
    Q_core = eps_core W (T_hc - T_mix)                      coolant -> air at the core
    Q_sup  = W (T_ain - T_cab)                              supply air -> cabin, net of
                                                            the air that leaves it
    Q_m    = UA_m (T_m - T_cab)
    Q_out  = (UA_out + UA_out_v v) (T_amb - T_m)
    C_cool dT_cool/dt = eta_heater P_heater - Q_core - UA_cool (T_cool - T_amb)
    tau_sup dT_ain/dt = T_mix + Q_core / W - T_ain          ducts and outlet sensors
    C_cab dT_cab/dt   = Q_sup + Q_m + Q_occ
    C_m dT_m/dt       = Q_out - Q_m

so the heater's power reaches the cabin with the ducts' lag, the fresh-air share costs
``f_fresh W (T_cab - T_amb)`` in the steady state (no separate vent path), and one
effectiveness ``eps_core`` sets both what the coolant gives and what the outlets read.

Ranges and priors (``acid/models/SOURCES.md``, ``datasets/plant/SOURCES.md``): blower air
0.01-0.15 kg/s [Wang2018 Table II, Fayazbakhsh2013] at 1.008 kJ/(kg K): ``W_lo``, ``W_hi``
10-160 W/K; heater-core effectiveness 0.4-0.9 [Steinstraeter2020, ChangWang1997] (range
0.2-1 as ``heating``'s ``eps_sup``); fresh-air share of an automatic unit in winter 0-1
(recirculation to full fresh air; defaults to fresh air against fogging [Ott2008]), prior
0.5 +- 0.3; ``C_cab``, ``C_m``, ``UA_m``, ``Q_occ`` with ``car_heat2``'s cited priors; the
coolant, blower-switch, shell and duct values are ``heating``'s.
"""

import casadi as ca

from acid.models import RK4, Model, Parameter
from acid.models.car_heat2 import model as HEAT2


def _blower(s):
    x = ca.fmin(ca.fmax((s.T_cool - s.T_c0) / s.dT_w, 0.0), 1.0)
    return s.W_lo + (s.W_hi - s.W_lo) * x


def ode(s):
    t_mix = s.T_cab + s.f_fresh * (s.T_amb - s.T_cab)
    t_hc = s.T_cool + s.eta_heater * s.P_heater / s.G_cool
    w = _blower(s)
    q_core = s.eps_core * w * (t_hc - t_mix)
    q_m = s.UA_m * (s.T_m - s.T_cab)
    q_out = (s.UA_out + s.UA_out_v * s.v_veh) * (s.T_amb - s.T_m)
    q_loss = s.UA_cool * (s.T_cool - s.T_amb)
    return {
        "T_cool": (s.eta_heater * s.P_heater - q_core - q_loss) / (1e3 * s.C_cool),
        "T_cab": (w * (s.T_ain - s.T_cab) + q_m + s.Q_occ) / (1e3 * s.C_cab),
        "T_ain": (t_mix + s.eps_core * (t_hc - t_mix) - s.T_ain) / s.tau_sup,
        "T_m": (q_out - q_m) / (1e3 * s.C_m),
    }


_h = {p.name: p for p in HEAT2.parameters}

model = Model(
    "car_heat3",
    states=list(HEAT2.states),
    inputs=list(HEAT2.inputs),
    disturbances=list(HEAT2.disturbances),
    parameters=[
        _h["C_cool"], _h["C_cab"], _h["C_m"],
        Parameter("W_lo", "W/K", 30.0, 10.0, 160.0,
                  description="blower air x c_p at its lowest level"),
        Parameter("W_hi", "W/K", 90.0, 10.0, 160.0,
                  description="blower air x c_p at its highest level"),
        _h["T_c0"], _h["dT_w"],
        Parameter("eps_core", "1", 0.6, 0.2, 1.0,
                  description="heater-core effectiveness (coolant to air)"),
        _h["tau_sup"],
        Parameter("f_fresh", "1", 0.5, 0.0, 1.0, prior=(0.5, 0.3),
                  description="fresh-air share of the blower's air"),
        _h["UA_m"], _h["UA_out"], _h["UA_out_v"], _h["UA_cool"], _h["G_cool"],
        _h["eta_heater"], _h["Q_occ"],
    ],
    Ts=HEAT2.Ts, ode=ode, integrator=RK4(substeps=2),
    description="cabin heating through the supply air: coolant, heater core, ducts, cabin "
                "air; one latent mass, one load",
)
