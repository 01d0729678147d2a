"""``acid fit|validate --model FILE.py``: the declared-model branches (``acid.models``,
``acid.ident``): option parsing, tables, files."""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path

from acid import __version__
from acid._io import file_sha256
from acid.data import MODEL_CHANNELS, Dataset
from acid.errors import ConfigError
from acid_cli._common import (
    chained_steps,
    note,
    print_table,
    progress_bar,
    require_range,
    say,
    warn,
    write_summary,
)

#: Largest --fit-starts accepted.
MAX_STARTS = 1000


#: Built-in declarations that ``--model`` names directly (``paper`` and ``econ`` name the
#: model families of ``acid fit``; their declarations are loaded by path or through Python).
DECLARED_NAMES = ("cabin3", "car_cabin", "heating")


def is_model_file(spec: str | None) -> bool:
    """Whether ``--model`` names a declared model (a file FILE.py or a built-in declaration
    such as ``car_cabin``: the declared path) rather than a family."""
    return spec is not None and (str(spec).endswith(".py") or str(spec) in DECLARED_NAMES)


def model_file_input(spec: str) -> str | None:
    """The ``--model`` value as a file to check (None for a built-in name)."""
    return spec if str(spec).endswith(".py") else None


def _num(v, digits: int = 5) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.{digits}g}"


def parse_fix(items: list[str] | None) -> dict[str, float]:
    """``--fix NAME=VALUE`` options as {name: value} (one line naming the bad one)."""
    out: dict[str, float] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        try:
            v = float(value)
        except ValueError:
            v = math.nan
        if not sep or not name.strip() or not math.isfinite(v):
            raise ConfigError(f"--fix {item!r}: expected NAME=VALUE with a finite number")
        _once(out, name.strip(), "--fix", item)
        out[name.strip()] = v
    return out


def _once(seen, name: str, option: str, item: str) -> None:
    if name in seen:
        raise ConfigError(f"{option} {item!r}: {name!r} is given twice; give each parameter "
                          "once")


#: Largest prior standard deviation, in the parameter's unit (its square must stay finite).
MAX_PRIOR_SD = 1e100


def check_priors(model, priors: dict[str, tuple[float, float]]) -> None:
    """Each ``--prior`` names a parameter of ``model``, its mean lies within the parameter's
    declared bounds and its SD is at most ``MAX_PRIOR_SD``: else one line naming it."""
    check_named(model, "--prior", priors)
    for name, (mean, sd) in priors.items():
        p = model.parameter(name)
        if not p.min <= mean <= p.max:
            raise ConfigError(f"--prior {name}={mean:g},{sd:g}: the mean lies outside "
                              f"{name}'s declared bounds [{p.min:g}, {p.max:g}]")
        if sd > MAX_PRIOR_SD:
            raise ConfigError(f"--prior {name}={mean:g},{sd:g}: SD above {MAX_PRIOR_SD:g} (no "
                              "prior at all: leave --prior out)")


def check_named(model, option: str, names) -> None:
    """Each of ``names`` (given with ``option``) is a parameter of ``model``: else one line
    naming the option (rather than the model file's own complaint)."""
    known = set(model.parameter_names)
    for name in names:
        if name not in known:
            listed = ", ".join(model.parameter_names)
            raise ConfigError(f"{option} {name!r}: not a parameter of model {model.name!r} "
                              f"(parameters: {listed[:300]}{'...' if len(listed) > 300 else ''})")


def parse_prior(items: list[str] | None) -> dict[str, tuple[float, float]]:
    """``--prior NAME=MEAN,SD`` options as {name: (mean, sd)} (one line naming the bad one)."""
    out: dict[str, tuple[float, float]] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        try:
            mean, sd = (float(v) for v in value.split(","))
        except ValueError:
            mean = sd = math.nan
        if not sep or not name.strip() or not (math.isfinite(mean) and math.isfinite(sd)
                                                 and sd > 0):
            raise ConfigError(f"--prior {item!r}: expected NAME=MEAN,SD with finite numbers "
                              "in the parameter's unit and SD > 0")
        _once(out, name.strip(), "--prior", item)
        out[name.strip()] = (mean, sd)
    return out


