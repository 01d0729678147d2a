"""Multi-start open-loop validation of the control-oriented model (paper section II-B-3).

From each of ``starts`` instants k0 on held-out data the model (eqs. 1-3) predicts
``horizon`` steps open loop (paper: 60 starts, 300 steps = 1500 s) from the measured initial
state x(k0) = [T_cab(k0), T_evap(k0)], driven by the measured inputs W_bl, T_evap_set. The
disturbances T_int and T_shell are held at their values at k0, as in the paper
(``exogenous="hold"``), or follow their measurements (``exogenous="measured"``).

Prediction step i = 0 .. horizon is the sample k0 + i; every window of ``horizon + 1``
samples lies inside one experiment. The predicted T_ain(i) is eq. 3 of the predicted
T_evap(i) and the measured W_bl(i). At i = 0 the predicted states equal the measurements
(error exactly 0); T_ain(0) is already a model output and may differ.

Everything here is in kelvin; errors are temperature differences (K = degC differences).
The result is data (``ValidationResult``); ``acid.report.validation`` draws Figs. 5-6.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from acid import model
from acid._io import json_safe
from acid.data import MODEL_CHANNELS, Dataset
from acid.errors import ConfigError, DataError
from acid.metrics import fit_percent
from acid.params import ModelParams, as_params
from acid.units import K2C

#: Validated channels, in the order of the last axis of the result arrays.
VALIDATED_CHANNELS = ("T_cab", "T_evap", "T_ain")

#: Prediction times (s) reported in the ``at_horizon`` table when inside the horizon.
REPORT_HORIZONS_S = (60.0, 300.0, 600.0, 900.0, 1200.0, 1500.0)

#: Below this standard deviation (K) a measured window counts as constant: fit % undefined.
CONSTANT_TRUTH_STD_K = 1e-9

EXOGENOUS_MODES = ("hold", "measured")
PLACEMENTS = ("even", "random")

#: Most prediction samples (starts x (horizon + 1)) one study may hold (about 1 GB of arrays).
MAX_PREDICTION_SAMPLES = 5_000_000


@dataclass(frozen=True)
class HeldOut:
    """Which part of a record a validation uses, why, and whether it is in-sample.

    ``fraction``: the last fraction of the samples (``None``: the whole record); ``source``:
    "--held-out-fraction", "params provenance" or "whole record"; ``warning``: set when the
    validated part overlaps the data the parameters were fitted on.
    """

    fraction: float | None
    source: str
    warning: str | None = None


def held_out_part(provenance: dict, data: str, data_sha256: str,
                  requested: float | None = None) -> HeldOut:
    """The part of ``data`` to validate on, from the fit's provenance (``acid fit`` records
    ``data_sha256``/``data_file`` and ``estimation_fraction``) and an explicit request.

    Parameters fitted on this file (same SHA-256, or the same path when no hash was
    recorded) are validated on the part after their estimation fraction; when they were
    fitted on all of it, or the requested part overlaps the estimation part, the result is
    in-sample and ``warning`` says so.
    """
    prov = provenance if isinstance(provenance, dict) else {}
    fitted_on, fitted_file = prov.get("data_sha256"), prov.get("data_file")
    if isinstance(fitted_on, str):
        same_file = maybe_same = fitted_on == data_sha256
    else:  # no hash: the recorded path, if any, decides; nothing recorded: maybe this file
        same_file = isinstance(fitted_file, str) and _same_path(fitted_file, data)
        maybe_same = same_file or not isinstance(fitted_file, str)
    est = prov.get("estimation_fraction")
    est = float(est) if isinstance(est, (int, float)) and not isinstance(est, bool) else None
    if est is not None and not (math.isfinite(est) and 0.0 < est <= 1.0):
        est = None
    if requested is not None:
        warning = None
        if same_file and (est is None or float(requested) > 1.0 - est + 1e-12):
            fitted = "all" if est is None or est >= 1.0 else f"the first {100 * est:g} %"
            warning = (f"{data}: the validated part (last {100 * float(requested):g} %) "
                       f"overlaps {fitted} of the record, on which the parameters were "
                       "fitted: this validation is partly in-sample")
        return HeldOut(float(requested), "--held-out-fraction", warning)
    if maybe_same and est is not None and est < 1.0:
        return HeldOut(1.0 - est, "params provenance")
    if same_file:
        return HeldOut(None, "whole record",
                       f"{data}: the parameters were fitted on this whole record (no held-out "
                       "part): this validation is in-sample; fit with --estimation-fraction "
                       "0.5 or validate on another record")
    return HeldOut(None, "whole record")


def _same_path(a: str, b: str) -> bool:
    import os

    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


@dataclass(frozen=True)
class ValidationResult:
    """Open-loop predictions from many starts, their errors and the statistics of them.

    Arrays have shape (S, H + 1, 3): S starts, prediction steps i = 0 .. H, channels
    ``VALIDATED_CHANNELS`` = (T_cab, T_evap, T_ain). Temperatures in K.

    Attributes
    ----------
    start_index : (S,) sample index k0 of each start in the dataset.
    start_time : (S,) dataset time of each start, s.
    horizon_s : (H + 1,) prediction time i * Ts, s.
    predicted, measured : (S, H + 1, 3) temperatures, K.
    errors : (S, H + 1, 3) predicted - measured, K.
    inputs : (S, H + 1, 2) measured [W_bl (kg/s), T_evap_set (K)] over each window.
    exogenous : (S, H + 1, 2) [T_int, T_shell] (K) as the model used them (held or measured).
    envelope : {channel: {"mean", "p5", "p95", "mean_abs", "max_abs"}: (H + 1,) K}; signed
        mean and 5th/95th percentiles of the error over the starts, and the mean and largest
        absolute error, at each prediction step.
    metrics : {channel: {name: float}} pooled over all starts and steps i = 0 .. H:
        ``rmse``, ``mean_abs``, ``median_abs``, ``p90_abs``, ``p95_abs``, ``max_abs`` (K),
        ``fit_percent`` (median over starts of the per-start fit, %) and
        ``fit_percent_pooled`` (one fit over all windows with the pooled mean, %). A fit is
        NaN (``null`` in JSON) where the truth is constant (std <= ``CONSTANT_TRUTH_STD_K``).
    per_start : {channel: {"rmse", "max_abs", "fit_percent"}: (S,)} metrics of each window.
    settings : how the study was run (mode, counts, ranges, parameters, data source).
    """

    start_index: np.ndarray
    start_time: np.ndarray
    horizon_s: np.ndarray
    predicted: np.ndarray
    measured: np.ndarray
    errors: np.ndarray
    inputs: np.ndarray
    exogenous: np.ndarray
    envelope: dict[str, dict[str, np.ndarray]]
    metrics: dict[str, dict[str, float]]
    per_start: dict[str, dict[str, np.ndarray]]
    settings: dict = field(default_factory=dict)
    channels: tuple[str, ...] = VALIDATED_CHANNELS

    # ------------------------------------------------------------------ views
    @property
    def n_starts(self) -> int:
        """Number of prediction windows S."""
        return int(self.start_index.shape[0])

    @property
    def horizon(self) -> int:
        """Number of prediction steps H."""
        return int(self.horizon_s.shape[0] - 1)

    @property
    def predicted_degC(self) -> np.ndarray:
        """Predicted temperatures (S, H + 1, 3), degC."""
        return K2C(self.predicted)

    @property
    def measured_degC(self) -> np.ndarray:
        """Measured temperatures (S, H + 1, 3), degC."""
        return K2C(self.measured)

    def channel(self, name: str) -> int:
        """Index of a validated channel on the last axis of the arrays."""
        try:
            return self.channels.index(name)
        except ValueError:
            raise DataError(f"{name!r} is not a validated channel "
                            f"(one of {', '.join(self.channels)})") from None

    def at_horizon(self, times_s=REPORT_HORIZONS_S) -> list[dict]:
        """Absolute-error statistics over the starts at given prediction times (s).

        Returns one row per time inside the horizon: ``step``, ``time_s`` and, per channel,
        ``mean_abs``, ``p95_abs``, ``max_abs`` (K) of the error at that step.
        """
        Ts = float(self.horizon_s[1] - self.horizon_s[0]) if self.horizon >= 1 else 1.0
        rows = []
        for t in times_s:
            i = int(round(t / Ts))
            if 0 <= i <= self.horizon:
                a = np.abs(self.errors[:, i, :])
                row = {"step": i, "time_s": float(self.horizon_s[i])}
                for c, name in enumerate(self.channels):
                    row[name] = {"mean_abs": float(a[:, c].mean()),
                                 "p95_abs": float(np.percentile(a[:, c], 95)),
                                 "max_abs": float(a[:, c].max())}
                rows.append(row)
        return rows

    def to_json_dict(self) -> dict:
        """JSON-ready summary (numbers in K, times in s; non-finite values become null).

        Keys: ``settings``, ``channels`` ({T_cab, T_evap, T_ain} -> pooled metrics),
        ``at_horizon``, ``vs_horizon`` (envelope per step), ``starts`` (indices, times and
        per-start metrics).
        """
        return json_safe({
            "settings": self.settings,
            "units": {"errors": "K", "time": "s"},
            "channels": {name: {**m, "unit": "K"} for name, m in self.metrics.items()},
            "fit_percent_definition": (
                "fit_percent = median over starts of 100 (1 - ||y - y_hat|| / ||y - mean(y)||) "
                "per window; fit_percent_pooled = the same over all windows at once"),
            "at_horizon": self.at_horizon(),
            "vs_horizon": {"horizon_s": self.horizon_s,
                           **{name: env for name, env in self.envelope.items()}},
            "starts": {"index": self.start_index, "time_s": self.start_time,
                       "per_start": self.per_start},
        })


# --------------------------------------------------------------------- study
def validate(ds: Dataset, params: ModelParams, starts: int = 60, horizon: int = 300,
             exogenous: str = "hold", held_out_fraction: float | None = None,
             start_range: tuple[int, int] | None = None, placement: str = "even",
             seed: int = 0) -> ValidationResult:
    """Multi-start open-loop validation of eqs. 1-3 on a dataset.

    Parameters
    ----------
    ds : dataset with the channels of ``acid.data.MODEL_CHANNELS``, sampled at ``params.Ts``.
    params : model parameters (kelvin convention): ``ModelParams`` or the result of
        ``acid.fit``.
    starts : number of prediction windows requested (paper: 60).
    horizon : prediction steps per window (paper: 300, i.e. 1500 s at Ts = 5 s).
    exogenous : ``"hold"`` keeps T_int, T_shell at their values at the start (paper);
        ``"measured"`` feeds their measurements over the window.
    held_out_fraction : use only the last fraction (0, 1] of the samples, e.g. the part not
        used for estimation. Exclusive with ``start_range``.
    start_range : (lo, hi) sample indices; every window lies in ``lo .. hi - 1``.
    placement : ``"even"`` spreads the starts evenly over the admissible start indices
        (deterministic); ``"random"`` draws them without replacement with
        ``numpy.random.default_rng(seed)``.
    seed : seed of the random placement.

    Returns
    -------
    ValidationResult

    Raises
    ------
    DataError
        A channel is missing, the sample times disagree, or not even one window of
        ``horizon + 1`` samples fits inside one experiment of the selected range
        ("record too short").
    ConfigError
        Invalid option values.

    Notes
    -----
    Starts are placed over all admissible indices (windows may overlap when the record is
    shorter than ``starts * horizon``). When fewer distinct admissible starts exist than
    requested, each is used once and a ``UserWarning`` says so.
    """
    params = as_params(params)  # a FitResult is accepted wherever parameters are
    if exogenous not in EXOGENOUS_MODES:
        raise ConfigError(f"--exogenous: unknown mode {exogenous!r} (choose 'hold' or 'measured')")
    if placement not in PLACEMENTS:
        raise ConfigError(f"--placement: unknown mode {placement!r} (choose 'even' or 'random')")
    if int(starts) < 1:
        raise ConfigError(f"--starts must be at least 1, got {starts}")
    if int(horizon) < 1:
        raise ConfigError(f"--horizon must be at least 1 step, got {horizon}")
    if not 0 <= int(seed) < 2**63:
        raise ConfigError(f"--seed must be an integer >= 0, got {seed}")
    starts, horizon = int(starts), int(horizon)
    src = ds.source
    ds.validate(require=MODEL_CHANNELS)
    if not math.isclose(ds.Ts, params.Ts, rel_tol=1e-6):
        raise DataError(f"{src}: sample time {ds.Ts:g} s differs from the model's "
                        f"Ts = {params.Ts:g} s (parameters {params.name!r})")

    lo, hi, range_note = _sample_range(len(ds), held_out_fraction, start_range, src)
    admissible = _admissible_starts(ds, lo, hi, horizon)
    if admissible.size == 0:
        segments = ds.segments()
        longest = max(max((min(b, hi) - max(a, lo) for a, b in segments), default=0), 0)
        where = " in the longest experiment" if len(segments) > 1 else ""
        raise DataError(
            f"{src}: record too short: {longest} samples "
            f"({longest * ds.Ts:g} s){where}{range_note}, "
            f"the study needs {horizon + 1} consecutive samples ({horizon * ds.Ts:g} s) "
            f"for a {horizon}-step prediction")
    k0 = _place_starts(admissible, min(starts, admissible.size), placement, seed)
    if k0.size * (horizon + 1) > MAX_PREDICTION_SAMPLES:
        raise ConfigError(f"--starts {k0.size} x --horizon {horizon} steps is "
                          f"{k0.size * (horizon + 1):.3g} prediction samples, more than "
                          f"{MAX_PREDICTION_SAMPLES:.0e}: lower --starts or --horizon")
    if k0.size < starts:
        warnings.warn(f"{src}: only {k0.size} distinct start instants fit a {horizon}-step "
                      f"window; using {k0.size} instead of {starts}", UserWarning,
                      stacklevel=2)

    # ---- gather windows (S, H + 1) by fancy indexing, then predict all starts at once
    idx = k0[:, None] + np.arange(horizon + 1)[None, :]
    T_cab, T_evap, T_ain, T_evap_set, T_int, T_shell = (
        ds.get(n, "K")[idx] for n in ("T_cab", "T_evap", "T_ain", "T_evap_set", "T_int",
                                      "T_shell"))
    W_bl = ds.get("W_bl", "kg/s")[idx]
    if exogenous == "hold":
        T_int = np.broadcast_to(T_int[:, :1], T_int.shape)
        T_shell = np.broadcast_to(T_shell[:, :1], T_shell.shape)
    x0 = np.stack([T_cab[:, 0], T_evap[:, 0]], axis=-1)
    with np.errstate(over="ignore", invalid="ignore"):  # divergence is refused just below
        cab_hat, evap_hat, _ = model.simulate(x0, W_bl[:, :-1], T_evap_set[:, :-1],
                                              T_int[:, :-1], T_shell[:, :-1], params)
        ain_hat = model.inlet_air(evap_hat, W_bl, params)  # eq. 3 at i = 0 .. H
    if not (np.all(np.isfinite(cab_hat)) and np.all(np.isfinite(evap_hat))
            and np.all(np.isfinite(ain_hat))):
        raise DataError(f"{src}: the predictions with parameters {params.name!r} diverge "
                        "(values beyond the range of floating point): the model is unstable")

    predicted = np.stack([cab_hat, evap_hat, ain_hat], axis=-1)
    measured = np.stack([T_cab, T_evap, T_ain], axis=-1)
    errors = predicted - measured

    horizon_s = np.arange(horizon + 1) * ds.Ts
    with np.errstate(over="ignore", invalid="ignore"):  # --allow-unstable: huge errors
        envelope, metrics, per_start = _statistics(measured, predicted, errors)
    settings = {
        "exogenous": exogenous,
        "starts_requested": starts,
        "starts": int(k0.size),
        "horizon_steps": horizon,
        "horizon_s": horizon * ds.Ts,
        "Ts_s": ds.Ts,
        "placement": placement,
        "seed": seed if placement == "random" else None,
        "sample_range": [lo, hi],
        "held_out_fraction": held_out_fraction,
        "admissible_starts": int(admissible.size),
        "params_name": params.name,
        "params_provenance": params.provenance,
        "data_source": src,
        "data_samples": len(ds),
        "metrics_over": "all starts, prediction steps i = 0 .. horizon",
    }
    return ValidationResult(
        start_index=k0, start_time=ds.time[k0].copy(), horizon_s=horizon_s,
        predicted=predicted, measured=measured, errors=errors,
        inputs=np.stack([W_bl, T_evap_set], axis=-1),
        exogenous=np.stack([T_int, T_shell], axis=-1),
        envelope=envelope, metrics=metrics, per_start=per_start, settings=settings)


# ------------------------------------------------------------------- helpers
def _sample_range(n: int, fraction: float | None, start_range: tuple[int, int] | None,
                  src: str) -> tuple[int, int, str]:
    """The (lo, hi) sample range the windows must lie in, and a note for messages."""
    if fraction is not None and start_range is not None:
        raise ConfigError("give either held_out_fraction or start_range, not both")
    if fraction is not None:
        f = float(fraction)
        if not (math.isfinite(f) and 0.0 < f <= 1.0):
            raise ConfigError(f"--held-out-fraction must be in (0, 1], got {fraction}")
        lo = int(round(n * (1.0 - f)))
        return lo, n, f" of the held-out part (last {100 * f:g} %, samples {lo}..{n - 1})"
    if start_range is not None:
        lo, hi = (int(v) for v in start_range)
        if not 0 <= lo < hi <= n:
            raise ConfigError(f"start_range {start_range} is not inside 0..{n} of {src}")
        return lo, hi, f" of samples {lo}..{hi - 1}"
    return 0, n, ""


def _admissible_starts(ds: Dataset, lo: int, hi: int, horizon: int) -> np.ndarray:
    """Every k0 whose window k0 .. k0 + horizon lies in [lo, hi) and in one experiment."""
    parts = []
    for a, b in ds.segments():
        a, b = max(a, lo), min(b, hi)
        if b - a >= horizon + 1:
            parts.append(np.arange(a, b - horizon))
    return np.concatenate(parts) if parts else np.empty(0, dtype=int)


def _place_starts(admissible: np.ndarray, starts: int, placement: str,
                  seed: int) -> np.ndarray:
    """Start indices: evenly spread over ``admissible`` or drawn at random; sorted, distinct."""
    m = admissible.size
    if placement == "random":
        rng = np.random.default_rng(seed)
        pick = rng.choice(m, size=min(starts, m), replace=False)
    else:
        pick = np.round(np.linspace(0, m - 1, starts)).astype(int)
    return np.unique(admissible[pick]).astype(int)


def _statistics(measured: np.ndarray, predicted: np.ndarray, errors: np.ndarray):
    """Envelope vs horizon, pooled metrics and per-start metrics for each channel."""
    abs_err = np.abs(errors)
    # signed envelope over starts (axis 0): shape (H + 1, 3)
    mean = errors.mean(axis=0)
    p5, p95 = np.percentile(errors, [5.0, 95.0], axis=0)
    mean_abs_h = abs_err.mean(axis=0)
    max_abs_h = abs_err.max(axis=0)
    # per start, over the window (axis 1): shape (S, 3)
    rmse_s = np.sqrt(np.mean(errors ** 2, axis=1))
    max_s = abs_err.max(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        fit_s = fit_percent(measured, predicted, axis=1)
    # a truth that does not vary (beyond round-off) has no defined fit
    fit_s = np.where(measured.std(axis=1) > CONSTANT_TRUTH_STD_K, fit_s, np.nan)
    # pooled over starts and steps: shape (3,)
    flat_e = abs_err.reshape(-1, abs_err.shape[-1])
    q50, q90, q95 = np.percentile(flat_e, [50.0, 90.0, 95.0], axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        fit_pooled = fit_percent(measured.reshape(-1, 3), predicted.reshape(-1, 3), axis=0)
    fit_pooled = np.where(measured.reshape(-1, 3).std(axis=0) > CONSTANT_TRUTH_STD_K,
                          fit_pooled, np.nan)

    envelope, metrics, per_start = {}, {}, {}
    for c, name in enumerate(VALIDATED_CHANNELS):
        envelope[name] = {"mean": mean[:, c], "p5": p5[:, c], "p95": p95[:, c],
                          "mean_abs": mean_abs_h[:, c], "max_abs": max_abs_h[:, c]}
        finite_fits = fit_s[:, c][np.isfinite(fit_s[:, c])]
        metrics[name] = {
            "rmse": float(np.sqrt(np.mean(errors[..., c] ** 2))),
            "mean_abs": float(flat_e[:, c].mean()),
            "median_abs": float(q50[c]),
            "p90_abs": float(q90[c]),
            "p95_abs": float(q95[c]),
            "max_abs": float(flat_e[:, c].max()),
            "fit_percent": float(np.median(finite_fits)) if finite_fits.size else math.nan,
            "fit_percent_pooled": float(fit_pooled[c]),
        }
        per_start[name] = {"rmse": rmse_s[:, c], "max_abs": max_s[:, c],
                           "fit_percent": fit_s[:, c]}
    return envelope, metrics, per_start
