"""acid.ident.fit: fits derived from a declaration (least squares where an equation allows
it, CVXPY bounds, output error with latent initial states, multi-start, per-experiment and
fixed parameters, identified combinations)."""

from __future__ import annotations

import numpy as np
import pytest

from acid.data import Dataset
from acid.errors import ConfigError
from acid.ident.fit import fit_model
from acid.models import Model, Parameter, Signal, State, load, sin
from acid.plant.declared import econ_plant


def _dataset(channels: dict, units: dict, Ts: float, experiment=None) -> Dataset:
    n = len(next(iter(channels.values())))
    return Dataset(np.arange(n) * Ts, channels, units, Ts, experiment=experiment)


# ------------------------------------------------------------------ least squares
def _paper_regressions(ds) -> dict:
    """The regressors of eqs. 1-3 and 5 written out with numpy (eq. 1 with the measured
    T_ain), rows inside the one experiment."""
    cab, evap, ain, Tset, Tint, Tsh = (ds.get(n, "K") for n in (
        "T_cab", "T_evap", "T_ain", "T_evap_set", "T_int", "T_shell"))
    W, Pbl = ds.get("W_bl"), ds.get("P_bl")
    one = np.ones(len(ds))
    k = slice(0, -1)
    return {
        ("gamma1", "gamma2", "gamma3", "tau1"): (
            np.c_[Tint[k] - cab[k], Tsh[k] - cab[k], (ain[k] - cab[k]) * W[k], one[k]],
            cab[1:] - cab[k]),
        ("gamma4", "gamma5", "tau2"): (np.c_[evap[k], evap[k] - Tset[k], one[k]], evap[1:]),
        ("gamma6", "gamma7", "tau3"): (np.c_[evap, W, one], ain),
        ("beta1", "beta2", "beta3"): (np.c_[W * W, W, one], Pbl),
    }


def test_paper_ls_equals_an_independent_lstsq_and_white_formula(noisy_model_dataset):
    ds = noisy_model_dataset
    res = fit_model("paper", ds, method="ls", covariance="white")
    assert res.method == "ls"
    assert {q.name: q.method for q in res.equations} == {
        "T_cab": "ls", "T_evap": "ls", "T_ain": "ls", "P_bl": "ls"}
    se = {e.name: e.stderr for e in res.estimates}
    for names, (X, y) in _paper_regressions(ds).items():
        theta = np.linalg.lstsq(X, y, rcond=None)[0]
        for n, t in zip(names, theta, strict=True):
            assert res.value(n) == pytest.approx(t, rel=1e-9), n
        if names[0] == "beta1":     # P_bl is noise-free here: its errors are round-off
            continue
        r = y - X @ theta
        cov = float(r @ r) / (X.shape[0] - X.shape[1]) * np.linalg.inv(X.T @ X)
        for n, s in zip(names, np.sqrt(np.diag(cov)), strict=True):
            assert se[n] == pytest.approx(s, rel=1e-6), n


def _toy(outputs_fn, parameters, source="toy.py", **kw):
    return Model("toy", states=[State("x", "1")], inputs=[Signal("u", "1")],
                 outputs=[Signal("y", "1")], parameters=parameters, Ts=1.0,
                 step=lambda s: {"x": s.x}, output=outputs_fn, source=source, **kw)


def _toy_data(u, y, experiment=None):
    return _dataset({"x": np.zeros_like(u), "u": u, "y": y}, {"x": "1", "u": "1", "y": "1"},
                    1.0, experiment)


