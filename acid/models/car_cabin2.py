"""``car_cabin`` with two thermal nodes: ``--model car_cabin2`` (a structure-selection
candidate, ``acid car select``).

The same logged channels as ``car_cabin`` (cabin air, evaporator air, ambient, speed) and the
same latent load, but the interior and the shell merged into one lumped mass: on the BMW i3
trips ``car_cabin``'s interior and shell appear only in combinations (several of their
parameters end on a bound, ``UA_out`` flips between its bounds when trips are added), so the
data may carry one slow node, not two::

    Q_sup  = G_sup (T_evap + dT_sup - T_cab)          supply air (blower level held)
    Q_m    = UA_m (T_m - T_cab)                        interior and shell -> cabin air
    Q_out  = (UA_out + UA_out_v v) (T_amb - T_m)       ambient -> shell (forced convection)

    C_cab dT_cab/dt = Q_sup + Q_m
    C_m dT_m/dt     = Q_out + Q_sol - Q_m
    dQ_sol/dt       = (Q_bar - Q_sol) / tau_Q  (+ noise sigma_Q)

Ranges (``acid/models/SOURCES.md``): ``C_cab``, ``G_sup``, ``UA_out``, ``UA_out_v`` and the
load as in ``car_cabin``; ``C_m`` the sum of the interior's and the shell's (20-200 and
20-300 kJ/K [Fayazbakhsh2013, Marcos2014, TorregrosaJaime2015]): 40-500 kJ/K; ``UA_m`` the
interior's and the inner shell's films in parallel (10-300 and 20-300 W/K): 30-600 W/K.
"""

from acid.models import RK4, Model, Parameter, State
from acid.models.car_cabin import Q_SOL_PRIOR, Q_SOL_SPREAD
from acid.models.car_cabin import model as CAR_CABIN


def ode(s):
    q_sup = s.G_sup * (s.T_evap + s.dT_sup - s.T_cab)
    q_m = s.UA_m * (s.T_m - s.T_cab)
    q_out = (s.UA_out + s.UA_out_v * s.v_veh) * (s.T_amb - s.T_m)
    return {
        "T_cab": (q_sup + q_m) / (1e3 * s.C_cab),
        "T_m": (q_out + s.Q_sol - q_m) / (1e3 * s.C_m),
        "Q_sol": (s.Q_bar - s.Q_sol) / s.tau_Q,
    }


def _between_cabin_and_ambient(m):
    return 0.5 * (m.T_cab + m.T_amb)


_SHARED = ("C_cab", "G_sup", "dT_sup", "UA_out", "UA_out_v", "Q_bar", "tau_Q", "sigma_cab",
           "sigma_y", "sigma_Q")
_cab = {p.name: p for p in CAR_CABIN.parameters}

model = Model(
    "car_cabin2",
    states=[State("T_cab", "K", description="cabin air (logged)", noise="sigma_cab",
                  sensor="sigma_y", spread=0.1),
            State("T_m", "K", measured=False, initial=_between_cabin_and_ambient,
                  description="interior and shell, one lumped mass; not logged"),
            State("Q_sol", "W", measured=False, initial=Q_SOL_PRIOR, noise="sigma_Q",
                  spread=Q_SOL_SPREAD,
                  description="solar and occupant load into the mass (not logged): returns "
                  "to Q_bar within tau_Q, driven by noise sigma_Q")],
    inputs=list(CAR_CABIN.inputs),
    disturbances=list(CAR_CABIN.disturbances),
    parameters=[
        _cab["C_cab"],
        Parameter("C_m", "kJ/K", 140.0, 40.0, 500.0,
                  description="interior and shell, lumped"),
        _cab["G_sup"], _cab["dT_sup"],
        Parameter("UA_m", "W/K", 160.0, 30.0, 600.0,
                  description="interior and inner shell surfaces <-> cabin air"),
        *(_cab[n] for n in _SHARED if n not in ("C_cab", "G_sup", "dT_sup")),
    ],
    Ts=CAR_CABIN.Ts, ode=ode, integrator=RK4(substeps=2),
    description="car cabin from logged channels: cabin air and one latent mass, latent load",
)
