"""Where acid's parallel work runs: in this process, or on a Dask cluster.

One abstraction serves ``acid reproduce`` (its stages) and ``acid sweep`` (its scenarios):

* :class:`InlineExecutor` runs each task in this process, one at a time, when the caller
  waits for it (``--jobs 1``; also what runs when Dask is not installed);
* :class:`DaskExecutor` runs tasks on Dask distributed: a ``LocalCluster`` of worker
  *processes* started here (one thread each, so CasADi, CoolProp and numpy never share an
  interpreter), or an existing cluster given by its scheduler address.

Both give the same small interface: ``submit(fn, *args)`` returns a handle (handles of
earlier tasks may be passed as arguments: the task then waits for them and receives their
results), ``wait_any(handles, timeout)`` returns the handles that finished, ``result(h)``
their value or raises their exception, and ``reporter(on_event)`` a picklable callable that
a task calls with progress messages, delivered to ``on_event`` in the waiting thread.

Interrupts and process lifetime
-------------------------------
* **Ctrl-C.** CasADi's solvers swallow ``KeyboardInterrupt`` (the solve simply returns), so
  a closed loop can run on through Ctrl-C. While an executor is open, SIGINT sets a flag as
  well as raising; :func:`check_interrupt` (called by every progress report, so once per
  closed-loop step) raises again where it is safe to. A second Ctrl-C ends the process at
  once (exit 130); what it leaves is hidden and removed by the next run
  (:mod:`acid.outdir`). Worker processes of a local cluster ignore SIGINT: the terminal
  sends it to the whole process group, and the parent, not each worker, decides to stop.
* **Workers end with their parent.** The cluster is closed in ``finally``; if the parent is
  killed outright (SIGKILL), every Dask worker process exits within milliseconds (each
  watches a pipe from its parent and calls ``os._exit`` when it closes, see
  ``distributed.process.AsyncProcess``), so nothing keeps the caller's pipes open.
"""

from __future__ import annotations

import abc
import contextlib
import logging
import os
import queue
import re
import signal
import threading
import time
import uuid
import warnings
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field

from acid.errors import AcidError, ConfigError

#: how often a task may send a progress message to the client, s (the last one always goes)
PROGRESS_INTERVAL_S = 0.25

_interrupted = threading.Event()
_guard_depth = [0]
#: topic -> callback for reporters whose events stay in this process (inline tasks)
_local_sinks: dict[str, Callable] = {}


def dask_available() -> bool:
    """True when ``dask.distributed`` can be imported (the ``distributed`` extra)."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True


def usable_cores() -> int:
    """Cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


# ------------------------------------------------------------------------------ interrupts
def check_interrupt() -> None:
    """Raise ``KeyboardInterrupt`` if Ctrl-C was pressed (even if a C extension swallowed it)."""
    if _interrupted.is_set():
        raise KeyboardInterrupt


def note_interrupt() -> None:
    """Record that Ctrl-C or SIGTERM arrived (the CLI's handler calls this), so that
    :func:`check_interrupt` raises from now on, with or without an open executor: a closed
    loop whose solver swallowed the ``KeyboardInterrupt`` stops at its next step."""
    _interrupted.set()


def clear_interrupt() -> None:
    """Forget a recorded interrupt (the CLI's guard, when its command has ended)."""
    _interrupted.clear()


def _chained(previous):
    """A handler that remembers the interrupt, then does what ``previous`` did."""

    def handler(signum, frame):
        first = not _interrupted.is_set()
        _interrupted.set()
        if callable(previous) and previous is not signal.default_int_handler:
            return previous(signum, frame)  # e.g. the CLI's guard (exit code, second signal)
        if not first:  # the first interrupt was not honoured in time: stop now
            with contextlib.suppress(OSError):
                os.write(2, b"interrupted (forced)\n")
            os._exit(128 + signum)
        raise KeyboardInterrupt

    return handler


