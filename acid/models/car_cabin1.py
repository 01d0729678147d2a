"""``car_cabin`` with one thermal node: ``--model car_cabin1`` (a structure-selection
candidate, ``acid car select``).

The cabin air and everything that follows it (trims, seats, panels) as one capacity, fed by
the supply air, losing to the ambient through the shell, and heated by the latent solar and
occupant load of ``car_cabin``::

    C dT_cab/dt = G_sup (T_evap + dT_sup - T_cab) + (UA_out + UA_out_v v) (T_amb - T_cab) + Q_sol
    dQ_sol/dt   = (Q_bar - Q_sol) / tau_Q  (+ noise sigma_Q)

The smallest structure a cabin can have: one time constant ``C / (G_sup + UA)``; whatever
the slow interior and shell add is left to the load the filter follows. Ranges
(``acid/models/SOURCES.md``): ``G_sup``, ``UA_out``, ``UA_out_v``, the load as in
``car_cabin``; ``C`` from the cabin air alone (3 kJ/K) to air, trims and the interior that
follows within the trip (3-40 plus 20-200 kJ/K [Marcos2014, Fayazbakhsh2013]): 3-240 kJ/K.
"""

from acid.models import RK4, Model, Parameter, State
from acid.models.car_cabin import Q_SOL_PRIOR, Q_SOL_SPREAD
from acid.models.car_cabin import model as CAR_CABIN


def ode(s):
    q_sup = s.G_sup * (s.T_evap + s.dT_sup - s.T_cab)
    q_out = (s.UA_out + s.UA_out_v * s.v_veh) * (s.T_amb - s.T_cab)
    return {
        "T_cab": (q_sup + q_out + s.Q_sol) / (1e3 * s.C_cab),
        "Q_sol": (s.Q_bar - s.Q_sol) / s.tau_Q,
    }


_cab = {p.name: p for p in CAR_CABIN.parameters}

model = Model(
    "car_cabin1",
    states=[State("T_cab", "K", description="cabin air and what follows it (logged)",
                  noise="sigma_cab", sensor="sigma_y", spread=0.1),
            State("Q_sol", "W", measured=False, initial=Q_SOL_PRIOR, noise="sigma_Q",
                  spread=Q_SOL_SPREAD,
                  description="solar and occupant load into the cabin (not logged): returns "
                  "to Q_bar within tau_Q, driven by noise sigma_Q")],
    inputs=list(CAR_CABIN.inputs),
    disturbances=list(CAR_CABIN.disturbances),
    parameters=[
        Parameter("C_cab", "kJ/K", 40.0, 3.0, 240.0,
                  description="cabin air, trims and the interior that follows them"),
        *(_cab[n] for n in ("G_sup", "dT_sup", "UA_out", "UA_out_v", "Q_bar", "tau_Q",
                            "sigma_cab", "sigma_y", "sigma_Q")),
    ],
    Ts=CAR_CABIN.Ts, ode=ode, integrator=RK4(substeps=2),
    description="car cabin from logged channels: one node and a latent load",
)
