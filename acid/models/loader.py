"""``load(name_or_path)``: a built-in declaration by name, or a user's model file.

A model file is a Python file that defines, at module level, ``model = Model(...)`` (or a
function ``model()`` returning one). It is executed as a module named after the file.

Loading a file is guarded: it is first loaded (imported and traced) in a forked child
process, so a file that ends the process (``os._exit``, a crash), never finishes (an endless
loop, a huge trace: bound ``ACID_MODEL_TIMEOUT``, default 60 s) or declares more than
``ACID_MODEL_MAX_STATES`` states (default 400) or ``ACID_MODEL_MAX_PARAMETERS`` parameters
(default 5000), prints more than ``MAX_OUTPUT_BYTES`` (1 MiB) or leaves a process running
(it started one with ``subprocess`` or ``os.fork``) is one ``DeclarationError`` naming the
file and the cause (the child's process group is killed in every case); then acid loads it
itself (with other threads running too: the child only loads the file, and the timeout
bounds a child that waits on a lock another thread held). Where ``fork`` is missing, only
the in-process checks apply.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.util
import math
import os
import select
import signal
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from acid.models.declaration import DeclarationError, Model

#: Built-in declarations: name -> module defining ``model``.
BUILT_IN = {"paper": "acid.models.paper", "econ": "acid.models.econ",
            "econ2": "acid.models.econ2",
            "cabin3": "acid.models.examples.cabin3", "car_cabin": "acid.models.car_cabin",
            "heating": "acid.models.heating", "car_ac": "acid.models.car_ac",
            "car_cabin2": "acid.models.car_cabin2", "car_cabin1": "acid.models.car_cabin1",
            "car_heat2": "acid.models.car_heat2", "car_heat3": "acid.models.car_heat3",
            "car_heat3n": "acid.models.car_heat3n"}

#: Wall-clock bound on loading (importing and tracing) a model file, s; env ACID_MODEL_TIMEOUT.
LOAD_TIMEOUT_S = 60.0
#: Size bounds of a declaration loaded from a file; env ACID_MODEL_MAX_STATES / _PARAMETERS.
MAX_STATES = 400
MAX_PARAMETERS = 5000
#: What a model file may print (stdout and stderr together) while it loads, bytes.
MAX_OUTPUT_BYTES = 1 << 20


def _bound(env: str, default: float) -> float:
    text = os.environ.get(env)
    if text is None:
        return default
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value > 0 or value == float("inf"):
        raise DeclarationError(f"{env}={text!r}: expected a positive finite number")
    return value


def load(spec: str | Path | Model) -> Model:
    """The declared model ``spec``: a ``Model`` as is, a built-in name (``paper``, ``econ``,
    ``cabin3``, ``car_cabin``) or the path of a ``.py`` file defining ``model``. Errors are
    one line (``DeclarationError``) naming the file."""
    if isinstance(spec, Model):
        return spec
    text = str(spec)
    if text in BUILT_IN:
        return _model_of(importlib.import_module(BUILT_IN[text]), text)
    path = Path(text)
    if path.suffix != ".py":
        raise DeclarationError(f"--model {text!r}: a built-in name ({', '.join(BUILT_IN)}) "
                               "or a .py file declaring a model")
    if not path.is_file():
        raise DeclarationError(f"{path}: model file not found")
    _check_in_child(path)
    return checked(_checked_size(_load_file(path), path), path)


#: Largest standard deviation a state's noise or sensor may declare (as the declaration
#: bounds a number given there), in the state's unit.
MAX_SD = 1e6
#: Where the equations are evaluated at load: the states' declared numeric ``initial``
#: (else a temperature for a kelvin state, a magnitude otherwise), inputs and disturbances
#: likewise, parameters at their declared values. A file is refused only when the step or an
#: output is NaN or inf at every one of these points (a NaN constant, ``log`` of a declared
#: value's zero): never for a singularity at one particular point.
PROBE_KELVIN = (293.15, 303.15, 273.15, 313.15, 373.15, 573.15, 250.15)
PROBE_OTHER = (0.1, 1.0, 100.0, 1.0e5, 0.01, 1.0e3, -1.0)


def checked(model: Model, path: Path | str) -> Model:
    """``model`` after the checks of what a loaded file declares: the parameters its states
    name as noise or sensor (a standard deviation: finite, within [0, 1e6], a sensor's
    above 0 since a filter divides by its variance), then its equations at the declared
    point (NaN or inf there is one line naming the file and the state or output)."""
    where = f"{Path(path).name}: model {model.name!r}"
    _check_noise_parameters(model, where)
    _check_equations_finite(model, where)
    return model


def _check_noise_parameters(model: Model, where: str) -> None:
    names = model.parameter_names
    for s in model.states:
        for what in ("noise", "sensor"):
            ref = getattr(s, what)
            if not isinstance(ref, str):
                continue          # a number: the declaration checked it
            if ref not in names:
                raise DeclarationError(f"{where}: state {s.name!r}: {what}={ref!r} is not a "
                                       f"declared parameter ({', '.join(names) or 'none'})")
            p = model.parameter(ref)
            lo_ok = p.min > 0.0 if what == "sensor" else p.min >= 0.0
            if not (lo_ok and math.isfinite(p.max) and p.max <= MAX_SD
                    and math.isfinite(p.value) and (p.value > 0.0 or what == "noise")):
                span = "(0" if what == "sensor" else "[0"
                raise DeclarationError(
                    f"{where}: parameter {ref!r} (state {s.name!r}'s {what}, a standard "
                    f"deviation in {s.unit}) must have min, value and max within "
                    f"{span}, {MAX_SD:g}], got min {p.min!r}, value {p.value!r}, max {p.max!r}")


def _probe(rows, i: int) -> np.ndarray:
    out = []
    for row in rows:
        start = getattr(row, "initial", None)
        if isinstance(start, (int, float)) and not isinstance(start, bool) \
                and math.isfinite(start) and i == 0:
            out.append(float(start))
        else:
            out.append((PROBE_KELVIN if row.unit == "K" else PROBE_OTHER)[i])
    return np.array(out, dtype=float)


def _check_equations_finite(model: Model, where: str) -> None:
    """Refuse a model whose step (a state) or an output is NaN or inf at every probe point."""
    names = [*model.state_names, *model.output_names]
    bad_everywhere = None
    first = None
    for i in range(len(PROBE_OTHER)):
        try:
            xn, y = model.step(_probe(model.states, i), _probe(model.inputs, i),
                               _probe(model.disturbances, i))
        except Exception as exc:  # noqa: BLE001 - CasADi refused to evaluate the equations
            raise DeclarationError(f"{where}: its equations cannot be evaluated at the "
                                   f"declared values: {type(exc).__name__}: "
                                   f"{str(exc).splitlines()[0] if str(exc) else ''}") from None
        bad = ~np.isfinite(np.concatenate([np.ravel(xn), np.ravel(y)]))
        if first is None:
            first = np.concatenate([np.ravel(xn), np.ravel(y)])
        bad_everywhere = bad if bad_everywhere is None else bad_everywhere & bad
        if not bad_everywhere.any():
            return
    k = int(np.flatnonzero(bad_everywhere)[0])
    kind = "state" if k < model.nx else "output"
    value = "NaN" if np.isnan(first[k]) else "inf"
    raise DeclarationError(
        f"{where}: the {'step' if kind == 'state' else 'output'} gives {value} for {kind} "
        f"{names[k]!r} at the declared values (parameters as declared, states and signals at "
        "plausible magnitudes): a NaN or inf constant, or an equation outside its domain "
        "(log or sqrt of a negative number, a division by zero) at the declared parameters")


def _load_file(path: Path) -> Model:
    name = f"acid_user_model_{abs(hash(str(path.resolve())))}"
    spec_ = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec_)
    sys.modules[name] = module
    no_bytecode, sys.dont_write_bytecode = sys.dont_write_bytecode, True  # no __pycache__
    try:                                                                   # beside the file
        _guarded(path, lambda: spec_.loader.exec_module(module), "while acid imports it")
    finally:
        sys.modules.pop(name, None)
        sys.dont_write_bytecode = no_bytecode
    return _model_of(module, str(path))


def _user_raised(exc: BaseException, path: Path) -> bool:
    """Whether ``exc`` was raised by a ``raise`` statement of the user's file (not by a signal
    arriving while the file ran)."""
    tb = exc.__traceback__
    last = None
    while tb is not None:
        last = tb
        tb = tb.tb_next
    if last is None or Path(last.tb_frame.f_code.co_filename).resolve() != path.resolve():
        return False
    import linecache

    return linecache.getline(str(path), last.tb_lineno).lstrip().startswith("raise")


def _guarded(path: Path, run, when: str):
    """``run()``, the user's file running: every way it can fail is one ``DeclarationError``
    naming the file (and line): an exception, ``sys.exit`` (which would otherwise end acid
    with a "success"), a ``KeyboardInterrupt`` the file raises itself (a real Ctrl-C still
    interrupts)."""
    try:
        return run()
    except DeclarationError:
        raise
    except SyntaxError as exc:
        raise DeclarationError(f"{path.name}:{exc.lineno}: syntax error: {exc.msg}") from None
    except SystemExit as exc:
        raise DeclarationError(f"{path.name}: the model file calls sys.exit({exc.code!r}) "
                               f"{when}; a model file only declares") from None
    except KeyboardInterrupt as exc:
        if not _user_raised(exc, path):
            raise
        raise DeclarationError(f"{path.name}: the model file raises KeyboardInterrupt "
                               f"{when}") from None
    except Exception as exc:  # noqa: BLE001 - the user's file failed
        from acid.models.declaration import user_line

        line = user_line(exc, str(path))
        msg = str(exc).splitlines()[0] if str(exc) else ""
        raise DeclarationError(f"{path.name}{':' + str(line) if line else ''}: "
                               f"{type(exc).__name__}: {msg} ({when})") from None


def _model_of(module, where: str) -> Model:
    obj = getattr(module, "model", None)
    if callable(obj) and not isinstance(obj, Model):
        obj = _guarded(Path(where), obj, "in model()")
    if not isinstance(obj, Model):
        raise DeclarationError(f"{Path(where).name}: defines no model (write "
                               "`model = acid.models.Model(...)` at module level)")
    return obj


def _checked_size(model: Model, path: Path) -> Model:
    for what, n, env, default in (("states", len(model.states), "ACID_MODEL_MAX_STATES",
                                   MAX_STATES),
                                  ("parameters", len(model.parameters),
                                   "ACID_MODEL_MAX_PARAMETERS", MAX_PARAMETERS)):
        limit = int(_bound(env, default))
        if n > limit:
            raise DeclarationError(f"{path.name}: declares {n} {what}, above the bound of "
                                   f"{limit} ({env} raises it)")
    return model


@contextlib.contextmanager
def _sizes_bounded(path: Path):
    """Refuse an oversized declaration before CasADi traces it (in the child only)."""
    init = Model.__init__

    def bounded(self, *args, **kw):
        if kw.get("source") is None:   # the declaring file, as Model itself would find it
            kw["source"] = sys._getframe(1).f_code.co_filename
        for what, env, default in (("states", "ACID_MODEL_MAX_STATES", MAX_STATES),
                                   ("parameters", "ACID_MODEL_MAX_PARAMETERS",
                                    MAX_PARAMETERS)):
            items = kw.get(what)
            if items is not None and not isinstance(items, (list, tuple)):
                items = kw[what] = tuple(items)
            limit = int(_bound(env, default))
            if items is not None and len(items) > limit:
                raise DeclarationError(f"{path.name}: declares {len(items)} {what}, above the "
                                       f"bound of {limit} ({env} raises it)")
        init(self, *args, **kw)

    Model.__init__ = bounded
    try:
        yield
    finally:
        Model.__init__ = init


def _check_in_child(path: Path) -> None:
    """Load ``path`` once in a forked child: what ends or hangs the child is one error here."""
    if os.environ.get("ACID_MODEL_GUARD") == "0" or not hasattr(os, "fork"):
        return
    timeout = _bound("ACID_MODEL_TIMEOUT", LOAD_TIMEOUT_S)
    _bound("ACID_MODEL_MAX_STATES", MAX_STATES)
    _bound("ACID_MODEL_MAX_PARAMETERS", MAX_PARAMETERS)
    read, write = os.pipe()
    sys.stdout.flush()
    sys.stderr.flush()
    with warnings.catch_warnings():   # Python >= 3.12 warns of fork with threads running:
        warnings.simplefilter("ignore", DeprecationWarning)   # the child only loads the file
        pid = os.fork()                                       # and the timeout bounds it
    if pid == 0:  # the child: load, report one line, end without running any cleanup
        status = 3
        try:
            os.close(read)
            os.setpgid(0, 0)   # its own group: what the file starts is killed with it
            signal.signal(signal.SIGINT, signal.SIG_DFL)
            if "faulthandler" in sys.modules:   # no crash report from the child
                sys.modules["faulthandler"].disable()
            out = _bounded_output()
            try:
                with _sizes_bounded(path):
                    _load_file(path)
                report = _after_load(path, out)
            except DeclarationError as exc:
                report = "error " + str(exc)
            except BaseException as exc:  # noqa: BLE001 - reported to the parent
                report = f"error {path.name}: {type(exc).__name__}: {exc} (while acid loads it)"
            if report != "ok":   # the failure may be the output bound's (EFBIG)
                report = _after_load(path, out, report)
            # the report ends with NUL: a process the file forked may hold the pipe open
            os.write(write, report.encode("utf-8", "replace")[:60000] + b"\0")
            status = 0
        finally:
            os._exit(status)
    os.close(write)
    report = b""
    try:
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise DeclarationError(
                    f"{path.name}: loading the model file did not finish within {timeout:g} s "
                    "(an endless loop or a huge model?); ACID_MODEL_TIMEOUT=SECONDS raises "
                    "the bound")
            ready, _, _ = select.select([read], [], [], min(left, 1.0))
            if ready:
                chunk = os.read(read, 65536)
                report += chunk
                if not chunk or chunk.endswith(b"\0"):
                    break
    finally:
        os.close(read)
        _, status = _reap(pid)
        with contextlib.suppress(OSError):   # what the file started (its process group)
            os.killpg(pid, signal.SIGKILL)
    text = report.rstrip(b"\0").decode("utf-8", "replace")
    if text.startswith("error "):
        raise DeclarationError(text[6:].splitlines()[0])
    if text != "ok":
        if os.WIFSIGNALED(status):
            cause = f"is killed by signal {signal.Signals(os.WTERMSIG(status)).name}"
        else:
            cause = f"ends the process (os._exit({os.WEXITSTATUS(status)}))"
        raise DeclarationError(f"{path.name}: the model file {cause} while acid loads it; "
                               "a model file only declares")


def _bounded_output() -> int:
    """In the child: stdin from /dev/null, stdout and stderr into one unlinked temporary
    file of at most ``MAX_OUTPUT_BYTES`` (+1: a write beyond fails, not the disk); its fd."""
    import resource
    import tempfile

    null = os.open(os.devnull, os.O_RDWR)
    os.dup2(null, 0)
    fd, name = tempfile.mkstemp(prefix="acid-model-output-")
    os.unlink(name)
    for k in (1, 2):
        os.dup2(fd, k)
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)   # a write past the bound fails (EFBIG)
    with contextlib.suppress(ValueError, OSError):
        resource.setrlimit(resource.RLIMIT_FSIZE, (MAX_OUTPUT_BYTES + 1, MAX_OUTPUT_BYTES + 1))
    sys.stdout = os.fdopen(os.dup(fd), "w", buffering=1)
    sys.stderr = os.fdopen(os.dup(fd), "w", buffering=1)
    return fd


def _after_load(path: Path, out: int, report: str = "ok") -> str:
    """In the child, the file loaded (``report``): "error ..." if it printed more than the
    bound or left a process running (a model file only declares), else ``report``."""
    with contextlib.suppress(OSError, ValueError):
        sys.stdout.flush()
        sys.stderr.flush()
    size = os.fstat(out).st_size
    if size > MAX_OUTPUT_BYTES:
        return (f"error {path.name}: the model file prints more than {MAX_OUTPUT_BYTES >> 20} MiB "
                "while acid loads it; a model file only declares")
    started = _group_members()
    if started:
        return (f"error {path.name}: the model file starts a process ({started[0]}) while "
                "acid loads it; a model file only declares")
    return report


def _group_members() -> list[str]:
    """In the child: the other live processes of its process group ("pid command")."""
    me, found = os.getpid(), []
    proc = Path("/proc")
    if proc.is_dir():
        for d in proc.iterdir():
            if not d.name.isdigit() or int(d.name) == me:
                continue
            with contextlib.suppress(OSError, ValueError, IndexError):
                stat = (d / "stat").read_text()
                fields = stat[stat.rindex(")") + 2:].split()
                if int(fields[2]) == me and fields[0] != "Z":
                    found.append(f"pid {d.name}: {stat[stat.index('(') + 1:stat.rindex(')')]}")
        return found
    with contextlib.suppress(ChildProcessError):   # no /proc: its own live children
        if os.waitpid(-1, os.WNOHANG) == (0, 0):
            found.append("a child process")
    return found


def _reap(pid: int) -> tuple[int, int]:
    """Wait for the child, killing it if it still runs (a timeout, an interrupt)."""
    done, status = os.waitpid(pid, os.WNOHANG)
    if done == 0:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
        done, status = os.waitpid(pid, 0)
    return done, status
