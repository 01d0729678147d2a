"""Reliability, round 4: a model file that prints megabytes, starts a process or forks is one
line naming the file and leaves no process; no output lies inside a folder of logs the
command reads; contradicting options are refused while parsing; and no child process
outlives sweeps, reproduces and studies stopped by SIGINT or SIGTERM (psutil)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import psutil
import pytest
from _procs import wait_for
from typer.testing import CliRunner

from acid.errors import OutputError
from acid.models.declaration import DeclarationError
from acid.models.loader import load
from acid_cli._common import check_paths
from acid_cli._options import EXCLUSIVE
from acid_cli.main import app

GOOD = (Path(__file__).resolve().parents[1] / "acid" / "models" / "examples"
        / "cabin3.py").read_text()


def _file(tmp_path: Path, head: str) -> Path:
    path = tmp_path / "m.py"
    path.write_text(head + "\n" + GOOD)
    return path


def _marked(mark: str) -> list[psutil.Process]:
    """Live processes carrying ``mark`` in their command line."""
    out = []
    for p in psutil.process_iter():
        try:
            if mark in " ".join(p.cmdline()) and p.status() != psutil.STATUS_ZOMBIE:
                out.append(p)
        except psutil.Error:
            pass
    return out


@pytest.mark.parametrize("head", [
    "import subprocess; subprocess.Popen(['sleep', '{mark}'])",
    "import os, time\nif os.fork() == 0:\n    time.sleep({mark})\n    os._exit(0)",
], ids=["popen", "fork"])
def test_a_model_file_that_starts_a_process_is_refused_and_nothing_is_left(tmp_path, head,
                                                                           monkeypatch):
    monkeypatch.setenv("ACID_MODEL_TIMEOUT", "20")   # a stalled load would show as 20 s
    mark = f"{3000 + os.getpid() % 997}.{time.monotonic_ns() % 10**6}"
    path = _file(tmp_path, head.format(mark=mark))
    t0 = time.monotonic()
    with pytest.raises(DeclarationError, match=r"m\.py: the model file starts a process"):
        load(path)
    assert time.monotonic() - t0 < 15.0
    if "sleep" in head:
        assert wait_for(lambda: not _marked(mark), 5.0), _marked(mark)


def test_a_model_file_printing_megabytes_is_refused_in_one_line(tmp_path, capfd):
    path = _file(tmp_path, "print('x' * 3_000_000)")
    with pytest.raises(DeclarationError, match=r"m\.py: the model file prints more than 1 MiB"):
        load(path)
    out, err = capfd.readouterr()
    assert len(out) + len(err) < 10_000


def test_a_model_file_printing_a_line_still_loads(tmp_path):
    assert load(_file(tmp_path, "print('declaring the cabin')")).nx == 3


def test_no_output_inside_a_folder_the_command_reads(tmp_path):
    logs = tmp_path / "logs"
    logs.mkdir()
    (logs / "TripA01.csv.gz").write_bytes(b"log")
    for out in (logs / "TripA01.csv.gz", logs / "new.json", tmp_path / "x" / ".." / "logs" / "a"):
        with pytest.raises(OutputError, match=r"--out .*inside the folder LOGS"):
            check_paths(outputs={"--out": out}, read_folders={"LOGS": logs})
    check_paths(outputs={"--out": tmp_path / "p.json"}, read_folders={"LOGS": logs})
    assert (logs / "TripA01.csv.gz").read_bytes() == b"log"


def test_the_same_file_given_as_two_records_is_refused(tmp_path):
    from acid.errors import DataError

    d = tmp_path / "d.h5"
    d.write_bytes(b"x")
    (tmp_path / "sub").mkdir()
    with pytest.raises(DataError, match=r"--add-record 1 .*same file as DATA"):
        check_paths(inputs={"DATA": d, "--add-record 1": tmp_path / "sub" / ".." / "d.h5"},
                    records=["DATA", "--add-record 1"])
    other = tmp_path / "e.h5"
    other.write_bytes(b"x")
    check_paths(inputs={"DATA": d, "--add-record 1": other}, records=["DATA", "--add-record 1"])
    check_paths(inputs={"DATA": d, "--params": d})   # not records: another check's business


@pytest.mark.parametrize("command,pair", [(c, p) for c, ps in EXCLUSIVE.items() for p in ps])
def test_contradicting_options_are_refused_while_parsing(tmp_path, command, pair):
    a, b = pair
    values = {"--planner": ["model"]}
    args = [*command.split(), a, *values.get(a, []), b, *values.get(b, []),
            "--out", str(tmp_path / "o")]
    t0 = time.monotonic()
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and a in lines[0] and b in lines[0], res.output
    assert time.monotonic() - t0 < 5.0 and not (tmp_path / "o").exists()


# ----------------------------------------------------- processes left by stopped commands
TESTS = Path(__file__).resolve().parent
#: a short scenario (60 s: its result file shows the cluster computing) beside a long one
#: (30000 s) that is still running on the other worker when the signal lands: a signal during
#: the interpreter's shutdown ends it by the signal itself, not mid-run
SPEC = ('title = "procs"\nplugins = ["_sweep_plugin"]\n'
        '[defaults]\ncycle = 12.0\nduration_s = 60.0\nwarmup_s = 30.0\ntail_s = 0.0\n'
        '[grid]\nambient_C = [30.0]\n[controllers.nmpc]\n[controllers.fragile]\n'
        'above_C = 40.0\n[[scenarios]]\nambient_C = 35.0\nduration_s = 30000.0\n')


def _group(pgid: int) -> list[str]:
    out = []
    for p in psutil.process_iter():
        try:
            if os.getpgid(p.pid) == pgid and p.status() != psutil.STATUS_ZOMBIE:
                out.append(" ".join(p.cmdline())[:100])
        except (psutil.Error, ProcessLookupError, PermissionError):
            pass
    return out


def _children() -> set[int]:
    out = set()
    for c in psutil.Process().children(recursive=True):
        try:
            if c.status() != psutil.STATUS_ZOMBIE and "resource_tracker" not in \
                    " ".join(c.cmdline()):
                out.add(c.pid)
        except psutil.Error:
            pass
    return out


@pytest.mark.slow
def test_stopped_sweeps_reproduces_and_studies_leave_no_process(tmp_path):
    """Multi-worker runs, each stopped by SIGTERM or SIGINT sent to the command's process
    alone (``kill PID``: the workers do not get it, the command must end them) once it is
    observably mid-run (a sweep's first scenario result written while the other scenario
    runs, a reproduce stage's temporary folder, the year sweep's first progress line): each
    exits 143/130, and afterwards neither its process group nor this test has a process left.
    The waits end on those states, not on a time: on a busy machine they take longer, and
    the runs last until they are stopped. (SIGINT to a sweep's whole group, as Ctrl-C:
    ``test_sweep_cli.py::test_ctrl_c_keeps_finished_scenarios_and_the_rerun_resumes``.)"""
    spec = tmp_path / "procs.toml"
    spec.write_text(SPEC)

    def stage_started(out: Path, lines) -> bool:
        return (out / "stages").is_dir() and any((out / "stages").glob(".*.tmp"))

    runs = [(("sweep", str(spec), "--out", str(tmp_path / "s1"), "--jobs", "2", "--no-figures"),
             signal.SIGTERM,
             lambda out, lines: any((out / "scenarios").glob("*.json"))
             if (out / "scenarios").is_dir() else False),
            (("reproduce", "--quick", "--out", str(tmp_path / "r1"), "--jobs", "2"),
             signal.SIGTERM, stage_started),
            (("year-sweep", "--quick", "--out", str(tmp_path / "y"), "--jobs", "2"),
             signal.SIGINT, lambda out, lines: any(ln.startswith("year sweep: 1/")
                                                   for ln in list(lines)))]
    before = _children()
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(TESTS), *filter(None, [os.environ.get("PYTHONPATH")])])}
    exe = os.path.join(os.path.dirname(sys.executable), "acid")
    for args, sig, mid_run in runs:
        p = subprocess.Popen([exe, *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             text=True, start_new_session=True, env=env,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        lines: list[str] = []
        reader = threading.Thread(target=lambda p=p, lines=lines: lines.extend(p.stdout),
                                  daemon=True)
        reader.start()
        out = Path(args[args.index("--out") + 1])
        assert wait_for(lambda p=p, o=out, ln=lines, m=mid_run: m(o, ln) or p.poll() is not None)
        assert p.poll() is None, (args[0], "ended before it was seen mid-run", "".join(lines))
        os.kill(p.pid, sig)
        p.wait(timeout=180)
        reader.join(30)
        text = "".join(lines)
        assert p.returncode in (128 + sig, 0), text   # 0: it ended before the signal
        assert "Traceback" not in text, text
        assert wait_for(lambda p=p: not _group(p.pid), 15.0), (args[0], _group(p.pid))
        assert not any(f.name.endswith(".part") for f in tmp_path.rglob(".*")), args[0]
    assert wait_for(lambda: _children() <= before, 15.0), _children() - before
