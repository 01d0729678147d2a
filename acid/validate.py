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

The econ model family (:mod:`acid.econ`) is validated by the same study: pass its
``EconParams`` and :mod:`acid.econ.validate` predicts the windows (interior and shell predicted,
speed and ambient held or measured); the extra channels go to ``extra_metrics``.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from acid._io import json_safe
from acid.data import MODEL_CHANNELS, Dataset
from acid.errors import ConfigError, DataError
from acid.metrics import fit_percent
from acid.params import ModelParams
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
    extra_metrics : {channel: pooled |error| statistics with their unit} of channels beyond
        the three (the econ model's T_int, T_shell, w_cab, P_comp, window energy); empty for
        the paper's model.
    yardsticks : {"persistence" | "arx" | "subspace": acid.yardsticks.YardstickPrediction}
        predicted over the same windows (``predicted`` (S, H + 1, 3), K); empty unless asked
        for (``validate(..., yardsticks=True)``). Yardsticks, never offered to a controller.
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
    extra_metrics: dict = field(default_factory=dict)
    yardsticks: dict = field(default_factory=dict)

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

    @property
    def window_design(self) -> dict:
        """How the windows lie: start spacing (s), horizon (s), overlap, what is held.

        ``overlap_fraction``: the mean share of a window's ``H + 1`` samples that the next
        window (in time) also holds; ``max_windows_per_sample``: the most windows one
        sample lies in (one event enters that many starts' errors).
        """
        k0, H = self.start_index, self.horizon
        Ts = float(self.settings.get("Ts_s", self.horizon_s[1] - self.horizon_s[0]
                                     if H >= 1 else 1.0))
        gaps = np.diff(k0)
        shared = np.clip(H + 1 - gaps, 0, None) / (H + 1)
        cover = np.zeros(int(k0.max()) + H + 2 if k0.size else 1, dtype=int)
        np.add.at(cover, k0, 1)
        np.add.at(cover, k0 + H + 1, -1)
        spacing = ({"min": float(gaps.min() * Ts), "median": float(np.median(gaps) * Ts),
                    "max": float(gaps.max() * Ts)} if gaps.size else None)
        return {
            "starts": self.n_starts,
            "starts_requested": self.settings.get("starts_requested", self.n_starts),
            "placement": self.settings.get("placement", "even"),
            "non_overlapping": bool(self.settings.get("non_overlapping", False)),
            "horizon_s": float(self.horizon_s[-1]),
            "start_spacing_s": spacing,
            "overlap_fraction": float(shared.mean()) if shared.size else 0.0,
            "max_windows_per_sample": int(np.cumsum(cover).max()) if k0.size else 0,
            "held_disturbances": held_meaning(self.settings.get("model", "paper"),
                                              self.settings.get("exogenous", "hold")),
        }

    def by_horizon(self, times_s=(0.0, *REPORT_HORIZONS_S)) -> dict:
        """{"model" | yardstick: {channel: {"<t>": {"rmse_K", "p90_K"}}}} at prediction
        times ``t`` (s) inside the horizon: RMSE and p90 of |error| over the starts."""
        from acid.yardsticks import by_horizon

        times = sorted(set(times_s) | {float(self.horizon_s[-1])})
        out = {"model": by_horizon(self.errors, self.horizon_s, self.channels, times)}
        for name, y in self.yardsticks.items():
            out[name] = by_horizon(y.predicted - self.measured, self.horizon_s,
                                   self.channels, times)
        return out

    def to_json_dict(self) -> dict:
        """JSON-ready summary (numbers in K, times in s; non-finite values become null).

        Keys: ``settings``, ``window_design``, ``channels`` ({T_cab, T_evap, T_ain} -> pooled
        metrics), ``at_horizon``, ``by_horizon`` (the model's RMSE and p90 |e| per channel
        and prediction time), ``vs_horizon`` (envelope per step), ``starts`` (indices, times
        and per-start metrics); with yardsticks also ``yardsticks`` ({persistence | arx |
        subspace: {channel: {horizon_s: {rmse_K, p90_K}}}}) and ``yardstick_settings``.
        """
        table = self.by_horizon()
        marks = {}
        if self.yardsticks:
            marks = {"yardsticks": {k: v for k, v in table.items() if k != "model"},
                     "yardstick_settings": {
                         k: {"description": y.description, **y.settings,
                             "note": "a yardstick: never offered to a controller"}
                         for k, y in self.yardsticks.items()}}
        return json_safe({
            "settings": self.settings,
            "units": {"errors": "K", "time": "s"},
            "channels": {name: {**m, "unit": "K"} for name, m in self.metrics.items()},
            "fit_percent_definition": (
                "fit_percent = median over starts of 100 (1 - ||y - y_hat|| / ||y - mean(y)||) "
                "per window; fit_percent_pooled = the same over all windows at once"),
            "at_horizon": self.at_horizon(),
            "window_design": self.window_design,
            "by_horizon": table["model"],
            **marks,
            "vs_horizon": {"horizon_s": self.horizon_s,
                           **{name: env for name, env in self.envelope.items()}},
            "starts": {"index": self.start_index, "time_s": self.start_time,
                       "per_start": self.per_start},
            **({"extra_channels": self.extra_metrics} if self.extra_metrics else {}),
        })


# --------------------------------------------------------------------- study
def validate(ds: Dataset, params, starts: int = 60, horizon: int = 300,
             exogenous: str = "hold", held_out_fraction: float | None = None,
             start_range: tuple[int, int] | None = None, placement: str = "even",
             seed: int = 0, non_overlapping: bool = False,
             yardsticks: bool = False) -> ValidationResult:
    """Multi-start open-loop validation of eqs. 1-3 on a dataset.

    Parameters
    ----------
    ds : dataset with the channels of ``acid.data.MODEL_CHANNELS``, sampled at ``params.Ts``
        (for the econ model: those of ``acid.econ.params.REQUIRED``).
    params : model parameters (kelvin convention): ``ModelParams`` or the result of
        ``acid.fit`` (the paper's eqs. 1-3), or ``acid.econ.EconParams``.
    starts : number of prediction windows requested (paper: 60).
    horizon : prediction steps per window (paper: 300, i.e. 1500 s at Ts = 5 s).
    exogenous : ``"hold"`` keeps T_int, T_shell at their values at the start (paper);
        ``"measured"`` feeds their measurements over the window. For the econ model (which
        predicts T_int and T_shell) the same choice applies to v_veh and T_amb.
    held_out_fraction : use only the last fraction (0, 1] of the samples, e.g. the part not
        used for estimation. Exclusive with ``start_range``.
    start_range : (lo, hi) sample indices; every window lies in ``lo .. hi - 1``.
    placement : ``"even"`` spreads the starts evenly over the admissible start indices
        (deterministic); ``"random"`` draws them without replacement with
        ``numpy.random.default_rng(seed)``.
    seed : seed of the random placement.
    non_overlapping : place the starts at least ``horizon + 1`` samples apart, so that no
        sample lies in two windows (evenly spread, ``placement="even"`` only); fewer starts
        than requested when the record is short (a ``UserWarning`` says how many).
    yardsticks : also predict the windows with persistence, ARX and a subspace model
        (:mod:`acid.yardsticks`), ARX and subspace fitted on the samples before the
        validated range (the estimation part), or on the whole record when there are none
        (then in-sample: ``settings["yardsticks_in_sample"]``).

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
    from acid.econ.params import as_any_params

    params = as_any_params(params)  # a fit result is accepted wherever parameters are
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
    if non_overlapping and placement != "even":
        raise ConfigError(f"--non-overlapping places the starts evenly: it cannot be combined "
                          f"with --placement {placement}")
    starts, horizon = int(starts), int(horizon)
    src = ds.source
    econ = _is_econ(params)
    if econ:
        from acid.econ.params import REQUIRED
    ds.validate(require=REQUIRED if econ else MODEL_CHANNELS)
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
    if non_overlapping:
        k0 = _place_non_overlapping(admissible, starts, horizon)
        if k0.size < starts:
            warnings.warn(f"{src}: --non-overlapping: {k0.size} windows of {horizon} steps "
                          f"({horizon * ds.Ts:g} s) fit without overlap{range_note}; using "
                          f"{k0.size} instead of {starts}", UserWarning, stacklevel=2)
    else:
        k0 = _place_starts(admissible, min(starts, admissible.size), placement, seed)
    if k0.size * (horizon + 1) > MAX_PREDICTION_SAMPLES:
        raise ConfigError(f"--starts {k0.size} x --horizon {horizon} steps is "
                          f"{k0.size * (horizon + 1):.3g} prediction samples, more than "
                          f"{MAX_PREDICTION_SAMPLES:.0e}: lower --starts or --horizon")
    if k0.size < starts and not non_overlapping:
        warnings.warn(f"{src}: only {k0.size} distinct start instants fit a {horizon}-step "
                      f"window; using {k0.size} instead of {starts}", UserWarning,
                      stacklevel=2)

    # ---- gather windows (S, H + 1) by fancy indexing, then predict all starts at once
    idx = k0[:, None] + np.arange(horizon + 1)[None, :]
    extra = {}
    with np.errstate(over="ignore", invalid="ignore"):  # divergence is refused just below
        if econ:
            from acid.econ.validate import extra_metrics, predict_windows

            win = predict_windows(ds, idx, params, exogenous)
            predicted, measured = win.predicted, win.measured
            inputs, exo = win.inputs, win.exogenous
            extra = extra_metrics(win)
        else:
            predicted, measured, inputs, exo = _paper_windows(ds, idx, params, exogenous)
    if not np.all(np.isfinite(predicted)):
        raise DataError(f"{src}: the predictions with parameters {params.name!r} diverge "
                        "(values beyond the range of floating point): the model is unstable")
    errors = predicted - measured

    horizon_s = np.arange(horizon + 1) * ds.Ts
    with np.errstate(over="ignore", invalid="ignore"):  # --allow-unstable: huge errors
        envelope, metrics, per_start = _statistics(measured, predicted, errors)
    marks, est = {}, (0, lo) if lo > 0 else (0, len(ds))
    if yardsticks:
        marks = _yardsticks(ds, k0, horizon, exogenous, econ, est)
    settings = {
        "exogenous": exogenous,
        "starts_requested": starts,
        "starts": int(k0.size),
        "horizon_steps": horizon,
        "horizon_s": horizon * ds.Ts,
        "Ts_s": ds.Ts,
        "placement": placement,
        "non_overlapping": bool(non_overlapping),
        "seed": seed if placement == "random" else None,
        "sample_range": [lo, hi],
        "held_out_fraction": held_out_fraction,
        "admissible_starts": int(admissible.size),
        "params_name": params.name,
        "model": "econ" if econ else "paper",
        "params_provenance": params.provenance,
        "data_source": src,
        "data_samples": len(ds),
        "metrics_over": "all starts, prediction steps i = 0 .. horizon",
    }
    if yardsticks:
        settings["yardsticks_fitted_on"] = list(est)
        settings["yardsticks_in_sample"] = lo == 0
    return ValidationResult(
        start_index=k0, start_time=ds.time[k0].copy(), horizon_s=horizon_s,
        predicted=predicted, measured=measured, errors=errors, inputs=inputs, exogenous=exo,
        envelope=envelope, metrics=metrics, per_start=per_start, settings=settings,
        extra_metrics=extra, yardsticks=marks)


# ------------------------------------------------------------------- helpers
def held_meaning(family: str, exogenous: str) -> str:
    """What the held (or measured) disturbances of a validation mean, in one sentence."""
    if family == "econ":
        held, pred = "v_veh and T_amb", "; T_int and T_shell are predicted from the start"
    else:
        held, pred = "T_int and T_shell", ""
    if exogenous == "hold":
        return (f"{held} are held at their value at each start over its window (the model "
                f"is not told how they evolve); W_bl and T_evap_set are the measured inputs"
                f"{pred}")
    return (f"{held} follow their measurements over each window (a perfect preview of "
            f"them); W_bl and T_evap_set are the measured inputs{pred}")


def window_design_text(d: dict) -> str:
    """``ValidationResult.window_design`` in one line: starts, spacing, horizon, overlap,
    what is held (the CLI and the report print it)."""
    sp = d["start_spacing_s"]
    spacing = ("one start" if sp is None else
               f"starts {sp['median']:g} s apart" if sp["min"] == sp["max"] else
               f"starts {sp['min']:g}..{sp['max']:g} s apart (median {sp['median']:g} s)")
    return (f"window design: {d['starts']} starts, {spacing}, horizon {d['horizon_s']:g} s; "
            f"consecutive windows share {100 * d['overlap_fraction']:.0f} % of their samples, "
            + ("no sample lies in two windows" if d["max_windows_per_sample"] <= 1 else
               f"a sample lies in up to {d['max_windows_per_sample']} windows") +
            f"{' (--non-overlapping)' if d['non_overlapping'] else ''}; "
            f"{d['held_disturbances']}")


#: Inputs the yardsticks are given, per model family (the model's own inputs and
#: disturbances), and the outputs they predict (the validated channels first).
YARDSTICK_SIGNALS = {
    "paper": (("W_bl", "T_evap_set", "T_int", "T_shell"), VALIDATED_CHANNELS),
    "econ": (("W_bl", "T_evap_set", "v_veh", "T_amb"),
             (*VALIDATED_CHANNELS, "T_int", "T_shell")),
}


def _yardsticks(ds: Dataset, k0: np.ndarray, horizon: int, exogenous: str, econ: bool,
                est: tuple[int, int]) -> dict:
    """Persistence, ARX and subspace over the windows, given what the model is given: the
    measured inputs, the disturbances held (or measured) as the model has them, and the
    outputs measured up to each start (for the econ model also T_int and T_shell)."""
    from acid.yardsticks import evaluate

    inputs, outputs = YARDSTICK_SIGNALS["econ" if econ else "paper"]
    unit = {"W_bl": "kg/s", "v_veh": "m/s"}
    u = np.stack([ds.get(n, unit.get(n, "K")) for n in inputs], axis=-1)
    y = np.stack([ds.get(n, "K") for n in outputs], axis=-1)
    held = np.array([exogenous == "hold" and n not in ("W_bl", "T_evap_set") for n in inputs])
    out = evaluate(y, u, ds.experiment, k0, horizon, held, est, input_names=inputs)
    nc = len(VALIDATED_CHANNELS)
    return {name: replace(p, predicted=p.predicted[..., :nc]) for name, p in out.items()}


def _place_non_overlapping(admissible: np.ndarray, starts: int, horizon: int) -> np.ndarray:
    """Up to ``starts`` start indices at least ``horizon + 1`` apart (no shared sample),
    spread evenly over each run of consecutive admissible starts (one run per experiment),
    shared among the runs in proportion to how many windows each holds."""
    cut = np.flatnonzero(np.diff(admissible) != 1) + 1
    runs = [(int(r[0]), int(r[-1])) for r in np.split(admissible, cut) if r.size]
    cap = np.array([(b - a) // (horizon + 1) + 1 for a, b in runs])
    n = min(int(starts), int(cap.sum()))
    share = np.minimum(np.floor(cap * n / cap.sum()).astype(int), cap)
    for i in np.argsort(-(cap * n / cap.sum() - share), kind="stable"):
        if share.sum() >= n:
            break
        if share[i] < cap[i]:
            share[i] += 1
    picks = [np.round(a + np.arange(m) * ((b - a) / (m - 1) if m > 1 else 0)).astype(int)
             for (a, b), m in zip(runs, share, strict=True) if m > 0]
    return np.concatenate(picks).astype(int)


def _is_econ(params) -> bool:
    """Whether ``params`` belong to the econ model family (:mod:`acid.econ`)."""
    return not isinstance(params, ModelParams) and getattr(params, "power_map", None) \
        is not None


def _paper_windows(ds: Dataset, idx: np.ndarray, params: ModelParams, exogenous: str):
    """The paper's declaration (``acid.models.paper``) simulated over the windows ``idx``
    (S, H + 1) from the measured states: (predicted, measured, inputs, exogenous), each
    (S, H + 1, .); the predicted T_ain(i) is eq. 3 of the predicted T_evap(i)."""
    import dataclasses

    from acid.ident.data import ModelData
    from acid.ident.oe import simulate_windows
    from acid.models import load

    decl = load("paper")
    data = ModelData.of(decl, ds, min_samples=2)
    S, L = idx.shape
    d = data.d[idx]                                                   # (S, H + 1, 2)
    if exogenous == "hold":
        d = np.broadcast_to(d[:, :1], d.shape)
    flat = dataclasses.replace(data, x=data.x[idx].reshape(S * L, -1),
                               u=data.u[idx].reshape(S * L, -1), d=d.reshape(S * L, -1),
                               y=data.y[idx].reshape(S * L, -1), censored=None)
    Y = simulate_windows(decl, flat, np.arange(S * L).reshape(S, L), data.x[idx[:, 0]],
                         np.tile(params.theta, (S, 1)))
    names = (*decl.state_names, *decl.output_names)
    pick = [names.index(c) for c in VALIDATED_CHANNELS]
    measured = np.stack([ds.get(c, "K")[idx] for c in VALIDATED_CHANNELS], axis=-1)
    return Y[..., pick], measured, data.u[idx], d


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
