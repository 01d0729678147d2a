"""Intelligent Constraint Management: speed-coordinated upper bound on T_cab (paper Fig. 9)."""

from __future__ import annotations

import numpy as np
import pytest

from acid.control.icm import ICMConfig, icm_upper_bound, speed_target
from acid.errors import ConfigError
from acid.studies.mpc_check.scenarios import stop_and_go_profile
from acid.units import C2K


def test_target_is_high_when_stopped_and_low_when_fast():
    c = ICMConfig()
    t = speed_target([0.0, c.v_slow, c.v_fast, 30.0], c)
    np.testing.assert_allclose(t, [c.T_high, c.T_high, c.T_low, c.T_low])
    mid = speed_target(0.5 * (c.v_slow + c.v_fast), c)
    assert mid == pytest.approx(0.5 * (c.T_low + c.T_high))


def test_target_decreases_monotonically_with_speed():
    v = np.linspace(0.0, 30.0, 61)
    assert np.all(np.diff(speed_target(v)) <= 1e-12)


def test_bound_respects_band_and_rate_limits():
    c = ICMConfig(fall_rate=0.1, rise_rate=0.2)
    t = np.arange(0.0, 200.0, 5.0)
    ub = icm_upper_bound(t, stop_and_go_profile(t), c)
    assert np.all(ub >= c.T_low - 1e-12) and np.all(ub <= c.T_high + 1e-12)
    d = np.diff(ub)
    assert d.min() >= -c.fall_rate * 5.0 - 1e-12
    assert d.max() <= c.rise_rate * 5.0 + 1e-12


def test_bound_follows_the_stop_and_go_profile():
    c = ICMConfig()
    t = np.arange(0.0, 101.0, 5.0)
    ub = icm_upper_bound(t, stop_and_go_profile(t), c, initial=C2K(24.0))
    assert ub[0] == pytest.approx(C2K(24.0))
    assert ub[t == 40.0][0] == pytest.approx(c.T_low)   # cruising at 25 m/s: cool
    assert ub[t == 70.0][0] == pytest.approx(c.T_high)  # stopped: let the cabin warm


def test_invalid_rules_are_rejected():
    with pytest.raises(ConfigError, match="T_low"):
        ICMConfig(T_low=C2K(27.0), T_high=C2K(25.0))
    with pytest.raises(ConfigError, match="v_slow"):
        ICMConfig(v_slow=10.0, v_fast=5.0)
    with pytest.raises(ConfigError, match="increase"):
        icm_upper_bound([0.0, 0.0], [1.0, 2.0])
