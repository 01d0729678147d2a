"""``predict``, ``compare`` and ``resid`` for the control-oriented model (MATLAB SITB vocabulary).

* :func:`predict` -- k-step-ahead predictions of T_cab, T_evap, T_ain along a dataset (MATLAB
  ``predict(sys, data, K)``): sample n is predicted from the measured state at n - k and the
  measured inputs and disturbances (W_bl, T_evap_set, T_int, T_shell) in between; ``k=None``
  simulates each experiment from its first sample (MATLAB ``sim``; ``compare``'s default).
* :func:`compare` -- several models against one dataset: fit per channel with MATLAB's
  definition ``100 (1 - ||y - y_hat|| / ||y - mean(y)||)`` (``acid.metrics.fit_percent``).
* :func:`resid` -- the one-step prediction errors and the two classical tests (Ljung 1999,
  sec. 16.6): their autocorrelation (whiteness) and their cross-correlation with the inputs
  (independence), each with the 99 % band ``+-2.576/sqrt(N)`` that holds when the residuals are
  white and independent of the inputs; Ljung-Box portmanteau p-values beside them.

Predictions never cross an experiment boundary. Temperatures are kelvin inside the results;
``to_frame()`` and ``plot()`` show degC (the edge). The functions take any declared
model's values (``ModelParams``, ``EconParams``, a fit, a parameter file): every channel it
measures, in its declared unit, and every declared input in ``resid``.

k-step prediction: sample n is predicted from the state at n - k and the measured inputs and
disturbances in between. Measured states are taken as measured; latent states come from a
forced run of the model along each experiment (the measured states reset to their
measurements at every sample, the latent ones propagated by the model's equations), started
from their declared ``initial`` rule or, with ``warmup`` > 0 s (W samples), from the state
fitted to the first W samples (``acid.ident.validate``'s warm start). ``k=None`` simulates
each experiment from its first predicted sample. Channels: every state and output the
dataset measures, in their declared units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from acid._io import json_safe
from acid.data import Dataset
from acid.errors import ConfigError, DataError
from acid.ident.data import ModelData
from acid.ident.fit import DeclaredFitResult
from acid.ident.oe import simulate_windows
from acid.ident.validate import (
    declared_parameters,
    fitted_parameters,
    parameters_at,
    read_parameters,
    samples_of,
    warm_start_states,
)
from acid.metrics import fit_percent, rmse
from acid.models.declaration import Model
from acid.models.loader import load
from acid.models.values import ParameterValues
from acid.units import K2C

# compare, predict and resid are served by __getattr__
__all__ = ["CompareResult", "PredictionResult", "ResidualResult", "compare",  # noqa: F822
           "predict", "resid"]  # noqa: F822
#: Two-sided 99 % standard-normal quantile.
Z99 = 2.5758293035489004


# ------------------------------------------------------------------------- results
@dataclass(frozen=True, repr=False, eq=False)
class PredictionResult:
    """k-step-ahead predictions along a dataset.

    Attributes
    ----------
    time : (N,) sample times, s.
    measured, predicted : (N, C) the channels, in their units (``predicted`` NaN where no
        prediction exists: the first k samples of each experiment).
    horizon : k, steps (None: simulation from each experiment's first sample).
    Ts : sample time, s.
    model : the parameters' name.
    source : the dataset's source.
    channels, units : the model's measured channels and their declared units.
    """

    time: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    horizon: int | None
    Ts: float
    model: str
    source: str
    channels: tuple[str, ...]
    units: tuple[str, ...]

    @property
    def valid(self) -> np.ndarray:
        """(N,) samples that have a prediction."""
        return np.all(np.isfinite(self.predicted), axis=1)

    @property
    def errors(self) -> np.ndarray:
        """(N, C) measured - predicted, channel units (NaN where no prediction)."""
        return self.measured - self.predicted

    @property
    def fit_percent(self) -> dict[str, float]:
        """MATLAB fit per channel over the predicted samples, % (100 is perfect)."""
        m = self.valid
        return {c: float(fit_percent(self.measured[m, i], self.predicted[m, i]))
                for i, c in enumerate(self.channels)}

    @property
    def rmse(self) -> dict[str, float]:
        """Root-mean-square prediction error per channel, in its unit."""
        m = self.valid
        return {c: float(rmse(self.measured[m, i], self.predicted[m, i]))
                for i, c in enumerate(self.channels)}

    @property
    def label(self) -> str:
        return "simulation" if self.horizon is None else f"{self.horizon}-step"

    def to_frame(self):
        """DataFrame indexed by time (s): ``<channel>`` measured and ``<channel>_pred``, degC
        for temperatures (``attrs["units"]`` per channel)."""
        import pandas as pd

        cols = {}
        for i, (c, u) in enumerate(zip(self.channels, self.units, strict=True)):
            cols[c] = _edge(self.measured[:, i], u)
            cols[f"{c}_pred"] = _edge(self.predicted[:, i], u)
        df = pd.DataFrame(cols, index=pd.Index(self.time, name="time_s"))
        df.attrs.update(units=dict(zip(self.channels, map(_edge_unit, self.units),
                                       strict=True)), horizon=self.label, model=self.model)
        return df

    def plot(self, title: str | None = None):
        """Measured and predicted channels (temperatures in degC) over time; the figure."""
        return _trace_figure(self.time, self.measured, {self.model: self}, self.channels,
                             title or f"{self.label} prediction ({self.source})",
                             self.units)

    def summary(self) -> str:
        """One line per channel: fit % and RMSE over the predicted samples."""
        lines = [f"{self.label} prediction of {self.model!r} on {self.source} "
                 f"({int(self.valid.sum())} of {self.time.size} samples predicted)"]
        lines += [f"  {c} [{u}]: fit {self.fit_percent[c]:.2f} %, RMSE {self.rmse[c]:.4g}"
                  for c, u in zip(self.channels, self.units, strict=True)]
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"PredictionResult(\n{self.summary()}\n)"

    def __eq__(self, other) -> bool:
        return isinstance(other, PredictionResult) and \
            self.to_json_dict() == other.to_json_dict()

    __hash__ = None

    def to_json_dict(self) -> dict:
        """The scores and every sample (``time_s``, ``measured``, ``predicted``; NaN as null):
        ``PredictionResult.from_json_dict`` reads it back."""
        return json_safe({"horizon": self.horizon, "Ts_s": self.Ts, "model": self.model,
                          "source": self.source, "fit_percent": self.fit_percent,
                          "rmse": self.rmse, "units": dict(zip(self.channels, self.units,
                                                               strict=True)),
                          "samples": int(self.valid.sum()), "channels": self.channels,
                          "time_s": self.time, "measured": self.measured,
                          "predicted": self.predicted})

    @classmethod
    def from_json_dict(cls, d: dict) -> PredictionResult:
        """The result ``to_json_dict`` wrote (NaN restored)."""
        chans = tuple(d["channels"])
        shape = (-1, len(chans))
        return cls(time=np.array(d["time_s"], dtype=float),
                   measured=np.array(d["measured"], dtype=float).reshape(shape),
                   predicted=np.array(d["predicted"], dtype=float).reshape(shape),
                   horizon=d["horizon"], Ts=float(d["Ts_s"]), model=d["model"],
                   source=d["source"], channels=chans,
                   units=tuple(d["units"][c] for c in chans))


@dataclass(frozen=True, repr=False, eq=False)
class CompareResult:
    """Several models against one dataset (MATLAB ``compare``).

    Attributes
    ----------
    predictions : {model label: PredictionResult}, same data and horizon.
    horizon : k (None: simulation).
    """

    predictions: dict[str, PredictionResult]
    horizon: int | None

    @property
    def fit_percent(self) -> dict[str, dict[str, float]]:
        """{model: {channel: fit %}}."""
        return {label: p.fit_percent for label, p in self.predictions.items()}

    @property
    def rmse(self) -> dict[str, dict[str, float]]:
        """{model: {channel: root-mean-square error}}, in each channel's unit (the figure
        benchmark papers quote)."""
        return {label: p.rmse for label, p in self.predictions.items()}

    def to_frame(self, metric: str = "fit_percent"):
        """DataFrame of fit % (``metric="fit_percent"``) or of the RMSE in each channel's unit
        (``metric="rmse"``); rows: models, columns: the channels."""
        import pandas as pd

        if metric not in ("fit_percent", "rmse"):
            raise ValueError(f"metric must be 'fit_percent' or 'rmse', got {metric!r}")
        df = pd.DataFrame(getattr(self, metric)).T
        df.index.name = "model"
        first = next(iter(self.predictions.values()))
        df.attrs.update(
            unit="%" if metric == "fit_percent" else dict(zip(first.channels, first.units,
                                                               strict=True)),
            definition="100 (1 - ||y - y_hat|| / ||y - mean(y)||)" if metric == "fit_percent"
            else "sqrt(mean((y - y_hat)^2))",
            horizon="simulation" if self.horizon is None else self.horizon)
        return df

    def plot(self, title: str | None = None):
        """Measured data and every model's prediction (fit % in the legend); the figure."""
        first = next(iter(self.predictions.values()))
        label = "simulation" if self.horizon is None else f"{self.horizon}-step prediction"
        return _trace_figure(first.time, first.measured, self.predictions, first.channels,
                             title or f"compare: {label} ({first.source})",
                             first.units)

    def summary(self) -> str:
        """Fit % per model (rows) and channel (columns)."""
        first = next(iter(self.predictions.values()))
        label = "simulation" if self.horizon is None else f"{self.horizon}-step prediction"
        w = max(12, *(len(k) for k in self.predictions))
        lines = [f"compare: {label} on {first.source}, fit % (100 is perfect)",
                 f"  {'model':{w}s}" + "".join(f"{c:>12s}" for c in first.channels)]
        lines += [f"  {k:{w}s}" + "".join(f"{v.get(c, math.nan):12.2f}" for c in first.channels)
                  for k, v in self.fit_percent.items()]
        lines.append(f"  {'RMSE':{w}s}" + "".join(f"{f'{c} [{u}]':>12s}" for c, u in
                                                   zip(first.channels, first.units,
                                                       strict=True)))
        lines += [f"  {k:{w}s}" + "".join(f"{v.get(c, math.nan):12.4g}" for c in first.channels)
                  for k, v in self.rmse.items()]
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"CompareResult(\n{self.summary()}\n)"

    def __eq__(self, other) -> bool:
        return isinstance(other, CompareResult) and \
            self.to_json_dict() == other.to_json_dict()

    __hash__ = None

    def to_json_dict(self) -> dict:
        """Fit % per model and each model's predictions (``from_json_dict`` reads it back)."""
        return json_safe({"horizon": self.horizon, "fit_percent": self.fit_percent,
                          "predictions": {k: p.to_json_dict()
                                          for k, p in self.predictions.items()}})

    @classmethod
    def from_json_dict(cls, d: dict) -> CompareResult:
        return cls({k: PredictionResult.from_json_dict(p) for k, p in d["predictions"].items()},
                   d["horizon"])


