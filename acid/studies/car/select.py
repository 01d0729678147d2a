"""Model structures chosen by cross-validation over trips (``acid car select``).

Each candidate declared structure is fitted by leave-trips-out cross-validation
(:func:`acid.ident.crossval.cross_validate`): the same folds of trips for every candidate,
each fold's trips predicted by the structure fitted without them, persistence, ARX and
subspace fitted on the same training trips and predicting the same windows. The table holds,
per candidate, the pooled RMSE and p90 of the held-out prediction error with 95 % intervals
(bootstrap over trips, then starts) at each reporting time, the verdicts against the
yardsticks, the parameters that end on a declared bound in some fold and how far each moves
between folds.

The rule (:data:`RULE`): the structure with the fewest free parameters whose pooled RMSE at
``rule_time_s`` lies inside the 95 % interval of the best candidate's RMSE there (the best:
the lowest RMSE); ties in size go to the lower RMSE. A bigger structure must earn its
parameters by a difference the held-out trips resolve.

A candidate that declares its noises (the Kalman filter's process and sensor noises, e.g.
``car_heat3n``) is fitted by prediction error and warm-started by the filter run over the
trip up to each start (:data:`NOISE_DECLARED`), whatever the season's method: an output-error
fit has no use for the noises and the filter needs them. The "free" count is the
declared free parameters; the noises PEM estimates come on top (``car_heat3n``: 15 + 7).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from acid._io import json_safe
from acid.data import Dataset
from acid.errors import DataError
from acid.ident.crossval import CrossValidation, Figure, fold_groups
from acid.ident.validate import REPORT_TIMES_S

#: The candidate structures of each season, smallest last (names of built-in declarations).
CANDIDATES = {"summer": ("car_cabin", "car_cabin2", "car_cabin1"),
              "winter": ("heating", "car_heat3n", "car_heat3", "car_heat2")}

#: How a candidate that declares its noises is fitted and warm-started (see the module text).
NOISE_DECLARED = {"method": "pem", "warm_start": "ekf-trip"}

RULE = ("the fewest free parameters whose pooled RMSE at {t:g} s lies inside the 95 % "
        "interval of the best candidate's RMSE there")

YARDSTICKS = ("persistence", "arx", "subspace")


@dataclass(frozen=True)
class CandidateScore:
    """One candidate structure's cross-validation: its size, pooled figures per reporting
    time (``Figure``: RMSE and p90 with intervals), pooled verdicts against the yardsticks
    ({yardstick: {time: (verdict, difference, lo, hi)}}), parameter rows across folds
    (``CrossValidation.parameters()``) and the wall time of its folds."""

    name: str
    n_free: int
    n_states: int
    figures: tuple[Figure, ...]
    verdicts: dict
    parameters: tuple[dict, ...]
    seconds: float
    cv: CrossValidation = field(repr=False, compare=False)

    def figure(self, time_s: float) -> Figure | None:
        return next((f for f in self.figures if f.time_s == time_s), None)

    @property
    def on_bounds(self) -> tuple[str, ...]:
        return tuple(r["name"] for r in self.parameters if r["on_bound_in_folds"])

    def to_dict(self) -> dict:
        return {"name": self.name, "free_parameters": self.n_free, "states": self.n_states,
                "figures": [f.__dict__ for f in self.figures], "verdicts": self.verdicts,
                "parameters": list(self.parameters), "on_bounds": list(self.on_bounds),
                "seconds": self.seconds, "fit_options": dict(self.cv.fit_options),
                "warm_start": self.cv.settings.get("warm_start"),
                "folds": list(self.cv.folds)}


@dataclass(frozen=True)
class StructureSelection:
    """The candidates' cross-validation on the same folds, the yardsticks' pooled figures
    (from the first candidate's run: the same folds, starts and training trips), the rule and
    the structure it chooses. ``settings``: the first candidate's; each candidate's own fit
    options and warm start are in its ``to_dict()``."""

    candidates: tuple[CandidateScore, ...]
    yardsticks: dict
    folds: tuple[tuple[str, ...], ...]
    rule_time_s: float
    best: str
    chosen: str
    settings: dict

    @property
    def rule(self) -> str:
        return RULE.format(t=self.rule_time_s)

    def candidate(self, name: str) -> CandidateScore:
        return next(c for c in self.candidates if c.name == name)

    def times_s(self) -> tuple[float, ...]:
        return tuple(sorted({f.time_s for c in self.candidates for f in c.figures}))

    def to_dict(self) -> dict:
        return json_safe({"rule": self.rule, "rule_time_s": self.rule_time_s,
                          "best": self.best, "chosen": self.chosen,
                          "folds": [list(f) for f in self.folds], "settings": self.settings,
                          "candidates": [c.to_dict() for c in self.candidates],
                          "yardsticks": {k: [f.__dict__ for f in v]
                                         for k, v in self.yardsticks.items()}})

    def rows(self, times_s: Sequence[float] | None = None) -> list[list[str]]:
        """One row per candidate then per yardstick: name, free parameters, then
        ``RMSE [lo, hi] / p90`` at each time (``*``: not resolved)."""
        times = tuple(times_s or self.times_s())
        out = []
        for c in self.candidates:
            out.append([c.name + (" (chosen)" if c.name == self.chosen else ""),
                        str(c.n_free), *(_cell(c.figure(t)) for t in times)])
        for y, figs in self.yardsticks.items():
            by = {f.time_s: f for f in figs}
            out.append([y, "", *(_cell(by.get(t)) for t in times)])
        return out

    def summary(self) -> str:
        times = self.times_s()
        head = ["structure", "free"] + [f"{t:g} s RMSE [95 %] / p90" for t in times]
        lines = [f"Structures by leave-trips-out cross-validation: {len(self.folds)} folds "
                 f"over {sum(map(len, self.folds))} trips, the same folds and windows for "
                 "every candidate and yardstick", "  " + " | ".join(head)]
        lines += ["  " + " | ".join(r) for r in self.rows(times)]
        for c in self.candidates:
            moving = [r for r in c.parameters if r["on_bound_in_folds"]
                      or r["spread_in_se"] > 2.0]
            vs = "; ".join(f"{y} {t} s: {v[0]} ({v[1]:+.2f} [{v[2]:+.2f}, {v[3]:+.2f}])"
                           for y, d in c.verdicts.items() for t, v in d.items()
                           if float(t) in REPORT_TIMES_S and v[0] != "not resolved")
            far = ", ".join(r["name"] for r in moving if r["spread_in_se"] > 2) or "none"
            lines.append(f"{c.name}: {c.n_free} free parameters, {c.n_states} states, "
                         f"{c.seconds:.0f} s; on a bound in some fold: "
                         f"{', '.join(c.on_bounds) or 'none'}; moving by > 2 s.e. between "
                         f"folds: {far}")
            lines.append(f"  verdicts, pooled RMSE difference [95 %] (resolved ones): {vs}")
        lines.append(f"Rule: {self.rule}. Best at {self.rule_time_s:g} s: {self.best}; "
                     f"chosen: {self.chosen}")
        return "\n".join(lines)


def _cell(f: Figure | None) -> str:
    if f is None or not math.isfinite(f.rmse):
        return "n/a"
    star = "" if f.resolved else " *"
    return f"{f.rmse:.2f} [{f.rmse_lo:.2f}, {f.rmse_hi:.2f}] / {f.p90:.2f}{star}"


def choose(candidates: Sequence[CandidateScore], time_s: float) -> tuple[str, str]:
    """(best, chosen) by :data:`RULE` at ``time_s`` among the candidates whose pooled figure
    there is resolved."""
    scored = [(c, c.figure(time_s)) for c in candidates]
    scored = [(c, f) for c, f in scored if f is not None and f.resolved
              and math.isfinite(f.rmse)]
    if not scored:
        raise DataError(f"no candidate has a resolved pooled RMSE at {time_s:g} s (too few "
                        "starts or trips reach it): choose an earlier rule time")
    best, fb = min(scored, key=lambda cf: cf[1].rmse)
    inside = [(c, f) for c, f in scored if f.rmse <= fb.rmse_hi]
    chosen, _ = min(inside, key=lambda cf: (cf[0].n_free, cf[1].rmse))
    return best.name, chosen.name


def select_structure(ds: Dataset, candidates: Sequence, *, fit_options: dict | None = None,
                     folds: int | None = 2, rule_time_s: float = 600.0, starts: int = 60,
                     horizon: int = 300, warmup: float = 300.0, exogenous: str = "measured",
                     to_end: bool = True, warm_start: str = "fit", n_resamples: int = 1000,
                     seed: int = 0, fit: Callable | None = None, channel: str | None = "T_cab",
                     progress: Callable[[int, int, str], None] | None = None
                     ) -> StructureSelection:
    """Cross-validate each of ``candidates`` (declared models or their names) on the trips
    (experiments) of ``ds`` over the same ``folds`` and choose one by :data:`RULE`.
    ``fit_options`` go to each fold's fit (``acid.ident.fit.fit_model``); the other
    arguments are :func:`acid.ident.crossval.cross_validate`'s. ``progress(done, total,
    label)`` after each fold's fit and validation of each candidate. ``channel``: the
    measured channel scored (the cabin air by default; None: the first one in kelvin, which
    for the heating structures is the coolant)."""
    from acid.ident.crossval import cross_validate
    from acid.models import load

    models = [load(c) for c in candidates]
    if len(models) < 2:
        raise DataError("structure selection needs at least 2 candidate structures")
    if len({m.name for m in models}) != len(models):
        raise DataError("candidate structures must have different names")
    groups = fold_groups(len(ds.experiment_names()), folds)
    per = 2 * len(groups)
    runs = []
    for k, m in enumerate(models):
        tick = None
        if progress is not None:
            def tick(done, total, label, k=k, m=m):
                progress(k * per + done, len(models) * per, f"{m.name}: {label}")
        t0 = time.perf_counter()
        opts, warm = candidate_options(m, fit_options, warm_start)
        cv = cross_validate(m, ds, fit_options=opts, folds=folds, designs=("even",),
                            starts=starts, horizon=horizon, warmup=warmup,
                            exogenous=exogenous, to_end=to_end, warm_start=warm,
                            channel=channel, n_resamples=n_resamples, seed=seed, fit=fit,
                            progress=tick)
        runs.append((m, cv, time.perf_counter() - t0))
    return assemble(runs, rule_time_s)


def declares_noises(model) -> bool:
    """Whether ``model`` declares a process or sensor noise on some state."""
    return any(s.noise is not None or s.sensor is not None for s in model.states)


def candidate_options(model, fit_options: dict | None, warm_start: str) -> tuple[dict, str]:
    """(fit options, warm start) of one candidate: :data:`NOISE_DECLARED` for a model that
    declares its noises when the given method is not already PEM, else the given ones."""
    opts = dict(fit_options or {})
    if not declares_noises(model) or opts.get("method") == "pem":
        return opts, warm_start
    opts = {k: v for k, v in opts.items() if not k.startswith("oe_")}
    opts["method"] = NOISE_DECLARED["method"]
    return opts, NOISE_DECLARED["warm_start"]


def score(model, cv: CrossValidation, seconds: float = math.nan) -> CandidateScore:
    """One candidate's row from its cross-validation (its first start design)."""
    from acid.models import load

    m = load(model)
    iv = cv.intervals[0]
    verdicts: dict = {}
    for v in iv.verdicts:
        if v.scope == "pooled":
            verdicts.setdefault(v.yardstick, {})[f"{v.time_s:g}"] = (
                v.verdict, v.difference, v.lo, v.hi)
    return CandidateScore(m.name, sum(not p.fixed for p in m.parameters), len(m.states),
                          tuple(f for f in iv.figures if f.scope == "pooled"
                                and f.predictor == "model"), verdicts,
                          tuple(cv.parameters()), float(seconds), cv)


def assemble(runs: Sequence[tuple], rule_time_s: float = 600.0) -> StructureSelection:
    """The selection from ``runs`` [(model, CrossValidation, seconds)], the candidates'
    cross-validations on the same folds (checked), e.g. run apart and read back with
    ``CrossValidation.from_dict``; the yardsticks from the first."""
    if len(runs) < 2:
        raise DataError("structure selection needs at least 2 candidate structures")
    folds = [tuple(tuple(f["held_out"]) for f in cv.folds) for _, cv, _ in runs]
    if len(set(folds)) != 1:
        raise DataError("the candidates' cross-validations were not run on the same folds")
    scores = tuple(score(m, cv, sec) for m, cv, sec in runs)
    first = runs[0][1]
    pooled = [f for f in first.intervals[0].figures if f.scope == "pooled"]
    yard = {y: tuple(f for f in pooled if f.predictor == y) for y in YARDSTICKS
            if any(f.predictor == y for f in pooled)}
    best, chosen = choose(scores, rule_time_s)
    settings = {"fit_options": dict(first.fit_options), "folds": len(first.folds),
                **first.settings}
    return StructureSelection(scores, yard, folds[0], float(rule_time_s), best, chosen,
                              settings)
