"""The plant protocol shared by the high-fidelity plant and the control-oriented model.

A plant is reset to initial conditions, then stepped by the sample time Ts with the inputs
(W_bl, T_evap_set) and the vehicle speed, or asked to simulate a whole schedule into a
``Dataset``. Conventions for one step k (row k of a dataset):

* states (T_cab, T_evap, T_int, T_shell, ...) are sampled at t_k, before the step;
* inputs u(k) = (W_bl, T_evap_set) and v_veh are held over [t_k, t_k + Ts);
* outputs and powers (T_ain, P_comp, P_bl, P_fan, COP, ...) are means over [t_k, t_k + Ts),
  so that sum(P) * Ts is the energy.

Temperatures cross this interface in kelvin (the library's inside); ``simulate`` stores
them in degC in the dataset it returns (the edge).
"""

from __future__ import annotations

import abc
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from acid import __version__
from acid.data import CHANNELS, Dataset
from acid.errors import ConfigError
from acid.units import K2C, is_temperature

#: Optional per-sample exogenous inputs of a schedule, passed to ``Plant.step`` as keywords (K).
EXOGENOUS = ("T_int", "T_shell", "T_amb")

Measurement = dict[str, float]
"""Channel name -> value for one sample; temperatures in K, other units as in CHANNELS."""


@dataclass
class InputSchedule:
    """Inputs over a run, one value per sample of period ``Ts``.

    Attributes
    ----------
    W_bl : (n,) blower air flow, kg/s.
    T_evap_set : (n,) evaporator wall set-point, K.
    v_veh : (n,) vehicle speed, m/s (mean over each sample).
    Ts : sample time, s.
    T_int, T_shell : optional (n,) exogenous temperatures, K. Only the control-oriented
        model plant uses them (the high-fidelity plant computes its own).
    T_amb : optional (n,) ambient temperature per sample, K (held over the sample); the
        plant's configured ambient when None.
    spec : how the schedule was made (generator, bounds, seed), stored as dataset metadata.
    """

    W_bl: np.ndarray
    T_evap_set: np.ndarray
    v_veh: np.ndarray
    Ts: float = 5.0
    T_int: np.ndarray | None = None
    T_shell: np.ndarray | None = None
    T_amb: np.ndarray | None = None
    spec: dict = field(default_factory=dict)

    def __post_init__(self):
        self.W_bl = np.asarray(self.W_bl, dtype=float)
        n = self.W_bl.shape[0]
        self.T_evap_set = np.broadcast_to(np.asarray(self.T_evap_set, dtype=float), (n,)).copy()
        self.v_veh = np.broadcast_to(np.asarray(self.v_veh, dtype=float), (n,)).copy()
        for name in EXOGENOUS:
            v = getattr(self, name)
            if v is not None:
                setattr(self, name, np.broadcast_to(np.asarray(v, dtype=float), (n,)).copy())

    def __len__(self) -> int:
        return int(self.W_bl.shape[0])


def validated_initial(initial: dict[str, float] | None, keys: tuple[str, ...]
                      ) -> dict[str, float]:
    """``initial`` (a plant's ``reset`` argument) checked against the state names ``keys``:
    floats, finite, temperatures (``T_*``) plausible in kelvin; ``ConfigError`` otherwise."""
    out = {}
    for key, value in (initial or {}).items():
        if key not in keys:
            raise ConfigError(f"initial condition {key!r} unknown (known: {', '.join(keys)})")
        value = float(value)
        if not math.isfinite(value):
            raise ConfigError(f"initial {key} = {value} is not finite")
        if key.startswith("T_") and not 200.0 < value < 400.0:
            raise ConfigError(f"initial {key} = {value} K is implausible "
                              "(temperatures are in kelvin)")
        out[key] = value
    return out


def balance_table(flows: dict[str, tuple[float, float, float]]) -> dict:
    """``{name: (stored, inflow, scale)}`` -> ``{name: {stored, inflow, residual, scale,
    relative}}``: residual = stored - inflow, relative = |residual| / scale (0 when scale is
    0). The form of every plant's ``balance()``."""
    res = {}
    for k, (stored, inflow, scale) in flows.items():
        r = stored - inflow
        res[k] = {"stored": stored, "inflow": inflow, "residual": r, "scale": scale,
                  "relative": abs(r) / scale if scale > 0 else 0.0}
    return res


