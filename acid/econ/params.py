"""Parameters of the econ model (:mod:`acid.models.econ`) as a named, unit-carrying table.

The table is the declaration's (:mod:`acid.models.econ`); every value is identified from data
by :func:`identify` (``acid fit --model econ``, acid.ident's staged fit); nothing is read from
a plant's configuration. The physical constants the model uses
(specific heat of air, latent heat of water, the atmosphere) are not fitted and are listed in
``CONSTANTS``.

A parameter file is JSON with ``"model": "econ"`` (the paper's files have no ``model`` key);
:func:`load_any_params` reads either family.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from acid._io import json_safe, write_json
from acid.errors import DataError
from acid.models import econ
from acid.models.econ import MAP_INPUTS, MAP_TERMS
from acid.params import PAPER_BETA
from acid.psychro import H_FG, P_ATM

if TYPE_CHECKING:
    from acid.ident.fit import DeclaredFitResult

MODEL_NAME = "econ"

#: (name, unit, meaning) of the thermal parameters: the declaration's table
#: (``acid.models.econ``), as are the constants and the power map's terms.
PARAMETER_TABLE: tuple[tuple[str, str, str], ...] = tuple(
    (n, u, m) for n, u, _, _, _, m in econ.THERMAL)
NAMES: tuple[str, ...] = econ.THERMAL_NAMES
UNITS: dict[str, str] = {row[0]: row[1] for row in PARAMETER_TABLE}
CONSTANTS = tuple((c.name, c.value, c.unit, c.description) for c in econ.model.constants) + (
    ("W_REF", econ.W_REF, "kg/s", "reference blower flow of ntu_ref (a normalisation)"),)


@dataclass(frozen=True)
class PowerMap:
    """Compressor electric power as a smooth map of the refrigerant-side cooling.

    ``P_comp = Q_e * f(q, t, s, a)`` (W), ``f`` (the inverse COP) a full quadratic in the
    normalised features (``MAP_TERMS``): ``q = Q_e / 1 kW``, ``t = (T_evap - 5 degC) / 5 K``,
    ``s = v / 10 m/s``, ``a = (T_amb - 30 degC) / 5 K``.

    Attributes
    ----------
    coef : (15,) coefficients of ``f`` in ``MAP_TERMS`` order (dimensionless, W/W).
    stderr : (15,) their standard errors.
    domain : {input: (low, high)} for ``MAP_INPUTS``: the range of the identification data;
        the map is not trusted outside it (:meth:`check_domain`).
    quality : fit statistics (``rms_W``, ``rms_pct`` of the mean power, ``max_pct``, ``n``,
        ``r2``; the ``steady_*`` numbers over near-steady samples only).
    """

    coef: tuple[float, ...]
    stderr: tuple[float, ...] = ()
    domain: dict = field(default_factory=dict)
    quality: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        coef = tuple(float(c) for c in self.coef)
        if len(coef) != len(MAP_TERMS) or not all(math.isfinite(c) for c in coef):
            raise DataError(f"power map needs {len(MAP_TERMS)} finite coefficients")
        object.__setattr__(self, "coef", coef)
        object.__setattr__(self, "stderr", tuple(float(c) for c in self.stderr))
        dom = {k: (float(v[0]), float(v[1])) for k, v in (self.domain or {}).items()}
        object.__setattr__(self, "domain", dom)

    def outside(self, **values) -> list[str]:
        """Inputs (``Q_e``, ``T_evap``, ``v_veh``, ``T_amb`` arrays) outside the data's range.

        Returns one phrase per offending input, e.g. ``"v_veh up to 36.1 m/s (data 0-30)"``;
        a margin of 2 % of the range (at least 0.05 units) is tolerated.
        """
        out = []
        units = dict(MAP_INPUTS)
        for name, vals in values.items():
            if name not in self.domain or vals is None:
                continue
            lo, hi = self.domain[name]
            tol = max(0.02 * (hi - lo), 0.05)
            v = np.asarray(vals, dtype=float)
            if v.size == 0:
                continue
            # what the user reads is in degC (the map works in K)
            shift, unit = (273.15, "degC") if units[name] == "K" else (0.0, units[name])
            data = f"(data {lo - shift:.4g}-{hi - shift:.4g})"
            if v.max() > hi + tol:
                out.append(f"{name} up to {v.max() - shift:.4g} {unit} {data}")
            if v.min() < lo - tol:
                out.append(f"{name} down to {v.min() - shift:.4g} {unit} {data}")
        return out

    def to_json_dict(self) -> dict:
        return json_safe({"form": "P_comp = Q_e f(q, t, s, a), f quadratic",
                          "terms": list(MAP_TERMS), "coef": list(self.coef),
                          "stderr": list(self.stderr),
                          "features": {"q": "Q_e / 1000 W", "t": "(T_evap - 278.15 K) / 5 K",
                                       "s": "v_veh / 10 m/s", "a": "(T_amb - 303.15 K) / 5 K"},
                          "domain": {k: list(v) for k, v in self.domain.items()},
                          "domain_units": dict(MAP_INPUTS), "quality": self.quality})

    @classmethod
    def from_json_dict(cls, d: dict, source: str) -> PowerMap:
        try:
            return cls(coef=tuple(d["coef"]), stderr=tuple(d.get("stderr") or ()),
                       domain=d.get("domain") or {}, quality=d.get("quality") or {})
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise DataError(f"{source}: malformed power_map ({exc})") from None


@dataclass(frozen=True)
class EconParams:
    """Identified parameters of the economic model (SI units, temperatures in K).

    Attributes
    ----------
    values : {name: value} of the 20 dynamic parameters (``PARAMETER_TABLE``).
    C_ew : effective heat capacity of the evaporator wall in the refrigerant heat, J/K
        (``Q_e = Q_coil - C_ew dT_evap/dt``), identified with the power map.
    power_map : the compressor power map.
    beta : blower power coefficients of paper eq. 5 (W, W_bl in kg/s).
    stderr : {name: standard error} of the identified values (may be empty).
    Ts : sample time of the identification data, s.
    name, provenance : label and where the values came from.
    """

    values: dict
    C_ew: float
    power_map: PowerMap
    beta: tuple[float, ...] = PAPER_BETA
    stderr: dict = field(default_factory=dict, compare=False)
    Ts: float = 5.0
    name: str = "econ"
    provenance: dict = field(default_factory=dict, compare=False)

    c_p = 1008.0
    h_fg = H_FG
    p_atm = P_ATM

    def __post_init__(self):
        missing = [n for n in NAMES if n not in self.values]
        if missing:
            raise DataError(f"econ parameters: missing {', '.join(missing)}")
        vals = {n: float(self.values[n]) for n in NAMES}
        bad = [n for n, v in vals.items() if not math.isfinite(v)]
        if bad:
            raise DataError(f"econ parameters: non-finite {', '.join(bad)}")
        for n in ("C_cab", "C_int", "C_sh", "tau_ew", "M_cab", "ntu_ref"):
            if vals[n] <= 0:
                raise DataError(f"econ parameters: {n} must be positive, got {vals[n]}")
        if not 0.0 <= vals["r_max"] < 1.0 or not 0.0 <= vals["RH_amb"] <= 1.0:
            raise DataError("econ parameters: r_max must lie in [0, 1) and RH_amb in [0, 1]")
        object.__setattr__(self, "values", vals)
        object.__setattr__(self, "beta", tuple(float(b) for b in self.beta))
        object.__setattr__(self, "C_ew", float(self.C_ew))

    def __getattr__(self, name):  # p.C_cab etc.: the model functions read attributes
        values = self.__dict__.get("values", {})
        if name in values:
            return values[name]
        raise AttributeError(name)

    def parameter_set(self):
        """These values as ``acid.ident.validate.ParameterSet`` of the declaration
        ``acid.models.econ`` (what ``acid validate`` runs)."""
        from acid.ident.validate import ParameterSet

        return ParameterSet(values=self.theta_all, source=self.name, label=self.name,
                            provenance=self.provenance, model="econ")

    @property
    def theta_all(self) -> np.ndarray:
        """Every number as the declared parameter vector of ``acid.models.econ.model``."""
        return np.concatenate([self.theta, [self.C_ew], self.power_map.coef, self.beta])

    @classmethod
    def from_vector(cls, theta, **fields) -> EconParams:
        """Parameters from the declared vector (``theta_all``); ``fields`` the rest."""
        t = np.asarray(theta, dtype=float)
        n, m = len(NAMES), len(MAP_TERMS)
        pm = fields.pop("power_map", None)
        pm = PowerMap(coef=tuple(t[n + 1:n + 1 + m])) if pm is None else \
            dataclasses.replace(pm, coef=tuple(t[n + 1:n + 1 + m]))
        return cls(values=dict(zip(NAMES, t[:n], strict=True)), C_ew=float(t[n]),
                   power_map=pm, beta=tuple(t[n + 1 + m:]), **fields)

    @property
    def theta(self) -> np.ndarray:
        """The dynamic parameters as a vector (``PARAMETER_TABLE`` order)."""
        return np.array([self.values[n] for n in NAMES])

    def replace(self, **changes) -> EconParams:
        """A copy with fields changed; dynamic parameters by name (``r_max=0.8``)."""
        vals = dict(self.values)
        for n in [k for k in changes if k in vals]:
            vals[n] = changes.pop(n)
        return dataclasses.replace(self, values=vals, **changes)

    def to_json_dict(self) -> dict:
        return json_safe({
            "model": MODEL_NAME, "name": self.name, "Ts": self.Ts,
            "parameters": {n: {"value": self.values[n], "unit": UNITS[n],
                               "stderr": self.stderr.get(n), "meaning": m}
                           for n, _, m in PARAMETER_TABLE},
            "C_ew": {"value": self.C_ew, "unit": "J/K", "stderr": self.stderr.get("C_ew")},
            "beta": list(self.beta), "power_map": self.power_map.to_json_dict(),
            "constants": {n: {"value": v, "unit": u, "source": s} for n, v, u, s in CONSTANTS},
            "units": "SI, temperatures in K, humidity ratio in kg/kg",
            "provenance": self.provenance,
        })

    def to_json(self, path: str | Path, extra: dict | None = None) -> Path:
        """Write the parameter file atomically; ``extra`` adds keys (e.g. the fit report)."""
        d = self.to_json_dict()
        d.update(extra or {})
        return write_json(path, d)

    @classmethod
    def from_json_dict(cls, d: dict, source: str = "params") -> EconParams:
        if not isinstance(d, dict) or d.get("model") != MODEL_NAME:
            raise DataError(f"{source}: not an econ parameter file (no \"model\": \"econ\")")
        try:
            par = d["parameters"]
            values = {n: par[n]["value"] for n in NAMES}
            stderr = {n: par[n].get("stderr") for n in NAMES if par[n].get("stderr") is not None}
            return cls(values=values, C_ew=d["C_ew"]["value"],
                       power_map=PowerMap.from_json_dict(d["power_map"], source),
                       beta=tuple(d.get("beta", PAPER_BETA)), stderr=stderr,
                       Ts=float(d.get("Ts", 5.0)), name=str(d.get("name", Path(source).stem)),
                       provenance=d.get("provenance") or {})
        except DataError as exc:
            raise DataError(f"{source}: {exc}") from None
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise DataError(f"{source}: malformed econ parameters (missing or bad {exc})") \
                from None

    @classmethod
    def from_json(cls, path: str | Path) -> EconParams:
        """Read and validate an econ parameter file (one-line ``DataError`` on any problem)."""
        return cls.from_json_dict(_read_json(path), source=str(path))


def _read_json(path: str | Path) -> object:
    from acid._readers import load_json

    return load_json(path, "parameter file", DataError, top=None)


def model_family(spec) -> str:
    """``"econ"`` or ``"paper"``: the model family of a parameter spec (path or 'paper')."""
    if spec is None or str(spec) == "paper":
        return "paper"
    d = _read_json(spec)
    return MODEL_NAME if isinstance(d, dict) and d.get("model") == MODEL_NAME else "paper"


def load_any_params(spec, allow_unstable: bool = False):
    """The parameters of either family: ``ModelParams`` (paper; unstable ones refused unless
    ``allow_unstable``, as ``acid.params.load_params``) or ``EconParams``."""
    from acid.params import load_params

    if model_family(spec) == MODEL_NAME:
        return EconParams.from_json(spec)
    return load_params(spec, allow_unstable=allow_unstable)


def as_any_params(obj):
    """``acid.params.as_params`` for both families: ``EconParams`` (or an econ fit result)
    as is, a path by its family, anything else as the paper's parameters."""
    from acid.params import as_params

    if isinstance(obj, EconParams):
        return obj
    if isinstance(getattr(obj, "params", None), EconParams):
        return obj.params
    if isinstance(obj, (str, Path)):
        return load_any_params(obj)
    return as_params(obj)


