"""A model file that ends the process or never finishes loading is refused with one line
naming the file (the trial load in a forked child), and a good file loads once, as before."""

from __future__ import annotations

import os
import time

import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.models.declaration import DeclarationError
from acid.models.loader import load
from acid_cli.main import app

GOOD = """from acid.models import Model, Parameter, Signal, State
print("declaring")
model = Model("gain", states=[State("x", "1", measured=False, initial=0.0)],
              inputs=[Signal("u", "1")], outputs=[Signal("y", "1")],
              parameters=[Parameter("k", "1", 1.0, -10.0, 10.0)], Ts=1.0,
              ode=lambda s: {"x": -s.x}, output=lambda s: {"y": s.k * s.u})
"""
pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="the trial load forks")


def _file(tmp_path, text: str, name: str = "m.py"):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize("text, how", [("import os\nos._exit(0)\n", "exit status 0"),
                                       ("import os\nos._exit(3)\n", "exit status 3"),
                                       ("import os\nos.abort()\n", "signal 6")])
def test_a_file_that_ends_the_process_is_refused(tmp_path, text, how):
    with pytest.raises(DeclarationError, match=f"m.py: the model file ended the process.*{how}"):
        load(_file(tmp_path, text))


def test_an_endless_loop_is_refused_after_the_limit(tmp_path, monkeypatch):
    monkeypatch.setenv("ACID_MODEL_LOAD_TIMEOUT_S", "1")
    t0 = time.monotonic()
    with pytest.raises(DeclarationError, match="did not finish within 1 s"):
        load(_file(tmp_path, "while True:\n    pass\n"))
    assert time.monotonic() - t0 < 30


def test_a_good_file_loads_once_and_prints_once(tmp_path, capfd):
    m = load(_file(tmp_path, GOOD))
    assert m.name == "gain"
    assert capfd.readouterr().out.count("declaring") == 1     # the child's output discarded


def test_the_cli_names_the_file_and_exits_2(tmp_path):
    f = _file(tmp_path, "import os\nos._exit(0)\n", "quits.py")
    res = CliRunner().invoke(app, ["fit", str(tmp_path / "none.h5"), "--model", str(f),
                                   "--out", str(tmp_path / "p.json")])
    assert res.exit_code == 2
    assert not (tmp_path / "p.json").exists()
    if "quits.py" in res.output:            # the data file is checked first or the model
        assert_one_line_error(res, "quits.py", "ended the process")
    else:
        assert_one_line_error(res, "none.h5")
