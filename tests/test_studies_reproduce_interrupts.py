"""``acid reproduce`` under Ctrl-C, SIGKILL and a concurrent second run (issue 11).

Ctrl-C stops with exit 130, no report and no temporaries; after SIGKILL its worker
processes end with it (the caller's pipes close) and the next run removes what was left;
a second run into the same folder is refused with one line.
"""

from __future__ import annotations

import pytest
from _procs import alive, descendants, hidden, interrupt, start, wait_for

pytestmark = pytest.mark.slow


def _stage_started(out, stage="*"):
    return lambda: bool(list((out / "stages").glob(f".{stage}.*.tmp"))) \
        if (out / "stages").is_dir() else False


def _group(pgid: int) -> list[str]:
    """Live (non-zombie) processes of process group ``pgid`` (children re-parented to init
    included)."""
    import os

    import psutil

    out = []
    for q in psutil.process_iter():
        try:
            if os.getpgid(q.pid) == pgid and q.status() != psutil.STATUS_ZOMBIE:
                out.append(" ".join(q.cmdline())[:120])
        except (psutil.Error, ProcessLookupError, PermissionError):
            pass
    return out


def test_ctrl_c_exits_130_with_nothing_half_written(tmp_path):
    """Ctrl-C once a stage runs on the two workers (the local cluster starts its workers
    before any stage): exit 130, nothing half written, and nothing left in the command's
    process group. (Ctrl-C inside the NMPC checks, where CasADi swallows it, is tested in
    ``test_studies_reproduce.py`` from the quick run's cache.)"""
    out = tmp_path / "paper"
    p = start("reproduce", "--quick", "--jobs", "2", "--out", str(out))
    assert wait_for(_stage_started(out)), p.communicate()[0]
    kids = descendants(p)
    interrupt(p)
    text, _ = p.communicate(timeout=120)
    assert p.returncode == 130, text
    assert "interrupted" in text and "Traceback" not in text
    assert not (out / "report.html").exists() and not (out / "summary.json").exists()
    assert hidden(out) == []
    assert wait_for(lambda: not alive(kids), 30), alive(kids)
    assert wait_for(lambda: not _group(p.pid), 15), _group(p.pid)


def test_killed_run_takes_its_workers_along_and_the_next_run_cleans_up(tmp_path):
    from acid.outdir import claim

    out = tmp_path / "paper"
    p = start("reproduce", "--quick", "--jobs", "2", "--out", str(out))
    assert wait_for(_stage_started(out)), p.communicate()[0]
    assert wait_for(lambda: len(descendants(p)) >= 2, 60)
    # a second run into the same folder is refused while the first holds it
    q = start("reproduce", "--quick", "--jobs", "1", "--out", str(out))
    text, _ = q.communicate(timeout=120)
    assert q.returncode == 2, text
    assert text.strip().startswith("error: ") and len(text.strip().splitlines()) == 1
    assert f"in use by acid reproduce (pid {p.pid}" in text
    kids = descendants(p)
    p.kill()
    p.communicate(timeout=60)  # returns: no worker holds the pipes open
    assert wait_for(lambda: not alive(kids), 30), alive(kids)
    assert hidden(out)  # the killed run's stage folders ...
    with claim(out, "acid reproduce"):  # ... are removed when the next run takes the folder
        assert hidden(out) == []


@pytest.mark.parametrize("when, group", [("cluster-starting", False),
                                         ("workers-up", True)])
def test_sigterm_with_two_jobs_is_one_quiet_line(tmp_path, when, group):
    """SIGTERM while the local Dask cluster starts (a worker process exists, the cluster is
    not up: Dask's exit handler used to print a 20-line traceback) or once both workers run
    (the whole process group: workers used to print 'interrupted' each): exit 143 and one
    line. Waits on process state, never on a fixed sleep."""
    import os
    import signal

    out = tmp_path / "paper"
    p = start("reproduce", "--quick", "--jobs", "2", "--out", str(out))
    n = 1 if when == "cluster-starting" else 2
    assert wait_for(lambda: len(descendants(p)) >= n or p.poll() is not None, 120)
    kids = descendants(p)
    if group:
        os.killpg(p.pid, signal.SIGTERM)
    else:
        p.send_signal(signal.SIGTERM)
    text, _ = p.communicate(timeout=120)
    assert p.returncode == 143, text
    lines = [ln for ln in text.splitlines() if ln.strip()]
    assert lines == ["interrupted: stopped, no partial output was kept"], text
    assert wait_for(lambda: not alive(kids), 30), alive(kids)
    assert not (out / "summary.json").exists()


def test_a_scheduler_port_that_refuses_is_one_line_before_any_client(tmp_path, monkeypatch):
    """A ``--scheduler`` address where nothing listens is refused at once, before any Dask
    client (which retries a refused address for its whole 10 s timeout) and before OUT."""
    import socket

    import distributed
    from _cli import assert_one_line_error
    from typer.testing import CliRunner

    from acid_cli.main import app

    def no_client(*args, **kwargs):
        raise AssertionError("a Dask client was started for a refused address")

    monkeypatch.setattr(distributed, "Client", no_client)
    with socket.socket() as s:   # a port that was free a moment ago: nothing listens there
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "r"
    res = CliRunner().invoke(app, ["reproduce", "--quick", "--out", str(out),
                                   "--scheduler", f"tcp://127.0.0.1:{port}"])
    assert res.exit_code == 2, res.output
    assert_one_line_error(res, "--scheduler", f"127.0.0.1:{port}", "connection refused")
    assert not out.exists()
