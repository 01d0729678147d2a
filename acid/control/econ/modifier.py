"""Modifier adaptation of the econ model's coil economics from steady holds on the plant.

What kept the economic NMPC's coil cold (measured on the default plant, UDDS conditions:
8.8 m/s, 30 degC, cabin held at 24.1 degC by the plant's PI loops at a fixed coil set-point):

* the identified power map prices a warm coil too high: at the plant's own refrigerant heat
  and evaporator temperature it over-predicts the compressor power by 1 W at a 5 degC coil
  and 21 W (5 %) at 10 degC: its inverse COP falls half as fast with the coil temperature
  as the plant's (the quadratic map, fitted on excitation data whose coil set-points rarely
  pass 10 degC, under the model's coil load);
* the air side splits the coil load differently (about 50 W more sensible, 60 W less latent
  than the plant at a 10 degC coil: the identified recirculation and ambient humidity absorb
  the plant's infiltration), so the model asks about 6 % more blower flow at every coil
  temperature, and blower power grows with its square.

Along the line of equal cabin temperature the model's steady power therefore has its
minimum near 8.6 degC, the plant's near 10 degC, and D and E ran their coils at 8.7-9.0 degC.

The remedy is the first-order **modifier adaptation** of real-time optimisation (Marchetti,
Chachuat & Bonvin, Ind. Eng. Chem. Res. 48(13), 2009): measure the plant's cost gradient at
the model's optimum and correct the model so that its gradient there agrees. Here the
gradient is that of the steady electric power (compressor + blower) with respect to the coil
set-point at a held cabin temperature: two steady holds of the plant's PI loops at ``T* +-
dT`` (``T*`` the model's optimal coil set-point), against the same difference on the model's
steady states. The correction goes into the power map's ``t`` coefficient (``P_comp = Q_e
f``, ``t = (T_evap - 5 degC) / 5 K``), so the NMPC's stage cost, its steady-state terminal
price and the best known plan all see the same corrected map; the map's coefficients are NLP
parameters, so a compiled solver is reused. The step is repeated at the corrected model's
new optimum (``iterations``). Temperatures in K, powers in W.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from acid.control.econ.terminal import SteadyStatePrice
from acid.control.pi_baselines import COIL_RANGE, PlantPI
from acid.models.econ import DT_SCALE, MAP_TERMS, STATES, air_side, parameters
from acid.models.econ_params import EconParams


@dataclass(frozen=True)
class CoilModifier:
    """The correction and its evidence (K, W, W/K).

    Attributes
    ----------
    params : the econ model with the corrected map.
    delta_t_coef : change of the map's ``t`` coefficient.
    steps : per iteration ``{"T_star_K", "plant_slope_W_K", "model_slope_W_K",
        "plant_W": [low, high], "model_W": [low, high], "Q_e_W"}``.
    conditions : ``{"v_veh", "T_amb_K", "T_cab_K", "dT_K", "hold_s"}``.
    """

    params: EconParams
    delta_t_coef: float
    steps: tuple
    conditions: dict

    def to_json_dict(self) -> dict:
        return {"method": "first-order modifier adaptation of the power map's T_evap "
                          "coefficient from steady holds of the plant's PI loops",
                "delta_t_coef": self.delta_t_coef, "steps": list(self.steps),
                "conditions": self.conditions,
                "model_optimal_coil_K": [s["T_star_K"] for s in self.steps]}


def model_steady_power(econ: EconParams, v: float, T_amb: float, T_cab: float,
                       T_coil: float | None = None, coil_range=COIL_RANGE):
    """(power W, coil set-point K, Q_e W) of the model's optimal steady state at ``T_cab``,
    the coil set-point held at ``T_coil`` or free within ``coil_range``."""
    lo, hi = (T_coil, T_coil) if T_coil is not None else coil_range
    price = SteadyStatePrice(econ, [0.05, lo], [0.15, hi])
    ss = price.steady_state(v, T_amb, T_cab, T_cab)
    x = dict(zip(STATES, ss.x, strict=True))
    air = air_side(parameters(econ.theta_all), x["T_cab"], x["T_evap"], x["w_cab"], ss.u[0],
                   T_amb)
    return ss.power_W, float(ss.u[1]), float(air.Q_coil)


def plant_steady_power(plant_factory: Callable[[], object], loops, start: dict | None,
                       v: float, T_amb: float, T_cab: float, T_coil: float,
                       hold_s: float = 7200.0, mean_s: float = 1800.0) -> float:
    """Mean compressor + blower power (W) of the plant's PI loops holding the cabin at
    ``T_cab`` with the coil set-point at ``T_coil``, over the last ``mean_s`` of a hold of
    ``hold_s`` at speed ``v`` and ambient ``T_amb``."""
    plant = plant_factory()
    plant.reset(start)
    ctrl = PlantPI(loops, plant.Ts, T_cab, T_coil)
    n, m = int(round(hold_s / plant.Ts)), int(round(mean_s / plant.Ts))
    power = []
    for k in range(n):
        row = plant.step(*ctrl.make_step(plant.measure(), k), v, T_amb=T_amb)
        power.append(float(row["P_comp"]) + float(row["P_bl"]))
    return float(np.mean(power[-m:]))


def coil_modifier(econ: EconParams, plant_factory: Callable[[], object], loops,
                  v: float, T_amb: float, T_cab: float, start: dict | None = None,
                  dT: float = 1.0, iterations: int = 2, hold_s: float = 7200.0,
                  coil_range=COIL_RANGE) -> CoilModifier:
    """Correct the map's ``t`` coefficient so the model's steady power gradient in the coil
    set-point matches the plant's at the model's optimum (module docstring)."""
    j = MAP_TERMS.index("t")
    e, total, steps = econ, 0.0, []
    for _ in range(max(1, int(iterations))):
        _, T_star, Q_e = model_steady_power(e, v, T_amb, T_cab, coil_range=coil_range)
        pts = np.clip([T_star - dT, T_star + dT], *coil_range)
        plant = [plant_steady_power(plant_factory, loops, start, v, T_amb, T_cab, float(c),
                                    hold_s) for c in pts]
        mod = [model_steady_power(e, v, T_amb, T_cab, float(c))[0] for c in pts]
        width = float(pts[1] - pts[0])
        s_plant, s_model = (plant[1] - plant[0]) / width, (mod[1] - mod[0]) / width
        dc = (s_plant - s_model) * DT_SCALE / max(Q_e, 100.0)
        coef = list(e.power_map.coef)
        coef[j] += dc
        total += dc
        e = dataclasses.replace(e, power_map=dataclasses.replace(e.power_map,
                                                                 coef=tuple(coef)))
        steps.append({"T_star_K": T_star, "plant_slope_W_K": s_plant,
                      "model_slope_W_K": s_model, "plant_W": plant, "model_W": mod,
                      "Q_e_W": Q_e, "delta_t_coef": dc})
    _, T_final, _ = model_steady_power(e, v, T_amb, T_cab, coil_range=coil_range)
    steps.append({"T_star_K": T_final})
    return CoilModifier(params=e, delta_t_coef=total, steps=tuple(steps),
                        conditions={"v_veh": v, "T_amb_K": T_amb, "T_cab_K": T_cab,
                                    "dT_K": dT, "hold_s": hold_s})
