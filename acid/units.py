"""Unit handling: kelvin inside the model, degrees Celsius at the edges.

The paper's identified gamma/tau only make sense with temperatures in kelvin (SPEC section 1):
eq. 3 with T_evap = 278.15 K and W_bl = 0.1 kg/s gives T_ain = 284.6 K, whereas the same
formula in degC gives 160 degC. Conversion therefore happens once, where data enter a model.
"""

from __future__ import annotations

import numpy as np

ZERO_CELSIUS = 273.15
"""Offset between the Celsius and Kelvin scales, K."""

TEMPERATURE_UNITS = ("degC", "K")
KNOWN_UNITS = (
    "degC", "K", "kg/s", "m/s", "W", "J", "rpm", "1", "kg/kg", "Pa", "s", "%", "W/K",
)

# Plausible ranges used to catch a temperature whose values contradict its declared unit.
_PLAUSIBLE = {"degC": (-60.0, 150.0), "K": (213.15, 423.15)}


def C2K(T_degC):
    """Celsius to kelvin (works on floats, arrays and CasADi symbols)."""
    return T_degC + ZERO_CELSIUS


def K2C(T_K):
    """Kelvin to Celsius (works on floats, arrays and CasADi symbols)."""
    return T_K - ZERO_CELSIUS


def is_temperature(unit: str) -> bool:
    """Whether ``unit`` is a temperature unit acid understands."""
    return unit in TEMPERATURE_UNITS


def convert(values, from_unit: str, to_unit: str):
    """Convert ``values`` between units of the same quantity (``UNIT_SCALES``).

    Raises ``ValueError`` when a unit is unknown or the two measure different quantities.
    """
    if from_unit == to_unit:
        return values
    if from_unit == "degC" and to_unit == "K":
        return C2K(values)
    if from_unit == "K" and to_unit == "degC":
        return K2C(values)
    if base_unit(from_unit) != base_unit(to_unit):
        raise ValueError(f"cannot convert {from_unit!r} to {to_unit!r}")
    return from_base(to_base(values, from_unit), to_unit)


#: Units acid converts at its edges (FMU maps, imports): unit -> (base unit, factor, offset),
#: with ``value_in_base = value * factor + offset``. The base units are acid's inside units:
#: K, W, J, kg/s, m/s, rpm, 1, kg/kg, Pa, s, W/K.
UNIT_SCALES: dict[str, tuple[str, float, float]] = {
    "K": ("K", 1.0, 0.0),
    "degC": ("K", 1.0, ZERO_CELSIUS),
    "degF": ("K", 5.0 / 9.0, ZERO_CELSIUS - 32.0 * 5.0 / 9.0),
    "W": ("W", 1.0, 0.0),
    "kW": ("W", 1e3, 0.0),
    "J": ("J", 1.0, 0.0),
    "kJ": ("J", 1e3, 0.0),
    "MJ": ("J", 1e6, 0.0),
    "kg/s": ("kg/s", 1.0, 0.0),
    "g/s": ("kg/s", 1e-3, 0.0),
    "kg/h": ("kg/s", 1.0 / 3600.0, 0.0),
    "m/s": ("m/s", 1.0, 0.0),
    "km/h": ("m/s", 1.0 / 3.6, 0.0),
    "rpm": ("rpm", 1.0, 0.0),
    "1/min": ("rpm", 1.0, 0.0),
    "rad/s": ("rpm", 30.0 / np.pi, 0.0),
    "1": ("1", 1.0, 0.0),
    "%": ("1", 0.01, 0.0),
    "kg/kg": ("kg/kg", 1.0, 0.0),
    "g/kg": ("kg/kg", 1e-3, 0.0),
    "Pa": ("Pa", 1.0, 0.0),
    "kPa": ("Pa", 1e3, 0.0),
    "bar": ("Pa", 1e5, 0.0),
    "s": ("s", 1.0, 0.0),
    "W/K": ("W/K", 1.0, 0.0),
}


def base_unit(unit: str) -> str:
    """acid's inside unit for the quantity ``unit`` measures (``"degC"`` -> ``"K"``)."""
    try:
        return UNIT_SCALES[unit][0]
    except KeyError:
        raise ValueError(f"unknown unit {unit!r} (known: {', '.join(UNIT_SCALES)})") from None


def to_base(values, unit: str):
    """``values`` in ``unit`` converted to acid's inside unit (``base_unit(unit)``)."""
    _, factor, offset = UNIT_SCALES[unit] if unit in UNIT_SCALES else (base_unit(unit), 1, 0)
    return values if (factor, offset) == (1.0, 0.0) else values * factor + offset


def from_base(values, unit: str):
    """``values`` in acid's inside unit converted to ``unit`` (inverse of ``to_base``)."""
    _, factor, offset = UNIT_SCALES[unit] if unit in UNIT_SCALES else (base_unit(unit), 1, 0)
    return values if (factor, offset) == (1.0, 0.0) else (values - offset) / factor


def temperature_unit_consistent(values: np.ndarray, unit: str) -> bool:
    """True when every finite value lies in the plausible range of ``unit``.

    Catches the common slip of storing kelvin under a degC label or vice versa: a cabin at
    300 degC or at 25 K is not a cabin.
    """
    lo, hi = _PLAUSIBLE[unit]
    v = np.asarray(values, dtype=float)
    return bool(np.all((v >= lo) & (v <= hi)))


# ------------------------------------------------------------------ unit-aware values
class Temperature(float):
    """A temperature that knows its scale: a float whose value is in **kelvin**.

    Make one with :func:`degC` or :func:`kelvin`; pass it anywhere acid takes a temperature.
    Arguments documented in K use it as is; those documented in degC (the excitation spec's
    bounds) convert it (:func:`in_degC`). Plain numbers keep the documented unit of each
    argument, so a value is never guessed::

        acid.make_plant("hifi", T_amb=acid.degC(35))          # 308.15 K
        acid.ExcitationSpec(T_evap_set_bounds=(acid.degC(3), acid.degC(10)))
    """

    __slots__ = ()

    @property
    def K(self) -> float:
        """Value in kelvin."""
        return float(self)

    @property
    def degC(self) -> float:
        """Value in degrees Celsius."""
        return float(self) - ZERO_CELSIUS

    def __repr__(self) -> str:
        return f"{self.degC:g} degC ({float(self):g} K)"


def degC(value: float) -> Temperature:
    """A temperature given in degrees Celsius (its float value is kelvin)."""
    return Temperature(float(value) + ZERO_CELSIUS)


def kelvin(value: float) -> Temperature:
    """A temperature given in kelvin."""
    return Temperature(float(value))


def in_degC(value):
    """``value`` in degC: a :class:`Temperature` is converted, a plain number is degC."""
    return value.degC if isinstance(value, Temperature) else value
