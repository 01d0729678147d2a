"""Declared models: one declaration gives the simulator, the fit and the validation.

``Model`` (``acid/models/declaration.py``) with ``State``, ``Signal``, ``Parameter``,
``Constant`` and ``RK4``; the built-in declarations ``paper`` (eqs. 1-5) and ``econ``; users'
own files through :func:`load`. ``exp``, ``sqrt``, ``log``, ``sin``, ``cos``, ``fabs``,
``fmax``, ``fmin`` and ``if_else`` work on the symbols the equations receive (CasADi's);
``smooth_max``, ``smooth_min``, ``smooth_sign``, ``smooth_sqrt``, ``smooth_step`` and
``soft_if_else`` (``acid.expr``) are their differentiable stand-ins (a threshold written with
them is fitted).
"""

from __future__ import annotations

from casadi import cos, exp, fabs, fmax, fmin, if_else, log, sin, sqrt

from acid.expr import (
    smooth_max,
    smooth_min,
    smooth_sign,
    smooth_sqrt,
    smooth_step,
    soft_if_else,
)
from acid.models.declaration import (
    RK4,
    Constant,
    Constraint,
    DeclarationError,
    Group,
    Model,
    Parameter,
    Signal,
    State,
)
from acid.models.loader import BUILT_IN, load

__all__ = ["RK4", "BUILT_IN", "Constant", "Constraint", "DeclarationError", "Group", "Model",
           "Parameter", "Signal", "State", "cos", "exp", "fabs", "fmax", "fmin", "if_else", "load",
           "log", "sin", "smooth_max", "smooth_min", "smooth_sign", "smooth_sqrt", "smooth_step",
           "soft_if_else", "sqrt"]