@dataclass(frozen=True, repr=False, eq=False)
class ResidualResult:
    """Residual analysis (MATLAB ``resid``): whiteness and independence from the inputs.

    Attributes
    ----------
    prediction : the k-step predictions the residuals come from (k = 1 by default).
    lags : (M + 1,) autocorrelation lags 0..M; ``cross_lags`` (2M + 1,) -M..M, samples.
    autocorrelation : (M + 1, C) normalised autocorrelation of each channel's residual.
    cross_correlation : (2M + 1, I, C) normalised cross-correlation r_ue(tau) of input u
        at t with the residual at t + tau (tau > 0: the residual after the input;
        significant values at tau < 0 suggest feedback).
    band99 : half-width of the 99 % band under whiteness/independence, 2.576 / sqrt(N).
    n : residual samples used.
    ljung_box : {channel: {"Q", "p_value", "lags"}} portmanteau test of whiteness.
    inputs, channels : the model's declared inputs and measured channels.
    """

    prediction: PredictionResult
    lags: np.ndarray
    cross_lags: np.ndarray
    autocorrelation: np.ndarray
    cross_correlation: np.ndarray
    band99: float
    n: int
    ljung_box: dict[str, dict[str, float]]
    inputs: tuple[str, ...]
    channels: tuple[str, ...]
    settings: dict = field(default_factory=dict)

    @property
    def residuals(self) -> np.ndarray:
        """(N, C) measured - predicted, channel units (NaN where no prediction)."""
        return self.prediction.errors

    @property
    def white(self) -> dict[str, bool]:
        """Per channel: every autocorrelation at lags 1..M inside the 99 % band."""
        a = np.abs(self.autocorrelation[1:])
        return {c: bool(np.all(a[:, i] <= self.band99)) for i, c in enumerate(self.channels)}

    @property
    def independent(self) -> dict[str, dict[str, bool]]:
        """{input: {channel: every cross-correlation inside the 99 % band}}."""
        a = np.abs(self.cross_correlation)
        return {u: {c: bool(np.all(a[:, j, i] <= self.band99))
                    for i, c in enumerate(self.channels)} for j, u in enumerate(self.inputs)}

    @property
    def interpretation(self) -> dict[str, str]:
        """{channel: what its whiteness and independence verdicts mean, in plain words}.

        A model fitted for one step (least squares) and used for many (a controller's
        horizon, the validation windows): autocorrelated one-step residuals mean the errors
        do not average out over a horizon but drift in one direction, so the multi-step
        validation, not the one-step fit, says what a controller gets; and standard errors
        that assume white residuals are too small.
        """
        out = {}
        M = int(self.lags[-1])
        for i, c in enumerate(self.channels):
            a = np.abs(self.autocorrelation[1:, i])
            lag = int(np.argmax(a)) + 1
            outside = int(np.sum(a > self.band99))
            p = self.ljung_box[c]["p_value"]
            if not np.all(np.isfinite(a)):
                out[c] = ("no test: the one-step residuals are zero (the model reproduces "
                          "the data exactly), so they have no correlation to test.")
                continue
            if outside == 0:
                text = (f"white at one step: every autocorrelation at lags 1..{M} is inside "
                        f"+-{self.band99:.3f} (largest {a.max():.2f}, lag {lag}; Ljung-Box "
                        f"p = {p:.2g}); what the multi-step errors show then comes from "
                        "information the model is not given (held disturbances), not from "
                        "structure it missed.")
            else:
                r = self.autocorrelation[1:, i]
                size = ("strong" if a.max() >= 0.5 else "moderate" if a.max() >= 0.2
                        else "weak")
                text = (f"not white: {outside} of {M} autocorrelations outside "
                        f"+-{self.band99:.3f}, largest {r[lag - 1]:+.2f} at lag {lag} ({size}; "
                        f"Ljung-Box p = {p:.2g}). ")
                if lag == 1 and r[0] < 0 and a[1:].max(initial=0.0) < 0.5 * a[0]:
                    text += ("A negative correlation at lag 1 alone is the mark of noise on "
                             "the measured state each one-step prediction starts from (the "
                             "same noise enters two consecutive residuals with opposite "
                             "signs); it does not build up over a horizon, and the multi-step "
                             "errors are the measure of the model.")
                else:
                    text += ("The one-step errors keep a pattern the model does not explain "
                             "(dynamics or disturbances lasting several samples), so over a "
                             "prediction horizon they add up in one direction instead of "
                             "averaging out: judge the model for control by the multi-step "
                             "errors, and use HAC standard errors (acid fit --covariance hac), not "
                             "white ones.")
                if size == "weak":
                    text += (f" The correlation is small; with N = {self.n} samples the band "
                             "is narrow enough to flag it.")
            for j, u in enumerate(self.inputs):
                cc = np.abs(self.cross_correlation[:, j, i])
                pos = cc[self.cross_lags > 0].max(initial=0.0)
                neg = cc[self.cross_lags < 0].max(initial=0.0)
                if pos > self.band99:
                    text += (f" Correlated with earlier {u} (up to {pos:.2f}): the model "
                             f"misses part of {u}'s effect.")
                elif neg > self.band99:
                    text += (f" Correlated with later {u} only (up to {neg:.2f}): the "
                             f"residual leads {u}, which points to feedback from {c} to {u} "
                             "in the data (or chance, for a slowly switching input), not to "
                             "a model error.")
            out[c] = text
        return out

    def to_frame(self):
        """DataFrame indexed by lag (-M..M): ``acf <channel>`` (lags >= 0) and
        ``ccf <input> <channel>``; ``attrs["band99"]`` the 99 % band."""
        import pandas as pd

        df = pd.DataFrame(index=pd.Index(self.cross_lags, name="lag"))
        M = int(self.lags[-1])
        for i, c in enumerate(self.channels):
            col = np.full(self.cross_lags.shape, np.nan)
            col[M:] = self.autocorrelation[:, i]
            df[f"acf {c}"] = col
        for j, u in enumerate(self.inputs):
            for i, c in enumerate(self.channels):
                df[f"ccf {u} {c}"] = self.cross_correlation[:, j, i]
        df.attrs.update(band99=self.band99, n=self.n, horizon=self.prediction.horizon)
        return df

    def plot(self, title: str | None = None):
        """Autocorrelations (top) and input cross-correlations (bottom) with the 99 % band."""
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(2, len(self.channels), figsize=(11, 5.5), sharey="row",
                                 constrained_layout=True, squeeze=False)
        for i, c in enumerate(self.channels):
            ax = axes[0, i]
            ax.bar(self.lags, self.autocorrelation[:, i], width=0.6, color="tab:blue")
            ax.set_title(f"{c}: residual autocorrelation")
            ax2 = axes[1, i]
            for j, u in enumerate(self.inputs):
                ax2.plot(self.cross_lags, self.cross_correlation[:, j, i], marker=".", lw=0.8,
                         label=u)
            ax2.set_title(f"{c}: cross-correlation with inputs")
            ax2.set_xlabel("lag (samples)")
            for a in (ax, ax2):
                a.axhspan(-self.band99, self.band99, color="0.85", zorder=0,
                          label="99 % band")
                a.axhline(0.0, color="0.3", lw=0.6)
        axes[1, 0].legend(fontsize=8)
        fig.suptitle(title or f"resid: {self.prediction.label} prediction errors "
                              f"({self.prediction.model}, N = {self.n})")
        return fig

    def summary(self) -> str:
        """Per channel: white or not, the inputs it correlates with, what that means."""
        lines = [f"resid: {self.prediction.label} prediction errors of "
                 f"{self.prediction.model!r}, N = {self.n}, 99 % band +-{self.band99:.3f}"]
        for c in self.channels:
            dep = [u for u in self.inputs if not self.independent[u][c]]
            lines.append(f"  {c}: {'white' if self.white[c] else 'not white'}, Ljung-Box p "
                         f"{self.ljung_box[c]['p_value']:.2g}, correlated with "
                         f"{', '.join(dep) or 'no input'}")
            lines.append(f"    {self.interpretation[c]}")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"ResidualResult(\n{self.summary()}\n)"

    def __eq__(self, other) -> bool:
        return isinstance(other, ResidualResult) and \
            self.to_json_dict() == other.to_json_dict()

    __hash__ = None

    @classmethod
    def from_json_dict(cls, d: dict) -> ResidualResult:
        """The result ``to_json_dict`` wrote (with its predictions)."""
        pr = PredictionResult.from_json_dict(d["prediction"])
        arr = lambda k: np.array(d[k], dtype=float)   # noqa: E731
        ni = len(d["inputs"])
        return cls(pr, arr("lags").astype(int), arr("cross_lags").astype(int),
                   arr("autocorrelation").reshape(-1, len(pr.channels)),
                   arr("cross_correlation").reshape(-1, ni, len(pr.channels)),
                   float(d["band99"]), int(d["n"]),
                   {c: {k: (math.nan if v is None else v) for k, v in t.items()}
                    for c, t in d["ljung_box"].items()},
                   tuple(d["inputs"]), pr.channels, dict(d.get("settings") or {}))

    def to_json_dict(self) -> dict:
        """The tests, their verdicts and the predictions they come from (``prediction``):
        ``ResidualResult.from_json_dict`` reads it back."""
        return json_safe({"horizon": self.prediction.horizon, "n": self.n,
                          "prediction": self.prediction.to_json_dict(),
                          "inputs": self.inputs, "settings": self.settings,
                          "band99": self.band99, "white": self.white,
                          "independent": self.independent, "ljung_box": self.ljung_box,
                          "interpretation": self.interpretation,
                          "lags": self.lags, "autocorrelation": self.autocorrelation,
                          "cross_lags": self.cross_lags,
                          "cross_correlation": self.cross_correlation})


