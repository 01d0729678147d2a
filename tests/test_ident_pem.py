"""The prediction-error method with an extended Kalman filter (``acid.ident.pem``): on data
of a declared model with a random-walk load that no channel measures, it recovers the
parameters and noise levels that made the data, its innovations are consistent, and the
filter's estimate of the load at validation starts follows the true load."""

from __future__ import annotations

import numpy as np
import pytest

from acid.data import Dataset
from acid.ident.data import ModelData
from acid.ident.fit import fit_model
from acid.ident.pem import filter_states, noise_parameters
from acid.ident.validate import validate_model
from acid.models import Model, load
from acid.models.values import ParameterValues

TRUTH = {"C": 30.0, "UA": 60.0, "sigma_T": 0.01, "sigma_y": 0.05, "sigma_Q": 15.0}


#: One air node against ambient, heated by an unmeasured random-walk load (a model file).
ROOM = """
from acid.models import RK4, Model, Parameter, Signal, State


def ode(s):
    return {"T": (s.UA * (s.T_amb - s.T) + s.Q) / (1e3 * s.C), "Q": 0.0 * s.Q}


model = Model(
    "room",
    states=[State("T", "K", noise="sigma_T", sensor="sigma_y", spread=0.1),
            State("Q", "W", measured=False, initial=300.0, noise="sigma_Q", spread=300.0)],
    disturbances=[Signal("T_amb", "K")],
    parameters=[Parameter("C", "kJ/K", 20.0, 5.0, 100.0),
                Parameter("UA", "W/K", 100.0, 10.0, 300.0),
                Parameter("sigma_T", "K", 0.05, 1e-3, 1.0, fixed=True),
                Parameter("sigma_y", "K", 0.1, 1e-3, 1.0, fixed=True),
                Parameter("sigma_Q", "W", 5.0, 0.1, 100.0, fixed=True)],
    Ts=5.0, ode=ode, integrator=RK4(2))
"""


def _room(folder) -> Model:
    path = folder / "room.py"
    path.write_text(ROOM, encoding="utf-8")
    return load(str(path))


