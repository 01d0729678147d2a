"""The NLP solver wrapper: no cap by default; a wall-clock cap on request, never a hang."""

from __future__ import annotations

import dataclasses
import threading

import casadi as ca
import numpy as np
import pytest

from acid.control.codegen import solver as solver_mod
from acid.control.codegen.solver import NLPSolver, _Worker
from acid.control.econ.nmpc import EconNMPCConfig
from acid.control.nmpc import NMPC, NMPCConfig
from acid.errors import SolverWarning
from acid.models.params import paper
from acid.units import C2K

IPOPT = {"print_time": False, "ipopt": {"print_level": 0, "sb": "yes"}}
SQP = {"qpsol": "qrqp", "print_time": False, "print_header": False, "print_iteration": False,
       "print_status": False, "qpsol_options": {"print_iter": False, "print_header": False,
                                                "print_info": False, "error_on_fail": False}}


def _nlp():
    x = ca.SX.sym("x", 2)
    return {"x": x, "f": (x[0] - 1) ** 2 + (x[1] + 2) ** 2, "g": x[0] + x[1]}


def _solve(s):
    return s.solve(np.zeros(2), [], -np.inf, np.inf, -10.0, 10.0)


class _HeldWorker(_Worker):
    """A worker whose thread waits on ``gate`` before it takes its first job: a solve that
    times out then does so before the thread has started, deterministically."""

    gate = threading.Event()

    def _loop(self):
        self.gate.wait()
        super()._loop()


def test_no_cap_by_default_anywhere():
    assert NMPCConfig().max_solve_s is None and EconNMPCConfig().max_solve_s is None
    s = NLPSolver("acid_nocap", _nlp(), "ipopt", IPOPT)
    assert s.timeout_s is None
    res = _solve(s)
    assert res.success and s._worker is None  # solved in the caller's thread


def test_a_solve_that_times_out_before_the_worker_starts_is_a_clean_timeout(monkeypatch):
    """The race of issue 22: the cap expires before the worker thread takes the job. It used
    to raise ``RuntimeError: release unlocked lock`` from the stop path."""
    gate = threading.Event()
    monkeypatch.setattr(_HeldWorker, "gate", gate)
    monkeypatch.setattr(solver_mod, "_Worker", _HeldWorker)
    s = NLPSolver("acid_race", _nlp(), "ipopt", IPOPT, timeout_s=1e-3)
    res = _solve(s)  # the thread is held: this times out before the job starts
    assert not res.success and res.status == "timeout" and s.timeouts == 1
    assert np.all(np.isnan(res.x))
    worker = s._worker
    assert worker is not None  # a cancelled job leaves the worker usable
    s.timeout_s = 1e-3
    res = _solve(s)  # again, while the thread is still held
    assert res.status == "timeout" and s.timeouts == 2
    s.close()  # stopping a worker whose thread never ran must not raise either
    gate.set()
    worker.thread.join(30)
    assert not worker.thread.is_alive()


def test_a_cancelled_job_never_runs_and_the_next_one_does():
    gate = threading.Event()
    w = _HeldWorker.__new__(_HeldWorker)
    w.gate = gate
    _Worker.__init__(w, "held")
    ran = []
    finished, started, _, _ = w.run(lambda: ran.append("first"), 1e-3)
    assert (finished, started) == (False, False)
    gate.set()
    finished, started, out, exc = w.run(lambda: ran.append("second") or 7, None)
    assert (finished, started, out, exc) == (True, True, 7, None)
    assert ran == ["second"]
    w.stop()
    w.stop()  # twice is harmless
    w.thread.join(30)
    assert not w.thread.is_alive()


class _LateCall(solver_mod._Call):
    """A job whose caller gives up only once the worker has started it: the timeout of a
    running solve, deterministically (the wait returns "not done" as soon as it started)."""

    def __init__(self, job):
        super().__init__(job)
        call, done = self, self.done

        class _Late(threading.Event):
            def wait(self, timeout=None):
                while True:  # until the worker has taken the job (no verdict on time)
                    with call.lock:
                        if call.started:   # the caller gives up now, even if a fast solve
                            return False   # has already finished (a busy machine)
                    threading.Event().wait(0.001)

        self.done = _Late()
        # the caller asks is_set only once it gave up: "not done" even when a fast solve on
        # a busy machine finished in between (the verdict never depends on scheduling)
        self.done.set, self.done.is_set = done.set, lambda: False


def test_a_running_job_past_its_cap_is_abandoned(monkeypatch):
    monkeypatch.setattr(solver_mod, "_Call", _LateCall)
    release = threading.Event()
    w = _Worker("busy")
    finished, started, _, _ = w.run(release.wait, 1e-3)  # blocks until released
    assert not finished and started
    release.set()
    w.stop()
    w.thread.join(30)
    assert not w.thread.is_alive()


def test_a_running_solve_past_its_cap_is_abandoned_and_the_solver_rebuilt(monkeypatch):
    s = NLPSolver("acid_late", _nlp(), "ipopt", IPOPT, timeout_s=1e-3)
    first = s._fn
    with monkeypatch.context() as m:
        m.setattr(solver_mod, "_Call", _LateCall)
        res = _solve(s)
    assert not res.success and res.status == "timeout" and s.timeouts == 1
    assert s._worker is None and s._fn is not first  # abandoned, rebuilt
    s.timeout_s = None
    res = _solve(s)
    assert res.success
    np.testing.assert_allclose(res.x, [1.0, -2.0], atol=1e-6)


