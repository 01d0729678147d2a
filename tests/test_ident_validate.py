"""acid.ident.validate: multi-start open-loop validation of declared models, the latent state
estimated from a warm-up stretch, parameter files written by the fit."""

from __future__ import annotations

import copy
import json
import pickle
import warnings

import numpy as np
import pytest

from acid.data import Dataset
from acid.errors import DataError
from acid.ident.fit import fit_model
from acid.ident.validate import (
    declared_parameters,
    fitted_parameters,
    read_parameters,
    validate_model,
)
from acid.models import load
from acid.models.values import ParameterValues


def _cabin3_record(p, rng, n=300, T_int0=315.0, noise=0.0, unobserved=()):
    m = load("cabin3")
    W = np.repeat(rng.uniform(0.04, 0.16, n // 20 + 1), 20)[:n]
    Tset = np.repeat(rng.uniform(275.0, 284.0, n // 20 + 1), 20)[:n]
    Ta = np.full(n, 306.0)
    X, Y = m.simulate(np.array([306.0, T_int0, 281.0]), np.c_[W, Tset], Ta[:, None], p)
    ch = {"T_cab": X[:-1, 0] - 273.15, "T_evap": X[:-1, 2] - 273.15,
          "T_ain": Y[:, 0] - 273.15, "W_bl": W, "T_evap_set": Tset - 273.15,
          "T_amb": Ta - 273.15}
    for c in ("T_cab", "T_evap", "T_ain") if noise else ():
        ch[c] = ch[c] + noise * rng.standard_normal(n)
    for c, k in unobserved:
        ch[c][k] = np.nan
    return Dataset(np.arange(n) * 5.0, ch, {k: "kg/s" if k == "W_bl" else "degC" for k in ch},
                   5.0)


def test_the_true_parameters_predict_their_own_data(rng):
    m = load("cabin3")
    ds = _cabin3_record(m.values, rng)
    res = validate_model(m, ds, starts=10, horizon=100, warmup=200.0)
    assert res.channels == ("T_cab", "T_evap", "T_ain") and res.starts.size == 10
    for c in res.channels:
        assert res.metrics[c]["max_abs"] < 1e-6, c
    assert "estimated from the 40 samples" in " ".join(res.notes)


def test_the_warm_up_estimate_beats_the_declared_initial_rule(rng):
    # the interior starts 9 K above the cabin: the rule (T_int = T_cab) is wrong early on
    m = load("cabin3")
    ds = _cabin3_record(m.values, rng, n=200, T_int0=320.0)
    warm = validate_model(m, ds, starts=5, horizon=60, warmup=150.0)
    rule = validate_model(m, ds, starts=5, horizon=60, warmup=0)
    assert "latent states started from their declared initial rule" in rule.notes
    assert warm.metrics["T_cab"]["rmse"] < 1e-6 < rule.metrics["T_cab"]["rmse"]
    assert len(warm.by_horizon) == 5 and warm.by_horizon[-1]["step"] == 60


def test_parameter_file_round_trip(rng, tmp_path):
    m = load("cabin3")
    ds = _cabin3_record(m.values, rng, n=160)
    res = fit_model(m, ds, method="ls")          # only T_ain's parameters: quick
    path = res.write(tmp_path / "p.json", m, {"data_sha256": "x"})
    ps = read_parameters(m, path)
    np.testing.assert_allclose(ps.theta, res.values)
    assert ps.per_experiment == {"Q_sol": {0: pytest.approx(m.parameter("Q_sol").value)}}
    d = json.loads(path.read_text())
    d["parameters"]["nope"] = {"value": 1.0}
    path.write_text(json.dumps(d))
    with pytest.raises(DataError, match="'nope' is not in model 'cabin3'"):
        read_parameters(m, path)
    with pytest.raises(DataError, match="parameters of model .paper., not .cabin3."):
        bad = tmp_path / "b.json"
        bad.write_text("{}")
        read_parameters(m, bad)


def test_per_experiment_values_are_used_per_start(rng):
    m = load("cabin3")
    p0, p1 = m.values.copy(), m.values.copy()
    i = m.parameter_names.index("Q_sol")
    p0[i], p1[i] = 100.0, 1200.0
    ds = Dataset.concatenate([_cabin3_record(p0, rng, n=150), _cabin3_record(p1, rng, n=150)])
    ps = ParameterValues(model=m, per_experiment={"Q_sol": {0: 100.0, 1: 1200.0}})
    good = validate_model(m, ds, ps, starts=6, horizon=50, warmup=150.0)
    assert good.metrics["T_cab"]["max_abs"] < 1e-6
    fitted = fitted_parameters(fit_model(m, ds, method="ls"))     # Q_sol kept as declared
    assert fitted.per_experiment == {"Q_sol": {0: 400.0, 1: 400.0}}
    mean = validate_model(m, ds, declared_parameters(m), starts=6, horizon=50, warmup=150.0)
    assert mean.metrics["T_cab"]["max_abs"] > 1e-2
    assert any("no fitted value" in n for n in mean.notes)


def test_a_fit_of_a_model_declared_without_a_file_keeps_its_declaration(rng):
    # a model built in Python (a notebook): nothing to load it from by its reference, so
    # the fit's values, their copies and the validator must use the Model itself
    m = copy.copy(load("cabin3"))
    m.name, m.source = "cabin3_notebook", "<notebook>"
    ds = _cabin3_record(m.values, rng, n=160)
    res = fit_model(m, ds, method="ls")
    ps = fitted_parameters(res)
    assert ps.declaration is m and ps.replace(per_experiment={}).declaration is m
    val = validate_model(m, ds, ps, starts=4, horizon=40, warmup=150.0)
    assert val.metrics["T_cab"]["max_abs"] < 1e-6 and val.settings["params"] == ps.label
    # pickled (a worker process) without the Model, which holds the user's functions
    assert pickle.loads(pickle.dumps(res)).declaration is None
    assert pickle.loads(pickle.dumps(ps)).values == ps.values


def test_too_short_a_record_is_one_line(rng):
    m = load("cabin3")
    ds = _cabin3_record(m.values, rng, n=50)
    with pytest.raises(DataError, match="longer than warmup \\+ horizon"):
        validate_model(m, ds, horizon=100)


def test_the_paper_declaration_matches_eqs_1_to_3_written_out(noisy_model_dataset):
    """T_int/T_shell held (the paper's protocol): every predicted T_cab, T_evap, T_ain
    equals eqs. 1-3 simulated by hand from the measured start."""
    from acid.models.params import paper

    ds, p = noisy_model_dataset, paper()
    g, tau = p.gamma, p.tau
    res = validate_model("paper", ds, starts=6, horizon=80, hold=("T_int", "T_shell"))
    W, Ts_ = ds.get("W_bl", "kg/s"), ds.get("T_evap_set", "K")
    for s, k0 in enumerate(res.starts):
        T_cab, T_evap = ds.get("T_cab", "K")[k0], ds.get("T_evap", "K")[k0]
        T_int, T_shell = ds.get("T_int", "K")[k0], ds.get("T_shell", "K")[k0]
        for i in range(1, 81):
            k = k0 + i - 1
            T_ain = g[5] * T_evap + g[6] * W[k] + tau[2]
            T_cab, T_evap = (T_cab + g[0] * (T_int - T_cab) + g[1] * (T_shell - T_cab)
                             + g[2] * (T_ain - T_cab) * W[k] + tau[0],
                             g[3] * T_evap + g[4] * (T_evap - Ts_[k]) + tau[1])
            want = (T_cab, T_evap, g[5] * T_evap + g[6] * W[k + 1] + tau[2])
            np.testing.assert_allclose(res.predicted[s, i, :3], want, rtol=0, atol=1e-9)


def test_non_overlapping_starts_and_the_window_design(rng):
    m = load("cabin3")
    ds = _cabin3_record(m.values, rng, n=400)
    res = validate_model(m, ds, starts=60, horizon=50, warmup=100.0, non_overlapping=True)
    assert np.all(np.diff(res.starts) >= 51) and res.starts.size == 7
    assert "no overlap" in res.notes[0] and res.notes[0].startswith("window design: 7 starts")
    dense = validate_model(m, ds, starts=60, horizon=50, warmup=100.0)
    assert "overlapping" in dense.notes[0]


@pytest.mark.parametrize("warm_start", ["fit", "ekf"])
def test_progress_names_each_step_and_changes_no_number(rng, warm_start):
    """``acid validate``'s progress comes from this callback: bit-identical results with and
    without it (latent states warm-started, disturbances held, yardsticks)."""
    m = load("cabin3")
    ds = _cabin3_record(m.values, rng, n=400)
    kw = {"starts": 40, "horizon": 60, "warmup": 100.0, "hold": ("T_amb",), "yardsticks": True,
          "warm_start": warm_start}
    seen = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        quiet = validate_model(m, ds, **kw)
        told = validate_model(m, ds, progress=lambda *a: seen.append(a), **kw)
    assert [(d, t) for d, t, _ in seen] == [(i, 5) for i in range(1, 6)]
    assert [label.split(" (")[0] for _, _, label in seen] == [
        "40 starts placed", "latent states estimated", "40 windows of 60 steps simulated",
        "errors scored", "yardsticks predicted"]
    assert seen[-1][2] == "yardsticks predicted (persistence, arx, subspace)"
    for name in ("starts", "predicted", "measured", "inputs", "start_time"):
        a, b = getattr(quiet, name), getattr(told, name)
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), name
    for c in quiet.errors:
        assert quiet.errors[c].tobytes() == told.errors[c].tobytes(), c
    assert json.dumps(quiet.to_json_dict(), sort_keys=True) == json.dumps(
        told.to_json_dict(), sort_keys=True)


def _noisy_cabin3(rng, n=160):
    """cabin3's record with 0.1 K noise on every channel and one unobserved T_ain sample,
    validated with parameters 5 % off: the warm-up fit has a non-zero residual."""
    m = load("cabin3")
    ds = _cabin3_record(m.values, rng, n=n, T_int0=320.0, noise=0.1,
                        unobserved=[("T_ain", 50)])
    return m, ds, declared_parameters(m).perturbed(0.05, rng)


def _noisy_heating(rng, n=160):
    """The heating declaration (nonlinear in the coolant: the cold-air guard) warming a
    cabin from -5 degC with random heater steps, 0.1 K noise, parameters 5 % off."""
    m = load("heating")
    P_h = np.repeat(rng.uniform(0.0, 5000.0, n // 20 + 1), 20)[:n]
    Ta, v = np.full(n, 268.15), np.repeat(rng.uniform(0.0, 20.0, n // 20 + 1), 20)[:n]
    X, _ = m.simulate(np.array([268.15, 268.15, 268.15, 268.15, 268.15]), P_h[:, None],
                      np.c_[Ta, v], declared_parameters(m).theta)
    ch = {c: X[:-1, i] - 273.15 + 0.1 * rng.standard_normal(n)
          for i, c in enumerate(("T_cool", "T_cab", "T_ain"))}
    ch.update(P_heater=P_h, T_amb=Ta - 273.15, v_veh=v)
    units = {c: {"P_heater": "W", "v_veh": "m/s"}.get(c, "degC") for c in ch}
    ds = Dataset(np.arange(n) * m.Ts, ch, units, m.Ts)
    return m, ds, declared_parameters(m).perturbed(0.01, rng)


@pytest.mark.parametrize("case, atol", [(_noisy_cabin3, 1e-7), (_noisy_heating, 1e-3)])
def test_the_warm_start_equals_the_joint_dense_solve(rng, case, atol):
    """Independent answer: every start's state at k - W fitted jointly, one dense problem
    over all starts (finite-difference Jacobian, the declaration's own numpy simulation),
    each channel divided by its std over every warm-up, then simulated W steps to k.
    cabin3 is linear in its state (one exact step); the heating model is not (the cold-air
    guard), and its latent interior and shell are weakly seen over 300 s: there the two
    solvers' stopping points may differ along that flat direction (about 1e-4 K), never in
    cost."""
    import scipy.optimize

    from acid.ident.data import ModelData
    from acid.ident.validate import _fit_initial_states, warm_start_states

    m, ds, p = case(rng)
    data = ModelData.of(m, ds, min_samples=2)
    W, k0 = 60, np.array([70, 85, 91, 120, 150])
    U, D = data.u, data.d
    meas = np.stack([data.observed()[k - W:k] for k in k0])              # (n, W, nx + ny)
    chan = [c for c, _ in data.measured_channels(m)]
    meas = meas[..., chan]
    ok = np.isfinite(meas)
    scale = np.array([np.std(meas[..., i][ok[..., i]]) for i in range(len(chan))])

    def predicted(z):
        X, Y = m.simulate(z.reshape(k0.size, m.nx), np.stack([U[k - W:k] for k in k0]),
                          np.stack([D[k - W:k] for k in k0]), p.theta)
        return np.concatenate([X[:, :-1], Y], axis=-1), X[:, -1]

    def resid(z):
        return ((predicted(z)[0][..., chan] - np.nan_to_num(meas)) / scale)[ok]

    z0 = data.initial_states(m, k0 - W).ravel()
    joint = scipy.optimize.least_squares(resid, z0, method="trf", x_scale="jac",
                                         ftol=1e-15, xtol=1e-15, gtol=1e-15)
    assert joint.cost > 0.1                                      # a real residual to fit
    expected = predicted(joint.x)[1]                            # (n, nx) state at k
    P = np.tile(p.theta, (k0.size, 1))
    latent = [i for i, st in enumerate(m.states) if not st.measured]
    measured = [i for i, st in enumerate(m.states) if st.measured]
    rule = data.initial_states(m, k0)
    got = warm_start_states(m, data, P, k0, W, rule, latent)
    np.testing.assert_allclose(got[:, latent], expected[:, latent], rtol=0, atol=atol)
    z = _fit_initial_states(m, data, P, (k0 - W)[:, None] + np.arange(W)[None, :], meas,
                            chan, scale, z0.reshape(k0.size, m.nx))
    assert 0.5 * np.sum(resid(z.ravel()) ** 2) <= joint.cost * (1 + 1e-9)
    np.testing.assert_array_equal(got[:, measured], rule[:, measured])
    assert np.max(np.abs(got[:, latent] - rule[:, latent])) > 0.5


def test_each_start_is_fitted_on_its_own(rng):
    """Separable: with the channel weights given, a window's fitted initial state is the
    same, bit for bit, alone or among others (no cost growing with the others)."""
    from acid.ident.data import ModelData
    from acid.ident.validate import _fit_initial_states

    m, ds, p = _noisy_cabin3(rng)
    data = ModelData.of(m, ds, min_samples=2)
    W, k0 = 30, np.array([40, 55, 61, 90, 130])
    idx = (k0 - W)[:, None] + np.arange(W)[None, :]
    chan = [c for c, _ in data.measured_channels(m)]
    meas = data.observed()[idx][..., chan]
    scale = np.array([0.7, 1.3, 2.1])
    P = np.tile(p.theta, (k0.size, 1))
    x_first = data.initial_states(m, k0 - W)
    together = _fit_initial_states(m, data, P, idx, meas, chan, scale, x_first)
    for s in (0, 2, 4):
        alone = _fit_initial_states(m, data, P[[s]], idx[[s]], meas[[s]], chan, scale,
                                    x_first[[s]])
        np.testing.assert_array_equal(alone[0], together[s])
    assert not np.allclose(together, x_first)                   # it did fit something
