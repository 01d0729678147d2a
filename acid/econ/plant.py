"""The econ model as a plant (the protocol of :mod:`acid.plant.base`): a plant whose true
parameters are known, to test identification and control end to end.

Each step integrates :func:`acid.econ.model.step` over one sample with the inputs held; the
row carries the states at t_k, the applied inputs and the interval means (T_ain, Q_evap as the
model's refrigerant heat, P_comp from the power map, P_bl from eq. 5). Temperatures in K.
"""

from __future__ import annotations

import numpy as np

from acid.econ import model
from acid.econ.params import EconParams
from acid.errors import ConfigError
from acid.plant.base import Measurement, Plant

#: Initial-condition keys accepted by ``EconPlant.reset`` (K, w_cab in kg/kg).
INITIAL_KEYS = model.STATES


class EconPlant(Plant):
    """The econ model as a plant.

    Parameters
    ----------
    params : the (true) model parameters.
    T_amb : default ambient temperature, K.
    initial : default initial state {name: value} (K, kg/kg).
    """

    name = "econ-model"
    INITIAL_KEYS = INITIAL_KEYS

    def __init__(self, params: EconParams, T_amb: float = 303.15,
                 initial: dict[str, float] | None = None):
        self.params = params
        self.Ts = float(params.Ts)
        self.T_amb0 = float(T_amb)
        self._initial = {"T_cab": 313.15, "T_int": 315.15, "T_shell": 315.15,
                         "T_evap": 303.15, "w_cab": 0.0085, **(initial or {})}
        self.reset()

    def config(self) -> dict:
        return {"model": "econ", "params": self.params.to_json_dict(), "T_amb_K": self.T_amb0}

    def reset(self, initial: dict[str, float] | None = None) -> Measurement:
        init = dict(self._initial)
        for key, value in (initial or {}).items():
            if key not in INITIAL_KEYS:
                raise ConfigError(f"initial condition {key!r} unknown "
                                  f"(known: {', '.join(INITIAL_KEYS)})")
            init[key] = float(value)
        self.x = np.array([init[k] for k in model.STATES])
        self.T_amb = self.T_amb0
        return self.measure()

    def measure(self) -> Measurement:
        return {**dict(zip(model.STATES, (float(v) for v in self.x), strict=True)),
                "T_amb": self.T_amb}

    def step(self, W_bl: float, T_evap_set: float, v_veh: float = 0.0, **kw) -> Measurement:
        p = self.params
        if "T_amb" in kw:
            self.T_amb = float(kw["T_amb"])
        row = self.measure()
        u = (float(W_bl), float(T_evap_set))
        r = model.step(tuple(self.x), u, (float(v_veh), self.T_amb), p, self.Ts)
        x_next = np.array([float(v) for v in r.x])
        Q_e = float(model.refrigerant_heat(r.Q_coil, self.x[3], x_next[3], self.Ts, p))
        P_c = max(float(model.compressor_power(Q_e, r.T_evap, float(v_veh), self.T_amb,
                                               p.power_map)), 0.0)
        self.x = x_next
        row.update(W_bl=u[0], T_evap_set=u[1], v_veh=float(v_veh), T_ain=float(r.T_ain),
                   Q_evap=Q_e, P_comp=P_c, P_bl=float(model.blower_power(u[0], p)))
        return row
