"""A prediction-error fit of a model that declares no noises warns when the filter's default
noises do not match the data (the normalised innovations' std far from 1), naming the
states, the one-step errors' RMS in their units and the two ways out; with the sensor noise
declared at its true value it does not warn."""

from __future__ import annotations

import numpy as np
import pytest

import acid
from acid.models import Model, Parameter, Signal, State

N, TS = 300, 0.01


def _model(sensor=None):
    return Model("lag", states=[State("y", "V", sensor=sensor)],
                 inputs=[Signal("u", "V", "input")],
                 parameters=[Parameter("a", "1/s", 2.0, 0.1, 50.0),
                             Parameter("b", "1/s", 2.0, 0.1, 50.0)],
                 Ts=TS, ode=lambda s: {"y": s.b * s.u - s.a * s.y})


@pytest.fixture(scope="module")
def record():
    rng = np.random.default_rng(2)
    u = np.repeat(rng.uniform(-0.01, 0.01, N // 20), 20)
    y = np.zeros(N)
    for k in range(N - 1):
        y[k + 1] = y[k] + TS * (5.0 * u[k] - 5.0 * y[k])
    y += rng.normal(0.0, 1e-4, N)
    return acid.Dataset(time=np.arange(N) * TS, Ts=TS, channels={"y": y, "u": u},
                        units={"y": "V", "u": "V"})


def test_default_noises_that_do_not_match_the_data_are_named(record):
    fit = acid.fit_model(_model(), record, method="pem", max_nfev=40)
    (w,) = [w for w in fit.warnings if "noises do not match" in w]
    assert "states y take the defaults" in w and " V" in w and "--method oe" in w
    assert fit.output_error["normalised_innovation_std"] < 0.5


def test_declared_noises_that_match_do_not_warn(record):
    fit = acid.fit_model(_model(sensor=1e-4), record, method="pem", max_nfev=40)
    assert not [w for w in fit.warnings if "noises do not match" in w]
    assert 0.5 <= fit.output_error["normalised_innovation_std"] <= 2.0
