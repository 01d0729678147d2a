"""One generated C call per step of the paper NMPC (acid.control.codegen.solver.StepSolver)."""

from __future__ import annotations

import numpy as np
import pytest

from acid.control.codegen import build
from acid.control.codegen.solver import NLPSolver
from acid.control.nmpc import NMPC, NMPCConfig
from acid.models.params import paper
from acid.units import C2K


def _closed_loop(mpc, steps=8):
    """First moves and objectives of a short closed loop on the model, bound steps in it."""
    x = np.array([C2K(30.0), C2K(9.0)])
    moves, objs = [], []
    for k in range(steps):
        ub = np.full(mpc.N + 1, C2K(25.0 - 0.4 * min(k, 4)))
        mpc.make_step(x, ub, C2K(30.0), C2K(33.0))
        sol = mpc.log.solutions[-1]
        moves.append(sol.u)
        objs.append(sol.objective)
        x = np.array([sol.T_cab[1], sol.T_evap[1]])
    return np.array(moves), np.array(objs)


@pytest.fixture(scope="module")
def fused():
    mpc = NMPC(paper())
    if mpc._step is None:
        pytest.skip("no working C compiler")
    return mpc


def test_a_step_is_exactly_one_c_call(fused, monkeypatch):
    calls = []
    real = build.CompiledFunction.call

    def counted(self):
        calls.append(self.name)
        return real(self)

    monkeypatch.setattr(build.CompiledFunction, "call", counted)
    fused.reset()
    _closed_loop(fused, 6)   # a cold start, then warm starts
    assert calls == ["acid_nmpc_step"] * 6
    assert fused.solver_fallbacks == 0 and fused.backend == "compiled"


def test_the_fused_step_moves_as_the_separate_calls(fused):
    sep = NMPC(paper())
    sep._step = None   # solver, convergence check and trajectory as separate C calls
    sep._nlp = NLPSolver("acid_nmpc", sep._ocp.nlp, *sep._solver_options("sqp"),
                         compiled=True, verify=(1e-8, 1e-8))
    fused.reset()
    u_f, f_f = _closed_loop(fused)
    u_s, f_s = _closed_loop(sep)
    assert sep._nlp.backend == "compiled"
    np.testing.assert_allclose(u_f, u_s, rtol=1e-12, atol=0)
    np.testing.assert_allclose(f_f, f_s, rtol=1e-12, atol=0)
    sol = fused.log.solutions[-1]
    # the warm start is the carried buffer of the last solution, not a copy
    assert fused._w_prev is fused._step.inputs["w_prev"]
    assert sol.T_cab.shape == (fused.N + 1,) and sol.slack_cab.shape == (fused.N,)


def test_a_capped_fused_step_runs_in_the_worker_with_the_same_moves(fused):
    capped = NMPC(paper(), NMPCConfig(max_solve_s=30.0))
    assert capped._step is not None and capped._step.timeout_s == 30.0
    fused.reset()
    u_f, _ = _closed_loop(fused, 4)
    u_c, _ = _closed_loop(capped, 4)
    assert capped._step._worker is not None
    np.testing.assert_array_equal(u_f, u_c)


def test_a_fused_step_past_its_cap_is_abandoned_and_reloaded(fused, monkeypatch):
    import warnings

    from test_control_solver import _LateCall

    from acid.control.codegen import solver as solver_mod
    from acid.errors import SolverWarning

    capped = NMPC(paper(), NMPCConfig(max_solve_s=1e-3))
    first = capped._step._cf
    x, ub = [C2K(27.0), C2K(6.0)], C2K(25.0)
    with monkeypatch.context() as m:
        m.setattr(solver_mod, "_Call", _LateCall)
        with pytest.warns(SolverWarning, match="timeout"):
            u = capped.make_step(x, ub, C2K(30.0), C2K(33.0))
    np.testing.assert_array_equal(u, capped.config.u_safe)
    assert capped._step.timeouts == 1 and capped._step._cf is not first   # reloaded
    # from its own copy of the library: the abandoned call shares no static memory with it
    assert capped._step._cf._lib._handle != first._lib._handle
    capped._step.timeout_s = None
    fused.reset()
    with warnings.catch_warnings():
        warnings.simplefilter("error", SolverWarning)
        np.testing.assert_array_equal(capped.make_step(x, ub, C2K(30.0), C2K(33.0)),
                                      fused.make_step(x, ub, C2K(30.0), C2K(33.0)))


def test_parameters_written_into_the_call_match_the_full_vector(fused):
    """The step writes its parameters straight into the call's buffer and keeps the blocks
    that did not change (the default lower bound, stage parameters): after any sequence of
    previews, stage parameters, disturbances and a rejected input, the buffer is the
    parameter vector the separate solver builds, and the moves are the same."""
    from acid.errors import DataError

    ref = NMPC(paper(), NMPCConfig(compiled=False))
    fused.reset()
    x = np.array([C2K(28.0), C2K(8.0)])
    ub = np.full(fused.N + 1, C2K(25.0))
    calls = [{}, {"T_cab_min": C2K(19.0)}, {}, {"T_amb": C2K(38.0)},
             {"eta_cop": np.linspace(3.0, 3.6, fused.N + 1)}, {},
             {"disturbance": [0.05, -0.02]}, {"T_cab_min": np.full(fused.N + 1, C2K(20.5))},
             {"T_amb": float("nan")}, {}, {"disturbance": [0.0, 0.0]}, {}]
    for kw in calls:
        if kw.get("T_amb") is not None and not np.isfinite(kw["T_amb"]):
            with pytest.raises(DataError, match="T_amb"):
                fused.solve(x, ub, C2K(30.0), C2K(33.0), **kw)
            continue
        a = fused.solve(x, ub, C2K(30.0), C2K(33.0), **kw)
        b = ref.solve(x, ub, C2K(30.0), C2K(33.0), **kw)
        assert np.array_equal(fused._step.inputs["p"], ref._pvec), kw
        assert a.success and b.success
        assert np.allclose(a.u, b.u, rtol=1e-7, atol=1e-9), kw
        assert a.objective == pytest.approx(b.objective, rel=1e-8)
        x = np.array([a.T_cab[1], a.T_evap[1]])
    with pytest.raises(DataError, match="disturbance"):
        fused.solve(x, ub, C2K(30.0), C2K(33.0), disturbance=[0.1, 0.2, 0.3])
