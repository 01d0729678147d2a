"""The control-oriented model (eqs. 1-5) wrapped as a plant, with optional noise.

Used to test every pipeline on a plant whose true parameters are known. T_int and T_shell
are exogenous here: held at their initial values, or taken from the schedule (the excitation
generator can vary them so they are excited too).
"""

from __future__ import annotations

import numpy as np

from acid import model
from acid.params import ModelParams, as_params, paper
from acid.plant.base import Measurement, Plant
from acid.units import C2K


class ModelPlant(Plant):
    """Eqs. 1-3 as a plant; powers from eqs. 4-5.

    Parameters
    ----------
    params : model parameters (kelvin convention); the paper preset by default.
    T_amb : ambient temperature for the compressor power model, K (Table II: 30 degC).
    meas_noise_std : std of white noise added to recorded T_cab, T_evap, T_ain, K.
    process_noise_std : std of white noise added to the state update of T_cab, T_evap, K.
    rng : random generator for the noise (seed it for reproducible data).
    """

    name = "model"

    def __init__(self, params: ModelParams | None = None, T_amb: float = C2K(30.0),
                 meas_noise_std: float = 0.0, process_noise_std: float = 0.0,
                 rng: np.random.Generator | None = None):
        self.params = paper() if params is None else as_params(params)
        self.Ts = self.params.Ts
        self.T_amb = float(T_amb)
        self.meas_noise_std = float(meas_noise_std)
        self.process_noise_std = float(process_noise_std)
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.reset()

    def config(self) -> dict:
        return {"params": self.params.to_json_dict(), "T_amb_K": self.T_amb,
                "meas_noise_std_K": self.meas_noise_std,
                "process_noise_std_K": self.process_noise_std}

    def measure(self) -> Measurement:
        """Current states T_cab, T_evap and exogenous T_int, T_shell, K (noise-free)."""
        return {"T_cab": self.T_cab, "T_evap": self.T_evap, "T_int": self.T_int,
                "T_shell": self.T_shell}

    def reset(self, initial: dict[str, float] | None = None) -> Measurement:
        init = {"T_cab": C2K(35.0), "T_evap": C2K(8.0), "T_int": C2K(35.0),
                "T_shell": C2K(38.0)}
        init.update(initial or {})
        self.T_cab, self.T_evap = float(init["T_cab"]), float(init["T_evap"])
        self.T_int, self.T_shell = float(init["T_int"]), float(init["T_shell"])
        return self.measure()

    def step(self, W_bl: float, T_evap_set: float, v_veh: float = 0.0, **exogenous) -> Measurement:
        p = self.params
        if "T_int" in exogenous:
            self.T_int = float(exogenous["T_int"])
        if "T_shell" in exogenous:
            self.T_shell = float(exogenous["T_shell"])
        if "T_amb" in exogenous:
            self.T_amb = float(exogenous["T_amb"])
        T_cab_next, T_evap_next, T_ain = model.step(
            self.T_cab, self.T_evap, W_bl, T_evap_set, self.T_int, self.T_shell, p)
        noise = (self.rng.standard_normal(3) * self.meas_noise_std if self.meas_noise_std
                 else np.zeros(3))
        row = {
            "T_cab": self.T_cab + noise[0], "T_evap": self.T_evap + noise[1],
            "T_ain": T_ain + noise[2], "W_bl": float(W_bl), "T_evap_set": float(T_evap_set),
            "T_int": self.T_int, "T_shell": self.T_shell, "T_amb": self.T_amb,
            "v_veh": float(v_veh),
            "P_comp": max(0.0, model.compressor_power(W_bl, T_ain, self.T_amb, p)),
            "P_bl": model.blower_power(W_bl, p),
        }
        if self.process_noise_std:
            w = self.rng.standard_normal(2) * self.process_noise_std
            T_cab_next, T_evap_next = T_cab_next + w[0], T_evap_next + w[1]
        self.T_cab, self.T_evap = float(T_cab_next), float(T_evap_next)
        return row
