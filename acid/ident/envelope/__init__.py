"""The envelope of an identified econ model: the ranges of its identification data, and
which steps of a prediction or a plan leave them.

An econ model (:mod:`acid.models.econ`) is trusted where its data were: its power map was
fitted on the cooling powers, evaporator temperatures, speeds and ambients of one record,
its cabin and coil balances on that record's cabin temperatures and blower flows. A hot
pull-down asks for cooling and evaporator temperatures no random excitation from a cool
cabin reaches; a controller planning there extrapolates. :func:`envelope_ranges` takes the
ranges of ``CHANNELS`` on the rows a fit used (``acid.ident.econ.identify`` stores them as
``PowerMap.envelope``); :class:`Envelope` flags values outside them (a margin of
``MARGIN`` of each range, as the power map's own ``outside``) and measures the excursion.
Units: SI and kelvin inside; degC in the messages.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: (name, unit) of the envelope's channels: refrigerant-side cooling, evaporator
#: temperature, cabin temperature, blower flow, ambient temperature
CHANNELS = (("Q_e", "W"), ("T_evap", "K"), ("T_cab", "K"), ("W_bl", "kg/s"), ("T_amb", "K"))
_UNITS = dict(CHANNELS)
#: share of each range tolerated beyond it (the power map's ``outside`` uses the same 2 %)
MARGIN = 0.02


def envelope_ranges(**values) -> dict[str, tuple[float, float]]:
    """{name: (min, max)} of each given array (finite values only), for ``CHANNELS``."""
    out = {}
    for name, v in values.items():
        if name not in _UNITS:
            raise KeyError(f"envelope: unknown channel {name!r} (known: "
                           f"{', '.join(_UNITS)})")
        a = np.asarray(v, dtype=float).ravel()
        a = a[np.isfinite(a)]
        if a.size:
            out[name] = (float(a.min()), float(a.max()))
    return out


def _show(name: str, value: float) -> str:
    unit = _UNITS.get(name, "")
    if unit == "K":
        return f"{value - 273.15:.3g} degC"
    if unit == "W":
        return f"{value / 1000.0:.3g} kW"
    return f"{value:.3g} {unit}"


@dataclass(frozen=True)
class Excursion:
    """How far steps left an envelope: ``n`` steps checked, ``n_outside`` of them outside
    (any channel), and the worst: ``channel``, its ``value`` (SI, K) and the distance beyond
    the range's edge in units of the range's width (``relative``: 0.5 = half a range)."""

    n: int = 0
    n_outside: int = 0
    channel: str = ""
    value: float = math.nan
    relative: float = 0.0
    by_channel: dict = field(default_factory=dict)

    def merged(self, other: Excursion) -> Excursion:
        """Two counts joined (a run's steps one at a time)."""
        worst = other if other.relative > self.relative else self
        by = dict(self.by_channel)
        for k, v in other.by_channel.items():
            by[k] = by.get(k, 0) + v
        return Excursion(self.n + other.n, self.n_outside + other.n_outside, worst.channel,
                         worst.value, worst.relative, by)

    def summary(self, envelope: Envelope | None = None) -> str:
        """One line: the count and the worst excursion (with the data's range if given)."""
        if self.n_outside == 0:
            return f"0 of {self.n} steps outside the model's envelope"
        rng = ""
        if envelope is not None and self.channel in envelope.ranges:
            lo, hi = envelope.ranges[self.channel]
            rng = f" (data {_show(self.channel, lo)} to {_show(self.channel, hi)})"
        return (f"{self.n_outside} of {self.n} steps outside the model's envelope; worst "
                f"{self.channel} {_show(self.channel, self.value)}{rng}")

    def to_dict(self) -> dict:
        return {"n": self.n, "n_outside": self.n_outside, "worst_channel": self.channel,
                "worst_value": self.value, "worst_relative": self.relative,
                "by_channel": dict(self.by_channel)}


@dataclass(frozen=True)
class Envelope:
    """The ranges (SI, K) of an econ model's identification data (``CHANNELS``)."""

    ranges: dict

    def __post_init__(self):
        object.__setattr__(self, "ranges", {k: (float(v[0]), float(v[1]))
                                            for k, v in (self.ranges or {}).items()})
        object.__setattr__(self, "_bounds", {k: self.bounds(k) for k in self.ranges})

    def inside(self, **values: float) -> bool:
        """Whether one step's scalar values all lie inside (the cheap test, per step)."""
        b = self._bounds
        for name, v in values.items():
            lo_hi = b.get(name)
            if lo_hi is not None and not lo_hi[0] <= v <= lo_hi[1]:
                return False
        return True

    @classmethod
    def of(cls, params) -> Envelope:
        """The envelope an identified econ model carries (its ``power_map.envelope``); for
        a file written before the envelope was stored, the power map's domain (Q_e,
        T_evap, T_amb; T_cab and W_bl then unchecked)."""
        pm = params.power_map
        env = dict(getattr(pm, "envelope", None) or {})
        for name in ("Q_e", "T_evap", "T_amb"):
            if name not in env and name in pm.domain:
                env[name] = pm.domain[name]
        return cls(env)

    def bounds(self, name: str) -> tuple[float, float] | None:
        """The accepted range of ``name`` (its data's range widened by ``MARGIN``)."""
        if name not in self.ranges:
            return None
        lo, hi = self.ranges[name]
        tol = MARGIN * (hi - lo)
        return lo - tol, hi + tol

    def relative(self, name: str, values) -> np.ndarray:
        """Distance beyond the accepted range per value, in range widths (0 inside)."""
        v = np.asarray(values, dtype=float)
        b = self.bounds(name)
        if b is None:
            return np.zeros(v.shape)
        lo, hi = self.ranges[name]
        width = max(hi - lo, 1e-12)
        return np.maximum(0.0, np.maximum(v - b[1], b[0] - v)) / width

    def flags(self, **values) -> np.ndarray:
        """(n,) True where any given channel (arrays of one length) is outside."""
        out = None
        for name, v in values.items():
            f = self.relative(name, v) > 0
            out = f if out is None else out | f
        return np.zeros(0, dtype=bool) if out is None else out

    def check(self, **values) -> Excursion:
        """The :class:`Excursion` of the given steps (channels as arrays of one length)."""
        n, worst, by = 0, ("", math.nan, 0.0), {}
        flagged = None
        for name, v in values.items():
            v = np.atleast_1d(np.asarray(v, dtype=float))
            r = self.relative(name, v)
            n = max(n, v.size)
            f = r > 0
            by[name] = int(f.sum())
            flagged = f if flagged is None else flagged | f
            if r.size and float(r.max()) > worst[2]:
                i = int(np.argmax(r))
                worst = (name, float(v[i]), float(r[i]))
        return Excursion(n, 0 if flagged is None else int(flagged.sum()), *worst,
                         {k: v for k, v in by.items() if v})

    def describe(self) -> str:
        """One line: every range in user units."""
        return ", ".join(f"{k} {_show(k, lo)} to {_show(k, hi)}"
                         for k, (lo, hi) in self.ranges.items())

    def to_dict(self) -> dict:
        return {k: list(v) for k, v in self.ranges.items()}
