"""Every option that sizes the work (durations, horizons, counts of runs, starts, workers) has
a limit: refused above it while parsing, in one line naming the option, before any work,
and stated in ``--help``."""

from __future__ import annotations

import pytest
import typer
from typer._click.exceptions import ClickException

from acid_cli._options import WORK_LIMITS
from acid_cli.main import app

ROOT = typer.main.get_command(app)
#: option names that size the work wherever they appear
WORK_NAMES = {"--warmup", "--tail", "--duration", "--horizon", "--econ-horizon", "--days",
              "--identify-duration", "--starts", "--max-evals", "--fit-starts",
              "--check-states", "--resamples", "--cv-folds", "--jobs", "--oe-window",
              "--min-dwell", "--max-dwell", "--pull-up"}


def _param(command: str, flag: str):
    return next(p for p in ROOT.commands[command].params if p.opts and p.opts[0] == flag)


def _parse(command: str, args: list[str]) -> None:
    cmd = ROOT.commands[command]
    required = []   # placeholders for required arguments and options (never read)
    for q in cmd.params:
        if q.required:
            required += ["x"] if q.param_type_name == "argument" else [q.opts[0], "x"]
    parent = ROOT.make_context("acid", [command], resilient_parsing=True)
    cmd.make_context(command, [*required, *args], parent=parent).close()


def test_every_work_option_of_every_command_has_a_limit():
    missing = [(name, p.opts[0]) for name, cmd in sorted(ROOT.commands.items())
               for p in getattr(cmd, "params", ()) if p.opts and p.opts[0] in WORK_NAMES
               and (name, p.opts[0]) not in WORK_LIMITS]
    assert not missing, f"work options without a limit in cli/_options.py: {missing}"
    for command, flag in WORK_LIMITS:   # and the table names only real options
        assert _param(command, flag) is not None


@pytest.mark.parametrize("key", sorted(WORK_LIMITS), ids=" ".join)
def test_a_value_above_the_limit_is_refused_while_parsing_and_help_states_it(key):
    command, flag = key
    lo, hi, unit = WORK_LIMITS[key]
    p = _param(command, flag)
    above = str(int(hi) + 1 if isinstance(hi, int) else hi * 10)
    with pytest.raises(ClickException) as info:
        _parse(command, [flag, *[above] * max(1, p.nargs)])
    msg = info.value.format_message()
    assert info.value.exit_code == 2 and "\n" not in msg and flag in msg, msg
    _parse(command, [flag, *[str(hi)] * max(1, p.nargs)])    # the limit itself parses
    cmd = ROOT.commands[command]
    ctx = cmd.make_context(command, [], resilient_parsing=True)
    shown = next(q for q in cmd.get_params(ctx) if q.name == p.name)
    assert f"(limit: {lo:g} to {hi:g}" in shown.help, shown.help
