"""acid.control.ocp: the one optimal-control builder over a declared model.

The paper NMPC is a configuration of it; its first moves must reproduce those recorded
from the hand-written builder it replaced (``tests/references/ocp_first_moves.json``,
recorded by ``tests/references/record_ocp_first_moves.py`` before the change).
"""

from __future__ import annotations

import json
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from acid.control.nmpc import NMPC, NMPCConfig
from acid.control.ocp import OCP, OCPSpec, SoftBound, disturbed_dynamics, tracking_cost
from acid.errors import ConfigError
from acid.models.paper import model as paper_model
from acid.models.params import paper

REFS = json.loads((Path(__file__).parent / "references" / "ocp_first_moves.json").read_text())


@pytest.mark.parametrize("variant", sorted({r["variant"] for r in REFS["paper"]}))
def test_paper_nmpc_reproduces_the_first_moves_of_the_builder_it_replaced(variant):
    rows = [r for r in REFS["paper"] if r["variant"] == variant]
    mpc = NMPC(paper(), NMPCConfig(compiled=False, **rows[0]["config"]))
    for r in rows:
        sol = mpc.solve(np.array(r["x"]), np.array(r["T_cab_max"]), r["T_int"], r["T_shell"],
                        **{k: np.asarray(v) for k, v in r["solve"].items()})
        assert sol.success, sol.status
        scale = np.array([0.15, 300.0])
        assert np.max(np.abs(sol.u - r["u"]) / scale) < 1e-6, (variant, sol.u, r["u"])
        assert sol.objective == pytest.approx(r["objective"], rel=1e-6)


def test_an_output_disturbance_acts_where_the_step_reads_the_output():
    # paper eq. 1 reads T_ain: a disturbance on T_ain moves the cabin by gamma3 W_bl d
    F = disturbed_dynamics(paper_model, ("T_ain",))
    theta = paper_model.values
    x, u, v = [300.0, 280.0], [0.1, 278.0], [305.0, 310.0]
    base, y0 = (np.asarray(a).ravel() for a in paper_model.F(x, u, v, theta))
    moved, y1 = (np.asarray(a).ravel() for a in F(x, u, v, theta, 0.5))
    g3 = theta[paper_model.parameter_names.index("gamma3")]
    assert moved[0] - base[0] == pytest.approx(g3 * 0.1 * 0.5, rel=1e-12)
    assert moved[1] == base[1]
    assert y1[0] - y0[0] == pytest.approx(0.5) and y1[1] == y0[1]


def test_a_tracking_cost_reaches_a_reachable_reference_in_one_step():
    # eq. 2, x+ = g4 x + g5 (x - u) + tau2: the set-point that puts T_evap on 279 K at once
    cost, refs = tracking_cost({"T_evap": 1.0})
    spec = OCPSpec(N=3, stage_cost=cost, stage_parameters=refs,
                   input_bounds={"W_bl": (0.05, 0.15), "T_evap_set": (270.0, 290.0)})
    ocp = OCP(paper_model, spec)
    theta = ocp.theta()
    x0 = np.array([300.0, 283.0])
    p = ocp.parameters(np.zeros(ocp.par.size), x0=x0, theta=theta,
                       d=np.tile([305.0, 310.0], (3, 1)), q=np.full((3, 1), 279.0))
    res = ca.nlpsol("t", "ipopt", ocp.nlp, {"print_time": False, "ipopt.print_level": 0,
                                            "ipopt.sb": "yes", "ipopt.tol": 1e-12})(
        x0=np.zeros(ocp.w.size), p=p, lbx=ocp.lbx, ubx=ocp.ubx, lbg=ocp.lbg, ubg=ocp.ubg)
    w = np.asarray(res["x"]).ravel()
    g = dict(zip(paper_model.parameter_names, theta, strict=True))
    x1 = 279.0  # stage 0 costs (x0 - ref)^2 whatever u; stage 1 costs (x1 - ref)^2
    u0 = (x1 - g["gamma4"] * x0[1] - g["gamma5"] * x0[1] - g["tau2"]) / -g["gamma5"]
    assert ocp.plan(w)[0, 1] == pytest.approx(u0, abs=1e-6)
    assert ocp.states(w)[1, 1] == pytest.approx(x1, abs=1e-8)


