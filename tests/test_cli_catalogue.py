"""The bad-input catalogue (``tests/_catalogue.py``): every case is one ``error:`` line naming
the culprit, exit 2, no traceback, nothing written and no earlier file changed."""

from __future__ import annotations

import pytest
from _catalogue import CASES, build_workspace, classify, run_case
from _cli import assert_one_line_error

from acid_cli.main import app


@pytest.fixture(scope="module")
def template(tmp_path_factory):
    return build_workspace(tmp_path_factory.mktemp("catalogue") / "template")


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input_gets_one_line_naming_the_culprit(case, template, tmp_path):
    w = tmp_path / "w"
    o = run_case(case, template, w)
    assert not o.changed, f"files changed or lost: {o.changed}\n{o.output}"
    assert o.exit_code == 2, o.output
    assert_one_line_error(o.result, *case.fragments(w))
    assert not o.created, f"files written by a failing command: {o.created}"
    assert classify(o, w) == "clean"


def test_the_catalogue_covers_every_command_and_class():
    assert len(CASES) >= 60
    commands = {c.args[0] for c in CASES}
    registered = {cmd.name for cmd in app.registered_commands}
    assert registered <= commands, f"commands without bad-input cases: {registered - commands}"
    classes = {c.cls for c in CASES}
    assert {"collision", "output", "markup", "params", "hdf5", "map", "mat", "csv", "options",
            "sizes"} <= classes