@dataclasses.dataclass(frozen=True)
class PaperOptions:
    """What ``acid fit --model paper`` adds: the reference values (``--reference``: shown
    beside ours, where output error starts, what collinear parameters stay closest to),
    ``--no-blower`` (beta held at them) and ``--use-eta-cop`` (eq. 4's COP read off P_comp
    into the file)."""

    reference: str = "paper"
    no_blower: bool = False
    use_eta_cop: bool = False


def _check_one_step_finite(model, ds) -> None:
    """Refuse a fully measured model whose step at the declared values is NaN or inf for a
    state from every sample of the data (an equation outside its domain wherever the data
    go): every method would otherwise fail inside (least squares' SVD) or, a filter skipping
    the non-finite innovations, report parameters the data never saw (prediction error)."""
    import numpy as np

    from acid.ident.data import ModelData

    if not all(s.measured for s in model.states):
        return   # latent states have no data to step from: the fit's own checks apply
    data = ModelData.of(model, ds)
    rows = np.isfinite(data.x).all(axis=1) & np.isfinite(data.u).all(axis=1) \
        & np.isfinite(data.d).all(axis=1)
    if not rows.any():
        return
    with np.errstate(all="ignore"):
        xn, _ = model.step(data.x[rows], data.u[rows], data.d[rows])
    dead = ~np.isfinite(xn).any(axis=0)
    if dead.any():
        name = model.state_names[int(np.flatnonzero(dead)[0])]
        raise ConfigError(f"{Path(model.source).name}: model {model.name!r}: the step gives "
                          f"NaN or inf for state {name!r} from every sample of {ds.source} at "
                          "the declared values: an equation outside its domain (log or sqrt "
                          "of a negative number, a division by zero) wherever the data go")