def compare_predictions(models, predict_one, k: int | None,
                        labels: list[str] | None = None) -> CompareResult:
    """``CompareResult`` of ``predict_one(m)`` for each of ``models``: labelled by ``labels``
    or the predictions' model names (made unique), every model predicting the same channels."""
    if not models:
        raise ConfigError("compare: give at least one model")
    if labels is not None and len(labels) != len(models):
        raise ConfigError(f"compare: {len(labels)} labels for {len(models)} models")
    preds: dict[str, PredictionResult] = {}
    for i, m in enumerate(models):
        pr = predict_one(m)
        label = labels[i] if labels is not None else pr.model
        if label in preds:
            label = f"{label} ({i + 1})"
        if preds and next(iter(preds.values())).channels != pr.channels:
            raise ConfigError(f"compare: {label} predicts {', '.join(pr.channels)}, the "
                              f"first model {', '.join(next(iter(preds.values())).channels)}")
        preds[label] = pr
    return CompareResult(predictions=preds, horizon=None if k is None else int(k))


def residual_tests(pr: PredictionResult, u: np.ndarray, inputs: tuple[str, ...],
                   exp: np.ndarray, M: int, settings: dict, source: str) -> ResidualResult:
    """Whiteness and input independence of the errors of ``pr`` (any model): ``u`` (N, nu)
    the inputs named ``inputs``, ``exp`` (N,) the experiment of each sample (no lag product
    crosses one)."""
    from scipy.stats import chi2

    e = pr.errors
    valid = pr.valid
    nv = int(valid.sum())
    if nv <= M + 1:
        raise DataError(f"{source}: {nv} residual samples are too few for {M} lags")
    e = e - np.nanmean(e[valid], axis=0)
    e[~valid] = 0.0
    # errors at round-off of the measured values (an exact equation): zero, "no test"
    size = np.nanmax(np.abs(pr.measured[valid]), axis=0)
    e[:, np.sqrt(np.mean(e[valid] ** 2, axis=0)) <= 1e-10 * size] = 0.0
    u = np.asarray(u, dtype=float).copy()
    u = u - u[valid].mean(axis=0)
    u[~valid] = 0.0
    nc, nu = e.shape[1], u.shape[1]

    def pairs(lag: int) -> tuple[slice, slice, np.ndarray]:
        """Index slices (t, t + lag) and the mask of pairs inside one experiment."""
        if lag >= 0:
            s0, s1 = slice(0, len(e) - lag), slice(lag, len(e))
        else:
            s0, s1 = slice(-lag, len(e)), slice(0, len(e) + lag)
        mask = valid[s0] & valid[s1] & (exp[s0] == exp[s1])
        return s0, s1, mask

    ee0 = np.sum(e * e, axis=0)
    uu0 = np.sum(u * u, axis=0)
    acf = np.empty((M + 1, nc))
    cross_lags = np.arange(-M, M + 1)
    ccf = np.empty((cross_lags.size, nu, nc))
    norm = np.sqrt(uu0[:, None] * ee0[None, :])
    with np.errstate(divide="ignore", invalid="ignore"):  # zero residuals: NaN, "no test"
        for lag in range(M + 1):
            s0, s1, m = pairs(lag)
            acf[lag] = np.sum(e[s0][m] * e[s1][m], axis=0) / ee0
        for i, lag in enumerate(cross_lags):
            s0, s1, m = pairs(int(lag))
            ccf[i] = np.einsum("tj,tc->jc", u[s0][m], e[s1][m]) / norm
    lags = np.arange(M + 1)
    q = nv * (nv + 2) * np.sum(acf[1:] ** 2 / (nv - lags[1:, None]), axis=0)
    ljung = {c: {"Q": float(q[i]), "p_value": float(chi2.sf(q[i], M)), "lags": M}
             for i, c in enumerate(pr.channels)}
    return ResidualResult(prediction=pr, lags=lags, cross_lags=cross_lags,
                          autocorrelation=acf, cross_correlation=ccf,
                          band99=float(Z99 / math.sqrt(nv)), n=nv, ljung_box=ljung,
                          inputs=tuple(inputs), channels=pr.channels, settings=settings)


