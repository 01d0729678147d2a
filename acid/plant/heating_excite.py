"""``acid excite --plant heating``: identification data from the heating plant.

The declared model ``heating`` (``acid/models/heating.py``) reads what the logged BMW i3
records: the heater's electric power, the coolant, the supply and cabin air, the ambient and
the speed; the car's blower level and recirculation are not logged, so the model holds them.
``HeatingExcitation`` runs the heating plant (``acid.plant.heating.HeatingPlant``) as that
car: coolant heater only (the logged i3 has no heat pump), the blower at a fixed level
(``W_bl``, kg/s) and a fixed recirculated share, the heater's power a random step signal
(APRBS between 0 and ``P_high``, with the schedule's dwell range, from its own seeded stream)
derated to nothing over the last 5 K below the coolant limit ``T_cool_max`` (the logged car
requests 85 degC of coolant at most [Steinstraeter2020]: without it a random full-power
step boils the coolant), speed and ambient from the excitation schedule (``--speed-range``,
``--t-amb-range``, ``--cycle``). The record starts from a cold soak at the configured ambient.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from acid import __version__, signals
from acid.data import Dataset
from acid.errors import ConfigError
from acid.plant.base import InputSchedule, measurements_to_dataset
from acid.plant.config import PlantConfig
from acid.plant.heating import HeatingPlant
from acid.plant.heating_config import HeatingConfig

#: Channels the record leaves out: the heat pump's outdoor coil (no heat pump: always zero;
#: the frost mass's unit, kg, is not a dataset unit) and the production controller's states
#: (inputs commanded: unused; the supply-air integrator is a difference in K, not a
#: temperature) and its target; the glass-to-dew-point margin (a difference too: T_glass
#: and T_dew are recorded).
DROPPED = ("M_frost", "m_frost", "defrost", "t_defrost", "defrosting", "sup_integrator",
           "heater_integrator", "hp_integrator", "T_sup_target", "fog_margin")

#: Child stream of the excitation seed that draws the heater power (``acid.excite.STREAMS``
#: numbers its own streams 0-6; this one is apart from them).
HEATER_STREAM = 25


class HeatingExcitation(HeatingPlant):
    """The heating plant driven as the logged car for identification (module docstring).

    Parameters
    ----------
    heating, config : as ``HeatingPlant`` (default: the i3's coolant heater, no heat pump;
        ``winter_plant_config()``).
    W_bl : the blower's fixed flow, kg/s (within the plant's blower range).
    recirc : the fixed recirculated share of the blower's air, 0-1.
    P_high : the heater power's upper level, W (at most ``P_heater_max``; the default 3 kW is
        the top of the logged warm-ups' 2-3.5 kW).
    T_cool_max : the coolant limit, K.
    """

    name = "heating"

    def __init__(self, heating: HeatingConfig | None = None, config: PlantConfig | None = None,
                 W_bl: float = 0.08, recirc: float = 0.8, P_high: float = 3000.0,
                 T_cool_max: float = 358.15):
        super().__init__(heating or HeatingConfig(heat_pump=False), config, mode="direct")
        c = self.cfg
        if not c.W_bl_min <= W_bl <= c.W_bl_max:
            raise ConfigError(f"HeatingExcitation: W_bl = {W_bl} kg/s outside the blower's "
                              f"{c.W_bl_min}-{c.W_bl_max} kg/s")
        if not 0.0 <= recirc <= 1.0:
            raise ConfigError(f"HeatingExcitation: recirc = {recirc} must lie in [0, 1]")
        if not 0.0 < P_high <= self.hc.P_heater_max:
            raise ConfigError(f"HeatingExcitation: P_high = {P_high} W outside (0, "
                              f"{self.hc.P_heater_max}] W")
        self.W_fixed, self.recirc = float(W_bl), float(recirc)
        self.P_high, self.T_cool_max = float(P_high), float(T_cool_max)

    def config(self) -> dict:
        return {**super().config(), "W_bl": self.W_fixed, "recirc": self.recirc,
                "P_high": self.P_high, "T_cool_max": self.T_cool_max}

    def heater_schedule(self, schedule: InputSchedule) -> tuple[np.ndarray, dict]:
        """The heater's commanded electric power (W) over ``schedule``: APRBS between 0 and
        ``P_high`` with the schedule's dwell range, seeded from its seed."""
        spec = schedule.spec
        seed = int(spec.get("seed", 0))
        rng = np.random.default_rng(np.random.SeedSequence([seed, HEATER_STREAM]))
        Ts = schedule.Ts
        lo = max(1, int(round(float(spec.get("min_dwell", 60.0)) / Ts)))
        hi = max(lo, int(round(float(spec.get("max_dwell", 600.0)) / Ts)))
        P, gen = signals.aprbs(rng, len(schedule), 0.0, self.P_high, lo, hi)
        return P, {**gen, "unit": "W", "stream": HEATER_STREAM}

    def simulate(self, schedule: InputSchedule, initial: dict[str, float] | None = None,
                 progress: Callable[[int, int], None] | None = None,
                 metadata: dict | None = None) -> Dataset:
        """Reset (a cold soak unless ``initial``), run the schedule's speed and ambient with
        the heater's random power, the fixed blower and recirculation; a dataset in degC."""
        if abs(schedule.Ts - self.Ts) > 1e-9:
            raise ConfigError(f"schedule sample time {schedule.Ts} s differs from the plant's "
                              f"{self.Ts} s")
        P, gen = self.heater_schedule(schedule)
        self.reset(initial)
        n = len(schedule)
        rows = []
        for k in range(n):
            kw = {} if schedule.T_amb is None else {"T_amb": schedule.T_amb[k]}
            derate = min(max((self.T_cool_max - self.T_cool) / 5.0, 0.0), 1.0)
            row = self.step(self.W_fixed, 0.0, schedule.v_veh[k], P_heater=P[k] * derate,
                            N_hp=0.0, recirc=self.recirc, **kw)
            rows.append({k2: v for k2, v in row.items() if k2 not in DROPPED})
            if progress is not None:
                progress(k + 1, n)
        excitation = {**schedule.spec, "generators": {**schedule.spec.get("generators", {}),
                                                      "P_heater": gen},
                      "held": {"W_bl": self.W_fixed, "recirc": self.recirc,
                               "T_evap_set": "not used (heating)"}}
        meta = {"plant": self.name, "plant_config": self.config(), "excitation": excitation,
                "acid_version": __version__}
        if "seed" in schedule.spec:
            meta["seed"] = schedule.spec["seed"]
        meta.update(metadata or {})
        return measurements_to_dataset(rows, self.Ts, meta, units=self.units())
