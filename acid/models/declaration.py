"""A model declared once: signals with units, a parameter table, constants and equations.

The equations are Python functions of one argument, a namespace in which every declared
name (state, input, disturbance, output, parameter, constant) is an attribute. They are
traced once with CasADi SX symbols into ``casadi.Function`` objects; simulation, the fits
and the validation all evaluate those Functions (numpy arrays in, ``.map`` over batches), so
there is one source of truth and CasADi gives every derivative.

Two forms:

* discrete time: ``step(s) -> {state: value one sample later, [output: value over the
  interval]}``; an interval output may read ``s.next.NAME``, the state at the interval's end
  (simulated: the step's own; fitted by equation error, ``acid.ident.stages``: the measured
  one);
* continuous time: ``ode(s) -> {state: time derivative}``, integrated over ``Ts`` by
  ``RK4(substeps)`` with inputs and disturbances held.

``output(s) -> {output: value at the sample}`` gives the outputs that depend on the sampled
state. A step or an ODE may read an output by name (``s.T_ain``): simulating, the output
equation is substituted; fitting by equation error, the measured output is (paper eq. 1
reads the measured T_ain). Any mistake in a declaration is a :class:`DeclarationError`, one
line naming the model file (and line) and the culprit.
"""

from __future__ import annotations

import inspect
import math
import traceback
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from acid.errors import AcidError
from acid.units import parse_unit


class DeclarationError(AcidError):
    """A model declaration is wrong (unknown name, symbolic branch, missing equation, unit)."""


# ------------------------------------------------------------------ declared objects
@dataclass(frozen=True)
class Signal:
    """An input, a measured disturbance or an output: a dataset channel of that name."""

    name: str
    unit: str
    description: str = ""


@dataclass(frozen=True)
class State:
    """A state. ``measured=False`` makes it latent: no channel measures it, its initial
    value in each window is estimated, started from ``initial`` (a function of the namespace
    of measured signals at the start instant, numpy arrays, or a number)."""

    name: str
    unit: str
    measured: bool = True
    initial: Callable | float | None = None
    description: str = ""
    #: Process noise for a filter (``acid.ident.pem``): the standard deviation of the
    #: state's random increment per sample, in its unit, or the name of a parameter that
    #: holds it (estimated by the prediction-error method). A latent state whose equation
    #: is zero with ``noise`` is a random walk: an unmeasured load the filter follows.
    noise: float | str | None = None
    #: Standard deviation of the initial value (in its unit) a filter starts from.
    spread: float | None = None
    #: A measured state's sensor noise for a filter: a standard deviation in its unit, or
    #: the name of a parameter that holds it.
    sensor: float | str | None = None


@dataclass(frozen=True)
class Parameter:
    """A row of the parameter table, in ``unit`` (the equations see the value as written).

    ``fixed``: not estimated unless freed; ``per_experiment``: one value per experiment of
    the dataset (e.g. a solar load that differs between recordings). ``prior``: (mean,
    standard deviation) in ``unit``, what is known before the data (a data sheet, the
    literature): output error and prediction error then maximise the posterior (MAP),
    adding ``((value - mean) / sd)^2`` to the data's weighted squared errors (a Gaussian
    prior; per experiment for a per-experiment parameter).
    """

    name: str
    unit: str
    value: float
    min: float = -math.inf
    max: float = math.inf
    fixed: bool = False
    per_experiment: bool = False
    description: str = ""
    prior: tuple[float, float] | None = None


@dataclass(frozen=True)
class Constant:
    """A number the equations use that is never estimated; a parameter file may give
    another value within ``[min, max]`` (e.g. a COP read off the data)."""

    name: str
    value: float
    unit: str
    description: str = ""
    min: float = -math.inf
    max: float = math.inf


@dataclass(frozen=True)
class Constraint:
    """An affine constraint ``min <= expr(s) <= max`` on the parameters, imposed by the
    constrained least squares (``--method cvx``). ``expr`` reads parameters and constants,
    and may read inputs and disturbances: it is then imposed over the measured range of
    each (``GRID`` points each, e.g. a power that must stay positive over the blower's
    range). Checked affine in the parameters by CasADi at declaration."""

    expr: Callable
    min: float = -math.inf
    max: float = math.inf
    description: str = ""
    GRID = 11


