"""A small, safe evaluator of arithmetic expressions over channels (for derived channels in
import maps, e.g. ``T_ain = { expr = "T_evap + 2", unit = "degC" }``).

Not Python ``eval``: the text is parsed with :mod:`ast` and only numbers, channel names,
``+ - * / **``, unary minus, one comparison (``<``, ``<=``, ``>``, ``>=``, ``==``, ``!=``,
giving 1 or 0) and the functions ``abs``, ``min``, ``max``, ``sqrt``, ``exp``, ``log``,
``clip(x, lo, hi)`` and ``where(cond, a, b)`` are accepted; anything else (attributes,
subscripts, strings, keywords, lambdas, other names of functions) is refused with one line
naming it. Values are numpy arrays; the result has the length of the channels.
"""

from __future__ import annotations

import ast
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from acid.errors import DataError

MAX_LENGTH = 500
"""Longest expression accepted, characters."""

_BINOPS = {ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply,
           ast.Div: np.divide, ast.Pow: np.power}
_UNARY = {ast.USub: np.negative, ast.UAdd: np.positive}
_COMPARE = {ast.Lt: np.less, ast.LtE: np.less_equal, ast.Gt: np.greater,
            ast.GtE: np.greater_equal, ast.Eq: np.equal, ast.NotEq: np.not_equal}
_FUNCS = {"abs": (np.abs, 1), "min": (np.minimum, 2), "max": (np.maximum, 2),
          "sqrt": (np.sqrt, 1), "exp": (np.exp, 1), "log": (np.log, 1),
          "clip": (np.clip, 3), "where": (lambda c, a, b: np.where(c != 0, a, b), 3)}

#: Words an expression may use besides channel names.
FUNCTIONS = tuple(_FUNCS)


@dataclass(frozen=True)
class Expression:
    """A parsed expression: its text and the channel names it reads."""

    text: str
    names: frozenset[str]
    _tree: ast.Expression

    @classmethod
    def parse(cls, text: object, where: str) -> Expression:
        """Parse ``text``; ``DataError`` naming ``where`` if it is not a safe expression."""
        if not isinstance(text, str) or not text.strip():
            raise DataError(f"{where}: 'expr' must be a non-empty text, got {text!r}")
        if len(text) > MAX_LENGTH:
            raise DataError(f"{where}: expression longer than {MAX_LENGTH} characters")
        try:
            tree = ast.parse(text.strip(), mode="eval")
        except (SyntaxError, ValueError, RecursionError, MemoryError) as exc:
            msg = getattr(exc, "msg", None) or exc.__class__.__name__
            raise DataError(f"{where}: cannot parse expression {text!r} ({msg})") from None
        names: set[str] = set()
        try:
            _check(tree.body, names, where, text)
        except RecursionError:
            raise DataError(f"{where}: expression {text!r} is nested too deeply") from None
        return cls(text=text, names=frozenset(names), _tree=tree)

    def evaluate(self, values: Mapping[str, np.ndarray], n: int) -> np.ndarray:
        """The expression over ``values`` ({name: array of n}) as a float array of n."""
        with np.errstate(all="ignore"):
            out = _eval(self._tree.body, values)
        out = np.asarray(out, dtype=float)
        return np.broadcast_to(out, (n,)).astype(float) if out.shape != (n,) else out


def _check(node: ast.AST, names: set[str], where: str, text: str) -> None:
    def refuse(what: str) -> None:
        raise DataError(f"{where}: expression {text!r} uses {what}, which acid does not "
                        f"evaluate (allowed: numbers, channel names, + - * / **, one "
                        f"comparison, {', '.join(FUNCTIONS)})")

    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            refuse(f"the constant {node.value!r}")
    elif isinstance(node, ast.Name):
        if node.id in _FUNCS:
            refuse(f"the function {node.id!r} without a call")
        names.add(node.id)
    elif isinstance(node, ast.BinOp):
        if type(node.op) not in _BINOPS:
            refuse(f"the operator {type(node.op).__name__}")
        _check(node.left, names, where, text)
        _check(node.right, names, where, text)
    elif isinstance(node, ast.UnaryOp):
        if type(node.op) not in _UNARY:
            refuse(f"the operator {type(node.op).__name__}")
        _check(node.operand, names, where, text)
    elif isinstance(node, ast.Compare):
        if len(node.ops) != 1 or type(node.ops[0]) not in _COMPARE:
            refuse("a chained or unknown comparison")
        _check(node.left, names, where, text)
        _check(node.comparators[0], names, where, text)
    elif isinstance(node, ast.Call):
        fn = node.func.id if isinstance(node.func, ast.Name) else None
        if fn not in _FUNCS:
            refuse(f"a call of {ast.unparse(node.func)!r}")
        if node.keywords or len(node.args) != _FUNCS[fn][1]:
            refuse(f"{fn}() with other than {_FUNCS[fn][1]} plain argument(s)")
        for a in node.args:
            _check(a, names, where, text)
    else:
        refuse(type(node).__name__)


