"""Multi-start open-loop validation of any declared model: ``validate_model(model, ds, ...)``.

From each start instant k the model predicts ``horizon`` samples open loop with the measured
inputs and disturbances. The state at k: measured states as measured; latent ones
estimated from the ``warmup`` seconds before k (the whole state at k - warmup fitted to the
measured channels of that stretch with the parameters held, then simulated to k), or their
declared ``initial`` rule when ``warmup`` is 0. Errors are reported per measured channel,
overall and at chosen horizons (RMSE, p90 of |e|), with ``acid.metrics``.

This is acid's one validator: the paper's Figs. 5-6 (60 starts x 300 steps, T_int and
T_shell held), the econ model beside it, and any declared model. Every statistic is a
k-step prediction error, k = 1 .. horizon (the start sample, where measured states are
exact by construction, is not scored). ``validate(ds, params)`` takes ``ModelParams``,
``EconParams`` (any ``acid.models.values.ParameterValues``) or a fit and finds the
declaration from them.
"""

from __future__ import annotations

import dataclasses
import math
import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.optimize

from acid._blas import fixed_blas
from acid.data import Dataset
from acid.errors import ConfigError, DataError
from acid.ident.data import ModelData
from acid.ident.oe import simulate_windows
from acid.ident.validation import DeclaredValidation
from acid.ident.yardsticks import estimation_ranges
from acid.metrics import fit_percent, max_abs_error, rmse
from acid.models.declaration import Model
from acid.models.loader import BUILT_IN, load
from acid.models.values import ParameterValues

PLACEMENTS = ("even", "random")
#: What the disturbances do over a prediction: held at the start value, or measured.
EXOGENOUS_MODES = ("hold", "measured")
#: Most prediction samples (starts x (horizon + 1)) one study may hold (about 1 GB).
MAX_PREDICTION_SAMPLES = 5_000_000
#: How latent states at a start are estimated from the warm-up stretch: ``"fit"`` (the
#: state at its beginning fitted by least squares, then simulated) or ``"ekf"`` (the
#: extended Kalman filter of ``acid.ident.pem`` run along it, with the declared noises) or
#: ``"ekf-trip"`` (the filter run from the start of the experiment, as in a car it runs
#: from the start of the trip; the starts still need ``warmup`` samples before them).
WARM_STARTS = ("fit", "ekf", "ekf-trip")
#: Prediction times (s) of ``by_time`` (the model's and each yardstick's errors).
REPORT_TIMES_S = (60.0, 300.0, 600.0, 1500.0)
#: ``warmup``'s default, s (as ``acid validate --warmup``: 60 samples of the paper's 5 s),
#: or ``DEFAULT_WARMUP_SAMPLES`` samples where it does not fit the data (``default_warmup``).
DEFAULT_WARMUP_S = 300.0
DEFAULT_WARMUP_SAMPLES = 60
#: Below this standard deviation a measured window counts as constant: fit % undefined.
CONSTANT_TRUTH_STD = 1e-9


def fitted_parameters(result) -> ParameterValues:
    """The values of a ``DeclaredFitResult`` (per-experiment ones by experiment id), bound
    to the fit's model (a built-in by name, else its file)."""
    per = {n: dict(zip(result.experiment_ids, map(float, v), strict=True))
           for n, v in result.per_experiment.items()}
    builtin = result.model in BUILT_IN and Path(result.model_source).stem == result.model
    ref = result.model if builtin else result.model_source
    return ParameterValues(np.asarray(result.values, dtype=float), per_experiment=per,
                           model=ref if result.declaration is None else result.declaration,
                           source=f"fit of {result.data_source}")


def as_values(params) -> ParameterValues:
    """``ModelParams``, ``EconParams`` or any ``ParameterValues`` as is; a
    ``DeclaredFitResult`` as its ``fitted_parameters``."""
    if isinstance(params, ParameterValues):
        return params
    if hasattr(params, "experiment_ids"):
        return fitted_parameters(params)
    raise DataError(f"expected model parameters (ParameterValues such as ModelParams or "
                    f"EconParams, or a fit), got {type(params).__name__}")


def declared_parameters(model: Model) -> ParameterValues:
    return ParameterValues(model=model, source="declared values")


def read_parameters(model: Model | None, path: str | Path) -> ParameterValues:
    """The parameter file ``path`` of ``model`` (None: the one it names; the one reader: the
    format ``acid fit`` writes and the layouts before it; one-line ``DataError`` when it is
    not one or names parameters the model lacks)."""
    return ParameterValues.from_json(path, model=model).replace(source=str(path))


def window_design_text(d: dict) -> str:
    """``DeclaredValidation.window_design`` in one line (the CLI and the report print it)."""
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