def fit_declared(data: Path, model_file: str, out: Path, json_path: Path | None, *,
                 method: str, fix: list[str] | None, free: list[str] | None, fit_starts: int,
                 seed: int, oe_window: int, covariance: str, bandwidth,
                 estimation_fraction: float, more: list[Path] = (), loss: str = "squared",
                 strict: bool = False, oe_estimate_x0: bool = True,
                 paper: PaperOptions | None = None, max_evals: int = 100,
                 oe_solver: str = "dense", prior: list[str] | None = None,
                 prior_weight: float = 1.0) -> None:
    """Fit the model declared in ``model_file`` to ``data``; print the report, write ``out``
    (for the paper's model, ``paper``: also the params.json keys the controllers read)."""
    from acid.ident.fit import METHODS, fit_model, provenance
    from acid.ident.result import unit_squared
    from acid.models import load

    if method not in METHODS:
        raise ConfigError(f"--method must be one of {', '.join(METHODS)} for a model file, "
                          f"got {method!r}")
    require_range(fit_starts, "--fit-starts", 1, MAX_STARTS)
    model = load(model_file)
    fixes = parse_fix(fix)
    priors = parse_prior(prior)
    for option, names in (("--fix", fixes), ("--free", free or ())):
        check_named(model, option, names)
    check_priors(model, priors)
    if priors:
        model = model.with_priors(priors)
    start, ref = None, None
    if paper is not None:
        from acid.models.params import load_params

        ref = load_params(paper.reference, allow_unstable=True)
        start = ref.as_dict()
        if paper.no_blower:
            fixes = {**{n: start[n] for n in ("beta1", "beta2", "beta3")}, **fixes}
    # the paper's fit needs every channel of eqs. 1-3 (T_ain too: eq. 1 reads it measured)
    need = {"require": MODEL_CHANNELS} if paper is not None else {}
    ds = Dataset.from_hdf5(data, min_samples=20, **need)
    est = ds if estimation_fraction == 1.0 else ds.split(estimation_fraction)[0]
    if more:
        parts = [Dataset.from_hdf5(p, min_samples=20, **need) for p in more]
        parts = [p if estimation_fraction == 1.0 else p.split(estimation_fraction)[0]
                 for p in parts]
        est = Dataset.concatenate([est, *parts])
        est.source = str(data)
    _check_one_step_finite(model, est)
    with progress_bar(f"fit {model.name}", None) as update:
        result = fit_model(model, est, method, fix=fixes, free=tuple(free or ()),
                           fit_starts=fit_starts, seed=seed, oe_window=oe_window,
                           covariance=covariance, hac_bandwidth=bandwidth, loss=loss,
                           oe_estimate_x0=oe_estimate_x0, start=start, strict=strict,
                           max_nfev=max_evals, oe_solver=oe_solver,
                           prior_weight=prior_weight, progress=update)
    prov = provenance(ds, result.method, loss)
    prov.update(estimation_fraction=estimation_fraction, model_file=str(model_file),
                prior_weight=prior_weight,
                records=[str(data), *map(str, more)])
    fitted = model.with_parameters(fixes, tuple(free or ()))
    extra, params = _paper_file(result, est, prov, paper) if paper else ({}, None)
    result.write(out, fitted, prov, extra=extra)

    say(f"{data}{' and ' + str(len(more)) + ' more record(s)' if more else ''}: "
        f"{len(est)} samples, {len(result.experiment_ids)} experiment(s), model "
        f"{model.name!r} ({model_file}), method {result.method}, covariance "
        f"{result.covariance_kind} "
        f"({result.elapsed_s:.1f} s)")
    ids = result.experiment_ids
    rows = [[e.name if e.experiment is None else f"{e.name} [exp {ids[e.experiment]}]",
             e.unit, _num(e.declared), _num(e.value), _num(e.stderr, 2),
             "-" if not math.isfinite(e.ci95[0]) else f"[{_num(e.ci95[0])}, {_num(e.ci95[1])}]",
             e.status] for e in result.estimates]
    beside = paper.reference if paper else "declared"
    if paper and math.isfinite(extra["eta_cop_estimate"]["value"]):
        eta, se = extra["eta_cop_estimate"]["value"], extra["eta_cop_estimate"]["stderr"]
        rows.append(["eta_cop", "1", _num(ref.eta_cop), _num(eta), _num(se, 2),
                     f"[{_num(eta - 1.96 * se)}, {_num(eta + 1.96 * se)}]",
                     "eq. 4, " + ("in params" if paper.use_eta_cop else "not used")])
    print_table(f"Parameters of {model.name!r}, {beside} beside fitted",
                ["name", "unit", beside, "estimate", "stderr", "95 % interval", "status"],
                rows)
    eq_rows = [[q.name, q.method, "-" if q.rank is None else f"{q.rank}/{q.n_columns}",
                _num(q.condition, 3), _num(q.residual_std, 3), _num(q.fit_percent, 4),
                _num(q.residual_acf1, 2), _num(q.ljung_box_p, 2),
                q.reason or ", ".join(q.parameters)] for q in result.equations]
    if eq_rows:
        print_table("Equations: how each was fitted (ls: equation-error least squares), rank, "
                    "condition, residual std, one-step fit %, residual lag-1 autocorrelation "
                    "and Ljung-Box p (20 lags)",
                    ["equation", "fit", "rank", "cond", "resid", "fit %", "acf1", "LB p",
                     "parameters / why not ls"], eq_rows)
    oe = result.output_error
    if oe and result.method == "pem":
        one = ", ".join(f"{c} {v:.2f} %" for c, v in oe["one_step_fit_percent"].items())
        say(f"prediction error: {oe['records']} records, objective {oe['loss']:.6g}, "
            f"{oe['nfev']} evaluations, {oe['status']}; one-step fit {one}, normalised "
            f"innovations' std {oe['normalised_innovation_std']:.3f} (1 when the filter's "
            "noises are consistent)")
    elif oe:
        sim = ", ".join(f"{c} {v:.2f} %" for c, v in oe["channel_fit_percent"].items())
        say(f"output error: {oe['windows']} windows of <= {oe['window']} samples, objective "
            f"{oe['loss']:.6g} (each channel weighted by its error scale), "
            f"{str(oe['status']).rstrip('. ')}; simulation fit {sim}")
    if len(result.optima) > 0:
        print_table(f"Distinct optima of {fit_starts} starts (best first): objective, starts that "
                    "reached it, largest parameter spread among those starts, and the "
                    "parameters farthest from the best optimum (relative)",
                    ["objective", "starts", "spread", "differs most from the best in"],
                    _optima_rows(result.optima))
    if result.failed_starts:
        print_table(f"Failed starts of {fit_starts} (no optimum reached; not among the optima "
                    "above): start number (0: the first start), final objective and why",
                    ["start", "objective", "why"],
                    [[str(f.start), _num(f.loss, 3), f.reason] for f in result.failed_starts])
    if result.on_bounds:
        say("on a declared bound (the data push past it; its interval is not reliable): "
            + "; ".join(result.on_bounds))
    for c in result.combinations:
        say(f"identified combination: {c}")
    if result.simulation_fit:
        latent = [s.name for s in result.declaration.states if not s.measured] \
            if result.declaration is not None else []
        say(f"{oe_window}-step simulation fit from measured states"
            + (f" ({', '.join(latent)} as the output-error fit estimated them)"
               if latent and result.output_error else "") + ": " + ", ".join(
            f"{c} {v:.2f} %" for c, v in result.simulation_fit.items()))
    if result.channel_mse:
        say(f"mean squared error per channel ({result.mse_scored}; comparable across models "
            "on the same data, unlike the objective), NMSE = MSE / the channel's variance: "
            + ", ".join(f"{c} {v['mse']:.4g} {unit_squared(v['unit'])} (NMSE {v['nmse']:.4g})"
                        for c, v in result.channel_mse.items()))
    for line in result.notes:
        note(line)
    for line in result.warnings:
        warn(line)
    for line in params.stability_problems() if params else ():
        warn(f"{out}: the fitted {line}; acid validate and mpc-check refuse these parameters "
             "without --allow-unstable")
    say(f"parameters written to {out}")
    write_summary(json_path, {"command": "fit", "acid_version": __version__,
                              "inputs": {"data": str(data), "model": str(model_file),
                                         **({"reference": paper.reference} if paper else {})},
                              "estimation_fraction": estimation_fraction, "out": str(out),
                              **({"params": params.to_json_dict()} if params else {}),
                              **result.to_json_dict()})


