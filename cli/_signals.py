"""Interrupts (Ctrl-C, SIGTERM) in the CLI: stop promptly, exit 130, keep nothing partial.

* During start-up (imports, before a command runs) SIGINT or SIGTERM exits at once and
  quietly with 130 / 143: nothing has been written yet.
* While a command runs, the first SIGINT or SIGTERM raises ``KeyboardInterrupt`` in the main
  thread, so every ``acid._io.atomic_path`` removes its temporary file and the command ends
  with 128 + the signal number (130 for Ctrl-C); a second signal leaves at once (a temporary
  file left then is removed by the next write into that folder).
* A run started as a background job of a non-interactive shell inherits SIGINT *ignored*
  (POSIX job control), so Python would never see Ctrl-C or ``kill -INT``: acid takes SIGINT
  back. This was why ``acid excite`` sometimes finished and exited 0 after Ctrl-C.
* After the command, the process ends through :func:`finish`, not through the interpreter's
  own shutdown: that one puts every signal back to its default action before it tears the
  modules down (most of a second with Dask, pandas and CasADi loaded), so a signal landing
  then killed the process (return code -2 / -15) instead of exiting 130 / 143.
  :func:`finish` joins the threads and runs the exit handlers as the interpreter would, with
  its own handlers still in place, and leaves by ``os._exit``: a signal is an exit code
  whenever it lands.
"""

from __future__ import annotations

import atexit
import os
import signal
import sys
import threading
from typing import NoReturn

HANDLED = (signal.SIGINT, signal.SIGTERM)
_startup_saved: dict[int, object] = {}
#: the signal the running command's guard received (None: none yet)
_pending: dict[str, int | None] = {"signum": None}
#: the signal that arrived while :func:`finish` ended the process (None: none did)
_at_exit: dict[str, int | None] = {"signum": None}


def _in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _flush() -> None:
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:  # noqa: BLE001 - a closed pipe must not stop the exit
            pass


def raise_if_interrupted() -> None:
    """``KeyboardInterrupt`` if the running command's guard received SIGINT / SIGTERM. The
    CLI's progress reports call it: a library that swallowed the first ``KeyboardInterrupt``
    (CasADi evaluated inside SciPy's ``least_squares``: ``acid car validate`` ran on to the
    end and exited 0) stops at its next report."""
    if _pending["signum"] is not None:
        raise KeyboardInterrupt


def _note_interrupt() -> None:
    """Tell acid's closed loops (``acid.executor.check_interrupt``) that a signal arrived."""
    executor = sys.modules.get("acid.executor")  # not imported: no loop can be waiting on it
    if executor is not None:
        executor.note_interrupt()


def _exit_now(signum: int, frame=None) -> None:
    _flush()
    try:
        os.write(2, b"interrupted\n")
    except OSError:
        pass
    os._exit(128 + signum)


def exit_interrupted() -> NoReturn:
    """Leave quietly after a Ctrl-C that no command's guard received: 130, one line (the
    exit handlers still run, see :func:`finish`; another signal leaves at once)."""
    _install_exit_handlers()
    _at_exit["signum"] = signal.SIGINT
    _flush()
    try:
        os.write(2, b"interrupted\n")
    except OSError:
        pass
    finish(128 + signal.SIGINT)


def _in_worker_process() -> bool:
    """True while a process that multiprocessing spawned from acid (a Dask worker) imports
    the ``acid`` script as ``__mp_main__`` (its ``sys.argv`` is then the parent's): its
    signals are its parent's business, and it must not print ``interrupted`` when the parent
    ends it. (In the parent, ``__mp_main__`` is ``__main__`` itself, or absent.)"""
    mp_main = sys.modules.get("__mp_main__")
    return mp_main is not None and mp_main is not sys.modules.get("__main__")


def begin_startup() -> None:
    """Exit quietly (128 + signal: 130, 143) on SIGINT or SIGTERM while the CLI is importing
    its modules (seconds on a busy machine). Not in a worker process (``_in_worker_process``)."""
    if not _in_main_thread() or _in_worker_process():
        return
    for sig in HANDLED:
        try:
            _startup_saved[sig] = signal.signal(sig, _exit_now)
        except (ValueError, OSError):
            pass


def end_startup() -> None:
    """Restore the previous SIGINT handler, taking SIGINT back if it was ignored.

    SIGTERM keeps the quiet exit (143) when its previous action was the default one (which
    would kill the process silently with -15): the short gap between start-up and a
    command's ``InterruptGuard`` then also exits cleanly, and the guard restores it after."""
    for sig in HANDLED:
        if sig not in _startup_saved:
            continue
        previous = _startup_saved.pop(sig)
        if sig == signal.SIGINT:
            if previous in (signal.SIG_IGN, None):
                previous = signal.default_int_handler
        elif previous in (signal.SIG_DFL, None):
            continue
        signal.signal(sig, previous)