@contextlib.contextmanager
def interrupt_guard() -> Iterator[None]:
    """Interrupts that survive C extensions: see the module docstring (re-entrant).

    SIGINT (and SIGTERM when a Python handler already catches it) additionally set the flag
    that :func:`check_interrupt` reads; the handler found in place still runs (the CLI's
    guard decides the exit code and what a second signal does). Nothing is installed outside
    the main thread or for a signal that is ignored or at its default (``nohup``, a
    background job of a non-interactive shell): that choice of the caller is kept.
    """
    saved = {}
    if _guard_depth[0] == 0 and threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            current = signal.getsignal(sig)
            if callable(current):
                saved[sig] = signal.signal(sig, _chained(current))
    _guard_depth[0] += 1
    try:
        yield
    finally:
        _guard_depth[0] -= 1
        for sig, previous in saved.items():
            signal.signal(sig, previous)
        if saved:
            _interrupted.clear()


# ------------------------------------------------------------------------------ progress
@dataclass
class ProgressReporter:
    """Picklable progress callback of a task: ``reporter(*message)``.

    In this process it calls the executor's sink directly (and checks for Ctrl-C); on a Dask
    worker it sends the message to the client as a worker event on ``topic``, at most every
    ``PROGRESS_INTERVAL_S`` seconds unless ``final`` is True.
    """

    topic: str
    _last: float = field(default=0.0, repr=False)

    def __call__(self, *message, final: bool = False) -> None:
        check_interrupt()
        sink = _local_sinks.get(self.topic)
        if sink is not None:
            sink(message)
            return
        now = time.monotonic()
        if not final and now - self._last < PROGRESS_INTERVAL_S:
            return
        self._last = now
        try:
            from distributed import get_worker

            get_worker().log_event(self.topic, message)
        except (ImportError, ValueError):  # not on a worker: nobody listens
            pass