def _paper_file(result, est: Dataset, prov: dict, paper: PaperOptions):
    """The params.json keys of the paper's model (``acid.models.params.ModelParams``, what the
    controllers read) and eq. 4's COP read off P_comp, beside the declared parameter file."""
    from acid.models.params import eta_cop_of, fitted

    eta, se = eta_cop_of(est)
    params = fitted(result, eta_cop=eta if paper.use_eta_cop else None,
                    provenance={**prov, "reference": paper.reference})
    return {**params.to_json_dict(),
            "eta_cop_estimate": {"value": eta, "stderr": se}}, params


def _optima_rows(optima, show: int = 3) -> list[list[str]]:
    """Rows of the distinct-optima table: the full values and spreads are in the JSON."""
    best = optima[0].values
    rows = []
    for o in optima:
        rel = {k: abs(v - best[k]) / max(abs(best[k]), 1e-12) for k, v in o.values.items()}
        far = sorted(rel, key=rel.get, reverse=True)[:show]
        spread = max(o.spread.items(), key=lambda kv: kv[1] / max(abs(o.values[kv[0]]),
                                                                   1e-12))
        rows.append([f"{o.loss:.6g}", str(o.n_starts),
                     f"{spread[0]} +/-{_num(spread[1], 2)}" if o.n_starts > 1 else "-",
                     "(best)" if o is optima[0] else ", ".join(
                         f"{k} {_num(o.values[k], 4)} (best {_num(best[k], 4)})"
                         for k in far)])
    return rows


