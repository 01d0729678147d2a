"""Validation with uncertainty: bootstrap intervals, paired verdicts against the yardsticks,
start designs varied, and leave-experiments-out cross-validation.

``validation_intervals(res, ds)`` turns a ``DeclaredValidation`` (``acid.ident.validate``)
into intervals: at every prediction time, the RMSE and p90 |e| of the model and of each
yardstick with a 95 % interval from a two-level bootstrap (experiments resampled with
replacement, then the starts inside each chosen experiment), with the number of starts and
experiments behind each figure. A figure resting on fewer than ``MIN_STARTS`` starts, or
(pooled) fewer than ``MIN_EXPERIMENTS`` experiments, is "not resolved".

Verdicts come from a paired bootstrap: the same resampled windows give the model's RMSE and
the yardstick's (a yardstick's unscored steps left out); the difference (model minus
yardstick) "beats" when its 95 % interval is below 0, "loses" when above, "no resolvable
difference" otherwise.

``cross_validate(model, ds, ...)`` predicts each experiment (or fold of experiments) with a
model fitted without it by ``acid.ident.fit.fit_model`` (the options ``acid fit`` uses), the
yardsticks fitted on the same training experiments, under one or several start designs.
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from acid._io import json_safe
from acid.data import Dataset
from acid.errors import ConfigError, DataError

#: How the starts are placed: ``validate_model``'s even and random placements, and even
#: starts at least one horizon apart (no sample in two windows).
STARTS_DESIGNS = ("even", "random", "non-overlapping")
#: Below these counts a figure is "not resolved" (per experiment: the starts only).
MIN_STARTS, MIN_EXPERIMENTS = 20, 3
DEFAULT_RESAMPLES = 1000
LEVEL = 0.95
VERDICTS = ("beats", "loses", "no resolvable difference", "not resolved")


def design_options(design: str) -> dict:
    """``validate_model`` keywords of a start design (``STARTS_DESIGNS``)."""
    if design not in STARTS_DESIGNS:
        raise ConfigError(f"--starts-design must be one of {', '.join(STARTS_DESIGNS)}, got "
                          f"{design!r}")
    if design == "non-overlapping":
        return {"placement": "even", "non_overlapping": True}
    return {"placement": design, "non_overlapping": False}


def _draws(groups: Sequence[np.ndarray], n: int, rng: np.random.Generator) -> list:
    """``n`` two-level resamples of the index arrays ``groups`` (one per experiment): the
    experiments with replacement, then each chosen experiment's indices with replacement
    (one experiment: its indices only)."""
    out = []
    for _ in range(n):
        pick = rng.integers(0, len(groups), len(groups)) if len(groups) > 1 else [0]
        out.append(np.concatenate([groups[g][rng.integers(0, groups[g].size,
                                                          groups[g].size)]
                                   for g in pick]))
    return out


def _rmse(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(e ** 2))) if e.size else math.nan


def _p90(e: np.ndarray) -> float:
    return float(np.percentile(np.abs(e), 90)) if e.size else math.nan


def _nan_p90_rows(a: np.ndarray) -> np.ndarray:
    """``np.nanpercentile(a, 90, axis=1)`` (linear interpolation) of (B, L, P), vectorised:
    NaN sorts last, so each row's n finite values come first."""
    a = np.sort(a, axis=1)
    n = np.isfinite(a).sum(axis=1)                                  # (B, P)
    pos = 0.9 * np.maximum(n - 1, 0)
    lo = np.floor(pos).astype(int)
    hi = np.minimum(lo + 1, np.maximum(n - 1, 0))
    a_lo = np.take_along_axis(a, lo[:, None, :], axis=1)[:, 0]
    a_hi = np.take_along_axis(a, hi[:, None, :], axis=1)[:, 0]
    return np.where(n > 0, a_lo + (a_hi - a_lo) * (pos - lo), np.nan)


def _ci(v: list[float]) -> tuple[float, float]:
    a = np.asarray(v, dtype=float)
    a = a[np.isfinite(a)]
    if not a.size:
        return math.nan, math.nan
    lo, hi = np.percentile(a, [50 * (1 - LEVEL), 100 - 50 * (1 - LEVEL)])
    return float(lo), float(hi)


@dataclass(frozen=True)
class Figure:
    """One predictor's error at one prediction time over one scope, with its interval."""

    scope: str            # "pooled" or an experiment's name
    predictor: str        # "model" or a yardstick
    time_s: float
    n_starts: int
    n_experiments: int
    rmse: float
    rmse_lo: float
    rmse_hi: float
    p90: float
    p90_lo: float
    p90_hi: float
    resolved: bool