# ------------------------------------------------------------------------------ executors
class Executor(abc.ABC):
    """Interface shared by :class:`InlineExecutor` and :class:`DaskExecutor`.

    Attributes
    ----------
    kind : ``"inline"``, ``"local"`` (a LocalCluster started here) or ``"cluster"``.
    workers : number of worker processes (1 for inline).
    address : scheduler address (None inline).
    """

    kind: str = "inline"
    workers: int = 1
    address: str | None = None

    def __init__(self):
        self._events: queue.SimpleQueue = queue.SimpleQueue()
        self._topics: list[str] = []

    def reporter(self, on_event: Callable[..., None], topic: str = "run") -> ProgressReporter:
        """A progress callback for tasks: ``reporter(*message)`` on the task side ends up as
        ``on_event(*message)`` in this process (at once inline; at the next :meth:`pump`
        for Dask workers, so always in the thread that waits for the tasks)."""
        topic = f"acid-progress-{topic}-{uuid.uuid4().hex[:8]}"
        self._topics.append(topic)
        self._listen(topic, on_event)
        return ProgressReporter(topic)

    def pump(self) -> None:
        """Deliver the progress messages that arrived from workers (no-op inline)."""
        while True:
            try:
                on_event, message = self._events.get_nowait()
            except queue.Empty:
                return
            on_event(*message)

    def describe(self) -> str:
        """One line for the user: where the work runs."""
        if self.kind == "inline":
            return "in this process"
        where = "local cluster" if self.kind == "local" else f"cluster {self.address}"
        return f"{self.workers} worker process{'es' if self.workers != 1 else ''} ({where})"

    # what each executor provides
    @abc.abstractmethod
    def _listen(self, topic: str, on_event: Callable) -> None:
        """Call ``on_event(payload)`` for every event a task publishes on ``topic``."""

    @abc.abstractmethod
    def submit(self, fn: Callable, *args):
        """Start ``fn(*args)``; returns a handle."""

    @abc.abstractmethod
    def wait_any(self, handles: Iterable, timeout: float = 0.2) -> list:
        """The handles of ``handles`` that finished, waiting at most ``timeout`` s."""

    @abc.abstractmethod
    def result(self, handle):
        """The return value of a finished task (its exception is raised)."""

    def close(self, interrupted: bool = False) -> None:  # noqa: B027 - nothing to release by default
        """Release workers (an interrupted run does not wait for running tasks)."""

    def close_soon(self) -> None:  # noqa: B027 - nothing to release by default
        """Start releasing the workers in the background: every task's result is in and no
        task will be submitted again. The caller goes on (writes its results) meanwhile;
        :meth:`close` (which the ``with`` block calls in any case) waits for it to end."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(interrupted=exc_type is KeyboardInterrupt)


class _InlineTask:
    __slots__ = ("fn", "args", "done", "value", "error")

    def __init__(self, fn, args):
        self.fn, self.args = fn, args
        self.done, self.value, self.error = False, None, None


class InlineExecutor(Executor):
    """Runs tasks in this process, one at a time, in submission order, when waited for."""

    def __init__(self):
        super().__init__()
        self._pending: list[_InlineTask] = []

    def _listen(self, topic: str, on_event: Callable) -> None:
        _local_sinks[topic] = lambda message: on_event(*message)

    def submit(self, fn: Callable, *args) -> _InlineTask:
        task = _InlineTask(fn, args)
        self._pending.append(task)
        return task

    def _run(self, task: _InlineTask) -> None:
        try:
            args = []
            for a in task.args:
                if isinstance(a, _InlineTask):
                    if not a.done:
                        self._run(a)
                    a = self.result(a)  # a failed dependency fails this task too
                args.append(a)
            task.value = task.fn(*args)
        except Exception as exc:  # the caller decides (result re-raises)
            task.error = exc
        task.done = True
        if task in self._pending:
            self._pending.remove(task)

    def wait_any(self, handles: Iterable, timeout: float = 0.2) -> list:
        handles = list(handles)
        done = [h for h in handles if h.done]
        if done or not handles:
            return done
        self._run(handles[0])
        return [handles[0]]

    def result(self, handle: _InlineTask):
        if handle.error is not None:
            raise handle.error
        return handle.value

    def close(self, interrupted: bool = False) -> None:
        self._pending.clear()
        for t in self._topics:
            _local_sinks.pop(t, None)


def workers_skip_main() -> None:
    """Worker processes started from now on do not run this process's ``__main__`` again.

    A worker of a local cluster is a new interpreter (multiprocessing's ``spawn``), which
    re-runs the parent's main script so that functions defined there can be found. For
    ``acid``'s console script that means importing the whole command-line interface (Typer,
    Rich, every command: about 1 CPU-s per worker, measured) for tasks that never use it.
    Call this only from a main that defines nothing a task needs (the CLI): it names the main
    module like ``python -m acid_cli`` would, which multiprocessing does not re-run.
    """
    import importlib.machinery
    import sys

    main = sys.modules.get("__main__")
    if main is not None and getattr(main, "__spec__", None) is None:
        main.__spec__ = importlib.machinery.ModuleSpec("acid_cli.__main__", None)


_server = {"started": False}


def start_worker_server(preload: Iterable[str]) -> bool:
    """Start now, once per process, the server that local-cluster workers are forked from,
    with ``preload`` (module names) imported in it; True if it runs.

    Without it each worker is a new interpreter that imports Dask and, at its first task,
    acid and CasADi (about 0.7 CPU-s a worker, measured). The server imports them once, in
    parallel with what this process still does before its cluster starts (reading the
    specification, its own imports), and every worker is a fork of it, ready at once.
    Afterwards every :class:`DaskExecutor` of this process starts its workers from it.
    Nothing is started (False) where ``fork`` is not available or outside the main thread.

    The server is multiprocessing's ``forkserver`` (one thread, so forking it is safe); it
    ignores Ctrl-C (so do the workers: the parent decides) and ends when this process does.
    Dask's environment for worker processes (one BLAS thread, the common hash seed) is set
    before it starts, as Dask itself would before spawning a worker.
    """
    import multiprocessing

    if _server["started"]:
        return True
    if ("forkserver" not in multiprocessing.get_all_start_methods()
            or threading.current_thread() is not threading.main_thread()):
        return False
    try:
        from multiprocessing import forkserver

        import dask
        import distributed  # noqa: F401  (its configuration defaults)
    except ImportError:
        return False
    env = {str(k): str(v) for k, v in
           (dask.config.get("distributed.nanny.pre-spawn-environ") or {}).items()}
    if os.environ.get("PYTHONHASHSEED") in (None, "0"):
        env["PYTHONHASHSEED"] = "6640"   # what Dask's nanny sets (the same on every worker)
    os.environ.update(env)
    multiprocessing.get_context("forkserver").set_forkserver_preload(
        ["distributed", *preload])
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)  # inherited by the server
    try:
        forkserver.ensure_running()
    except OSError:
        return False
    finally:
        signal.signal(signal.SIGINT, previous)
    _server["started"] = True
    return True


def _worker_server_pid() -> int | None:
    if not _server["started"]:
        return None
    from multiprocessing import forkserver

    return getattr(forkserver._forkserver, "_forkserver_pid", None)


def _ignore_sigint_plugin():
    from distributed.diagnostics.plugin import WorkerPlugin

    class IgnoreSigint(WorkerPlugin):
        """Worker processes leave Ctrl-C to the client (see the module docstring)."""

        name = "acid-ignore-sigint"

        def setup(self, worker):
            if threading.current_thread() is threading.main_thread():
                signal.signal(signal.SIGINT, signal.SIG_IGN)

    return IgnoreSigint()


def _worker_acid_version() -> str:
    from acid import __version__

    return __version__


#: Dask settings of a local cluster. Tasks are whole closed loops (seconds each, one per
#: worker at a time), so what Dask does in the background every few milliseconds is cost
#: without use: on a machine with as many workers as cores it takes CPU from the tasks
#: (measured, 2 idle workers: 0.03 CPU-s per second in the client and in each worker by
#: default, 0.003-0.006 with these). Off: the statistical profiler (samples every worker's
#: task thread every 10 ms and takes the GIL to do it), work stealing (tasks are queued on
#: the scheduler and given to a worker only when it is free: nothing to steal), and, with
#: ``memory_limit=0``, the memory monitor and spilling (a nanny polls its worker's memory
#: every 100 ms). Slower: the event-loop ticks (20 ms) and the system monitor (0.5 s)
#: only feed diagnostics.
LOCAL_CLUSTER_CONFIG = {
    "distributed.scheduler.allowed-failures": 1,
    # one task per worker at a time, the rest queued on the scheduler: a long task is never
    # parked behind another on a busy worker while one idles
    "distributed.scheduler.worker-saturation": 1.0,
    "distributed.scheduler.work-stealing": False,
    "distributed.worker.daemon": False,
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
}


_SCHEMES = ("tcp", "tls", "inproc", "ucx", "ws", "wss")
_ADDRESS = re.compile(r"^(?:(?P<scheme>[a-z]+)://)?(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9]"
                      r"(?:[A-Za-z0-9._-]{0,252}))(?::(?P<port>[0-9]{1,5}))?/?$")


def check_scheduler_address(address: str) -> str:
    """``address`` if it reads as a Dask scheduler address (``[scheme://]host[:port]``, a
    known scheme, a host name or IP, a port 1-65535), else ``ConfigError`` naming
    ``--scheduler``."""
    m = _ADDRESS.match(address) if isinstance(address, str) else None
    if m is None:
        raise ConfigError(f"--scheduler {address!r}: not a scheduler address (expected "
                          "tcp://HOST:PORT)")
    if m["scheme"] is not None and m["scheme"] not in _SCHEMES:
        raise ConfigError(f"--scheduler {address!r}: unknown scheme {m['scheme']!r} "
                          f"(known: {', '.join(_SCHEMES)})")
    if m["port"] is not None and not 1 <= int(m["port"]) <= 65535:
        raise ConfigError(f"--scheduler {address!r}: port {m['port']} outside 1..65535")
    return address


class DaskExecutor(Executor):
    """Tasks on Dask distributed: a new ``LocalCluster`` of ``workers`` processes (one
    thread each), or the existing cluster at ``address``.

    Workers of an existing cluster must have the same acid version installed (checked when
    connecting); they need not share a filesystem with this process (``acid sweep`` and
    ``acid reproduce`` send inputs with the tasks and write what comes back).
    """

    def __init__(self, workers: int | None = None, address: str | None = None):
        super().__init__()
        try:
            import dask
            from distributed import Client, LocalCluster
        except ImportError:
            raise AcidError("parallel runs need Dask: pip install 'acid[distributed]'") from None
        self.cluster = None
        self._closer: threading.Thread | None = None
        self._pids: set[int] = set()
        if address:
            check_scheduler_address(address)
            self.kind, self.address = "cluster", address
            try:
                self.client = Client(address, timeout="10s")
            except (OSError, TimeoutError, ValueError, TypeError) as exc:
                raise ConfigError(f"--scheduler {address}: cannot connect "
                                  f"({str(exc).splitlines()[0]})") from None
            except MemoryError:   # a service that is not a Dask scheduler answered
                raise ConfigError(f"--scheduler {address}: what answers there is not a Dask "
                                  "scheduler (its reply is not Dask's protocol)") from None
            self._check_versions()
        else:
            n = int(workers or usable_cores())
            if n < 1:
                raise AcidError(f"workers must be at least 1, got {n}")
            self.kind = "local"
            import multiprocessing

            from distributed.deploy.spec import SpecCluster

            before = {c.pid for c in multiprocessing.active_children()} | _os_children()
            clusters = set(SpecCluster._instances)
            try:
                method = "forkserver" if _server["started"] else "spawn"
                with dask.config.set({**LOCAL_CLUSTER_CONFIG,
                                      "distributed.worker.multiprocessing-method": method}), \
                        warnings.catch_warnings():
                    # no dashboard: its port taken by another cluster is no news
                    warnings.filterwarnings("ignore", message="Port .* is already in use")
                    with _workers_start_without_sigint():
                        self.cluster = LocalCluster(n_workers=n, threads_per_worker=1,
                                                    processes=True, dashboard_address=None,
                                                    scheduler_kwargs={"dashboard": False},
                                                    memory_limit=0,
                                                    silence_logs=logging.CRITICAL)
                        self.client = Client(self.cluster)
                self.address = self.cluster.scheduler_address
                self.client.register_plugin(_ignore_sigint_plugin())
                self._pids = set(self.client.run(os.getpid).values())
            except BaseException as exc:  # a worker died, or Ctrl-C / SIGTERM while starting
                _silence_dask_logs()
                self._abandon(before, clusters)
                if not isinstance(exc, Exception):
                    raise
                first = str(exc).splitlines()[0] if str(exc) else ""
                raise AcidError(f"the local Dask cluster of {n} worker"
                                f"{'s' * (n != 1)} did not start ({type(exc).__name__}"
                                f"{': ' + first[:200] if first else ''}); try --jobs 1") from None
        self.workers = max(1, len(self.client.scheduler_info().get("workers", {})))

    def _check_versions(self) -> None:
        from acid import __version__

        try:
            found = self.client.run(_worker_acid_version)
        except Exception as exc:  # a worker without acid cannot even unpickle the call
            raise AcidError(f"--scheduler {self.address}: workers cannot run acid "
                            f"({type(exc).__name__}: {str(exc).splitlines()[0]})") from None
        if not found:
            raise AcidError(f"--scheduler {self.address}: the cluster has no workers")
        bad = {w: v for w, v in found.items() if v != __version__}
        if bad:
            w, v = next(iter(bad.items()))
            raise AcidError(f"--scheduler {self.address}: worker {w} has acid {v}, this is "
                            f"acid {__version__}")

    def _listen(self, topic: str, on_event: Callable) -> None:
        # the handler runs on the client's event-loop thread: queue for pump()
        self.client.subscribe_topic(topic, lambda ev: self._events.put((on_event, ev[1])))

    def submit(self, fn: Callable, *args):
        return self.client.submit(fn, *args, pure=False)

    def wait_any(self, handles: Iterable, timeout: float = 0.2) -> list:
        from distributed import wait

        handles = list(handles)
        if not handles:
            return []
        try:
            done, _ = wait(handles, timeout=timeout, return_when="FIRST_COMPLETED")
        except TimeoutError:
            return []
        return [h for h in handles if h in done]

    def result(self, handle):
        return handle.result()

    def close_soon(self) -> None:
        if self.cluster is None or self._closer is not None:
            return
        self._closer = threading.Thread(target=self._close, name="acid-executor-close",
                                        daemon=True)
        self._closer.start()

    def close(self, interrupted: bool = False) -> None:
        closer = self._closer
        if closer is None:
            self._close(interrupted)
            return
        if interrupted:  # the closing under way may wait for the workers: end them now
            _silence_dask_logs()
            self._kill_workers()
        try:
            closer.join()
        except BaseException:  # Ctrl-C / SIGTERM while waiting: wait no longer for them
            _silence_dask_logs()
            self._kill_workers()
            raise
        self._kill_workers()

    def _close(self, interrupted: bool = False) -> None:
        with contextlib.suppress(Exception):
            for t in self._topics:
                self.client.unsubscribe_topic(t)
        if self.cluster is None:  # an existing cluster keeps running; it drops our tasks
            with contextlib.suppress(Exception):
                self.client.close(timeout=5)
            return
        if interrupted:  # do not wait for running tasks: end our worker processes now
            _silence_dask_logs()  # the comms we break would log tracebacks on stderr
            self._kill_workers()
        try:
            with contextlib.suppress(Exception):
                self.client.close(timeout=2 if interrupted else 10)
            with contextlib.suppress(Exception):
                self.cluster.close(timeout=2 if interrupted else 10)
        except BaseException:  # Ctrl-C / SIGTERM during an orderly close: end them now
            _silence_dask_logs()
            self._kill_workers()
            raise
        self._kill_workers()  # whatever a close that timed out left running

    def _abandon(self, before: set[int], clusters: set) -> None:
        """End what a failed or interrupted start left, quietly: the worker processes started
        since ``before`` are killed, and the clusters created since ``clusters`` are taken off
        Dask's exit handler, which would otherwise try to close a half-started cluster at
        exit and print a traceback (``AssertionError: Status.init``)."""
        import multiprocessing

        from distributed.deploy.spec import SpecCluster

        self._pids |= {c.pid for c in multiprocessing.active_children()} - before
        self._kill_workers()
        new = set(SpecCluster._instances) - clusters
        for cluster in new:  # its event loop would go on starting workers from its own thread
            with contextlib.suppress(Exception):
                cluster._loop_runner.stop()
        # a worker whose start was under way is not in multiprocessing's list yet: left alive,
        # it fails to rebuild its semaphore once this process exits and prints a traceback. The
        # starts already queued finish within a few scans; 10 s bounds a starved machine.
        quiet_since, deadline = time.monotonic(), time.monotonic() + 10.0
        while time.monotonic() - quiet_since < 0.5 and time.monotonic() < deadline:
            stray = _os_children() - before - {_resource_tracker_pid(), _worker_server_pid()}
            for pid in stray:
                with contextlib.suppress(OSError):
                    os.kill(pid, signal.SIGKILL)
            if stray:
                quiet_since = time.monotonic()
            time.sleep(0.05)
        client = getattr(self, "client", None)
        if client is not None:
            with contextlib.suppress(Exception):
                client.close(timeout=2)
        for cluster in new:
            SpecCluster._instances.discard(cluster)
            with contextlib.suppress(Exception):
                cluster.shutdown_on_close = False

    def _kill_workers(self) -> None:
        """SIGKILL the local cluster's worker processes (only children of this process)."""
        import multiprocessing

        for child in multiprocessing.active_children():
            if child.pid in self._pids:
                with contextlib.suppress(Exception):
                    child.kill()


@contextlib.contextmanager
def _workers_start_without_sigint() -> Iterator[None]:
    """Worker processes spawned meanwhile start with SIGINT blocked, so never see it.

    Ctrl-C goes to the whole process group; a worker spawned as a new interpreter took it
    while importing, before it ignores SIGINT, and printed a traceback after acid's one
    line. multiprocessing spawns every such process through ``util.spawnv_passfds`` (from
    the cluster's event-loop thread); while the cluster starts, that call blocks SIGINT
    in the calling thread for the moment of the spawn, which the new process inherits (as
    multiprocessing does itself for its resource tracker). This process's own handling of
    Ctrl-C is untouched."""
    from multiprocessing import util

    spawn = util.spawnv_passfds
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return

    def spawn_without_sigint(path, args, passfds):
        old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            return spawn(path, args, passfds)
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)

    util.spawnv_passfds = spawn_without_sigint
    try:
        yield
    finally:
        util.spawnv_passfds = spawn


