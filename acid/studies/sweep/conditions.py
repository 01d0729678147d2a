"""Operating conditions of a sweep scenario and their one mapping onto the plant configuration.

A sweep speaks the user's language (ambient in degC, relative humidity in %, solar irradiance
in W/m2, refrigerant, cabin set-point and comfort band in degC); the high-fidelity plant
speaks :class:`acid.plant.config.PlantConfig` (SI, kelvin). :func:`plant_config_for` is the
only place that translates one into the other, so that a new plant generation needs one
function changed.

Mapping onto the current ``PlantConfig``
----------------------------------------
* ambient -> ``T_amb``; humidity -> ``RH_amb`` (fraction); refrigerant -> ``refrigerant``;
  set-point -> ``T_cab_set`` (the nominal controller's target).
* solar irradiance ``G``: a plant configuration with an irradiance field (``G_solar``,
  W/m2; the second-generation plant) takes it as is; the current one has two absorbed solar gains
  whose default corresponds to ``G_REF = 800 W/m2`` (``Q_solar_shell``: "1.5 m^2 roof x
  800 W/m^2 x 0.6 + sides"), scaled by ``G / G_REF``.
* the hot soak the plant starts from follows the climate: the evaporator and condenser
  walls start at ambient, the cabin air, interior and shell at ambient plus the default
  soak's excess over its 30 degC ambient, scaled by ``G / G_REF`` (no sun, no soak).
"""

from __future__ import annotations

from dataclasses import dataclass

from acid.errors import ConfigError
from acid.plant.config import REFRIGERANTS, PlantConfig
from acid.units import C2K

#: True when the plant configuration has an irradiance field (W/m2) rather than gains (W)
HAS_IRRADIANCE = "G_solar" in PlantConfig.field_names()

#: irradiance of the default plant configuration, W/m2 (the solar gains' reference)
G_REF = float(PlantConfig().G_solar) if HAS_IRRADIANCE else 800.0

#: plant fields set by the conditions (a sweep's ``plant`` overrides may not set them)
MAPPED_FIELDS = {"T_amb": "ambient_C", "RH_amb": "humidity_pct", "refrigerant": "refrigerant",
                 "T_cab_set": "setpoint_C", "G_solar": "solar_W_m2", "Q_solar_int": "solar_W_m2",
                 "Q_solar_shell": "solar_W_m2", "T_cab0": "ambient_C", "T_int0": "ambient_C",
                 "T_shell0": "ambient_C", "T_ew0": "ambient_C", "T_cw0": "ambient_C"}

#: accepted ranges (edge units): a cooling study of a passenger-car A/C
RANGES = {"ambient_C": (0.0, 55.0), "humidity_pct": (0.0, 100.0),
          "solar_W_m2": (0.0, 1400.0), "setpoint_C": (15.0, 32.0)}


@dataclass(frozen=True)
class Conditions:
    """Climate and comfort of one scenario (degC, %, W/m2 at the edge).

    Attributes
    ----------
    ambient_C : outside air temperature, degC.
    humidity_pct : outside relative humidity, %.
    solar_W_m2 : solar irradiance on the vehicle, W/m2.
    refrigerant : ``"R134a"`` or ``"R1234yf"``.
    setpoint_C : cabin set-point, degC (the constant bound of the paper's NMPC, the target
        of the nominal controller).
    band_C : comfort band (low, high), degC (the ICM bound moves inside it; violations are
        measured against it).
    """

    ambient_C: float = 30.0
    humidity_pct: float = 50.0
    solar_W_m2: float = G_REF
    refrigerant: str = "R134a"
    setpoint_C: float = 24.0
    band_C: tuple[float, float] = (22.0, 26.0)

    def __post_init__(self):
        for name, (lo, hi) in RANGES.items():
            v = getattr(self, name)
            if not lo <= v <= hi:
                raise ConfigError(f"{name} = {v:g} is outside {lo:g}..{hi:g}")
        if self.refrigerant not in REFRIGERANTS:
            raise ConfigError(f"refrigerant {self.refrigerant!r} not supported (choose "
                              f"{' or '.join(REFRIGERANTS)})")
        low, high = self.band_C
        if not low < high:
            raise ConfigError(f"band_C = [{low:g}, {high:g}]: low must be below high")
        if not low <= self.setpoint_C <= high:
            raise ConfigError(f"setpoint_C = {self.setpoint_C:g} lies outside band_C = "
                              f"[{low:g}, {high:g}]")

    @property
    def T_amb(self) -> float:
        """Ambient temperature, K."""
        return C2K(self.ambient_C)

    @property
    def T_set(self) -> float:
        """Cabin set-point, K."""
        return C2K(self.setpoint_C)

    @property
    def T_low(self) -> float:
        """Comfort band lower edge, K."""
        return C2K(self.band_C[0])

    @property
    def T_high(self) -> float:
        """Comfort band upper edge, K."""
        return C2K(self.band_C[1])


def plant_config_for(conditions: Conditions, overrides: dict | None = None,
                     base: PlantConfig | None = None) -> PlantConfig:
    """The plant configuration of a scenario: ``base`` + ``overrides`` + the conditions.

    Parameters
    ----------
    conditions : climate and comfort of the scenario.
    overrides : other ``PlantConfig`` fields (SI units, K), e.g. a different vehicle; fields
        that the conditions set (``MAPPED_FIELDS``) are refused.
    base : configuration to start from (default ``PlantConfig()``).

    Raises ``ConfigError`` (one line) for an unknown or conflicting field or a value the
    plant refuses.
    """
    base = base or PlantConfig()
    overrides = dict(overrides or {})
    for key in overrides:
        if key in MAPPED_FIELDS:
            raise ConfigError(f"plant override {key!r} is set by the scenario's "
                              f"{MAPPED_FIELDS[key]}; set that instead")
    cfg = PlantConfig.from_dict({**base.to_dict(), **overrides}, "plant overrides")
    ref = PlantConfig()
    sun = conditions.solar_W_m2 / G_REF
    T_amb = conditions.T_amb
    solar = ({"G_solar": conditions.solar_W_m2} if HAS_IRRADIANCE else
             {"Q_solar_int": ref.Q_solar_int * sun, "Q_solar_shell": ref.Q_solar_shell * sun})
    return cfg.replace(
        T_amb=T_amb, RH_amb=conditions.humidity_pct / 100.0,
        refrigerant=conditions.refrigerant, T_cab_set=conditions.T_set, **solar,
        T_cab0=T_amb + (ref.T_cab0 - ref.T_amb) * sun,
        T_int0=T_amb + (ref.T_int0 - ref.T_amb) * sun,
        T_shell0=T_amb + (ref.T_shell0 - ref.T_amb) * sun,
        T_ew0=T_amb, T_cw0=T_amb)
