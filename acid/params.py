"""Values of the paper's model (eqs. 1-5): a container over the declaration's parameter
table (``acid.models.paper``), what the controllers, plants and parameter files use.

gamma1..gamma7 and tau1..tau3 parameterise eqs. 1-3 with **temperatures in kelvin** and W_bl
in kg/s at Ts = 5 s; beta1..beta3 the blower power curve (eq. 5, W with W_bl in kg/s).
``paper()`` is the set identified from CoolSim in the paper (section II-B-2 and eq. 5).
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from acid._io import write_json
from acid.claims import MODEL as _PAPER_MODEL
from acid.claims import TABLE_II as _TABLE_II
from acid.errors import DataError
from acid.models.paper import PARAMETER_TABLE as _DECLARED_TABLE

UNITS_CONVENTION = (
    "temperatures in kelvin, W_bl in kg/s, Ts = 5 s; "
    "gamma1,2 [1], gamma3 [s/kg], gamma4,5 [1], gamma6 [1], gamma7 [K s/kg], "
    "tau1,2,3 [K]; beta1 [W s^2/kg^2], beta2 [W s/kg], beta3 [W]"
)

#: (name, unit, meaning) of every parameter, in the order of the vectors: the paper
#: declaration's table (``acid.models.paper``), the one parameter table.
PARAMETER_TABLE = _DECLARED_TABLE


def _block(prefix: str) -> slice:
    """The contiguous slice of ``PARAMETER_TABLE`` whose names start with ``prefix``."""
    idx = [i for i, row in enumerate(PARAMETER_TABLE) if row[0].rstrip("0123456789") == prefix]
    if idx != list(range(idx[0], idx[-1] + 1)):
        raise AssertionError(f"parameters {prefix}* are not contiguous in PARAMETER_TABLE")
    return slice(idx[0], idx[-1] + 1)


#: Named slices of the 13-vector ``ModelParams.theta`` (``PARAMETER_TABLE`` order).
GAMMA = _block("gamma")
TAU = _block("tau")
BETA = _block("beta")
#: gamma and tau: the parameters of the dynamics, eqs. 1-3 (refined by output error).
DYNAMICS = slice(GAMMA.start, TAU.stop)

# The paper's values live in the claims registry (the one place the paper's numbers are
# written); the names below are kept for the code and tests that import them.
PAPER_GAMMA = _PAPER_MODEL.gamma
PAPER_TAU = _PAPER_MODEL.tau
PAPER_BETA = _PAPER_MODEL.beta

#: Table II range of the blower flow W_bl (kg/s) over which the cabin pole is checked.
W_BL_RANGE = (_TABLE_II.W_bl_min, _TABLE_II.W_bl_max)
#: Operating point at which steady temperatures are checked for plausibility (K, kg/s).
CHECK_T_EVAP_SET, CHECK_W_BL = 278.15, 0.1
#: A steady temperature outside this range (K) means parameters in another convention.
PLAUSIBLE_STEADY_K = (200.0, 400.0)
#: Plausible specific heat of air, J/(kg K) (Table II: 1008), and COP range.
C_P_RANGE = (900.0, 1100.0)
ETA_COP_RANGE = (0.1, 50.0)


@dataclass(frozen=True)
class ModelParams:
    """Parameters of eqs. 1-5.

    Attributes
    ----------
    gamma : tuple of 7 floats (units in ``PARAMETER_TABLE``), kelvin convention.
    tau : tuple of 3 floats, K.
    beta : tuple of 3 floats, blower power coefficients (W, W_bl in kg/s).
    c_p : specific heat of air, J/(kg K) (Table II: 1008).
    eta_cop : COP used by the compressor power model eq. 4 (Table II: 3.5).
    Ts : sample time, s.
    name : a label for tables and figures.
    provenance : where the values came from (data file, method, ...).
    """

    gamma: tuple[float, ...]
    tau: tuple[float, ...]
    beta: tuple[float, ...] = PAPER_BETA
    c_p: float = _TABLE_II.c_p
    eta_cop: float = _TABLE_II.eta_cop
    Ts: float = _TABLE_II.Ts
    name: str = "custom"
    provenance: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        for attr, n in (("gamma", 7), ("tau", 3), ("beta", 3)):
            vals = tuple(float(v) for v in getattr(self, attr))
            if len(vals) != n:
                raise DataError(f"parameter {attr!r} needs {n} numbers, got {len(vals)}")
            if not all(math.isfinite(v) for v in vals):
                raise DataError(f"parameter {attr!r} has a non-finite value: {vals}")
            object.__setattr__(self, attr, vals)
        for attr in ("c_p", "eta_cop", "Ts"):
            v = float(getattr(self, attr))
            if not (math.isfinite(v) and v > 0):
                raise DataError(f"parameter {attr!r} must be a positive number, got {v}")
            object.__setattr__(self, attr, v)

    # ------------------------------------------------------------------ views

    def parameter_set(self):
        """These values as ``acid.ident.validate.ParameterSet`` of the declaration
        ``acid.models.paper`` (what ``acid validate`` runs)."""
        from acid.ident.validate import ParameterSet

        return ParameterSet(values=self.theta, source=self.name, label=self.name,
                            provenance=self.provenance, model="paper")

    @property
    def theta(self) -> np.ndarray:
        """All 13 parameters as one vector, in ``PARAMETER_TABLE`` order."""
        return np.array(self.gamma + self.tau + self.beta)

    def with_theta(self, theta, **changes) -> ModelParams:
        """A copy with gamma, tau, beta from a 13-vector (``PARAMETER_TABLE`` order)."""
        theta = np.asarray(theta, dtype=float)
        if theta.shape != (len(PARAMETER_TABLE),):
            raise DataError(f"theta needs {len(PARAMETER_TABLE)} numbers, got {theta.shape}")
        return self.replace(gamma=tuple(theta[GAMMA]), tau=tuple(theta[TAU]),
                            beta=tuple(theta[BETA]), **changes)

    def as_dict(self) -> dict[str, float]:
        """{name: value} for the 13 parameters."""
        return {row[0]: float(v) for row, v in zip(PARAMETER_TABLE, self.theta, strict=True)}

    def replace(self, **changes) -> ModelParams:
        """A copy with some fields changed (frozen dataclass helper)."""
        return dataclasses.replace(self, **changes)

    def perturbed(self, rel: float, rng: np.random.Generator) -> ModelParams:
        """A copy with every gamma/tau scaled by (1 + rel * N(0, 1)); for mismatch studies."""
        g = np.array(self.gamma) * (1 + rel * rng.standard_normal(7))
        t = np.array(self.tau) * (1 + rel * rng.standard_normal(3))
        return self.replace(gamma=tuple(g), tau=tuple(t), name=f"{self.name}-perturbed")

    # ------------------------------------------------------------ plausibility
    def stability_problems(self) -> list[str]:
        """Why eqs. 1-3 with these parameters are unstable or not in kelvin (empty if fine).

        * eq. 2: T_evap(k+1) = (gamma4 + gamma5) T_evap(k) + ...: needs |gamma4 + gamma5| < 1;
        * eq. 1: the cabin pole 1 - gamma1 - gamma2 - gamma3 W_bl must lie inside the unit
          circle over Table II's W_bl range (0.05-0.15 kg/s; it is linear in W_bl, so both
          ends suffice);
        * the steady T_evap at a 5 degC set-point and eq. 3's T_ain there at 0.1 kg/s must be
          temperatures in kelvin (200-400 K): parameters fitted in degC fail this.
        """
        g, t = self.gamma, self.tau
        out = []
        a_evap = g[3] + g[4]
        if not abs(a_evap) < 1.0:
            out.append(f"eq. 2 is unstable: gamma4 + gamma5 = {a_evap:.6g}, needs "
                       "|gamma4 + gamma5| < 1")
        for W in W_BL_RANGE:
            pole = 1.0 - g[0] - g[1] - g[2] * W
            if not abs(pole) < 1.0:
                out.append(f"eq. 1 is unstable: the cabin pole 1 - gamma1 - gamma2 - gamma3 "
                           f"W_bl = {pole:.6g} at W_bl = {W:g} kg/s lies outside the unit "
                           "circle (gamma1, gamma2, gamma3)")
                break
        if not out:
            lo, hi = PLAUSIBLE_STEADY_K
            T_evap = (t[1] - g[4] * CHECK_T_EVAP_SET) / (1.0 - a_evap)
            T_ain = g[5] * T_evap + g[6] * CHECK_W_BL + t[2]
            for name, value, keys in (("steady T_evap", T_evap, "gamma4, gamma5, tau2"),
                                      ("eq. 3 T_ain", T_ain, "gamma6, gamma7, tau3")):
                if not (math.isfinite(value) and lo <= value <= hi):
                    out.append(f"{name} = {value:.6g} K at a 5 degC set-point and W_bl = "
                               f"{CHECK_W_BL:g} kg/s is not a plausible temperature in kelvin "
                               f"({keys})")
                    break
        return out

    def check_stable(self, source: str = "parameters") -> ModelParams:
        """Refuse (``DataError``, one line) what ``stability_problems`` finds; returns self."""
        problems = self.stability_problems()
        if problems:
            raise DataError(f"{source}: {problems[0]} (--allow-unstable uses them anyway)")
        return self

    # ------------------------------------------------------------------- I/O
    def to_json_dict(self) -> dict:
        return {
            "name": self.name,
            "gamma": list(self.gamma),
            "tau": list(self.tau),
            "beta": list(self.beta),
            "c_p": self.c_p,
            "eta_cop": self.eta_cop,
            "Ts": self.Ts,
            "units": UNITS_CONVENTION,
            "provenance": self.provenance,
        }

    def to_json(self, path: str | Path, extra: dict | None = None) -> Path:
        """Write ``params.json`` atomically; ``extra`` adds keys (e.g. the fit report)."""
        d = self.to_json_dict()
        if extra:
            d.update(extra)
        return write_json(path, d)

    @classmethod
    def from_json_dict(cls, d: dict, source: str = "params") -> ModelParams:
        """Build from a parsed params.json, checking every key's type (one-line errors)."""
        if not isinstance(d, dict):
            raise DataError(f"{source}: expected a JSON object with gamma, tau, beta")
        for key in ("gamma", "tau"):
            if key not in d:
                raise DataError(f"{source}: missing key {key!r}")
        units = d.get("units", UNITS_CONVENTION)
        if not isinstance(units, str):
            raise DataError(f"{source}: 'units' must be a text, got {type(units).__name__}")
        if "celsius" in units.lower():
            raise DataError(f"{source}: parameters in a Celsius convention are not supported "
                            "(acid's gamma/tau are in kelvin)")
        vectors = {key: _numbers(d.get(key, default), key, n, source)
                   for key, n, default in (("gamma", 7, None), ("tau", 3, None),
                                           ("beta", 3, PAPER_BETA))}
        scalars = {key: _number(d.get(key, default), key, source)
                   for key, default in (("c_p", _TABLE_II.c_p), ("eta_cop", _TABLE_II.eta_cop),
                                        ("Ts", _TABLE_II.Ts))}
        for key, (lo, hi) in (("c_p", C_P_RANGE), ("eta_cop", ETA_COP_RANGE)):
            if not lo <= scalars[key] <= hi:
                raise DataError(f"{source}: {key} = {scalars[key]:g} is implausible "
                                f"(expected {lo:g}..{hi:g})")
        name = d.get("name", Path(source).stem)
        if not isinstance(name, str):
            raise DataError(f"{source}: 'name' must be a text, got {type(name).__name__}")
        provenance = d.get("provenance") or {}
        if not isinstance(provenance, dict):
            raise DataError(f"{source}: 'provenance' must be a JSON object, got "
                            f"{type(provenance).__name__}")
        try:
            return cls(**vectors, **scalars, name=name, provenance=provenance)
        except DataError as exc:
            raise DataError(f"{source}: {exc}") from None

    @classmethod
    def from_json(cls, path: str | Path) -> ModelParams:
        """Read and validate a ``params.json`` (one-line ``DataError`` on any problem)."""
        from acid._readers import load_json

        path = Path(path)
        d = load_json(path, "parameter file", DataError, top=None)
        return cls.from_json_dict(d, source=str(path))