def validate_declared(data: Path, model_file: str, params: str, json_path: Path | None, *,
                      starts: int, horizon: int, warmup: float, placement: str, seed: int,
                      held_out_fraction: float | None, hold_all: bool = False,
                      non_overlapping: bool = False, yardsticks: bool = True,
                      to_end: bool = False, warm_start: str = "fit", values=None,
                      beside=None, figures: Path | None = None,
                      intervals: tuple | None = None) -> None:
    """Validate the model declared in ``model_file`` on ``data``; print the errors, write
    Figs. 5-6 (and the yardsticks' figure) into ``figures``. ``values``: the parameters
    (``ParameterValues``) when already read (the paper's and the econ model's files);
    ``beside``: other ``ParameterValues``, validated on the same starts. ``intervals``:
    (designs, resamples): bootstrap intervals and verdicts (``acid.ident.crossval``) for
    each start design."""
    from acid.ident.validate import (
        declared_parameters,
        held_out_part,
        read_parameters,
        validate_model,
        window_design_text,
    )
    from acid.models import load
    from acid_cli._residuals import residual_section, residual_tests

    model = load(model_file)
    ps = values if values is not None else declared_parameters(model) \
        if params == "paper" else read_parameters(model, params)
    ds = Dataset.from_hdf5(data, min_samples=2)
    sha = file_sha256(data)
    record, offset = _record_of(ps.provenance, data, sha)
    prov = ps.provenance if record is None else {**ps.provenance, "data_sha256": sha}
    part = held_out_part(prov, str(data), sha, held_out_fraction)
    if part.warning:
        warn(part.warning)
    frac = part.fraction
    own = sorted(set(ds.experiment.tolist()))
    if ps.per_experiment and record is None:
        ps = ps.replace(per_experiment={})
        note("per-experiment parameters were fitted on another record: their mean is used")
    lo = int(round(len(ds) * (1.0 - frac))) if frac is not None and frac < 1.0 else 0
    hi, estimation = len(ds), ((0, lo) if lo > 0 else None)
    est = _fit_records(ps, sha) if yardsticks else None
    base = 0
    if est is not None:
        # the yardsticks are fitted on the records the parameters were fitted on (their
        # estimation part; not DATA itself), placed before DATA; the starts stay in DATA
        n_est = len(est)
        base = len(set(est.experiment.tolist()))
        ds = Dataset.concatenate([est, ds])
        lo, hi, estimation = n_est + lo, n_est + hi, (0, n_est)
    if ps.per_experiment and record is not None:
        # this record's own per-experiment values: the fit numbered the experiments of its
        # records in turn; DATA's k-th experiment is the fit's offset + k, here base + k
        ids = own if est is None else range(base, base + len(own))
        ps = ps.replace(per_experiment={
            n: {int(e): t[offset + k] for k, e in enumerate(ids) if offset + k in t}
            for n, t in ps.per_experiment.items()})
        note(f"per-experiment parameters: this record's own values (record {record + 1} "
             "of the fit)")
    kw = {"starts": starts, "horizon": horizon, "warmup": warmup, "placement": placement,
          "seed": seed, "non_overlapping": non_overlapping, "start_range": (lo, hi),
          "hold": tuple(d.name for d in model.disturbances) if hold_all else (),
          "to_end": to_end, "warm_start": warm_start}
    # the work first, with its progress (a bar on a terminal: nothing else is printed while
    # it moves), then the report
    with progress_bar(f"validate {model.name}", None) as update:
        library, step = chained_steps(update, after=2 + (beside is not None))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = validate_model(model, ds, ps, yardsticks=yardsticks,
                                 estimation=estimation, progress=library, **kw)
        other = None
        if beside is not None:
            other_model = beside.declaration   # e.g. the paper's beside the econ model
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the same windows: warned about below
                other = validate_model(other_model, ds, beside, **{
                    **kw, "start_index": res.starts, "non_overlapping": False,
                    "yardsticks": False,
                    "hold": tuple(d.name for d in other_model.disturbances)
                    if hold_all else ()})
            step(f"beside: {beside.label} validated on the same starts")
        residuals = residual_tests(ds, (model, ps), lo, len(ds))
        step("one-step residuals tested")
        saved = _save_figures(res, figures)
        step(f"{len(saved)} figures drawn" if saved else "no figures (no temperature)")
    for w in caught:
        warn(w.message)
    if est is not None:
        note(f"yardsticks fitted on the parameters' records ({est.source})")
    say(f"{data}: {res.starts.size} starts x {horizon} steps ({horizon * model.Ts:g} s), model "
        f"{model.name!r}, parameters from {ps.label}"
        + (f", last {100 * frac:g} % of the record ({part.source})" if frac is not None
           and frac < 1 else ""))
    say(window_design_text(res.window_design))
    print_table("Open-loop prediction error, all starts and steps 1 .. horizon",
                ["channel", "unit", "RMSE", "median |e|", "p90 |e|", "p95 |e|", "max |e|",
                 "fit %", "fit % pooled"],
                [[c, u, *[_num(res.metrics[c][k], 3) for k in
                          ("rmse", "median_abs", "p90_abs", "p95_abs", "max_abs")],
                  _num(res.metrics[c]["fit_percent"], 4),
                  _num(res.metrics[c]["fit_percent_pooled"], 4)]
                 for c, u in zip(res.channels, res.units, strict=True)])
    if res.energy:
        print_table("Energy of each window: |error| (% of the measured)",
                    ["channel", "median", "p90", "max", "bias %"],
                    [[c, *[_num(e[k], 3) for k in ("median_abs", "p90_abs", "max_abs",
                                                    "bias_pct")]]
                     for c, e in res.energy.items()])
    _print_horizon_table(res)
    for line in res.notes:
        # the window design line above already says these two
        if not line.startswith(("window design:", "held at their start values:")):
            note(line)
    if yardsticks and estimation is None:
        note(f"ARX and subspace fitted on samples 0..{len(ds) - 1}, the validated samples "
             "themselves (no held-out part): in-sample, they are favoured; yardsticks are "
             "never used for control")
    elif yardsticks:
        say(f"  ARX and subspace fitted on samples {estimation[0]}..{estimation[1] - 1} (the "
            "estimation part); yardsticks are never used for control")
    if other is not None:
        print_table(f"Beside: |e| median / p90, {ps.label!r} vs {beside.label!r}, same starts",
                    ["channel", "this", "beside"],
                    [[c, f"{_num(res.metrics[c]['median_abs'], 3)} / "
                         f"{_num(res.metrics[c]['p90_abs'], 3)}",
                      f"{_num(other.metrics[c]['median_abs'], 3)} / "
                      f"{_num(other.metrics[c]['p90_abs'], 3)}"]
                     for c in res.channels if c in other.metrics])
    residuals = residual_section(residuals)
    ivs = _intervals(res, ds, model, ps, kw, estimation, yardsticks, intervals)
    if saved:
        say(f"figures written to {', '.join(saved.values())}")
    write_summary(json_path, {"command": "validate", "acid_version": __version__,
                              "inputs": {"data": str(data), "data_sha256": sha,
                                         "model": str(model_file), "params": params},
                              "held_out_fraction_source": part.source,
                              "in_sample_warning": part.warning, "figures": saved,
                              **res.to_json_dict(), "residuals": residuals,
                              **({"intervals": [iv.to_dict() for iv in ivs]} if ivs else {}),
                              **({"beside": {"channels": other.to_json_dict()["channels"]}}
                                 if other is not None else {})})