@dataclass(frozen=True)
class Verdict:
    """The model against one yardstick at one prediction time over one scope: the RMSE
    difference (model minus yardstick, same windows, K) and its paired-bootstrap interval."""

    scope: str
    yardstick: str
    time_s: float
    n_starts: int
    n_experiments: int
    difference: float
    lo: float
    hi: float
    verdict: str


def _resolved(n_starts: int, n_exp: int, pooled: bool) -> bool:
    return n_starts >= MIN_STARTS and (not pooled or n_exp >= MIN_EXPERIMENTS)


def _judge(lo: float, hi: float, resolved: bool) -> str:
    if not resolved or not (math.isfinite(lo) and math.isfinite(hi)):
        return "not resolved"
    return "beats" if hi < 0 else "loses" if lo > 0 else "no resolvable difference"


def interval_tables(errors: dict[str, np.ndarray], experiment: np.ndarray, names: Sequence[str],
                    Ts: float, times_s: Sequence[float], *, n_resamples: int = DEFAULT_RESAMPLES,
                    seed: int = 0, per_experiment: bool = True
                    ) -> tuple[tuple[Figure, ...], tuple[Verdict, ...]]:
    """Figures and verdicts from per-start errors: ``errors[predictor]`` (starts, horizon)
    (``"model"`` first, the others yardsticks, NaN where not scored), ``experiment``
    (starts,) each start's experiment index into ``names``; at each time in ``times_s``."""
    if int(n_resamples) < 10:
        raise ConfigError(f"resamples must be at least 10, got {n_resamples}")
    rng = np.random.default_rng(seed)
    experiment = np.asarray(experiment, dtype=int)
    scopes = [("pooled", np.ones(experiment.size, bool))]
    if per_experiment:
        scopes += [(names[g], experiment == g) for g in np.unique(experiment)]
    figs, verdicts = [], []
    keys = list(errors)
    H = errors["model"].shape[1]
    for t in times_s:
        h = int(round(t / Ts))
        if not 1 <= h <= H:
            continue
        V = np.stack([errors[k][:, h - 1] for k in keys], axis=1)       # (starts, P)
        for scope, mask in scopes:
            pooled = scope == "pooled"
            ok = mask & np.isfinite(V[:, 0])
            if not ok.any():
                continue
            groups = [np.flatnonzero(ok & (experiment == g))
                      for g in np.unique(experiment[ok])]
            draws = _draws(groups, n_resamples, rng)      # the same windows for every one
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                L = max(d.size for d in draws)
                W = np.full((len(draws), L, V.shape[1]), np.nan)     # padded with NaN
                for b, d in enumerate(draws):
                    W[b, :d.size] = V[d]
                R = np.sqrt(np.nanmean(W ** 2, axis=1))
                Q = _nan_p90_rows(np.abs(W))
                D = R[:, :1] - R                                    # model minus each
            for j, k in enumerate(keys):
                v = V[ok, j]
                v = v[np.isfinite(v)]
                n = int(v.size)
                ne = len({int(g) for g in experiment[ok][np.isfinite(V[ok, j])]})
                if n == 0:
                    continue
                r_lo, r_hi = _ci(R[:, j])
                p_lo, p_hi = _ci(Q[:, j])
                figs.append(Figure(scope, k, h * Ts, n, ne, _rmse(v), r_lo, r_hi, _p90(v),
                                   p_lo, p_hi, _resolved(n, ne, pooled)))
                if j == 0:
                    continue
                both = ok & np.isfinite(V[:, j])
                nb = int(both.sum())
                neb = len({int(g) for g in experiment[both]})
                lo, hi = _ci(D[:, j])
                verdicts.append(Verdict(scope, k, h * Ts, nb, neb,
                                        _rmse(V[both, 0]) - _rmse(V[both, j]), lo, hi,
                                        _judge(lo, hi, _resolved(nb, neb, pooled))))
    return tuple(figs), tuple(verdicts)


