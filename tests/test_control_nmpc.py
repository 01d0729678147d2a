"""NMPC (paper eqs. 7-13): closed-loop constraints, optimality, fallback, eq. 13 readings."""

from __future__ import annotations

import numpy as np
import pytest
from _paper_oracle import inlet_air as _inlet_air
from _paper_oracle import power as _power
from _paper_oracle import step as _step
from scipy.optimize import minimize

from acid.control.nmpc import NMPC, NMPCConfig
from acid.errors import ConfigError, DataError, SolverWarning
from acid.models.params import paper
from acid.plant import ModelPlant
from acid.studies.mpc_check.scenarios import (
    BOUND_STEPS,
    MODEL_T_INT,
    MODEL_T_SHELL,
    cav_scenario,
    closed_loop,
    run_cav_scenario,
    run_model_scenario,
    run_plant_scenario,
    step_bound,
)
from acid.units import C2K

P = paper()


@pytest.fixture(scope="module")
def model_scenario():
    return run_model_scenario(P)


@pytest.fixture(scope="module")
def mpc():
    return NMPC(P, NMPCConfig())


# ------------------------------------------------------------------ scenario (a)
def test_model_scenario_meets_constraints_after_first_step(model_scenario):
    assert model_scenario.passed, model_scenario.to_json_dict()
    for run in model_scenario.runs:
        assert run.max_violation_K <= 0.01, (run.label, run.violation)
        assert not run.fallback.any()


def test_hot_start_first_step_violation_is_the_unavoidable_one(model_scenario):
    hot = model_scenario.runs[0]
    unavoidable = model_scenario.metrics["unavoidable_first_step_violation_K"][0]
    assert unavoidable > 0.5  # the scenario really starts hot
    assert hot.first_step_violation_K == pytest.approx(unavoidable, abs=0.01)


def test_cabin_rides_its_upper_bound_in_steady_state(model_scenario):
    for run in model_scenario.runs:
        last = run.time >= run.time[-1] - 20.0
        np.testing.assert_allclose(run.T_cab[last], run.T_cab_max[last], atol=0.01,
                                   err_msg=f"{run.label}: minimum energy rides the bound")


def test_scenario_energy_is_the_sum_of_step_powers(model_scenario):
    run = model_scenario.runs[1]
    assert run.energy_J() == pytest.approx(np.sum(run.P_comp + run.P_bl) * 5.0)
    assert model_scenario.energy_MJ == pytest.approx(
        sum(r.energy_J() for r in model_scenario.runs) / 1e6)


# ------------------------------------------------------------------ optimality
N = 6
_LB = NMPCConfig()


def _condensed(z, x0, T_int, T_shell, ub):
    """Cost (kW) and constraints of eqs. 7-13, condensed on z = [W, Tset, s_cab, s_evap].

    ``z`` may carry leading batch dimensions (the last axis holds the 4 N variables).
    """
    cfg = _LB
    W = cfg.W_bl_min + z[..., :N] * (cfg.W_bl_max - cfg.W_bl_min)
    Ts = cfg.T_evap_set_min + z[..., N:2 * N] * (cfg.T_evap_set_max - cfg.T_evap_set_min)
    s_c, s_e = z[..., 2 * N:3 * N], z[..., 3 * N:]
    Tc, Te = x0[0] + 0 * z[..., 0], x0[1] + 0 * z[..., 0]
    cost, cons = 0.0, []
    for i in range(N):
        Wi = W[..., i]
        Tc_n, Te_n, Ta = _step(Tc, Te, Wi, Ts[..., i], T_int, T_shell, P)
        cost = cost + _power(Wi, Ta, cfg.T_amb, P)
        cost = cost + cfg.slack_penalty * (s_c[..., i] + s_e[..., i])
        Tc, Te = Tc_n, Te_n
        cons += [ub[i + 1] + s_c[..., i] - Tc, Tc + s_c[..., i] - cfg.T_cab_min,
                 cfg.T_evap_max + s_e[..., i] - Te, Te + s_e[..., i] - cfg.T_evap_min]
    Wl = W[..., -1]
    Ta = _inlet_air(Te, Wl, P)
    cost = cost + _power(Wl, Ta, cfg.T_amb, P)
    return cost * 1e-3, cons


def _complex_step_grad(fun, z, h=1e-30):
    """Exact first derivatives of a + - * function by the complex-step method (batched)."""
    Z = z.astype(complex) + 1j * h * np.eye(z.size)
    return (np.imag(np.asarray(fun(Z), dtype=complex)) / h).T