def _record(model: Model, rng, n: int, q0: float):
    """A noisy record of ``model`` with the true parameters; the true load alongside."""
    p = np.array([TRUTH[k] for k in model.parameter_names])
    Ta = 300.0 + 4.0 * np.sin(np.arange(n) / 60.0) + np.repeat(
        rng.uniform(-3, 3, n // 50 + 1), 50)[:n]
    x = np.array([300.0, q0])
    T, Q = np.empty(n), np.empty(n)
    for k in range(n):
        T[k], Q[k] = x
        x, _ = model.step(x, np.zeros(0), [Ta[k]], p)
        x = x + rng.normal(0.0, [TRUTH["sigma_T"], TRUTH["sigma_Q"]])
    y = T + rng.normal(0.0, TRUTH["sigma_y"], n)
    ds = Dataset(np.arange(n) * 5.0, {"T": y - 273.15, "T_amb": Ta - 273.15},
                 {"T": "degC", "T_amb": "degC"}, 5.0)
    return ds, Q


def test_recovers_parameters_and_noise_levels_with_an_unmeasured_random_walk_load(rng,
                                                                                  tmp_path):
    m = _room(tmp_path)
    assert noise_parameters(m) == ("sigma_T", "sigma_y", "sigma_Q")
    parts = [_record(m, rng, 1500, q0) for q0 in (200.0, 600.0)]
    ds = Dataset.concatenate([p for p, _ in parts])
    res = fit_model(m, ds, "pem", max_nfev=200)
    assert res.method == "pem" and res.output_error["converged"]
    # the noise parameters are estimated though declared fixed (output error cannot see them)
    assert {e.name for e in res.estimates if e.status == "estimated (pem)"} == set(TRUTH)
    for name, tol in (("C", 0.1), ("UA", 0.1), ("sigma_y", 0.15), ("sigma_Q", 0.35)):
        assert res.value(name) == pytest.approx(TRUTH[name], rel=tol), name
    for e in res.estimates:          # the truth inside 3 standard errors
        if e.name in ("C", "UA"):
            assert abs(e.value - TRUTH[e.name]) < 3 * e.stderr + 1e-9, e
    # consistent filter: normalised innovations of unit spread
    assert res.output_error["normalised_innovation_std"] == pytest.approx(1.0, abs=0.1)
    assert "states with process noise: T, Q" in res.notes[0]


def test_filter_at_validation_starts_follows_the_unmeasured_load(rng, tmp_path):
    m = _room(tmp_path)
    ds, Q = _record(m, rng, 1200, 700.0)
    p = np.array([TRUTH[k] for k in m.parameter_names])
    data = ModelData.of(m, ds)
    k0 = np.array([300, 600, 900, 1150])
    x = filter_states(m, data, np.tile(p, (k0.size, 1)), k0, 240)
    # started at 300 W +/- 300 W, the filter finds the load within its walk over 20 min
    assert np.abs(x[:, 1] - Q[k0]).max() < 80.0
    # much nearer the truth than where it started
    assert np.abs(x[:, 1] - Q[k0]).mean() < 0.3 * np.abs(300.0 - Q[k0]).mean()
    # and the open-loop predictions from those states beat the least-squares warm start
    ps = ParameterValues(p, model=m)
    kw = dict(start_index=k0[:3], horizon=40, warmup=1200.0)
    ekf = validate_model(m, ds, ps, warm_start="ekf", **kw)
    assert any("extended Kalman filter" in n for n in ekf.notes)
    assert ekf.metrics["T"]["rmse"] < 0.3
    # the filter from the start of the record: each start's own stretch, its last sample
    trip = validate_model(m, ds, ps, warm_start="ekf-trip", **kw)
    assert any("from the start of each experiment" in n for n in trip.notes)
    x_var = filter_states(m, data, np.tile(p, (3, 1)), k0[:3], k0[:3])
    x_one = np.vstack([filter_states(m, data, p[None], [k], k) for k in k0[:3]])
    np.testing.assert_allclose(x_var, x_one, rtol=1e-9)
    assert trip.metrics["T"]["rmse"] < 0.3
    with pytest.raises(Exception, match="warm_start"):
        validate_model(m, ds, ps, warm_start="kalman", **kw)


def test_cli_fits_by_prediction_error_with_an_evaluation_cap_and_validates_with_the_filter(
        rng, tmp_path):
    import json

    from typer.testing import CliRunner

    from acid_cli.main import app

    m = _room(tmp_path)
    src = tmp_path / "room.py"
    path = tmp_path / "d.h5"
    _record(m, rng, 600, 400.0)[0].to_hdf5(path)
    runner = CliRunner()
    res = runner.invoke(app, ["fit", str(path), "--model", str(src), "--method", "pem",
                              "--max-evals", "3", "--out", str(tmp_path / "p.json"),
                              "--json", str(tmp_path / "f.json")])
    assert res.exit_code == 0, res.output
    fit = json.loads((tmp_path / "f.json").read_text())
    assert fit["method"] == "pem" and fit["output_error"]["nfev"] <= 4
    assert not fit["output_error"]["converged"] and "did not converge" in res.output
    res = runner.invoke(app, ["validate", str(path), "--model", str(src), "--params",
                              str(tmp_path / "p.json"), "--starts", "4", "--warmup", "500",
                              "--horizon", "50", "--warm-start", "ekf", "--no-yardsticks",
                              "--no-figures"])
    assert res.exit_code == 0, res.output
    assert "extended Kalman filter" in res.output
    for args, opt in ((["fit", str(path), "--max-evals", "0"], "--max-evals"),
                      (["fit", str(path), "--model", "econ", "--max-evals", "50"],
                       "--max-evals"),
                      (["validate", str(path), "--model", str(src), "--warm-start", "x"],
                       "--warm-start")):
        res = runner.invoke(app, args)
        assert res.exit_code == 2 and opt in res.output, res.output


def test_per_experiment_parameters_and_outputs_of_a_built_in_declaration(rng):
    """cabin3 (no noises declared: a sensor noise on each measured channel, the latent
    interior started from its rule), fitted from its declared values, recovers the values
    that made the data and its per-experiment load."""
    m = load("cabin3")
    truth = {"C_cab": 14.0, "UA_int": 200.0, "UA_amb": 80.0, "tau_evap": 30.0}
    parts = []
    for q in (200.0, 900.0):
        n = 400
        W = np.repeat(rng.uniform(0.03, 0.12, n // 40 + 1), 40)[:n]
        Ts = np.repeat(rng.uniform(276.0, 290.0, n // 40 + 1), 40)[:n]
        Ta = np.full(n, 303.0)
        p = m.values.copy()
        for k, v in {**truth, "Q_sol": q}.items():
            p[m.parameter_names.index(k)] = v
        X, Y = m.simulate(np.array([305.0, 310.0, 285.0]), np.c_[W, Ts], Ta[:, None], p)
        ch = {"T_cab": X[:-1, 0] - 273.15, "T_evap": X[:-1, 2] - 273.15,
              "T_ain": Y[:, 0] - 273.15, "W_bl": W, "T_evap_set": Ts - 273.15,
              "T_amb": Ta - 273.15}
        parts.append(Dataset(np.arange(n) * 5.0, ch, {k: "kg/s" if k == "W_bl" else "degC"
                                                     for k in ch}, 5.0))
    res = fit_model(m, Dataset.concatenate(parts), "pem", fix={"C_int": 60.0}, max_nfev=200)
    assert res.output_error["converged"]
    np.testing.assert_allclose(res.per_experiment["Q_sol"], [200.0, 900.0], rtol=1e-2)
    for name, v in truth.items():
        assert res.value(name) == pytest.approx(v, rel=1e-2), name


def test_converges_within_the_default_budget_and_says_how_it_knows(rng, tmp_path):
    """L-BFGS-B alone stops at its cap far from the optimum; the Newton steps with the
    Fisher information end where the Newton decrement is below its tolerance, and the status
    says so with the numbers (decrement, projected gradient, evaluations, matrices)."""
    from acid.ident.ms.newton import DECREMENT_TOL

    m = _room(tmp_path)
    ds, _ = _record(m, rng, 600, 400.0)
    res = fit_model(m, ds, "pem")                      # the default budget (100)
    oe_ = res.output_error
    assert oe_["converged"], oe_["status"]
    assert oe_["status"].startswith("converged: Newton decrement")
    dec = float(oe_["status"].split("Newton decrement ")[1].split(" ")[0])
    assert dec <= DECREMENT_TOL and "Fisher matrices" in oe_["status"]
    # a tiny budget: not converged, and the status says how far (decrement, gradient)
    capped = fit_model(m, ds, "pem", max_nfev=3)
    assert not capped.output_error["converged"]
    assert "not converged after 3 gradient evaluations (cap 3)" in \
        capped.output_error["status"]
    assert "projected gradient" in capped.output_error["status"]
    assert "(cap 1): budget spent; Newton decrement" in capped.output_error["status"]
    assert "\n" not in capped.output_error["status"]
    assert capped.output_error["loss"] >= oe_["loss"] - 1e-6 * abs(oe_["loss"])


def test_fisher_steps_reach_the_exact_newton_optimum_with_a_matching_curvature(rng,
                                                                                tmp_path):
    """The Newton phase on the Fisher information (first derivatives of the innovations and
    their covariances) ends at the optimum the exact-Hessian Newton phase finds, to 1e-9 of
    the loss, and at that optimum of a well-specified model the two curvatures (hence the
    standard errors) agree."""
    from acid.ident.pem import fit_pem

    m = _room(tmp_path)
    ds, _ = _record(m, rng, 600, 400.0)
    fi = fit_pem(m, ds, curvature="fisher")
    ex = fit_pem(m, ds, curvature="exact")
    assert fi.output_error["converged"] and ex.output_error["converged"]
    assert "exact Hessians" in ex.output_error["status"]
    assert fi.output_error["loss"] == pytest.approx(ex.output_error["loss"], rel=1e-9)
    for name in ("C", "UA", "sigma_y", "sigma_Q"):
        assert fi.value(name) == pytest.approx(ex.value(name), rel=1e-4), name
        se_f, se_x = (next(e.stderr for e in r.estimates if e.name == name) for r in (fi, ex))
        assert se_f == pytest.approx(se_x, rel=0.3), name


def test_fit_starts_group_converged_pem_fits_into_basins_and_name_failed_ones(rng, tmp_path):
    """``fit_starts`` with the prediction-error method: every start is a converged optimum
    (grouped: loss, parameters, count) or a failed start with its reason; the best is
    reported. With a budget too small to converge, every start is a failed one."""
    m = _room(tmp_path)
    ds, _ = _record(m, rng, 600, 400.0)
    res = fit_model(m, ds, "pem", fit_starts=3, seed=1)
    assert res.optima and sum(o.n_starts for o in res.optima) + len(res.failed_starts) == 3
    best = res.optima[0]
    assert res.output_error["loss"] == pytest.approx(best.loss, rel=1e-12)
    assert set(best.values) == set(res.covariance_names)
    assert any(n.startswith("multi-start: 3 starts") for n in res.notes)
    capped = fit_model(m, ds, "pem", fit_starts=3, seed=1, max_nfev=3)
    assert not capped.optima and len(capped.failed_starts) == 3
    assert all(f.reason.startswith("not converged (") for f in capped.failed_starts)
    assert any("none of the 3 starts converged" in w for w in capped.warnings)
