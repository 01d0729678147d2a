"""Unit handling: kelvin inside the model, degrees Celsius at the edges.

The paper's identified gamma/tau only make sense with temperatures in kelvin (SPEC section 1):
eq. 3 with T_evap = 278.15 K and W_bl = 0.1 kg/s gives T_ain = 284.6 K, whereas the same
formula in degC gives 160 degC. Conversion therefore happens once, where data enter a model.
"""

from __future__ import annotations

import math
import re

import numpy as np

ZERO_CELSIUS = 273.15
"""Offset between the Celsius and Kelvin scales, K."""

TEMPERATURE_UNITS = ("degC", "K")

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


#: The one unit table of acid's edges (import maps, FMU maps, FMU export):
#: unit -> (base unit, factor, offset), with ``value_in_base = value * factor + offset``.
#: The base units are acid's inside units (K, W, kg/s, m/s, ...); datasets store every
#: channel in its base unit, except temperatures, which they store in degC (``storage_unit``).
UNIT_SCALES: dict[str, tuple[str, float, float]] = {
    # temperature
    "K": ("K", 1.0, 0.0),
    "degC": ("K", 1.0, ZERO_CELSIUS),
    "\u00b0C": ("K", 1.0, ZERO_CELSIUS),
    "degF": ("K", 5.0 / 9.0, ZERO_CELSIUS - 32.0 * 5.0 / 9.0),
    "\u00b0F": ("K", 5.0 / 9.0, ZERO_CELSIUS - 32.0 * 5.0 / 9.0),
    # power and energy
    "W": ("W", 1.0, 0.0),
    "kW": ("W", 1e3, 0.0),
    "J": ("J", 1.0, 0.0),
    "kJ": ("J", 1e3, 0.0),
    "MJ": ("J", 1e6, 0.0),
    "Wh": ("J", 3600.0, 0.0),
    "kWh": ("J", 3.6e6, 0.0),
    # mass flow
    "kg/s": ("kg/s", 1.0, 0.0),
    "g/s": ("kg/s", 1e-3, 0.0),
    "kg/min": ("kg/s", 1.0 / 60.0, 0.0),
    "kg/h": ("kg/s", 1.0 / 3600.0, 0.0),
    # volume flow
    "m3/s": ("m3/s", 1.0, 0.0),
    "m3/h": ("m3/s", 1.0 / 3600.0, 0.0),
    "l/min": ("m3/s", 1e-3 / 60.0, 0.0),
    "l/h": ("m3/s", 1e-3 / 3600.0, 0.0),
    # speed, acceleration, length
    "m/s": ("m/s", 1.0, 0.0),
    "km/h": ("m/s", 1.0 / 3.6, 0.0),
    "mph": ("m/s", 0.44704, 0.0),
    "m/s2": ("m/s2", 1.0, 0.0),
    "m/s^2": ("m/s2", 1.0, 0.0),
    "m": ("m", 1.0, 0.0),
    "km": ("m", 1e3, 0.0),
    # rotation, torque
    "rpm": ("rpm", 1.0, 0.0),
    "1/min": ("rpm", 1.0, 0.0),
    "rad/s": ("rpm", 30.0 / np.pi, 0.0),
    "Nm": ("Nm", 1.0, 0.0),
    # fractions and humidity
    "1": ("1", 1.0, 0.0),
    "-": ("1", 1.0, 0.0),      # dimensionless, as engineering tables write it
    "%": ("1", 0.01, 0.0),
    "%RH": ("1", 0.01, 0.0),
    "kg/kg": ("kg/kg", 1.0, 0.0),
    "g/kg": ("kg/kg", 1e-3, 0.0),
    # pressure
    "Pa": ("Pa", 1.0, 0.0),
    "hPa": ("Pa", 1e2, 0.0),
    "mbar": ("Pa", 1e2, 0.0),
    "kPa": ("Pa", 1e3, 0.0),
    "bar": ("Pa", 1e5, 0.0),
    # time
    "s": ("s", 1.0, 0.0),
    "ms": ("s", 1e-3, 0.0),
    "min": ("s", 60.0, 0.0),
    "h": ("s", 3600.0, 0.0),
    # heat transfer, heat capacity, irradiance
    "W/K": ("W/K", 1.0, 0.0),
    "J/K": ("J/K", 1.0, 0.0),
    "kJ/K": ("J/K", 1e3, 0.0),
    "W/m2": ("W/m2", 1.0, 0.0),
    "W/m^2": ("W/m2", 1.0, 0.0),
    # electrical
    "V": ("V", 1.0, 0.0),
    "A": ("A", 1.0, 0.0),
}

