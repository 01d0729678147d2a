"""The smooth helpers of the declaration API: differentiable where max, sqrt and a threshold
in if_else are not, so a fit moves a threshold written with them."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import acid
from acid.ident.fit import fit_model
from acid.models import (
    Model,
    Parameter,
    Signal,
    State,
    if_else,
    smooth_max,
    smooth_min,
    smooth_sqrt,
    smooth_step,
    soft_if_else,
)


def test_the_helpers_approach_their_sharp_forms_and_keep_a_gradient():
    assert smooth_max(3.0, -1.0, 1e-3) == pytest.approx(3.0, abs=1e-6)
    assert smooth_min(3.0, -1.0, 1e-3) == pytest.approx(-1.0, abs=1e-6)
    assert smooth_sqrt(9.0, 1e-3) == pytest.approx(3.0, abs=1e-6)
    assert smooth_step(5.0, 0.0, 0.5) == pytest.approx(1.0, abs=1e-4)
    assert soft_if_else(-5.0, 0.0, 7.0, 2.0, 0.5) == pytest.approx(2.0, abs=1e-3)
    x, c = ca.SX.sym("x"), ca.SX.sym("c")
    slope = ca.Function("d", [x], [ca.jacobian(smooth_sqrt(x, 1e-2), x)])
    for v in (-1.0, 0.0, 1e-8):                      # sqrt: inf at 0, NaN below
        assert np.isfinite(float(slope(v)))
    sharp = ca.Function("g", [x, c], [ca.jacobian(if_else(x > c, 1.0, 0.0), c)])
    soft = ca.Function("g", [x, c], [ca.jacobian(smooth_step(x, c, 0.1), c)])
    assert float(sharp(0.05, 0.0)) == 0.0 and float(soft(0.05, 0.0)) < -1.0


def _threshold_model(step):
    return Model("switch", states=[State("x", "1", measured=False, initial=0.0)],
                 inputs=[Signal("u", "1")], outputs=[Signal("y", "1")],
                 parameters=[Parameter("c", "1", 0.0, -2.0, 2.0)], Ts=1.0,
                 ode=lambda s: {"x": -s.x}, output=lambda s: {"y": step(s.u, s.c)})


def test_a_threshold_written_with_smooth_step_is_fitted():
    rng = np.random.default_rng(1)
    u = rng.uniform(-2.0, 2.0, 300)
    y = (u > 0.7).astype(float) + rng.normal(0.0, 0.05, u.size)
    ds = acid.Dataset(time=np.arange(u.size) * 1.0, channels={"u": u, "y": y},
                      units={"u": "1", "y": "1"}, Ts=1.0)
    soft = fit_model(_threshold_model(lambda x, c: smooth_step(x, c, 0.05)), ds, "oe")
    assert soft.value("c") == pytest.approx(0.7, abs=0.05)


def test_a_threshold_only_inside_if_else_is_named_at_declaration():
    with pytest.warns(UserWarning, match=r"parameter\(s\) c reach the equations only "
                                         r"through a comparison"):
        _threshold_model(lambda x, c: if_else(x > c, 1.0, 0.0))
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _threshold_model(lambda x, c: smooth_step(x, c, 0.05))       # no warning
        _threshold_model(lambda x, c: if_else(x > 0.5, c * x, 0.0))  # c has a gradient
