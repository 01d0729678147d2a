"""Tuned PI baselines of ``acid cav-study`` and the sweeps: what a production unit would do.

Both baselines are the plant's own loops (:mod:`acid.plant.controller`): the blower flow is
the plant's :class:`~acid.plant.controller.BlowerLoop` (PI on the cabin air error, anti-windup)
run at the sample time, and the compressor tracks the evaporator-wall set-point with the
plant's internal compressor PI (the plant's "direct" mode). They differ only in the coil
(evaporator-wall) set-point:

* **production-style automatic climate control** (:class:`CoilReset`): the set-point is reset
  as production units do. Pull-down: a cabin warmer than its set-point by ``e_cold`` or more
  gets the coldest coil (``T_cold``, 3 degC, the paper's Table II lower limit); as the cabin
  error shrinks to ``e_warm`` the set-point rises linearly to ``T_warm`` (11 degC): a warm coil
  is cheaper (higher evaporating pressure, less condensate). Humidity overrides: above
  ``RH_high`` cabin relative humidity the set-point is pulled down, linearly, to ``T_cold``
  at ``RH_high + RH_span`` (dehumidification, fog protection). The set-point moves at most
  ``rate`` K/s. This is the practice vendors describe for humidity-sensor climate control
  (the evaporator cools the air only as far as the humidity requires, "enabling a large
  reduction in operating rate of the compressor": Keihin, climate control systems,
  http://www.keihin-na.com/automotive/climate-control/); the thresholds are acid's.
* **best fixed-coil PI at equal comfort** (:func:`golden_min`): the coil set-point held
  constant, searched over ``[3, 12]`` degC by golden section, each point tuned to the study's
  mean cabin temperature; the least tail-corrected energy with the cabin RH inside the band
  (:data:`acid.comfort.RH_BAND`) wins.

The cabin set-point ``T_cab_set`` of either is what ``acid cav-study`` tunes to the common
mean cabin temperature. Temperatures in K inside, relative humidity as a fraction.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from acid.errors import ConfigError
from acid.plant.controller import BlowerLoop
from acid.psychro import P_ATM, relative_humidity
from acid.units import C2K

#: the coil set-point range of the fixed-coil search, K (Table II's 3 degC to a warm 12 degC)
COIL_RANGE = (C2K(3.0), C2K(12.0))


@dataclass(frozen=True)
class CoilReset:
    """The production-style evaporator set-point reset (module docstring), K and fractions."""

    T_cold: float = C2K(3.0)
    T_warm: float = C2K(11.0)
    e_cold: float = 1.5
    e_warm: float = 0.3
    RH_high: float = 0.55
    RH_span: float = 0.05
    rate: float = 0.05

    def __post_init__(self):
        if not (self.T_cold < self.T_warm and self.e_warm < self.e_cold
                and 0.0 < self.RH_high < 1.0 and self.RH_span > 0 and self.rate > 0):
            raise ConfigError("coil reset: need T_cold < T_warm, e_warm < e_cold, "
                              "0 < RH_high < 1, RH_span > 0 and rate > 0")

    def target(self, e_cab: float, rh: float) -> float:
        """Set-point the rule asks for at cabin error ``e_cab`` (K) and RH ``rh`` (0-1), K."""
        span = self.T_warm - self.T_cold
        by_error = self.T_warm - span * min(1.0, max(0.0, (e_cab - self.e_warm)
                                                     / (self.e_cold - self.e_warm)))
        by_humidity = self.T_warm - span * min(1.0, max(0.0, (rh - self.RH_high)
                                                        / self.RH_span))
        return min(by_error, by_humidity)

    def describe(self) -> str:
        """The rule in one line (degC and %), for the CLI and the JSON."""
        return (f"coil set-point {self.T_cold - 273.15:g} degC at a cabin error of "
                f"{self.e_cold:g} K or more, rising linearly to {self.T_warm - 273.15:g} degC "
                f"as the error falls to {self.e_warm:g} K; pulled down to "
                f"{self.T_cold - 273.15:g} degC as cabin RH rises from "
                f"{100 * self.RH_high:g} % to {100 * (self.RH_high + self.RH_span):g} %; at "
                f"most {self.rate:g} K/s")

    def to_json_dict(self) -> dict:
        return {"rule": self.describe(), "T_cold_K": self.T_cold, "T_warm_K": self.T_warm,
                "e_cold_K": self.e_cold, "e_warm_K": self.e_warm, "RH_high": self.RH_high,
                "RH_span": self.RH_span, "rate_K_s": self.rate}


@dataclass
class _Log:
    step_time_s: list = field(default_factory=list)
    fallback: list = field(default_factory=list)


class PlantPI:
    """The plant's blower PI plus a coil set-point (fixed, K, or a :class:`CoilReset`).

    ``make_step(meas, k)`` returns ``[W_bl, T_evap_set]`` for the plant's direct mode;
    ``loops`` is any object with the blower loop's gains (``Kp_bl``, ``Ki_bl``, ``W_bl_min``,
    ``W_bl_max``, ``anti_windup``), e.g. the plant's ``PlantConfig``.
    """

    def __init__(self, loops, Ts: float, T_cab_set: float, coil, p_atm: float = P_ATM):
        self.loops, self.Ts, self.T_cab_set = loops, float(Ts), float(T_cab_set)
        self.coil, self.p_atm = coil, float(p_atm)
        self.reset()

    def reset(self) -> None:
        self.blower = BlowerLoop(self.loops)
        self.T_set = self.coil.T_cold if isinstance(self.coil, CoilReset) else float(self.coil)
        self.log = _Log()

    def make_step(self, meas: dict, k: int) -> np.ndarray:
        T_cab = float(meas["T_cab"])
        W = self.blower.update(T_cab, self.T_cab_set, self.Ts)
        if isinstance(self.coil, CoilReset):
            rh = float(relative_humidity(T_cab, float(meas["w_cab"]), self.p_atm))
            goal = self.coil.target(T_cab - self.T_cab_set, rh)
            step = self.coil.rate * self.Ts
            self.T_set += min(step, max(-step, goal - self.T_set))
        self.log.step_time_s.append(0.0)
        self.log.fallback.append(False)
        return np.array([W, self.T_set])


def golden_min(f: Callable[[float], tuple], lo: float, hi: float, tol: float = 0.25,
               max_eval: int = 12):
    """Golden-section search of a unimodal ``f`` on ``[lo, hi]``.

    ``f(x)`` returns ``(key, payload)``; keys are compared with ``<`` (a tuple such as
    ``(outside_band, energy)`` ranks every admissible point first). Returns ``(x, payload,
    history)`` of the best point evaluated, history ``[(x, key)]`` in evaluation order.
    """
    g = (math.sqrt(5.0) - 1.0) / 2.0
    hist, cache = [], {}

    def ev(x):
        if x not in cache:
            cache[x] = f(x)
            hist.append((x, cache[x][0]))
        return cache[x][0]

    a, b = float(lo), float(hi)
    c, d = b - g * (b - a), a + g * (b - a)
    while b - a > tol and len(cache) < max_eval:
        if ev(c) < ev(d):
            b, d = d, c
            c = b - g * (b - a)
        else:
            a, c = c, d
            d = a + g * (b - a)
    for x in (c, d) if not cache else ():
        ev(x)
    best = min(cache, key=lambda x: cache[x][0])
    return best, cache[best][1], tuple(hist)