def _slsqp(x0, T_int, T_shell, ub, rng, starts=4):
    """Independent solution: SLSQP from many starts on the condensed problem."""

    def f(z):
        return _condensed(z, x0, T_int, T_shell, ub)[0]

    def g(z):
        return np.stack(_condensed(z, x0, T_int, T_shell, ub)[1], axis=-1)

    bounds = [(0.0, 1.0)] * (2 * N) + [(0.0, None)] * (2 * N)
    best = None
    for _ in range(starts):
        z0 = np.r_[rng.uniform(0, 1, 2 * N), np.zeros(2 * N)]
        viol = np.maximum(0.0, -g(z0))  # start feasible: slacks cover the violations
        z0[2 * N:3 * N] = np.maximum(viol[0::4], viol[1::4]) + 0.1
        z0[3 * N:] = np.maximum(viol[2::4], viol[3::4]) + 0.1
        res = minimize(f, z0, jac=lambda z: np.real(_complex_step_grad(f, z)),
                       bounds=bounds, method="SLSQP",
                       constraints=[{"type": "ineq", "fun": g,
                                     "jac": lambda z: np.real(_complex_step_grad(g, z))}],
                       options={"ftol": 1e-14, "maxiter": 500})
        # status 8 (line search stalled) at ftol 1e-14 is SLSQP's limited precision: keep
        # such a point when it is feasible
        feasible = res.status in (0, 8) and g(res.x).min() > -1e-7
        if feasible and (best is None or res.fun < best.fun):
            best = res
    assert best is not None, "SLSQP failed from every start"
    cfg = _LB
    u0 = np.array([cfg.W_bl_min + best.x[0] * (cfg.W_bl_max - cfg.W_bl_min),
                   cfg.T_evap_set_min + best.x[N] * (cfg.T_evap_set_max - cfg.T_evap_set_min)])
    return u0, best.fun * 1e3


def _random_problem(rng):
    x0 = np.array([C2K(rng.uniform(22.0, 31.0)), C2K(rng.uniform(2.0, 11.0))])
    T_int, T_shell = C2K(rng.uniform(27.0, 32.0)), C2K(rng.uniform(29.0, 36.0))
    jump = rng.integers(1, N + 1)
    ub = np.where(np.arange(N + 1) < jump, C2K(rng.uniform(24.0, 28.5)),
                  C2K(rng.uniform(24.0, 28.5)))
    return x0, T_int, T_shell, ub


def test_optimum_matches_slsqp_multistart_on_random_states(mpc):
    rng = np.random.default_rng(7)
    errs = []
    for _ in range(20):
        x0, T_int, T_shell, ub = _random_problem(rng)
        mpc.reset()  # no warm start: each problem on its own
        sol = mpc.solve(x0, ub, T_int, T_shell)
        assert sol.success, sol.status
        u_ref, f_ref = _slsqp(x0, T_int, T_shell, ub, rng)
        rel_u = np.abs(sol.u - u_ref) / np.abs(u_ref)
        rel_f = abs(sol.objective - f_ref) / abs(f_ref)
        errs.append(max(rel_u.max(), rel_f))
        # ours is never worse than the best SLSQP start (tolerance of the solvers)
        assert sol.objective <= f_ref * (1 + 1e-6) + 1e-6
    assert max(errs) <= 1e-4, f"max relative error {max(errs):.2e}"


def test_objective_is_eq7_evaluated_with_the_model_functions(mpc):
    mpc.reset()
    x0 = np.array([C2K(28.0), C2K(8.0)])
    ub = np.full(N + 1, C2K(26.0))
    sol = mpc.solve(x0, ub, MODEL_T_INT, MODEL_T_SHELL)
    T_cab, T_evap, T_ain = [x0[0]], [x0[1]], []
    for W, Ts in zip(sol.W_bl, sol.T_evap_set, strict=True):
        c, e, a = _step(T_cab[-1], T_evap[-1], W, Ts, MODEL_T_INT, MODEL_T_SHELL, P)
        T_cab.append(c)
        T_evap.append(e)
        T_ain.append(a)
    np.testing.assert_allclose(sol.T_cab, T_cab, atol=1e-6)
    np.testing.assert_allclose(sol.T_evap, T_evap, atol=1e-6)
    np.testing.assert_allclose(sol.T_ain[:N], T_ain, atol=1e-6)
    f_ref = _condensed(np.r_[(sol.W_bl - 0.05) / 0.1, (sol.T_evap_set - C2K(3.0)) / 7.0,
                             sol.slack_cab, sol.slack_evap], x0, MODEL_T_INT, MODEL_T_SHELL,
                       ub)[0] * 1e3
    assert sol.objective == pytest.approx(f_ref, rel=1e-7)
    np.testing.assert_allclose(sol.slack_cab, np.maximum(0.0, T_cab[1:] - ub[1:]), atol=1e-5)


