"""Moist-air relations (psychrometrics) for models: numpy arrays and CasADi symbols alike.

Saturation vapour pressure over water by the Magnus formula with the Sonntag (1990)
constants recommended by the WMO (2008, Guide to Meteorological Instruments, Annex 4.B):
``p_ws = 611.2 exp(17.62 t / (243.12 + t))`` Pa, ``t`` in degC, better than 0.1 % from -45
to 60 degC. Humidity ratio ``w = 0.621945 p_w / (p_atm - p_w)`` (kg water per kg dry air;
0.621945 is the ratio of the molar masses of water and dry air). Temperatures in K.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

P_ATM = 101325.0
"""Standard atmosphere, Pa."""

H_FG = 2.45e6
"""Latent heat of vaporisation of water near 20 degC, J/kg (steam tables: 2.454e6)."""

_MW_RATIO = 0.621945


def _exp(x):
    """exp that keeps CasADi symbols symbolic and numpy arrays numeric."""
    return ca.exp(x) if isinstance(x, (ca.SX, ca.MX)) else np.exp(x)


def saturation_pressure(T):
    """Saturation vapour pressure of water at ``T`` (K), Pa (Magnus, WMO 2008)."""
    t = T - 273.15
    return 611.2 * _exp(17.62 * t / (243.12 + t))


def humidity_ratio(T, RH, p_atm: float = P_ATM):
    """Humidity ratio of air at ``T`` (K) and relative humidity ``RH`` (0-1), kg/kg."""
    p_w = RH * saturation_pressure(T)
    return _MW_RATIO * p_w / (p_atm - p_w)


def relative_humidity(T, w, p_atm: float = P_ATM):
    """Relative humidity (0-1) of air at ``T`` (K) with humidity ratio ``w`` (kg/kg)."""
    p_w = w * p_atm / (_MW_RATIO + w)
    return p_w / saturation_pressure(T)