#: SI dimensions of each base unit (FMI ``BaseUnit`` exponents; rpm counts as rad/s), so an
#: exported FMU declares its units and an FMU's own unit definitions are understood.
BASE_DIMENSIONS: dict[str, dict[str, int]] = {
    "K": {"K": 1}, "W": {"kg": 1, "m": 2, "s": -3}, "J": {"kg": 1, "m": 2, "s": -2},
    "kg/s": {"kg": 1, "s": -1}, "m3/s": {"m": 3, "s": -1}, "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2}, "m": {"m": 1}, "rpm": {"rad": 1, "s": -1},
    "Nm": {"kg": 1, "m": 2, "s": -2}, "1": {}, "kg/kg": {}, "Pa": {"kg": 1, "m": -1, "s": -2},
    "s": {"s": 1}, "W/K": {"kg": 1, "m": 2, "s": -3, "K": -1},
    "J/K": {"kg": 1, "m": 2, "s": -2, "K": -1}, "W/m2": {"kg": 1, "s": -3},
    "V": {"kg": 1, "m": 2, "s": -3, "A": -1}, "A": {"A": 1},
}

#: Units a stored dataset's channel may carry: degC (temperatures) and the base units; "%"
#: is kept for datasets written before the table existed.
KNOWN_UNITS: tuple[str, ...] = tuple(dict.fromkeys(
    ["degC", "K", *(b for b, _, _ in UNIT_SCALES.values()), "%"]))


def storage_unit(unit: str) -> str:
    """The unit a dataset stores a channel declared in ``unit`` in: degC for temperatures,
    else acid's base unit (``"km/h"`` -> ``"m/s"``, ``"kW"`` -> ``"W"``)."""
    base = base_unit(unit)
    return "degC" if base == "K" else base


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
    """True when every finite value lies in the plausible range of ``unit`` (-60 .. 150 degC
    in any temperature unit of ``UNIT_SCALES``).

    Catches the common slip of storing kelvin under a degC label or vice versa: a cabin at
    300 degC or at 25 K is not a cabin.
    """
    v = np.asarray(values, dtype=float)
    if unit not in _PLAUSIBLE:
        v = K2C(to_base(v, unit))
        unit = "degC"
    lo, hi = _PLAUSIBLE[unit]
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


# ------------------------------------------------------------------ compound units
#: Atoms of compound units beyond ``UNIT_SCALES`` (whose single-word, offset-free units are
#: atoms too, with ``BASE_DIMENSIONS``): name -> (factor to SI, {dimension: power}).
_EXTRA_ATOMS: dict[str, tuple[float, dict[str, float]]] = {
    "kg": (1.0, {"kg": 1}), "g": (1e-3, {"kg": 1}), "mm": (1e-3, {"m": 1}),
    "min": (60.0, {"s": 1}), "h": (3600.0, {"s": 1}), "N": (1.0, {"kg": 1, "m": 1, "s": -2}),
}


def _atom(name: str):
    """(factor, dimensions) of one word of a compound unit, or None."""
    if name in _EXTRA_ATOMS:
        f, d = _EXTRA_ATOMS[name]
        return f, dict(d)
    row = UNIT_SCALES.get(name)
    if row is None or "/" in name or row[2] != 0.0:
        return None
    base, factor, _ = row
    return factor, dict(BASE_DIMENSIONS.get(base, {}))


def parse_unit(text: str) -> tuple[float, dict[str, float]]:
    """A compound unit such as ``"W/K"``, ``"kJ/K"``, ``"K s/kg"``, ``"J/(kg K)"`` or
    ``"W/K/(m/s)^0.8"`` as (factor to SI, {dimension: power}).

    A unit of ``UNIT_SCALES`` is read from that one table (``degC`` and ``degF`` alone, as
    temperatures). Otherwise: factors separated by spaces, ``*`` or ``/`` (``/`` divides by
    the next factor only); a factor is a word (an offset-free unit of ``UNIT_SCALES`` or
    kg, g, mm, min, h, N), ``1`` or a parenthesised unit, with an optional ``^power``.
    Raises ``ValueError`` naming the part it cannot read.
    """
    text = str(text).strip()
    if text in UNIT_SCALES:
        base, factor, _ = UNIT_SCALES[text]
        return factor, {k: float(v) for k, v in BASE_DIMENSIONS.get(base, {}).items()}
    tokens = _unit_tokens(text)
    factor, dims, pos = _unit_product(tokens, 0, text)
    if pos != len(tokens):
        raise ValueError(f"cannot read unit {text!r} at {tokens[pos]!r}")
    return factor, {k: v for k, v in dims.items() if v != 0}


