"""Two coupled tanks, declared for acid and identified from a laboratory's data (the
laboratory: the same physics integrated independently by SciPy, with sensor noise)."""

import numpy as np
from scipy.integrate import solve_ivp

import acid
from acid.models import RK4, Model, Parameter, Signal, State, sqrt

EPS = 1e-6   # m: sqrt guarded at an empty tank (smooth, finite derivative)

def ode(s):
    q1 = s.c1 * sqrt(s.h1 + EPS)                  # upper tank's outflow, m/s
    return {"h1": s.k * s.u - q1,
            "h2": s.c12 * q1 / s.c1 - s.c2 * sqrt(s.h2 + EPS)}

model = Model(
    "two_tanks",
    states=[State("h1", "m"), State("h2", "m")],
    inputs=[Signal("u", "V", "pump voltage")],
    parameters=[Parameter("k", "m/(V s)", 0.001, 0.0, 0.1),
                Parameter("c1", "m^0.5/s", 0.01, 0.0, 0.1),
                Parameter("c12", "m^0.5/s", 0.01, 0.0, 0.1),
                Parameter("c2", "m^0.5/s", 0.01, 0.0, 0.1)],
    Ts=4.0, ode=ode, integrator=RK4(substeps=2))

# the laboratory: scipy's integrator, a random staircase on the pump, 0.5 mm sensor noise
true = {"k": 0.0012, "c1": 0.009, "c12": 0.008, "c2": 0.007}
rng = np.random.default_rng(1)
Ts, n = 4.0, 1500
u = np.repeat(rng.uniform(2.0, 8.0, n // 25), 25)

def lab(t, h):
    q1 = true["c1"] * np.sqrt(max(h[0], 0.0) + EPS)
    return [true["k"] * u[min(int(t // Ts), n - 1)] - q1,
            true["c12"] * q1 / true["c1"] - true["c2"] * np.sqrt(max(h[1], 0.0) + EPS)]

sol = solve_ivp(lab, (0.0, n * Ts), [0.10, 0.10], t_eval=np.arange(n) * Ts, max_step=1.0)
h = sol.y + rng.normal(0.0, 5e-4, sol.y.shape)
data = acid.Dataset(time=np.arange(n) * Ts, channels={"h1": h[0], "h2": h[1], "u": u},
                    units={"h1": "m", "h2": "m", "u": "V"}, Ts=Ts)
est, val = data.split(0.5)
fit = acid.fit_model(model, est, method="oe")      # output error over windows, HAC errors
for e in fit.estimates:
    print(f"{e.name:4s} {e.value:.5f} +- {e.stderr:.1e}   (true {true[e.name]})")
print(acid.compare(val, fit).to_frame().round(1))   # fit % on the held-out half
