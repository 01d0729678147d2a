"""``heating`` reduced to what the winter trips identify: ``--model car_heat2`` (a
structure-selection candidate, ``acid car select``).

Fitted on the BMW i3 winter trips, ``heating`` leaves ``C_cab``, ``G_hi``, ``G_vent`` and
some trips' ``Q_occ`` on their bounds, and the standard errors of ``C_shell``, every ``UA`` and
every ``Q_occ`` exceed their values. This candidate keeps ``heating``'s coolant loop, automatic
blower and outlet air (what the logs see), and drops what they do not:

* the interior and the shell are one lumped mass ``T_m`` (their capacities and films appeared
  only in combinations);
* no separate fresh-air path ``G_vent`` (it ended on a bound; the cabin loses to the ambient
  through the mass);
* one occupant and sun load ``Q_occ`` for every trip (not one per trip, which a trip the fit
  never saw cannot have anyway: it got the mean), with a prior.

Heat flows (W), the rest as in ``heating``::

    T_hc   = T_cool + eta_heater P_heater / G_cool
    G_hc   = G_lo + (G_hi - G_lo) sat((T_cool - T_c0) / dT_w)
    Q_hc   = G_hc (T_hc - T_cab)
    Q_m    = UA_m (T_m - T_cab)
    Q_out  = (UA_out + UA_out_v v) (T_amb - T_m)
    C_cool dT_cool/dt = eta_heater P_heater - Q_hc - UA_cool (T_cool - T_amb)
    C_cab dT_cab/dt   = Q_hc + Q_m + Q_occ
    C_m dT_m/dt       = Q_out - Q_m
    tau_sup dT_ain/dt = T_cab + eps_sup (T_hc - T_cab) - T_ain

Priors (mean, sd), from the cited ranges (``acid/models/SOURCES.md``): ``C_cab`` 10 +- 5 kJ/K
(about 3 kJ/K of cabin air and the trims that follow it [Marcos2014, TorregrosaJaime2015]),
``C_m`` 140 +- 70 kJ/K (interior 20-200 and shell 20-300 kJ/K [Fayazbakhsh2013,
TorregrosaJaime2015]), ``Q_occ`` 150 +- 150 W (one or two occupants at ~100 W each and a low
winter sun [Fayazbakhsh2013, Marcos2014]), ``UA_m`` 160 +- 80 W/K (the interior's and inner
shell's films in parallel [Fayazbakhsh2013]). The coolant and blower ranges are
``heating``'s (``datasets/plant/SOURCES.md``: Steinstraeter2020, Wang2018, ChangWang1997).
"""

import casadi as ca
import numpy as np

from acid.models import RK4, Model, Parameter, State
from acid.models.heating import model as HEATING


def ode(s):
    t_hc = s.T_cool + s.eta_heater * s.P_heater / s.G_cool
    x = ca.fmin(ca.fmax((s.T_cool - s.T_c0) / s.dT_w, 0.0), 1.0)
    q_hc = (s.G_lo + (s.G_hi - s.G_lo) * x) * (t_hc - s.T_cab)
    q_m = s.UA_m * (s.T_m - s.T_cab)
    q_out = (s.UA_out + s.UA_out_v * s.v_veh) * (s.T_amb - s.T_m)
    q_loss = s.UA_cool * (s.T_cool - s.T_amb)
    return {
        "T_cool": (s.eta_heater * s.P_heater - q_hc - q_loss) / (1e3 * s.C_cool),
        "T_cab": (q_hc + q_m + s.Q_occ) / (1e3 * s.C_cab),
        "T_ain": (s.T_cab + s.eps_sup * (t_hc - s.T_cab) - s.T_ain) / s.tau_sup,
        "T_m": (q_out - q_m) / (1e3 * s.C_m),
    }


def _mass_start(m):
    # heating's interior (the colder of cabin and outlets after a cold soak) and its shell
    # (half-way to the ambient), lumped: three quarters of the way from ambient
    inner = np.minimum(m.T_cab, m.T_ain)
    return 0.75 * inner + 0.25 * m.T_amb


_h = {p.name: p for p in HEATING.parameters}
_KEPT = ("C_cool", "G_lo", "G_hi", "T_c0", "dT_w", "eps_sup", "tau_sup", "UA_out", "UA_out_v",
         "UA_cool", "G_cool", "eta_heater")

model = Model(
    "car_heat2",
    states=[*(s for s in HEATING.states if s.name in ("T_cool", "T_cab", "T_ain")),
            State("T_m", "K", measured=False, initial=_mass_start,
                  description="interior, shell, glazing and trim, one lumped mass; not logged")],
    inputs=list(HEATING.inputs),
    disturbances=list(HEATING.disturbances),
    parameters=[
        _h["C_cool"],
        Parameter("C_cab", "kJ/K", 10.0, 3.0, 40.0, prior=(10.0, 5.0),
                  description="cabin air and trims"),
        Parameter("C_m", "kJ/K", 140.0, 40.0, 500.0, prior=(140.0, 70.0),
                  description="interior and shell, lumped"),
        *(_h[n] for n in _KEPT if n != "C_cool"),
        Parameter("UA_m", "W/K", 160.0, 20.0, 600.0, prior=(160.0, 80.0),
                  description="interior and inner shell surfaces <-> cabin air"),
        Parameter("Q_occ", "W", 150.0, -300.0, 1500.0, prior=(150.0, 150.0),
                  description="occupants and sun into the cabin, one value for every trip"),
    ],
    Ts=HEATING.Ts, ode=ode, integrator=RK4(substeps=2),
    description="cabin heating from logged channels: coolant, cabin air, supply air; one "
                "latent mass, one load",
)