def test_collinear_parameters_report_the_identified_combination(rng):
    m = _toy(lambda s: {"y": s.a * s.u + s.b * s.u + s.c},
             [Parameter("a", "1", 1.0), Parameter("b", "1", 0.0), Parameter("c", "1", 0.0)])
    u = rng.standard_normal(300)
    res = fit_model(m, _toy_data(u, 3.0 * u + 0.5 + 0.01 * rng.standard_normal(300)),
                    method="ls")
    assert any(c.startswith("a + b = 3.0") or c.startswith("a + b = 2.99")
               for c in res.combinations), res.combinations
    status = {e.name: e.status for e in res.estimates}
    assert status["a"] == status["b"] == "combination" and status["c"] == "estimated (ls)"
    # closest to the declared values: the correction splits evenly between a and b
    assert res.value("a") - 1.0 == pytest.approx(res.value("b") - 0.0, rel=1e-9)
    assert res.value("a") + res.value("b") == pytest.approx(3.0, abs=0.01)


def test_a_constant_input_identifies_the_scaled_combination(rng):
    # u held at 0.1: y = g u + c identifies 0.1 g + c (acid.fit held g at a reference)
    m = _toy(lambda s: {"y": s.g * s.u + s.c}, [Parameter("g", "1", 30.0),
                                                 Parameter("c", "1", 150.0)])
    u = np.full(300, 0.1)
    res = fit_model(m, _toy_data(u, 0.1 * 35.0 + 154.5 + 0.01 * rng.standard_normal(300)),
                    method="ls")
    (combo,) = res.combinations
    assert combo.startswith("0.1 g + c = "), combo
    assert float(combo.split("= ")[1].split()[0]) == pytest.approx(158.0, abs=0.005)
    assert 0.1 * res.value("g") + res.value("c") == pytest.approx(158.0, abs=0.005)


def test_cvx_keeps_the_declared_bounds(rng):
    m = _toy(lambda s: {"y": s.g * s.u + s.c},
             [Parameter("g", "1", 0.5, 0.0, 1.0), Parameter("c", "1", 0.0)])
    u = rng.standard_normal(200)
    ds = _toy_data(u, 2.0 * u + 1.0)
    ls = fit_model(m, ds, method="ls")
    assert ls.value("g") == pytest.approx(2.0) and ls.warnings
    cvx = fit_model(m, ds, method="cvx")
    assert cvx.value("g") == pytest.approx(1.0, abs=1e-9)
    assert any("g at its max" in a for q in cvx.equations for a in q.active_bounds)


def test_per_experiment_parameter_by_least_squares(rng):
    m = _toy(lambda s: {"y": s.g * s.u + s.q},
             [Parameter("g", "1", 1.0), Parameter("q", "1", 0.0, per_experiment=True)])
    u = rng.standard_normal(300)
    exp = np.repeat([0, 1, 2], 100)
    q_true = np.array([1.0, -2.0, 5.0])
    res = fit_model(m, _toy_data(u, 0.7 * u + q_true[exp], exp), method="ls")
    np.testing.assert_allclose(res.per_experiment["q"], q_true, atol=1e-10)
    assert res.value("g") == pytest.approx(0.7, abs=1e-12)


def test_fixed_parameter_is_held_and_freed_again(rng):
    m = _toy(lambda s: {"y": s.g * s.u + s.c},
             [Parameter("g", "1", 1.0, fixed=True), Parameter("c", "1", 0.0)])
    u = rng.standard_normal(200)
    ds = _toy_data(u, 2.0 * u + 1.0)
    held = fit_model(m, ds)
    assert held.value("g") == 1.0 and {e.name: e.status for e in held.estimates}["g"] == "fixed"
    freed = fit_model(m, ds, free=("g",))
    assert freed.value("g") == pytest.approx(2.0) and freed.value("c") == pytest.approx(1.0)
    fixed = fit_model(m, ds, fix={"c": 0.5}, free=("g",))
    assert fixed.value("c") == 0.5


def test_unknown_method_is_one_line(noisy_model_dataset):
    with pytest.raises(ConfigError, match="unknown method 'nope'"):
        fit_model("paper", noisy_model_dataset, method="nope")


