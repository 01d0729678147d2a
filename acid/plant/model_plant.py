"""The paper's model as a plant: its declaration through ``DeclaredPlant``, with noise.

Used to test every pipeline on a plant whose true parameters are known. T_int and T_shell
are held at their initial values, or taken from the schedule (the excitation generator can
vary them so they are excited too). P_comp is eq. 4 (``acid.models.paper``) at the ambient.
"""

from __future__ import annotations

import numpy as np

from acid.models.paper import compressor_power
from acid.models.plant import DeclaredPlant
from acid.params import ModelParams, as_params, paper
from acid.plant.base import Measurement
from acid.units import C2K

_INITIAL = {"T_cab": C2K(35.0), "T_evap": C2K(8.0), "T_int": C2K(35.0), "T_shell": C2K(38.0)}


class ModelPlant(DeclaredPlant):
    """Eqs. 1-3 and 5 (the declaration) as a plant; P_comp from eq. 4.

    Parameters
    ----------
    params : model parameters (kelvin convention); the paper preset by default.
    T_amb : ambient temperature for the compressor power model, K (Table II: 30 degC).
    meas_noise_std : std of white noise added to recorded T_cab, T_evap, T_ain, K.
    process_noise_std : std of white noise added to the state update of T_cab, T_evap, K.
    rng : random generator for the noise (seed it for reproducible data).
    """

    name = "model"
    INITIAL_KEYS = tuple(_INITIAL)

    def __init__(self, params: ModelParams | None = None, T_amb: float = C2K(30.0),
                 meas_noise_std: float = 0.0, process_noise_std: float = 0.0,
                 rng: np.random.Generator | None = None):
        self.params = paper() if params is None else as_params(params)
        self.meas_noise_std = float(meas_noise_std)
        self.process_noise_std = float(process_noise_std)
        self.rng = rng if rng is not None else np.random.default_rng(0)
        super().__init__("paper", values=self.params.theta, T_amb=float(T_amb))

    def config(self) -> dict:
        return {"params": self.params.to_json_dict(), "T_amb_K": self.T_amb0,
                "meas_noise_std_K": self.meas_noise_std,
                "process_noise_std_K": self.process_noise_std}

    def reset(self, initial: dict[str, float] | None = None) -> Measurement:
        init = {**_INITIAL, **(initial or {})}
        self.constant.update(T_int=float(init.pop("T_int")), T_shell=float(init.pop("T_shell")))
        return super().reset(init)

    @property
    def T_cab(self) -> float:  # noqa: N802 - the channel's name
        """Cabin air now, K (settable: a disturbance a test adds)."""
        return float(self.x[0])

    @T_cab.setter
    def T_cab(self, value: float) -> None:  # noqa: N802
        self.x = np.array([float(value), self.x[1]])

    @property
    def T_evap(self) -> float:  # noqa: N802
        """Evaporator wall now, K."""
        return float(self.x[1])

    def measure(self) -> Measurement:
        """Current states T_cab, T_evap and exogenous T_int, T_shell, K (noise-free)."""
        return {"T_cab": float(self.x[0]), "T_evap": float(self.x[1]),
                "T_int": self.constant["T_int"], "T_shell": self.constant["T_shell"]}

    def step(self, W_bl: float, T_evap_set: float, v_veh: float = 0.0, **exogenous) -> Measurement:
        for name in ("T_int", "T_shell"):   # a given disturbance holds until the next one
            if name in exogenous:
                self.constant[name] = float(exogenous.pop(name))
        row = super().step(W_bl, T_evap_set, v_veh, **exogenous)
        p = self.params
        row.update(T_amb=self.T_amb, v_veh=float(v_veh), P_comp=max(0.0, float(
            compressor_power(float(W_bl), row["T_ain"], self.T_amb, p.c_p, p.eta_cop))))
        if self.meas_noise_std:
            noise = self.rng.standard_normal(3) * self.meas_noise_std
            for name, n in zip(("T_cab", "T_evap", "T_ain"), noise, strict=True):
                row[name] += n
        if self.process_noise_std:
            self.x = self.x + self.rng.standard_normal(2) * self.process_noise_std
        return row
