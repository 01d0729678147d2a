"""Yardsticks of the validation (acid/yardsticks.py): persistence, ARX and subspace.

On data of a known linear system the ARX and subspace yardsticks must recover it (open-loop
prediction error at round-off) while persistence cannot; on acid's plant data persistence is
exact at step 0 and equals y(k0) - y(k0 + i) after it.
"""

from __future__ import annotations

import numpy as np
import pytest

from acid.ident.validate import by_time, validate
from acid.ident.yardsticks import (
    YARDSTICKS,
    evaluate,
    fit_arx,
    moesp_model,
    moesp_observability,
    segment_first,
    windows,
)
from acid.models.params import paper

# x(k+1) = A x + B u, y = C x + D u (+ 10): two states, two inputs, two outputs, a direct
# feedthrough from the first input to the second output (as W_bl to T_ain)
A = np.array([[0.95, 0.03], [0.0, 0.8]])
B = np.array([[0.1, 0.0], [0.05, 0.2]])
C = np.array([[1.0, 0.0], [0.5, 1.0]])
D = np.array([[0.0, 0.0], [0.3, 0.0]])


def linear_data(n: int = 2000, noise: float = 0.0, seed: int = 0):
    """Outputs and inputs of the known system under piecewise-constant random inputs."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.normal(size=(n // 10, 2)), 10, axis=0)
    x, y = np.zeros(2), np.empty((n, 2))
    for k in range(n):
        y[k] = C @ x + D @ u[k]
        x = A @ x + B @ u[k]
    return y + 10.0 + noise * rng.normal(size=y.shape), u


def _errors(pred, y, k0, horizon):
    idx = k0[:, None] + np.arange(horizon + 1)[None, :]
    return pred.predicted - y[idx]


@pytest.fixture(scope="module")
def exact():
    y, u = linear_data()
    k0 = np.arange(1100, 1900, 20)
    out = evaluate(y, u, np.zeros(len(y), dtype=int), k0, 60, np.zeros(2, dtype=bool),
                   (0, 1000))
    return y, k0, out


def test_arx_and_subspace_recover_a_known_linear_system(exact):
    y, k0, out = exact
    assert tuple(out) == YARDSTICKS
    rms = {name: float(np.sqrt(np.mean(_errors(p, y, k0, 60) ** 2)))
           for name, p in out.items()}
    assert rms["persistence"] > 0.5, rms           # the outputs do move over 300 s
    assert rms["arx"] < 1e-8 and rms["subspace"] < 1e-8, rms
    assert out["arx"].settings["stable"] and out["subspace"].settings["stable"]
    assert out["subspace"].settings["order"] >= 2  # two states cannot be told by fewer


def test_with_measurement_noise_they_stay_far_better_than_persistence():
    y, u = linear_data(noise=0.01, seed=1)
    k0 = np.arange(1100, 1900, 20)
    out = evaluate(y, u, np.zeros(len(y), dtype=int), k0, 60, np.zeros(2, dtype=bool),
                   (0, 1000))
    rms = {name: float(np.sqrt(np.mean(_errors(p, y, k0, 60)[:, 1:] ** 2)))
           for name, p in out.items()}
    assert rms["arx"] < 0.03 * rms["persistence"], rms
    assert rms["subspace"] < 0.03 * rms["persistence"], rms


def test_step_zero_is_the_measurement_and_persistence_holds_it(exact):
    y, k0, out = exact
    for p in out.values():
        np.testing.assert_array_equal(p.predicted[:, 0], y[k0])
    e = _errors(out["persistence"], y, k0, 60)
    np.testing.assert_array_equal(e, y[k0][:, None, :] - y[k0[:, None] + np.arange(61)])


def test_a_held_input_is_held_and_changes_the_prediction():
    y, u = linear_data()
    k0 = np.arange(1100, 1900, 40)
    exp = np.zeros(len(y), dtype=int)
    measured = evaluate(y, u, exp, k0, 60, np.array([False, False]), (0, 1000))
    held = evaluate(y, u, exp, k0, 60, np.array([False, True]), (0, 1000))
    assert held["arx"].settings["held_inputs"] == ["u1"]
    gap = np.abs(held["arx"].predicted - measured["arx"].predicted)[:, 1:].max()
    assert gap > 0.1  # the held second input is not what drove the data
    w = windows(u, k0, 60, 3, segment_first(exp), np.array([False, True]))
    np.testing.assert_array_equal(w[:, 3:, 1], np.repeat(u[k0, 1][:, None], 61, axis=1))
    np.testing.assert_array_equal(w[:, :, 0], u[k0[:, None] + np.arange(-3, 61)][..., 0])


def test_windows_repeat_the_first_sample_before_an_experiment_starts():
    x = np.arange(10.0)[:, None]
    exp = np.array([0, 0, 0, 0, 1, 1, 1, 1, 1, 1])
    w = windows(x, np.array([5]), 2, 3, segment_first(exp))
    np.testing.assert_array_equal(w[0, :, 0], [4.0, 4.0, 4.0, 5.0, 6.0, 7.0])


def test_arx_order_rule_finds_an_arx_system_and_its_coefficients():
    rng = np.random.default_rng(3)
    n = 3000
    u = rng.normal(size=(n, 1))
    y = np.zeros((n, 1))
    for k in range(2, n):  # na = 2, nb = 1 (lag 0 only)
        y[k] = 1.5 * y[k - 1] - 0.7 * y[k - 2] + 0.5 * u[k] + 0.05 * rng.normal()
    m, aic = fit_arx(y, u, [(0, n)])  # without estimation windows: least AIC
    assert m.na >= 2 and m.stable  # AIC may add a lag, never drop one the data need
    assert m.aic == min(aic.values())
    np.testing.assert_allclose(m.A[:2, 0, 0], [1.5, -0.7], atol=0.05)
    np.testing.assert_allclose(m.A[2:, 0, 0], 0.0, atol=0.05)
    np.testing.assert_allclose(m.B[0, 0, 0], 0.5, atol=0.02)
    np.testing.assert_allclose(m.B[1:, 0, 0], 0.0, atol=0.05)
    low, _ = fit_arx(y, u, [(0, n)], orders=(1,))
    assert m.aic < low.aic


def test_moesp_finds_the_order_and_the_poles():
    y, u = linear_data()
    y = y - 10.0  # the system itself (no offset)
    U, sv = moesp_observability(y, u)
    assert sv[1] > 1e6 * sv[2]  # two states: two singular values above round-off
    m = moesp_model(U, sv, 2, y, u)
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(m.A).real), [0.8, 0.95], atol=1e-8)
    np.testing.assert_allclose(m.D, D, atol=1e-8)


def test_too_short_an_estimation_part_leaves_the_fitted_ones_out_with_a_warning():
    y, u = linear_data(n=400)
    with pytest.warns(UserWarning, match="ARX and subspace left out"):
        out = evaluate(y, u, np.zeros(400, dtype=int), np.array([300]), 20,
                       np.zeros(2, dtype=bool), (0, 50))
    assert tuple(out) == ("persistence",)


def test_by_time_reports_rmse_and_p90_at_the_times_inside_the_horizon():
    e = np.zeros((10, 12))             # steps 1 .. 12 of 5 s
    e[:, 11] = np.arange(10.0)
    d = by_time({"T_cab": e}, 5.0, (60.0, 300.0))
    assert set(d["T_cab"]) == {"60"}
    assert d["T_cab"]["60"]["rmse_K"] == pytest.approx(np.sqrt(np.mean(np.arange(10.0) ** 2)))
    assert d["T_cab"]["60"]["p90_K"] == pytest.approx(np.percentile(np.arange(10.0), 90))
    assert d["T_cab"]["60"]["n"] == 10


def test_on_plant_data_persistence_holds_the_start_value(model_dataset):
    r = validate(model_dataset, paper(), starts=10, horizon=120, held_out_fraction=0.5,
                 yardsticks=True)
    assert set(r.yardsticks) == set(YARDSTICKS)
    for c in ("T_cab", "T_evap", "T_ain"):   # persistence: the error is y(k0) - y(k0 + k)
        i = r.channels.index(c)
        e = r.measured[:, :1, i] - r.measured[:, 1:, i]
        np.testing.assert_allclose(r.yardsticks["persistence"]["rmse_by_step"][c],
                                   np.sqrt(np.mean(e ** 2, axis=0)), rtol=1e-12)
        assert r.yardsticks["persistence"]["by_time"][c]["60"]["rmse_K"] == pytest.approx(
            np.sqrt(np.mean(e[:, 11] ** 2)))
    # fitted on the first half, the part before the validated samples
    assert r.settings["yardsticks_fitted_on"] == [0, len(model_dataset) // 2]


def test_econ_model_yardsticks_predict_interior_and_shell(econ_model_dataset, econ_truth):
    r = validate(econ_model_dataset, econ_truth, starts=8, horizon=120,
                 held_out_fraction=0.5, yardsticks=True)
    for y in r.yardsticks.values():  # every measured channel, T_int/T_shell included
        assert {"T_cab", "T_evap", "T_ain", "T_int", "T_shell"} <= set(y["channels"])
        assert all(np.isfinite(v["rmse"]) for v in y["channels"].values())
    assert "v_veh and T_amb held" in r.window_design["held_disturbances"]