def _edge(values: np.ndarray, unit: str) -> np.ndarray:
    """Values shown to the user: kelvin as degC, other units as they are."""
    return K2C(values) if unit == "K" else values


def _edge_unit(unit: str) -> str:
    return "degC" if unit == "K" else unit


# --------------------------------------------------------------------------- figures
def _trace_figure(time, measured, predictions: dict, channels, title: str, units=None):
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(channels), 1, figsize=(10, 2.3 * len(channels)), sharex=True,
                             constrained_layout=True)
    units = units or ("K",) * len(channels)
    for i, (ax, c) in enumerate(zip(np.atleast_1d(axes), channels, strict=True)):
        ax.plot(time, _edge(measured[:, i], units[i]), color="k", lw=1.0, label="measured")
        for label, pr in predictions.items():
            ax.plot(time, _edge(pr.predicted[:, i], units[i]), lw=1.0,
                    label=f"{label}: fit {pr.fit_percent[c]:.1f} %")
        ax.set_ylabel(f"{c} ({_edge_unit(units[i])})")
        ax.legend(fontsize=8, loc="upper right")
    np.atleast_1d(axes)[-1].set_xlabel("time (s)")
    fig.suptitle(title)
    return fig

def resolve(params, model: Model | str | None = None) -> tuple[Model, ParameterValues, str]:
    """(model, values, label) of ``params``: ``ParameterValues`` of any declaration
    (``ModelParams``, ``EconParams``...), a ``DeclaredFitResult``, a parameter file or
    ``(model, values)``; ``model`` (a ``Model``, built-in name or file) overrides the one the
    parameters name. ``params=None``: the model's declared values, or the paper's preset
    without a model (as ``"paper"``)."""
    from acid.models.params import paper

    if isinstance(params, tuple):
        model, params = params
    if (params is None and model is None) or (isinstance(params, str) and params == "paper"):
        params = paper()
    if isinstance(getattr(params, "params", None), ParameterValues):
        params = params.params   # a stage's fit (EconFit)
    if isinstance(params, DeclaredFitResult):
        pv = fitted_parameters(params)
        m = pv.declaration if model is None else load(model)
        return m, pv, f"{m.name} (fit-{params.method})"
    if isinstance(params, (str, Path)):
        pv = read_parameters(None if model is None else load(model), params)
        return pv.declaration, pv, f"{pv.declaration.name} ({Path(params).name})"
    if params is None:
        params = declared_parameters(load(model))
    if not isinstance(params, ParameterValues):
        raise ConfigError(f"expected a fit result, a parameter file or ParameterValues, got "
                          f"{type(params).__name__}")
    m = params.declaration if model is None else load(model)
    return m, params, params.name if params.source is None else f"{m.name} ({params.source})"