def checked_ambient(value) -> float:
    """A per-step ambient temperature (K) as a float; ``ConfigError`` when implausible."""
    T = float(value)
    if not 230.0 < T < 330.0:
        raise ConfigError(f"ambient temperature T_amb = {value} K is implausible "
                          "(kelvin, -43 to 57 degC)")
    return T


class Plant(abc.ABC):
    """Base class of every plant: subclasses implement ``reset``, ``step`` and ``config``."""

    #: name used by ``--plant`` and stored in dataset metadata
    name: str = "plant"
    #: sample time, s
    Ts: float = 5.0

    @abc.abstractmethod
    def reset(self, initial: dict[str, float] | None = None) -> Measurement:
        """Reset to initial conditions (K for temperatures); returns the sample at t = 0."""

    @abc.abstractmethod
    def step(self, W_bl: float, T_evap_set: float, v_veh: float = 0.0, **exogenous) -> Measurement:
        """Advance one sample period with inputs held; returns row k (see module docstring)."""

    @abc.abstractmethod
    def measure(self) -> Measurement:
        """The current state (K), i.e. what a closed loop measures before the next step.

        ``step`` returns row k (the states *before* the step); a controller needs the states
        after it, at t_{k+1}: at least T_cab, T_evap, T_int and T_shell.
        """

    @abc.abstractmethod
    def config(self) -> dict:
        """The plant's resolved configuration, JSON-serialisable (stored with datasets)."""

    def units(self) -> dict[str, str]:
        """Units of the channels this plant reports that ``acid.data.CHANNELS`` does not
        know, in the plant's inside units (K for temperatures). Empty by default."""
        return {}

    def simulate(self, schedule: InputSchedule, initial: dict[str, float] | None = None,
                 progress: Callable[[int, int], None] | None = None,
                 metadata: dict | None = None) -> Dataset:
        """Reset, run the whole schedule and return it as a dataset (degC storage).

        ``progress(done, total)`` is called after each step when given.
        """
        if abs(schedule.Ts - self.Ts) > 1e-9:
            raise ConfigError(f"schedule sample time {schedule.Ts} s differs from the plant's "
                              f"{self.Ts} s")
        self.reset(initial)
        n = len(schedule)
        rows: list[Measurement] = []
        for k in range(n):
            exo = {name: getattr(schedule, name)[k] for name in EXOGENOUS
                   if getattr(schedule, name) is not None}
            rows.append(self.step(schedule.W_bl[k], schedule.T_evap_set[k],
                                  schedule.v_veh[k], **exo))
            if progress is not None:
                progress(k + 1, n)
        meta = {"plant": self.name, "plant_config": self.config(), "excitation": schedule.spec,
                "acid_version": __version__}
        if "seed" in schedule.spec:
            meta["seed"] = schedule.spec["seed"]
        meta.update(metadata or {})
        return measurements_to_dataset(rows, self.Ts, meta, units=self.units())


def measurements_to_dataset(rows: list[Measurement], Ts: float, metadata: dict,
                            units: dict[str, str] | None = None) -> Dataset:
    """Stack per-step measurements (K inside) into a dataset with temperatures in degC.

    ``units`` gives the inside unit of channels that ``CHANNELS`` does not know.
    """
    names = list(rows[0])
    known = units or {}
    channels, units = {}, {}
    for name in names:
        v = np.array([r[name] for r in rows], dtype=float)
        if name in CHANNELS:
            unit = CHANNELS[name].unit
        else:
            unit = known.get(name) or guess_unit(name)
        if is_temperature(unit):
            v, unit = K2C(v), "degC"
        channels[name], units[name] = v, unit
    time = np.arange(len(rows)) * Ts
    return Dataset(time=time, channels=channels, units=units, Ts=Ts, metadata=metadata)


def guess_unit(name: str) -> str:
    if name.startswith("T_"):
        return "degC"
    if name.startswith(("P_", "Q_")):
        return "W"
    return "1"
