"""A static gain y = k u (or (a + b) u) with a latent state the output does not read: a
declared model whose fits have closed forms."""

from __future__ import annotations

import numpy as np

import acid
from acid.models import Model, Parameter, Signal, State

TS, N = 1.0, 400


def gain_model(prior=None, split: bool = False) -> Model:
    params = ([Parameter("a", "1", 1.0, -10.0, 10.0),
               Parameter("b", "1", 0.5, -10.0, 10.0, prior=prior)] if split else
              [Parameter("k", "1", 1.0, -10.0, 10.0, prior=prior)])
    gain = (lambda s: s.a + s.b) if split else (lambda s: s.k)
    return Model("gain", states=[State("x", "1", measured=False, initial=0.0)],
                 inputs=[Signal("u", "1")], outputs=[Signal("y", "1")],
                 parameters=params, Ts=TS, ode=lambda s: {"x": -s.x},
                 output=lambda s: {"y": gain(s) * s.u})


def gain_data(k_true: float = 2.0, noise: float = 0.1, n: int = N) -> acid.Dataset:
    rng = np.random.default_rng(0)
    u = rng.normal(0.0, 1.0, n)
    y = k_true * u + rng.normal(0.0, noise, n)
    return acid.Dataset(time=np.arange(n) * TS, channels={"u": u, "y": y},
                        units={"u": "1", "y": "1"}, Ts=TS)
