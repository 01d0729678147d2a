"""A signal is an exit code whenever it lands: SIGINT / SIGTERM arriving after the command has
written everything, while the process exits (threads joined, exit handlers, a Dask cluster's
teardown), ends it with 130 / 143 and one line, the outputs whole, nothing left running.

The exit phases are made long on purpose by the test's own entry code (``python -c``), not by
anything in acid: a non-daemon thread that lingers once the main thread is done, an ``atexit``
handler that sleeps, an object whose finaliser sleeps in the interpreter's module teardown.
Each prints a line when its phase begins; the test sends the signal on that line. Before the
fix the process died of the signal (-2 / -15) or printed a traceback and exited 0.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import psutil
import pytest

from acid.data import Dataset

#: test-only entry: the phases of the exit, each announced on stdout, then the CLI as usual
ENTRY = """
import atexit, os, sys, threading, time
phase = os.environ["EXIT_PHASE"]
class Teardown:
    def __del__(self):
        os.write(1, b"phase: teardown\\n"); time.sleep(1.5)
teardown = Teardown()   # a module global: finalised in the interpreter's module teardown
if phase == "threads":
    def linger():
        threading.main_thread().join()   # returns once the main thread has finished
        os.write(1, b"phase: threads\\n"); time.sleep(1.5)
    threading.Thread(target=linger).start()
if phase == "atexit":
    def slow_exit():
        os.write(1, b"phase: atexit\\n"); time.sleep(1.5)
    atexit.register(slow_exit)
from acid_cli.main import app
app()
"""
EXCITE = ["excite", "--plant", "model", "--duration", "600"]   # 120 samples, ~1 CPU-s


def _start(args, phase: str, cwd: Path) -> subprocess.Popen:
    env = {**os.environ, "EXIT_PHASE": phase}
    return subprocess.Popen([sys.executable, "-c", ENTRY, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, cwd=cwd,
                            start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _signal_on(p: subprocess.Popen, marker: str, sig: int, group: bool = False) -> list[str]:
    """Read stdout until ``marker`` (sending ``sig`` then) and to its end: the lines."""
    lines = []
    for line in p.stdout:
        lines.append(line)
        if line.startswith(marker):
            (os.killpg if group else os.kill)(p.pid, sig)
    p.wait(timeout=60)
    return lines


def _said(err: str) -> list[str]:
    """The lines of stderr beside the progress lines."""
    return [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("exciting")]


def _group_left(pgid: int) -> list[str]:
    left = []
    for q in psutil.process_iter():
        try:
            if os.getpgid(q.pid) == pgid and q.status() != psutil.STATUS_ZOMBIE:
                left.append(" ".join(q.cmdline())[:100])
        except (psutil.Error, ProcessLookupError, PermissionError):
            pass
    return left


@pytest.mark.parametrize("phase,sig", [("atexit", signal.SIGINT), ("atexit", signal.SIGTERM),
                                       ("threads", signal.SIGINT)])
def test_a_signal_while_the_process_exits_is_its_exit_code(tmp_path, phase, sig):
    out = tmp_path / "x.h5"
    p = _start([*EXCITE, "--out", str(out)], phase, tmp_path)
    lines = _signal_on(p, f"phase: {phase}", sig)
    err = p.stderr.read()
    assert f"phase: {phase}\n" in lines, (lines, err)   # the signal was sent in that phase
    assert p.returncode == 128 + sig, err
    assert _said(err) == ["interrupted (while exiting: the command had ended)"], err
    assert len(Dataset.from_hdf5(out)) == 120          # the output is whole
    assert sorted(os.listdir(tmp_path)) == ["x.h5"]     # and nothing beside it


def test_the_exit_skips_the_module_teardown_where_signals_are_at_their_default(tmp_path):
    """The interpreter's module teardown (most of a second with Dask, pandas and CasADi
    loaded) runs with every signal at its default action: acid's exit leaves before it."""
    out = tmp_path / "x.h5"
    p = _start([*EXCITE, "--out", str(out)], "none", tmp_path)
    lines = _signal_on(p, "phase: teardown", signal.SIGTERM)
    err = p.stderr.read()
    assert "phase: teardown\n" not in lines and p.returncode == 0, (p.returncode, err)
    assert len(Dataset.from_hdf5(out)) == 120


