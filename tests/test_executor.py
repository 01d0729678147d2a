"""Where parallel work runs: the in-process executor's order and errors, progress messages,
and Ctrl-C that survives CasADi (which swallows KeyboardInterrupt inside a solve)."""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap

import pytest

from acid.executor import InlineExecutor, check_interrupt, interrupt_guard, open_executor


def add(a, b):
    return a + b


def fail(msg):
    raise ValueError(msg)


def test_inline_runs_lazily_in_order_and_passes_results_on():
    ex = InlineExecutor()
    calls = []
    a = ex.submit(lambda: calls.append("a") or 1)
    b = ex.submit(add, a, 10)
    assert calls == []  # nothing runs until waited for
    assert ex.wait_any([b]) == [b] and calls == ["a"]
    assert ex.result(b) == 11 and ex.result(a) == 1


def test_inline_errors_come_back_from_result_and_from_dependents():
    ex = InlineExecutor()
    bad = ex.submit(fail, "broken")
    dep = ex.submit(add, bad, 1)
    assert ex.wait_any([dep]) == [dep]
    for h in (bad, dep):
        with pytest.raises(ValueError, match="broken"):
            ex.result(h)


def test_progress_reaches_the_callback_in_this_process():
    seen = []
    with open_executor(1) as ex:
        report = ex.reporter(lambda *m: seen.append(m))
        h = ex.submit(lambda: [report("stage", i, 3) for i in range(1, 4)])
        ex.wait_any([h])
        ex.pump()
    assert seen == [("stage", 1, 3), ("stage", 2, 3), ("stage", 3, 3)]


def test_guard_remembers_the_interrupt_and_keeps_the_handler_in_place():
    """The CLI's own handler still decides; the flag outlives a swallowed interrupt."""
    calls = []

    def outer(signum, frame):
        calls.append(signum)
        raise KeyboardInterrupt

    prev = signal.signal(signal.SIGINT, outer)
    try:
        with interrupt_guard():
            with pytest.raises(KeyboardInterrupt):
                signal.raise_signal(signal.SIGINT)
            assert calls == [signal.SIGINT]
            with pytest.raises(KeyboardInterrupt):  # e.g. after CasADi swallowed the first
                check_interrupt()
        check_interrupt()  # cleared when the guard ends
        assert signal.getsignal(signal.SIGINT) is outer
    finally:
        signal.signal(signal.SIGINT, prev)


LOOP = textwrap.dedent("""
    import os, signal, threading
    import numpy as np
    from acid.executor import check_interrupt, interrupt_guard
    from acid.control.nmpc import NMPC, NMPCConfig
    from acid.models.params import paper
    from acid.units import C2K
    mpc = NMPC(paper(), NMPCConfig())
    x, ub = np.array([C2K(30.0), C2K(10.0)]), np.full(7, C2K(24.0))
    guard = len(os.sys.argv) > 1
    solves = 0
    threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
    try:
        with interrupt_guard() if guard else open(os.devnull):
            for solves in range(1, 20001):
                mpc.solve(x, ub, C2K(30.0), C2K(33.0))
                if guard:
                    check_interrupt()
        print("finished", solves)
    except KeyboardInterrupt:
        print("interrupted", solves)
""")


@pytest.mark.slow
def test_ctrl_c_stops_a_casadi_loop_under_the_guard():
    """Without the guard CasADi swallows SIGINT and the loop finishes (measured: 3000
    solves ran through a Ctrl-C); with it the loop stops at the next check."""

    def run(*args):
        out = subprocess.run([sys.executable, "-c", LOOP, *args], capture_output=True,
                             text=True, timeout=300,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        return out.stdout.split()

    state, solves = run("guard")
    assert state == "interrupted" and int(solves) < 20000
