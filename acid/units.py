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
    """Convert ``values`` between units; only temperatures need converting."""
    if from_unit == to_unit:
        return values
    if from_unit == "degC" and to_unit == "K":
        return C2K(values)
    if from_unit == "K" and to_unit == "degC":
        return K2C(values)
    raise ValueError(f"cannot convert {from_unit!r} to {to_unit!r}")


def temperature_unit_consistent(values: np.ndarray, unit: str) -> bool:
    """True when every finite value lies in the plausible range of ``unit``.

    Catches the common slip of storing kelvin under a degC label or vice versa: a cabin at
    300 degC or at 25 K is not a cabin.
    """
    lo, hi = _PLAUSIBLE[unit]
    v = np.asarray(values, dtype=float)
    return bool(np.all((v >= lo) & (v <= hi)))