def _state_track(model: Model, data: ModelData, P: np.ndarray, first: np.ndarray,
                 warmup: int) -> np.ndarray:
    """(N, nx) the state at every sample: measured states as measured; latent ones from a
    forced run of each experiment from its sample ``first[e]`` (NaN before it)."""
    X = data.x.copy()
    latent = [i for i, s in enumerate(model.states) if not s.measured]
    if not latent:
        return X
    X[:, latent] = np.nan
    for (_a, b), s in zip(data.segments, first, strict=True):
        if s >= b:
            continue
        x0 = data.initial_states(model, np.array([s]))
        if warmup > 0:
            x0 = warm_start_states(model, data, P[[s]], np.array([s]), warmup, x0, latent)
        x = x0[0]
        for n in range(s, b):
            X[n, latent] = x[latent]
            if n + 1 == b:
                break
            x = np.where(np.isfinite(data.x[n]), data.x[n], x)
            x, _ = model.step(x, data.u[n], data.d[n], P[n])
            x = np.asarray(x, dtype=float).ravel()
    return X


def predict_model(ds: Dataset, params=None, k: int | None = 1, *, model=None,
                  warmup: float = 0.0) -> PredictionResult:
    """k-step-ahead predictions of every measured channel of a declared model along ``ds``
    (module docstring). ``params`` as :func:`resolve`; ``k`` >= 1 steps or None
    (simulation); ``warmup`` seconds (a whole number of samples, as ``validate_model``'s)
    at the start of each experiment that fit the latent states (none are predicted there).
    Returns a ``PredictionResult`` in the declared units."""
    if k is not None and (isinstance(k, bool) or int(k) != k or int(k) < 1):
        raise ConfigError(f"predict: horizon k must be a whole number of samples >= 1 or None, "
                          f"got {k!r}")
    if isinstance(warmup, bool):
        raise ConfigError(f"predict: warmup must be a duration >= 0 s, got {warmup!r}")
    m, ps, label = resolve(params, model)
    data = ModelData.of(m, ds, min_samples=2)
    latent = any(not s.measured for s in m.states)
    W = samples_of(warmup, ds.Ts, "predict: warmup", used=latent)
    W = W if latent else 0
    n = len(data)
    notes: list[str] = []
    P = parameters_at(m, data, ps, np.arange(n), notes)
    first = np.array([a + W for a, _ in data.segments])
    X = _state_track(m, data, P, first, W)
    chans = data.measured_channels(m)
    cols = [c for c, _ in chans]
    meas = np.concatenate([data.x, data.y], axis=1)[:, cols]
    pred = np.full(meas.shape, np.nan)
    for (_a, b), s in zip(data.segments, first, strict=True):
        steps = (b - s - 1) if k is None else int(k)
        if steps < 1 or b - s <= steps:
            continue
        starts = np.array([s]) if k is None else np.arange(s, b - steps)
        idx = starts[:, None] + np.arange(steps + 1)[None, :]
        Y = simulate_windows(m, data, idx, X[starts], P[starts])[..., cols]
        if k is None:
            pred[s:b] = Y[0]
        else:
            pred[starts + steps] = Y[:, -1]
    unit_of = {r.name: r.unit for r in m.states + m.outputs}
    names = tuple(nm for _, nm in chans)
    return PredictionResult(time=np.asarray(ds.time, dtype=float).copy(), measured=meas,
                            predicted=pred, horizon=None if k is None else int(k), Ts=m.Ts,
                            model=label, source=ds.source, channels=names,
                            units=tuple(unit_of[c] for c in names))