def test_unknown_names_and_missing_bounds_are_one_line_errors():
    cost, refs = tracking_cost({"T_nowhere": 1.0})
    bounds = {"W_bl": (0.05, 0.15), "T_evap_set": (270.0, 290.0)}
    with pytest.raises(ConfigError, match="T_nowhere"):
        OCP(paper_model, OCPSpec(N=2, stage_cost=cost, stage_parameters=refs,
                                 input_bounds=bounds))
    with pytest.raises(ConfigError, match="T_evap_set"):
        OCP(paper_model, OCPSpec(N=2, stage_cost=tracking_cost({"T_cab": 1.0})[0],
                                 stage_parameters=("ref_T_cab",),
                                 input_bounds={"W_bl": (0.05, 0.15)}))
    with pytest.raises(ConfigError, match="T_dash"):
        OCP(paper_model, OCPSpec(N=2, stage_cost=tracking_cost({"T_cab": 1.0})[0],
                                 stage_parameters=("ref_T_cab",), input_bounds=bounds,
                                 soft_bounds=(SoftBound("T_dash", upper=300.0),)))
    with pytest.raises(ConfigError, match="gamma99"):
        OCP(paper_model, OCPSpec(N=2, stage_cost=tracking_cost({"T_cab": 1.0})[0],
                                 stage_parameters=("ref_T_cab",),
                                 input_bounds=bounds)).theta({"gamma99": 1.0})


@pytest.mark.parametrize("stage_functions", [False, True], ids=["inlined", "stage-functions"])
@pytest.mark.parametrize("terminal", ["steady", "heat", "none"])
def test_econ_nmpc_reproduces_the_first_moves_of_the_builder_it_replaced(econ_truth, terminal,
                                                                         stage_functions):
    import warnings

    from acid.control.econ.nmpc import EconNMPC, EconNMPCConfig

    rows = [r for r in REFS["econ"] if r["terminal"] == terminal]
    cfg = EconNMPCConfig(intervals=tuple(rows[0]["intervals"]), T_cab_min=rows[0]["T_cab_min"],
                         T_cab_max=rows[0]["T_cab_max"], compiled=False, terminal=terminal,
                         solver="ipopt", tol=1e-10, stage_functions=stage_functions)
    for r in rows:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sol = EconNMPC(econ_truth, cfg).solve(np.array(r["x"]), r["v_veh"], r["T_amb"])
        assert sol.success, sol.status
        scale = np.array([0.15, 300.0])
        assert np.max(np.abs(sol.u - r["u"]) / scale) < 1e-6, (terminal, sol.u, r["u"])
        assert sol.objective == pytest.approx(r["objective"], rel=1e-6)
        assert sol.energy_J == pytest.approx(r["energy_J"], rel=1e-6)


def test_the_steady_state_problem_is_the_models_fixed_point():
    # tracking T_evap = 279 K at rest: eq. 2's fixed point gives the set-point in closed form
    cost, refs = tracking_cost({"T_evap": 1.0})
    ocp = OCP(paper_model, OCPSpec(N=2, stage_cost=cost, stage_parameters=refs,
                                   input_bounds={"W_bl": (0.05, 0.15),
                                                 "T_evap_set": (260.0, 300.0)}))
    nlp = ocp.steady_state_nlp()
    res = ca.nlpsol("ss", "ipopt", nlp, {"print_time": False, "ipopt.print_level": 0,
                                         "ipopt.sb": "yes", "ipopt.tol": 1e-12})(
        x0=np.r_[300.0, 280.0, 0.1, 280.0], p=np.r_[305.0, 310.0, ocp.theta(), 279.0],
        lbx=np.r_[-np.inf, -np.inf, ocp.u_nlp(ocp.u_min)],
        ubx=np.r_[np.inf, np.inf, ocp.u_nlp(ocp.u_max)], lbg=0.0, ubg=0.0)
    z = np.asarray(res["x"]).ravel()
    g = dict(zip(paper_model.parameter_names, ocp.theta(), strict=True))
    u_set = (279.0 * (1 - g["gamma4"] - g["gamma5"]) - g["tau2"]) / -g["gamma5"]
    assert z[1] == pytest.approx(279.0, abs=1e-8)
    assert ocp.u_offset[1] + z[3] / ocp.u_scale[1] == pytest.approx(u_set, abs=1e-6)
    x_next = np.asarray(paper_model.F(z[:2], [z[2], z[3]], [305.0, 310.0],
                                      ocp.theta())[0]).ravel()
    np.testing.assert_allclose(x_next, z[:2], atol=1e-8)


