"""``car_heat3`` with the filter's noises declared: ``--model car_heat3n`` (a winter
structure-selection candidate, ``acid car select --season winter``; fitted by prediction
error, ``acid fit --model car_heat3n --method pem``).

The physics, parameters, ranges and priors are ``car_heat3``'s (see its module text). What
is added are the noises of the Kalman filter that the prediction-error fit and the
``ekf-trip`` warm start run: each state's random increment per 5 s sample (``sigma_cool``,
``sigma_cab``, ``sigma_ain``, ``sigma_m``: what the ODE does not explain, e.g. the sun, the
doors, passengers, the heater's controller) and each logged state's sensor noise
(``sigma_ycool``, ``sigma_ycab``, ``sigma_yain``). No published value fixes them for this
car: they are **fitted** by PEM (declared ``fixed`` so that an output-error fit, which has no
use for them, leaves them alone; PEM estimates them). Their ranges are wide on purpose: a
sensor noise of 0.005-2 K (up to an outlet sensor in a mixed, unsteady air stream) and a
random increment of 1e-4-2 K per sample; the nominal values (0.1 K
sensor, 0.05 K per sample) are only the starts.

Without them ``car_heat3``'s prediction-error fit runs the filter with no process noise: on
the winter estimation trips its normalised innovations have a standard deviation of 26
(instead of 1), the likelihood is a poor one and its Newton phase does not converge; with
them the same fit ends with innovations of standard deviation 1.0.
"""

import dataclasses

from acid.models import RK4, Model, Parameter
from acid.models.car_heat3 import model as HEAT3
from acid.models.car_heat3 import ode

#: state -> (its random increment per sample, its sensor noise or None if not logged)
NOISES = {"T_cool": ("sigma_cool", "sigma_ycool"), "T_cab": ("sigma_cab", "sigma_ycab"),
          "T_ain": ("sigma_ain", "sigma_yain"), "T_m": ("sigma_m", None)}

_states = []
_noises = []
for _s in HEAT3.states:
    _q, _r = NOISES[_s.name]
    _states.append(dataclasses.replace(_s, noise=_q, sensor=_r if _s.measured else None))
    _noises.append(Parameter(_q, "K", 0.05, 1e-4, 2.0, fixed=True,
                             description=f"{_s.name}'s random increment per sample "
                                         "(fitted by PEM)"))
    if _r is not None and _s.measured:
        _noises.append(Parameter(_r, "K", 0.1, 0.005, 2.0, fixed=True,
                                 description=f"{_s.name}'s sensor noise (fitted by PEM)"))

model = Model(
    "car_heat3n", states=_states, inputs=list(HEAT3.inputs),
    disturbances=list(HEAT3.disturbances), outputs=list(HEAT3.outputs),
    constants=list(HEAT3.constants), parameters=list(HEAT3.parameters) + _noises,
    Ts=HEAT3.Ts, ode=ode, integrator=RK4(substeps=2),
    description="car_heat3 with the Kalman filter's process and sensor noises (fitted by "
                "PEM)",
)
