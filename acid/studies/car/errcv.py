"""Grey box plus what it misses, cross-validated over trips: the residual ARX of
:mod:`acid.ident.errmodel` on the folds of a leave-trips-out cross-validation.

In each fold the declared model keeps the parameters fitted without the fold's trips
(``fold_values``, e.g. the chosen structure's rows of ``acid car select``); the residual ARX
is fitted on windows of the training trips only, and the fold's trips are predicted by the
grey box alone, the grey box plus the residual ARX, and persistence, ARX and subspace fitted
on the same training trips, from the same starts. The folds' windows are pooled into one
table (bootstrap over trips, then starts, paired differences; ``interval_tables``).

``every`` (samples) replaces the even placement of ``starts`` by a start grid: every
``every``-th sample of a held-out trip that has the whole horizon of trip after it (and the
warm-up before it), so the longest horizon is scored from every start that reaches it (e.g.
1500 s from a 15 s grid), not from the few even starts that happen to fall early in a long
trip. Grid windows overlap: the intervals resample trips first, so they are as wide as the
trips make them, whatever the number of starts.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from acid.data import Dataset
from acid.errors import DataError
from acid.ident.crossval import Figure, Verdict, fold_groups, interval_tables
from acid.ident.errmodel import validate_with_error_model
from acid.models import load
from acid.models.values import ParameterValues

#: Prediction times of the table, s.
TIMES_S = (60.0, 300.0, 600.0, 1500.0)


@dataclass(frozen=True)
class ErrorModelCV:
    """The pooled and per-trip figures (``predictor`` "model" = grey box + residual ARX,
    "greybox", the yardsticks) and the verdicts of grey box + ARX against the others;
    ``folds``: per fold the held-out trips and the residual ARX's orders and windows."""

    model: str
    channel: str
    figures: tuple[Figure, ...]
    verdicts: tuple[Verdict, ...]
    folds: tuple[dict, ...]
    settings: dict

    def to_dict(self) -> dict:
        return {"model": self.model, "channel": self.channel,
                "figures": [vars(f) for f in self.figures],
                "verdicts": [vars(v) for v in self.verdicts],
                "folds": list(self.folds), "settings": self.settings}

    def summary(self, scopes: Sequence[str] = ("pooled",)) -> str:
        lines = [f"{self.channel} held out, {self.model} + residual ARX ({len(self.folds)} "
                 "folds; residual ARX per fold: " + ", ".join(
                     f"na={f['na']} nb={f['nb']} from {f['windows']} windows"
                     for f in self.folds) + "); RMSE [95 %] / p90 [95 %], K"]
        for f in self.figures:
            if f.scope in scopes:
                lines.append(f"  {f.scope:>8} {f.time_s:6g} s {f.predictor:>12}: "
                             f"{f.rmse:.2f} [{f.rmse_lo:.2f}, {f.rmse_hi:.2f}] / {f.p90:.2f} "
                             f"[{f.p90_lo:.2f}, {f.p90_hi:.2f}]  {f.n_starts} starts / "
                             f"{f.n_experiments} trips" + ("" if f.resolved else
                                                            "  not resolved"))
        for v in self.verdicts:
            if v.scope in scopes:
                lines.append(f"  {v.scope:>8} {v.time_s:6g} s grey box + ARX vs "
                             f"{v.yardstick}: {v.verdict}, {v.difference:+.2f} "
                             f"[{v.lo:+.2f}, {v.hi:+.2f}] K")
        return "\n".join(lines)


def error_model_cv(model, ds: Dataset, fold_values: Sequence, *, folds: int | None = 2,
                   starts: int = 60, horizon: int = 300, warmup: int = 0,
                   to_end: bool = True, warm_start: str = "fit", channel: str | None = None,
                   n_resamples: int = 1000, seed: int = 0, every: int | None = None,
                   progress: Callable[[int, int, str], None] | None = None) -> ErrorModelCV:
    """Cross-validate ``model`` plus a residual ARX over the trips of ``ds`` on the folds of
    ``acid.ident.crossval.fold_groups(n_trips, folds)``; ``fold_values[i]``: fold i's
    parameters (``ParameterValues`` or a {name: value} dict) fitted without its trips.
    Exogenous signals are measured along each window (as ``acid car select``); ``every``:
    the start grid (module docstring) instead of ``starts`` even starts."""
    m = load(model)
    names = ds.experiment_names()
    segs = ds.segments()
    groups = fold_groups(len(segs), folds)
    if len(fold_values) != len(groups):
        raise DataError(f"error model: {len(fold_values)} parameter sets for "
                        f"{len(groups)} folds")
    parts = [ds.window(a, b) for a, b in segs]
    errs: dict[str, list] = {}
    exps, rows, ch = [], [], channel
    for i, test in enumerate(groups):
        held = set(test.tolist())
        order = [j for j in range(len(parts)) if j not in held] + test.tolist()
        both = Dataset.concatenate([parts[j] for j in order])
        both.source = ds.source
        n_est = sum(len(parts[j]) for j in order[:len(order) - len(test)])
        p = fold_values[i]
        p = p if isinstance(p, ParameterValues) else ParameterValues(dict(p), model=m)
        grid = {} if every is None else {"start_index": start_grid(
            both, n_est, horizon, warmup if _latent(m) else 0, every)}
        if grid and grid["start_index"].size == 0:
            raise DataError(f"fold {i + 1}: no held-out trip is longer than the warm-up and "
                            f"{horizon} samples")
        r = validate_with_error_model(m, both, p, n_estimation=n_est, channel=ch,
                                      starts=starts, fit_starts=starts, horizon=horizon,
                                      warmup=warmup, to_end=to_end, warm_start=warm_start,
                                      hold=(), n_resamples=10, seed=seed, **grid)
        ch = r.channel
        for k, e in r.errors.items():
            errs.setdefault(k, []).append(e)
        exps.append(np.asarray(order)[r.experiment])
        st = r.residual.settings
        rows.append({"fold": i + 1, "held_out": [names[j] for j in test], "na": st["na"],
                     "nb": st["nb"], "windows": st["windows"], "stable": bool(st["stable"])})
        if progress:
            progress(i + 1, len(groups), f"fold {i + 1}: residual ARX na={st['na']} "
                                         f"nb={st['nb']}, {len(r.experiment)} starts")
    errors = {k: np.concatenate(v, axis=0) for k, v in errs.items()}
    figs, verdicts = interval_tables(errors, np.concatenate(exps), names, ds.Ts, TIMES_S,
                                     n_resamples=n_resamples, seed=seed)
    return ErrorModelCV(m.name, ch, tuple(figs), tuple(verdicts), tuple(rows),
                        {"starts_per_fold": starts, "start_every": every,
                         "horizon": horizon, "warmup": warmup,
                         "to_end": to_end, "warm_start": warm_start,
                         "exogenous": "measured", "resamples": n_resamples, "seed": seed})


def start_grid(ds: Dataset, first: int, horizon: int, warmup: int, every: int) -> np.ndarray:
    """Sample indices of ``ds`` from ``first`` on, every ``every``-th sample of each trip
    (segment) counted from its warm-up's end, whose window of ``horizon`` steps ends inside
    the trip."""
    if int(every) < 1:
        raise DataError(f"start grid: every must be at least 1 sample, got {every}")
    out = [np.arange(max(a, first) + warmup, b - horizon, int(every))
           for a, b in ds.segments() if b > first]
    return np.concatenate([*out, np.zeros(0, int)]).astype(int)


def _latent(model) -> bool:
    return any(not s.measured for s in model.states)
