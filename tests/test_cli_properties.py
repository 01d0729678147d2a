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


def _commands(group=ROOT, prefix: str = "") -> dict[str, object]:
    """{"fit": command, "car select": command, ...}: every command, a group's too."""
    out = {}
    for name, cmd in sorted(group.commands.items()):
        if hasattr(cmd, "commands"):
            out.update(_commands(cmd, f"{prefix}{name} "))
        else:
            out[f"{prefix}{name}"] = cmd
    return out


COMMANDS = _commands()


def _make_context(command: str, args: list[str]):
    """The context of ``acid COMMAND ARGS`` (a sub-command inside its group's context)."""
    words = command.split()
    parent = ROOT.make_context("acid", [words[0]], resilient_parsing=True)
    for word in words[:-1]:
        parent = parent.command.commands[word].make_context(word, [words[-1]], parent=parent,
                                                            resilient_parsing=True)
    return COMMANDS[command].make_context(words[-1], args, parent=parent)


def _numeric_options():
    out = []
    for name, cmd in COMMANDS.items():
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
    assert ("car select", "rule_time", "--rule-time", float) in OPTIONS   # sub-commands too


@settings(max_examples=600, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(option=st.sampled_from(OPTIONS), value=VALUES)
def test_numeric_options_parse_or_name_the_option(option, value):
    command, name, flag, _kind = option
    cmd = COMMANDS[command]
    required = [a for q in cmd.params if q.required and q.name != name
                for a in (["x"] if q.param_type_name == "argument" else [q.opts[0], "x"])]
    try:
        _make_context(command, [*required, f"{flag}={value}"]).close()
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


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(option=st.sampled_from(OPTIONS), first=st.sampled_from(["1", "2", "0.5"]),
       second=st.sampled_from(["1", "2", "0.5"]), inline=st.booleans())
def test_an_option_given_twice_keeps_one_value_or_is_refused(option, first, second, inline):
    """An option that keeps one value, given twice with different values, is one usage
    error naming it (never the last value silently); a repeatable one parses."""
    command, name, flag, _kind = option
    cmd = COMMANDS[command]
    param = next(p for p in cmd.params if p.name == name)
    n = max(1, param.nargs)
    one = [f"{flag}={first}"] if inline and n == 1 else [flag, *[first] * n]
    required = [a for q in cmd.params if q.required and q.name != name
                for a in (["x"] if q.param_type_name == "argument" else [q.opts[0], "x"])]
    args = [*required, *one, flag, *[second] * n]
    try:
        _make_context(command, args).close()
    except ClickException as exc:
        msg = exc.format_message()
        assert exc.exit_code == 2 and "\n" not in msg.strip(), msg
        if not param.multiple and first != second:
            assert f"{flag} is given twice" in msg, msg
        return
    assert param.multiple or first == second, (command, flag, first, second)


# ------------------------------------------- the loader's numeric declarations (values)
SDS = st.one_of(st.sampled_from([None, 0.0, -0.0, -1.0, 1e-9, 0.05, 1e6, 1.1e6, 1e300,
                                 math.inf, -math.inf, math.nan]),
                st.floats(allow_nan=True, allow_infinity=True, width=32))
FACTORS = st.sampled_from([1.0, 0.0, -1.0, 1e300, math.inf, math.nan, 1e-300])


def _lit(v) -> str:
    if v is None:
        return "None"
    return {"nan": "float('nan')", "inf": "float('inf')", "-inf": "float('-inf')"}.get(
        repr(v), repr(v))


#: a valid declaration; each example replaces one of these with a generated value
VALID = {"noise": 0.02, "sensor": 0.05, "spread": 0.1, "lo": 0.001, "value": 0.05, "hi": 0.5,
         "factor": 1.0, "initial": 293.15}


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(field=st.sampled_from(sorted(VALID)), hostile=st.one_of(SDS, FACTORS),
       by_name=st.sampled_from(["noise", "sensor", None]))
def test_declared_noises_bounds_and_equations_load_or_fail_in_one_line(
        tmp_path_factory, field, hostile, by_name):
    """Generated numeric declarations (a state's noise, sensor, spread and initial value, the
    min/value/max of a parameter named as noise or sensor, a factor in the equation; one at
    a time, the others valid): the file loads, and then what a filter and a simulation read
    is sound (noise parameters within [0, 1e6], the step's factor finite), or it is one line
    naming the file."""
    v = {**VALID, field: hostile}
    noise, sensor, spread, initial, factor = (v["noise"], v["sensor"], v["spread"],
                                              v["initial"], v["factor"])
    q = (v["lo"], v["value"], v["hi"])
    lo, value, hi = q
    noise_arg = "'q'" if by_name == "noise" else _lit(noise)
    sensor_arg = "'q'" if by_name == "sensor" else _lit(sensor)
    path = tmp_path_factory.mktemp("n") / "decl.py"
    path.write_text(
        "from acid.models import Model, Parameter, Signal, State\n"
        "model = Model('decl', states=[State('T_cab', 'K', noise="
        f"{noise_arg}, sensor={sensor_arg}, spread={_lit(spread)}),\n"
        "    State('T_m', 'K', measured=False, initial="
        f"{_lit(initial) if initial is not None else 293.15})],\n"
        "    inputs=[Signal('W_bl', 'kg/s')],\n"
        "    parameters=[Parameter('a', '1/s', 0.1, 0.0, 1.0),\n"
        f"                Parameter('q', 'K', {_lit(value)}, {_lit(lo)}, {_lit(hi)})],\n"
        "    Ts=5.0, step=lambda s: {'T_cab': s.T_cab + s.a * (s.T_m - s.T_cab) * "
        f"{_lit(factor)},\n"
        "                           'T_m': s.T_m + 0.01 * (s.T_cab - s.T_m) + 0 * s.q})\n")
    try:
        model = load(path)
    except DeclarationError as exc:
        text = str(exc)
        assert "\n" not in text.strip() and "decl.py" in text, text
        return
    for s in model.states:
        for what in ("noise", "sensor", "spread"):
            v = getattr(s, what)
            if isinstance(v, str):
                p = model.parameter(v)
                assert 0.0 <= p.min <= p.value <= p.max <= 1e6, (what, p)
                assert what != "sensor" or p.min > 0.0, p
            elif v is not None:
                assert math.isfinite(v) and 0.0 <= v <= 1e6, (what, v)
                assert what != "sensor" or v > 0.0, v
    assert math.isfinite(factor), factor   # NaN/inf in the step at every point: refused


# ------------------------------------- text options of the newer commands (parsed by acid)
NUMBER_TEXT = st.one_of(HOSTILE_TEXT, st.floats(allow_nan=True, allow_infinity=True).map(repr),
                        st.integers(min_value=-(10 ** 20), max_value=10 ** 20).map(str))
NAME_TEXT = st.one_of(st.sampled_from(["C_cab", "gamma1", "", " ", "=", "a=b", "x,y"]),
                      st.text(max_size=8))


@settings(max_examples=120, deadline=None)
@given(items=st.lists(st.tuples(NAME_TEXT, st.sampled_from(["=", "", "=="]),
                                st.lists(NUMBER_TEXT, min_size=0, max_size=3)), max_size=4),
       which=st.sampled_from(["--prior", "--fix"]))
def test_prior_and_fix_values_parse_sound_or_name_the_option(items, which):
    """``--prior NAME=MEAN,SD`` and ``--fix NAME=VALUE`` from generated text: a dict of
    finite numbers (SD > 0, each name once) or one line naming the option."""
    from acid.errors import ConfigError
    from acid_cli._declared import parse_fix, parse_prior

    texts = [f"{name}{sep}{','.join(nums)}" for name, sep, nums in items]
    try:
        got = (parse_prior if which == "--prior" else parse_fix)(texts)
    except ConfigError as exc:
        assert str(exc).startswith(which) and "\n" not in str(exc), str(exc)
        return
    assert len(got) == len(texts)   # no name silently given twice
    for value in got.values():
        numbers = value if isinstance(value, tuple) else (value,)
        assert all(math.isfinite(v) for v in numbers), got
        assert which == "--fix" or numbers[1] > 0, got


@settings(max_examples=200, deadline=None)
@given(address=st.one_of(
    st.sampled_from(["tcp://127.0.0.1:8786", "tcp://h:0", "tcp://h:65536", "http://h:1",
                     "h:-1", "", " ", "tcp://", "://x", "tcp://h:99999999999999999999"]),
    st.text(max_size=30),
    st.builds(lambda s, h, p: f"{s}{h}:{p}", st.sampled_from(["", "tcp://", "tls://", "x://"]),
              st.text(min_size=0, max_size=10), st.integers(-5, 10 ** 6))))
def test_scheduler_addresses_read_or_name_the_option(address):
    """``--scheduler`` text: an address of a known scheme with a port in 1..65535, or one
    line naming ``--scheduler`` (checked before any connection is tried)."""
    from acid.errors import ConfigError
    from acid.executor import check_scheduler_address

    try:
        assert check_scheduler_address(address) == address
    except ConfigError as exc:
        assert str(exc).startswith("--scheduler") and "\n" not in str(exc), str(exc)


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(seeds=st.lists(NUMBER_TEXT, max_size=6).map(",".join) | st.text(max_size=12)
       | st.integers(0, 300).map(lambda n: ",".join(map(str, range(n)))))
def test_compare_identify_records_is_one_line_before_any_work(tmp_path_factory, seeds):
    """``acid compare --identify-records`` from generated text, with ``--json`` under a file:
    one usage line (naming --identify-records, or --json once the seeds read well), before
    any work, never a traceback."""
    import time

    from typer.testing import CliRunner

    w = tmp_path_factory.mktemp("c")
    (w / "afile").write_text("x")
    t0 = time.monotonic()
    res = CliRunner().invoke(app, ["compare", "--identify-records", seeds,
                                   "--json", str(w / "afile" / "c.json")])
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert res.exit_code == 2 and len(lines) == 1, res.output
    assert "--identify-records" in lines[0] or "--json" in lines[0], lines[0]
    assert time.monotonic() - t0 < 20.0
