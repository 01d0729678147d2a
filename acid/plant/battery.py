"""The traction battery and the on-board charger of a connected car's day (``acid day``).

``Battery`` keeps the state of charge against the usable energy (the share of the gross
energy the battery management lets the driver use); ``Charger`` turns grid (AC) energy into
battery or cabin energy at its efficiency and at most its rated power. Energies in J inside,
kWh in fields and at the edges; the i3 values cite ``datasets/plant/SOURCES.md`` keys.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from acid.errors import ConfigError

J_PER_KWH = 3.6e6


def _positive(owner: str, **values: float) -> None:
    for name, v in values.items():
        if not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0.0:
            raise ConfigError(f"{owner}: {name} must be a positive number, got {v!r}")


@dataclass(frozen=True)
class Battery:
    """A traction battery: usable and gross energy (kWh) and the state of charge (0-1 of the
    usable energy). Defaults: the BMW i3 120 Ah (2019-2022), [BMW-i3-120Ah]: 42.2 kWh gross,
    37.9 kWh usable."""

    usable_kWh: float = 37.9
    gross_kWh: float = 42.2
    soc: float = 0.9

    def __post_init__(self):
        _positive("Battery", usable_kWh=self.usable_kWh, gross_kWh=self.gross_kWh)
        if self.usable_kWh > self.gross_kWh:
            raise ConfigError(f"Battery: usable {self.usable_kWh:g} kWh exceeds gross "
                              f"{self.gross_kWh:g} kWh")
        if not (math.isfinite(self.soc) and 0.0 <= self.soc <= 1.0):
            raise ConfigError(f"Battery: soc must lie in 0..1, got {self.soc!r}")

    @property
    def energy_kWh(self) -> float:
        """Usable energy left, kWh."""
        return self.soc * self.usable_kWh

    def drawn(self, E_J: float) -> Battery:
        """The battery after ``E_J`` joules taken out (negative: put in), the state of charge
        held to 0..1 (``exhausted`` tells whether the draw reached empty)."""
        soc = self.soc - E_J / (self.usable_kWh * J_PER_KWH)
        return Battery(self.usable_kWh, self.gross_kWh, min(1.0, max(0.0, soc)))

    def exhausted(self, E_J: float) -> bool:
        """Whether drawing ``E_J`` joules would empty the usable energy."""
        return E_J >= self.soc * self.usable_kWh * J_PER_KWH


@dataclass(frozen=True)
class Charger:
    """An on-board AC charger: rated AC power (W) and AC-to-DC efficiency. Defaults: the i3's
    7.4 kW single-phase charger ([BMW-i3-120Ah]; 11 kW three-phase on later cars) and 0.86,
    FASTSim's BEV value, inside the 0.85-0.92 band of Level-2 on-board chargers
    (``road_load.CHARGER_EFFICIENCY``, [FASTSim])."""

    P_ac_W: float = 7400.0
    efficiency: float = 0.86

    def __post_init__(self):
        _positive("Charger", P_ac_W=self.P_ac_W, efficiency=self.efficiency)
        if self.efficiency > 1.0:
            raise ConfigError(f"Charger: efficiency must be at most 1, got {self.efficiency}")

    def grid_J(self, E_dc_J: float) -> float:
        """Grid (AC) energy that delivers ``E_dc_J`` on the car's DC side."""
        return E_dc_J / self.efficiency

    def covers(self, P_dc_W: float) -> bool:
        """Whether the charger alone can supply a DC load of ``P_dc_W``."""
        return P_dc_W <= self.P_ac_W * self.efficiency

    def time_to_charge_s(self, E_dc_J: float) -> float:
        """Time to put ``E_dc_J`` into the battery at full power, s."""
        return E_dc_J / (self.P_ac_W * self.efficiency)


__all__ = ["Battery", "Charger", "J_PER_KWH"]