def test_an_exception_in_the_job_reaches_the_caller():
    w = _Worker("raises")
    finished, started, out, exc = w.run(lambda: 1 / 0, None)
    assert finished and started and isinstance(exc, ZeroDivisionError)
    w.stop()


def test_nmpc_falls_back_when_its_solve_times_out(monkeypatch):
    gate = threading.Event()
    monkeypatch.setattr(_HeldWorker, "gate", gate)
    monkeypatch.setattr(solver_mod, "_Worker", _HeldWorker)
    mpc = NMPC(paper(), NMPCConfig(max_solve_s=1e-3, compiled=False))
    with pytest.warns(SolverWarning, match="timeout"):
        u = mpc.make_step([C2K(27.0), C2K(6.0)], C2K(25.0), C2K(30.0), C2K(33.0))
    np.testing.assert_array_equal(u, mpc.config.u_safe)
    assert mpc.fallbacks == 1 and mpc._nlp.timeouts == 1
    gate.set()
    # a cap is only a run's choice: the same controller uncapped solves the same state
    plain = NMPC(paper(), dataclasses.replace(mpc.config, max_solve_s=None))
    assert plain.solve([C2K(27.0), C2K(6.0)], C2K(25.0), C2K(30.0), C2K(33.0)).success


# --------------------------------------------- the paper NMPC: warm-started SQP, fatrop after
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


def test_the_default_is_warm_started_sqp_with_fatrops_optimum():
    sqp = NMPC(paper())
    fatrop = NMPC(paper(), NMPCConfig(solver="fatrop"))
    assert sqp.config.solver == "sqp" and sqp._nlp.plugin == "sqpmethod"
    assert sqp._fallback_solver().plugin == "fatrop" and fatrop._fallback_solver() is None
    u_s, f_s = _closed_loop(sqp)
    u_f, f_f = _closed_loop(fatrop)
    assert sqp.solver_fallbacks == 0 and sqp.fallbacks == 0 and fatrop.fallbacks == 0
    assert sqp._w_prev is not None  # warm-started from its previous solution
    np.testing.assert_allclose(u_s, u_f, rtol=1e-6, atol=0)
    np.testing.assert_allclose(f_s, f_f, rtol=1e-6, atol=0)


def _declare_failed(mpc):
    """Make ``mpc``'s SQP report every solve as failed (C return code 1), whichever path
    it takes: the one fused C call per step, or the separate solver."""
    if mpc._step is not None:
        step = mpc._step.step
        mpc._step.step = lambda warm: (step(warm)[0], 1)
        return
    failing = mpc._nlp.solve

    def fail(*args):
        res = failing(*args)
        return dataclasses.replace(res, success=False, status="failed (code 1)")

    mpc._nlp.solve = fail


def test_a_failed_sqp_solve_is_solved_by_fatrop():
    mpc = NMPC(paper())
    ref = NMPC(paper(), NMPCConfig(solver="fatrop"))
    _declare_failed(mpc)
    u_a, _ = _closed_loop(mpc, 3)
    u_b, _ = _closed_loop(ref, 3)
    assert mpc.solver_fallbacks == 3 and mpc.fallbacks == 0
    assert mpc._fallback_nlp.backend == "compiled"
    assert "fatrop after sqp" in mpc.log.solutions[-1].status
    np.testing.assert_allclose(u_a, u_b, rtol=1e-9, atol=0)


def test_without_a_fallback_solver_a_failed_solve_applies_the_safe_input():
    mpc = NMPC(paper(), NMPCConfig(fallback_solver=None))
    assert mpc._fallback_solver() is None
    _declare_failed(mpc)
    with pytest.warns(SolverWarning, match="fallback applied"):
        u = mpc.make_step([C2K(27.0), C2K(6.0)], C2K(25.0), C2K(30.0), C2K(33.0))
    np.testing.assert_array_equal(u, mpc.config.u_safe)


def _rosenbrock():
    x = ca.SX.sym("x", 2)
    return {"x": x, "f": (1 - x[0]) ** 2 + 100 * (x[1] - x[0] ** 2) ** 2, "g": x[0] + x[1]}


@pytest.mark.parametrize("compiled", [True, False])
def test_an_sqp_stopped_at_its_iteration_limit_is_not_a_success(compiled):
    """CasADi's generated sqpmethod returns 0 when it stops at max_iter: the residual check
    catches it, in both backends alike."""
    opts = dict(SQP, max_iter=1, tol_pr=1e-10, tol_du=1e-10)
    s = NLPSolver("acid_sqp_limit", _rosenbrock(), "sqpmethod", opts, compiled=compiled,
                  verify=(1e-8, 1e-8))
    res = s.solve(np.array([-1.2, 1.0]), [], -np.inf, np.inf, -10.0, 10.0)
    assert not res.success
    if s.backend == "compiled":  # the generated code said 0; the check said no
        assert res.status.startswith("not converged")
    s = NLPSolver("acid_sqp_limit", _rosenbrock(), "sqpmethod", dict(opts, max_iter=100),
                  compiled=compiled, verify=(1e-8, 1e-8))
    res = s.solve(np.array([-1.2, 1.0]), [], -np.inf, np.inf, -10.0, 10.0)
    assert res.success
    np.testing.assert_allclose(res.x, [1.0, 1.0], atol=1e-8)