def validate(ds: Dataset, params, *, held_out_fraction: float | None = None,
             exogenous: str = "hold", **kw) -> DeclaredValidation:
    """``validate_model`` for parameters that name their model (``as_values``): on the
    last ``held_out_fraction`` of ``ds`` (the yardsticks fitted on the part before it),
    every disturbance held at each start (``exogenous="hold"``, the paper's protocol for
    T_int and T_shell) or measured (``"measured"``)."""
    if exogenous not in EXOGENOUS_MODES:
        raise ConfigError(f"--exogenous must be one of {', '.join(EXOGENOUS_MODES)}, got "
                          f"{exogenous!r}")
    ps = as_values(params)
    model = ps.declaration
    lo = held_out_start(len(ds), held_out_fraction)
    kw.setdefault("estimation", (0, lo) if lo > 0 else None)
    kw.setdefault("start_range", (lo, len(ds)))
    return validate_model(model, ds, ps,
                          hold=tuple(d.name for d in model.disturbances)
                          if exogenous == "hold" else (), **kw)


def held_out_start(n: int, fraction: float | None) -> int:
    """The first sample of the last ``fraction`` of ``n`` (0 for the whole record)."""
    if fraction is None:
        return 0
    f = float(fraction)
    if not (math.isfinite(f) and 0.0 < f <= 1.0):
        raise ConfigError(f"--held-out-fraction must be in (0, 1], got {fraction}")
    return int(round(n * (1.0 - f)))


def samples_of(value_s: float, Ts: float, name: str, used: bool = True) -> int:
    """A time ``value_s`` (s) as whole samples of ``Ts`` (s); a one-line ``ConfigError``
    naming ``name`` when it is not a whole number of samples (the CLI rounds up and says
    so; the API takes exactly what it is given) and ``used`` (a warm-up of a model without
    latent states is not used: any duration >= 0 passes, rounded up)."""
    v = float(value_s)
    if not math.isfinite(v) or v < 0:
        raise ConfigError(f"{name} must be a duration >= 0 s, got {value_s!r}")
    n = int(round(v / Ts))
    if not used:
        return math.ceil(v / Ts - 1e-9)
    if not math.isclose(n * Ts, v, rel_tol=1e-9, abs_tol=1e-9 * Ts):
        lo = math.floor(v / Ts)
        raise ConfigError(f"{name} {v:g} s is not a whole number of samples of {Ts:g} s "
                          f"(e.g. {lo * Ts:g} s or {(lo + 1) * Ts:g} s)")
    return n


def default_warmup(ds: Dataset, horizon: int) -> tuple[float, str | None]:
    """The default warm-up (s) for ``ds`` and ``horizon`` steps, and a note when it is not
    ``DEFAULT_WARMUP_S``: 300 s where that is a whole number of samples of ``ds.Ts`` and some
    experiment holds 300 s + ``horizon`` steps; otherwise ``DEFAULT_WARMUP_SAMPLES`` samples
    (a record at another time scale: a 600 Hz oscillator, a 1 kHz drive)."""
    n = DEFAULT_WARMUP_S / ds.Ts
    whole = math.isclose(round(n) * ds.Ts, DEFAULT_WARMUP_S, rel_tol=1e-9)
    longest = max(int(np.sum(ds.experiment == e)) for e in np.unique(ds.experiment)) \
        if len(ds) else 0
    if whole and longest > round(n) + int(horizon):
        return DEFAULT_WARMUP_S, None
    why = (f"{DEFAULT_WARMUP_S:g} s is not a whole number of samples of {ds.Ts:g} s"
           if not whole else f"no experiment holds {DEFAULT_WARMUP_S:g} s + {int(horizon)} "
           "steps")
    s = DEFAULT_WARMUP_SAMPLES * ds.Ts
    return s, (f"warm-up: {DEFAULT_WARMUP_SAMPLES} samples ({s:g} s), the default where {why} "
               "(set it with --warmup / warmup=)")


