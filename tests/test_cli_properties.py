"""Property-based guards (hypothesis): the CLI's option parser and the model-file loader fed
generated values never end in a traceback.

* every numeric option of every command (found from the Typer app's parameters, not a hand
  list) parses a generated value (NaN, inf, negative, zero, huge, malformed text) either
  cleanly or into a usage error (exit 2) that names the option;
* the model-file loader, given generated declarations (state and parameter counts, sample
  times, values and bounds, a first statement that exits, raises or kills), returns a model
  or raises one ``DeclarationError`` line naming the file.

Bounded budget: a few hundred examples, no per-example deadline; the file runs in ~20 s.
"""

from __future__ import annotations

import math
import typing

import typer
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer._click.exceptions import ClickException

from acid.models.declaration import DeclarationError
from acid.models.loader import load
from acid_cli.main import app

ROOT = typer.main.get_command(app)


def _numeric(annotation) -> type | None:
    """``float`` or ``int`` when an option takes numbers (also lists and optionals of them)."""
    if annotation in (float, int):
        return annotation
    for arg in typing.get_args(annotation):
        kind = _numeric(arg)
        if kind is not None:
            return kind
    return None


def _numeric_options():
    out = []
    for name, cmd in sorted(ROOT.commands.items()):
        for p in cmd.params:
            desc = getattr(p, "type_descriptor", None)
            kind = _numeric(getattr(desc, "annotation", None))
            if kind is not None and p.opts and p.opts[0].startswith("--") \
                    and not getattr(p, "is_flag", False):
                out.append((name, p.name, p.opts[0], kind))
    return out


OPTIONS = _numeric_options()

HOSTILE_TEXT = st.sampled_from(["nan", "NaN", "inf", "-inf", "1e400", "-1e400", "0", "-0",
                                "-1", "", " ", "abc", "1,5", "1e-320", "9" * 40, "-" + "9" * 40,
                                "0x10", "1_000"])
VALUES = st.one_of(
    HOSTILE_TEXT,
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(min_value=-(10 ** 30), max_value=10 ** 30).map(str),
    st.integers(min_value=-5, max_value=5).map(str))


def test_the_app_has_numeric_options():
    assert len(OPTIONS) > 30, OPTIONS   # generated from the app, so it follows new options
    assert ("year-sweep", "switch_over", "--switch-over", float) in OPTIONS


@settings(max_examples=600, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(option=st.sampled_from(OPTIONS), value=VALUES)
def test_numeric_options_parse_or_name_the_option(option, value):
    command, name, flag, _kind = option
    cmd = ROOT.commands[command]
    parent = ROOT.make_context("acid", [command], resilient_parsing=True)
    try:
        ctx = cmd.make_context(command, [f"{flag}={value}"], parent=parent)
        ctx.close()
    except ClickException as exc:
        assert exc.exit_code == 2, (command, flag, value, exc.format_message())
        msg = exc.format_message()
        assert "\n" not in msg.strip(), msg
        if getattr(exc, "param", None) is not None and exc.param.name == name:
            assert flag in msg or name in msg, (command, flag, value, msg)
    # anything else (ValueError, TypeError, an AcidError out of a callback) fails the test:
    # it would be a traceback and exit 1


# ------------------------------------------------------------------ the model-file loader
HEADS = st.sampled_from([
    "", "import os; os._exit(0)", "import os; os._exit(7)", "import sys; sys.exit(0)",
    "import sys; sys.exit('bye')", "raise KeyboardInterrupt", "raise MemoryError",
    "raise RecursionError('deep')", "import os, signal; os.kill(os.getpid(), signal.SIGABRT)",
    "x = 1/0", "import not_a_module_anywhere", "def model(:"])
NUMBERS = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=32),
                    st.sampled_from([0.0, -1.0, 1e308, -1e308, 1.0]))


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(head=HEADS, n_states=st.sampled_from([0, 1, 2, 3, 401, 3000]),
       n_params=st.sampled_from([0, 1, 2, 5001]), Ts=NUMBERS, value=NUMBERS, low=NUMBERS,
       high=NUMBERS)
def test_generated_model_files_load_or_fail_in_one_line(tmp_path_factory, head, n_states,
                                                        n_params, Ts, value, low, high):
    folder = tmp_path_factory.mktemp("m")
    path = folder / "gen.py"
    path.write_text(
        f"{head}\n"
        "from acid.models import Model, Parameter, Signal, State\n"
        f"n, m = {n_states}, {n_params}\n"
        "model = Model('gen', states=[State(f'x{i}', 'K', measured=(i == 0)) "
        "for i in range(n)],\n"
        f"    parameters=[Parameter(f'a{{j}}', '1/s', {value!r}, {low!r}, {high!r}) "
        "for j in range(m)],\n"
        f"    Ts={Ts!r}, inputs=[Signal('u', 'K')],\n"
        "    ode=lambda s: {f'x{i}': (s.a0 if m else 0.1) * (s.u - getattr(s, f'x{i}'))\n"
        "                   for i in range(n)})\n".replace("nan", "float('nan')")
        .replace("inf", "float('inf')"))
    try:
        model = load(path)
    except DeclarationError as exc:
        text = str(exc)
        assert "\n" not in text.strip() and "gen.py" in text, text
        return
    assert model.nx == n_states <= 400 and model.np == n_params <= 5000
    assert math.isfinite(model.Ts) and model.Ts > 0