def test_a_failing_command_keeps_its_exit_code_and_message(tmp_path):
    p = _start(["excite", "--plant", "model", "--duration", "-5", "--out",
                str(tmp_path / "x.h5")], "atexit", tmp_path)
    lines = _signal_on(p, "never", signal.SIGTERM)
    err = p.stderr.read()
    assert p.returncode == 2, err
    assert len(_said(err)) == 1 and _said(err)[0].startswith("error:"), err
    assert "phase: atexit\n" in lines   # the exit handlers still ran
    assert os.listdir(tmp_path) == []


SWEEP = ('title = "late"\nplugins = ["_sweep_plugin"]\n'
         '[defaults]\ncycle = 12.0\nduration_s = 60.0\nwarmup_s = 30.0\ntail_s = 0.0\n'
         '[grid]\nambient_C = [30.0, 35.0]\n[controllers.nmpc]\n')


@pytest.mark.slow
def test_ctrl_c_after_a_parallel_sweep_wrote_everything(tmp_path):
    """Ctrl-C to the whole group 0.1 s after the last output line of a sweep on two worker
    processes (on main: the process died of SIGINT, -2, in the interpreter's teardown)."""
    spec = tmp_path / "late.toml"
    spec.write_text(SWEEP)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(Path(__file__).parent), *filter(None, [os.environ.get("PYTHONPATH")])])}
    exe = os.path.join(os.path.dirname(sys.executable), "acid")
    p = subprocess.Popen([exe, "sweep", str(spec), "--out", str(tmp_path / "out"), "--jobs",
                          "2", "--no-figures"], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, env=env, start_new_session=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    lines = []
    for line in p.stdout:
        lines.append(line)
        if line.startswith("summary:"):
            time.sleep(0.1)
            try:
                os.killpg(p.pid, signal.SIGINT)
            except ProcessLookupError:   # the whole group already ended
                pass
    p.wait(timeout=60)
    text = "".join(lines)
    assert p.returncode in (0, 130), text   # gone already, or 130: never a signal death
    assert "Traceback" not in text
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["computed"] == 2, summary
    time.sleep(0.5)
    assert _group_left(p.pid) == []


# ------------------------------------------------------------- Ctrl-C in the middle of a run
REAL = next((p for p in (Path(__file__).resolve().parents[1].parent / "shared" / "real-data"
                          / "bmw-i3", Path("/work/shared/real-data/bmw-i3")) if p.is_dir()),
            Path("../shared/real-data/bmw-i3"))   # ../shared beside the repository
TRIPS = ("TripA04", "TripA05", "TripA07")
#: the long commands no other test interrupts: (arguments, when to press Ctrl-C: a line of
#: their progress on stderr, or the CPU seconds their process tree has used: past the
#: imports, into the work). ``{logs}``: copies of three real trips; ``{h5}``: them imported;
#: ``{all}``: copies of every trip;
#: ``{old}``: the JSON an earlier run left, which must stay as it was.
MID_RUN = {
    "compare": (["compare", "--quick", "--jobs", "2", "--json", "{old}"], 3.0),
    "cav-study": (["cav-study", "--no-figures", "--json", "{old}"], 3.0),
    "day": (["day", "--quick", "--jobs", "2", "--json", "{old}"], 3.0),
    "pulldown": (["pulldown", "--quick", "--json", "{old}"], 3.0),
    "car select": (["car", "select", "{logs}", "--folds", "2", "--json", "{old}"], 3.0),
    "car validate": (["car", "validate", "{all}", "--json", "{old}"], "car validate: 1/"),
    "fit": (["fit", "{h5}", "--model", "car_cabin", "--method", "pem", "--out", "{old}"],
            "fit car_cabin: 1/"),   # the optimiser under way (its first evaluation done)
    "validate": (["validate", "{h5}", "--model", "car_cabin", "--cv", "experiments", "--json",
                  "{old}"], 3.0),
    # its NMPC's IPOPT swallowed the KeyboardInterrupt and the loop ran on (> 120 s)
    # (no warm-up or tail: the NMPC phase a second of CPU sooner)
    "heating-control": (["heating-control", "--warmup", "0", "--tail", "0", "--json", "{old}"],
                        "NMPC"),
}


@pytest.fixture(scope="module")
def trips(tmp_path_factory):
    if not REAL.is_dir():
        pytest.skip(f"the real BMW i3 trips are not at {REAL}")
    base = tmp_path_factory.mktemp("trips")
    logs = base / "logs"
    logs.mkdir()
    for t in TRIPS:   # copies: a run must never be able to write into the shared folder
        shutil.copy(REAL / f"{t}.csv.gz", logs / f"{t}.csv.gz")
    every = base / "all"   # car validate: under a second of work on three trips
    every.mkdir()
    for f in REAL.glob("Trip*.csv.gz"):
        shutil.copy(f, every / f.name)
    h5 = base / "trips.h5"
    from typer.testing import CliRunner

    from acid_cli.main import app

    r = CliRunner().invoke(app, ["import", *(str(logs / f"{t}.csv.gz") for t in TRIPS),
                                 "--map", "example:bmw_i3_map.toml", "--out", str(h5)])
    assert r.exit_code == 0, r.output
    return {"logs": str(logs), "h5": str(h5), "all": str(every)}


def _tree_cpu(proc: psutil.Process) -> float:
    total = 0.0
    for q in [proc, *proc.children(recursive=True)]:
        try:
            total += sum(q.cpu_times()[:2])
        except psutil.Error:
            pass
    return total


@pytest.mark.slow
@pytest.mark.parametrize("command", list(MID_RUN))
def test_ctrl_c_mid_run_is_130_and_leaves_nothing(tmp_path, trips, command):
    args, when = MID_RUN[command]
    old = tmp_path / "old.json"
    old.write_text('{"earlier": "run"}\n')
    args = [a.format(old=old, **trips) for a in args]
    exe = os.path.join(os.path.dirname(sys.executable), "acid")
    p = subprocess.Popen([exe, *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                         text=True, cwd=tmp_path, start_new_session=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    err: list[str] = []
    reader = threading.Thread(target=lambda: err.extend(p.stderr), daemon=True)
    reader.start()
    proc = psutil.Process(p.pid)
    deadline = time.monotonic() + 300
    while p.poll() is None and time.monotonic() < deadline:
        if (any(when in line for line in err) if isinstance(when, str)
                else _tree_cpu(proc) >= when):
            break
        time.sleep(0.05)
    if p.poll() is not None:
        pytest.skip(f"{command} ended before it was interrupted (rc {p.returncode})")
    os.killpg(p.pid, signal.SIGINT)
    try:
        p.wait(timeout=60)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        pytest.fail(f"{command} still ran 60 s after Ctrl-C")
    reader.join(10)
    said = [ln for ln in err if ln.strip() and "%" not in ln and not ln.startswith(
        (f"{command}:", "heating-control:", "compare:"))]
    assert p.returncode == 130, "".join(err)
    assert not any("Traceback" in ln for ln in err), "".join(err)
    assert said[-1].startswith("interrupted"), "".join(err)
    assert old.read_text() == '{"earlier": "run"}\n'           # the earlier output is kept
    assert sorted(f.name for f in tmp_path.rglob("*")) == ["old.json"]   # and nothing else
    time.sleep(0.5)
    assert _group_left(p.pid) == []
