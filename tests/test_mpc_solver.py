"""The NLP solver wrapper: a wall-clock cap per solve, never a hang."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from acid.errors import SolverWarning
from acid.mpc.nmpc import NMPC, NMPCConfig
from acid.mpc.solver import NLPSolver
from acid.params import paper
from acid.units import C2K


def _nlp():
    x = ca.SX.sym("x", 2)
    return {"x": x, "f": (x[0] - 1) ** 2 + (x[1] + 2) ** 2, "g": x[0] + x[1]}


def test_a_solve_past_its_cap_is_abandoned_and_reported_then_the_next_one_works():
    s = NLPSolver("acid_cap", _nlp(), "ipopt", {"print_time": False,
                                                "ipopt": {"print_level": 0, "sb": "yes"}},
                  timeout_s=1e-9)
    res = s.solve(np.zeros(2), [], -np.inf, np.inf, -10.0, 10.0)
    assert not res.success and res.status == "timeout" and s.timeouts == 1
    assert np.all(np.isnan(res.x))
    s.timeout_s = 30.0
    res = s.solve(np.zeros(2), [], -np.inf, np.inf, -10.0, 10.0)
    assert res.success
    np.testing.assert_allclose(res.x, [1.0, -2.0], atol=1e-6)


def test_nmpc_falls_back_when_its_solve_times_out():
    mpc = NMPC(paper(), NMPCConfig(max_solve_s=1e-9))
    with pytest.warns(SolverWarning, match="timeout"):
        u = mpc.make_step([C2K(27.0), C2K(6.0)], C2K(25.0), C2K(30.0), C2K(33.0))
    np.testing.assert_array_equal(u, mpc.config.u_safe)
    assert mpc.fallbacks == 1 and mpc._nlp.timeouts == 1


def test_solver_without_a_cap_runs_in_the_callers_thread():
    s = NLPSolver("acid_nocap", _nlp(), "ipopt", {"print_time": False,
                                                  "ipopt": {"print_level": 0, "sb": "yes"}},
                  timeout_s=None)
    res = s.solve(np.zeros(2), [], -np.inf, np.inf, -10.0, 10.0)
    assert res.success and s._worker is None
