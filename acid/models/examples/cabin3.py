"""A three-state cabin: cabin air, a lumped interior node no sensor measures, the evaporator wall.

An example of a model file (``acid fit DATA --model cabin3.py``): continuous time, RK4,
physical parameters with units and ranges, one latent state and one per-experiment
parameter (the solar and internal load, which differs between recordings).

Ranges: the cabin air of a compact car is about 3 kg (2.5 m^3), 3 kJ/K, plus the fast
trims it exchanges heat with; interiors (seats, dash, panels, 40-80 kg at 1-1.5 kJ/(kg K))
store 40-120 kJ/K; the body's overall conductance to ambient is 30-150 W/K (Fayazbakhsh &
Bahrami 2013, SAE 2013-01-1507, cabin load model; Marcos et al. 2014, Appl. Therm. Eng.
70:1172); a solar load of 0-1500 W (1000 W/m^2 on ~1.5 m^2 of glazing, part absorbed).
"""

from acid.models import RK4, Constant, Model, Parameter, Signal, State


def ode(s):
    Q_int = s.UA_int * (s.T_int_lumped - s.T_cab)                 # interior -> cabin air, W
    return {
        "T_cab": (Q_int + s.UA_amb * (s.T_amb - s.T_cab)
                  + s.W_bl * s.c_p * (s.T_ain - s.T_cab)) / (1e3 * s.C_cab),
        "T_int_lumped": (s.Q_sol - Q_int) / (1e3 * s.C_int),
        "T_evap": (s.T_evap_set + s.dT_evap - s.T_evap) / s.tau_evap,
    }


def output(s):
    # supply air: the coil's bypass share of the recirculated cabin air, plus blower heat
    return {"T_ain": s.T_evap + s.bypass * (s.T_cab - s.T_evap) + s.dT_fan}


model = Model(
    "cabin3",
    states=[State("T_cab", "K", description="cabin air"),
            State("T_int_lumped", "K", measured=False, initial=lambda m: m.T_cab,
                  description="seats, dash and panels, lumped; started at the cabin air"),
            State("T_evap", "K", description="evaporator wall")],
    inputs=[Signal("W_bl", "kg/s", "blower air flow"),
            Signal("T_evap_set", "K", "evaporator wall set-point")],
    disturbances=[Signal("T_amb", "K", "ambient air")],
    outputs=[Signal("T_ain", "K", "supply air")],
    parameters=[
        Parameter("C_cab", "kJ/K", 10.0, 2.0, 60.0, description="cabin air and trims"),
        Parameter("C_int", "kJ/K", 60.0, 10.0, 300.0, description="interior, lumped"),
        Parameter("UA_int", "W/K", 150.0, 5.0, 1000.0, description="interior <-> cabin air"),
        Parameter("UA_amb", "W/K", 60.0, 5.0, 300.0, description="body <-> ambient"),
        Parameter("tau_evap", "s", 20.0, 1.0, 300.0, description="evaporator wall lag"),
        Parameter("dT_evap", "K", 0.0, -10.0, 10.0, description="wall offset from set-point"),
        Parameter("bypass", "1", 0.1, 0.0, 1.0, description="coil bypass share"),
        Parameter("dT_fan", "K", 0.5, -5.0, 5.0, description="blower heat in the supply air"),
        Parameter("Q_sol", "W", 400.0, -500.0, 3000.0, per_experiment=True,
                  description="solar and internal load into the interior"),
    ],
    constants=[Constant("c_p", 1008.0, "J/(kg K)", "specific heat of air (Table II)")],
    Ts=5.0, ode=ode, integrator=RK4(substeps=2), output=output,
    description="three-state cabin: air, lumped interior (latent), evaporator wall",
)
