"""Intelligent Constraint Management (ICM): a speed-coordinated upper bound on T_cab.

The A/C is more efficient when the vehicle is fast: ram air through the condenser lowers
the condensing pressure and the compressor work (paper section II-A, Table I: about 30 %
less energy at 25 m/s than at standstill). Given a speed profile previewed at t = 0 (a
connected and automated vehicle knows it from V2V/V2I and traffic models, paper section
IV-C), ICM moves the NMPC's upper cabin bound ``T_cab_max`` inside a comfort band so that the
controller cools more while driving fast and lets the cabin warm while slow or stopped
(paper Fig. 9). The NMPC then minimises energy under that bound; it rides the bound.

The rule (all parameters in :class:`ICMConfig`):

1. **Speed to bound**, a linear map clipped to the comfort band::

       r(t) = clip((v(t) - v_slow) / (v_fast - v_slow), 0, 1)
       target(t) = T_high - r(t) * (T_high - T_low)

   ``T_low`` when at or above ``v_fast`` (cool: efficient), ``T_high`` at or below
   ``v_slow`` (warm: inefficient), linear in between.
2. **Rate limits**, applied forward in time: the bound may fall at most ``fall_rate`` K/s
   (so that the cabin can follow it with the available cooling power and the NMPC is not
   handed an infeasible step) and rise at most ``rise_rate`` K/s (comfort: no sudden jump,
   and the cabin warms at a finite rate anyway)::

       T_max(t_j) = clip(target(t_j), T_max(t_{j-1}) - fall_rate * dt,
                                     T_max(t_{j-1}) + rise_rate * dt)

   starting from ``target(t_0)`` (or ``initial`` when given).

Temperatures are kelvin; speeds m/s; times s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acid.errors import ConfigError
from acid.units import C2K


@dataclass(frozen=True)
class ICMConfig:
    """Parameters of the ICM rule.

    Attributes
    ----------
    T_low : bound when fast (cool while efficient), K. Default 22 degC.
    T_high : bound when slow or stopped (let the cabin warm), K. Default 26 degC.
    v_slow : at or below this speed the bound is ``T_high``, m/s. Default 2 m/s.
    v_fast : at or above this speed the bound is ``T_low``, m/s. Default 20 m/s.
    fall_rate : largest decrease of the bound, K/s. Default 0.1 K/s (2 K in 20 s, what the
        A/C achieves near its limits with the paper's model).
    rise_rate : largest increase of the bound, K/s. Default 0.2 K/s.
    """

    T_low: float = C2K(22.0)
    T_high: float = C2K(26.0)
    v_slow: float = 2.0
    v_fast: float = 20.0
    fall_rate: float = 0.1
    rise_rate: float = 0.2

    def __post_init__(self):
        if not self.T_low < self.T_high:
            raise ConfigError(f"ICM: T_low ({self.T_low} K) must be below T_high "
                              f"({self.T_high} K)")
        if not 0.0 <= self.v_slow < self.v_fast:
            raise ConfigError(f"ICM: need 0 <= v_slow < v_fast, got {self.v_slow}, "
                              f"{self.v_fast} m/s")
        if not (self.fall_rate > 0 and self.rise_rate > 0):
            raise ConfigError("ICM: fall_rate and rise_rate must be positive (K/s)")

    def to_json_dict(self) -> dict:
        """The rule's parameters (K, m/s, K/s)."""
        return {"T_low_K": self.T_low, "T_high_K": self.T_high, "v_slow_m_s": self.v_slow,
                "v_fast_m_s": self.v_fast, "fall_rate_K_s": self.fall_rate,
                "rise_rate_K_s": self.rise_rate}


def speed_target(v_veh, config: ICMConfig | None = None) -> np.ndarray:
    """Step 1 of the rule: the comfort-band bound for each speed (K), no rate limit."""
    c = config or ICMConfig()
    r = np.clip((np.asarray(v_veh, dtype=float) - c.v_slow) / (c.v_fast - c.v_slow), 0.0, 1.0)
    return c.T_high - r * (c.T_high - c.T_low)


def icm_upper_bound(time_s, v_veh, config: ICMConfig | None = None,
                    initial: float | None = None) -> np.ndarray:
    """The ICM upper bound on T_cab over a previewed speed profile (paper Fig. 9).

    Parameters
    ----------
    time_s : (n,) increasing sample times, s.
    v_veh : (n,) previewed vehicle speed at those times, m/s.
    config : rule parameters (defaults of :class:`ICMConfig`).
    initial : bound at ``time_s[0]``, K (default: the speed target there).

    Returns
    -------
    (n,) upper bound on T_cab, K, inside ``[T_low, T_high]`` (or starting from ``initial``).
    """
    c = config or ICMConfig()
    t = np.asarray(time_s, dtype=float)
    target = speed_target(v_veh, c)
    if t.shape != target.shape or t.ndim != 1 or t.size == 0:
        raise ConfigError("ICM: time and speed profiles must be 1-D arrays of equal length")
    if np.any(np.diff(t) <= 0):
        raise ConfigError("ICM: sample times must increase")
    out = np.empty_like(target)
    out[0] = target[0] if initial is None else float(initial)
    for j in range(1, t.size):
        dt = t[j] - t[j - 1]
        out[j] = np.clip(target[j], out[j - 1] - c.fall_rate * dt,
                         out[j - 1] + c.rise_rate * dt)
    return out
