"""acid.control.econ.nmpc: the economic NMPC on the econ model."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from acid.control.econ.nmpc import EconNMPC, EconNMPCConfig, stage_means
from acid.control.econ.terminal import SteadyStatePrice
from acid.errors import ConfigError, ExtrapolationWarning, SolverWarning
from acid.plant.declared import econ_plant
from acid.units import C2K

X = np.array([C2K(24.5), C2K(27.0), C2K(35.0), C2K(8.0), 0.008])
SHORT = (5.0,) * 8


def _cfg(**kw):  # CasADi's solver: compiling generated C takes minutes per structure
    return EconNMPCConfig(**{"intervals": SHORT, "T_cab_min": C2K(22.0),
                             "T_cab_max": C2K(24.0), "compiled": False, **kw})


def test_closed_loop_on_its_own_model_keeps_the_band(econ_truth):
    mpc = EconNMPC(econ_truth, _cfg())
    plant = econ_plant(econ_truth.theta_all)
    plant.reset(dict(zip(("T_cab", "T_int", "T_shell", "T_evap", "w_cab"), X, strict=True)))
    E, T = 0.0, []
    for _ in range(30):
        m = plant.measure()
        u = mpc.make_step([m[k] for k in ("T_cab", "T_int", "T_shell", "T_evap", "w_cab")],
                          12.0, C2K(30.0))
        assert np.all(u >= mpc.config.u_min) and np.all(u <= mpc.config.u_max)
        row = plant.step(u[0], u[1], 12.0, T_amb=C2K(30.0))
        E += (row["P_comp"] + row["P_bl"]) * 5.0
        T.append(plant.measure()["T_cab"])
    assert mpc.fallbacks == 0 and E > 0
    assert max(T[3:]) <= C2K(24.0) + 0.05       # after the pull-down, inside the band
    assert min(T[3:]) >= C2K(22.0) - 0.05
    assert T[-1] == pytest.approx(C2K(24.0), abs=0.1)   # rides the upper edge: least energy
    sol = mpc.log.solutions[-1]
    assert sol.success and sol.terminal_prices[0] > 0 and sol.x.shape == (9, 5)


def test_more_cooling_costs_more(econ_truth):
    e = []
    for top in (23.0, 24.0, 25.0):
        sol = EconNMPC(econ_truth, _cfg(T_cab_max=C2K(top))).solve(X, 12.0, C2K(30.0))
        assert sol.success
        e.append(sol.energy_J)
    assert e[0] > e[1] > e[2]


def test_fatrop_and_ipopt_solve_the_same_nlp(econ_truth):
    a = EconNMPC(econ_truth, _cfg()).solve(X, 12.0, C2K(30.0))
    b = EconNMPC(econ_truth, _cfg(solver="ipopt")).solve(X, 12.0, C2K(30.0))
    assert a.success and b.success
    np.testing.assert_allclose(a.u, b.u, rtol=1e-3)
    assert a.objective == pytest.approx(b.objective, rel=1e-5)


def test_without_preview_the_speed_is_held(econ_truth):
    ramp = np.linspace(0.0, 30.0, len(SHORT))
    held = EconNMPC(econ_truth, _cfg(preview=False))
    same = EconNMPC(econ_truth, _cfg())
    u_held = held.make_step(X, ramp, C2K(30.0))
    u_const = same.make_step(X, np.full(len(SHORT), ramp[0]), C2K(30.0))
    np.testing.assert_allclose(u_held, u_const, rtol=1e-9)


def test_non_uniform_grid_and_stage_means(econ_truth):
    cfg = _cfg(intervals=(5.0, 5.0, 10.0, 20.0))
    sol = EconNMPC(econ_truth, cfg).solve(X, 10.0, C2K(30.0))
    assert sol.success and sol.t[-1] == 40.0 and cfg.horizon_s == 40.0
    prof = np.arange(10.0)
    np.testing.assert_allclose(stage_means(prof, 2, (5.0, 5.0, 10.0), 5.0), [2, 3, 4.5])
    np.testing.assert_allclose(stage_means(prof, 8, (5.0, 10.0), 5.0), [8, 9])  # last holds


def test_terminal_prices(econ_truth):
    """'steady': the optimal steady state's multipliers at the horizon's mean speed;
    'heat': the heat content's gradient at the marginal compressor price; 'none': zero."""
    ramp = np.linspace(0.0, 30.0, len(SHORT))
    sol = {t: EconNMPC(econ_truth, _cfg(terminal=t)).solve(X, ramp, C2K(30.0))
           for t in ("steady", "heat", "none")}
    assert all(s.success for s in sol.values())
    mpc = EconNMPC(econ_truth, _cfg())
    lam = SteadyStatePrice(econ_truth, mpc.config.u_min, mpc.config.u_max)(
        15.0, C2K(30.0), C2K(22.0), C2K(24.0))
    np.testing.assert_allclose(sol["steady"].terminal_prices, lam, rtol=1e-6)
    p = econ_truth
    w_sh = p.hA_sh / (p.hA_sh + p.hA_ext0 + p.hA_ext_v * 30.0 ** 0.8)
    pi = sol["heat"].terminal_prices[0] / p.C_cab
    np.testing.assert_allclose(sol["heat"].terminal_prices,
                               pi * np.array([p.C_cab, p.C_int, w_sh * p.C_sh, p.C_ew,
                                              p.M_cab * p.h_fg]), rtol=1e-7)
    assert 0.05 <= pi < 1.0
    np.testing.assert_array_equal(sol["none"].terminal_prices, 0.0)
    s = sol["none"]   # objective = energy + slack penalty, nothing at the end
    assert s.objective == pytest.approx(
        s.energy_J + s.slack.sum() * 5.0 * _cfg().slack_penalty, rel=1e-5)


