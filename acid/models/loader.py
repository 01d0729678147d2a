"""``load(name_or_path)``: a built-in declaration by name, or a user's model file.

A model file is a Python file that defines, at module level, ``model = Model(...)`` (or a
function ``model()`` returning one). It is executed as a module named after the file.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from pathlib import Path

from acid.models.declaration import DeclarationError, Model

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
    name = f"acid_user_model_{abs(hash(str(path.resolve())))}"
    spec_ = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec_)
    sys.modules[name] = module
    no_bytecode, sys.dont_write_bytecode = sys.dont_write_bytecode, True  # no __pycache__
    try:                                                                   # beside the file
        spec_.loader.exec_module(module)
    except DeclarationError:
        raise
    except SyntaxError as exc:
        raise DeclarationError(f"{path.name}:{exc.lineno}: syntax error: {exc.msg}") from None
    except Exception as exc:  # noqa: BLE001 - the user's file failed while importing
        from acid.models.declaration import user_line

        line = user_line(exc, str(path))
        msg = str(exc).splitlines()[0] if str(exc) else ""
        raise DeclarationError(f"{path.name}{':' + str(line) if line else ''}: "
                               f"{type(exc).__name__}: {msg}") from None
    finally:
        sys.modules.pop(name, None)
        sys.dont_write_bytecode = no_bytecode
    return _model_of(module, str(path))


def _model_of(module, where: str) -> Model:
    obj = getattr(module, "model", None)
    if callable(obj) and not isinstance(obj, Model):
        obj = obj()
    if not isinstance(obj, Model):
        raise DeclarationError(f"{Path(where).name}: defines no model (write "
                               "`model = acid.models.Model(...)` at module level)")
    return obj
