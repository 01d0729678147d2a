"""What a loaded model file declares is checked at load: equations that are NaN or inf at the
declared point, and the parameters its states name as a filter's noise or sensor, are one
``DeclarationError`` line naming the file and the state, output or parameter."""

from __future__ import annotations

import pytest

from acid.models.declaration import DeclarationError
from acid.models.loader import BUILT_IN, checked, load

HEAD = "from acid.models import Model, Parameter, Signal, State\nimport casadi as ca\n"


def _file(tmp_path, body: str, name: str = "m.py"):
    path = tmp_path / name
    path.write_text(HEAD + body)
    return path


def _one_state(step: str, params: str = "Parameter('a', '1/s', 0.1, 0.0, 1.0)",
               state: str = "State('T_cab', 'K')", extra: str = "") -> str:
    return (f"model = Model('m', states=[{state}], inputs=[Signal('W_bl', 'kg/s')],\n"
            f"    parameters=[{params}], Ts=5.0, step=lambda s: {step}{extra})\n")


def _refused(path, *fragments):
    with pytest.raises(DeclarationError) as info:
        load(path)
    text = str(info.value)
    assert "\n" not in text and path.name in text, text
    for f in fragments:
        assert f in text, text
    return text


@pytest.mark.parametrize("step, value", [
    ("{'T_cab': s.T_cab * float('nan') + s.a * s.W_bl}", "NaN"),
    ("{'T_cab': s.T_cab + ca.log(s.a - 0.1) + s.W_bl}", "inf"),     # log(0) at the value
    ("{'T_cab': s.T_cab + s.W_bl / (s.a - 0.1)}", "inf"),           # 1/0 at the value
    ("{'T_cab': s.T_cab + ca.sqrt(-s.a) * s.W_bl}", "NaN"),
])
def test_a_step_non_finite_at_the_declared_values_is_refused(tmp_path, step, value):
    _refused(_file(tmp_path, _one_state(step)), "model 'm'", "'T_cab'", value, "step")


def test_an_output_non_finite_at_the_declared_values_names_the_output(tmp_path):
    body = ("model = Model('m', states=[State('T_cab', 'K')], inputs=[Signal('W_bl', 'kg/s')],"
            "\n    outputs=[Signal('T_ain', 'K')],"
            "\n    parameters=[Parameter('a', '1/s', 0.1, 0.0, 1.0)], Ts=5.0,"
            "\n    step=lambda s: {'T_cab': s.T_cab + s.a * s.W_bl},"
            "\n    output=lambda s: {'T_ain': s.T_cab + ca.log(s.a - 0.1)})\n")
    _refused(_file(tmp_path, body), "output", "'T_ain'", "inf")


def test_a_singularity_at_one_point_only_is_not_refused(tmp_path):
    # singular where T_cab = 293.15 K or W_bl = 0.1 (the first probe point), finite elsewhere:
    # a valid model that the data never drives there
    step = "{'T_cab': s.T_cab + s.a / (s.T_cab - 293.15) + 1 / (s.W_bl - 0.1)}"
    assert load(_file(tmp_path, _one_state(step))).nx == 1


@pytest.mark.parametrize("noise_param, what, fragment", [
    ("Parameter('q', 'K', 0.5, 0.0, 1e300)", "noise", "max 1e+300"),
    ("Parameter('q', 'K', 0.5, 0.0, float('inf'))", "noise", "max inf"),
    ("Parameter('q', 'K', 0.5, -1.0, 1.0)", "noise", "min -1.0"),
    ("Parameter('q', 'K', 2e6, 0.0, 1e7)", "noise", "value 2000000.0"),
    ("Parameter('q', 'K', 0.0, 0.0, 1.0)", "sensor", "value 0.0"),
    ("Parameter('q', 'K', 0.1, 0.0, 1.0)", "sensor", "min 0.0"),
])
def test_a_noise_or_sensor_parameter_out_of_range_is_refused(tmp_path, noise_param, what,
                                                              fragment):
    body = _one_state("{'T_cab': s.T_cab + s.a * (s.W_bl - 0.1)}",
                      params=f"Parameter('a', '1/s', 0.1, 0.0, 1.0), {noise_param}",
                      state=f"State('T_cab', 'K', {what}='q')")
    _refused(_file(tmp_path, body), "parameter 'q'", what, fragment)


def test_a_noise_naming_no_parameter_is_refused(tmp_path):
    body = _one_state("{'T_cab': s.T_cab + s.a * (s.W_bl - 0.1)}",
                      state="State('T_cab', 'K', noise='sigma')")
    _refused(_file(tmp_path, body), "noise='sigma'", "not a declared parameter")


def test_valid_noise_parameters_load(tmp_path):
    body = _one_state("{'T_cab': s.T_cab + s.a * (s.W_bl - 0.1)}",
                      params="Parameter('a', '1/s', 0.1, 0.0, 1.0), "
                             "Parameter('q', 'K', 0.0, 0.0, 1.0), "
                             "Parameter('r', 'K', 0.05, 0.005, 0.5)",
                      state="State('T_cab', 'K', noise='q', sensor='r')")
    assert load(_file(tmp_path, body)).np == 3


@pytest.mark.parametrize("name", sorted(BUILT_IN))
def test_every_built_in_declaration_passes_the_load_checks(name):
    model = load(name)
    assert checked(model, f"{name}.py") is model