def _eval(node: ast.AST, values: Mapping[str, np.ndarray]):
    if isinstance(node, ast.Constant):
        return float(node.value)
    if isinstance(node, ast.Name):
        return values[node.id]
    if isinstance(node, ast.BinOp):
        return _BINOPS[type(node.op)](_eval(node.left, values), _eval(node.right, values))
    if isinstance(node, ast.UnaryOp):
        return _UNARY[type(node.op)](_eval(node.operand, values))
    if isinstance(node, ast.Compare):
        op = _COMPARE[type(node.ops[0])]
        return op(_eval(node.left, values), _eval(node.comparators[0], values)).astype(float)
    fn, _ = _FUNCS[node.func.id]
    return fn(*(_eval(a, values) for a in node.args))


# ------------------------------------------------------------ smooth helpers for declarations
# Differentiable stand-ins for the kinks of max, min, sqrt at 0 and a threshold in if_else,
# for the equations of a declared model (``acid.models`` exports them). They work on CasADi
# symbols and on plain floats. A fit follows gradients: a parameter that enters only through
# ``if_else(x > threshold, ...)`` gets none and stays at its declared value; written with
# ``smooth_step`` the threshold is fitted like any other parameter.

def smooth_max(a, b, width):
    """max(a, b) rounded over ``width`` (same unit as a and b): 0.5 (a + b +
    sqrt((a - b)^2 + width^2)); above the max by width / 2 where a == b and by less than
    width^2 / (4 |a - b|) away from it; differentiable everywhere for width > 0."""
    import casadi as ca

    return 0.5 * (a + b + ca.sqrt((a - b) * (a - b) + width * width))


def smooth_min(a, b, width):
    """min(a, b) rounded over ``width``: 0.5 (a + b - sqrt((a - b)^2 + width^2))."""
    import casadi as ca

    return 0.5 * (a + b - ca.sqrt((a - b) * (a - b) + width * width))


def smooth_sqrt(x, width):
    """sqrt(max(x, 0)) without the infinite slope at 0 nor NaN below it:
    sqrt(smooth_max(x, 0, width)); sqrt(width / 2) at x = 0, within width^2 / (8 x^1.5) of
    sqrt(x) for x >> width (``width`` in the unit of x)."""
    import casadi as ca

    return ca.sqrt(smooth_max(x, 0.0, width))


def smooth_step(x, threshold, width):
    """A soft ``x > threshold``: 0.5 (1 + tanh((x - threshold) / width)), 0 well below the
    threshold, 1 well above it (0.12 / 0.88 at one width either side); its gradient with
    respect to ``threshold`` is not zero, so a fitted threshold moves."""
    import casadi as ca

    return 0.5 * (1.0 + ca.tanh((x - threshold) / width))


def smooth_sign(x, width):
    """A soft ``sign(x)``: tanh(x / width), -1 well below 0, +1 well above (+-0.76 at one
    width); for Coulomb friction ``Fc * smooth_sign(v, width)``, whose exact ``sign(v)``
    has no derivative at v = 0, where a positioning system spends its rests."""
    import casadi as ca

    return ca.tanh(x / width)


def soft_if_else(x, threshold, above, below, width):
    """``if_else(x > threshold, above, below)`` blended over ``width``:
    below + (above - below) * smooth_step(x, threshold, width)."""
    return below + (above - below) * smooth_step(x, threshold, width)