@dataclass(frozen=True)
class Group:
    """Parameters read and written together under one name (``p.power_map``): ``view``,
    when given, builds the object shown (``view(coef=values, **info)``) and its other
    fields are kept with the values (``ParameterValues.info``). Names ``x1, x2, ...`` form
    the group ``x`` without being declared."""

    names: tuple[str, ...]
    view: Callable | None = None


@dataclass(frozen=True)
class RK4:
    """Classical Runge-Kutta 4 over one sample, ``substeps`` equal sub-steps."""

    substeps: int = 1

    def integrate(self, f: Callable, z, dt: float):
        """``z`` after ``dt`` seconds of ``dz/dt = f(z)`` (CasADi column vectors)."""
        h = dt / self.substeps
        for _ in range(self.substeps):
            k1 = f(z)
            k2 = f(z + 0.5 * h * k1)
            k3 = f(z + 0.5 * h * k2)
            k4 = f(z + h * k3)
            z = z + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        return z


# ------------------------------------------------------------------------ namespace
class _Names:
    """Attribute access to the symbols of one equation; an unknown name is one line."""

    def __init__(self, symbols: Mapping, where: str, model: Model):
        object.__setattr__(self, "_symbols", dict(symbols))
        object.__setattr__(self, "_where", where)
        object.__setattr__(self, "_model", model)

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        try:
            return self._symbols[name]
        except KeyError:
            raise self._model._error(f"{self._where}: unknown name {name!r} (declared: "
                                     f"{', '.join(self._model.all_names)})",
                                     user_frame=True) from None

    def __getitem__(self, name):
        return self.__getattr__(name)

    def __setattr__(self, name, value):
        raise self._model._error(f"{self._where}: the namespace is read-only (assign "
                                 f"{name!r} to a local variable)", user_frame=True)


