"""``load(name_or_path)``: a built-in declaration by name, or a user's model file.

A model file is a Python file that defines, at module level, ``model = Model(...)`` (or a
function ``model()`` returning one). It is executed as a module named after the file.
"""

from __future__ import annotations

import importlib
import importlib.util
import math
import os
import select
import signal
import sys
import warnings
from pathlib import Path

from acid.models.declaration import DeclarationError, Model

#: Seconds a model file may take to load and declare its model (a trial load in a forked
#: child first, where the platform forks): beyond, an endless loop or a runaway
#: declaration is refused. ``ACID_MODEL_LOAD_TIMEOUT_S`` changes it (0: no trial load).
LOAD_TIMEOUT_S = 120.0

#: Built-in declarations: name -> module defining ``model``.
BUILT_IN = {"paper": "acid.models.paper", "econ": "acid.models.econ",
            "cabin3": "acid.models.examples.cabin3", "car_cabin": "acid.models.car_cabin",
            "heating": "acid.models.heating", "car_ac": "acid.models.car_ac"}


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
    _trial_load(path)
    return _load_file(path)


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


def _timeout_s() -> float:
    text = os.environ.get("ACID_MODEL_LOAD_TIMEOUT_S", "")
    try:
        value = float(text) if text else LOAD_TIMEOUT_S
    except ValueError:
        value = math.nan
    if not (value >= 0.0 and math.isfinite(value)):
        raise DeclarationError(f"ACID_MODEL_LOAD_TIMEOUT_S must be a number of seconds >= 0, "
                               f"got {text!r}")
    return value


def _trial_load(path: Path) -> None:
    """Load ``path`` once in a forked child, its output discarded, bounded by
    ``LOAD_TIMEOUT_S``: a file that ends the process (``os._exit``, a crash) or never
    finishes is refused with one line naming the file, before acid runs it itself. Any other
    failure is left to the real load, which names it. Skipped without ``os.fork`` and with a
    timeout of 0. The child only runs the user's file: should another thread of the parent
    hold a lock it needs, the child waits and the timeout names it."""
    timeout = _timeout_s()
    if timeout == 0.0 or not hasattr(os, "fork"):
        return
    r, w = os.pipe()
    with warnings.catch_warnings():   # Python >= 3.12 warns of fork with threads running
        warnings.simplefilter("ignore", DeprecationWarning)
        pid = os.fork()
    if pid == 0:                                           # the child: load, report, leave
        try:
            os.close(r)
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, 1)
            os.dup2(null, 2)
            sys.stdout = sys.stderr = open(os.devnull, "w")   # noqa: SIM115 - os._exit ends it
            try:
                _load_file(path)
            except BaseException:  # noqa: BLE001 - the real load names it
                pass
            os.write(w, b"done")
        finally:
            os._exit(0)
    os.close(w)
    try:
        ready, _, _ = select.select([r], [], [], timeout)
        said = os.read(r, 4) if ready else None
    finally:
        os.close(r)
        if not ready:
            os.kill(pid, signal.SIGKILL)
        _, status = os.waitpid(pid, 0)
    if said is None:
        raise DeclarationError(f"{path.name}: loading the model file did not finish within "
                               f"{timeout:g} s (an endless loop, or a declaration too large "
                               "to trace); ACID_MODEL_LOAD_TIMEOUT_S raises the limit")
    if said != b"done":
        how = (f"signal {os.WTERMSIG(status)}" if os.WIFSIGNALED(status)
               else f"exit status {os.WEXITSTATUS(status)}")
        raise DeclarationError(f"{path.name}: the model file ended the process while acid "
                               f"loaded it ({how}: os._exit or a crash); a model file only "
                               "declares")


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