def _os_children() -> set[int]:
    """PIDs of this process's live descendants as the OS sees them (psutil, which Dask
    requires; workers forked by the worker server are its children); a killed child not yet
    reaped is not one."""
    import psutil

    live = set()
    with contextlib.suppress(psutil.Error):
        for child in psutil.Process().children(recursive=True):
            with contextlib.suppress(psutil.Error):
                if child.status() != psutil.STATUS_ZOMBIE:
                    live.add(child.pid)
    return live


def _resource_tracker_pid() -> int | None:
    """multiprocessing's resource tracker, a child that must outlive the workers it tracks."""
    from multiprocessing import resource_tracker

    return getattr(resource_tracker._resource_tracker, "_pid", None)


def _silence_dask_logs() -> None:
    """Mute Dask's and Tornado's loggers in this process (closing comms on purpose)."""
    for name in ("distributed", "tornado", "asyncio"):
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)


@contextlib.contextmanager
def open_executor(workers: int | None = 1, scheduler: str | None = None,
                  inline_when_single: bool = True,
                  notice: Callable[[str], None] | None = None) -> Iterator[Executor]:
    """An executor for the duration of a ``with`` block, closed however the block ends.

    Parameters
    ----------
    workers : worker processes of a local cluster (None: one per usable core).
    scheduler : address of an existing Dask scheduler (overrides ``workers``).
    inline_when_single : ``workers == 1`` runs inline instead of on a one-worker cluster.
    notice : called with a sentence when the request cannot be met as asked (Dask missing:
        the work then runs inline).
    """
    with interrupt_guard():
        if scheduler is None and (workers == 1 and inline_when_single):
            ex: Executor = InlineExecutor()
        elif scheduler is None and not dask_available() and inline_when_single:
            if notice is not None:
                notice("Dask is not installed (pip install 'acid[distributed]'): "
                       "running one task at a time in this process")
            ex = InlineExecutor()
        else:
            ex = DaskExecutor(workers, scheduler)
        interrupted = False
        try:
            yield ex
        except KeyboardInterrupt:
            interrupted = True
            raise
        finally:
            ex.close(interrupted=interrupted)


__all__ = ["Executor", "InlineExecutor", "DaskExecutor", "open_executor", "check_interrupt",
           "note_interrupt", "clear_interrupt",
           "check_scheduler_address",
           "interrupt_guard", "ProgressReporter", "dask_available", "usable_cores",
           "workers_skip_main", "start_worker_server", "LOCAL_CLUSTER_CONFIG"]
