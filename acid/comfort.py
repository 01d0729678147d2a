"""Thermal comfort of a cabin trajectory: Fanger's PMV (ISO 7730:2005) via ``pythermalcomfort``.

The inputs a cabin run has are the air temperature (``T_cab``), the humidity ratio
(``w_cab``, turned into relative humidity at ``T_cab``) and two surface temperatures.
What PMV also needs is stated in :class:`ComfortConfig`:

* mean radiant temperature: the mean of the interior (seats, dash) and shell (roof, doors,
  glass) temperatures, equal view factors assumed;
* relative air speed 0.2 m/s (ventilated cabin, ASHRAE 55's upper still-air value);
* metabolic rate 1.2 met (seated driving, light activity; ISO 7730 Table B.1 / ASHRAE 55);
* clothing 0.5 clo (summer: trousers and short-sleeved shirt, ISO 7730 Table C.1).

ISO 7730's applicability limits (e.g. mean radiant temperature up to 40 degC) are not
enforced (``limit_inputs=False``): a hot-soaked shell exceeds them, and a number with the
assumptions stated beats a missing one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acid.psychro import relative_humidity
from acid.units import K2C

#: Cabin relative-humidity band of every energy comparison (fractions): a controller whose mean
#: cabin RH lies outside it is marked "outside RH band" and not ranked. The edges are EN
#: 16798-1:2019 (after EN 15251:2007, Table B.6) category II ("normal expectation") design
#: criteria for humidity: dehumidify above 60 %, humidify below 25 %. ASHRAE 55-2020 sets no
#: lower limit and caps the humidity ratio at 0.012 kg/kg (about 60 % RH at 26 degC).
RH_BAND = (0.25, 0.60)
RH_BAND_SOURCE = ("EN 16798-1:2019 category II humidity design criteria (EN 15251:2007 "
                  "Table B.6): 25-60 % RH")


def rh_band_distance(rh: float, band: tuple[float, float] = RH_BAND) -> float:
    """How far a relative humidity (0-1) lies outside ``band``, 0 inside (fraction of RH)."""
    return max(0.0, band[0] - rh, rh - band[1])


@dataclass(frozen=True)
class ComfortConfig:
    """The PMV assumptions (see the module docstring)."""

    met: float = 1.2
    clo: float = 0.5
    v_air: float = 0.2

    def to_json_dict(self) -> dict:
        return {"model": "PMV, ISO 7730:2005 (pythermalcomfort.models.pmv_ppd_iso)",
                "met": self.met, "clo": self.clo, "v_air_m_s": self.v_air,
                "mean_radiant_temperature": "mean of T_int and T_shell",
                "relative_humidity": "from w_cab at T_cab"}


@dataclass(frozen=True)
class ComfortStats:
    """PMV and humidity over a run (samples 1..n)."""

    pmv_mean: float
    pmv_min: float
    pmv_max: float
    ppd_mean: float
    rh_mean: float
    w_mean_g_kg: float

    def to_json_dict(self) -> dict:
        return {"pmv_mean": self.pmv_mean, "pmv_min": self.pmv_min, "pmv_max": self.pmv_max,
                "ppd_mean_pct": self.ppd_mean, "rh_mean_pct": 100.0 * self.rh_mean,
                "w_cab_mean_g_kg": self.w_mean_g_kg}


def pmv(T_cab, T_int, T_shell, w_cab, config: ComfortConfig | None = None):
    """(PMV, PPD %) arrays for cabin states (K, kg/kg)."""
    from pythermalcomfort.models import pmv_ppd_iso  # lazy: numba takes seconds to load

    c = config or ComfortConfig()
    T_cab = np.asarray(T_cab, dtype=float)
    rh = 100.0 * np.clip(relative_humidity(T_cab, np.asarray(w_cab, dtype=float)), 0.0, 1.0)
    tr = K2C(0.5 * (np.asarray(T_int, dtype=float) + np.asarray(T_shell, dtype=float)))
    res = pmv_ppd_iso(tdb=K2C(T_cab), tr=tr, vr=np.full(T_cab.shape, c.v_air), rh=rh,
                      met=np.full(T_cab.shape, c.met), clo=np.full(T_cab.shape, c.clo),
                      model="7730-2005", limit_inputs=False, round_output=False)
    return np.asarray(res.pmv, dtype=float), np.asarray(res.ppd, dtype=float)


def comfort_stats(T_cab, T_int, T_shell, w_cab, config: ComfortConfig | None = None
                  ) -> ComfortStats:
    """PMV/PPD and humidity statistics of a trajectory (use samples 1..n)."""
    p, ppd = pmv(T_cab, T_int, T_shell, w_cab, config)
    rh = relative_humidity(np.asarray(T_cab, dtype=float), np.asarray(w_cab, dtype=float))
    return ComfortStats(pmv_mean=float(np.mean(p)), pmv_min=float(np.min(p)),
                        pmv_max=float(np.max(p)), ppd_mean=float(np.mean(ppd)),
                        rh_mean=float(np.mean(rh)), w_mean_g_kg=1e3 * float(np.mean(w_cab)))