def horizon_columns(res) -> list[int]:
    """The prediction steps ``acid validate`` tabulates: the first, each of
    ``REPORT_TIMES_S`` inside the horizon, and the horizon (every step is in --json)."""
    from acid.ident.validate import REPORT_TIMES_S

    return sorted({1, res.horizon, *[int(round(t / res.Ts)) for t in REPORT_TIMES_S
                                     if 1 <= int(round(t / res.Ts)) <= res.horizon]})


def _print_horizon_table(res) -> None:
    """One table of the errors vs prediction time: a row per channel and predictor (the
    model, then each yardstick on the same windows), RMSE / p90 |e| at ``horizon_columns``;
    a cell whose step fewer starts reach than were placed says how many, in brackets."""
    steps, cols = res.by_step(), horizon_columns(res)

    def cell(s, h):
        n = s["n"][h - 1]
        return (f"{_num(s['rmse'][h - 1], 3)} / {_num(s['p90_abs'][h - 1], 3)}"
                + (f" ({n})" if n != res.n_starts else ""))

    rows = []
    for c in res.channels:
        who = [w for w in steps if c in steps[w]]
        rows += [[c if i == 0 else "", w, *[cell(steps[w][c], h) for h in cols]]
                 for i, w in enumerate(who)]
    title = (f"Error vs prediction time: RMSE / p90 |e|, {res.n_starts} starts"
             + (", the yardsticks on the same windows" if res.yardsticks else ""))
    print_table(title, ["_channel", "_predictor",
                        *[f"{h * res.Ts:g} s" for h in cols]], rows)
    for y in res.yardsticks.values():
        say(f"  {y['description']}")