def test_extrapolation_is_an_explicit_warning(econ_truth):
    mpc = EconNMPC(econ_truth, _cfg())
    with pytest.warns(ExtrapolationWarning, match="v_veh up to 50"):
        mpc.make_step(X, 50.0, C2K(30.0))
    assert mpc.extrapolation


def test_solver_failure_falls_back_to_the_plan(econ_truth):
    mpc = EconNMPC(econ_truth, _cfg())
    mpc.make_step(X, 10.0, C2K(30.0))
    plan = mpc.log.solutions[-1].plan
    starved = EconNMPC(econ_truth, _cfg(max_iter=1))
    starved._plan, starved._plan_age = plan, 0
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        u = starved.make_step(X + 1.0, 10.0, C2K(30.0))
    assert any(issubclass(w.category, SolverWarning) for w in caught)
    assert starved.fallbacks == 1 and starved.log.fallback == [True]
    np.testing.assert_allclose(u, plan[1])


@pytest.mark.parametrize("kw, match", [
    ({"T_cab_min": C2K(24.0), "T_cab_max": C2K(22.0)}, "comfort band is empty"),
    ({"intervals": (5.0,)}, "at least 2"),
    ({"RH_max": 1.5}, "RH_max"),
    ({"terminal": "zero"}, "terminal must be one of"),
])
def test_bad_configuration(kw, match):
    with pytest.raises(ConfigError, match=match):
        _cfg(**kw)


def test_first_interval_must_be_the_sample_time(econ_truth):
    with pytest.raises(ConfigError, match="sample time"):
        EconNMPC(econ_truth, _cfg(intervals=(10.0, 10.0)))


def test_offset_free_estimation_removes_the_bias_of_a_mismatched_model(econ_truth):
    # the plant releases 200 W more into the cabin and has a better shell contact than the
    # model: without estimation the cabin settles above the band, with it on the band
    plant_p = econ_truth.replace(Q_cab=econ_truth.Q_cab + 200.0, hA_sh=85.0)
    start = dict(zip(("T_cab", "T_int", "T_shell", "T_evap", "w_cab"), X, strict=True))
    settled = {}
    for offset_free in (False, True):
        mpc = EconNMPC(econ_truth, _cfg(offset_free=offset_free))
        plant = econ_plant(plant_p.theta_all)
        plant.reset(start)
        for _ in range(60):
            m = plant.measure()
            u = mpc.make_step([m[k] for k in start], 12.0, C2K(30.0))
            plant.step(u[0], u[1], 12.0, T_amb=C2K(30.0))
        settled[offset_free] = plant.measure()["T_cab"]
        assert mpc.fallbacks == 0
    assert settled[False] > C2K(24.0) + 0.2
    assert settled[True] == pytest.approx(C2K(24.0), abs=0.02)
    assert mpc.log.disturbance[-1][0] > 0.0   # the estimated extra heat on the cabin air


