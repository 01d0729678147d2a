"""What a fit of a declared model returns: :class:`DeclaredFitResult` (the fitted table with
its standard errors and intervals, per-equation reports, optima of a multi-start fit, notes and
warnings, provenance) and its rows. Written by :mod:`acid.ident.fit` and :mod:`acid.ident.pem`;
``summary()`` is its text."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from acid._io import json_safe
from acid.models.declaration import Model


@dataclass(frozen=True)
class Estimate:
    """One row of the fitted table (a per-experiment parameter has a row per experiment,
    ``name@experiment``)."""

    name: str
    unit: str
    declared: float
    value: float
    stderr: float
    ci95: tuple[float, float]
    status: str      # estimated (ls | cvx | oe), fixed, not fitted, combination
    experiment: int | None = None


@dataclass(frozen=True)
class EquationReport:
    """How one equation was treated and what the data say about it."""

    name: str
    method: str                   # "ls", "cvx" or "oe"/"-" (not by equation error)
    reason: str                   # why not least squares ("" when it was)
    parameters: tuple[str, ...]
    rank: int | None = None
    n_columns: int | None = None
    condition: float | None = None
    residual_std: float | None = None
    n_rows: int | None = None
    fit_percent: float | None = None
    combinations: tuple[str, ...] = ()
    active_bounds: tuple[str, ...] = ()
    residual_acf1: float | None = None      # lag-1 autocorrelation of the residuals
    ljung_box_p: float | None = None        # whiteness test of the residuals (20 lags)


@dataclass(frozen=True)
class Optimum:
    """A distinct optimum of the multi-start output error."""

    loss: float
    n_starts: int
    values: dict
    spread: dict       # max - min of each parameter over the starts that reached it


@dataclass(frozen=True)
class FailedStart:
    """A multi-start output-error run that reached no optimum: its start number (0 is the
    least-squares / declared start), its final loss and why it counts as failed."""

    start: int
    loss: float
    reason: str
    values: dict


@dataclass(frozen=True, repr=False)
class DeclaredFitResult:
    """What ``fit_model`` found (frozen): ``print(fit)`` or ``fit.summary()`` for the table,
    ``fit.to_frame()`` for pandas rows, ``fit.mse`` and ``fit.nmse`` to compare models on the
    same data (``fit.objective`` is what the optimiser minimised: it compares starts of one
    fit, not models)."""

    model: str
    model_source: str
    method: str
    estimates: tuple[Estimate, ...]
    equations: tuple[EquationReport, ...]
    values: np.ndarray                      # (np,) the fitted table (per-experiment: mean)
    per_experiment: dict                    # {name: (E,) values}
    experiment_ids: tuple[int, ...]
    covariance: np.ndarray
    covariance_names: tuple[str, ...]
    covariance_kind: str
    hac_bandwidth: dict
    output_error: dict
    optima: tuple[Optimum, ...]
    combinations: tuple[str, ...]
    notes: tuple[str, ...]
    warnings: tuple[str, ...]
    n_samples: int
    data_source: str
    elapsed_s: float = field(default=math.nan, compare=False)
    #: {channel: fit %} of ``window``-sample simulations started from the measured states
    #: (latent ones from their declared rule), the fitted parameters, every measured channel
    simulation_fit: dict = field(default_factory=dict)
    #: {equation: fit %} of its one-step predictions along the data with the fitted table
    #: (measured states, inputs and read outputs substituted; equations reading a latent
    #: state are left out)
    one_step_fit: dict = field(default_factory=dict)
    #: the loss function minimised, ``--loss``: "squared" or "huber"
    loss: str = "squared"
    #: multi-start runs that reached no optimum (non-finite or diverged loss, solver
    #: failure), kept out of ``optima``
    failed_starts: tuple[FailedStart, ...] = ()
    #: "NAME at its min|max VALUE" for every fitted parameter that ends on a declared bound
    on_bounds: tuple[str, ...] = ()
    #: the ``Model`` fitted (``fitted_parameters`` binds the values to it)
    declaration: Model | None = field(default=None, repr=False, compare=False)
    #: {channel: {"unit", "mse", "variance", "nmse", "n", "scored"}}: the mean squared error
    #: of each fitted channel in its unit squared, the channel's variance over the same
    #: samples and their ratio (NMSE), scored as the method scores: "simulation" (least
    #: squares, output error: the windows of ``simulation_fit``,
    #: ``acid.ident.fit.simulation_errors``) or "one-step" (prediction error: the filter's
    #: innovations)
    channel_mse: dict = field(default_factory=dict)

    def to_frame(self):
        """The fitted table as a pandas DataFrame, a row per estimate (per-experiment
        parameters a row per experiment): name, experiment, unit, declared, value, stderr,
        ci95_low, ci95_high, status."""
        import pandas as pd

        return pd.DataFrame([{"name": e.name, "experiment": e.experiment, "unit": e.unit,
                              "declared": e.declared, "value": e.value, "stderr": e.stderr,
                              "ci95_low": e.ci95[0], "ci95_high": e.ci95[1],
                              "status": e.status} for e in self.estimates])

    @property
    def mse(self) -> dict:
        """{channel: mean squared error} with the fitted table, in the channel's unit squared
        (K^2 for a temperature), scored as ``channel_mse`` says (least squares and output
        error: simulations over ``simulation_fit``'s windows from the measured states, latent
        ones as the output-error fit estimated them; prediction error: one-step innovations):
        compares models on the same data."""
        return {k: v["mse"] for k, v in self.channel_mse.items()}

    @property
    def nmse(self) -> dict:
        """{channel: normalised mean squared error}: the channel's mean squared error
        (``mse``) divided by its variance over the same samples, (1 - fit % / 100) ** 2.
        0 is perfect, 1 is no better than the channel's mean; unlike the optimiser's
        objective it compares fits of different models on the same data."""
        if self.channel_mse:
            return {k: v["nmse"] for k, v in self.channel_mse.items()}
        return {k: (1.0 - v / 100.0) ** 2 if math.isfinite(v) else math.nan
                for k, v in self.simulation_fit.items()}

    @property
    def mse_scored(self) -> str:
        """How ``mse`` and ``nmse`` were scored: "simulation" or "one-step"."""
        kinds = {v.get("scored", "simulation") for v in self.channel_mse.values()}
        return kinds.pop() if len(kinds) == 1 else "simulation"

    @property
    def objective(self) -> float:
        """What the optimiser minimised, at the optimum (``objective_text`` says what it is
        for this method; NaN for least squares, one problem per equation). It ranks the
        starts of one fit; it does not compare models (``mse``, ``nmse`` do)."""
        v = self.output_error.get("loss") if self.output_error else None
        return math.nan if v is None else float(v)

    @property
    def objective_text(self) -> str:
        """What ``objective`` is for this fit's method."""
        prior = "; plus the priors' squared standardised distances when declared"
        if self.method == "pem":
            return ("prediction error: -2 log-likelihood of the one-step innovations of the "
                    f"extended Kalman filter, up to a constant{prior}")
        if self.output_error:
            return ("output error: half the sum of the squared simulation errors, each "
                    "channel's divided by its weight (its error scale), over the windows' "
                    f"samples (about half their number at a good fit){prior}")
        return ("least squares: one problem per equation, no single objective (each "
                "equation's residual std is in the equations table)")

    def summary(self) -> str:
        """The fit as text: what was fitted how, the parameter table, the per-channel error
        RMS (output error: simulation over windows; prediction error: one-step innovations),
        parameters on a bound, warnings."""
        rms = self.output_error.get("channel_rms") or self.output_error.get(
            "innovation_rms") or {}
        lines = [f"{self.model}: {self.method} fit of {self.n_samples} samples "
                 f"({self.data_source})"]
        width = max([len(e.name) + (4 if e.experiment is not None else 0)
                     for e in self.estimates] + [4])
        uw = max([len(e.unit) for e in self.estimates] + [4])
        lines.append(f"  {'name':<{width}} {'value':>12} {'stderr':>10}  {'unit':<{uw}}  status")
        for e in self.estimates:
            label = e.name if e.experiment is None else f"{e.name}@{e.experiment}"
            lines.append(f"  {label:<{width}} {e.value:>12.5g} {e.stderr:>10.3g}  "
                         f"{e.unit:<{uw}}  {e.status}")
        if rms:
            lines.append("  error RMS: " + ", ".join(f"{k} {v:.4g}" for k, v in rms.items()))
        if self.channel_mse:
            lines.append(f"  MSE ({self.mse_scored}): " + ", ".join(
                f"{k} {v['mse']:.4g} {unit_squared(v['unit'])}"
                for k, v in self.channel_mse.items()))
        if self.nmse:
            lines.append(f"  NMSE ({self.mse_scored}, MSE / variance): "
                         + ", ".join(f"{k} {v:.4g}" for k, v in self.nmse.items()))
        if math.isfinite(self.objective):
            lines.append(f"  objective {self.objective:.6g} (what the optimiser minimised; "
                         "not comparable across models)")
        lines += [f"  on a bound: {b}" for b in self.on_bounds]
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"DeclaredFitResult(\n{self.summary()}\n)"

    def __getstate__(self):   # pickled without the Model (it holds the user's functions)
        return {k: v for k, v in self.__dict__.items() if k != "declaration"}

    def value(self, name: str, experiment: int | None = None) -> float:
        """The fitted value of ``name``; a per-experiment one of the experiment index
        ``experiment`` (default: its mean over the experiments)."""
        if name in self.per_experiment:
            vals = self.per_experiment[name]
            return float(vals[experiment] if experiment is not None else np.mean(vals))
        for e in self.estimates:
            if e.name == name and e.experiment is None:
                return e.value
        raise KeyError(name)

    def to_json_dict(self) -> dict:
        return json_safe({
            "model": self.model, "model_source": self.model_source, "method": self.method,
            "n_samples": self.n_samples, "data": self.data_source,
            "covariance_kind": self.covariance_kind, "hac_bandwidth": self.hac_bandwidth,
            "parameters": [{"name": e.name, "unit": e.unit, "declared": e.declared,
                            "estimate": e.value, "stderr": e.stderr, "ci95_low": e.ci95[0],
                            "ci95_high": e.ci95[1], "status": e.status,
                            "experiment": e.experiment} for e in self.estimates],
            "equations": [vars(q) for q in self.equations],
            "combinations": list(self.combinations),
            "output_error": self.output_error, "loss": self.loss,
            "objective": {"value": self.objective, "what": self.objective_text},
            "mse_per_channel": self.channel_mse,
            "fit_percent_simulation": self.simulation_fit,
            "fit_percent_one_step": self.one_step_fit,
            "nmse": self.nmse, "nmse_scored": self.mse_scored,
            "nmse_simulation": self.nmse if self.mse_scored == "simulation" else {},
            "optima": [vars(o) for o in self.optima],
            "failed_starts": [vars(f) for f in self.failed_starts],
            "on_bounds": list(self.on_bounds),
            "covariance": {"names": list(self.covariance_names), "matrix": self.covariance},
            "notes": list(self.notes), "warnings": list(self.warnings),
            "elapsed_s": self.elapsed_s, "values": self.values,
            "per_experiment": self.per_experiment, "experiment_ids": list(self.experiment_ids),
        })

    @classmethod
    def from_json_dict(cls, d: dict) -> DeclaredFitResult:
        """The result ``to_json_dict`` wrote (without the declaration; non-finite numbers,
        stored as null, come back as NaN): ``from_json_dict(r.to_json_dict()) == r``."""
        def num(v):
            return math.nan if v is None else float(v)

        def tup(q):
            return {k: tuple(v) if isinstance(v, list) else v for k, v in q.items()}

        cov = d["covariance"]
        return cls(
            model=d["model"], model_source=d["model_source"], method=d["method"],
            estimates=tuple(Estimate(p["name"], p["unit"], num(p["declared"]),
                                     num(p["estimate"]), num(p["stderr"]),
                                     (num(p["ci95_low"]), num(p["ci95_high"])), p["status"],
                                     p["experiment"]) for p in d["parameters"]),
            equations=tuple(EquationReport(**tup(q)) for q in d["equations"]),
            values=np.array(d["values"], dtype=float),
            per_experiment={n: np.array(v, dtype=float)
                            for n, v in d["per_experiment"].items()},
            experiment_ids=tuple(d["experiment_ids"]),
            covariance=np.array(cov["matrix"], dtype=float),
            covariance_names=tuple(cov["names"]), covariance_kind=d["covariance_kind"],
            hac_bandwidth=d["hac_bandwidth"], output_error=d["output_error"],
            optima=tuple(Optimum(**o) for o in d["optima"]),
            combinations=tuple(d["combinations"]), notes=tuple(d["notes"]),
            warnings=tuple(d["warnings"]), n_samples=d["n_samples"], data_source=d["data"],
            elapsed_s=num(d["elapsed_s"]), simulation_fit=d["fit_percent_simulation"],
            one_step_fit=d["fit_percent_one_step"], loss=d["loss"],
            failed_starts=tuple(FailedStart(**f) for f in d["failed_starts"]),
            on_bounds=tuple(d["on_bounds"]),
            channel_mse={k: {**v, **{q: num(v[q]) for q in ("mse", "variance", "nmse")}}
                         for k, v in d.get("mse_per_channel", {}).items()})

    def to_dict(self) -> dict:
        """The result as plain JSON types (``to_json_dict``): the parameter table, the
        per-channel ``mse_simulation`` and ``nmse_simulation`` (comparable across models),
        the ``objective`` with what it is, the covariance, notes and warnings."""
        return self.to_json_dict()

    def __eq__(self, other) -> bool:
        """Equal when their JSON is (arrays compared by value, NaN equal to NaN)."""
        if not isinstance(other, DeclaredFitResult):
            return NotImplemented
        return self.to_json_dict() == other.to_json_dict()

    __hash__ = None

    def write(self, path: str | Path, model: Model, provenance: dict | None = None,
              extra: dict | None = None) -> Path:
        """The parameter file (``acid.models.values``' format) with this report as
        ``fit``; ``extra`` adds keys (the paper's: its ``ModelParams``'s name and eq. 4's
        COP), never the fitted values and their standard errors."""
        from acid._io import write_json
        from acid.models.values import ParameterValues

        values = ParameterValues(
            self.values, model=model, name=f"fit-{self.method}", provenance=provenance,
            stderr={e.name: e.stderr for e in self.estimates if e.experiment is None},
            per_experiment={n: dict(zip(self.experiment_ids, map(float, v), strict=True))
                            for n, v in self.per_experiment.items()})
        d = values.to_json_dict()
        return write_json(path, json_safe({**d, **(extra or {}), "fit": self.to_json_dict(),
                                           **{k: d[k] for k in ("parameters",
                                                                "per_experiment")}}))


def unit_squared(unit: str) -> str:
    """A unit squared, as printed beside an MSE: K^2, (kg/s)^2."""
    return f"{unit}^2" if unit.isalnum() else f"({unit})^2"
