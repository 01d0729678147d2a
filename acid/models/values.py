"""Values of a declared model's parameter table: one class for every declaration.

``ParameterValues`` holds a value for each declared parameter (by name, or as ``theta`` in
the table's order), the declared constants a file gives another value (the paper's COP),
per-experiment values, standard errors, what a group's view keeps beside its values (the
econ power map's domain), the sample time, a label and the provenance. Names of the
declaration read as attributes: ``p.gamma1``, a group ``p.gamma`` (``gamma1..gamma7``) or
``p.power_map`` (its declared view), a constant ``p.c_p``. What makes values implausible
is the declaration's ``checks`` (``problems()``).

One file format, naming its model (``"format": "acid-declared-params"``); the reader also
takes the layouts acid wrote before it (the paper's ``gamma``/``tau``/``beta`` lists, the
econ model's ``"model": "econ"`` file), one-line ``DataError`` naming the file and the key.
``acid.models.params.ModelParams`` and ``acid.models.econ_params.EconParams`` are this class bound
to
the paper's and the econ declaration.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import casadi as ca
import numpy as np

from acid._io import json_safe, write_json
from acid.errors import AcidError, DataError
from acid.models.declaration import Model
from acid.models.loader import BUILT_IN, load

#: The ``format`` key of a parameter file.
FORMAT = "acid-declared-params"
#: (model of the file given, model wanted) -> how to make the file wanted from it
MADE_FROM = {("car_cabin", "car_ac"): "`acid car fit LOGS --params FILE` writes the car_ac "
             "file from it (the A/C power rows fitted on the logs)",
             ("car_ac", "car_cabin"): "validate it with --model car_ac"}
_LOADED: dict[str, Model] = {}
#: {model name: the class bound to it} (``ModelParams``, ``EconParams``): what a file of
#: that model is read as
BINDINGS: dict[str, type] = {}


def declaration(ref: str | Model) -> Model:
    """The declaration a ``ParameterValues.model`` names (built-in name or model file)."""
    if isinstance(ref, Model):
        return ref
    if ref not in _LOADED:
        _LOADED[ref] = load(ref)
    return _LOADED[ref]


def reference(m: Model) -> str:
    """How values name their declaration: a built-in's name, else its file."""
    builtin = m.name in BUILT_IN and Path(m.source).resolve() == Path(
        load(m.name).source).resolve()
    return m.name if builtin else m.source


