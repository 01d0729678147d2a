"""car_heat3 with the filter's noises declared (estimated by PEM): each state's random
increment per sample and each logged state's sensor noise (a model file:
``acid fit est_w.h5 --model benchmarks/winter_pem/car_heat3n.py --method pem``).

``car_heat3`` declares no noise, so its prediction-error fit runs the filter with no process
noise (normalised innovations' std 25.9 on the winter estimation trips) and the
``--warm-start ekf-trip`` of ``acid validate`` has no fitted noise to work with. The noises'
ranges: a sensor of 0.005-2 K, a random increment per 5 s sample of 1e-4-2 K."""
import dataclasses

from acid.models import RK4, Model, Parameter
from acid.models.car_heat3 import model as H3
from acid.models.car_heat3 import ode

NOISE = {"T_cool": ("sigma_cool", "sigma_ycool"), "T_cab": ("sigma_cab", "sigma_ycab"),
         "T_ain": ("sigma_ain", "sigma_yain"), "T_m": ("sigma_m", None)}
states = []
extra = []
for s in H3.states:
    q, r = NOISE[s.name]
    states.append(dataclasses.replace(s, noise=q, sensor=r if s.measured else None))
    extra.append(Parameter(q, "K", 0.05, 1e-4, 2.0, fixed=True,
                           description=f"{s.name}'s random increment per sample"))
    if r is not None and s.measured:
        extra.append(Parameter(r, "K", 0.1, 0.005, 2.0, fixed=True,
                               description=f"{s.name}'s sensor noise"))

model = Model("car_heat3n", states=states, inputs=list(H3.inputs),
              disturbances=list(H3.disturbances), outputs=list(H3.outputs),
              constants=list(H3.constants), parameters=list(H3.parameters) + extra,
              Ts=H3.Ts, ode=ode, integrator=RK4(substeps=2),
              description="car_heat3 with the filter's noises")