@fixed_blas
def validate_model(model: Model | str, ds: Dataset, params: ParameterValues | None = None, *,
                   starts: int = 60, horizon: int = 300, warmup: float | None = None,
                   placement: str = "even", seed: int = 0,
                   horizons: tuple[int, ...] | None = None,
                   hold: tuple[str, ...] | None = None,
                   start_index=None, non_overlapping: bool = False,
                   start_range=None, yardsticks: bool = True,
                   estimation=None,
                   to_end: bool = False, warm_start: str = "fit",
                   progress: Callable[[int, int, str], None] | None = None
                   ) -> DeclaredValidation:
    """Predict ``horizon`` samples open loop from ``starts`` instants (module docstring).

    Units as ``acid validate``'s options: ``horizon`` (and ``horizons``, ``start_index``,
    ``start_range``, ``estimation`` ranges) in samples of the data, ``warmup`` in seconds
    (default ``default_warmup``: 300 s, or 60 samples where 300 s does not fit the data; for
    a model with latent states a whole number of samples of the data's Ts, else a one-line
    ``ConfigError``; unused without latent states).

    ``params``: a fit (``DeclaredFitResult``), any ``ParameterValues`` or None (the declared
    values).

    The defaults are ``acid validate``'s: every disturbance held, the yardsticks on.

    ``hold``: disturbances held at their value at the start (the paper's protocol for T_int
    and T_shell) instead of measured along the prediction; None (the default, as ``acid
    validate --exogenous hold``) holds every disturbance, ``()`` measures them all
    (``--exogenous measured``). ``start_index``: these start samples instead of ``starts``
    placed by ``placement`` (e.g. another study's windows).
    ``non_overlapping``: starts at least ``horizon + 1`` samples apart.
    ``start_range`` (lo, hi): every window inside samples lo .. hi - 1 (e.g. the held-out
    part), or a list of such ranges (the second half of each record). ``yardsticks``
    (default True, as the CLI): persistence, ARX and subspace (``acid.ident.yardsticks``) on
    the same windows, given the same inputs and held disturbances, fitted on
    ``estimation``. ``estimation``: the samples the parameters were fitted on, as (lo, hi),
    a list of (lo, hi) ranges of ``ds`` (the first half of each record), or the estimation
    ``Dataset`` itself (what was given to ``fit_model``): the yardsticks are fitted on
    exactly those samples. With a ``Dataset``, its samples are found in ``ds`` by position
    (``estimation_samples``: each of its experiments placed as one contiguous stretch of a
    record, not sample values that merely recur) and every window that would score one of
    them (in-sample) is left out, with a note; with ranges, the windows that overlap them
    are marked (``settings["in_sample_starts"]``, a note). Default: the whole record,
    in-sample, with a note. ``to_end``: a start may lie less than
    ``horizon`` samples before its experiment's end (at least ``horizon // 25`` steps, 60 s
    of 300 x 5 s); its prediction stops there, and the errors per prediction time count only
    the starts that reach it (short trips). Censored samples (a ``<channel>_censored`` mask)
    are neither scored nor used by the warm-up. ``warm_start``: one of ``WARM_STARTS``.
    ``progress``: ``progress(done, total, label)`` after each step (starts placed, latent
    states estimated, windows simulated, errors scored, yardsticks), ``label`` saying what
    finished; it reads nothing back, so every number is the same with or without it.
    """
    model = load(model)
    if hold is None:
        hold = tuple(d.name for d in model.disturbances)
    unknown = [h for h in hold if h not in [d.name for d in model.disturbances]]
    if unknown:
        raise ConfigError(f"hold: {unknown[0]!r} is not a disturbance of model "
                          f"{model.name!r}")
    params = declared_parameters(model) if params is None else as_values(params)
    if warm_start not in WARM_STARTS:
        raise ConfigError(f"warm_start must be one of {', '.join(WARM_STARTS)}, got "
                          f"{warm_start!r}")
    if placement not in PLACEMENTS:
        raise ConfigError(f"placement must be one of {', '.join(PLACEMENTS)}, got "
                          f"{placement!r}")
    if non_overlapping and placement != "even":
        raise ConfigError(f"--non-overlapping places the starts evenly: it cannot be "
                          f"combined with --placement {placement}")
    for name, v, lo in (("starts", starts, 1), ("horizon", horizon, 1)):
        if int(v) < lo:
            raise ConfigError(f"{name} must be at least {lo}, got {v}")
    data = ModelData.of(model, ds, min_samples=2)
    latent = [i for i, s in enumerate(model.states) if not s.measured]
    warmup_note = None
    if warmup is None:
        warmup, warmup_note = default_warmup(ds, horizon)
    warmup = samples_of(warmup, ds.Ts, "warmup", used=bool(latent))
    need_warm = warmup if latent else 0
    step = _Steps(progress, 3 + bool(latent and need_warm > 0) + bool(yardsticks))
    ranges = [(0, len(data))] if start_range is None else \
        estimation_ranges(start_range, len(data))
    lo_r, hi_r = ranges[0][0], ranges[-1][1]
    reach = max(1, horizon // 25) if to_end else horizon
    cand = np.concatenate([np.arange(max(a, lo) + need_warm, min(b, hi) - reach)
                           for a, b in data.segments for lo, hi in ranges]
                          + [np.zeros(0, int)]).astype(int)
    est_data, notes_pre = None, [warmup_note] if warmup_note and latent else []
    if isinstance(estimation, Dataset):
        est_data = ModelData.of(model, estimation, min_samples=2)
        fitted, placed = estimation_samples(data, est_data, ds.time, estimation.time)
        notes_pre += placed
        if fitted.any() and start_index is None:
            # a window scoring a sample the parameters were fitted on is in-sample: left out
            ends = np.array([b for _, b in data.segments])
            stop = np.minimum(cand + horizon, ends[np.searchsorted(ends, cand, side="right")]
                              - 1)
            seen = np.concatenate([[0], np.cumsum(fitted)])
            keep = seen[stop + 1] - seen[cand] == 0     # the start's own sample too
            if not keep.all():
                notes_pre.append(f"{int(fitted.sum())} of {len(data)} samples are the estimation "
                                 f"data's (placed by position): {int((~keep).sum())} of "
                                 f"{cand.size} candidate starts whose windows score them were "
                                 "left out (in-sample)")
            cand = cand[keep]
    elif estimation is not None:
        estimation = estimation_ranges(estimation, len(data))
    if cand.size == 0:
        raise DataError(f"{ds.source}: record too short: no experiment is longer than "
                        f"warmup + horizon "
                        f"({need_warm} + {reach} + 1 samples of {ds.Ts:g} s; shorten the "
                        "warm-up or the horizon)")
    if start_index is not None:
        k0 = np.asarray(start_index, dtype=int)
        bad = k0[~np.isin(k0, cand)]
        if bad.size:
            raise DataError(f"{ds.source}: start {int(bad[0])} leaves no room for the "
                            f"warm-up and {horizon} steps inside its experiment")
    elif non_overlapping:
        k0 = _place_non_overlapping(cand, starts, horizon)
    elif placement == "even":
        pick = np.unique(np.round(np.linspace(0, cand.size - 1, min(starts, cand.size))))
        k0 = cand[pick.astype(int)]
    else:
        k0 = np.sort(np.random.default_rng(seed).choice(cand, min(starts, cand.size),
                                                        replace=False))
    if start_index is None and k0.size < starts:  # stacklevel 3: the caller, past fixed_blas
        warnings.warn(f"{ds.source}: only {k0.size} "
                      + (f"windows of {horizon} steps ({horizon * model.Ts:g} s) fit without "
                         "overlap (--non-overlapping)" if non_overlapping else
                         f"distinct start instants fit a {horizon}-step window")
                      + f"; using {k0.size} instead of {starts}", UserWarning, stacklevel=3)
    if k0.size * (horizon + 1) > MAX_PREDICTION_SAMPLES:
        raise ConfigError(f"--starts {k0.size} x --horizon {horizon} steps is "
                          f"{k0.size * (horizon + 1):.3g} prediction samples, more than "
                          f"{MAX_PREDICTION_SAMPLES:.0e}: lower --starts or --horizon")
    in_sample = _windows_over(data, k0, horizon, estimation) \
        if estimation is not None and est_data is None else np.zeros(k0.size, dtype=bool)
    if in_sample.any():
        notes_pre.append(f"{int(in_sample.sum())} of {k0.size} windows score samples of the "
                         "estimation ranges: in-sample (settings in_sample_starts)")
    step(f"{k0.size} starts placed")
    gaps = np.diff(np.sort(k0))
    notes = [*notes_pre, f"window design: {k0.size} starts, spacing "
             + (f"{np.median(gaps) * model.Ts:g} s (median, min {gaps.min() * model.Ts:g} s)"
                if gaps.size else "one start")
             + f", horizon {horizon * model.Ts:g} s, "
             + ("overlapping" if gaps.size and gaps.min() <= horizon else "no overlap")]
    P = parameters_at(model, data, params, k0, notes)
    x0 = data.initial_states(model, k0)
    if latent and need_warm > 0:
        if warm_start in ("ekf", "ekf-trip"):
            from acid.ident.pem import filter_states

            first = np.array([a for a, _ in data.segments])
            W = k0 - first[np.searchsorted(first, k0, side="right") - 1] \
                if warm_start == "ekf-trip" else need_warm
            x0[:, latent] = filter_states(model, data, P, k0, W)[:, latent]
        else:
            x0 = warm_start_states(model, data, P, k0, need_warm, x0, latent)
        notes.append(f"latent states ({', '.join(model.states[i].name for i in latent)}) "
                     + ("estimated by the extended Kalman filter run from the start of "
                        "each experiment" if warm_start == "ekf-trip" else
                        f"estimated from the {need_warm} samples ({need_warm * model.Ts:g} s) "
                        "before each start" + (" by the extended Kalman filter"
                                               if warm_start == "ekf" else "")))
        step("latent states estimated (" + {"fit": "least squares over the warm-up",
                                            "ekf": "Kalman filter over the warm-up",
                                            "ekf-trip": "Kalman filter from each trip's "
                                                        "start"}[warm_start] + ")")
    elif latent:
        notes.append("latent states started from their declared initial rule")
    idx = k0[:, None] + np.arange(horizon + 1)[None, :]
    ends = np.array([b for _, b in data.segments])
    last = ends[np.searchsorted(ends, k0, side="right")] - 1
    inside = idx <= last[:, None]
    idx = np.minimum(idx, last[:, None])
    if not inside.all():
        notes.append(f"predictions stop at the end of their experiment: "
                     f"{int((~inside[:, -1]).sum())} of {k0.size} starts lie less than "
                     f"{horizon} steps before it (at least {reach} steps each)")
    if data.censored is not None:
        notes.append("censored samples (a clipping sensor, or a sample the import flagged or "
                     "filled) are not scored")
    data0 = data
    if hold:
        held = [i for i, d in enumerate(model.disturbances) if d.name in hold]
        dd = np.repeat(data.d[k0][:, None, :], horizon + 1, axis=1)   # (S, H + 1, nd)
        # windows get their own rows: the held values differ per start
        flat = np.arange(idx.size).reshape(idx.shape)
        data = dataclasses.replace(
            data, x=data.x[idx].reshape(idx.size, model.nx),
            u=data.u[idx].reshape(idx.size, model.nu),
            d=np.where(np.isin(np.arange(model.nd), held), dd,
                       data.d[idx]).reshape(idx.size, model.nd),
            y=data.y[idx].reshape(idx.size, model.ny),
            censored=None if data.censored is None
            else data.censored[idx].reshape(idx.size, -1))
        idx = flat
        notes.append(f"held at their start values: {', '.join(hold)}")
    with np.errstate(over="ignore", invalid="ignore"):
        Y = simulate_windows(model, data, idx, x0, P)
    step(f"{k0.size} windows of {horizon} steps simulated")
    if not np.all(np.isfinite(Y[inside])):
        raise DataError(f"{ds.source}: the predictions with parameters from {params.label} "
                        "diverge (values beyond the range of floating point): the model is "
                        "unstable")
    meas = np.where(inside[..., None], data.observed()[idx], np.nan)
    channels, units, errors, metrics, energy = [], [], {}, {}, {}
    rows = [(c, n) for c, n in data.measured_channels(model)]
    unit_of = {r.name: r.unit for r in model.states + model.outputs}
    for c, name in rows:
        e = (Y[:, 1:, c] - meas[:, 1:, c])
        errors[name] = e
        channels.append(name)
        units.append(unit_of[name])
        metrics[name] = _channel_metrics(meas[:, 1:, c], Y[:, 1:, c])
        if unit_of[name] == "W" and name in model.output_names:
            energy[name] = _energy_errors(meas[:, 1:, c], Y[:, 1:, c])
    steps = sorted({h for h in (horizons or _default_horizons(horizon)) if 1 <= h <= horizon})
    by_h = []
    for h in steps:
        row = {"step": h, "time_s": h * model.Ts}
        for name in channels:
            e = errors[name][:, h - 1]
            e = e[np.isfinite(e)]
            row[name] = {"rmse": float(np.sqrt(np.mean(e ** 2))) if e.size else math.nan,
                         "p90_abs": float(np.percentile(np.abs(e), 90)) if e.size
                         else math.nan, "n": int(e.size)}
        by_h.append(row)
    step("errors scored")
    ys = {}
    if yardsticks:
        ys = _yardsticks(model, data0, rows, k0, horizon, hold, steps,
                         None if est_data is not None else estimation or [(0, len(data0))],
                         inside, est_data)
        step(f"yardsticks predicted ({', '.join(ys) or 'none'})")
        if estimation is None:
            notes.append("yardsticks fitted on the whole record (in-sample: favoured)")
        elif est_data is not None:
            notes.append(f"yardsticks fitted on the estimation data ({len(est_data)} "
                         "samples, not scored)")
    settings = {"params": params.label, "model": model.name,
                "params_provenance": params.provenance, "hold": tuple(hold),
                "sample_range": [int(lo_r), int(hi_r)], "placement": placement,
                "seed": seed if placement == "random" else None,
                "non_overlapping": bool(non_overlapping), "starts_requested": int(starts),
                "in_sample_starts": [int(k) for k in k0[in_sample]],
                "data_source": ds.source, "data_samples": len(ds),
                "yardsticks_fitted_on": _fitted_on(estimation, est_data, len(data0))
                if yardsticks else None}
    pick = [c for c, _ in rows]
    return DeclaredValidation(model=model.name, channels=tuple(channels), units=tuple(units),
                              starts=k0, horizon=int(horizon), warmup=int(need_warm),
                              Ts=model.Ts, errors=errors, metrics=metrics,
                              by_horizon=tuple(by_h), notes=tuple(notes), yardsticks=ys,
                              by_time=by_time(errors, model.Ts), predicted=Y[..., pick],
                              measured=meas[..., pick], start_time=ds.time[k0].copy(),
                              energy=energy, settings=settings, inputs=data.u[idx],
                              input_names=tuple(r.name for r in model.inputs),
                              input_units=tuple(r.unit for r in model.inputs))


class _Steps:
    """``progress(done, total, label)`` once per finished step of a validation (a no-op
    without a callback)."""

    def __init__(self, progress: Callable[[int, int, str], None] | None, total: int):
        self.progress, self.total, self.done = progress, total, 0

    def __call__(self, label: str) -> None:
        self.done += 1
        if self.progress is not None:
            self.progress(self.done, self.total, label)


def _channel_metrics(m: np.ndarray, p: np.ndarray) -> dict:
    """Pooled |error| statistics of (starts, steps) measured ``m`` and predicted ``p`` (NaN
    where not scored); ``fit_percent`` the median over starts of each window's fit (NaN
    for a window whose truth is constant), ``fit_percent_pooled`` one fit over all."""
    ok = np.isfinite(m) & np.isfinite(p)
    a, b = m[ok], p[ok]
    fits = [float(fit_percent(m[s][ok[s]], p[s][ok[s]])) for s in range(m.shape[0])
            if ok[s].sum() > 1 and np.std(m[s][ok[s]]) > CONSTANT_TRUTH_STD]
    e = np.abs(b - a)
    q50, q90, q95 = np.percentile(e, [50.0, 90.0, 95.0]) if e.size else (math.nan,) * 3
    with np.errstate(divide="ignore", invalid="ignore"):
        return {"rmse": float(rmse(a, b)), "mean_abs": float(e.mean()) if e.size else math.nan,
                "median_abs": float(q50), "p90_abs": float(q90), "p95_abs": float(q95),
                "max_abs": float(max_abs_error(a, b)) if e.size else math.nan,
                "fit_percent": float(np.median(fits)) if fits else math.nan,
                "fit_percent_pooled": float(fit_percent(a, b))
                if e.size and np.std(a) > CONSTANT_TRUTH_STD else math.nan}


def _energy_errors(m: np.ndarray, p: np.ndarray) -> dict:
    """|error| of each window's energy (a power channel, W, summed over the scored steps),
    % of the measured energy (at least 1 W per step), and the pooled bias, %."""
    ok = np.isfinite(m) & np.isfinite(p)
    E_m, E_p = np.where(ok, m, 0.0).sum(axis=1), np.where(ok, p, 0.0).sum(axis=1)
    rel = 100.0 * np.abs(E_p - E_m) / np.maximum(E_m, ok.sum(axis=1))
    return {"unit": "% per window", "rmse": float(np.sqrt(np.mean(rel ** 2))),
            "median_abs": float(np.median(rel)), "p90_abs": float(np.percentile(rel, 90)),
            "max_abs": float(rel.max()),
            "bias_pct": float(100.0 * (E_p.sum() - E_m.sum()) / E_m.sum())}


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


def by_time(errors: dict, Ts: float, times_s=REPORT_TIMES_S) -> dict:
    """{channel: {"<t>": {"rmse_K", "p90_K", "n"}}} at each prediction time ``t`` (s)
    inside the horizon, over the starts whose prediction reaches it (finite errors)."""
    out = {}
    for name, e in errors.items():
        out[name] = {}
        for t in times_s:
            h = int(round(t / Ts))
            v = e[:, h - 1] if 1 <= h <= e.shape[1] else np.zeros(0)
            v = v[np.isfinite(v)]
            if v.size:
                out[name][f"{h * Ts:g}"] = {"rmse_K": float(np.sqrt(np.mean(v ** 2))),
                                            "p90_K": float(np.percentile(np.abs(v), 90)),
                                            "n": int(v.size)}
    return out


#: Most placements of one estimation experiment compared sample by sample (beyond: the
#: placements whose first, middle and last samples agree all count, conservatively).
MAX_PLACEMENTS = 64


def estimation_samples(data: ModelData, est: ModelData, time: np.ndarray | None = None,
                       est_time: np.ndarray | None = None) -> tuple[np.ndarray, list[str]]:
    """(N,) bool, True on the samples of ``data`` the estimation data ``est`` holds, by
    position, and notes on what could not be placed.

    Each experiment of ``est`` (a stretch of one record: ``Dataset.split``, ``window``, or
    one part of a ``concatenate``) is placed as one contiguous block inside one experiment
    of ``data``, where all its samples (states, inputs, disturbances, outputs, in order)
    are the block's; only the samples of that block are marked. A value that merely recurs
    (a sensor holding a value across the split, a repeated sample) is not marked. When
    the block fits several places (a stretch repeated exactly), the one at the same time
    stamps is taken, else all of them (said in a note); an experiment found nowhere (a
    resampled or filtered copy) is said in a note and marks nothing."""
    def rows(d):
        return np.ascontiguousarray(np.concatenate([d.x, d.u, d.d, d.y], axis=1))

    A, B = rows(data), rows(est)
    first: dict[bytes, list[int]] = {}
    for i, r in enumerate(A):
        first.setdefault(r.tobytes(), []).append(i)
    end_of = np.empty(len(A), dtype=int)
    for a, b in data.segments:
        end_of[a:b] = b
    mark = np.zeros(len(A), dtype=bool)
    lost, several = [], []
    for e, (a, b) in enumerate(est.segments):
        L = b - a
        cand = np.array([o for o in first.get(B[a].tobytes(), []) if o + L <= end_of[o]],
                        dtype=int)
        for k in (L // 2, L - 1):                  # cheap checks before the whole block
            if cand.size:
                cand = cand[_same_rows(A[cand + k], B[a + k])]
        if cand.size <= MAX_PLACEMENTS:
            cand = cand[[np.array_equal(A[o:o + L], B[a:b], equal_nan=True) for o in cand]]
        if cand.size > 1 and time is not None and est_time is not None:
            same = cand[np.isclose(time[cand], est_time[a], rtol=0.0, atol=1e-6 * data.Ts)]
            cand = same if same.size == 1 else cand
        if not cand.size:
            lost.append(f"{e} ({L} samples)")
        elif cand.size > 1:
            several.append(f"{e} ({cand.size} places)")
        for o in cand:
            mark[o:o + L] = True
    notes = []
    if lost:
        notes.append("estimation experiment(s) " + ", ".join(lost) + " are not a stretch of "
                     "this record (resampled, filtered or another record?): their samples "
                     "could not be placed, windows over them are not marked in-sample")
    if several:
        notes.append("estimation experiment(s) " + ", ".join(several) + " repeat exactly in "
                     "this record: every place they fit is counted as in-sample")
    return mark, notes


def _windows_over(data: ModelData, k0: np.ndarray, horizon: int, ranges) -> np.ndarray:
    """(S,) bool: the window of each start ``k0`` (its start to ``horizon`` steps on, within
    its experiment) holds a sample of the (lo, hi) ``ranges``."""
    mark = np.zeros(len(data) + 1, dtype=int)
    for lo, hi in ranges:
        mark[lo:hi] = 1
    seen = np.concatenate([[0], np.cumsum(mark[:-1])])
    ends = np.array([b for _, b in data.segments])
    stop = np.minimum(k0 + horizon, ends[np.searchsorted(ends, k0, side="right")] - 1)
    return seen[stop + 1] - seen[k0] > 0


def _same_rows(rows: np.ndarray, row: np.ndarray) -> np.ndarray:
    """(n,) bool: each of ``rows`` (n, c) equals ``row`` (c,), NaN equal to NaN."""
    return np.all((rows == row) | (np.isnan(rows) & np.isnan(row)), axis=1)


def _fitted_on(estimation, est_data, n: int):
    """What the yardsticks were fitted on, for the settings: [lo, hi], a list of them, or
    {"estimation_data": samples}."""
    if est_data is not None:
        return {"estimation_data_samples": len(est_data)}
    ranges = estimation or [(0, n)]
    return [int(v) for v in ranges[0]] if len(ranges) == 1 else \
        [[int(lo), int(hi)] for lo, hi in ranges]


def _yardsticks(model: Model, data: ModelData, rows, k0, horizon: int, hold, steps,
                estimation, inside, est_data: ModelData | None = None) -> dict:
    """Persistence, ARX and subspace (``acid.ident.yardsticks``) on the model's windows: the same
    inputs and disturbances (held as the model has them), predicting the measured channels
    that are recorded throughout; RMSE and p90 |e| overall and at ``steps``."""
    from acid.ident.yardsticks import evaluate

    meas = np.concatenate([data.x, data.y], axis=1)
    use = [(c, n) for c, n in rows if np.all(np.isfinite(meas[:, c]))]
    if not use:
        return {}
    y = meas[:, [c for c, _ in use]]
    obs = data.observed()[:, [c for c, _ in use]]
    u = np.concatenate([data.u, data.d], axis=1)
    names = tuple(r.name for r in model.inputs + model.disturbances)
    held = np.array([n in hold for n in names], dtype=bool)
    out = {}
    # windows that stop at their experiment's end (to_end) read past the record's last
    # sample: it is repeated there, and those steps are not scored
    pad = np.arange(len(data) + horizon + 1).clip(max=len(data) - 1)
    y, u, exp, k = y[pad], u[pad], data.experiment[pad], k0
    if est_data is not None:
        # the estimation data placed before the validated record, as experiments of its own
        est_y = np.concatenate([est_data.x, est_data.y], axis=1)[:, [c for c, _ in use]]
        if not np.all(np.isfinite(est_y)):
            return {}
        y = np.concatenate([est_y, y])
        u = np.concatenate([np.concatenate([est_data.u, est_data.d], axis=1), u])
        exp = np.concatenate([est_data.experiment, exp + est_data.experiment.max() + 1])
        k, estimation = k0 + len(est_data), [(0, len(est_data))]
    for name, pred in evaluate(y, u, exp, k, horizon, held, estimation,
                               input_names=names).items():
        idx = np.minimum(k0[:, None] + np.arange(1, horizon + 1)[None, :], len(data) - 1)
        e = np.where(inside[:, 1:, None], pred.predicted[:, 1:, :] - obs[idx], np.nan)
        out[name] = {
            "description": pred.description,
            "channels": {n: {"rmse": _nan_rms(e[..., j]), "p90_abs": _nan_p90(e[..., j])}
                         for j, (_, n) in enumerate(use)},
            "by_horizon": [{"step": h, **{n: {"rmse": _nan_rms(e[:, h - 1, j]),
                                              "p90_abs": _nan_p90(e[:, h - 1, j])}
                                          for j, (_, n) in enumerate(use)}} for h in steps],
            "by_time": by_time({n: e[..., j] for j, (_, n) in enumerate(use)}, model.Ts),
            "rmse_by_step": {n: _rms_by_step(e[..., j]) for j, (_, n) in enumerate(use)},
            # (starts, horizon) errors on the model's windows (paired comparisons)
            "errors": {n: e[..., j] for j, (_, n) in enumerate(use)}}
    return out


def _rms_by_step(e: np.ndarray) -> np.ndarray:
    """(H,) RMS over the starts at each step, NaN where no start reaches it (to_end)."""
    n = np.isfinite(e).sum(axis=0)
    return np.where(n > 0, np.sqrt(np.nansum(e ** 2, axis=0) / np.maximum(n, 1)), np.nan)


def _nan_rms(e: np.ndarray) -> float:
    e = e[np.isfinite(e)]
    return float(np.sqrt(np.mean(e ** 2))) if e.size else math.nan


def _nan_p90(e: np.ndarray) -> float:
    e = e[np.isfinite(e)]
    return float(np.percentile(np.abs(e), 90)) if e.size else math.nan


def _default_horizons(H: int) -> tuple[int, ...]:
    return tuple(sorted({1, max(H // 10, 1), max(H // 4, 1), max(H // 2, 1), H}))


def parameters_at(model: Model, data: ModelData, params: ParameterValues, k0, notes) -> np.ndarray:
    if tuple(params.values) != tuple(model.parameter_names):
        raise ConfigError(f"{params.label}: parameters of another model than {model.name!r}")
    P = np.tile(params.theta, (k0.size, 1))
    for i, p in enumerate(model.parameters):
        if not p.per_experiment:
            continue
        table = params.per_experiment.get(p.name, {})
        ids = np.array(data.experiment_ids)[data.experiment[k0]]
        known = np.array([int(e) in table for e in ids])
        P[known, i] = [table[int(e)] for e in ids[known]]
        if not known.all():
            notes.append(f"{p.name}: no fitted value for experiment(s) "
                         f"{sorted(set(ids[~known].tolist()))}; the table value "
                         f"{params.values[p.name]:.6g} {p.unit} is used")
    return P


def warm_start_states(model: Model, data: ModelData, P, k0, W: int, x_k, latent) -> np.ndarray:
    """The state at each start: fit the state at k - W to the measured channels over the
    W samples before k (parameters held), simulate to k; measured states as measured.

    Each channel's residuals are divided by its standard deviation over every warm-up
    stretch (one weight per channel for all starts); with these weights held, start s's
    residuals depend on its own state only, so the joint least-squares problem is
    separable: each start is solved as its own small problem (``_fit_initial_states``),
    at a cost linear in the number of starts and with the joint solve's estimate.
    """
    idx = (k0 - W)[:, None] + np.arange(W + 1)[None, :]
    chan = [c for c, _ in data.measured_channels(model)]
    meas = data.observed()[idx][:, :W][..., chan]
    obs = np.isfinite(meas)
    scale = np.array([max(float(np.std(meas[..., i][obs[..., i]])), 1e-6)
                      for i in range(len(chan))])
    z = _fit_initial_states(model, data, P, idx[:, :W], meas, chan, scale,
                            data.initial_states(model, k0 - W))
    X = simulate_windows(model, data, idx, z, P)[:, -1, :model.nx]
    out = x_k.copy()
    out[:, latent] = X[:, latent]
    return out


def _fit_initial_states(model: Model, data: ModelData, P, idx, meas, chan, scale,
                        x_first) -> np.ndarray:
    """The initial state (nw, nx) of each window ``idx`` (nw, W) that minimises its
    ``chan`` channels' squared errors against ``meas`` (nw, W, C; NaN unobserved), each
    divided by ``scale`` (C,), from ``x_first`` (nw, nx), parameters ``P`` held.

    One trust-region reflective least-squares problem per window with its exact (W C, nx)
    CasADi Jacobian: the windows share nothing, so their estimates are those of the one
    joint problem (whose Jacobian is block diagonal), at a cost linear in their number; a
    window's estimate does not depend on the other windows.
    """
    obs = np.isfinite(meas)
    meas = np.nan_to_num(meas)
    out = np.empty_like(x_first, dtype=float)
    for s in range(idx.shape[0]):
        out[s] = _fit_window(model, data, idx[[s]], P[[s]], meas[s], obs[s], chan, scale,
                             x_first[s])
    return out


def _fit_window(model: Model, data: ModelData, win, Ps, target, ok, chan, scale,
                x0) -> np.ndarray:
    """One window's initial state (nx,): :func:`_fit_initial_states` for ``win`` (1, W)."""

    def resid(z):
        Y = simulate_windows(model, data, win, z[None], Ps)[0][:, chan]
        return ((Y - target) / scale)[ok]

    def jac(z):
        _, J = simulate_windows(model, data, win, z[None], Ps, free=())
        return (J[0][:, chan, :] / scale[None, :, None])[ok]           # (W C, nx)

    return scipy.optimize.least_squares(resid, x0, jac=jac, method="trf", x_scale="jac",
                                        max_nfev=50).x


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
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False