def test_sqp_warm_started_reaches_the_interior_point_optimum(econ_truth):
    # cold start: SQP from the simulated guess may stall and IPOPT finishes it; warm
    # starts from the shifted plan converge in SQP, to IPOPT's optimum
    sqp = EconNMPC(econ_truth, _cfg(solver="sqp"))
    ip = EconNMPC(econ_truth, _cfg(solver="ipopt", tol=1e-10))
    plant = econ_plant(econ_truth.theta_all)
    plant.reset(dict(zip(("T_cab", "T_int", "T_shell", "T_evap", "w_cab"), X, strict=True)))
    for _ in range(8):
        m = plant.measure()
        x = [m[n] for n in ("T_cab", "T_int", "T_shell", "T_evap", "w_cab")]
        u = sqp.make_step(x, 12.0, C2K(30.0))
        ref = ip.solve(x, 12.0, C2K(30.0))
        assert np.max(np.abs(u - ref.u) / (sqp.config.u_max - sqp.config.u_min)) < 1e-6
        plant.step(u[0], u[1], 12.0, T_amb=C2K(30.0))
    assert sqp.fallbacks == 0 and sqp.solver_fallbacks <= 1
    assert "ipopt after sqp" not in sqp.log.solutions[-1].status



def test_first_moves_match_ipopt_at_tight_tolerance_with_the_default_horizon(econ_truth):
    # the economic cost is flat in the moves near its optimum: IPOPT at its default tol
    # (1e-6, scaled) stops up to 1e-3 (relative) from the optimal moves; at 1e-10 IPOPT
    # and the warm-started SQP (24 x 5 s, steady terminal price) agree to 1e-9
    cfg = EconNMPCConfig(T_cab_min=C2K(22.0), T_cab_max=C2K(24.0), compiled=False)
    sqp = EconNMPC(econ_truth, cfg)
    tight = EconNMPC(econ_truth, cfg.replace(solver="ipopt", tol=1e-10))
    plant = econ_plant(econ_truth.theta_all)
    plant.reset(dict(zip(("T_cab", "T_int", "T_shell", "T_evap", "w_cab"), X, strict=True)))
    for k in range(4):
        m = plant.measure()
        x = [m[n] for n in ("T_cab", "T_int", "T_shell", "T_evap", "w_cab")]
        v = 12.0 + 3.0 * np.sin(k)
        u = sqp.make_step(x, v, C2K(30.0))
        ref = tight.solve(x, v, C2K(30.0))
        tight.reset()
        assert ref.success and np.max(np.abs(u - ref.u) / np.abs(ref.u)) < 1e-8
        plant.step(u[0], u[1], v, T_amb=C2K(30.0))
    assert sqp.fallbacks == 0 and sqp.solver_fallbacks == 0


def test_ipopt_after_a_failed_sqp_solves_to_the_sqps_accuracy(econ_truth):
    off = EconNMPC(econ_truth, _cfg(solver="sqp", sqp_rescue=False))
    _declared_unconverged(off._solver)
    sol = off.solve(X, 12.0, C2K(30.0))
    ref = EconNMPC(econ_truth, _cfg(solver="ipopt", tol=1e-10)).solve(X, 12.0, C2K(30.0))
    assert "ipopt after sqp" in sol.status and sol.success
    assert np.max(np.abs(sol.u - ref.u) / np.abs(ref.u)) < 1e-8


def _declared_unconverged(solver):
    """Make ``solver`` (an NLPSolver) report every result as not converged."""
    solve = solver.solve

    def failing(*args, **kw):
        res = solve(*args, **kw)
        return type(res)(**{**res.__dict__, "success": False, "status": "not converged"})

    solver.solve = failing


def test_a_failed_sqp_solve_is_finished_by_the_convexified_sqp_at_ipopts_optimum(econ_truth):
    # the exact-Hessian SQP's failures are nonconvex QPs (qrqp cycling on a bound, steps
    # between bounds): the rescue solves the same NLP on a convexified Hessian, from the
    # same guess, before IPOPT; its result must be IPOPT's optimum
    mpc = EconNMPC(econ_truth, _cfg(solver="sqp"))
    _declared_unconverged(mpc._solver)
    sol = mpc.solve(X, 12.0, C2K(30.0))
    ref = EconNMPC(econ_truth, _cfg(solver="ipopt", tol=1e-10)).solve(X, 12.0, C2K(30.0))
    assert sol.success and "sqp_convex after sqp" in sol.status
    assert mpc.solver_rescues == 1 and mpc.solver_fallbacks == 0
    assert np.max(np.abs(sol.u - ref.u) / (mpc.config.u_max - mpc.config.u_min)) < 1e-6
    assert sol.objective == pytest.approx(ref.objective, rel=1e-6)
    off = EconNMPC(econ_truth, _cfg(solver="sqp", sqp_rescue=False))
    _declared_unconverged(off._solver)
    assert "ipopt after sqp" in off.solve(X, 12.0, C2K(30.0)).status
    assert off.solver_rescues == 0 and off.solver_fallbacks == 1


