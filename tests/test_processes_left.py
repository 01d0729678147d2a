"""No child process outlives its command: Dask workers and whatever they start are gone after
a sweep or a pipeline ends, whether it succeeded or a scenario or stage raised (stopped
sweeps: ``test_sweep_cli.py`` and ``test_reliability_round4.py``).

The commands run in their own session (as a terminal's foreground job), so every process they
start is in their process group unless it leaves it on purpose; after the command exits the
test counts the live processes of that group (psutil), which also finds children that were
re-parented to init when their parent ended. The in-process pipeline runs count the children
of the test process itself before and after.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import psutil
import pytest
from _procs import output_until_exit, wait_for

from acid.pipeline import Stage, run_pipeline

pytest.importorskip("distributed")

TESTS = Path(__file__).resolve().parent
#: two short constant-speed scenarios (one raises with the fragile controller at 40 degC)
SPEC = ('title = "procs"\nplugins = ["_sweep_plugin"]\n'
        '[defaults]\ncycle = 12.0\nduration_s = {duration}\nwarmup_s = 30.0\ntail_s = 0.0\n'
        '[grid]\nambient_C = [30.0, {hot}]\n[controllers.nmpc]\n[controllers.fragile]\n'
        'above_C = 40.0\n')


def _start(*args: str) -> subprocess.Popen:
    """``acid ARGS`` in a new session (own process group), SIGINT at its default, with the
    tests folder on the path (the spec's plugin)."""
    exe = os.path.join(os.path.dirname(sys.executable), "acid")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(TESTS), *filter(None, [os.environ.get("PYTHONPATH")])])}
    return subprocess.Popen([exe, *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, start_new_session=True, env=env,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def group(pgid: int) -> list[psutil.Process]:
    """Live (non-zombie) processes of process group ``pgid``."""
    out = []
    for p in psutil.process_iter():
        try:
            if os.getpgid(p.pid) == pgid and p.status() != psutil.STATUS_ZOMBIE:
                out.append(p)
        except (psutil.Error, ProcessLookupError, PermissionError):
            pass
    return out


def _left(pgid: int, timeout: float = 15.0) -> list[str]:
    """What is still running in the group after ``timeout`` s (empty: nothing left)."""
    wait_for(lambda: not group(pgid), timeout)
    left = []
    for p in group(pgid):
        try:
            left.append(" ".join(p.cmdline())[:120])
        except psutil.Error:       # ended between the listing and the reading
            pass
    return left


@pytest.mark.slow
@pytest.mark.parametrize("how", ["success", "failure"])
def test_acid_sweep_leaves_no_process(tmp_path, how):
    """A sweep on two worker processes that succeeds, or in which a scenario raises, leaves
    no process of its group. That the workers ran is read from the command's own report
    ("2 worker processes (local cluster)"), not from catching them alive: the scenarios
    take a fraction of a second, and on a busy machine a poll may miss them. (Stopped by
    Ctrl-C: ``test_sweep_cli.py::test_ctrl_c_keeps_finished_scenarios_and_the_rerun_resumes``;
    by SIGTERM or SIGINT to the command alone: ``test_reliability_round4.py``.)"""
    spec = tmp_path / "procs.toml"
    spec.write_text(SPEC.format(hot=41.0 if how == "failure" else 35.0, duration=60.0))
    p = _start("sweep", str(spec), "--out", str(tmp_path / "out"), "--jobs", "2",
               "--no-figures")
    text = output_until_exit(p)
    assert p.returncode == 0, text
    assert "2 worker processes (local cluster)" in text, text
    if how == "failure":
        assert "too hot for this controller" in text
    assert _left(p.pid) == []


# ``acid reproduce`` interrupted by Ctrl-C with two workers: the same group check is in
# ``test_studies_reproduce_interrupts.py::test_ctrl_c_exits_130_with_nothing_half_written``
# (one run of the command serves both)


# --------------------------------------------------------- the pipeline, in this process
def tiny(workdir, inputs, config, progress):
    (workdir / "x.txt").write_text(str(config["x"]))
    progress(1, 1)
    return {"x": config["x"]}


def raising(workdir, inputs, config, progress):
    raise RuntimeError("this stage fails")


def _children() -> set[int]:
    """Live children of this process, multiprocessing's resource tracker aside (it serves the
    interpreter, not a run, and ends with it)."""
    from multiprocessing import resource_tracker

    tracker = getattr(resource_tracker._resource_tracker, "_pid", None)
    out = set()
    for c in psutil.Process().children(recursive=True):
        try:
            if c.pid != tracker and c.status() != psutil.STATUS_ZOMBIE:
                out.add(c.pid)
        except psutil.Error:
            pass
    return out


@pytest.mark.parametrize("fail", [False, True])
def test_pipeline_on_two_workers_leaves_no_process(tmp_path, fail):
    stages = [Stage("a", "a", tiny, {"x": 1}), Stage("b", "b", tiny, {"x": 2}),
              Stage("c", "c", raising if fail else tiny, {"x": 3}, depends=("a",))]
    before = _children()
    if fail:
        with pytest.raises(RuntimeError, match="this stage fails"):
            run_pipeline(stages, tmp_path / "out", jobs=2)
    else:
        outcomes = run_pipeline(stages, tmp_path / "out", jobs=2)
        assert [outcomes[k].summary["x"] for k in "abc"] == [1, 2, 3]
    assert wait_for(lambda: _children() <= before, 15), _children() - before
