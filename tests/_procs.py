"""Helpers for tests that interrupt or kill acid commands (imported as ``from _procs ...``).

Commands start in their own session (as a terminal's foreground job would), with SIGINT at
its default (the test runner may have inherited it ignored), so that ``interrupt`` sends
SIGINT to the whole process group, as Ctrl-C does.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import threading
import time

import psutil


def start(*args: str) -> subprocess.Popen:
    """``acid ARGS`` in a new session, stdout and stderr piped together."""
    exe = shutil.which("acid") or os.path.join(os.path.dirname(sys.executable), "acid")
    return subprocess.Popen([exe, *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


#: how long a test waits for a command's progress (a stage started, a scenario finished) by
#: default: a wait ends as soon as its condition holds, so this only bounds a run that never
#: gets there. Generous on purpose: at load 20 on 2 cores ``acid reproduce --quick`` reaches
#: its NMPC stage after several minutes, and a 120 s wait failed a test that had done nothing
#: wrong.
PROGRESS_TIMEOUT_S = 900.0


def wait_for(condition, timeout: float = PROGRESS_TIMEOUT_S) -> bool:
    """Poll ``condition()`` every 50 ms until it is true (True) or ``timeout`` s (False)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if condition():
            return True
        time.sleep(0.05)
    return False


def descendants(proc: subprocess.Popen) -> list[psutil.Process]:
    """Every process below ``proc`` now."""
    try:
        return psutil.Process(proc.pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []


def alive(procs) -> list[int]:
    """Pids of ``procs`` still running (zombies count as ended)."""
    out = []
    for p in procs:
        try:
            if p.is_running() and p.status() != psutil.STATUS_ZOMBIE:
                out.append(p.pid)
        except psutil.NoSuchProcess:
            pass
    return out


def dead_pid() -> int:
    """The process id of a process that has ended (for stale temporary-file names)."""
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def output_until_exit(proc: subprocess.Popen, timeout: float = PROGRESS_TIMEOUT_S) -> str:
    """Wait for ``proc`` itself to exit (not for its output pipe to close) and return what
    it wrote. ``communicate()`` waits for the pipe's end, which a process the command left
    behind holds open: the wait would last as long as that process, which then ends before
    any check of what was left."""
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True)
    reader.start()
    proc.wait(timeout=timeout)
    reader.join(2.0)   # the rest of the output, unless a leftover holds the pipe
    return "".join(lines)


def group_left(pgid: int) -> list[str]:
    """Command lines of the live (non-zombie) processes of process group ``pgid`` (a command
    started by :func:`start` leads its own group: its pid), children re-parented to init
    when their parent ended included."""
    left = []
    for p in psutil.process_iter():
        try:
            if os.getpgid(p.pid) == pgid and p.status() != psutil.STATUS_ZOMBIE:
                left.append(" ".join(p.cmdline())[:120])
        except (psutil.Error, ProcessLookupError, PermissionError):
            pass
    return left


def interrupt(proc: subprocess.Popen) -> None:
    """Ctrl-C: SIGINT to the command's whole process group."""
    os.killpg(proc.pid, signal.SIGINT)


def hidden(folder) -> list[str]:
    """Hidden temporaries (``.*.part`` files, ``.*.tmp`` folders) left below ``folder``."""
    from pathlib import Path

    return sorted(str(p) for p in Path(folder).rglob(".*")
                  if p.name.endswith((".part", ".tmp")))
