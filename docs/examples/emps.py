"""EMPS, the electro-mechanical positioning system benchmark (Janot, Gautier & Brunot, 2019):
a prismatic joint driven by a DC motor through a ball screw, under the benchmark's cascaded
position / velocity controller. Declared for acid, simulated with the benchmark's published
rigid-body model and parameter values (the "laboratory"), and identified back from two
records whose constant force offset differs, validated record by record."""

import numpy as np

import acid
from acid.models import RK4, Constant, Model, Parameter, Signal, State, smooth_sign

# ------------------------------------------------------------------ the declaration
GTAU, KP, KV = 35.15, 160.18, 243.45     # N/V, 1/s, V s/m: the benchmark's drive and gains
W = 0.0005                                # m/s: width of the smooth Coulomb friction

def force(s):                             # the controller's motor force, N
    return s.gtau * s.kv * (s.kp * (s.qg - s.q) - s.v)

def ode(s):
    friction = s.Fv * s.v + s.Fc * smooth_sign(s.v, W) + s.OFF
    return {"q": s.v, "v": (force(s) - friction) / s.M}

model = Model(
    "emps",
    states=[State("q", "m"),                                  # measured (the encoder)
            State("v", "m/s", measured=False, initial=0.0)],  # latent: estimated
    inputs=[Signal("qg", "m", "reference position")],
    outputs=[Signal("tau", "N", "motor force")],
    constants=[Constant("gtau", GTAU, "N/V"), Constant("kp", KP, "1/s"),
               Constant("kv", KV, "V*s/m")],
    parameters=[Parameter("M", "kg", 50.0, 1.0, 500.0),
                Parameter("Fv", "N*s/m", 100.0, 0.0, 1000.0),
                Parameter("Fc", "N", 10.0, 0.0, 100.0),
                Parameter("OFF", "N", 0.0, -50.0, 50.0, per_experiment=True)],
    Ts=0.01, ode=ode, integrator=RK4(substeps=4), output=lambda s: {"tau": force(s)})

# ------------------------------------- the laboratory: the published model, exact sign(v)
PUBLISHED = {"M": 95.1089, "Fv": 203.5034, "Fc": 20.3935, "OFF": -3.1648}
OFFSETS = (PUBLISHED["OFF"], 2.0)        # N: record 1's offset is ours (a moved cable)
rng = np.random.default_rng(7)
Ts, n = 0.01, 800                        # 8 s per record at 100 Hz

def reference(n):                        # point-to-point moves with a cosine profile
    qg, k = np.full(n, 0.1), 0
    while k < n:
        dur, rest = int(rng.uniform(0.3, 1.0) / Ts), int(rng.uniform(0.1, 0.5) / Ts)
        a, b, m = qg[k], rng.uniform(0.02, 0.22), min(dur, n - k)
        qg[k:k + m] = a + (b - a) * 0.5 * (1 - np.cos(np.pi * np.arange(m) / dur))
        qg[k + m:] = b
        k += dur + rest
    return qg

def lab(x, g, off):
    p = PUBLISHED
    f = GTAU * KV * (KP * (g - x[0]) - x[1])
    return np.array([x[1], (f - p["Fv"] * x[1] - p["Fc"] * np.sign(x[1]) - off) / p["M"]])

def record(off):                         # RK4 at 0.5 ms; 1 um encoder and 1 N force noise
    qg = reference(n)
    x, h, X = np.array([qg[0], 0.0]), Ts / 20, np.empty((n, 2))
    for i in range(n):
        X[i] = x
        for _ in range(20):
            k1 = lab(x, qg[i], off)
            k2 = lab(x + h / 2 * k1, qg[i], off)
            k3 = lab(x + h / 2 * k2, qg[i], off)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + lab(x + h * k3, qg[i], off))
    tau = GTAU * KV * (KP * (qg - X[:, 0]) - X[:, 1])
    return acid.Dataset(time=np.arange(n) * Ts, Ts=Ts,
                        channels={"q": X[:, 0] + rng.normal(0, 1e-6, n), "qg": qg,
                                  "tau": tau + rng.normal(0, 1.0, n)},
                        units={"q": "m", "qg": "m", "tau": "N"})

records = [record(off) for off in OFFSETS]
# each record's first half to fit, its second half held out: two experiments in each part
est = acid.Dataset.concatenate([r.window(0, n // 2) for r in records])
val = acid.Dataset.concatenate([r.window(n // 2, n) for r in records])

fit = acid.fit_model(model, est, method="oe", oe_window=200)
print(fit.to_frame()[["name", "experiment", "unit", "value", "stderr"]].round(4))
