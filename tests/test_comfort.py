"""acid.comfort: PMV of cabin states through pythermalcomfort."""

from __future__ import annotations

import numpy as np
import pytest

from acid.comfort import ComfortConfig, comfort_stats, pmv
from acid.psychro import humidity_ratio
from acid.units import C2K


def test_pmv_is_near_neutral_in_a_comfortable_cabin_and_rises_with_heat():
    T = C2K(np.array([22.0, 24.0, 26.0, 28.0]))
    w = humidity_ratio(T, 0.5)
    p, ppd = pmv(T, T, T, w)
    assert np.all(np.diff(p) > 0)             # warmer is warmer
    assert -1.0 < p[1] < 0.5 and ppd.min() >= 5.0   # 5 % dissatisfied at best (Fanger)
    # a hot shell (radiant temperature) makes the same air feel warmer
    p_hot, _ = pmv(T, T, T + 10.0, w)
    assert np.all(p_hot > p)


def test_stats_report_the_assumptions_and_humidity():
    T = np.full(4, C2K(24.0))
    s = comfort_stats(T, T, T, humidity_ratio(T, 0.4), ComfortConfig(met=1.2, clo=0.5))
    assert s.rh_mean == pytest.approx(0.4, rel=1e-9)
    assert s.pmv_min == pytest.approx(s.pmv_max)
    d = ComfortConfig().to_json_dict()
    assert d["met"] == 1.2 and d["clo"] == 0.5 and "T_int" in d["mean_radiant_temperature"]
