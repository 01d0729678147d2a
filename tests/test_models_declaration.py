"""acid.models: declarations traced into CasADi Functions; one-line declaration errors; the
built-in declarations step exactly as the hand-written models."""

from __future__ import annotations

import textwrap

import numpy as np
import pytest

from acid.models import DeclarationError, Model, Parameter, Signal, State, load
from acid.models.params import paper

HEADER = "from acid.models import Model, Parameter, Signal, State, RK4\n"


def _file(tmp_path, body: str, name: str = "my_model.py"):
    path = tmp_path / name
    path.write_text(HEADER + textwrap.dedent(body))
    return path


GOOD = """
def step(s):
    return {"T": s.T + s.a * (s.T_amb - s.T) + s.b * s.W}

model = Model("toy", states=[State("T", "K")], inputs=[Signal("W", "kg/s")],
              disturbances=[Signal("T_amb", "K")],
              parameters=[Parameter("a", "1", 0.1, 0.0, 1.0), Parameter("b", "K s/kg", 2.0)],
              Ts=5.0, step=step)
"""


def _error(tmp_path, body):
    with pytest.raises(DeclarationError) as exc:
        load(_file(tmp_path, body))
    text = str(exc.value)
    assert "\n" not in text and text.startswith("my_model.py")
    return text


def test_a_good_file_loads_and_steps(tmp_path):
    m = load(_file(tmp_path, GOOD))
    x, _ = m.step([300.0], [0.1], [310.0])
    assert x[0] == pytest.approx(300.0 + 0.1 * 10.0 + 2.0 * 0.1)


def test_unknown_name_names_file_line_and_name(tmp_path):
    text = _error(tmp_path, GOOD.replace("s.T_amb - s.T)", "s.T_ambient - s.T)"))
    assert "'T_ambient'" in text and "my_model.py:4" in text and "unknown name" in text


def test_python_if_on_a_symbol(tmp_path):
    body = GOOD.replace('    return {"T"', '    if s.T > 300:\n        pass\n    return {"T"')
    text = _error(tmp_path, body)
    assert "my_model.py:4" in text and "if" in text and "if_else" in text


def test_state_without_equation(tmp_path):
    body = GOOD.replace('states=[State("T", "K")]', 'states=[State("T", "K"), State("U", "K")]')
    assert "state 'U' has no equation" in _error(tmp_path, body)


def test_equation_for_undeclared_state(tmp_path):
    body = GOOD.replace('"T": s.T +', '"T": s.T, "Q": s.T +')
    text = _error(tmp_path, body)
    assert "'Q'" in text and "not declared" in text


def test_unit_that_cannot_be_parsed(tmp_path):
    text = _error(tmp_path, GOOD.replace('"K s/kg"', '"K s/furlong"'))
    assert "'b'" in text and "furlong" in text


def test_temperature_signal_in_degC_is_refused(tmp_path):
    text = _error(tmp_path, GOOD.replace('Signal("T_amb", "K")', 'Signal("T_amb", "degC")'))
    assert "'T_amb'" in text and "kelvin" in text


def test_latent_state_needs_an_initial_rule(tmp_path):
    body = GOOD.replace('State("T", "K")', 'State("T", "K", measured=False)')
    assert "latent state 'T' needs initial=" in _error(tmp_path, body)


def test_value_outside_its_bounds(tmp_path):
    text = _error(tmp_path, GOOD.replace('Parameter("a", "1", 0.1,', 'Parameter("a", "1", 2.0,'))
    assert "'a'" in text and "[min, max]" in text


def test_file_without_a_model(tmp_path):
    with pytest.raises(DeclarationError, match="defines no model"):
        load(_file(tmp_path, "x = 1\n"))


def test_ode_with_rk4_integrates_the_declared_derivative():
    def ode(s):
        return {"x": -s.k * s.x}

    m = Model("decay", states=[State("x", "1")], parameters=[Parameter("k", "1/s", 0.1)],
              Ts=1.0, ode=ode, source="decay.py")
    from acid.models import RK4  # noqa: F401 - default RK4(1)
    x, _ = m.step([1.0], [], [])
    h = -0.1
    rk4 = 1 + h + h**2 / 2 + h**3 / 6 + h**4 / 24
    assert x[0] == pytest.approx(rk4, rel=1e-14)


def test_paper_declaration_steps_as_the_papers_equations(rng):
    """The declaration against eqs. 1-3 and 5 transcribed here from the paper (eq. 3's T_ain
    substituted in eq. 1)."""
    m = load("paper")
    n = 200
    x = np.c_[rng.uniform(285, 320, n), rng.uniform(270, 290, n)]
    u = np.c_[rng.uniform(0.03, 0.2, n), rng.uniform(273, 288, n)]
    d = np.c_[rng.uniform(285, 330, n), rng.uniform(285, 340, n)]
    xn, y = m.step(x, u, d)
    p = paper()
    g1, g2, g3, g4, g5, g6, g7 = p.gamma
    t1, t2, t3 = p.tau
    b1, b2, b3 = p.beta
    T_cab, T_evap = x.T
    W_bl, T_evap_set = u.T
    T_int, T_shell = d.T
    ain = g6 * T_evap + g7 * W_bl + t3                                            # eq. 3
    cab = (T_cab + g1 * (T_int - T_cab) + g2 * (T_shell - T_cab)
           + g3 * (ain - T_cab) * W_bl + t1)                                      # eq. 1
    evap = g4 * T_evap + g5 * (T_evap - T_evap_set) + t2                          # eq. 2
    np.testing.assert_allclose(xn[:, 0], cab, rtol=0, atol=1e-12 * 300)
    np.testing.assert_allclose(xn[:, 1], evap, rtol=0, atol=1e-12 * 300)
    np.testing.assert_allclose(y[:, 0], ain, rtol=1e-12)
    np.testing.assert_allclose(y[:, 1], b1 * W_bl**2 + b2 * W_bl + b3, rtol=1e-12)  # eq. 5
    assert m.parameter_names == tuple(p.as_dict())