def _unit_tokens(text: str) -> list[str]:
    import re

    tokens = re.findall(r"[A-Za-z%]+|\d+(?:\.\d+)?|[()*/^·-]|\S", text)
    if not tokens:
        raise ValueError("empty unit (write '1' for a dimensionless quantity)")
    return tokens


def _unit_product(tokens, pos, text):
    factor, dims = 1.0, {}
    divide = False
    expect = True
    while pos < len(tokens) and tokens[pos] != ")":
        tok = tokens[pos]
        if tok in ("*", "·"):
            pos += 1
            continue
        if tok == "/":
            divide, pos = True, pos + 1
            continue
        if tok == "(":
            f, d, pos = _unit_product(tokens, pos + 1, text)
            if pos >= len(tokens) or tokens[pos] != ")":
                raise ValueError(f"unit {text!r}: unbalanced parenthesis")
            pos += 1
        elif _atom(tok) is not None:
            f, d = _atom(tok)
            pos += 1
        else:
            raise ValueError(f"unit {text!r}: unknown unit {tok!r} (known: "
                             f"{', '.join(u for u in UNIT_SCALES if u not in ('1', '-'))}, "
                             "kg, g, mm, min, h, N, and their products, quotients and powers "
                             "such as 'W/(m^2 K)' or '1/s^2'; degC alone; '1' or '-' for a "
                             "dimensionless quantity)")
        power = 1.0
        if pos < len(tokens) and tokens[pos] == "^":
            sign = 1.0
            pos += 1
            if pos < len(tokens) and tokens[pos] == "-":
                sign, pos = -1.0, pos + 1
            try:
                power = sign * float(tokens[pos])
            except (IndexError, ValueError):
                raise ValueError(f"unit {text!r}: '^' needs a number") from None
            pos += 1
        if divide:
            power, divide = -power, False
        factor *= f ** power
        for k, v in d.items():
            dims[k] = dims.get(k, 0.0) + v * power
        expect = False
    if expect or divide:
        raise ValueError(f"unit {text!r}: incomplete")
    return factor, dims, pos


#: an absolute temperature in kelvin (what a result object may carry inside): the values a
#: key ending ``_K`` holds when it is a temperature and not a difference (a difference of
#: 150 K or more is no difference acid ever reports)
_KELVIN_RANGE = (150.0, 450.0)


#: keys whose ``_K`` is part of a derived unit (W/K, J/(kg K), ...), never a temperature
_DERIVED_K = re.compile(r"(per|_W|_kW|_J|_kJ|_MJ|_kg|_s|_m2|_m)_K$")


def _absolute_kelvin(value) -> bool:
    """True when ``value`` is a number or a (nested) list of numbers, at least one finite,
    every finite one inside ``_KELVIN_RANGE``."""
    if isinstance(value, bool):
        return False
    if isinstance(value, (int, float)):
        return math.isfinite(value) and _KELVIN_RANGE[0] <= value <= _KELVIN_RANGE[1]
    if isinstance(value, (list, tuple)) and value:
        finite = [v for v in value if not (isinstance(v, float) and not math.isfinite(v))
                  and v is not None]
        return bool(finite) and all(_absolute_kelvin(v) for v in finite)
    return False


def _to_degC(value):
    if isinstance(value, (list, tuple)):
        return [_to_degC(v) for v in value]
    if value is None or not math.isfinite(value):
        return value
    return round(value - ZERO_CELSIUS, 9)


def json_in_degC(obj):
    """A JSON-ready copy of ``obj`` for the user: every absolute temperature in degC.

    Result objects speak kelvin inside (``T_amb_K``, ``final_T_cab_K``); a key ending ``_K``
    whose numbers are absolute temperatures (``_KELVIN_RANGE``) becomes ``..._C`` with its
    values in degC. Temperature differences (``max_violation_K``, ``rmse_K``: a kelvin and a
    degC of difference are the same) keep their names.
    """
    if isinstance(obj, dict):
        out = {}
        for key, value in obj.items():
            if (isinstance(key, str) and key.endswith("_K") and not _DERIVED_K.search(key)
                    and _absolute_kelvin(value)):
                out[key[:-2] + "_C"] = _to_degC(value)
            else:
                out[key] = json_in_degC(value)
        return out
    if isinstance(obj, (list, tuple)):
        return [json_in_degC(v) for v in obj]
    return obj
