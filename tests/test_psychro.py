"""acid.psychro: moist-air relations, numeric and symbolic alike."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from acid.psychro import humidity_ratio, relative_humidity, saturation_pressure
from acid.units import C2K


def test_against_tabulated_values():
    # saturation pressure at 20 / 30 degC: 2339 / 4247 Pa (steam tables); Magnus within 0.5 %
    assert saturation_pressure(C2K(20.0)) == pytest.approx(2339.0, rel=5e-3)
    assert saturation_pressure(C2K(30.0)) == pytest.approx(4247.0, rel=5e-3)
    # 25 degC, 50 %, sea level: humidity ratio 9.9 g/kg (ASHRAE psychrometric chart)
    assert humidity_ratio(C2K(25.0), 0.5) == pytest.approx(0.00988, rel=5e-3)


def test_relative_humidity_inverts_humidity_ratio():
    T = C2K(np.array([10.0, 24.0, 35.0]))
    rh = np.array([0.2, 0.55, 0.9])
    np.testing.assert_allclose(relative_humidity(T, humidity_ratio(T, rh)), rh, rtol=1e-12)


def test_casadi_symbols_give_the_numeric_values():
    T, rh = ca.SX.sym("T"), ca.SX.sym("rh")
    f = ca.Function("w", [T, rh], [humidity_ratio(T, rh)])
    assert float(f(C2K(27.0), 0.4)) == pytest.approx(humidity_ratio(C2K(27.0), 0.4), rel=1e-14)
