"""Multi-start open-loop validation of any declared model: ``validate_model(model, ds, ...)``.

From each start instant k the model predicts ``horizon`` samples open loop with the measured
inputs and disturbances. The state at k: measured states as measured; latent ones
estimated from the ``warmup`` samples before k (the whole state at k - warmup fitted to the
measured channels of that stretch with the parameters held, then simulated to k), or their
declared ``initial`` rule when ``warmup`` is 0. Errors are reported per measured channel,
overall and at chosen horizons (RMSE, p90 of |e|), with ``acid.metrics``.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.optimize

from acid._io import json_safe
from acid.data import Dataset
from acid.errors import ConfigError, DataError
from acid.ident.data import ModelData
from acid.ident.fit import PARAMS_FORMAT
from acid.ident.oe import simulate_windows
from acid.metrics import fit_percent, max_abs_error, percentile_abs_error, rmse
from acid.models.declaration import Model
from acid.models.loader import load

PLACEMENTS = ("even", "random")
#: How latent states at a start are estimated from the warm-up stretch: ``"fit"`` (the
#: state at its beginning fitted by least squares, then simulated) or ``"ekf"`` (the
#: extended Kalman filter of ``acid.ident.pem`` run along it, with the declared noises) or
#: ``"ekf-trip"`` (the filter run from the start of the experiment, as in a car it runs
#: from the start of the trip; the starts still need ``warmup`` samples before them).
WARM_STARTS = ("fit", "ekf", "ekf-trip")
#: Prediction times (s) of ``by_time`` (the model's and each yardstick's errors).
REPORT_TIMES_S = (60.0, 300.0, 600.0, 1500.0)


@dataclass(frozen=True)
class ParameterSet:
    """Values for a declared model: the table (np,) and per-experiment values by id."""

    values: np.ndarray
    per_experiment: dict = field(default_factory=dict)   # {name: {experiment id: value}}
    source: str = "declared"
    provenance: dict = field(default_factory=dict)
    #: how results name these values (default: the model's name and ``source``)
    label: str | None = None


def fitted_parameters(result) -> ParameterSet:
    """The values of a ``DeclaredFitResult`` (per-experiment ones by experiment id)."""
    per = {n: dict(zip(result.experiment_ids, map(float, v), strict=True))
           for n, v in result.per_experiment.items()}
    return ParameterSet(values=np.asarray(result.values, dtype=float), per_experiment=per,
                        source=f"fit of {result.data_source}")


def declared_parameters(model: Model) -> ParameterSet:
    return ParameterSet(values=model.values, source="declared values")


def read_parameters(model: Model, path: str | Path) -> ParameterSet:
    """A parameter file written by ``acid fit --model FILE`` for this model (one-line
    ``DataError`` when it is not one, or names parameters the model lacks)."""
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: parameter file not found")
    try:
        d = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise DataError(f"{path}: not valid JSON ({type(exc).__name__})") from None
    if not isinstance(d, dict) or d.get("format") != PARAMS_FORMAT:
        raise DataError(f"{path}: not a parameter file of a declared model (no \"format\": "
                        f"\"{PARAMS_FORMAT}\"; write one with acid fit --model FILE.py)")
    if d.get("model") != model.name:
        raise DataError(f"{path}: parameters of model {d.get('model')!r}, not "
                        f"{model.name!r}")
    par = d.get("parameters")
    if not isinstance(par, dict):
        raise DataError(f"{path}: 'parameters' must be a JSON object")
    values = model.values.copy()
    names = model.parameter_names
    for name, row in par.items():
        if name not in names:
            raise DataError(f"{path}: parameter {name!r} is not in model {model.name!r}")
        v = row.get("value") if isinstance(row, dict) else None
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise DataError(f"{path}: parameter {name!r} needs a finite 'value'")
        values[names.index(name)] = float(v)
    per = {}
    for name, row in (d.get("per_experiment") or {}).items():
        if name not in names:
            raise DataError(f"{path}: per-experiment parameter {name!r} is not in the model")
        try:
            per[name] = {int(e): float(v) for e, v in zip(row["experiments"], row["values"],
                                                          strict=True)}
        except (KeyError, TypeError, ValueError):
            raise DataError(f"{path}: per_experiment {name!r} needs 'experiments' and "
                            "'values' of equal length") from None
    prov = d.get("provenance") if isinstance(d.get("provenance"), dict) else {}
    return ParameterSet(values=values, per_experiment=per, source=str(path), provenance=prov)


@dataclass(frozen=True)
class DeclaredValidation:
    """Open-loop errors of a declared model (frozen; printing lives in the CLI).

    ``errors[channel]`` is (n_starts, horizon): prediction minus measurement at 1..horizon
    steps ahead (NaN where the channel is not recorded).
    """

    model: str
    channels: tuple[str, ...]
    units: tuple[str, ...]
    starts: np.ndarray
    horizon: int
    warmup: int
    Ts: float
    errors: dict
    metrics: dict
    by_horizon: tuple
    notes: tuple[str, ...]
    yardsticks: dict = field(default_factory=dict)
    #: {channel: {"<t>": {"rmse_K", "p90_K", "n"}}} at ``REPORT_TIMES_S`` (the starts that
    #: reach each time); each yardstick has its own under ``yardsticks[name]["by_time"]``.
    by_time: dict = field(default_factory=dict)

    def to_json_dict(self) -> dict:
        return json_safe({
            "model": self.model, "horizon": self.horizon, "warmup": self.warmup,
            "Ts": self.Ts, "n_starts": int(self.starts.size),
            "starts": self.starts.tolist(),
            "channels": {c: {"unit": u, **self.metrics[c]}
                         for c, u in zip(self.channels, self.units, strict=True)},
            "by_horizon": list(self.by_horizon), "notes": list(self.notes),
            "yardsticks": self.yardsticks, "by_time": self.by_time,
            "yardsticks_by_time": {k: y["by_time"] for k, y in self.yardsticks.items()}})


def validate_model(model: Model | str, ds: Dataset, params: ParameterSet | None = None, *,
                   starts: int = 60, horizon: int = 300, warmup: int = 60,
                   placement: str = "even", seed: int = 0,
                   horizons: tuple[int, ...] | None = None, hold: tuple[str, ...] = (),
                   start_index=None, non_overlapping: bool = False,
                   start_range: tuple[int, int] | None = None, yardsticks: bool = False,
                   estimation: tuple[int, int] | None = None,
                   to_end: bool = False, warm_start: str = "fit") -> DeclaredValidation:
    """Predict ``horizon`` samples open loop from ``starts`` instants (module docstring).

    ``hold``: disturbances held at their value at the start (the paper's protocol for T_int
    and T_shell) instead of measured along the prediction. ``start_index``: these start
    samples instead of ``starts`` placed by ``placement`` (e.g. another study's windows).
    ``non_overlapping``: starts at least ``horizon + 1`` samples apart (acid.validate's rule).
    ``start_range`` (lo, hi): every window inside samples lo .. hi - 1 (e.g. the held-out
    part). ``yardsticks``: persistence, ARX and subspace (``acid.yardsticks``) on the same
    windows, given the same inputs and held disturbances, fitted on ``estimation`` (lo, hi)
    samples (default: the whole record, in-sample). ``to_end``: a start may lie less than
    ``horizon`` samples before its experiment's end (at least ``horizon // 25`` steps, 60 s
    of 300 x 5 s); its prediction stops there, and the errors per prediction time count only
    the starts that reach it (short trips). Censored samples (a ``<channel>_censored`` mask)
    are neither scored nor used by the warm-up. ``warm_start``: one of ``WARM_STARTS``.
    """
    model = load(model)
    unknown = [h for h in hold if h not in [d.name for d in model.disturbances]]
    if unknown:
        raise ConfigError(f"hold: {unknown[0]!r} is not a disturbance of model "
                          f"{model.name!r}")
    params = params or declared_parameters(model)
    if warm_start not in WARM_STARTS:
        raise ConfigError(f"warm_start must be one of {', '.join(WARM_STARTS)}, got "
                          f"{warm_start!r}")
    if placement not in PLACEMENTS:
        raise ConfigError(f"placement must be one of {', '.join(PLACEMENTS)}, got "
                          f"{placement!r}")
    for name, v, lo in (("starts", starts, 1), ("horizon", horizon, 1), ("warmup", warmup, 0)):
        if int(v) < lo:
            raise ConfigError(f"{name} must be at least {lo}, got {v}")
    data = ModelData.of(model, ds, min_samples=2)
    latent = [i for i, s in enumerate(model.states) if not s.measured]
    need_warm = warmup if latent else 0
    lo_r, hi_r = start_range or (0, len(data))
    reach = max(1, horizon // 25) if to_end else horizon
    cand = np.concatenate([np.arange(max(a, lo_r) + need_warm, min(b, hi_r) - reach)
                           for a, b in data.segments] + [np.zeros(0, int)]).astype(int)
    if cand.size == 0:
        raise DataError(f"{ds.source}: no experiment is longer than warmup + horizon "
                        f"({need_warm} + {reach} + 1 samples)")
    if start_index is not None:
        k0 = np.asarray(start_index, dtype=int)
        bad = k0[~np.isin(k0, cand)]
        if bad.size:
            raise DataError(f"{ds.source}: start {int(bad[0])} leaves no room for the "
                            f"warm-up and {horizon} steps inside its experiment")
    elif non_overlapping:
        from acid.validate import _place_non_overlapping

        k0 = _place_non_overlapping(cand, starts, horizon)
    elif placement == "even":
        pick = np.unique(np.round(np.linspace(0, cand.size - 1, min(starts, cand.size))))
        k0 = cand[pick.astype(int)]
    else:
        k0 = np.sort(np.random.default_rng(seed).choice(cand, min(starts, cand.size),
                                                        replace=False))
    gaps = np.diff(np.sort(k0))
    notes = [f"window design: {k0.size} starts, spacing "
             + (f"{np.median(gaps) * model.Ts:g} s (median, min {gaps.min() * model.Ts:g} s)"
                if gaps.size else "one start")
             + f", horizon {horizon * model.Ts:g} s, "
             + ("overlapping" if gaps.size and gaps.min() <= horizon else "no overlap")]
    P = _parameters_at(model, data, params, k0, notes)
    x0 = data.initial_states(model, k0)
    if latent and need_warm > 0:
        if warm_start in ("ekf", "ekf-trip"):
            from acid.ident.pem import filter_states

            first = np.array([a for a, _ in data.segments])
            W = k0 - first[np.searchsorted(first, k0, side="right") - 1] \
                if warm_start == "ekf-trip" else need_warm
            x0[:, latent] = filter_states(model, data, P, k0, W)[:, latent]
        else:
            x0 = _warm_start(model, data, P, k0, need_warm, x0, latent)
        notes.append(f"latent states ({', '.join(model.states[i].name for i in latent)}) "
                     + ("estimated by the extended Kalman filter run from the start of "
                        "each experiment" if warm_start == "ekf-trip" else
                        f"estimated from the {need_warm} samples ({need_warm * model.Ts:g} s) "
                        "before each start" + (" by the extended Kalman filter"
                                               if warm_start == "ekf" else "")))
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
        notes.append("censored samples (a clipping sensor) are not scored")
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
    Y = simulate_windows(model, data, idx, x0, P)
    meas = np.where(inside[..., None], data.observed()[idx], np.nan)
    channels, units, errors, metrics = [], [], {}, {}
    rows = [(c, n) for c, n in data.measured_channels(model)]
    unit_of = {r.name: r.unit for r in model.states + model.outputs}
    for c, name in rows:
        e = (Y[:, 1:, c] - meas[:, 1:, c])
        errors[name] = e
        ok = np.isfinite(e)
        m, p = meas[:, 1:, c][ok], Y[:, 1:, c][ok]
        channels.append(name)
        units.append(unit_of[name])
        metrics[name] = {"rmse": float(rmse(m, p)),
                         "p90_abs": float(percentile_abs_error(m, p, 90)),
                         "max_abs": float(max_abs_error(m, p)),
                         "fit_percent": float(fit_percent(m, p))}
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
    ys = {}
    if yardsticks:
        ys = _yardsticks(model, data0, rows, k0, horizon, hold, steps,
                         estimation or (0, len(data0)), inside)
        if estimation is None:
            notes.append("yardsticks fitted on the whole record (in-sample: favoured)")
    return DeclaredValidation(model=model.name, channels=tuple(channels), units=tuple(units),
                              starts=k0, horizon=int(horizon), warmup=int(need_warm),
                              Ts=model.Ts, errors=errors, metrics=metrics,
                              by_horizon=tuple(by_h), notes=tuple(notes), yardsticks=ys,
                              by_time=by_time(errors, model.Ts))


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


def _yardsticks(model: Model, data: ModelData, rows, k0, horizon: int, hold, steps,
                estimation, inside) -> dict:
    """Persistence, ARX and subspace (``acid.yardsticks``) on the model's windows: the same
    inputs and disturbances (held as the model has them), predicting the measured channels
    that are recorded throughout; RMSE and p90 |e| overall and at ``steps``."""
    from acid.yardsticks import evaluate

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
    for name, pred in evaluate(y[pad], u[pad], data.experiment[pad], k0, horizon, held,
                               estimation, input_names=names).items():
        idx = np.minimum(k0[:, None] + np.arange(1, horizon + 1)[None, :], len(data) - 1)
        e = np.where(inside[:, 1:, None], pred.predicted[:, 1:, :] - obs[idx], np.nan)
        out[name] = {
            "description": pred.description,
            "channels": {n: {"rmse": _nan_rms(e[..., j]), "p90_abs": _nan_p90(e[..., j])}
                         for j, (_, n) in enumerate(use)},
            "by_horizon": [{"step": h, **{n: {"rmse": _nan_rms(e[:, h - 1, j]),
                                              "p90_abs": _nan_p90(e[:, h - 1, j])}
                                          for j, (_, n) in enumerate(use)}} for h in steps],
            "by_time": by_time({n: e[..., j] for j, (_, n) in enumerate(use)}, model.Ts)}
    return out


def _nan_rms(e: np.ndarray) -> float:
    e = e[np.isfinite(e)]
    return float(np.sqrt(np.mean(e ** 2))) if e.size else math.nan


def _nan_p90(e: np.ndarray) -> float:
    e = e[np.isfinite(e)]
    return float(np.percentile(np.abs(e), 90)) if e.size else math.nan


def _default_horizons(H: int) -> tuple[int, ...]:
    return tuple(sorted({1, max(H // 10, 1), max(H // 4, 1), max(H // 2, 1), H}))


def _parameters_at(model: Model, data: ModelData, params: ParameterSet, k0, notes) -> np.ndarray:
    P = np.tile(params.values, (k0.size, 1))
    names = model.parameter_names
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
                         f"{params.values[names.index(p.name)]:.6g} {p.unit} is used")
    return P


def _warm_start(model: Model, data: ModelData, P, k0, W: int, x_k, latent) -> np.ndarray:
    """The state at each start: fit the state at k - W to the measured channels over the
    W samples before k (parameters held), simulate to k; measured states as measured."""
    idx = (k0 - W)[:, None] + np.arange(W + 1)[None, :]
    n, nx = k0.size, model.nx
    chan = [c for c, _ in data.measured_channels(model)]
    meas = data.observed()[idx][:, :W][..., chan]
    obs = np.isfinite(meas)
    meas = np.nan_to_num(meas)
    scale = np.array([max(float(np.std(meas[..., i][obs[..., i]])), 1e-6)
                      for i in range(len(chan))])
    z0 = data.initial_states(model, k0 - W).ravel()

    def resid(z):
        Y = simulate_windows(model, data, idx[:, :W], z.reshape(n, nx), P)[..., chan]
        return ((Y - meas) / scale)[obs]

    def jac(z):
        _, J = simulate_windows(model, data, idx[:, :W], z.reshape(n, nx), P, free=())
        J = J[:, :, chan, :] / scale[None, None, :, None]              # (n, W, C, nx)
        full = np.zeros(J.shape[:3] + (n * nx,))
        for s in range(n):
            full[s, :, :, s * nx:(s + 1) * nx] = J[s]
        return full[obs]

    sol = scipy.optimize.least_squares(resid, z0, jac=jac, method="trf", x_scale="jac",
                                       max_nfev=50)
    X = simulate_windows(model, data, idx, sol.x.reshape(n, nx), P)[:, -1, :nx]
    out = x_k.copy()
    out[:, latent] = X[:, latent]
    return out