@dataclass(init=False, eq=False)
class ParameterValues:
    """Values of a declared model (module docstring). ``values``: {name: value} of every
    parameter, in its declared unit; ``constants``: the declared constants given another
    value; ``per_experiment``: {name: {experiment id: value}}; ``stderr``: {name: standard
    error}; ``info``: {group: what its view keeps beside the values}; ``Ts``: s;
    ``source``: where they come from when results should say it (a file, a fit)."""

    model: str
    values: dict
    constants: dict
    per_experiment: dict
    stderr: dict
    info: dict
    Ts: float
    name: str
    provenance: dict
    source: str | None
    #: the declaration a binding (``ModelParams``, ``EconParams``) is for
    MODEL: ClassVar[str | None] = None

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        BINDINGS.setdefault(cls.MODEL, cls)

    def __init__(self, values=None, *, model=None, constants=None, per_experiment=None,
                 stderr=None, info=None, Ts=None, name=None, provenance=None, source=None,
                 **named):
        m = declaration(model or self.MODEL)
        names = m.parameter_names
        vals = dict(zip(names, m.values.tolist(), strict=True))
        if isinstance(values, dict):
            vals.update(values)
        elif values is not None:
            theta = np.asarray(values, dtype=float).ravel()
            if theta.size != len(names):
                raise DataError(f"theta needs {len(names)} numbers, got {theta.size}")
            vals = dict(zip(names, theta.tolist(), strict=True))
        declared = {c.name: c for c in m.constants}
        consts, info = dict(constants or {}), {k: dict(v) for k, v in (info or {}).items()}
        for key, v in named.items():
            grp = m.groups.get(key)
            if key in vals:
                vals[key] = v
            elif key in declared:
                consts[key] = v
            elif grp is None:
                raise DataError(f"{m.name!r} has no parameter, group or constant {key!r}")
            else:
                if grp.view is not None and hasattr(v, "coef"):
                    info[key] = {f.name: getattr(v, f.name) for f in dataclasses.fields(v)
                                 if f.name != "coef"}
                    v = v.coef
                v = tuple(v)
                if len(v) != len(grp.names):
                    raise DataError(f"parameter {key!r} needs {len(grp.names)} numbers, got "
                                    f"{len(v)}")
                vals.update(zip(grp.names, v, strict=True))
        unknown = sorted(set(vals) - set(names))
        if unknown:
            raise DataError(f"parameter {unknown[0]!r} is not in model {m.name!r}")
        for key, v in list(vals.items()) + list(consts.items()):
            if isinstance(v, bool) or not isinstance(v, (int, float, np.number)) \
                    or not math.isfinite(v):
                raise DataError(f"parameter {key!r} has a non-finite value: {v!r}")
        for key, v in consts.items():
            c = declared[key]
            if not c.min <= v <= c.max:
                raise DataError(f"{key} = {v:g} is implausible (expected {c.min:g}..{c.max:g})")
        Ts = m.Ts if Ts is None else float(Ts)
        if not (math.isfinite(Ts) and Ts > 0):
            raise DataError(f"parameter 'Ts' must be a positive number, got {Ts}")
        for key, v in (("model", reference(m)), ("Ts", Ts), ("name", str(name or m.name)),
                       ("values", {n: float(vals[n]) for n in names}),
                       ("constants", {k: float(v) for k, v in consts.items()
                                      if float(v) != declared[k].value}),
                       ("per_experiment", dict(per_experiment or {})), ("info", info),
                       ("stderr", dict(stderr or {})), ("provenance", dict(provenance or {})),
                       ("source", source), ("_declaration", m)):
            object.__setattr__(self, key, v)

    def __setattr__(self, key, value):   # frozen, bindings included
        raise dataclasses.FrozenInstanceError(f"cannot assign to {key!r}")

    __delattr__ = __setattr__

    # ------------------------------------------------------------------ views
    @property
    def declaration(self) -> Model:
        """The ``Model`` these values were made for (after unpickling: by its reference)."""
        m = self.__dict__.get("_declaration")
        return declaration(self.model) if m is None else m

    def __getstate__(self):   # pickled without the Model (it holds the user's functions)
        return {k: v for k, v in self.__dict__.items() if k != "_declaration"}

    def __getattr__(self, key):   # p.gamma1, p.gamma, p.power_map, p.c_p
        d = self.__dict__
        if key.startswith("__") or "values" not in d:
            raise AttributeError(key)
        if key in d["values"]:
            return d["values"][key]
        m = self.declaration
        grp = m.groups.get(key)
        if grp is not None:
            vals = tuple(d["values"][n] for n in grp.names)
            return vals if grp.view is None else grp.view(coef=vals, **d["info"].get(key, {}))
        for c in m.constants:
            if c.name == key:
                return d["constants"].get(key, c.value)
        raise AttributeError(f"{type(self).__name__} of {m.name!r} has no {key!r}")

    def _key(self) -> tuple:
        return (self.model, tuple(self.values.items()), tuple(sorted(self.constants.items())),
                self.Ts, self.name, json.dumps(json_safe(self.info), sort_keys=True))

    def __eq__(self, other):
        return isinstance(other, ParameterValues) and self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    @property
    def label(self) -> str:
        """How results name these values: their ``source``, else their name."""
        return self.source or self.name

    @property
    def theta(self) -> np.ndarray:
        """Every parameter as one vector, in the declared order."""
        return np.array(list(self.values.values()))

    theta_all = theta   # the name the econ controllers read

    def as_dict(self) -> dict[str, float]:
        return dict(self.values)

    def replace(self, **changes) -> ParameterValues:
        """A copy with fields, parameters, groups or constants changed by name."""
        return dataclasses.replace(self, **{"model": self.declaration, **changes})

    def with_theta(self, theta, **changes) -> ParameterValues:
        """A copy with every parameter from the vector ``theta`` (declared order)."""
        return self.replace(values=np.asarray(theta, dtype=float), **changes)

    @classmethod
    def from_vector(cls, theta, **fields) -> ParameterValues:
        return cls(values=np.asarray(theta, dtype=float), **fields)

    def perturbed(self, rel: float, rng: np.random.Generator, names=None) -> ParameterValues:
        """A copy with ``names`` (default: what the state equations read, outputs
        substituted) scaled by (1 + rel N(0, 1)), in table order; for mismatch studies."""
        m = self.declaration
        if names is None:
            x_next = m.F(m._x, m._u, m._d, m._p)[0]
            names = [n for i, n in enumerate(m.parameter_names)
                     if ca.depends_on(x_next, m._p[i])]
        names = [n for n in m.parameter_names if n in set(names)]
        scale = 1 + rel * rng.standard_normal(len(names))
        return self.replace(**{n: self.values[n] * s for n, s in zip(names, scale, strict=True)},
                            name=f"{self.name}-perturbed")

    # ------------------------------------------------------------ plausibility
    def problems(self) -> list[str]:
        """What the declaration's ``checks`` find implausible (empty if nothing)."""
        checks = self.declaration.checks
        return list(checks(self)) if checks is not None else []

    stability_problems = problems

    def check(self, source: str = "parameters") -> ParameterValues:
        """Refuse (``DataError``, one line) what ``problems`` finds; returns self."""
        problems = self.problems()
        if problems:
            raise DataError(f"{source}: {problems[0]} (--allow-unstable uses them anyway)")
        return self

    # ------------------------------------------------------------------- I/O
    def to_json_dict(self) -> dict:
        m = self.declaration
        consts = {c.name: {"value": self.constants.get(c.name, c.value), "unit": c.unit}
                  for c in m.constants}
        return json_safe({
            "format": FORMAT, "model": m.name, "model_source": m.source, "name": self.name,
            "Ts": self.Ts, "units": "as declared per parameter; temperatures in kelvin",
            "parameters": {p.name: {"value": self.values[p.name], "unit": p.unit,
                                    "stderr": self.stderr.get(p.name), "meaning": p.description}
                           for p in m.parameters},
            "per_experiment": {n: {"experiments": list(map(int, v)), "values": list(v.values())}
                               for n, v in self.per_experiment.items()},
            "constants": consts, "info": self.info, "provenance": self.provenance,
            # the groups as lists, for readers of the files before this format
            **{g: list(getattr(self, g)) for g, grp in m.groups.items() if grp.view is None}})

    def to_json(self, path: str | Path, extra: dict | None = None) -> Path:
        """Write the parameter file atomically; ``extra`` adds keys (e.g. the fit report)."""
        return write_json(path, json_safe({**self.to_json_dict(), **(extra or {})}))

    @classmethod
    def from_json_dict(cls, d, source: str = "params", model=None) -> ParameterValues:
        """The one reader: a parsed parameter file of ``model`` (default: the binding's, else
        the one the file names; a file naming none is the paper's)."""
        if not isinstance(d, dict):
            raise DataError(f"{source}: expected a JSON object (a parameter file)")
        named = d.get("model", "paper")
        for key, kind in (("model", str), ("name", str), ("provenance", dict), ("info", dict),
                          ("per_experiment", dict)):
            if key in d and not isinstance(d[key], kind):
                raise DataError(f"{source}: {key!r} must be a "
                                f"{'text' if kind is str else 'JSON object'}, got "
                                f"{type(d[key]).__name__}")
        try:
            m = declaration(model or cls.MODEL or (named if named in BUILT_IN or not isinstance(
                d.get("model_source"), str) else d["model_source"]))
        except AcidError as exc:   # a model file that is gone or wrong
            raise DataError(f"{source}: {exc}") from None
        if named != m.name:
            hint = MADE_FROM.get((named, m.name))
            raise DataError(f"{source}: parameters of model {named!r}, not {m.name!r}"
                            + (f"; {hint}" if hint else ""))
        fmt = d.get("format")
        if fmt is not None and fmt != FORMAT:
            raise DataError(f"{source}: unknown format {fmt!r} (expected {FORMAT!r})")
        names = m.parameter_names
        units = d.get("units", "")
        if not isinstance(units, str):
            raise DataError(f"{source}: 'units' must be a text, got {type(units).__name__}")
        if "celsius" in units.lower():
            raise DataError(f"{source}: parameters in a Celsius convention are not supported "
                            "(acid's are in kelvin)")
        vals, stderr, info, consts = {}, {}, {}, {}
        par = d.get("parameters", {})
        if not isinstance(par, dict):
            raise DataError(f"{source}: 'parameters' must be a JSON object")
        rows = [(n, row, f"parameters.{n}") for n, row in par.items()]
        if fmt is None:   # the layouts before the one format: values at the top level
            rows += [(k, v, k) for k, v in d.items() if k in names]
            for g, grp in m.groups.items():
                if g not in d:
                    continue
                v = d[g]
                if grp.view is not None and isinstance(v, dict):
                    fields = {f.name for f in dataclasses.fields(grp.view)} - {"coef"}
                    info[g] = {k: v[k] for k in fields if v.get(k) is not None}
                    v = v.get("coef")
                vals.update(zip(grp.names, _numbers(v, g, len(grp.names), source),
                                strict=True))
        for n, row, key in rows:
            if n not in names:
                raise DataError(f"{source}: parameter {n!r} is not in model {m.name!r}")
            v = row.get("value") if isinstance(row, dict) else row
            vals[n] = _number(v, f"{key}.value" if isinstance(row, dict) else key, source)
            if isinstance(row, dict) and row.get("stderr") is not None:
                stderr[n] = _number(row["stderr"], f"{key}.stderr", source)
        missing = [n for n in names if n not in vals]
        if fmt is None and missing:
            grp = next((g for g, v in m.groups.items() if missing[0] in v.names), missing[0])
            raise DataError(f"{source}: missing key {grp!r}")
        block = d.get("constants", {})
        block = block if isinstance(block, dict) else {}
        for c in m.constants:
            v = d.get(c.name, block.get(c.name))
            if v is not None:
                consts[c.name] = _number(v.get("value") if isinstance(v, dict) else v,
                                         c.name, source)
        per = {}
        for n, row in (d.get("per_experiment") or {}).items():
            if n not in names:
                raise DataError(f"{source}: per-experiment parameter {n!r} is not in the model")
            try:
                per[n] = {int(e): float(v) for e, v in zip(row["experiments"], row["values"],
                                                           strict=True)}
            except (KeyError, TypeError, ValueError):
                raise DataError(f"{source}: per_experiment {n!r} needs 'experiments' and "
                                "'values' of equal length") from None
        try:
            out = (cls if cls.MODEL else BINDINGS.get(m.name, cls))(
                vals, model=m, constants=consts, per_experiment=per, stderr=stderr,
                info={**info, **d.get("info", {})}, Ts=_number(d.get("Ts", m.Ts), "Ts", source),
                name=d.get("name", Path(source).stem), provenance=d.get("provenance"))
            for g in (g for g, grp in m.groups.items() if grp.view is not None):
                getattr(out, g)   # a view refuses what it cannot show (the map's domain)
            return out
        except DataError as exc:
            raise DataError(f"{source}: {exc}") from None
        except (TypeError, ValueError, IndexError, KeyError, AttributeError) as exc:
            raise DataError(f"{source}: malformed 'info' ({exc})") from None

    @classmethod
    def from_json(cls, path: str | Path, model=None) -> ParameterValues:
        """Read and validate a parameter file (one-line ``DataError`` on any problem)."""
        from acid._readers import load_json

        d = load_json(Path(path), "parameter file", DataError, top=None)
        return cls.from_json_dict(d, source=str(path), model=model)


def _number(value, key: str, source: str) -> float:
    """A JSON number (not a bool, not a string) as a finite float."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise DataError(f"{source}: malformed parameter values: {key!r} must be a number, "
                        f"got {_show(value)}")
    try:
        out = float(value)
    except OverflowError:
        raise DataError(f"{source}: {key!r} = {value} is too large") from None
    if not math.isfinite(out):
        raise DataError(f"{source}: parameter {key!r} has a non-finite value: {out}")
    return out


def _numbers(value, key: str, n: int, source: str) -> tuple[float, ...]:
    """A JSON list of ``n`` numbers (a string or an object is refused)."""
    if not isinstance(value, (list, tuple)):
        raise DataError(f"{source}: malformed parameter values: {key!r} must be a list of {n} "
                        f"numbers, got {_show(value)}")
    if len(value) != n:
        raise DataError(f"{source}: parameter {key!r} needs {n} numbers, got {len(value)}")
    return tuple(_number(v, f"{key}[{i}]", source) for i, v in enumerate(value))


def _show(value) -> str:
    text = json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."