@dataclass(frozen=True)
class ValidationIntervals:
    """Intervals and verdicts of one validation (module docstring); frozen.

    ``figures``: every (scope, predictor, time) with RMSE, p90 |e|, their 95 % intervals and
    counts; ``verdicts``: the model against each yardstick; ``design``: the start design and
    window settings; ``notes``: what was done (resamples, seed, in-sample windows...)."""

    model: str
    channel: str
    design: str
    n_resamples: int
    seed: int
    figures: tuple[Figure, ...]
    verdicts: tuple[Verdict, ...]
    notes: tuple[str, ...] = ()

    def figure(self, time_s: float, predictor: str = "model", scope: str = "pooled") -> Figure:
        for f in self.figures:
            if f.scope == scope and f.predictor == predictor and math.isclose(f.time_s, time_s):
                return f
        raise KeyError((scope, predictor, time_s))

    def verdict(self, time_s: float, yardstick: str = "persistence",
                scope: str = "pooled") -> Verdict:
        for v in self.verdicts:
            if v.scope == scope and v.yardstick == yardstick and math.isclose(v.time_s, time_s):
                return v
        raise KeyError((scope, yardstick, time_s))

    @property
    def times_s(self) -> tuple[float, ...]:
        return tuple(sorted({f.time_s for f in self.figures}))

    def to_dict(self) -> dict:
        return json_safe({"model": self.model, "channel": self.channel, "design": self.design,
                          "n_resamples": self.n_resamples, "seed": self.seed,
                          "level": LEVEL, "min_starts": MIN_STARTS,
                          "min_experiments": MIN_EXPERIMENTS,
                          "figures": [f.__dict__ for f in self.figures],
                          "verdicts": [v.__dict__ for v in self.verdicts],
                          "notes": list(self.notes)})

    @classmethod
    def from_dict(cls, d: dict) -> ValidationIntervals:
        def nan(x):
            return math.nan if x is None else x

        return cls(d["model"], d["channel"], d["design"], int(d["n_resamples"]), int(d["seed"]),
                   tuple(Figure(**{k: nan(v) for k, v in f.items()}) for f in d["figures"]),
                   tuple(Verdict(**{k: nan(v) for k, v in f.items()}) for f in d["verdicts"]),
                   tuple(d.get("notes", ())))

    def to_frame(self):
        """The figures as a ``pandas.DataFrame``, one row per (scope, predictor, time)."""
        import pandas as pd

        return pd.DataFrame([f.__dict__ for f in self.figures])

    def summary(self, scopes: Sequence[str] | None = None) -> str:
        """A readable table: RMSE and p90 with intervals and counts, then the verdicts."""
        scopes = scopes or list(dict.fromkeys(f.scope for f in self.figures))
        lines = [f"{self.model}, {self.channel}: 95 % intervals, two-level bootstrap "
                 f"(experiments, then starts; {self.n_resamples} resamples, seed {self.seed}); "
                 f"start design {self.design}; '*' not resolved (< {MIN_STARTS} starts or, "
                 f"pooled, < {MIN_EXPERIMENTS} experiments)"]
        for sc in scopes:
            lines.append(f"[{sc}]  time s | predictor | RMSE [95 %] | p90 |e| [95 %] | "
                         "starts / experiments")
            for f in self.figures:
                if f.scope == sc:
                    lines.append(f"  {f.time_s:7g} | {f.predictor:11s} | {f.rmse:.2f} "
                                 f"[{f.rmse_lo:.2f}, {f.rmse_hi:.2f}] | {f.p90:.2f} "
                                 f"[{f.p90_lo:.2f}, {f.p90_hi:.2f}] | {f.n_starts} / "
                                 f"{f.n_experiments}{'' if f.resolved else ' *'}")
            for v in self.verdicts:
                if v.scope == sc:
                    lines.append(f"  {v.time_s:7g} | vs {v.yardstick:8s} | RMSE diff "
                                 f"{v.difference:+.2f} [{v.lo:+.2f}, {v.hi:+.2f}] -> "
                                 f"{v.verdict}")
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)

    def __repr__(self) -> str:
        n = len({f.scope for f in self.figures} - {"pooled"})
        return (f"ValidationIntervals(model={self.model!r}, channel={self.channel!r}, "
                f"design={self.design!r}, times_s={self.times_s}, experiments={n}, "
                f"n_resamples={self.n_resamples})")


