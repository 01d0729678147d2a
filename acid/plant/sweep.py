"""The speed-sensitivity study of the paper (section II-A, Fig. 3, Table I).

The high-fidelity plant runs with its nominal controller from the same hot soak and cabin
set-point at constant vehicle speeds 0, 5, ..., 25 m/s for 600 s.

Which energy Table I counts: the paper lists the condenser fan inside CoolSim's cooling-circuit
block but calls the compressor "the primary energy consumer", names "two major energy
consumers in the A/C system ... the compressor and the blower" (section III) and computes the
A/C energy of Fig. 8 from "blower power and compressor power". acid therefore reads Table I as
compressor + blower (``energy_MJ``) and reports the condenser fan apart
(``energy_fan_MJ``) and in a total with it (``energy_with_fan_MJ``).

Ram air through the condenser (and the fan switched off at speed) lowers the head pressure,
so the COP rises with speed. How that moves the energy depends on the compressor: below its
capacity (acid's default vehicle, at most 78 % of N_max) the energy follows load / COP and
falls 37 % from 0 to 25 m/s (about 80 % of it COP gain, 20 % lower load); at its capacity
(the paper vehicle, ``acid.plant.vehicles``) the energy is the compressor's maximum power and
falls only as the head pressure does, as in the paper's Table I. See
``datasets/plant/SOURCES.md``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from acid.paper import TABLE_I
from acid.plant.config import PlantConfig
from acid.plant.hifi import HifiPlant

#: Paper Table I (from the claims registry, ``acid.claims.TABLE_I``): speeds (m/s), A/C
#: energy over 600 s (MJ) and per distance (MJ/km, NaN at 0).
PAPER_TABLE_I = {
    "speeds_mps": TABLE_I.speeds_mps,
    "energy_MJ": TABLE_I.energy_MJ,
    "energy_MJ_per_km": tuple(math.nan if e is None else e for e in TABLE_I.energy_MJ_per_km),
}

#: Channels kept per speed for the figure (``SweepResult.traces``).
TRACE_CHANNELS = ("T_cab", "T_evap", "T_ain", "W_bl", "N_comp", "P_comp", "P_bl", "P_fan",
                  "T_c", "COP", "p_dis", "m_ca")


@dataclass(frozen=True)
class SweepResult:
    """Energy of the nominal controller at constant speeds (paper Table I, Fig. 3).

    Attributes
    ----------
    speeds_mps : (S,) vehicle speeds, m/s.
    duration_s : simulated time per speed, s.
    energy_MJ : (S,) compressor + blower energy over ``duration_s``, MJ.
    energy_MJ_per_km : (S,) energy per distance, MJ/km (NaN at standstill).
    energy_comp_MJ, energy_bl_MJ, energy_fan_MJ : (S,) the parts, MJ (the fan is not in
        ``energy_MJ``; ``energy_with_fan_MJ`` adds it).
    time : (n,) sample instants of the traces, s.
    traces : {channel: (S, n) array}, temperatures in K, powers in W (``TRACE_CHANNELS``).
    config : the plant configuration used (flat dict, as a plant file gives it: temperatures
        in degC, ``PlantConfig.to_file_dict``).
    """

    speeds_mps: np.ndarray
    duration_s: float
    energy_MJ: np.ndarray
    energy_MJ_per_km: np.ndarray
    energy_comp_MJ: np.ndarray
    energy_bl_MJ: np.ndarray
    energy_fan_MJ: np.ndarray
    time: np.ndarray
    traces: dict
    config: dict

    @property
    def ratio_last_first(self) -> float:
        """E(last speed) / E(first speed) (paper Table I: 0.80)."""
        return float(self.energy_MJ[-1] / self.energy_MJ[0])

    @property
    def energy_with_fan_MJ(self) -> np.ndarray:
        """Compressor + blower + condenser fan energy, MJ."""
        return self.energy_MJ + self.energy_fan_MJ

    @property
    def ratio_last_first_with_fan(self) -> float:
        """E(last speed) / E(first speed) with the condenser fan counted."""
        e = self.energy_with_fan_MJ
        return float(e[-1] / e[0])

    def to_json_dict(self) -> dict:
        """JSON-ready summary: NaN becomes None; includes the paper's row."""
        def clean(a):
            return [None if not math.isfinite(x) else round(float(x), 6) for x in a]

        return {
            "speeds_mps": clean(self.speeds_mps),
            "duration_s": self.duration_s,
            "energy_MJ": clean(self.energy_MJ),
            "energy_MJ_per_km": clean(self.energy_MJ_per_km),
            "energy_comp_MJ": clean(self.energy_comp_MJ),
            "energy_bl_MJ": clean(self.energy_bl_MJ),
            "energy_fan_MJ": clean(self.energy_fan_MJ),
            "energy_with_fan_MJ": clean(self.energy_with_fan_MJ),
            "ratio_last_first": round(self.ratio_last_first, 6),
            "ratio_last_first_with_fan": round(self.ratio_last_first_with_fan, 6),
            "paper": {k: clean(v) for k, v in PAPER_TABLE_I.items()},
            "plant_config": self.config,
        }


