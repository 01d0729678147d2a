"""The econ model family (``acid.econ.model``) as a declaration.

Five states (cabin air, interior, shell, evaporator wall, cabin humidity), continuous time
integrated by the model's own RK4 (``acid.econ.model.step``, one 5 s sub-step), so the
equations are the existing functions, traced once with CasADi symbols. Outputs are interval
means: the supply air T_ain, the compressor power map at the refrigerant heat (``P_comp``,
unclipped as in the NLPs) and the blower power (paper eq. 5). Values: a start of the size
identified on acid's high-fidelity plant (``acid fit --model econ`` identifies them).
"""

from __future__ import annotations

from types import SimpleNamespace

from acid.econ import model as econ
from acid.econ.fit import _BOUNDS
from acid.econ.params import CONSTANTS, MAP_TERMS, PARAMETER_TABLE
from acid.models.declaration import Constant, Model, Parameter, Signal, State
from acid.params import PAPER_BETA
from acid.params import PARAMETER_TABLE as PAPER_TABLE

TS = 5.0
_START = {"r_max": 0.8, "k_rec": 0.1, "ntu_ref": 2.75, "ntu_exp": 0.4, "kappa_bl": 0.1,
          "C_cab": 4500.0, "hA_int": 190.0, "hA_sh": 67.0, "Q_cab": 80.0, "C_int": 65000.0,
          "Q_int": 350.0, "C_sh": 65000.0, "hA_ext0": 60.0, "hA_ext_v": 9.0, "Q_sh": 900.0,
          "tau_ew": 11.0, "dT_ew": 0.1, "M_cab": 3.7, "m_w": 1.4e-5, "RH_amb": 0.5}
_MAP_START = (0.155, 0.051, -0.029, -0.006, 0.05, -0.004, -0.01, -0.0015, 0.0027, 0.0022,
              0.0005, -0.005, 0.0014, -0.0015, -0.0052)
#: parameter names of the power-map coefficients, ``MAP_TERMS`` order ("q t" -> "f_qt")
MAP_NAMES = tuple("f_" + t.replace("^2", "2").replace(" ", "") for t in MAP_TERMS)


def params_namespace(s) -> SimpleNamespace:
    """What ``acid.econ.model`` reads (attributes of ``EconParams``) from the namespace."""
    return SimpleNamespace(**{n: s[n] for n, _, _ in PARAMETER_TABLE}, C_ew=s.C_ew,
                           power_map=SimpleNamespace(coef=[s[n] for n in MAP_NAMES]),
                           beta=(s.beta1, s.beta2, s.beta3), c_p=s.c_p, h_fg=s.h_fg,
                           p_atm=s.p_atm)


def step(s):
    p = params_namespace(s)
    x = (s.T_cab, s.T_int, s.T_shell, s.T_evap, s.w_cab)
    r = econ.step(x, (s.W_bl, s.T_evap_set), (s.v_veh, s.T_amb), p, TS)
    Q_e = econ.refrigerant_heat(r.Q_coil, s.T_evap, r.x[3], TS, p)
    return {**dict(zip(econ.STATES, r.x, strict=True)), "T_ain": r.T_ain,
            "P_comp": econ.compressor_power(Q_e, r.T_evap, s.v_veh, s.T_amb, p.power_map),
            "P_bl": econ.blower_power(s.W_bl, p)}


model = Model(
    "econ",
    states=[State(n, u) for n, u in zip(econ.STATES, econ.STATE_UNITS, strict=True)],
    inputs=[Signal("W_bl", "kg/s"), Signal("T_evap_set", "K")],
    disturbances=[Signal("v_veh", "m/s"), Signal("T_amb", "K")],
    outputs=[Signal("T_ain", "K"), Signal("P_comp", "W"), Signal("P_bl", "W")],
    parameters=(
        [Parameter(n, u, _START[n], *_BOUNDS[n], description=m) for n, u, m in PARAMETER_TABLE]
        + [Parameter("C_ew", "J/K", 2000.0, 0.0, 5e4,
                     description="evaporator wall capacity in the refrigerant heat")]
        + [Parameter(n, "1", c, description=f"inverse-COP map term {t}")
           for n, c, t in zip(MAP_NAMES, _MAP_START, MAP_TERMS, strict=True)]
        + [Parameter(n, u, b, description=m)
           for (n, u, m), b in zip(PAPER_TABLE[-3:], PAPER_BETA, strict=True)]),
    constants=[Constant(n, v, u, src) for n, v, u, src in CONSTANTS if n != "W_REF"],
    Ts=TS, step=step,
    description="acid's economic model: cabin, interior, shell, evaporator wall, humidity",
)