def validation_intervals(res, ds: Dataset, *, channel: str | None = None,
                         times_s: Sequence[float] | None = None,
                         n_resamples: int = DEFAULT_RESAMPLES, seed: int = 0,
                         design: str | None = None, experiment: np.ndarray | None = None,
                         names: Sequence[str] | None = None,
                         notes: Sequence[str] = ()) -> ValidationIntervals:
    """Intervals and verdicts of the validation ``res`` (a ``DeclaredValidation`` run on
    ``ds``): ``channel`` (default: the first temperature, else the first channel), at
    ``times_s`` (default: ``REPORT_TIMES_S`` and every step of ``res.by_horizon``).
    ``experiment``/``names``: each start's experiment and their names (default: from ``ds``)."""
    from acid.ident.validate import REPORT_TIMES_S

    if channel is None:
        channel = next((c for c, u in zip(res.channels, res.units, strict=True) if u == "K"),
                       res.channels[0])
    if channel not in res.errors:
        raise DataError(f"channel {channel!r} was not validated (validated: "
                        f"{', '.join(res.channels)})")
    if times_s is None:
        times_s = sorted({*REPORT_TIMES_S, *(r["time_s"] for r in res.by_horizon)})
    if experiment is None:
        experiment = np.asarray(ds.experiment)[res.starts]
        ids = np.unique(np.asarray(ds.experiment))
        all_names = ds.experiment_names()
        names = [all_names[int(np.searchsorted(ids, i))] for i in ids]
        experiment = np.searchsorted(ids, experiment)
    errors = {"model": res.errors[channel],
              **{k: y["errors"][channel] for k, y in res.yardsticks.items()
                 if channel in y.get("errors", {})}}
    figs, verdicts = interval_tables(errors, experiment, list(names), res.Ts, times_s,
                                     n_resamples=n_resamples, seed=seed)
    if design is None:
        design = ("non-overlapping" if res.settings.get("non_overlapping") else
                  res.settings.get("placement", "even"))
    return ValidationIntervals(res.model, channel, design, int(n_resamples), int(seed), figs,
                               verdicts, tuple(notes))


@dataclass(frozen=True)
class CrossValidation:
    """Leave-experiments-out cross-validation (``cross_validate``); frozen.

    ``folds``: per fold, the held-out and training experiments, the fit's method, loss and
    values; ``intervals``: one ``ValidationIntervals`` per start design over the held-out
    windows of every fold (per experiment and pooled); ``robust``: per yardstick and time,
    whether the pooled verdict is the same under every design."""

    model: str
    channel: str
    fit_options: dict
    folds: tuple[dict, ...]
    intervals: tuple[ValidationIntervals, ...]
    settings: dict = field(default_factory=dict)

    @property
    def robust(self) -> dict:
        """{yardstick: {time: verdict if every design agrees else "differs across designs:
        ..."}} of the pooled verdicts."""
        out: dict = {}
        for iv in self.intervals:
            for v in iv.verdicts:
                if v.scope == "pooled":
                    out.setdefault(v.yardstick, {}).setdefault(f"{v.time_s:g}", []).append(
                        f"{iv.design}: {v.verdict}")
        return {y: {t: (vs[0].split(": ", 1)[1] if len({s.split(": ", 1)[1] for s in vs}) == 1
                        else "differs across designs: " + "; ".join(vs))
                    for t, vs in d.items()} for y, d in out.items()}

    def to_dict(self) -> dict:
        return json_safe({"model": self.model, "channel": self.channel,
                          "fit_options": self.fit_options, "folds": list(self.folds),
                          "parameters": self.parameters(),
                          "intervals": [iv.to_dict() for iv in self.intervals],
                          "robust": self.robust, "settings": self.settings})

    @classmethod
    def from_dict(cls, d: dict) -> CrossValidation:
        return cls(d["model"], d["channel"], dict(d["fit_options"]), tuple(d["folds"]),
                   tuple(ValidationIntervals.from_dict(x) for x in d["intervals"]),
                   dict(d.get("settings", {})))

    def to_frame(self):
        import pandas as pd

        return pd.concat([iv.to_frame().assign(design=iv.design) for iv in self.intervals],
                         ignore_index=True)

    def parameters(self) -> list[dict]:
        """Per estimated parameter (shared by all experiments): its value in every fold, the
        spread across folds (max - min) also in units of the median fold standard error,
        and the folds where it ended on a declared bound."""
        rows = []
        for name in self.folds[0]["values"] if self.folds else ():
            if not any(name in f.get("stderr", {}) for f in self.folds):
                continue                                     # fixed, or per experiment
            ses = np.array([math.nan if f.get("stderr", {}).get(name) is None
                            else float(f["stderr"][name]) for f in self.folds])
            v = [float(f["values"][name]) for f in self.folds]
            se = float(np.nanmedian(ses)) if np.isfinite(ses).any() else math.nan
            spread = max(v) - min(v)
            rows.append({"name": name, "values": v, "spread": spread,
                         "spread_in_se": spread / se if se > 0 else math.nan,
                         "on_bound_in_folds": [f["fold"] for f in self.folds if any(
                             b.split(" at its ")[0] == name for b in f.get("on_bounds", ()))]})
        return rows

    def summary(self) -> str:
        lines = [f"Cross-validation of {self.model!r}: {len(self.folds)} folds, each "
                 f"held-out experiment predicted by a model fitted without it "
                 f"({', '.join(f'{k}={v}' for k, v in self.fit_options.items())}); "
                 "yardsticks fitted on the same training experiments"]
        for f in self.folds:
            lines.append(f"  fold {f['fold']}: held out {', '.join(f['held_out'])} "
                         f"(trained on {len(f['trained_on'])} experiments)")
        moving = [r for r in self.parameters() if r["on_bound_in_folds"]
                  or r["spread_in_se"] > 2.0]
        if moving:
            lines.append("Parameters across folds (on a bound in some fold, or moving by more "
                         "than 2 standard errors):")
            lines += [f"  {r['name']}: {', '.join(f'{x:.4g}' for x in r['values'])} (spread "
                      f"{r['spread']:.3g} = {r['spread_in_se']:.1f} s.e.)"
                      + (f"; on a bound in fold {', '.join(map(str, r['on_bound_in_folds']))}"
                         if r["on_bound_in_folds"] else "") for r in moving]
        for iv in self.intervals:
            lines.append(iv.summary())
        if len(self.intervals) > 1:
            lines.append("Pooled verdicts across start designs:")
            for y, d in self.robust.items():
                lines += [f"  vs {y} at {t} s: {v}" for t, v in d.items()]
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (f"CrossValidation(model={self.model!r}, channel={self.channel!r}, "
                f"folds={len(self.folds)}, designs={tuple(i.design for i in self.intervals)})")