def test_ipopt_and_fatrop_reach_the_same_optimum():
    rng = np.random.default_rng(3)
    a, b = NMPC(P, NMPCConfig(solver="fatrop")), NMPC(P, NMPCConfig(solver="ipopt"))
    for _ in range(5):
        x0, T_int, T_shell, ub = _random_problem(rng)
        sa, sb = a.solve(x0, ub, T_int, T_shell), b.solve(x0, ub, T_int, T_shell)
        assert sa.success and sb.success
        np.testing.assert_allclose(sa.u, sb.u, rtol=1e-5)
        assert sa.objective == pytest.approx(sb.objective, rel=1e-6)


# ------------------------------------------------------------------ eq. 13 readings
def test_pinned_first_move_is_fixed_to_the_applied_input():
    ctl = NMPC(P, NMPCConfig(first_move="pinned"))
    x0, ub = np.array([C2K(27.0), C2K(6.0)]), np.full(N + 1, C2K(25.0))
    u_now = np.array([0.07, C2K(8.0)])
    sol = ctl.solve(x0, ub, MODEL_T_INT, MODEL_T_SHELL, u_prev=u_now)
    assert sol.success
    np.testing.assert_allclose(sol.plan[0], u_now, atol=1e-6)
    with pytest.raises(ConfigError, match="u_prev"):
        ctl.solve(x0, ub, MODEL_T_INT, MODEL_T_SHELL)


def test_pinned_make_step_applies_the_committed_move_then_the_plans_second():
    u_init = np.array([0.1, C2K(6.0)])
    ctl = NMPC(P, NMPCConfig(first_move="pinned"))
    ctl.reset(u_initial=u_init)
    x0, ub = np.array([C2K(27.0), C2K(6.0)]), np.full(N + 1, C2K(25.0))
    u0 = ctl.make_step(x0, ub, MODEL_T_INT, MODEL_T_SHELL)
    np.testing.assert_allclose(u0, u_init)
    committed = ctl.log.solutions[0].plan[1]
    u1 = ctl.make_step(x0, ub, MODEL_T_INT, MODEL_T_SHELL)
    np.testing.assert_allclose(u1, committed)


def test_free_first_move_ignores_u_prev_as_a_constraint(mpc):
    x0, ub = np.array([C2K(27.0), C2K(6.0)]), np.full(N + 1, C2K(25.0))
    mpc.reset()
    a = mpc.solve(x0, ub, MODEL_T_INT, MODEL_T_SHELL)
    mpc.reset()
    b = mpc.solve(x0, ub, MODEL_T_INT, MODEL_T_SHELL, u_prev=[0.05, C2K(10.0)])
    np.testing.assert_allclose(a.u, b.u, rtol=1e-6)
    assert abs(a.u[0] - 0.05) > 1e-3  # the optimum is not the guess


# ------------------------------------------------------------------ fallback
def test_forced_solver_failure_uses_the_shifted_plan_and_is_counted():
    ctl = NMPC(P, NMPCConfig())
    plant = ModelPlant(P)
    plant.reset({"T_cab": C2K(26.0), "T_evap": C2K(5.0), "T_int": MODEL_T_INT,
                 "T_shell": MODEL_T_SHELL})
    ub = np.full(N + 1, C2K(25.0))
    applied = []
    for k in range(6):
        bound = ub.copy()
        if k in (2, 3):
            bound[:] = np.nan  # an absurd bound: the solver cannot work with it
        x = [plant.T_cab, plant.T_evap]
        if k in (2, 3):
            with pytest.warns(SolverWarning, match="fallback"):
                u = ctl.make_step(x, bound, MODEL_T_INT, MODEL_T_SHELL)
        else:
            u = ctl.make_step(x, bound, MODEL_T_INT, MODEL_T_SHELL)
        applied.append(u)
        plant.step(u[0], u[1])
    assert ctl.fallbacks == 2
    assert ctl.log.fallback == [False, False, True, True, False, False]
    plan = ctl.log.solutions[1].plan
    np.testing.assert_allclose(applied[2], plan[1])
    np.testing.assert_allclose(applied[3], plan[2])
    assert ctl.log.solutions[4].success  # recovered


