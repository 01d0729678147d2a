"""Every command's ``--help`` as a user reads it: a flag takes no value, so its row shows no
value type (typer 0.29 writes ``<bool>`` after every flag, ``--quick <bool>``); an option that
takes a value keeps its type."""

from __future__ import annotations

import re

import pytest
import typer
from typer.testing import CliRunner

from acid_cli.main import app

runner = CliRunner()
COMMANDS = sorted(typer.main.get_command(app).commands)


def _help(*args: str) -> str:
    res = runner.invoke(app, [*args, "--help"], env={"COLUMNS": "160"})
    assert res.exit_code == 0, res.output
    return res.output


def _row(text: str, option: str) -> str:
    """The row of ``option`` in the help's options panel (its first line)."""
    return next(line for line in text.splitlines() if re.match(rf"\W*{option}\b", line))


@pytest.mark.parametrize("command", [None, *COMMANDS])
def test_no_flag_suggests_a_value(command):
    args = () if command is None else (command,)
    text = _help(*args)
    assert "<bool>" not in text, f"acid {' '.join(args)} --help:\n{text}"
    assert "--help" in text


def test_flags_show_no_type_and_value_options_keep_theirs():
    text = _help("validate")
    for flag in ("--non-overlapping", "--yardsticks", "--allow-unstable", "--help"):
        assert "<" not in _row(text, flag), _row(text, flag)
    assert "<int>" in _row(text, "--starts") and "<path>" in _row(text, "--out")
    top = _help()
    assert "<" not in _row(top, "--version")


def test_every_command_is_walked():
    assert len(COMMANDS) > 10 and {"validate", "sweep", "reproduce"} <= set(COMMANDS)