# ------------------------------------------------------------------- output error
def _cabin3_data(truth, q_sol, rng, n=240):
    """Noise-free data of the cabin3 declaration itself: two experiments, one Q_sol each."""
    m = load("cabin3")
    parts = []
    for q in q_sol:
        dwell = 20
        W = np.repeat(rng.uniform(0.04, 0.16, n // dwell + 1), dwell)[:n]
        Ts_ = np.repeat(rng.uniform(275.0, 284.0, n // dwell + 1), dwell)[:n]
        Ta = 305.0 + 3.0 * np.sin(np.arange(n) / 60.0)
        p = truth.copy()
        p[m.parameter_names.index("Q_sol")] = q
        X, Y = m.simulate(np.array([308.0, 312.0, 281.0]), np.c_[W, Ts_], Ta[:, None], p)
        ch = {"T_cab": X[:-1, 0] - 273.15, "T_evap": X[:-1, 2] - 273.15,
              "T_ain": Y[:, 0] - 273.15, "W_bl": W, "T_evap_set": Ts_ - 273.15,
              "T_amb": Ta - 273.15}
        parts.append(Dataset(np.arange(n) * 5.0, ch, {k: "kg/s" if k == "W_bl" else "degC"
                                                    for k in ch}, 5.0))
    return Dataset.concatenate(parts)


def test_output_error_recovers_a_latent_state_model_and_per_experiment_load(rng):
    m = load("cabin3")
    truth = np.array([8.0, 80.0, 120.0, 70.0, 15.0, 0.5, 0.15, 0.8, 0.0])
    ds = _cabin3_data(truth, (300.0, 900.0), rng)
    res = fit_model(m, ds, oe_window=120)
    assert res.method == "oe" and res.output_error["converged"]
    assert {q.name: q.method for q in res.equations}["T_ain"] == "ls start, oe"
    for name, t in zip(m.parameter_names, truth, strict=True):
        if name != "Q_sol":
            assert res.value(name) == pytest.approx(t, rel=1e-3), name
    np.testing.assert_allclose(res.per_experiment["Q_sol"], [300.0, 900.0], rtol=1e-3)
    assert "latent: T_int_lumped" in " ".join(res.notes)


def test_multi_start_finds_the_global_optimum_and_reports_distinct_optima():
    # y = A sin(w u) on a ramp: many local optima in w
    m = _toy(lambda s: {"y": s.A * sin(s.w * s.u)},
             [Parameter("A", "1", 1.5, 0.5, 2.0), Parameter("w", "1", 0.62, 0.05, 1.0)])
    u = np.arange(40.0)
    ds = _toy_data(u, np.sin(0.3 * u))
    one = fit_model(m, ds, method="oe", oe_window=40)
    assert abs(one.value("w") - 0.3) > 1e-2          # a single start stays in a local optimum
    res = fit_model(m, ds, method="oe", oe_window=40, fit_starts=16, seed=3)
    assert res.value("w") == pytest.approx(0.3, rel=1e-6)
    assert res.value("A") == pytest.approx(1.0, rel=1e-6)
    assert len(res.optima) >= 2 and sum(o.n_starts for o in res.optima) == 16
    assert res.optima[0].loss < 1e-12 < res.optima[1].loss
    assert res.optima[0].values["w"] == pytest.approx(0.3, rel=1e-6)
    again = fit_model(m, ds, method="oe", oe_window=40, fit_starts=16, seed=3)
    assert again.optima == res.optima                  # same seed, same result


def test_the_econ_declaration_gains_output_error():
    from acid.excite import excite, spec_for_model

    m = load("econ")
    truth = {"C_cab": 5000.0, "hA_int": 170.0, "Q_sh": 700.0, "tau_ew": 14.0}
    theta = m.values.copy()
    for n, v in truth.items():
        theta[m.parameter_names.index(n)] = v
    plant = econ_plant(theta)
    ds = excite(plant, spec_for_model("econ", duration=1200.0, seed=1))
    free = tuple(truth)
    res = fit_model(m, ds, method="oe", oe_window=120,
                    fix={n: v for n, v in zip(m.parameter_names, m.values, strict=True)
                         if n not in free})
    for n in free:
        assert res.value(n) == pytest.approx(truth[n], rel=1e-6), n
    assert set(res.output_error["channel_rms"]) >= {"T_cab", "T_int", "w_cab", "P_comp"}


def test_paper_hac_standard_errors_equal_statsmodels(noisy_model_dataset):
    """Newey-West with the fit's own lag against statsmodels' HAC (Bartlett kernel, small-
    sample correction n / (n - k))."""
    sm = pytest.importorskip("statsmodels.api")
    res = fit_model("paper", noisy_model_dataset, method="ls", covariance="hac")
    se = {e.name: e.stderr for e in res.estimates}
    for names, (X, y) in _paper_regressions(noisy_model_dataset).items():
        if names[0] == "beta1":      # P_bl is noise-free here: round-off errors
            continue
        lag = res.hac_bandwidth[{"gamma1": "T_cab", "gamma4": "T_evap",
                                 "gamma6": "T_ain"}[names[0]]]
        ref = sm.OLS(y, X).fit(cov_type="HAC", cov_kwds={"maxlags": lag,
                                                          "use_correction": True})
        for n, s in zip(names, ref.bse, strict=True):
            assert se[n] == pytest.approx(s, rel=1e-6), n


def test_a_users_linear_model_file_equals_an_independent_lstsq(tmp_path, rng):
    path = tmp_path / "arx_cabin.py"
    path.write_text(
        "from acid.models import Model, Parameter, Signal, State\n"
        "def step(s):\n"
        "    return {'T_cab': s.a * s.T_cab + s.b * s.T_amb + s.c * s.W_bl * s.T_ain + s.d}\n"
        "model = Model('arx', states=[State('T_cab', 'K')],\n"
        "              inputs=[Signal('W_bl', 'kg/s'), Signal('T_ain', 'K')],\n"
        "              disturbances=[Signal('T_amb', 'K')],\n"
        "              parameters=[Parameter(n, u, 0.0) for n, u in\n"
        "                          (('a', '1'), ('b', '1'), ('c', 's/kg'), ('d', 'K'))],\n"
        "              Ts=5.0, step=step)\n")
    n = 400
    W, Tain, Tamb = rng.uniform(0.05, 0.15, n), rng.uniform(280, 290, n), rng.uniform(300, 310, n)
    T = np.empty(n)
    T[0] = 300.0
    for k in range(n - 1):
        T[k + 1] = (0.95 * T[k] + 0.03 * Tamb[k] + 0.2 * W[k] * Tain[k] - 0.3
                    + 0.02 * rng.standard_normal())
    ds = _dataset({"T_cab": T - 273.15, "W_bl": W, "T_ain": Tain - 273.15,
                   "T_amb": Tamb - 273.15},
                  {"T_cab": "degC", "W_bl": "kg/s", "T_ain": "degC", "T_amb": "degC"}, 5.0)
    res = fit_model(str(path), ds)
    assert res.method == "ls" and res.equations[0].method == "ls"
    X = np.c_[T[:-1], Tamb[:-1], W[:-1] * Tain[:-1], np.ones(n - 1)]
    theta = np.linalg.lstsq(X, T[1:], rcond=None)[0]
    for name, t in zip("abcd", theta, strict=True):
        assert res.value(name) == pytest.approx(t, rel=1e-6), name


def test_residual_whiteness_per_equation(rng):
    m = _toy(lambda s: {"y": s.g * s.u + s.c}, [Parameter("g", "1", 1.0),
                                                 Parameter("c", "1", 0.0)])
    u = rng.standard_normal(2000)
    white = fit_model(m, _toy_data(u, 2 * u + rng.standard_normal(2000)), method="ls")
    ar = np.zeros(2000)
    for k in range(1, 2000):   # AR(1) errors: the equation misses dynamics
        ar[k] = 0.8 * ar[k - 1] + rng.standard_normal()
    coloured = fit_model(m, _toy_data(u, 2 * u + ar), method="ls")
    (w,) = [q for q in white.equations if q.name == "y"]
    (c,) = [q for q in coloured.equations if q.name == "y"]
    assert abs(w.residual_acf1) < 0.1 and w.ljung_box_p > 0.01
    assert c.residual_acf1 == pytest.approx(0.8, abs=0.05) and c.ljung_box_p < 1e-6


def test_multi_start_lists_diverged_starts_as_failed_not_as_optima():
    # y = A exp(k u): starts with k above ~70 overflow, others between diverge in the solver
    from acid.models import exp

    m = _toy(lambda s: {"y": s.A * exp(s.k * s.u)},
             [Parameter("A", "1", 1.2, 0.5, 2.0), Parameter("k", "1", 0.12, 0.0, 100.0)])
    u = np.linspace(0, 10, 40)
    res = fit_model(m, _toy_data(u, np.exp(0.1 * u)), method="oe", oe_window=40,
                    fit_starts=8, seed=1)
    assert res.failed_starts and len(res.failed_starts) + sum(
        o.n_starts for o in res.optima) == 8
    assert all(f.reason for f in res.failed_starts)
    assert all(np.isfinite(o.loss) and o.loss < 1e-6 for o in res.optima)
    assert res.value("k") == pytest.approx(0.1, rel=1e-6)
    assert "failed" in " ".join(res.notes)
    assert res.to_json_dict()["failed_starts"][0]["reason"] == res.failed_starts[0].reason
    # the basins in one line: loss x starts per optimum, failed starts per kind
    note = next(n for n in res.notes if n.startswith("multi-start"))
    n_best = res.optima[0].n_starts
    assert f"x {n_best})" in note or f"x {n_best}," in note
    assert f"{len(res.failed_starts)} failed (" in note and "the solver failed x" in note


def test_a_failed_start_that_ended_at_a_converged_optimum_says_so():
    from acid.ident.fit import _in_basins
    from acid.ident.linear import Column
    from acid.ident.result import FailedStart, Optimum

    cols = [Column(0, "a", None), Column(1, "b", None)]
    best = Optimum(2.0, 3, {"a": 1.0, "b": -4.0}, {"a": 0.0, "b": 0.0})
    other = Optimum(5.0, 1, {"a": 3.0, "b": 1.0}, {"a": 0.0, "b": 0.0})
    stopped = FailedStart(4, 5.0 * (1 + 1e-9), "solver failed or stopped: cap",
                          {"a": 3.0 * (1 + 1e-6), "b": 1.0})
    away = FailedStart(5, 9.0, "solver failed or stopped: cap", {"a": 0.2, "b": 7.0})
    out = _in_basins([stopped, away], [best, other], cols)
    assert out[0].reason.endswith("; it ended at optimum 2")
    assert out[1] == away


def test_a_parameter_ending_on_its_bound_is_named(rng):
    # y = a u with a true 3 but declared at most 2: least squares inside the bounds ends on it
    m = _toy(lambda s: {"y": s.a * s.u + s.c},
             [Parameter("a", "1", 1.0, 0.0, 2.0), Parameter("c", "1", 0.0, -1.0, 1.0)])
    u = rng.standard_normal(200)
    res = fit_model(m, _toy_data(u, 3.0 * u + 0.2 + 0.01 * rng.standard_normal(200)),
                    method="cvx")
    assert res.on_bounds == ("a at its max 2",)
    oe = fit_model(m, _toy_data(u, 3.0 * u + 0.2), method="oe", oe_window=50)
    assert oe.on_bounds == ("a at its max 2",)
    assert oe.to_json_dict()["on_bounds"] == ["a at its max 2"]