def test_simulate_matches_repeated_steps(rng):
    m = load("cabin3")
    H = 20
    u = np.c_[rng.uniform(0.05, 0.15, H), rng.uniform(275, 283, H)]
    d = rng.uniform(300, 310, (H, 1))
    X, Y = m.simulate(np.array([300.0, 305.0, 280.0]), u, d)
    x = np.array([300.0, 305.0, 280.0])
    for k in range(H):
        x_next, y = m.step(x, u[k], d[k])
        np.testing.assert_allclose(Y[k], y, rtol=1e-14)
        x = x_next
    np.testing.assert_allclose(X[-1], x, rtol=1e-14)


def test_fix_and_free_change_the_table():
    m = load("cabin3").with_parameters({"C_cab": 12.0}, ("Q_sol",))
    assert m.parameter("C_cab").fixed and m.parameter("C_cab").value == 12.0
    with pytest.raises(DeclarationError, match="outside the declared bounds"):
        load("cabin3").with_parameters({"C_cab": 1e6})
    with pytest.raises(DeclarationError, match="unknown parameter 'nope'"):
        load("cabin3").with_parameters({"nope": 1.0})


def test_signal_declared_twice():
    with pytest.raises(DeclarationError, match="declared twice"):
        Model("x", states=[State("T", "K")], inputs=[Signal("T", "K")], parameters=[],
              Ts=1.0, step=lambda s: {"T": s.T}, source="x.py")


def test_next_state_is_for_interval_outputs_only():
    kw = dict(states=[State("T", "K")], inputs=[Signal("W", "kg/s")],
              outputs=[Signal("P", "W")], parameters=[Parameter("a", "1", 0.5)], Ts=1.0,
              source="nx.py")
    m = Model("nx", step=lambda s: {"T": s.a * s.T + s.W, "P": s.next.T - s.T}, **kw)
    x_next, y = m.step([2.0], [1.0], [])
    assert x_next[0] == 2.0 and y[0] == 0.0          # simulated: the step's own end state
    assert set(m.equations_next) == {"P"}
    with pytest.raises(DeclarationError, match="only a step's interval outputs may read s.next"):
        Model("nx", step=lambda s: {"T": s.next.T, "P": s.T}, **kw)
    with pytest.raises(DeclarationError, match="only a step's interval outputs"):
        Model("nx", step=lambda s: {"T": s.T}, output=lambda s: {"P": s.next.T}, **kw)


@pytest.mark.parametrize(("what", "value"), [("sensor", -0.1), ("sensor", 0.0),
                                             ("noise", float("nan")),
                                             ("spread", float("inf")), ("noise", 1e300),
                                             ("spread", "C_cab"), ("sensor", True)])
def test_a_noise_spread_or_sensor_that_is_no_standard_deviation_is_named(what, value):
    """Negative, NaN, infinite or absurd filter noises are refused at the declaration, naming
    the state and the field (they reached PEM as a LinAlgError before)."""
    from acid.models import DeclarationError, Model, Parameter, Signal, State

    with pytest.raises(DeclarationError, match=rf"state 'x': {what} must be"):
        Model("m", states=[State("x", "K", **{what: value})], inputs=[Signal("u", "W")],
              parameters=[Parameter("a", "1", 1.0)], Ts=1.0,
              step=lambda s: {"x": s.x + s.a * s.u})


@pytest.mark.parametrize(("body", "said"), [
    ("import sys\nsys.exit(0)\n", "calls sys.exit(0) while acid imports it"),
    ("import sys\ndef model():\n    sys.exit(3)\n", "calls sys.exit(3) in model()"),
    ("def model():\n    raise RuntimeError('boom')\n", ":2: RuntimeError: boom (in model())"),
    ("raise KeyboardInterrupt\n", "raises KeyboardInterrupt while acid imports it"),
    ("def model():\n    raise KeyboardInterrupt\n", "raises KeyboardInterrupt in model()"),
])
def test_a_model_file_that_exits_raises_or_interrupts_is_one_line_naming_it(tmp_path, body,
                                                                            said):
    """sys.exit in a model file ended acid with exit 0 having done nothing; an exception in
    model() was an internal error; a KeyboardInterrupt the file raises looked like Ctrl-C."""
    from acid.models import DeclarationError, load

    f = tmp_path / "bad_model.py"
    f.write_text(body)
    with pytest.raises(DeclarationError) as err:
        load(f)
    assert str(err.value).startswith("bad_model.py") and said in str(err.value)
