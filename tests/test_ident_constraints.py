"""Declared affine constraints: checked affine at declaration, imposed by ``--method cvx``,
reported when active; the constrained estimates against independent solves (the KKT system
of the active constraint in numpy, and a plain CVXPY problem)."""

from __future__ import annotations

import cvxpy as cp
import numpy as np
import pytest

from acid.data import Dataset
from acid.ident.fit import fit_model
from acid.models import Constraint, DeclarationError, Model, Parameter, Signal, State, load

TRUE = {"a": 0.9, "b": 0.12, "beta1": 2000.0, "beta2": -400.0, "beta3": 18.0}


def _model(constraints=None) -> Model:
    def step(s):
        return {"T_cab": s.a * s.T_cab + s.b * s.T_amb}

    def output(s):
        return {"P_bl": s.beta1 * s.W_bl**2 + s.beta2 * s.W_bl + s.beta3}

    return Model(
        "gain", states=[State("T_cab", "K")], inputs=[Signal("W_bl", "kg/s")],
        disturbances=[Signal("T_amb", "K")], outputs=[Signal("P_bl", "W")],
        parameters=[Parameter(n, u, v) for n, u, v in (
            ("a", "1", 0.5), ("b", "1", 0.5), ("beta1", "W s^2/kg^2", 0.0),
            ("beta2", "W s/kg", 0.0), ("beta3", "W", 0.0))],
        constraints=constraints if constraints is not None else [
            Constraint(lambda s: s.a + s.b, max=1.0, description="steady gain at most one"),
            Constraint(lambda s: s.beta1 * s.W_bl**2 + s.beta2 * s.W_bl + s.beta3, min=0.0,
                       description="P_bl >= 0 over the measured W_bl range")],
        Ts=5.0, step=step, output=output)


def _record(n: int = 400, seed: int = 3) -> Dataset:
    """The truth (a + b = 1.02; P_bl dips to -2 W at W_bl = 0.1 kg/s) with noise: least
    squares leaves both constraints."""
    rng = np.random.default_rng(seed)
    T_amb = 300.0 + np.cumsum(rng.normal(0.0, 0.3, n))
    W = rng.uniform(0.05, 0.15, n)
    T = np.empty(n)
    T[0] = 300.0
    for k in range(n - 1):
        T[k + 1] = TRUE["a"] * T[k] + TRUE["b"] * T_amb[k] + rng.normal(0.0, 0.05)
    P = TRUE["beta1"] * W**2 + TRUE["beta2"] * W + TRUE["beta3"] + rng.normal(0.0, 0.2, n)
    ch = {"T_cab": T - 273.15, "T_amb": T_amb - 273.15, "W_bl": W, "P_bl": P}
    units = {"T_cab": "degC", "T_amb": "degC", "W_bl": "kg/s", "P_bl": "W"}
    return Dataset(np.arange(n) * 5.0, ch, units, 5.0)


def test_cvx_sits_on_the_declared_constraints_as_the_independent_solves_do():
    m, ds = _model(), _record()
    ls, cvx = fit_model(m, ds, "ls"), fit_model(m, ds, "cvx")
    assert ls.value("a") + ls.value("b") > 1.0 + 1e-3          # least squares leaves it
    T, Ta = ds.get("T_cab", "K"), ds.get("T_amb", "K")
    X, y = np.column_stack([T[:-1], Ta[:-1]]), T[1:]
    # independent: min ||X t - y||^2 s.t. a + b = 1 (the KKT system), a multiplier >= 0
    c = np.array([1.0, 1.0])
    K = np.block([[2 * X.T @ X, c[:, None]], [c[None, :], np.zeros((1, 1))]])
    sol = np.linalg.solve(K, np.r_[2 * X.T @ y, 1.0])
    assert sol[2] > 0        # the multiplier of a + b <= 1 is positive: it is active
    got = np.array([cvx.value("a"), cvx.value("b")])
    np.testing.assert_allclose(got, sol[:2], rtol=1e-6)
    # P_bl >= 0 on 11 points over the measured W_bl range: a plain CVXPY problem
    W, P = ds.get("W_bl", "kg/s"), ds.get("P_bl", "W")
    grid = np.linspace(W.min(), W.max(), 11)
    beta = cp.Variable(3)
    cp.Problem(cp.Minimize(cp.sum_squares(np.column_stack([W**2, W, np.ones_like(W)]) @ beta
                                          - P)),
               [np.column_stack([grid**2, grid, np.ones_like(grid)]) @ beta >= 0]).solve()
    got = np.array([cvx.value(n) for n in ("beta1", "beta2", "beta3")])
    np.testing.assert_allclose(got, beta.value, rtol=1e-4)
    lsP = np.polyval([ls.value("beta1"), ls.value("beta2"), ls.value("beta3")], grid)
    assert lsP.min() < -1.0 and np.polyval(got, grid).min() > -1e-6
    notes = " ".join(cvx.notes)
    assert "steady gain at most one: at its max 1" in notes
    assert "P_bl >= 0 over the measured W_bl range: at its min 0" in notes
    assert "steady gain" not in " ".join(ls.notes)    # least squares imposes nothing


def test_a_constraint_that_is_not_affine_is_a_one_line_declaration_error():
    with pytest.raises(DeclarationError, match=r"test_ident_constraints\.py: model 'gain': "
                                               r"constraint 'a b' is not affine"):
        _model([Constraint(lambda s: s.a * s.b, max=1.0, description="a b")])
    with pytest.raises(DeclarationError, match="reads no parameter"):
        _model([Constraint(lambda s: s.W_bl, max=1.0)])
    with pytest.raises(DeclarationError, match="unknown name 'c'"):
        _model([Constraint(lambda s: s.c, max=1.0)])


def test_the_paper_declares_its_two_constraints():
    m = load("paper")
    labels = {c.description: (c.min, c.max, reads) for c, _, reads in m.constraints}
    assert labels["stable, non-oscillating evaporator pole"] == (0.0, 0.999, ())
    assert labels["P_bl >= 0 over the measured W_bl range"][2] == ("W_bl",)
