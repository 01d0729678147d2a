"""A model file is loaded in a guarded child first: what ends the process, never finishes or
declares an oversized model is one DeclarationError naming the file and the cause."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from acid.models.declaration import DeclarationError
from acid.models.loader import load

GOOD = (Path(__file__).resolve().parents[1] / "acid" / "models" / "examples"
        / "cabin3.py").read_text()


def _file(tmp_path: Path, head: str, name: str = "m.py") -> Path:
    path = tmp_path / name
    path.write_text(head + "\n" + GOOD)
    return path


def test_good_file_loads_fast(tmp_path):
    """A good file loads through the guard (its cost: benchmarks, not an assertion)."""
    path = _file(tmp_path, "")
    model = load(path)
    assert model.nx == 3


@pytest.mark.parametrize("head, cause", [
    ("import os; os._exit(0)", r"os\._exit\(0\)"),
    ("import os, signal; os.kill(os.getpid(), signal.SIGSEGV)", "SIGSEGV"),
])
def test_file_ending_the_process_is_named(tmp_path, head, cause):
    path = _file(tmp_path, head, "ender.py")
    with pytest.raises(DeclarationError, match=rf"ender\.py: .*{cause}"):
        load(path)


def test_os_exit_in_model_function(tmp_path):
    path = tmp_path / "late.py"
    path.write_text(GOOD.replace("model = Model(", "def model():\n    import os\n"
                                 "    os._exit(3)\n\n\n_unused = Model(", 1))
    with pytest.raises(DeclarationError, match=r"late\.py: .*os\._exit\(3\)"):
        load(path)


def test_endless_loop_is_bounded(tmp_path, monkeypatch):
    monkeypatch.setenv("ACID_MODEL_TIMEOUT", "1")
    path = _file(tmp_path, "while True:\n    pass", "loop.py")
    t0 = time.perf_counter()
    with pytest.raises(DeclarationError, match=r"loop\.py: .*within 1 s.*ACID_MODEL_TIMEOUT"):
        load(path)
    assert time.perf_counter() - t0 < 60   # bounded by the timeout, not by the loop


def test_oversized_declaration_refused_before_tracing(tmp_path):
    path = tmp_path / "big.py"
    path.write_text(
        "from acid.models import Model, Parameter, Signal, State\n"
        "n = 3000\n"
        "model = Model('big', states=[State(f'x{i}', 'K', measured=(i == 0)) "
        "for i in range(n)],\n"
        "    parameters=[Parameter('a', '1/s', 0.1, 0.0, 1.0)], Ts=1.0,\n"
        "    inputs=[Signal('u', 'K')],\n"
        "    ode=lambda s: {f'x{i}': s.a * (s.u - getattr(s, f'x{i}')) for i in range(n)})\n")
    t0 = time.perf_counter()
    with pytest.raises(DeclarationError, match=r"big\.py: declares 3000 states, above the "
                                               r"bound of 400 \(ACID_MODEL_MAX_STATES"):
        load(path)
    assert time.perf_counter() - t0 < 60   # refused before tracing 3000 states


def test_size_bound_from_env(tmp_path, monkeypatch):
    monkeypatch.setenv("ACID_MODEL_MAX_STATES", "2")
    with pytest.raises(DeclarationError, match=r"m\.py: declares 3 states, above the bound of 2"):
        load(_file(tmp_path, ""))
    monkeypatch.setenv("ACID_MODEL_GUARD", "0")   # the in-process check still applies
    with pytest.raises(DeclarationError, match=r"declares 3 states"):
        load(_file(tmp_path, ""))


@pytest.mark.parametrize("value", ["abc", "-1", "0", "inf", "nan"])
def test_bad_bound_env_named(tmp_path, monkeypatch, value):
    monkeypatch.setenv("ACID_MODEL_TIMEOUT", value)
    with pytest.raises(DeclarationError, match=r"ACID_MODEL_TIMEOUT="):
        load(_file(tmp_path, ""))


def test_a_good_file_prints_once(tmp_path, capfd):
    """The trial child's output is discarded: the file's own print appears once."""
    f = tmp_path / "talks.py"
    f.write_text("from acid.models import Model, Parameter, Signal, State\n"
                 "print('declaring')\n"
                 "model = Model('gain', states=[State('x', '1', measured=False, initial=0.0)],"
                 " inputs=[Signal('u', '1')], outputs=[Signal('y', '1')],"
                 " parameters=[Parameter('k', '1', 1.0, -10.0, 10.0)], Ts=1.0,"
                 " ode=lambda s: {'x': -s.x}, output=lambda s: {'y': s.k * s.u})\n")
    from acid.models.loader import load

    assert load(f).name == "gain"
    assert capfd.readouterr().out.count("declaring") == 1
