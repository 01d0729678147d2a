"""Interrupts of real ``acid`` processes: Ctrl-C and SIGTERM stop a run with 130/143 and no
output, also when the shell started it with SIGINT ignored (a background job); SIGKILL in the
middle of writing damages nothing and the next run removes the temporary file."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time

import psutil
import pytest
from typer.testing import CliRunner

from acid.data import Dataset
from acid_cli.main import app

ACID = [sys.executable, "-c", "from acid_cli.main import app; app()"]
#: a progress line (``exciting model plant: 1/50000 (0 %), 0 s``): not an error line
PROGRESS = re.compile(r"\(\d+ %\), \d+ s$")
LONG = ["excite", "--plant", "model", "--duration", "250000"]  # 50,000 steps: ~5 s quiet


def _start(out, ignore_sigint: bool = False) -> subprocess.Popen:
    def preexec():
        if ignore_sigint:  # what a non-interactive shell does to a background job
            signal.signal(signal.SIGINT, signal.SIG_IGN)

    return subprocess.Popen([*ACID, *LONG, "--out", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=preexec)


@pytest.mark.slow
@pytest.mark.parametrize("sig,ignore,code", [(signal.SIGINT, False, 130),
                                             (signal.SIGINT, True, 130),
                                             (signal.SIGTERM, False, 143)])
def test_a_signal_stops_excite_without_output(tmp_path, sig, ignore, code):
    out = tmp_path / "x.h5"
    p = _start(out, ignore)
    # past the interpreter's own start-up (before any Python code runs, no handler can be
    # installed): then in acid's imports or in the simulation, either way nothing may be
    # written. Waiting on the child's CPU time, not the wall clock, holds on a busy machine.
    child = psutil.Process(p.pid)
    deadline = time.monotonic() + 120.0
    while p.poll() is None and time.monotonic() < deadline:
        if sum(child.cpu_times()[:2]) >= 1.0:
            break
        time.sleep(0.05)
    p.send_signal(sig)
    _, err = p.communicate(timeout=120)
    assert p.returncode == code, err
    said = [ln for ln in err.strip().splitlines() if not PROGRESS.search(ln)]  # a progress
    assert "Traceback" not in err and len(said) <= 1, err   # line may come first: then one line
    assert list(tmp_path.iterdir()) == []


#: ``acid`` whose atomic writes stop (SIGSTOP) halfway through writing their temporary file:
#: a run that is observably mid-write, whatever the machine's load
PAUSED_MID_WRITE = """
import os, pathlib, signal
_write = pathlib.Path.write_bytes
def write_bytes(self, data):
    if self.name.endswith(".part"):
        with open(self, "wb") as fh:
            fh.write(data[: len(data) // 2])
            fh.flush()
        os.kill(os.getpid(), signal.SIGSTOP)
    return _write(self, data)
pathlib.Path.write_bytes = write_bytes
from acid_cli.main import app
app()
"""


def test_sigkill_mid_write_damages_nothing_and_the_next_run_cleans_up(tmp_path):
    """SIGKILL while the temporary file is half written (the run stops itself there, so the
    moment is a state to wait on, not a race): the earlier output is untouched, and the next
    run removes the stale temporary."""
    from _procs import wait_for

    out = tmp_path / "x.h5"
    cmd = ["excite", "--plant", "model", "--duration", "600", "--out", str(out)]
    earlier = CliRunner().invoke(app, cmd)
    assert earlier.exit_code == 0, earlier.output
    before = out.read_bytes()
    p = subprocess.Popen([sys.executable, "-c", PAUSED_MID_WRITE, *cmd[:-2], "--seed", "1",
                          "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True)
    child = psutil.Process(p.pid)
    assert wait_for(lambda: p.poll() is not None
                    or child.status() == psutil.STATUS_STOPPED, 120), "never stopped"
    assert p.poll() is None, p.communicate()
    (part,) = [f for f in tmp_path.iterdir() if f.name.endswith(".part")]
    assert 0 < part.stat().st_size < len(before)   # half written
    p.send_signal(signal.SIGKILL)
    p.communicate(timeout=60)
    assert p.returncode == -signal.SIGKILL
    assert out.read_bytes() == before  # the earlier output is untouched
    assert part.exists()  # the stale temporary
    again = CliRunner().invoke(app, cmd)
    assert again.exit_code == 0, again.output
    assert sorted(os.listdir(tmp_path)) == ["x.h5"]
    assert len(Dataset.from_hdf5(out)) == 120


def test_an_interrupt_turned_into_another_exception_by_a_c_extension_is_still_an_interrupt(
        capsys):
    """CasADi's SWIG layer turns a KeyboardInterrupt raised while it converts arguments into a
    NotImplementedError about the arguments: once a signal has arrived, that is an interrupt
    (exit 130, one line), not an internal error (it was, under load, in reproduce's NMPC
    stage)."""
    import typer

    from acid_cli._common import handle_errors

    @handle_errors
    def command():
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)  # the handler raises KeyboardInterrupt here
        except KeyboardInterrupt:
            raise NotImplementedError("Wrong number or type of arguments") from None

    with pytest.raises(typer.Exit) as exc:
        command()
    assert exc.value.exit_code == 130
    err = capsys.readouterr().err
    assert "interrupted" in err and "internal error" not in err


def test_ctrl_c_while_typer_builds_the_commands_exits_quietly(tmp_path):
    """The gap between start-up and a command's guard (typer building the command tree,
    seconds on a busy machine): a KeyboardInterrupt there is the same quiet exit 130, not a
    traceback. Provoked deterministically by raising it from typer's get_command."""
    code = ("import typer.main as tm\n"
            "def interrupted(*a, **k):\n"
            "    raise KeyboardInterrupt\n"
            "tm.get_command = interrupted\n"
            "from acid_cli.main import app\n"
            "app()\n")
    p = subprocess.run([sys.executable, "-c", code, *LONG, "--out", str(tmp_path / "x.h5")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 130, p.stderr
    assert p.stderr.strip() == "interrupted", p.stderr
    assert list(tmp_path.iterdir()) == []


# one run per writer class (text/CSV, JSON, PNG figure, HDF5 dataset), each signalled the
# moment that writer's temporary file appears: the earlier output stays byte for byte, and no
# temporary is left behind
YEAR = ["year-sweep", "--quick", "--plant-config", "paper"]
WRITERS = [("year.csv", signal.SIGINT), ("year.json", signal.SIGTERM),
           ("year_share.png", signal.SIGINT)]


#: ``acid`` (arguments after PREFIX) that stops itself (SIGSTOP) as soon as it has created and
#: named the temporary file ``.PREFIX.*.part`` of an atomic write: a run observably inside
#: that write, whatever the machine's load
PAUSED_AT_TEMPORARY = """
import os, signal, sys, tempfile
prefix = "." + sys.argv.pop(1) + "."
_mkstemp, _close, mine = tempfile.mkstemp, os.close, set()
def mkstemp(*args, **kwargs):
    fd, name = _mkstemp(*args, **kwargs)
    if os.path.basename(name).startswith(prefix):
        mine.add(fd)
    return fd, name
def close(fd):
    _close(fd)
    if fd in mine:
        mine.discard(fd)
        os.kill(os.getpid(), signal.SIGSTOP)
tempfile.mkstemp, os.close = mkstemp, close
from acid_cli.main import app
app()
"""


def _signal_at_temporary(args, folder, prefix: str, sig) -> tuple[int, str]:
    """Run ``acid ARGS`` until it has created ``.PREFIX.*.part`` in ``folder``, send ``sig``
    to its group there, let it go on. Its exit code and output."""
    from _procs import wait_for

    p = subprocess.Popen([sys.executable, "-c", PAUSED_AT_TEMPORARY, prefix, *args],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                         start_new_session=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    child = psutil.Process(p.pid)
    assert wait_for(lambda: p.poll() is not None
                    or child.status() == psutil.STATUS_STOPPED, 300), "never stopped"
    assert p.poll() is None, p.communicate()[0]   # it stopped inside the write
    assert [f for f in os.listdir(folder) if f.startswith(f".{prefix}.")
            and f.endswith(".part")]
    os.killpg(p.pid, sig)
    os.killpg(p.pid, signal.SIGCONT)
    text, _ = p.communicate(timeout=300)
    return p.returncode, text


@pytest.fixture(scope="module")
def year_output(tmp_path_factory):
    """One earlier ``acid year-sweep`` output (in-process), the folder every writer's test
    runs into in turn (its JSON names the folder: one folder, the same bytes each run)."""
    out = tmp_path_factory.mktemp("year") / "year"
    first = CliRunner().invoke(app, [*YEAR, "--out", str(out)])
    assert first.exit_code == 0, first.output
    return out


@pytest.mark.slow
@pytest.mark.parametrize("name,sig", WRITERS, ids=[w[0] for w in WRITERS])
def test_a_signal_at_each_writers_temporary_keeps_the_old_output(name, sig, year_output):
    from _procs import hidden

    out = year_output   # the earlier output: left as it was by the previous test
    assert hidden(out.parent) == []
    before = {f: (out / f).read_bytes() for f in ("year.csv", "year.json")}
    code, text = _signal_at_temporary([*YEAR, "--out", str(out)], out, name, sig)
    assert code == 128 + sig, text   # stopped inside the write
    assert "Traceback" not in text
    assert hidden(out.parent) == []
    for f, data in before.items():       # deterministic: old or new, the same bytes
        assert (out / f).read_bytes() == data
    assert (out / "year_share.png").stat().st_size > 0


def test_an_interrupt_inside_mkstemp_leaves_no_temporary(tmp_path, monkeypatch):
    """The signal lands after ``mkstemp`` created the file but before its name came back (the
    window a signal at the first temporary file hits): the file is still removed, the old
    output kept, and another write of the same process in progress is left alone."""
    import tempfile

    from acid import _io

    target = tmp_path / "out.txt"
    target.write_text("old\n")
    real = tempfile.mkstemp

    def interrupted(*args, **kw):
        real(*args, **kw)
        raise KeyboardInterrupt

    with _io.atomic_path(tmp_path / "other.txt") as other:   # a write in progress
        monkeypatch.setattr(tempfile, "mkstemp", interrupted)
        with pytest.raises(KeyboardInterrupt):
            _io.write_text(target, "new\n")
        monkeypatch.setattr(tempfile, "mkstemp", real)
        assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".part")] == [other.name]
        other.write_text("other\n")
    assert target.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["other.txt", "out.txt"]