def paper() -> ModelParams:
    """The paper's identified parameters (section II-B-2, eq. 5 and Table II), kelvin convention."""
    return ModelParams(
        gamma=PAPER_GAMMA,
        tau=PAPER_TAU,
        beta=PAPER_BETA,
        c_p=_TABLE_II.c_p,
        eta_cop=_TABLE_II.eta_cop,
        Ts=_TABLE_II.Ts,
        name="paper",
        provenance={"source": "Wang et al., ACC 2018, section II-B-2, eq. 5, Table II "
                              "(acid.claims)"},
    )


def _number(value, key: str, source: str) -> float:
    """A JSON number (not a bool, not a string) as float."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise DataError(f"{source}: malformed parameter values: {key!r} must be a number, "
                        f"got {_show(value)}")
    try:
        return float(value)
    except OverflowError:
        raise DataError(f"{source}: {key!r} = {value} is too large") from None


def _numbers(value, key: str, n: int, source: str) -> tuple[float, ...]:
    """A JSON list of ``n`` numbers as a float tuple (a string or an object is refused)."""
    if not isinstance(value, (list, tuple)):
        raise DataError(f"{source}: malformed parameter values: {key!r} must be a list of {n} "
                        f"numbers, got {_show(value)}")
    if len(value) != n:
        raise DataError(f"{source}: parameter {key!r} needs {n} numbers, got {len(value)}")
    out = tuple(_number(v, f"{key}[{i}]", source) for i, v in enumerate(value))
    if not all(math.isfinite(v) for v in out):
        raise DataError(f"{source}: parameter {key!r} has a non-finite value: {out}")
    return out


def _show(value) -> str:
    text = json.dumps(value) if isinstance(value, (str, int, float, bool, type(None))) else \
        f"a JSON {'object' if isinstance(value, dict) else type(value).__name__}"
    return text if len(text) <= 40 else text[:37] + "..."


def load_params(spec: str | Path | None, allow_unstable: bool = False) -> ModelParams:
    """``None`` or ``"paper"`` gives the paper preset; anything else is a params.json path.

    Unstable or implausible parameters (``ModelParams.stability_problems``) are refused with
    a one-line ``DataError`` unless ``allow_unstable``.
    """
    if spec is None or str(spec) == "paper":
        return paper()
    p = ModelParams.from_json(spec)
    return p if allow_unstable else p.check_stable(str(spec))


def fitted(result, eta_cop: float | None = None, name: str | None = None,
           provenance: dict | None = None) -> ModelParams:
    """The paper's parameters from a fit of its declaration (``acid.ident.fit_model(
    "paper", ...)``); ``eta_cop`` replaces Table II's COP (eq. 4, e.g. ``eta_cop_of``)."""
    changes = {} if eta_cop is None or not math.isfinite(eta_cop) or eta_cop <= 0 \
        else {"eta_cop": float(eta_cop)}
    return paper().with_theta(np.asarray(result.values, dtype=float),
                              name=name or f"fit-{result.method}",
                              provenance=dict(provenance or {}), **changes)