def test_fallback_without_a_plan_is_the_conservative_input():
    ctl = NMPC(P, NMPCConfig(max_iter=1))  # cannot converge in one iteration
    x0, ub = np.array([C2K(30.0), C2K(9.0)]), np.full(N + 1, C2K(25.0))
    with pytest.warns(SolverWarning):
        u = ctl.make_step(x0, ub, MODEL_T_INT, MODEL_T_SHELL)
    np.testing.assert_allclose(u, ctl.config.u_safe)
    assert ctl.fallbacks == 1


def test_closed_loop_survives_failures_without_crashing():
    ctl = NMPC(P, NMPCConfig(max_iter=1))
    n = 6
    ub = step_bound(np.arange(n + N + 1) * 5.0, BOUND_STEPS)
    with pytest.warns(SolverWarning):
        run = closed_loop(ModelPlant(P), ctl, {"T_cab": C2K(28.0), "T_evap": C2K(6.0)}, ub,
                          np.zeros(n), "all failing",
                          disturbance={"T_int": MODEL_T_INT, "T_shell": MODEL_T_SHELL})
    assert run.fallback.all() and run.n_steps == n
    assert np.all(np.isfinite(run.T_cab))


def test_config_rejects_unknown_readings():
    with pytest.raises(ConfigError, match="first_move"):
        NMPCConfig(first_move="maybe")
    with pytest.raises(ConfigError, match="solver"):
        NMPCConfig(solver="snopt")


# ------------------------------------------------------------------ plant scenarios
@pytest.mark.slow
def test_plant_scenario_runs_short_on_the_hifi_plant():
    pytest.importorskip("acid.plant.hifi")
    res = run_plant_scenario(P, duration_s=30.0)
    assert res.skipped is None
    for run in res.runs:
        assert run.n_steps == 6 and not run.fallback.any()
        assert np.all(run.P_comp >= 0.0) and np.all(run.P_bl > 0.0)


@pytest.mark.slow
def test_cav_scenario_case1_saves_energy():
    pytest.importorskip("acid.plant.hifi")
    ticks = []
    res = run_cav_scenario(P, progress=lambda: ticks.append(1))
    m = res.metrics
    assert res.passed and m["case1_energy_MJ"] < m["case2_energy_MJ"]
    # the progress total mpc-check announces is the number of closed-loop steps run
    assert len(ticks) == cav_scenario(P).closed_loop_steps(plants=2)
    assert m["periodic"]["cycles"] == 4 and m["periodic"]["window_s"] == [80.0, 320.0]
    assert "speed_blind_plant" in m and "saving_from_speed_pct" in m
    case1 = res.runs[0]
    assert not case1.compressor_on[12:16].any() and case1.compressor_on[:12].all()


def test_plant_scenarios_are_skipped_plainly_without_the_hifi_plant(monkeypatch):
    import acid.studies.mpc_check.scenarios as sc

    monkeypatch.setattr(sc, "hifi_available", lambda: "high-fidelity plant not available")
    for fn in (run_plant_scenario, run_cav_scenario):
        res = fn(P)
        assert res.skipped == "high-fidelity plant not available" and res.passed is None
        assert res.runs == () and res.to_json_dict()["skipped"]


# ------------------------------------------------------------------ inputs, bounds
def test_a_nan_measurement_falls_back_with_a_warning_and_never_reaches_the_solver():
    ctl = NMPC(P, NMPCConfig())
    ub = np.full(N + 1, C2K(25.0))
    u0 = ctl.make_step([C2K(27.0), C2K(6.0)], ub, MODEL_T_INT, MODEL_T_SHELL)
    for bad in ([np.nan, C2K(6.0)], [C2K(27.0), np.inf]):
        with pytest.warns(SolverWarning, match="non-finite measurement"):
            u = ctl.make_step(bad, ub, MODEL_T_INT, MODEL_T_SHELL)
        assert np.all(np.isfinite(u))
    with pytest.warns(SolverWarning, match="non-finite"):
        ctl.make_step([C2K(27.0), C2K(6.0)], ub, np.nan, MODEL_T_SHELL)
    np.testing.assert_allclose(ctl.log.u[1], ctl.log.solutions[0].plan[1])  # shifted plan
    assert ctl.fallbacks == 3 and ctl.log.solutions[1] is None
    u = ctl.make_step([C2K(27.0), C2K(6.0)], ub, MODEL_T_INT, MODEL_T_SHELL)  # recovers
    assert ctl.log.solutions[-1].success
    np.testing.assert_allclose(u, u0, rtol=1e-6)
    with pytest.raises(DataError, match="not finite"):
        ctl.solve([np.nan, C2K(6.0)], ub, MODEL_T_INT, MODEL_T_SHELL)