def _intervals(res, ds, model, ps, kw, estimation, yardsticks, intervals) -> list:
    """--intervals: the validation ``res`` and, for each further start design, the same
    validation re-placed, with their bootstrap intervals and verdicts, printed."""
    if intervals is None:
        return []
    from acid.ident.crossval import design_options, validation_intervals
    from acid.ident.validate import validate_model

    designs, resamples = intervals
    out = []
    for d in designs:
        opts = design_options(d)
        same = (opts["placement"] == kw["placement"]
                and opts["non_overlapping"] == kw["non_overlapping"])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = res if same else validate_model(model, ds, ps, yardsticks=yardsticks,
                                                estimation=estimation, **{**kw, **opts})
        iv = validation_intervals(r, ds, n_resamples=resamples, seed=kw["seed"], design=d)
        say(iv.summary())
        out.append(iv)
    _say_robust(out)
    return out


def _say_robust(ivs) -> None:
    """Whether each pooled verdict is the same under every start design."""
    if len(ivs) < 2:
        return
    from acid.ident.crossval import CrossValidation

    cv = CrossValidation(ivs[0].model, ivs[0].channel, {}, (), tuple(ivs))
    say("Pooled verdicts across start designs:")
    for y, d in cv.robust.items():
        for t, v in d.items():
            say(f"  vs {y} at {t} s: {v}")