def eta_cop_of(ds, c_p: float = _TABLE_II.c_p) -> tuple[float, float]:
    """eta_cop and its standard error from a dataset's P_comp, T_amb, W_bl and T_ain (eq. 4,
    ``acid.models.paper.estimate_eta_cop``); NaN when the data lack a channel."""
    from acid.models.paper import estimate_eta_cop

    if not all(n in ds for n in ("P_comp", "T_amb", "W_bl", "T_ain")):
        return math.nan, math.nan
    return estimate_eta_cop(ds.get("W_bl", "kg/s"), ds.get("T_ain", "K"), ds.get("T_amb", "K"),
                            ds.get("P_comp", "W"), c_p)


def as_params(obj) -> ModelParams:
    """The model parameters of ``obj``: a ``ModelParams`` as is, a fit of the paper's
    declaration (``acid.ident.fit_model``'s result, or anything with ``params``),
    ``None``/``"paper"`` for the preset or a params.json path.
    """
    if isinstance(obj, ModelParams):
        return obj
    inner = getattr(obj, "params", None)
    if isinstance(inner, ModelParams):
        return inner
    if getattr(obj, "model", None) == "paper" and hasattr(obj, "values"):
        return fitted(obj)
    if obj is None or isinstance(obj, (str, Path)):
        return load_params(obj)
    raise DataError(f"expected model parameters (ModelParams, a fit result or a params.json "
                    f"path), got {type(obj).__name__}")