class InterruptGuard:
    """Context manager turning SIGINT/SIGTERM into ``KeyboardInterrupt`` for one command.

    ``exit_code`` is 128 + the number of the signal received (130 when none was: a
    ``KeyboardInterrupt`` raised some other way). Previous handlers are restored on exit, so
    the guard is harmless in tests that call commands in-process.
    """

    def __init__(self) -> None:
        self.signum: int | None = None
        self._count = 0
        self._saved: dict[int, object] = {}
        self._pid = os.getpid()
        self._hook = None

    @property
    def exit_code(self) -> int:
        return 128 + (self.signum or signal.SIGINT)

    def _handler(self, signum: int, frame) -> None:
        if os.getpid() != self._pid:  # a forked child: behave as if we were not here
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)
            return
        self._count += 1
        self.signum = _pending["signum"] = signum
        if self._count > 1:
            _exit_now(signum)
        _note_interrupt()  # a solver that swallows the KeyboardInterrupt: its loop's next step
        raise KeyboardInterrupt

    def __enter__(self) -> InterruptGuard:
        if _in_main_thread():
            for sig in HANDLED:
                try:
                    self._saved[sig] = signal.signal(sig, self._handler)
                except (ValueError, OSError):
                    pass
            # a signal landing in a callback Python cannot raise from (a weakref or __del__
            # during shutdown) is "ignored" with a traceback: keep the note, drop the trace
            self._hook = sys.unraisablehook
            sys.unraisablehook = self._unraisable
        return self

    def _unraisable(self, unraisable) -> None:
        if isinstance(unraisable.exc_value, KeyboardInterrupt):
            return
        (self._hook or sys.__unraisablehook__)(unraisable)

    @property
    def installed(self) -> bool:
        """Whether this guard's handlers catch SIGINT/SIGTERM (the main thread only)."""
        return bool(self._saved)

    def __exit__(self, *exc) -> None:
        for sig, previous in self._saved.items():
            if previous is None:
                previous = signal.SIG_DFL
            try:
                signal.signal(sig, previous)
            except (ValueError, OSError):
                pass
        if self._saved:
            _pending["signum"] = None
        self._saved.clear()
        executor = sys.modules.get("acid.executor")
        if self.signum is not None and executor is not None:
            executor.clear_interrupt()  # the next command (in-process callers) starts afresh
        if self._hook is not None:
            sys.unraisablehook = self._hook
            self._hook = None


# ------------------------------------------------------------------------------ the end
def _end_children() -> None:
    """SIGKILL the child processes multiprocessing still tracks (a Dask cluster's workers
    whose closing was under way), so nothing waits for them and none outlives the exit."""
    mp = sys.modules.get("multiprocessing")
    if mp is None:
        return
    try:
        children = mp.active_children()
    except Exception:  # noqa: BLE001 - the exit must go on
        return
    for child in children:
        try:
            child.kill()
        except Exception:  # noqa: BLE001, S110 - already gone
            pass


def _signal_at_exit(signum: int, frame) -> None:
    """A signal while :func:`finish` runs: the exit code becomes 128 + ``signum`` and the
    children still tracked are killed, so the joins left return at once; a second signal
    leaves at once."""
    if _at_exit["signum"] is not None:
        _flush()
        os._exit(128 + signum)
    _at_exit["signum"] = signum
    try:
        os.write(2, b"interrupted (while exiting: the command had ended)\n")
    except OSError:
        pass
    _end_children()


def _install_exit_handlers() -> None:
    """SIGINT / SIGTERM from now on: :func:`_signal_at_exit` (a SIGTERM the caller ignores
    stays ignored). The first thing the process does once its command is over."""
    if not _in_main_thread():
        return
    for sig in HANDLED:
        try:
            if sig == signal.SIGINT or signal.getsignal(sig) is not signal.SIG_IGN:
                signal.signal(sig, _signal_at_exit)
        except (ValueError, OSError):
            pass


def finish(code: object = 0) -> NoReturn:
    """End this process with ``code`` (a ``SystemExit`` code: None, an int or a message),
    or with 128 + the number of a SIGINT / SIGTERM landing meanwhile.

    What the interpreter does at exit, in its order, while this module's handler stays
    installed: the non-daemon threads are joined (and ``threading``'s own exit calls run),
    then the ``atexit`` handlers (multiprocessing ends its children there, Dask its
    clusters, acid its temporary folders), the standard streams are flushed, and the
    process ends by ``os._exit``, skipping the module teardown (nothing of acid's is left
    to it: every output was written by an atomic rename before the command returned).
    Only for the ``acid`` process itself (the console script), never in a library call.
    """
    _install_exit_handlers()
    if isinstance(code, str):
        try:
            sys.stderr.write(code + "\n")
        except Exception:  # noqa: BLE001, S110 - a closed stream must not stop the exit
            pass
        code = 1
    elif code is None:
        code = 0
    elif not isinstance(code, int):
        code = 1
    if _in_main_thread():
        try:
            stop_threads = getattr(threading, "_shutdown", None)
            if stop_threads is not None:
                stop_threads()
        except Exception:  # noqa: BLE001, S110 - as at the interpreter's exit: go on
            pass
        atexit._run_exitfuncs()
    _flush()
    signum = _at_exit["signum"]
    os._exit(128 + signum if signum is not None else code)