def fold_groups(n_experiments: int, folds: int | None) -> list[np.ndarray]:
    """Experiment indices of each fold: one experiment per fold (``folds`` None), else
    ``folds`` groups taking the experiments in turn (0, k, 2k... in fold 0)."""
    if folds is None or int(folds) >= n_experiments:
        return [np.array([i]) for i in range(n_experiments)]
    if int(folds) < 2:
        raise ConfigError(f"--cv-folds must be at least 2, got {folds}")
    return [np.arange(i, n_experiments, int(folds)) for i in range(int(folds))]


def cross_validate(model, ds: Dataset, *, fit_options: dict | None = None,
                   folds: int | None = None, designs: Sequence[str] = ("even",),
                   starts: int = 60, horizon: int = 300, warmup: float | None = None,
                   exogenous: str = "hold", to_end: bool = False, warm_start: str = "fit",
                   channel: str | None = None, n_resamples: int = DEFAULT_RESAMPLES,
                   seed: int = 0, fit: Callable | None = None,
                   progress: Callable[[int, int, str], None] | None = None
                   ) -> CrossValidation:
    """Leave-experiments-out cross-validation of ``model`` on the experiments of ``ds``.

    Each fold's experiments are predicted by ``fit_model(model, training, **fit_options)``
    fitted on the other experiments only (a held-out experiment's per-experiment
    parameters, never fitted, take the table value: the mean over the training ones); the
    yardsticks are fitted on the same training experiments. ``starts`` per fold, placed by
    each design in ``designs`` (``STARTS_DESIGNS``; random ones seeded by ``seed``),
    ``horizon`` steps, ``warmup`` seconds (``validate_model``'s units and default, as ``acid
    validate --cv``'s options); the
    windows of every fold are pooled into one ``ValidationIntervals`` per design.
    ``fit``: the fitter (default ``acid.ident.fit.fit_model``), called as
    ``fit(model, training_dataset, **fit_options)``."""
    from acid.ident.fit import fit_model
    from acid.ident.validate import (
        EXOGENOUS_MODES,
        default_warmup,
        fitted_parameters,
        validate_model,
    )
    from acid.models.loader import load

    model = load(model)
    if warmup is None:
        warmup = default_warmup(ds, horizon)[0]
    if exogenous not in EXOGENOUS_MODES:
        raise ConfigError(f"--exogenous must be one of {', '.join(EXOGENOUS_MODES)}, got "
                          f"{exogenous!r}")
    for d in designs:
        design_options(d)
    fit = fit or fit_model
    fit_options = dict(fit_options or {})
    segs = ds.segments()
    names = ds.experiment_names()
    if len(segs) < 2:
        raise DataError(f"{ds.source}: cross-validation needs at least 2 experiments, got "
                        f"{len(segs)}")
    groups = fold_groups(len(segs), folds)
    hold = tuple(d.name for d in model.disturbances) if exogenous == "hold" else ()
    parts = [ds.window(a, b) for a, b in segs]
    per_design: dict[str, dict] = {d: {"errors": {}, "exp": [], "notes": []} for d in designs}
    fold_rows = []
    total = len(groups) * (1 + len(designs))
    done = 0
    for i, test in enumerate(groups):
        train = [j for j in range(len(segs)) if j not in set(test.tolist())]
        tr = Dataset.concatenate([parts[j] for j in train])
        tr.source = f"{ds.source} without {', '.join(names[j] for j in test)}"
        result = fit(model, tr, **fit_options)
        ps = fitted_parameters(result)
        done += 1
        if progress:
            progress(done, total, f"fold {i + 1}: fitted on {len(train)} experiments")
        te = Dataset.concatenate([parts[j] for j in test])
        both = Dataset.concatenate([tr, te])
        both.source = ds.source
        n_tr = len(tr)
        fold_rows.append({"fold": i + 1, "held_out": [names[j] for j in test],
                          "trained_on": [names[j] for j in train],
                          "training_samples": int(n_tr), "method": result.method,
                          "values": dict(zip(model.parameter_names,
                                             map(float, result.values), strict=True)),
                          "stderr": {e.name: float(e.stderr) for e in result.estimates
                                     if e.experiment is None},
                          "on_bounds": list(result.on_bounds)})
        for d in designs:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                res = validate_model(model, both, ps, starts=starts, horizon=horizon,
                                     warmup=warmup, hold=hold, seed=seed + i,
                                     start_range=(n_tr, len(both)), yardsticks=True,
                                     estimation=(0, n_tr), to_end=to_end,
                                     warm_start=warm_start, **design_options(d))
            acc = per_design[d]
            acc["notes"] += [f"fold {i + 1}: {w.message}" for w in caught]
            ch = channel or next((c for c, u in zip(res.channels, res.units, strict=True)
                                  if u == "K"), res.channels[0])
            acc["channel"] = ch
            acc["Ts"] = res.Ts
            acc["by_horizon"] = res.by_horizon
            # experiment of each start: index into the held-out list -> into ds
            exp_local = np.asarray(both.experiment)[res.starts] - len(train)
            acc["exp"].append(test[exp_local])
            errs = {"model": res.errors[ch], **{k: y["errors"][ch]
                                                for k, y in res.yardsticks.items()
                                                if ch in y.get("errors", {})}}
            for k, e in errs.items():
                acc["errors"].setdefault(k, []).append(e)
            done += 1
            if progress:
                progress(done, total, f"fold {i + 1}: {res.n_starts} starts validated "
                                      f"({d})")
    from acid.ident.validate import REPORT_TIMES_S

    intervals = []
    for d, acc in per_design.items():
        errors = {k: np.concatenate(v, axis=0) for k, v in acc["errors"].items()}
        times = sorted({*REPORT_TIMES_S, *(r["time_s"] for r in acc["by_horizon"])})
        figs, verdicts = interval_tables(errors, np.concatenate(acc["exp"]), names, acc["Ts"],
                                         times, n_resamples=n_resamples, seed=seed)
        notes = [f"{len(groups)} folds; starts per fold {starts}, design {d}"
                 + (f" (seed {seed} + fold)" if d == "random" else ""),
                 "held-out experiments' per-experiment parameters (never fitted) take the "
                 "training mean", *dict.fromkeys(acc["notes"])]
        intervals.append(ValidationIntervals(model.name, acc["channel"], d, int(n_resamples),
                                             int(seed), figs, verdicts, tuple(notes)))
    return CrossValidation(model.name, intervals[0].channel, json_safe(fit_options),
                           tuple(fold_rows), tuple(intervals),
                           {"starts_per_fold": starts, "horizon": horizon, "warmup_s": warmup,
                            "exogenous": exogenous, "to_end": to_end,
                            "warm_start": warm_start, "designs": list(designs),
                            "data_source": ds.source})


def dumps(obj) -> str:
    """``obj.to_dict()`` as JSON text (NaN as null)."""
    return json.dumps(obj.to_dict(), allow_nan=False)