def cross_validate_declared(data: Path, model_file: str, json_path: Path | None, *,
                            starts: int, horizon: int, warmup: float, seed: int, designs,
                            folds: int | None, hold_all: bool, to_end: bool,
                            warm_start: str, resamples: int, method: str,
                            max_evals: int, prior: list[str] | None = None) -> None:
    """``acid validate --cv experiments``: leave-experiments-out cross-validation of the
    declared model (``acid.ident.crossval.cross_validate``), printed and in --json."""
    from acid.ident.crossval import cross_validate
    from acid.ident.fit import METHODS
    from acid.models import load

    if method not in METHODS:
        raise ConfigError(f"--method must be one of {', '.join(METHODS)}, got {method!r}")
    require_range(max_evals, "--max-evals", 1, 100_000)
    if folds is not None:
        require_range(folds, "--cv-folds", 2, 100_000)
    model = load(model_file)
    priors = parse_prior(prior)
    check_priors(model, priors)
    if priors:
        model = model.with_priors(priors)
    ds = Dataset.from_hdf5(data, min_samples=2)
    with progress_bar(f"cross-validate {model.name}", None) as update:
        cv = cross_validate(model, ds, fit_options={"method": method, "max_nfev": max_evals},
                            folds=folds, designs=designs, starts=starts, horizon=horizon,
                            warmup=warmup, exogenous="hold" if hold_all else "measured",
                            to_end=to_end, warm_start=warm_start, n_resamples=resamples,
                            seed=seed, progress=update)
    say(cv.summary())
    write_summary(json_path, {"command": "validate", "acid_version": __version__,
                              "inputs": {"data": str(data), "data_sha256": file_sha256(data),
                                         "model": str(model_file)},
                              "cross_validation": cv.to_dict()})


def _save_figures(res, figures: Path | None) -> dict[str, str]:
    """Figs. 5-6 of the validation ``res`` (and the yardsticks' figure) into ``figures``,
    when it has temperatures to draw: ``{name: path}``."""
    if figures is None or "K" not in res.units:     # the figures draw temperatures
        return {}
    from acid._io import save_figure
    from acid.report.validation import error_figure, prediction_figure, yardstick_figure

    draw = {"fig5_prediction": prediction_figure, "fig6_errors": error_figure,
            **({"fig6b_yardsticks": yardstick_figure} if res.yardsticks else {})}
    return {k: str(save_figure(f(res), figures / f"{k}.png")) for k, f in draw.items()}


def _record_of(provenance: dict, data: Path, data_sha: str) -> tuple[int | None, int]:
    """Which of the fit's records ``data`` is (its index in ``provenance["records"]``, None
    when none) and how many experiments the records before it hold (the fit numbered its
    experiments record after record)."""
    if provenance.get("data_sha256") == data_sha:
        return 0, 0
    records = [Path(r) for r in provenance.get("records") or []]
    offset = 0
    for i, r in enumerate(records):
        if not r.is_file():
            return None, 0
        if i > 0 and file_sha256(r) == data_sha:
            return i, offset
        part = Dataset.from_hdf5(r, min_samples=2)
        offset += len(set(part.experiment.tolist()))
    return None, 0


def _fit_records(ps, data_sha: str) -> Dataset | None:
    """The records the parameters were fitted on (their provenance), when they are not the
    validation data and are all here: the yardsticks' estimation data."""
    records = [Path(r) for r in ps.provenance.get("records") or []]
    if not records or not all(r.is_file() for r in records):
        return None
    frac = ps.provenance.get("estimation_fraction")
    split = isinstance(frac, (int, float)) and 0.0 < float(frac) < 1.0
    if not split:
        # fitted on whole records: never DATA itself (its validation is in-sample anyway)
        if ps.provenance.get("data_sha256") == data_sha:
            return None
        records = [r for r in records if file_sha256(r) != data_sha]
        if not records:
            return None
    # fitted on the first F of each record: the yardsticks on exactly those samples, DATA's
    # own estimation part included (its held-out part is what is scored)
    parts = [Dataset.from_hdf5(r, min_samples=2) for r in records]
    if split:
        parts = [p.split(float(frac))[0] for p in parts]     # their estimation part only
    est = parts[0] if len(parts) == 1 else Dataset.concatenate(parts)
    est.source = ", ".join(map(str, records)) + (f" (the first {100 * float(frac):g} % of "
                                                 "each)" if split else "")
    return est