def compare_models(ds: Dataset, *params, k: int | None = None, labels=None, model=None,
                   warmup: float = 0.0) -> CompareResult:
    """Fit % per channel of one or more declared parameter sets on ``ds`` (MATLAB
    ``compare``; ``k`` None: simulation)."""
    return compare_predictions(
        params, lambda p: predict_model(ds, p, k, model=model, warmup=warmup), k, labels)

def resid_model(ds: Dataset, params=None, max_lag: int = 25, k: int = 1, *, model=None,
                warmup: float = 0.0) -> ResidualResult:
    """Residual tests of a declared model on ``ds`` (MATLAB ``resid``): autocorrelation of
    every channel's k-step errors and their cross-correlation with every declared input."""
    if int(max_lag) < 1:
        raise ConfigError(f"resid: max_lag must be >= 1, got {max_lag}")
    pr = predict_model(ds, params, k, model=model, warmup=warmup)
    m, _, _ = resolve(params, model)
    data = ModelData.of(m, ds, min_samples=2)
    return residual_tests(pr, data.u, tuple(r.name for r in m.inputs), ds.experiment,
                          int(max_lag), {"max_lag": int(max_lag), "k": k, "warmup_s": warmup},
                          ds.source)


#: MATLAB's names: ``predict(data, params, k=1, *, warmup=0)``, ``compare(data, *params,
#: k=None, labels=None, warmup=0)``, ``resid(data, params, max_lag=25, k=1, *, warmup=0)``
#: (``k`` in steps, ``warmup`` in seconds).
predict = predict_model
compare = compare_models
resid = resid_model