def test_comfort_price_holds_a_reference_and_is_not_counted_as_energy(econ_truth):
    # band 22-26 degC as a soft bound, the comfort price pulls toward the reference
    cfg = _cfg(T_cab_max=C2K(26.0), comfort_weight=30.0)
    mpc = EconNMPC(econ_truth, cfg)
    cool, warm = (mpc.solve(X, 12.0, C2K(30.0), T_cab_ref=C2K(r)) for r in (23.0, 25.0))
    assert cool.success and warm.success
    # a lower reference plans a cooler cabin and costs more energy
    assert cool.x[-1, 0] < warm.x[-1, 0] - 0.2 and cool.energy_J > warm.energy_J
    for sol, ref in ((cool, C2K(23.0)), (warm, C2K(25.0))):
        # energy_J is the electric energy alone (recomputed from the plan's powers, whose
        # P_comp takes the wall's end-point mean for the interval mean: 1e-3)
        assert sol.energy_J == pytest.approx(float(np.sum(5.0 * (sol.P_comp + sol.P_bl))),
                                             rel=1e-3)
        # the objective adds the comfort price at each stage's start state and the terminal
        # price (slacks are zero inside the band)
        price = float(np.sum(5.0 * 30.0 * (sol.x[:-1, 0] - ref) ** 2))
        term = float(sol.terminal_prices @ (sol.x[-1] - sol.x[0]))
        assert np.max(sol.slack) < 1e-6
        assert sol.objective == pytest.approx(sol.energy_J + price + term, rel=1e-5)
    # without the weight the reference is ignored and the band's edge binds
    plain = EconNMPC(econ_truth, _cfg(T_cab_max=C2K(24.0))).solve(X, 12.0, C2K(30.0),
                                                                  T_cab_ref=C2K(23.0))
    assert plain.success and plain.x[-1, 0] == pytest.approx(C2K(24.0), abs=0.05)


def test_comfort_weight_must_be_non_negative():
    with pytest.raises(ConfigError, match="comfort_weight"):
        EconNMPCConfig(comfort_weight=-1.0)


@pytest.mark.slow
def test_the_compiled_sqp_step_is_one_c_call_with_casadis_moves(econ_truth, monkeypatch):
    # the whole step (warm-start shift or cold guess, SQP, convergence check, the stages'
    # outputs) is one generated C function; 3 intervals keep its compile short
    from acid.control.codegen import build

    cfg = _cfg(intervals=(5.0,) * 3, compiled=True)
    fused = EconNMPC(econ_truth, cfg)
    if fused._step is None:
        pytest.skip("no working C compiler")
    ref = EconNMPC(econ_truth, cfg.replace(compiled=False))
    calls = []
    real = build.CompiledFunction.call

    def counted(self):
        calls.append(self.name)
        return real(self)

    monkeypatch.setattr(build.CompiledFunction, "call", counted)
    plant = econ_plant(econ_truth.theta_all)
    plant.reset(dict(zip(("T_cab", "T_int", "T_shell", "T_evap", "w_cab"), X, strict=True)))
    for k in range(5):
        m = plant.measure()
        x = [m[n] for n in ("T_cab", "T_int", "T_shell", "T_evap", "w_cab")]
        n0 = len(calls)
        u = fused.make_step(x, 12.0 + k, C2K(30.0))
        assert calls[n0:] == ["acid_econ_nmpc_step"]
        np.testing.assert_allclose(u, ref.make_step(x, 12.0 + k, C2K(30.0)), rtol=1e-12)
        plant.step(u[0], u[1], 12.0 + k, T_amb=C2K(30.0))
    assert fused.fallbacks == 0 and fused.backend == "compiled"