def test_a_state_in_degC_is_refused_with_a_message_saying_so():
    ctl = NMPC(P, NMPCConfig())
    with pytest.raises(DataError, match="looks like degC"):
        ctl.make_step([27.0, 6.0], C2K(25.0), MODEL_T_INT, MODEL_T_SHELL)
    with pytest.raises(DataError, match="T_int"):
        ctl.solve([C2K(27.0), C2K(6.0)], C2K(25.0), 30.0, MODEL_T_SHELL)
    with pytest.raises(DataError, match="T_cab_max"):
        ctl.solve([C2K(27.0), C2K(6.0)], 25.0, MODEL_T_INT, MODEL_T_SHELL)


def test_an_active_bound_is_met_exactly_not_overshot(model_scenario):
    """The solvers relax bounds by 1e-8 |bound|: 2.7e-6 K on a cabin bound before; the
    scaled NLP leaves at most 1e-8 K, and eq. 7 is the true one at the plan."""
    over = []
    for run in model_scenario.runs:
        riding = np.abs(run.T_cab - run.T_cab_max) < 1e-4
        riding[:2] = False
        over.append(np.max(run.T_cab[riding] - run.T_cab_max[riding]))
    assert max(over) < 1e-8


def test_the_objective_charges_the_slacks_actually_needed(mpc):
    mpc.reset()
    x0 = np.array([C2K(31.0), C2K(10.0)])  # hot: the bound cannot be met at once
    ub = np.full(N + 1, C2K(25.0))
    sol = mpc.solve(x0, ub, MODEL_T_INT, MODEL_T_SHELL)
    viol = np.maximum(sol.T_cab[1:] - ub[1:], 0.0)
    assert viol[0] > 1.0
    np.testing.assert_allclose(sol.slack_cab, viol, atol=1e-12)
    powers = np.sum(sol.P_comp + sol.P_bl)
    assert sol.objective == pytest.approx(powers + 1e5 * np.sum(viol + sol.slack_evap),
                                          rel=1e-12)


def test_the_three_solvers_reach_one_optimum():
    rng = np.random.default_rng(11)
    ctl = {s: NMPC(P, NMPCConfig(solver=s)) for s in ("fatrop", "ipopt", "sqp")}
    for _ in range(4):
        x0, T_int, T_shell, ub = _random_problem(rng)
        sol = {}
        for s, c in ctl.items():
            c.reset()
            sol[s] = c.solve(x0, ub, T_int, T_shell)
            assert sol[s].success, (s, sol[s].status)
        np.testing.assert_allclose(sol["sqp"].u, sol["ipopt"].u, rtol=1e-8)
        np.testing.assert_allclose(sol["fatrop"].u, sol["sqp"].u, rtol=1e-7)
        assert sol["fatrop"].objective == pytest.approx(sol["sqp"].objective, rel=1e-6)


@pytest.mark.slow
@pytest.mark.parametrize("which", ["paper", "identified"])
def test_plant_scenario_keeps_avoidable_violations_within_0_05_K(which):
    """Scenario (b) of acid mpc-check with the back-off; identified = acid fit --method oe
    on 2 h of acid excite data of the same plant."""
    pytest.importorskip("acid.plant.hifi")
    params = P
    if which == "identified":
        from acid.excite import ExcitationSpec, excite
        from acid.ident.fit import fit
        from acid.models.params import fitted
        from acid.plant.hifi import HifiPlant

        ds = excite(HifiPlant(), ExcitationSpec(seed=0))
        params = fitted(fit(ds, method="oe"))
    res = run_plant_scenario(params)
    d = res.to_json_dict()
    assert res.passed, d
    assert d["max_avoidable_violation_K"] <= 0.05
    # issue 13: after the first step no violation above 0.05 K at all (the 31 degC hot start
    # is one that maximum cooling brings under the bound by t = 2 Ts)
    assert d["max_violation_K"] <= 0.05
    assert all(r.to_json_dict()["unavoidable_violation_K"] <= 1e-9 for r in res.runs)