# ------------------------------------------------------------------ identification
#: Channels ``acid fit --model econ`` needs (P_bl optional: eq. 5 then keeps its start).
REQUIRED = econ.STATES + ("W_bl", "T_evap_set", "v_veh", "T_amb", "T_ain", "P_comp")
#: |dT_cab/dt| and |dT_evap/dt| below this count as near-steady (the map's steady error), K/s
_STEADY_RATE = 0.02


@dataclass(frozen=True)
class EconFit:
    """The econ model identified by :func:`identify`: ``params`` (with the power map's
    domain and quality) and ``fit``, acid.ident's report of the staged fit."""

    params: EconParams
    fit: DeclaredFitResult

    @property
    def power_map_quality(self) -> dict:
        return self.params.power_map.quality

    @property
    def warnings(self) -> tuple[str, ...]:
        return self.fit.warnings

    def to_json_dict(self) -> dict:
        return {**self.fit.to_json_dict(), "power_map_quality": self.power_map_quality}


def identify(ds, covariance: str = "hac", hac_bandwidth="auto") -> EconFit:
    """Identify the econ model from ``ds`` (channels ``REQUIRED``) with acid.ident's staged
    fit of the declaration (``acid.models.econ.FIT_STAGES``); warnings (``warnings.warn``,
    ``IdentifiabilityWarning``) where the excitation leaves a part unidentified."""
    import warnings

    from acid.errors import IdentifiabilityWarning
    from acid.ident.fit import provenance
    from acid.ident.stages import Stage, fit_stages

    ds.validate(require=REQUIRED, min_samples=20)
    for name, unit, need in (("v_veh", "m/s", 5.0), ("T_amb", "K", 2.0)):
        if float(np.ptp(ds.get(name, unit))) < need:
            warnings.warn(f"{name} varies by only {np.ptp(ds.get(name, unit)):.3g} {unit} in "
                          f"the data: the power map and the shell balance are not identified "
                          f"in {name} (use `acid excite --model econ`)", IdentifiabilityWarning,
                          stacklevel=2)
    for name, unit, need, part in (("W_bl", "kg/s", 0.02, "air side"),
                                   ("T_evap_set", "K", 1.0, "evaporator")):
        if float(np.ptp(ds.get(name, unit))) < need:
            raise DataError(f"{ds.source}: {name} is (nearly) constant: the {part} is not "
                            "identifiable; excite it")
    fit = fit_stages(econ.model, ds, [Stage(*s) for s in econ.FIT_STAGES],
                     covariance=covariance, hac_bandwidth=hac_bandwidth,
                     skip_s=econ.FIT_SKIP_S)
    # the map's domain and quality on the rows it was fitted on, as fitted: the model's coil
    # load from the measured state, the wall's storage from the measured end state
    x = np.column_stack([ds.get(n, u) for n, u in zip(econ.STATES, econ.STATE_UNITS,
                                                      strict=True)])
    keep = np.zeros(len(ds), dtype=bool)
    for a, b in ds.segments():
        keep[a + int(round(econ.FIT_SKIP_S / ds.Ts)): b - 1] = True
    k = np.flatnonzero(keep)
    u = np.column_stack([ds.get("W_bl", "kg/s"), ds.get("T_evap_set", "K")])[k]
    d = np.column_stack([ds.get("v_veh", "m/s"), ds.get("T_amb", "K")])[k]
    out = econ.casadi_interval(ds.Ts).map(k.size)(x[k].T, u.T, d.T,
                                                  np.tile(fit.values, (k.size, 1)).T,
                                                  np.zeros((len(econ.STATES), k.size)))
    Q_coil, T_ev = (np.asarray(out[j]).ravel() for j in (5, 6))
    s = econ.parameters(fit.values)
    Q_e = econ.refrigerant_heat(s, Q_coil, x[k, 3], x[k + 1, 3], ds.Ts)
    P_hat = econ.compressor_power(s, Q_e, T_ev, d[:, 0], d[:, 1])
    P = ds.get("P_comp", "W")[k]
    e = P - P_hat
    steady = (np.abs(x[k + 1, 0] - x[k, 0]) / ds.Ts < _STEADY_RATE) & \
        (np.abs(x[k + 1, 3] - x[k, 3]) / ds.Ts < _STEADY_RATE) & (P > 0.05 * P.max())
    rms = float(np.sqrt(np.mean(e**2)))
    quality = {"n": int(P.size), "rms_W": rms, "rms_pct": 100.0 * rms / float(np.mean(P)),
               "max_abs_W": float(np.max(np.abs(e))),
               "r2": 1.0 - float(e @ e) / float(np.sum((P - P.mean()) ** 2)),
               "mean_P_W": float(np.mean(P)), "n_steady": int(steady.sum())}
    if steady.sum() >= 10:
        quality.update(steady_rms_pct=100.0 * float(np.sqrt(np.mean((e / P)[steady] ** 2))),
                       steady_max_pct=100.0 * float(np.max(np.abs(e / P)[steady])))
    domain = {n: (float(v.min()), float(v.max())) for (n, _), v in
              zip(MAP_INPUTS, (Q_e, T_ev, d[:, 0], d[:, 1]), strict=True)}
    se = {e.name: e.stderr for e in fit.estimates}
    prov = {**provenance(ds, "acid.ident staged fit (acid.models.econ.FIT_STAGES)"),
            "skip_s": econ.FIT_SKIP_S, **({"data_seed": ds.metadata["seed"]}
                                          if "seed" in ds.metadata else {})}
    params = EconParams.from_vector(
        fit.values, power_map=PowerMap(coef=fit.values[len(NAMES) + 1:len(NAMES) + 16],
                                       stderr=tuple(se[n] for n in econ.MAP_NAMES),
                                       domain=domain, quality=quality),
        stderr={n: se[n] for n in NAMES + ("C_ew",)}, Ts=float(ds.Ts), name="econ-fit",
        provenance=prov)
    return EconFit(params=params, fit=fit)
