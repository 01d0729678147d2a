"""Offset-free estimation (Kalman filter with integrating disturbances) and the back-off."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from acid.control.estimator import (
    BackoffConfig,
    ErrorBackoff,
    EstimatorConfig,
    OffsetFreeEstimator,
)
from acid.control.nmpc import NMPC, NMPCConfig, model_function, predict
from acid.errors import ConfigError
from acid.models.params import paper
from acid.plant import ModelPlant
from acid.units import C2K

P = paper()


@pytest.mark.parametrize("disturbance", ["state", "inlet"])
def test_the_filter_recovers_a_constant_disturbance_of_the_plant(disturbance):
    true_d = np.array([0.15, -0.4])
    est = OffsetFreeEstimator(model_function(P, disturbance))
    rng = np.random.default_rng(1)
    x = np.array([C2K(27.0), C2K(6.0)])
    v = np.array([C2K(30.0), C2K(33.0)])
    est.update(x)
    for _ in range(60):
        u = np.array([rng.uniform(0.05, 0.15), C2K(rng.uniform(3.0, 10.0))])
        x = np.array(predict(x[0], x[1], u[0], u[1], v[0], v[1], true_d, P, disturbance)[:2])
        x_hat, d_hat = est.update(x, u, v)
    np.testing.assert_allclose(d_hat, true_d, atol=1e-3)
    np.testing.assert_allclose(x_hat, x, atol=1e-3)


def test_additive_disturbance_input_matrix_is_the_same_as_state_disturbances():
    x, u, v = (ca.SX.sym(n, 2) for n in ("x", "u", "v"))
    c, e, _ = predict(x[0], x[1], u[0], u[1], v[0], v[1], [0, 0], P)
    f3 = ca.Function("f3", [x, u, v], [ca.vertcat(c, e)])
    a = OffsetFreeEstimator(f3, B_d=np.eye(2), compiled=False)
    b = OffsetFreeEstimator(model_function(P), compiled=False)
    y0 = np.array([C2K(26.0), C2K(5.0)])
    for est in (a, b):
        est.update(y0)
        est.update(y0 + 0.3, [0.1, C2K(5.0)], [C2K(30.0), C2K(33.0)])
    np.testing.assert_allclose(a.d, b.d, rtol=1e-12)


def test_nmpc_with_offset_free_prediction_rides_the_bound_on_a_biased_plant():
    """The model plant with a constant leak of heat into the cabin (a disturbance the
    model does not know): the offset-free NMPC removes the steady offset."""

    def Leaky(params):  # noqa: N802 - a plant, as ModelPlant
        plant = ModelPlant(params)
        model_step = plant.step

        def step(W_bl, T_evap_set, v_veh=0.0, **kw):
            row = model_step(W_bl, T_evap_set, v_veh, **kw)
            plant.T_cab += 0.2
            return row

        plant.step = step
        return plant

    from acid.studies.mpc_check.scenarios import closed_loop

    dist = {"T_int": C2K(30.0), "T_shell": C2K(33.0)}
    n, bound = 30, C2K(25.0)
    ends = {}
    for of in (False, True):
        mpc = NMPC(P, NMPCConfig(offset_free=of))
        run = closed_loop(Leaky(P), mpc, {"T_cab": C2K(26.0), "T_evap": C2K(5.0), **dist},
                          np.full(n + 7, bound), np.zeros(n), "leaky", disturbance=dist)
        ends[of] = run.T_cab[-5:] - bound
    assert np.all(ends[False] > 0.15)  # the paper's NMPC sits above its bound by the leak
    np.testing.assert_allclose(ends[True], 0.0, atol=0.01)


def test_backoff_grows_with_errors_of_its_sign_and_forgets_them():
    b = ErrorBackoff(BackoffConfig(kappa=2.0, memory=0.5, sigma0=0.0))
    assert b.upper == 0.0 and b.lower == 0.0
    b.update(300.0, 300.2)  # the plant ended 0.2 K above the prediction
    assert b.upper == pytest.approx(2.0 * np.sqrt(0.5 * 0.04)) and b.lower == 0.0
    for _ in range(40):
        b.update(300.0, 300.0)
    assert b.upper < 1e-5
    b.update(300.0, float("nan"))  # ignored
    assert np.isfinite(b.upper)
    assert ErrorBackoff(BackoffConfig(sigma0=0.1)).upper == pytest.approx(0.2)
    assert ErrorBackoff(BackoffConfig(sigma0=5.0, max_margin=0.5)).upper == 0.5


def test_estimator_and_backoff_options_are_validated():
    with pytest.raises(ConfigError, match="sigma_d"):
        EstimatorConfig(sigma_d=-1.0)
    with pytest.raises(ConfigError, match="memory"):
        BackoffConfig(memory=1.0)
    with pytest.raises(ConfigError, match="disturbance"):
        NMPCConfig(disturbance="elsewhere")
