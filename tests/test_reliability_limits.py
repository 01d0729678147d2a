"""Every option that sizes the work (durations, horizons, counts of runs, starts, workers) has
a limit: refused above it while parsing, in one line naming the option, before any work,
and stated in ``--help``."""

from __future__ import annotations

import pytest
import typer
from typer._click.exceptions import ClickException

from acid_cli._options import LIST_LIMITS, WORK_LIMITS
from acid_cli.main import app

ROOT = typer.main.get_command(app)
#: option names that size the work wherever they appear
WORK_NAMES = {"--warmup", "--tail", "--duration", "--horizon", "--econ-horizon", "--days",
              "--identify-duration", "--starts", "--max-evals", "--fit-starts",
              "--check-states", "--resamples", "--cv-folds", "--jobs", "--oe-window",
              "--min-dwell", "--max-dwell", "--pull-up"}


def _commands(group=ROOT, prefix: str = "") -> dict[str, object]:
    """{"fit": command, "car select": command, ...}: every command, groups' too."""
    out = {}
    for name, cmd in group.commands.items():
        if hasattr(cmd, "commands"):
            out.update(_commands(cmd, f"{prefix}{name} "))
        else:
            out[f"{prefix}{name}"] = cmd
    return out


COMMANDS = _commands()


def _param(command: str, flag: str):
    return next(p for p in COMMANDS[command].params if p.opts and p.opts[0] == flag)


def _context(command: str, args: list[str], **kw):
    """The context of ``acid COMMAND ARGS`` (a sub-command below its group's context)."""
    parent = ROOT.make_context("acid", [command.split()[0]], resilient_parsing=True)
    words = command.split()
    for word in words[:-1]:   # the groups
        group = parent.command.commands[word]
        parent = group.make_context(word, [words[-1]], parent=parent, resilient_parsing=True)
    cmd = COMMANDS[command]
    return cmd.make_context(words[-1], args, parent=parent, **kw)


def _parse(command: str, args: list[str]) -> None:
    cmd = COMMANDS[command]
    required = []   # placeholders for required arguments and options (never read)
    for q in cmd.params:
        if q.required:
            required += ["x"] if q.param_type_name == "argument" else [q.opts[0], "x"]
    _context(command, [*required, *args]).close()


def test_every_work_option_of_every_command_has_a_limit():
    missing = [(name, p.opts[0]) for name, cmd in sorted(COMMANDS.items())
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
    cmd = COMMANDS[command]
    ctx = _context(command, [], resilient_parsing=True)
    shown = next(q for q in cmd.get_params(ctx) if q.name == p.name)
    assert f"(limit: {lo:g} to {hi:g}" in shown.help, shown.help


@pytest.mark.parametrize("key", sorted(LIST_LIMITS), ids=" ".join)
def test_a_list_longer_than_its_limit_is_refused_while_parsing_and_help_states_it(key):
    command, flag = key
    most, what = LIST_LIMITS[key]
    p = _param(command, flag)
    items = [str(i) for i in range(most + 1)]
    args = [a for i in items for a in (flag, i)] if p.multiple else [flag, ",".join(items)]
    with pytest.raises(ClickException) as info:
        _parse(command, args)
    msg = info.value.format_message()
    assert info.value.exit_code == 2 and flag in msg and f"at most {most}" in msg, msg
    ok = [a for i in items[:most] for a in (flag, i)] if p.multiple \
        else [flag, ",".join(items[:most])]
    _parse(command, ok)    # the limit itself parses
    shown = next(q for q in COMMANDS[command].get_params(_context(command, [],
                 resilient_parsing=True)) if q.name == p.name)
    assert f"(limit: at most {most} {what}" in shown.help, shown.help