def _numeric(value, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise TypeError(f"{what} must be a number, got {type(value).__name__}")
    return float(value)


def check_prior(name: str, prior, unit: str, error) -> None:
    """A prior is (mean, sd): two finite numbers, sd > 0; else ``error(message)`` is raised
    (a callable making the exception, or the exception class)."""
    ok = isinstance(prior, (tuple, list)) and len(prior) == 2 and all(
        not isinstance(v, bool) and isinstance(v, (int, float, np.floating, np.integer))
        and math.isfinite(float(v)) for v in prior)
    if not ok or not float(prior[1]) > 0.0:
        raise error(f"parameter {name!r}: prior must be (mean, standard deviation) in {unit}, "
                    f"both finite, the standard deviation > 0, got {prior!r}")


# ---------------------------------------------------------------------------- model
class Model:
    """A declared model (see the module docstring; ``acid/models/paper.py`` is an example).

    Parameters
    ----------
    name : a label (parameter files carry it).
    states, inputs, disturbances, outputs : ``State`` / ``Signal`` objects; inputs and
        disturbances are measured channels held over each sample interval.
    parameters : ``Parameter`` rows; constants : ``Constant`` rows.
    Ts : sample time, s.
    step : discrete-time equations; or ``ode`` with ``integrator`` (default ``RK4(1)``).
    output : equations of the sampled outputs.
    source : the file the model is declared in (default: the caller's file), named by every
        error.
    """

    def __init__(self, name: str, *, states, parameters, Ts: float, inputs=(),
                 disturbances=(), outputs=(), constants=(), step: Callable | None = None,
                 ode: Callable | None = None, integrator: RK4 | None = None,
                 output: Callable | None = None, source: str | None = None,
                 description: str = "", constraints=(), groups=None,
                 checks: Callable | None = None):
        if source is None:  # the file that declares the model
            source = inspect.currentframe().f_back.f_code.co_filename
        self.source = str(source)
        self.name = str(name)
        self.description = description
        self.states = tuple(states)
        self.inputs = tuple(inputs)
        self.disturbances = tuple(disturbances)
        self.outputs = tuple(outputs)
        self.parameters = tuple(parameters)
        self.constants = tuple(constants)
        self._check_table()
        try:
            self.Ts = _numeric(Ts, "Ts")
        except TypeError as exc:
            raise self._error(str(exc)) from None
        if not (math.isfinite(self.Ts) and self.Ts > 0):
            raise self._error(f"Ts must be a positive number of seconds, got {Ts!r}")
        if (step is None) == (ode is None):
            raise self._error("declare exactly one of step= (discrete time) or ode= "
                              "(continuous time)")
        if integrator is not None and ode is None:
            raise self._error("integrator= goes with ode=, not step=")
        self.integrator = integrator or (RK4(1) if ode is not None else None)
        if self.integrator is not None and not (
                isinstance(self.integrator, RK4) and isinstance(self.integrator.substeps, int)
                and self.integrator.substeps >= 1):
            raise self._error(f"integrator must be RK4(substeps >= 1), got {integrator!r}")
        self.continuous = ode is not None
        self._step_fn, self._ode_fn, self._output_fn = step, ode, output
        self._trace()
        #: ``checks(s) -> [problem, ...]``: what makes values implausible (``s`` by name)
        self.checks = checks
        self.groups = {**{g: v for g, v in _numbered_groups(self.parameter_names).items()
                          if g not in self.all_names},
                       **{g: v if isinstance(v, Group) else Group(tuple(v))
                          for g, v in (groups or {}).items()}}
        for g, grp in self.groups.items():
            bad = [n for n in grp.names if n not in self.parameter_names]
            if bad or g in self.all_names:
                raise self._error(f"group {g!r}: " + (f"unknown parameter {bad[0]!r}" if bad
                                                      else "a name already declared"))
        self.constraints = tuple(self._constraint(c) for c in constraints)

    # ------------------------------------------------------------- declaration checks
    def _error(self, message: str, user_frame: bool = False) -> DeclarationError:
        where = Path(self.source).name
        if user_frame:
            for fr in reversed(traceback.extract_stack()):
                if Path(fr.filename) == Path(self.source):
                    where = f"{where}:{fr.lineno}"
                    break
        return DeclarationError(f"{where}: model {self.name!r}: {message}")

    def _check_table(self) -> None:
        kinds = (("state", self.states, State), ("input", self.inputs, Signal),
                 ("disturbance", self.disturbances, Signal), ("output", self.outputs, Signal),
                 ("parameter", self.parameters, Parameter), ("constant", self.constants,
                                                              Constant))
        seen: dict[str, str] = {}
        for kind, rows, cls in kinds:
            for row in rows:
                if not isinstance(row, cls):
                    raise self._error(f"a {kind} must be declared as {cls.__name__}(...), "
                                      f"got {type(row).__name__}")
                if not (isinstance(row.name, str) and row.name.isidentifier()
                        and not row.name.startswith("_")):
                    raise self._error(f"{kind} name {row.name!r} is not a Python identifier")
                if row.name in seen:
                    raise self._error(f"name {row.name!r} is declared twice ({seen[row.name]} "
                                      f"and {kind})")
                seen[row.name] = kind
                try:
                    parse_unit(row.unit)
                except (ValueError, TypeError) as exc:
                    raise self._error(f"{kind} {row.name!r}: {exc}") from None
                if kind in ("state", "input", "disturbance", "output") and \
                        row.unit in ("degC", "degF"):
                    raise self._error(f"{kind} {row.name!r}: declare temperatures in 'K' "
                                      "(kelvin inside; datasets in degC are converted)")
        if not self.states:
            raise self._error("a model needs at least one state")
        for s in self.states:
            for what in ("noise", "sensor", "spread"):
                v = getattr(s, what)
                if v is None or (isinstance(v, str) and what != "spread"):
                    continue   # a parameter's name: checked where the filter reads it
                lo_open = what == "sensor"   # a filter divides by the sensor's variance
                if isinstance(v, bool) or not isinstance(v, (int, float)) \
                        or not math.isfinite(v) or v < 0.0 or (lo_open and v == 0.0) \
                        or v > 1e6:
                    span = "(0, 1e6]" if lo_open else "[0, 1e6]"
                    raise self._error(f"state {s.name!r}: {what} must be a standard deviation "
                                      f"in {span} {s.unit} (or, but for spread, a "
                                      f"parameter's name), got {v!r}")
        for p in self.parameters:
            try:
                v, lo, hi = (_numeric(p.value, f"parameter {p.name!r} value"),
                             _numeric(p.min, f"parameter {p.name!r} min"),
                             _numeric(p.max, f"parameter {p.name!r} max"))
            except TypeError as exc:
                raise self._error(str(exc)) from None
            if not math.isfinite(v) or not lo <= v <= hi:
                raise self._error(f"parameter {p.name!r}: value {p.value!r} must be finite "
                                  f"and within [min, max] = [{lo:g}, {hi:g}]")
            if p.prior is not None:
                check_prior(p.name, p.prior, p.unit, self._error)
        for c in self.constants:
            try:
                _numeric(c.value, f"constant {c.name!r}")
            except TypeError as exc:
                raise self._error(str(exc)) from None
        for s in self.states:
            if not s.measured and s.initial is None:
                raise self._error(f"latent state {s.name!r} needs initial= (a number, or a "
                                  "function of the measured signals, e.g. "
                                  "lambda s: s.T_cab)")

    # -------------------------------------------------------------------- tracing
    def _symbols(self):
        self._x = ca.SX.sym("x", self.nx)
        self._u = ca.SX.sym("u", self.nu)
        self._d = ca.SX.sym("d", self.nd)
        self._p = ca.SX.sym("p", self.np)
        self._yr = ca.SX.sym("y", self.ny)   # outputs read by a step / an ODE
        sym = {}
        for group, vec in ((self.states, self._x), (self.inputs, self._u),
                           (self.disturbances, self._d), (self.parameters, self._p),
                           (self.outputs, self._yr)):
            for i, row in enumerate(group):
                sym[row.name] = vec[i]
        for c in self.constants:
            sym[c.name] = float(c.value)
        self._xn = ca.SX.sym("xn", self.nx)   # s.next.NAME: the state at the interval's end
        sym.setdefault("next", _Names({s.name: self._xn[i] for i, s in enumerate(self.states)},
                                      "next", self))
        return sym

    def _call(self, fn: Callable, symbols: dict, what: str, allowed: tuple[str, ...]) -> dict:
        ns = _Names(symbols, what, self)
        try:
            out = fn(ns)
        except DeclarationError:
            raise
        except Exception as exc:  # noqa: BLE001 - any failure of user code while tracing
            line = user_line(exc, self.source)
            msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            if "truth value" in msg or "symbolic" in msg.lower() and "bool" in msg.lower():
                msg = ("a Python if/and/or/comparison on a symbolic value; use "
                       "acid.models.if_else / fmax / fmin instead")
            where = f"{Path(self.source).name}{':' + str(line) if line else ''}"
            raise DeclarationError(f"{where}: model {self.name!r}: {what}: {msg}") from None
        if not isinstance(out, Mapping):
            raise self._error(f"{what} must return a dict {{name: expression}}, got "
                              f"{type(out).__name__}")
        result = {}
        for key, val in out.items():
            if key not in allowed:
                known = key in self.all_names
                raise self._error(f"{what}: an equation for {key!r}, which is "
                                  + ("not one of its targets (" + ", ".join(allowed) + ")"
                                     if known else "not declared"))
            try:
                expr = ca.SX(val) if not isinstance(val, ca.SX) else val
            except Exception:  # noqa: BLE001
                raise self._error(f"{what}: the equation for {key!r} is not a number or an "
                                  f"expression ({type(val).__name__})") from None
            if expr.shape != (1, 1):
                raise self._error(f"{what}: the equation for {key!r} has shape "
                                  f"{expr.shape}, expected a scalar")
            result[key] = expr
        return result

    def _trace(self) -> None:
        sym = self._sym = self._symbols()
        state_names = tuple(s.name for s in self.states)
        out_names = tuple(o.name for o in self.outputs)
        y_sampled: dict = {}
        if self._output_fn is not None:
            y_sampled = self._call(self._output_fn, sym, "output", out_names)
            for key, expr in y_sampled.items():
                if ca.depends_on(expr, self._yr):
                    raise self._error(f"output: the equation for {key!r} reads an output")
        if self.continuous:
            eqs = self._call(self._ode_fn, sym, "ode", state_names)
            y_interval: dict = {}
        else:
            eqs = self._call(self._step_fn, sym, "step", state_names + out_names)
            y_interval = {k: v for k, v in eqs.items() if k in out_names}
            eqs = {k: v for k, v in eqs.items() if k in state_names}
        missing = [s for s in state_names if s not in eqs]
        if missing:
            raise self._error(f"state {missing[0]!r} has no equation in "
                              f"{'ode' if self.continuous else 'step'}")
        both = sorted(set(y_sampled) & set(y_interval))
        if both:
            raise self._error(f"output {both[0]!r} has two equations (output and step)")
        no_eq = [o for o in out_names if o not in y_sampled and o not in y_interval]
        if no_eq:
            raise self._error(f"output {no_eq[0]!r} has no equation")
        if any(ca.depends_on(e, self._xn) for e in [*eqs.values(), *y_sampled.values()]):
            raise self._error("only a step's interval outputs may read s.next (the state at "
                              "the end of the interval)")
        self.sampled_outputs = tuple(o for o in out_names if o in y_sampled)
        self.interval_outputs = tuple(o for o in out_names if o in y_interval)
        for key in y_interval:
            if _reads(y_interval[key], self._yr, self.outputs, self.interval_outputs) or any(
                    _reads(e, self._yr, self.outputs, self.interval_outputs)
                    for e in eqs.values()):
                raise self._error("step: an equation reads an output that the step itself "
                                  f"defines ({', '.join(self.interval_outputs)})")
        x, u, d, p, yr = self._x, self._u, self._d, self._p, self._yr
        h = ca.vertcat(*[y_sampled.get(o, ca.SX(0)) for o in out_names]) \
            if out_names else ca.SX(0, 1)
        self.h = ca.Function("h", [x, u, d, p], [h], ["x", "u", "d", "p"], ["y"])
        rhs = ca.vertcat(*[eqs[s] for s in state_names])
        # the equations as written (outputs read as symbols): equation error substitutes data
        self.equations_raw = {s: eqs[s] for s in state_names}
        self.equations_raw.update({o: y_sampled[o] for o in self.sampled_outputs})
        self.equations_raw.update({o: ca.substitute(y_interval[o], self._xn, rhs)
                                   for o in self.interval_outputs})
        # outputs that read s.next: equation error gives them the measured end state
        self.equations_next = {o: e for o, e in y_interval.items()
                               if ca.depends_on(e, self._xn)}
        y_int = ca.substitute(ca.vertcat(*[y_interval.get(o, ca.SX(0)) for o in out_names]),
                              self._xn, rhs) if out_names else ca.SX(0, 1)
        if self.continuous:
            f = ca.Function("f", [x, u, d, p], [ca.substitute(rhs, yr, h)])
            x_next = self.integrator.integrate(lambda z: f(z, u, d, p), x, self.Ts)
            self.f = f
            # the integrated map is the state "equation" a fit reads
            for i, s in enumerate(state_names):
                self.equations_raw[s] = x_next[i]
        else:
            x_next = ca.substitute(rhs, yr, h)
            y_int = ca.substitute(y_int, yr, h)
        y = h + y_int if out_names else h
        self.F = ca.Function("F", [x, u, d, p], [x_next, y], ["x", "u", "d", "p"],
                             ["x_next", "y"])

    def _constraint(self, c: Constraint) -> tuple:
        """(constraint, f(p, u, d) -> value, names of the signals it reads), checked affine
        in the parameters."""
        if not isinstance(c, Constraint):
            raise self._error(f"a constraint must be declared as Constraint(...), got "
                              f"{type(c).__name__}")
        sym = {k: v for k, v in self._sym.items()
               if k not in self.state_names + self.output_names + ("next",)}
        expr = self._call(lambda s: {"constraint": c.expr(s)}, sym,
                          f"constraint {c.description or 'expr'!r}", ("constraint",))
        e = expr["constraint"]
        what = f"constraint {c.description or 'expr'!r}"
        if not ca.depends_on(e, self._p):
            raise self._error(f"{what} reads no parameter")
        if ca.depends_on(ca.jacobian(e, self._p), self._p):
            raise self._error(f"{what} is not affine in the parameters")
        try:
            lo, hi = _numeric(c.min, f"{what} min"), _numeric(c.max, f"{what} max")
        except TypeError as exc:
            raise self._error(str(exc)) from None
        if not lo <= hi or (math.isinf(lo) and math.isinf(hi)):
            raise self._error(f"{what} needs min <= max, one of them finite")
        signals = tuple(r.name for r, v in zip(self.inputs + self.disturbances,
                                               ca.vertsplit(ca.vertcat(self._u, self._d)),
                                               strict=True) if ca.depends_on(e, v))
        return c, ca.Function("g", [self._p, self._u, self._d], [e]), signals

    # ------------------------------------------------------------------------ views
    @property
    def nx(self) -> int:
        return len(self.states)

    @property
    def nu(self) -> int:
        return len(self.inputs)

    @property
    def nd(self) -> int:
        return len(self.disturbances)

    @property
    def ny(self) -> int:
        return len(self.outputs)

    @property
    def np(self) -> int:
        return len(self.parameters)

    @property
    def all_names(self) -> tuple[str, ...]:
        return tuple(r.name for group in (self.states, self.inputs, self.disturbances,
                                          self.outputs, self.parameters, self.constants)
                     for r in group)

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.states)

    @property
    def output_names(self) -> tuple[str, ...]:
        return tuple(o.name for o in self.outputs)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    @property
    def values(self) -> np.ndarray:
        """The declared parameter values, table order."""
        return np.array([p.value for p in self.parameters], dtype=float)

    def parameter(self, name: str) -> Parameter:
        for p in self.parameters:
            if p.name == name:
                return p
        raise DeclarationError(f"{Path(self.source).name}: model {self.name!r}: unknown "
                               f"parameter {name!r} (parameters: "
                               f"{', '.join(self.parameter_names)})")

    def with_priors(self, priors: Mapping[str, tuple[float, float]]) -> Model:
        """A copy whose table gives these parameters the prior (mean, sd) (replacing any
        declared one); checked as a declared prior."""
        import copy
        import dataclasses

        for n, pr in priors.items():
            p = self.parameter(n)
            check_prior(n, pr, p.unit, DeclarationError)
        other = copy.copy(self)
        other.parameters = tuple(dataclasses.replace(p, prior=tuple(map(float, priors[p.name])))
                                 if p.name in priors else p for p in self.parameters)
        return other

    def with_parameters(self, fix: Mapping[str, float] | None = None,
                        free: tuple[str, ...] = ()) -> Model:
        """A copy whose table fixes ``fix`` (name -> value) and frees ``free``."""
        import copy
        import dataclasses

        fix = dict(fix or {})
        for n in list(fix) + list(free):
            self.parameter(n)
        both = sorted(set(fix) & set(free))
        if both:
            raise DeclarationError(f"parameter {both[0]!r} is both fixed and freed")
        rows = []
        for p in self.parameters:
            if p.name in fix:
                v = float(fix[p.name])
                if not (math.isfinite(v) and p.min <= v <= p.max):
                    raise DeclarationError(f"--fix {p.name}={v:g}: outside the declared "
                                           f"bounds [{p.min:g}, {p.max:g}] {p.unit}")
                p = dataclasses.replace(p, value=v, fixed=True)
            elif p.name in free:
                p = dataclasses.replace(p, fixed=False)
            rows.append(p)
        other = copy.copy(self)
        other.parameters = tuple(rows)
        return other

    # ------------------------------------------------------------------- numerics
    def step(self, x, u, d, p=None):
        """One sample of the model (numpy): ``(x_next, y)`` for arrays whose last axis is
        the declared order (``x`` (..., nx), ``u`` (..., nu), ``d`` (..., nd)); ``p`` (np,)
        or (..., np), default the declared values. Batches go through ``F.map``."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        p = self.values if p is None else np.asarray(p, dtype=float)
        u = np.asarray(u, dtype=float).reshape(x.shape[:-1] + (self.nu,)) if self.nu else \
            np.zeros(x.shape[:-1] + (0,))
        d = np.asarray(d, dtype=float).reshape(x.shape[:-1] + (self.nd,)) if self.nd else \
            np.zeros(x.shape[:-1] + (0,))
        batch = x.shape[:-1]
        n = int(np.prod(batch)) if batch else 1
        P = np.broadcast_to(p, batch + (self.np,)).reshape(n, self.np)
        fn = self.F if n == 1 else self.F.map(n)
        xn, y = fn(x.reshape(n, self.nx).T, u.reshape(n, self.nu).T, d.reshape(n, self.nd).T,
                   P.T)
        return (np.asarray(xn).T.reshape(batch + (self.nx,)),
                np.asarray(y).T.reshape(batch + (self.ny,)))

    def simulate(self, x0, u, d, p=None):
        """Open loop over H samples, vectorised over a batch of starts (numpy).

        ``x0`` (..., nx); ``u`` (..., H, nu); ``d`` (..., H, nd); ``p`` (np,) or (..., np).
        Returns ``x`` (..., H + 1, nx) and ``y`` (..., H, ny).
        """
        x0 = np.asarray(x0, dtype=float)
        u = np.asarray(u, dtype=float)
        d = np.asarray(d, dtype=float)
        H = u.shape[-2] if self.nu else d.shape[-2]
        batch = x0.shape[:-1]
        X = np.empty(batch + (H + 1, self.nx))
        Y = np.empty(batch + (H, self.ny))
        X[..., 0, :] = x0
        for k in range(H):
            X[..., k + 1, :], Y[..., k, :] = self.step(
                X[..., k, :], u[..., k, :] if self.nu else np.zeros(batch + (0,)),
                d[..., k, :] if self.nd else np.zeros(batch + (0,)), p)
        return X, Y

    def describe(self) -> list[str]:
        """One line per declared row (for ``acid fit`` and the docs)."""
        form = (f"ODE, RK4 x {self.integrator.substeps}" if self.continuous
                else "discrete step")
        lines = [f"model {self.name!r} ({form}, Ts = {self.Ts:g} s), declared in "
                 f"{self.source}"]
        for s in self.states:
            lines.append(f"state {s.name} [{s.unit}]" + ("" if s.measured else " (latent)"))
        for kind, rows in (("input", self.inputs), ("disturbance", self.disturbances),
                           ("output", self.outputs)):
            lines += [f"{kind} {r.name} [{r.unit}]" for r in rows]
        return lines


def _numbered_groups(names) -> dict:
    """``{"gamma": Group(("gamma1", ..., "gamma7"))}``: names that differ only by a
    trailing number 1..n form a group."""
    out = {}
    for n in names:
        stem = n.rstrip("0123456789")
        if stem != n and stem not in out:
            k = 1
            while f"{stem}{k}" in names:
                k += 1
            if k > 2:
                out[stem] = Group(tuple(f"{stem}{i}" for i in range(1, k)))
    return out


def _reads(expr, yr, outputs, names) -> bool:
    idx = [i for i, o in enumerate(outputs) if o.name in names]
    return any(ca.depends_on(expr, yr[i]) for i in idx)


def user_line(exc: BaseException, source: str) -> int | None:
    """The line of the model file where ``exc`` was raised (innermost frame in the file)."""
    line = None
    for fr in traceback.extract_tb(exc.__traceback__):
        try:
            if Path(fr.filename).resolve() == Path(source).resolve():
                line = fr.lineno
        except OSError:
            continue
    return line