def test_the_trajectory_as_generated_c_equals_casadis():
    from acid.control.codegen.build import find_compiler

    if find_compiler() is None:
        pytest.skip("no C compiler")
    mpc = NMPC(paper(), NMPCConfig(compiled=False))
    ocp = mpc._ocp
    args = (np.array([300.0, 280.0]), np.array([[0.1] * 6, np.linspace(277, 283, 6)]),
            np.full((2, 6), 305.0), np.tile([[303.15], [3.5], [1008.0]], (1, 7)), mpc._theta,
            np.array([0.02, -0.01]))
    fast, slow = ocp.trajectory_evaluator("auto"), ocp.trajectory_evaluator(False)
    for a, b in zip(fast(*args), slow(*args), strict=True):
        assert a.shape == b.shape
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-9)


def test_stage_functions_are_differentiated_only_by_the_decision_variables(econ_truth):
    """The stage function leaves its parameters out of its derivatives (``is_diff_in``):
    the NLP's constraint Jacobian and Lagrangian Hessian must still equal those of the
    inlined form (CasADi SX, which knows nothing of it) at a point on the model's
    trajectory; and no derivative is taken by a parameter."""
    from acid.control.econ.nmpc import EconNMPC, EconNMPCConfig, ocp_spec
    from acid.models.econ import model as econ_model

    cfg = EconNMPCConfig(compiled=False, solver="ipopt", comfort_weight=30.0)
    mpc = EconNMPC(econ_truth, cfg)
    x0 = np.array([299.0, 301.0, 306.0, 281.0, 0.009])
    v, Ta = np.linspace(5.0, 15.0, cfg.N), np.full(cfg.N, 306.0)
    w = mpc._scaled_guess(x0, v, Ta, np.zeros(5), cfg.u_safe)
    lam = np.full(5, 0.3)
    p = mpc._ocp.parameters(mpc._pvec.copy(), x0=x0, dist=np.zeros(5),
                            d=np.column_stack((v, Ta)), lam=lam,
                            q=np.full((cfg.N, 1), 297.15),
                            bounds={("T_cab", "hi"): np.full(cfg.N, cfg.T_cab_max),
                                    ("T_cab", "lo"): np.full(cfg.N, cfg.T_cab_min)})
    rng = np.random.default_rng(3)
    derivatives = {}
    for stage_functions in (True, False):
        nlp = OCP(econ_model, ocp_spec(cfg.replace(stage_functions=stage_functions))).nlp
        assert nlp["p"].shape[0] == p.size
        lam_g = rng.standard_normal(nlp["g"].shape[0])
        rng = np.random.default_rng(3)   # the same multipliers for both forms
        L = nlp["f"] + ca.dot(ca.DM(lam_g), nlp["g"])
        H = ca.Function("H", [nlp["x"], nlp["p"]], [ca.hessian(L, nlp["x"])[0]])
        J = ca.Function("J", [nlp["x"], nlp["p"]], [ca.jacobian(nlp["g"], nlp["x"])])
        derivatives[stage_functions] = [np.asarray(ca.densify(F(w, p))) for F in (H, J)]
        assert np.all(np.isfinite(derivatives[stage_functions][0]))
    for a, b in zip(derivatives[True], derivatives[False], strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9 * np.abs(b).max())
    F = mpc._ocp._stage_function(cfg.intervals[0], False)
    # inputs: x, u, s, d, theta, dist, q, qN, lim, xn
    assert [F.is_diff_in(i) for i in range(F.n_in())] == [True] * 3 + [False] * 6 + [True]