def speed_sweep(config: PlantConfig | None = None,
                speeds: Sequence[float] = (0, 5, 10, 15, 20, 25), duration: float = 600.0,
                progress: Callable[[int, int], None] | None = None,
                plant_factory: Callable[[], object] | None = None) -> SweepResult:
    """Run the nominal controller at each constant speed from the same hot soak.

    Parameters
    ----------
    config : plant configuration (default calibration when None).
    speeds : vehicle speeds, m/s.
    duration : simulated time per speed, s (rounded to whole samples of Ts).
    progress : ``progress(done, total)`` called after each speed.
    plant_factory : another plant in its nominal mode (e.g. an FMU plant running its own
        controller), built once per speed; default ``HifiPlant(config, mode="nominal")``.
        Channels it does not report are NaN in the traces.

    Returns
    -------
    SweepResult (energy = compressor + blower, as in the paper's Table I).
    """
    from acid.errors import ConfigError

    config = config or PlantConfig()
    speeds = np.asarray(speeds, dtype=float)
    if speeds.ndim != 1 or speeds.size == 0 or np.any(~np.isfinite(speeds)) or np.any(speeds < 0):
        raise ConfigError("speeds must be a non-empty list of non-negative numbers (m/s)")
    n = int(round(duration / config.Ts))
    if n < 1:
        raise ConfigError(f"duration {duration} s is shorter than one sample ({config.Ts} s)")
    Ts = config.Ts
    traces = {name: np.empty((speeds.size, n)) for name in TRACE_CHANNELS}
    E_c, E_b, E_f = (np.empty(speeds.size) for _ in range(3))
    for s, v in enumerate(speeds):
        plant = (HifiPlant(config, mode="nominal") if plant_factory is None
                 else plant_factory())
        if abs(plant.Ts - Ts) > 1e-9:
            raise ConfigError(f"plant sample time {plant.Ts:g} s differs from {Ts:g} s")
        plant.reset()
        rows = [plant.step(0.0, config.T_ew_set, float(v)) for _ in range(n)]
        for name in TRACE_CHANNELS:
            traces[name][s] = [r.get(name, np.nan) for r in rows]
        E_c[s] = traces["P_comp"][s].sum() * Ts / 1e6
        E_b[s] = traces["P_bl"][s].sum() * Ts / 1e6
        E_f[s] = traces["P_fan"][s].sum() * Ts / 1e6
        if progress is not None:
            progress(s + 1, speeds.size)
    energy = E_c + E_b
    distance_km = speeds * n * Ts / 1000.0
    with np.errstate(divide="ignore", invalid="ignore"):
        per_km = np.where(distance_km > 0, energy / np.where(distance_km > 0, distance_km, 1.0),
                          np.nan)
    return SweepResult(speeds_mps=speeds, duration_s=n * Ts, energy_MJ=energy,
                       energy_MJ_per_km=per_km, energy_comp_MJ=E_c, energy_bl_MJ=E_b,
                       energy_fan_MJ=E_f, time=np.arange(n) * Ts, traces=traces,
                       config=config.to_file_dict())
