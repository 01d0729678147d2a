"""Fit any declared model (``acid.models``) to a dataset: ``fit_model(model, ds, ...)``.

Methods
-------
``"ls"``   equation-error least squares on every equation that allows it (``acid.ident.
           linear``: target measured, no latent state read, linear in its free parameters,
           detected with CasADi); the report names those equations. Parameters only other
           equations read keep their declared values ("not fitted").
``"cvx"``  the same regressions with the declared bounds (CVXPY) where the unconstrained
           solution leaves them.
``"oe"``   output error (``acid.ident.oe``) over all free parameters, latent initial states
           included, started from the least-squares estimates where there are any.
``"pem"``  prediction error (``acid.ident.pem``): an extended Kalman filter over each whole
           experiment, latent states and random-walk loads followed by the filter.
``"auto"`` (default) ``"ls"`` when least squares reaches every free parameter and no state is
           latent, else ``"oe"``.

Standard errors: ``"hac"`` (default, Newey-West sandwich, lags inside experiments) or
``"white"``; 95 % t-intervals. ``fit_starts = N`` runs output error from N - 1 more starts
drawn inside the bounds (a seeded ``numpy.random.Generator``) and reports the distinct
optima with their loss and parameter spread. ``fix`` / ``free`` change the table for one
fit; per-experiment parameters get one value per experiment.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from acid import __version__
from acid._blas import fixed_blas
from acid._io import file_sha256
from acid.data import Dataset
from acid.errors import ConfigError, DataError
from acid.ident import hac, linear, oe
from acid.ident.data import ModelData
from acid.ident.prior import weighted
from acid.ident.result import (  # noqa: F401 (the fit's result types, read from here too)
    DeclaredFitResult,
    EquationReport,
    Estimate,
    FailedStart,
    Optimum,
)
from acid.models.declaration import Model
from acid.models.loader import load

METHODS = ("auto", "ls", "cvx", "oe", "pem")
COVARIANCES = ("hac", "white")
#: The default of ``fit_model(covariance=...)`` and ``acid fit --covariance``.
DEFAULT_COVARIANCE = "hac"
LOSSES = ("squared", "huber")
#: Output-error solvers: "dense" (scipy's least squares over the windows with CasADi's
#: Jacobian) or "ms" (one sparse multiple-shooting NLP by IPOPT, linear in the data).
OE_SOLVERS = ("dense", "ms")


#: A start whose simulation error (RMS, a channel's own units) ends above this many times
#: the channel's standard deviation in the data diverged, even when its solver stopped
#: cleanly (a model that predicts the channel's mean is 1).
DIVERGED_ERROR_RATIO = 100.0


# -------------------------------------------------------------------------- fitter
@hac.warnings_as_note
@fixed_blas
def fit_model(model: Model | str, ds: Dataset, method: str = "auto", *,
              fix: dict | None = None, free: tuple[str, ...] = (), fit_starts: int = 1,
              seed: int = 0, oe_window: int = 300, covariance: str = "hac",
              hac_bandwidth="auto", solver: str | None = None,
              max_nfev: int = 100, loss: str = "squared", oe_estimate_x0: bool = True,
              start: dict | None = None, strict: bool = False,
              oe_solver: str = "dense", prior_weight: float = 1.0,
              progress=None) -> DeclaredFitResult:
    """Fit ``model`` (a ``Model`` or a name/path for :func:`acid.models.load`) to ``ds``.

    See the module docstring for the methods. ``fix`` {name: value} and ``free`` (names)
    change the declared table for this fit; ``start`` {name: value} replaces declared
    values (where output error starts, what a collinear set stays closest to) without
    fixing them. ``loss="huber"``: robust to outliers (equation error by CVXPY, output
    error by scipy's Huber loss). ``prior_weight``: every declared prior's information
    scaled by it (0: no priors, 1: as declared). ``oe_estimate_x0=False``: output-error
    windows start from the measured states (latent ones are still estimated). ``strict``:
    a parameter the data do not separate from another is an error, not a reported
    combination. ``progress``:
    called as ``progress(evaluations, None, label)`` while the optimiser runs (output error
    and prediction error), the label naming the start, the pass and the loss.
    """
    t0 = time.perf_counter()
    model = load(model)
    if method not in METHODS:
        raise ConfigError(f"unknown method {method!r} (choose from {', '.join(METHODS)})")
    if loss not in LOSSES:
        raise ConfigError(f"unknown loss {loss!r} (choose from {', '.join(LOSSES)})")
    if oe_solver not in OE_SOLVERS:
        raise ConfigError(f"unknown output-error solver {oe_solver!r} (choose from "
                          f"{', '.join(OE_SOLVERS)})")
    if oe_solver == "ms" and loss != "squared":
        raise ConfigError("the multiple-shooting output error (oe_solver 'ms') minimises "
                          "the squared loss only; use the dense solver with loss 'huber'")
    bw = hac_bandwidth
    if not (bw in ("auto", "nw") or (isinstance(bw, (int, np.integer))
                                     and not isinstance(bw, bool) and bw >= 0)):
        raise ConfigError(f"hac_bandwidth must be 'auto', 'nw' or an integer >= 0, got {bw!r}")
    if int(oe_window) < 5:
        raise ConfigError(f"oe_window must be at least 5 samples, got {oe_window}")
    if covariance not in COVARIANCES:
        raise ConfigError(f"unknown covariance {covariance!r} (choose from "
                          f"{', '.join(COVARIANCES)})")
    if int(fit_starts) < 1:
        raise ConfigError(f"fit_starts must be at least 1, got {fit_starts}")
    if int(fit_starts) > 1 and method in ("ls", "cvx"):
        raise ConfigError(f"--fit-starts {fit_starts}: the starts are output-error starts; "
                          f"use --method oe (or auto), not {method}")
    if fix or free:
        model = model.with_parameters(fix, tuple(free))
    if start:
        model = _with_values(model, start)
    model = weighted(model, prior_weight)
    priors = [p.name for p in model.parameters if p.prior is not None and not p.fixed]
    if priors and method in ("ls", "cvx") and loss == "huber":
        raise ConfigError(f"--method {method} --loss huber: the priors on "
                          f"{', '.join(priors)} are honoured by the squared loss")
    if method == "pem":
        from acid.ident.pem import fit_pem

        res = fit_pem(model, ds, fix=fix, max_nfev=max_nfev, t0=t0,
                      progress=_labelled(progress, "prediction error"))
        if int(fit_starts) > 1:
            res = _pem_starts(model, ds, res, int(fit_starts), seed, fix, max_nfev, t0,
                              progress)
        return dataclasses.replace(res, channel_mse=_one_step_mse(model, res.output_error))
    data = ModelData.of(model, ds)
    E = data.n_experiments
    names = model.parameter_names
    free_idx = tuple(i for i, p in enumerate(model.parameters) if not p.fixed)
    per_exp = {i for i, p in enumerate(model.parameters) if p.per_experiment}
    forms = linear.equation_forms(model, data, free_idx)
    # a parameter read only by outputs the data lack cannot be fitted: kept as declared
    unseen = sorted(set(free_idx) - {i for f in forms for i in f.free
                                     if not (f.name in model.output_names
                                             and f.reason.endswith("is not measured"))})
    free_idx = tuple(i for i in free_idx if i not in unseen)
    columns = tuple(c for i in free_idx for c in (
        [linear.Column(i, names[i], e) for e in range(E)] if i in per_exp
        else [linear.Column(i, names[i])]))
    declared = model.values
    theta = np.array([declared[c.index] for c in columns])          # free columns
    status = ["not fitted"] * len(columns)
    stderr = np.full(len(columns), np.nan)
    cov = np.full((len(columns), len(columns)), np.nan)
    dof = np.ones(len(columns), dtype=int)
    notes: list[str] = []
    warn: list[str] = []
    bandwidths: dict = {}
    combos: list[str] = []
    lo = np.array([model.parameters[c.index].min for c in columns])
    hi = np.array([model.parameters[c.index].max for c in columns])

    if unseen:
        notes.append(f"not fitted (kept at the declared values): "
                     f"{', '.join(names[i] for i in unseen)}: only outputs the data lack "
                     "read them")
    reports: dict[str, EquationReport] = {
        f.name: EquationReport(f.name, "-", f.reason, tuple(names[i] for i in f.free))
        for f in forms}
    P = data.parameter_matrix(model, declared)
    col_pos = {(c.index, c.experiment): k for k, c in enumerate(columns)}
    ls_method = "cvx" if method == "cvx" else "ls"
    outside: list[str] = []
    for group in linear.groups(forms):
        reg = linear.regression(model, data, group, P, per_exp)
        if reg.X.shape[0] <= reg.X.shape[1]:
            for f in group:
                reports[f.name] = EquationReport(
                    f.name, "-", f"{reg.X.shape[0]} rows for {reg.X.shape[1]} parameters",
                    tuple(names[i] for i in f.free))
            continue
        pos = [col_pos[(c.index, c.experiment)] for c in reg.columns]
        sol = linear.solve(reg, data, theta[pos], covariance, hac_bandwidth,
                           bounds=(lo[pos], hi[pos]) if ls_method == "cvx" else None,
                           solver=solver, loss=loss, constraints=tuple(
                               linear.affine_rows(model, data, reg.columns, P[0])
                               if ls_method == "cvx" else ()),
                           prior=linear.prior_arrays(model, reg.columns))
        theta[pos] = sol.theta
        stderr[pos] = sol.stderr
        cov[np.ix_(pos, pos)] = sol.cov
        dof[pos] = sol.dof
        for k, ok in zip(pos, sol.identified, strict=True):
            status[k] = f"estimated ({ls_method})" if ok else "combination"
        if sol.bandwidth is not None:
            bandwidths["+".join(reg.names)] = sol.bandwidth
        combos += list(sol.combinations)
        if sol.combinations:
            lost = [c.label for c, ok in zip(reg.columns, sol.identified, strict=True)
                    if not ok]
            if strict:
                raise DataError(f"{ds.source}: {' + '.join(reg.names)}: the data do not "
                                f"separate {', '.join(lost)} (they identify "
                                f"{'; '.join(sol.combinations)}); excite the inputs")
            warn.append(f"{' + '.join(reg.names)}: the data do not separate "
                        f"{', '.join(lost)}; they identify {'; '.join(sol.combinations)} "
                        "(estimates closest to the declared values)")
        outside += [f"{c.label} = {t:.4g}" for c, t, a, b in
                    zip(reg.columns, sol.theta, lo[pos], hi[pos], strict=True)
                    if not a <= t <= b]
        for k, f in enumerate(group):
            rows = reg.eq == k
            r = reg.y[rows] - reg.X[rows] @ sol.theta
            tgt = _target(model, data, f.name, reg.sample[rows])
            den = np.linalg.norm(tgt - tgt.mean())
            reports[f.name] = EquationReport(
                name=f.name, method=ls_method, reason="", parameters=tuple(
                    c.label for c in reg.columns if c.index in f.free),
                rank=sol.rank, n_columns=len(reg.columns), condition=sol.condition,
                residual_std=float(np.sqrt(np.mean(r ** 2))), n_rows=int(rows.sum()),
                fit_percent=float(100 * (1 - np.linalg.norm(r) / den)) if den > 0 else None,
                combinations=sol.combinations, active_bounds=sol.active,
                **_whiteness(r, data.experiment[reg.sample[rows]]))
    ls_reached = [s != "not fitted" for s in status]
    latent = [s.name for s in model.states if not s.measured]
    if method == "auto":
        method = "ls" if all(ls_reached) and not latent and fit_starts == 1 \
            and not priors else "oe"
        notes.append(f"method auto: {method} (" + (
            "declared priors" if priors and method == "oe" else
            "least squares reaches every free parameter" if method == "ls" else
            f"{fit_starts} output-error starts asked for" if fit_starts > 1 else
            "latent states " + ", ".join(latent) if latent and all(ls_reached) else
            "not every parameter is in a linear, fully measured equation") + ")")
    lin = [f.name for f in forms if reports[f.name].method in ("ls", "cvx")]
    if lin:
        notes.append(f"equation-error least squares on {', '.join(lin)} (linear in their "
                     "free parameters, every signal measured)")
        if method in ("ls", "cvx") and linear.prior_note(model, columns, theta):
            notes.append(linear.prior_note(model, columns, theta))
    oe_summary: dict = {}
    oe_x0 = None     # (windows, nx) initial states the output-error fit estimated
    optima: list[Optimum] = []
    failed: list[FailedStart] = []
    if method == "oe" and columns:
        base = data.parameter_matrix(model, declared)
        prob = oe.OEProblem(model, data, columns, _window_base(base, columns, oe.Windows.of(
            data.segments, oe_window)), oe_window, estimate_x0=oe_estimate_x0)
        theta_start = np.where(np.isfinite(theta), theta, declared[[c.index for c in columns]])
        _check_finite_start(model, prob, theta_start, lo, hi, ds.source)
        solve = oe.solve
        if oe_solver == "ms":
            from acid.ident.ms.shooting import solve_ms

            def solve(*a, max_nfev, **kw):
                return solve_ms(*a, max_iter=3 * max_nfev, **kw)
        dense = oe_solver == "dense"
        res = solve(prob, theta_start, lo, hi, covariance=covariance,
                    hac_bandwidth=hac_bandwidth, max_nfev=max_nfev, loss=loss,
                    **({"progress": _labelled(progress, "start 1")} if dense else {}))
        if fit_starts > 1:
            rng = np.random.default_rng(seed)
            scale = {n: max(float(np.std(prob.meas[..., i][prob.obs[..., i]])), 1e-9)
                     for i, n in enumerate(prob.chan_names)}
            runs = []
            chosen = None
            for k, s0 in enumerate([None, *_starts(rng, fit_starts - 1, theta, lo, hi)]):
                try:
                    r = res if s0 is None else solve(
                        prob, s0, lo, hi, reweight=False, covariance=covariance,
                        hac_bandwidth=hac_bandwidth, max_nfev=max_nfev, loss=loss,
                        **({"progress": _labelled(progress, f"start {k + 1}/{fit_starts}")}
                           if dense else {}))
                except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                    failed.append(FailedStart(k, math.nan, f"the solver failed: {exc}", {
                        c.label: float(v) for c, v in zip(columns, s0, strict=True)}))
                    continue
                why = _failure(r, scale)
                if why:
                    failed.append(FailedStart(k, float(r.loss), why, {
                        c.label: float(v) for c, v in zip(columns, r.theta, strict=True)}))
                    continue
                runs.append((r.loss, r.theta))
                if chosen is None or r.loss < chosen.loss * (1 - 1e-9):
                    chosen = r
            if chosen is not None:
                res = chosen
                optima = _distinct(runs, columns, lo, hi)
                failed = _in_basins(failed, optima, columns)
                notes.append(_basins_note(fit_starts, len(runs), optima, failed))
            else:
                warn.append(f"multi-start: none of the {fit_starts} starts converged; the "
                            "first start's result is reported")
        theta, oe_x0 = res.theta, res.x0
        stderr, cov = res.stderr, res.cov
        dof[:] = res.dof
        ident, oe_combos = linear.combinations(
            res.jacobian_scaled, res.column_scale, tuple(c.label for c in columns), theta, cov)
        status = ["estimated (oe)" if ok else "combination" for ok in ident]
        stderr = np.where(np.array(ident), stderr, np.nan)
        combos += oe_combos
        if oe_combos:
            warn.append("output error: the data do not separate some parameters; they "
                        f"identify {'; '.join(oe_combos)}")
        if res.bandwidth is not None:
            bandwidths["oe"] = res.bandwidth
        oe_summary = {"windows": res.n_windows, "window": oe_window, "loss": res.loss,
                      "status": res.status, "converged": res.success, "nfev": res.nfev,
                      "channel_rms": res.channel_rms, "channel_fit_percent": res.channel_fit,
                      "weights": dict(zip(prob.chan_names, res.weights.tolist(),
                                          strict=True)),
                      "condition": res.condition, "rank": res.rank,
                      "n_parameters": len(columns)}
        if not res.success:
            warn.append(f"output error did not converge ({res.status})")
        if linear.prior_note(model, columns, theta):
            notes.append(linear.prior_note(model, columns, theta))
        notes.append(f"output error over {res.n_windows} windows of <= {oe_window} samples, "
                     + ("each window's initial state estimated" if oe_estimate_x0 else
                        "each window started from the measured states") + (
                         f" (latent: {', '.join(latent)}, estimated)" if latent else ""))
        for f in forms:
            q = reports[f.name]
            if q.method == "-" and f.free:
                reports[f.name] = EquationReport(f.name, "oe", f.reason,
                                                 tuple(names[i] for i in f.free))
            elif q.method in ("ls", "cvx"):
                reports[f.name] = dataclasses.replace(q, method=f"{q.method} start, oe")
    elif method in ("ls", "cvx"):
        if outside and method == "ls":
            warn.append(f"least squares leaves the declared bounds ({', '.join(outside)}); "
                        "--method cvx keeps them")
        active = [a for q in reports.values() for a in q.active_bounds]
        if active:
            notes.append("--method cvx: active at the solution: " + "; ".join(active))
        left = sorted({c.name for c, ok in zip(columns, ls_reached, strict=True) if not ok})
        if left:
            notes.append(f"not fitted by equation error (kept at the declared values): "
                         f"{', '.join(left)}; --method oe fits them")

    # ------------------------------------------------------------------ the table
    values = declared.copy()
    per_experiment: dict[str, np.ndarray] = {}
    for i in per_exp:
        per_experiment[names[i]] = np.full(E, declared[i])
    for k, c in enumerate(columns):
        if c.experiment is None:
            values[c.index] = theta[k]
        else:
            per_experiment[c.name][c.experiment] = theta[k]
    for n, v in per_experiment.items():
        values[names.index(n)] = float(np.mean(v))
    import scipy.stats  # here, not at the top: ~0.6 s off the CLI's start-up

    estimates = []
    for i, p in enumerate(model.parameters):
        cols = [k for k, c in enumerate(columns) if c.index == i]
        if not cols:
            estimates.append(Estimate(p.name, p.unit, p.value, p.value, math.nan,
                                      (math.nan, math.nan),
                                      "not fitted" if i in unseen else "fixed"))
            if i in per_exp:
                for e in range(E):
                    estimates.append(Estimate(p.name, p.unit, p.value, p.value, math.nan,
                                              (math.nan, math.nan), "fixed", e))
            continue
        for k in cols:
            q = scipy.stats.t.ppf(0.975, max(int(dof[k]), 1))
            se = float(stderr[k])
            ci = (theta[k] - q * se, theta[k] + q * se) if math.isfinite(se) else \
                (math.nan, math.nan)
            estimates.append(Estimate(p.name, p.unit, p.value, float(theta[k]), se, ci,
                                      status[k], columns[k].experiment))
    P_fit = _values_at(data, values, per_experiment, names)
    sim = simulation_errors(model, data, P_fit, oe_window, latent_x0=oe_x0)
    return DeclaredFitResult(
        simulation_fit={k: 100.0 * (1.0 - math.sqrt(v["nmse"])) for k, v in sim.items()},
        channel_mse={k: {**v, "scored": "simulation"} for k, v in sim.items()},
        one_step_fit=one_step_fit(model, data, forms, P_fit),
        loss=loss, model=model.name, model_source=model.source, method=method, declaration=model,
        estimates=tuple(estimates), equations=tuple(reports.values()), values=values,
        per_experiment=per_experiment, experiment_ids=data.experiment_ids,
        covariance=cov, covariance_names=tuple(c.label for c in columns),
        covariance_kind=covariance, hac_bandwidth=bandwidths, output_error=oe_summary,
        optima=tuple(optima), combinations=tuple(combos), notes=tuple(notes),
        failed_starts=tuple(failed),
        on_bounds=tuple(_on_bounds(columns, theta, lo, hi)),
        warnings=tuple(warn), n_samples=len(ds), data_source=ds.source,
        elapsed_s=time.perf_counter() - t0)


def simulation_errors(model: Model, data: ModelData, P: np.ndarray, window: int,
                      latent_x0: np.ndarray | None = None) -> dict:
    """{channel: {"unit", "mse", "variance", "nmse", "n"}} of ``window``-sample simulations
    of every experiment from the measured states with the parameters ``P`` (N, np) per
    sample; latent states from ``latent_x0`` (windows, nx: the states an output-error fit over
    the same windows estimated at each start) or, without it, their declared rule (a wrong
    start of an unmeasured velocity or wall would be scored as model error). Every measured
    channel: the mean squared error
    (the channel's unit squared), the channel's variance over the same samples and their
    ratio NMSE (0 perfect, 1 no better than the channel's mean); the multi-step quality a
    one-step fit does not show, on the same footing for every model and method."""
    w = oe.Windows.of(data.segments, window)
    i0 = w.idx[:, 0]
    x0 = data.initial_states(model, i0)
    latent = [i for i, s in enumerate(model.states) if not s.measured]
    if latent_x0 is not None and latent and latent_x0.shape == x0.shape:
        x0[:, latent] = latent_x0[:, latent]
    Y = oe.simulate_windows(model, data, w.idx, x0, P[i0])
    meas = data.observed()[w.idx]
    unit = {r.name: r.unit for r in model.states + model.outputs}
    out = {}
    for c, name in data.measured_channels(model):
        ok = w.mask & np.isfinite(meas[..., c])
        m, y = meas[..., c][ok], Y[..., c][ok]
        mse = float(np.mean((y - m) ** 2)) if m.size else math.nan
        var = float(np.var(m)) if m.size else math.nan
        out[name] = {"unit": unit[name], "mse": mse, "variance": var,
                     "nmse": mse / var if var > 0 else math.nan, "n": int(m.size)}
    return out


def _one_step_mse(model: Model, pem: dict) -> dict:
    """``channel_mse`` of a prediction-error fit from its one-step innovations (RMS and fit
    % over the same samples: MSE = RMS^2, NMSE = (1 - fit % / 100)^2, variance their ratio)."""
    unit = {r.name: r.unit for r in model.states + model.outputs}
    out = {}
    for k, rms in pem.get("innovation_rms", {}).items():
        fit = pem["one_step_fit_percent"].get(k, math.nan)
        mse, nmse = rms ** 2, (1.0 - fit / 100.0) ** 2
        out[k] = {"unit": unit.get(k, ""), "mse": mse,
                  "variance": mse / nmse if nmse > 0 else math.nan, "nmse": nmse,
                  "scored": "one-step"}
    return out


def simulation_fit(model: Model, data: ModelData, P: np.ndarray, window: int) -> dict:
    """{channel: fit %} of the simulations of ``simulation_errors``: 100 (1 - sqrt(NMSE))."""
    return {k: 100.0 * (1.0 - math.sqrt(v["nmse"]))
            for k, v in simulation_errors(model, data, P, window).items()}


def one_step_fit(model: Model, data: ModelData, forms, P: np.ndarray) -> dict:
    """{equation: fit %} of one-step predictions along the data with parameters ``P``
    (N, np) per sample: a state's next value from the measured state, inputs and read
    outputs; an output at its sample. Equations that read a latent state are left out."""
    import casadi as ca

    out = {}
    args = (model._x, model._u, model._d, model._p, model._yr)
    for f in forms:
        if f.reason.startswith("reads the latent"):
            continue
        rows, target = linear.equation_rows(model, data, f.name)
        if rows.size < 2:
            continue
        fn = ca.Function("e", list(args), [f.expr]).map(rows.size)
        pred = np.asarray(fn(*[np.nan_to_num(a[rows]).T for a in (data.x, data.u, data.d)],
                             P[rows].T, np.nan_to_num(data.y[rows]).T)).ravel()
        den = np.linalg.norm(target - target.mean())
        out[f.name] = float(100.0 * (1.0 - np.linalg.norm(pred - target) / den)) if den > 0 \
            else math.nan
    return out


def _values_at(data: ModelData, values: np.ndarray, per_experiment: dict,
               names: tuple[str, ...]) -> np.ndarray:
    """(N, np) the fitted table at every sample (per-experiment values by experiment)."""
    P = np.tile(values, (data.x.shape[0], 1))
    for n, v in per_experiment.items():
        P[:, names.index(n)] = np.asarray(v)[data.experiment]
    return P


def _with_values(model: Model, start: dict) -> Model:
    """A copy of ``model`` whose table has the values ``start`` (name -> value)."""
    import copy

    for n in start:
        model.parameter(n)
    other = copy.copy(model)
    other.parameters = tuple(dataclasses.replace(p, value=float(start[p.name]))
                             if p.name in start else p for p in model.parameters)
    return other


def fit(ds: Dataset, method: str = "auto", model: Model | str = "paper",
        **options) -> DeclaredFitResult:
    """``fit_model(model, ds, method, **options)`` with the paper's model by default
    (``acid.fit(est, method="oe")``)."""
    return fit_model(model, ds, method, **options)


def _whiteness(r: np.ndarray, exp: np.ndarray, lags: int = 20) -> dict:
    """Lag-1 autocorrelation and the Ljung-Box p-value of residuals in time order (lag
    products inside one experiment): a small p says the residuals are not white, the
    equation misses dynamics (and white standard errors would be too small)."""
    import scipy.stats

    n = r.size
    if n <= lags + 2:
        return {}
    e = r - r.mean()
    den = float(e @ e)
    if den <= 0:
        return {}
    rho = np.array([float((e[k:] * e[:-k])[exp[k:] == exp[:-k]].sum()) / den
                    for k in range(1, lags + 1)])
    q = n * (n + 2) * float(np.sum(rho**2 / (n - np.arange(1, lags + 1))))
    return {"residual_acf1": float(rho[0]),
            "ljung_box_p": float(scipy.stats.chi2.sf(q, lags))}


def _target(model: Model, data: ModelData, name: str, rows: np.ndarray) -> np.ndarray:
    if name in model.state_names:
        return data.x[rows + 1, model.state_names.index(name)]
    return data.y[rows, model.output_names.index(name)]


def _window_base(P: np.ndarray, columns, w: oe.Windows) -> np.ndarray:
    """(nw, np) parameters of each window with the free entries zeroed (added back by E)."""
    base = P[w.idx[:, 0]].copy()
    for c in columns:
        base[:, c.index] = 0.0
    return base


def _starts(rng: np.random.Generator, n: int, theta, lo, hi) -> list[np.ndarray]:
    """``n`` starts uniform inside the bounds; an unbounded side spans the value +/- its
    magnitude (at least 1)."""
    span = np.maximum(np.abs(theta), 1.0)
    a = np.where(np.isfinite(lo), lo, theta - span)
    b = np.where(np.isfinite(hi), hi, theta + span)
    a, b = np.maximum(a, lo), np.minimum(b, hi)
    return [a + (b - a) * rng.random(theta.size) for _ in range(n)]


def _check_finite_start(model: Model, prob, theta0, lo, hi, source: str) -> None:
    """A ``ConfigError`` naming the channel and sample where the simulation from the start
    values is not finite (an equation outside its domain: log or sqrt of a negative number, a
    division by zero), instead of the solver's internal error."""
    z0 = np.concatenate([np.clip(theta0, lo, hi), prob.x0_start[:, prob.x0_free].ravel()])
    with np.errstate(all="ignore"):
        e0 = prob.errors(z0)
    bad = ~np.isfinite(e0) & prob.obs
    if bad.any():
        w, step, c = (int(i) for i in np.argwhere(bad)[0])
        raise ConfigError(f"model {model.name!r}: its simulation from the start values gives "
                          f"NaN or inf on {source} (channel {prob.chan_names[c]}, sample "
                          f"{int(prob.w.idx[w, step])}): an equation outside its domain (log "
                          "or sqrt of a negative number, a division by zero) at these states "
                          "and inputs, or start values that make it so")


def _failure(r, scale: dict) -> str:
    """Why an output-error run reached no optimum ("" when it did); ``scale``: each
    channel's standard deviation in the data."""
    if not (np.isfinite(r.loss) and np.all(np.isfinite(r.theta))):
        return "non-finite loss or parameters"
    ratio = {n: r.channel_rms[n] / s for n, s in scale.items()}
    worst = max(ratio, key=lambda n: ratio[n] if math.isfinite(ratio[n]) else math.inf)
    if not ratio[worst] <= DIVERGED_ERROR_RATIO:
        return (f"diverged ({worst}'s simulation error is {ratio[worst]:.3g} times its "
                f"standard deviation in the data)")
    if not r.success:
        return f"solver failed or stopped: {r.status} ({r.nfev} evaluations)"
    return ""


#: seconds between two progress reports of a running fit (the first is reported at once)
PROGRESS_EVERY_S = 2.0


def _labelled(progress, prefix: str):
    """``progress`` with ``prefix`` before each label, forwarded at most every
    ``PROGRESS_EVERY_S`` (a fit evaluates thousands of times; None stays None)."""
    if progress is None:
        return None
    last = [-math.inf]

    def report(done, total=None, label=None):
        now = time.monotonic()
        if now - last[0] >= PROGRESS_EVERY_S:
            last[0] = now
            progress(done, total, f"{prefix}, {label}")
    return report


def _on_bounds(columns, theta, lo, hi) -> list[str]:
    """"NAME at its min|max VALUE" for every column within round-off of a declared bound."""
    return [f"{c.label} at its {w} {b:g}" for c, t, a, z in zip(columns, theta, lo, hi,
                                                                 strict=True)
            for b, w in ((a, "min"), (z, "max"))
            if math.isfinite(b) and math.isfinite(t) and abs(t - b) <= 1e-8 * (1 + abs(b))]


def _same_basin(loss, th, l0, t0, atol: float, rtol_loss: float = 1e-6,
                rtol_theta: float = 1e-3) -> bool:
    """Same loss (relative ``rtol_loss`` or ``atol``) and parameters within ``rtol_theta`` of
    their magnitude."""
    scale = np.maximum(np.abs(t0), 1e-9)
    return bool(abs(loss - l0) <= rtol_loss * abs(l0) + atol
                and np.all(np.abs(th - t0) <= rtol_theta * scale))


def _pem_starts(model: Model, ds: Dataset, first, n: int, seed: int, fix, max_nfev: int,
                t0: float, progress) -> DeclaredFitResult:
    """``fit_starts`` for the prediction-error method: ``n - 1`` more fits from starts drawn
    inside the bounds of its free columns (the declared start first); the converged ones
    grouped into optima (loss, parameters, count), the others failed starts with the
    reason; the best converged fit is reported."""
    from acid.ident.pem import columns_for, fit_pem

    columns = columns_for(model, ModelData.of(model, ds), fix)
    lo = np.array([model.parameters[c.index].min for c in columns])
    hi = np.array([model.parameters[c.index].max for c in columns])

    def theta(r):                   # the free columns' values, in the columns' order
        return np.array([e.value for e in r.estimates if e.status != "fixed"])
    runs, failed, best = [], [], None
    rng = np.random.default_rng(seed)
    for k, s0 in enumerate([None, *_starts(rng, n - 1, theta(first), lo, hi)]):
        if s0 is None:
            r = first
        else:
            start: dict = {}
            for c, v in zip(columns, s0, strict=True):     # a per-trip column: its mean
                start.setdefault(c.name, []).append(float(v))
            r = fit_pem(_with_values(model, {k_: float(np.mean(v)) for k_, v in
                                             start.items()}), ds, fix=fix,
                        max_nfev=max_nfev, t0=t0,
                        progress=_labelled(progress, f"prediction error, start {k + 1}/{n}"))
        oe_ = r.output_error
        th = theta(r)
        if not (math.isfinite(oe_["loss"]) and np.all(np.isfinite(th))):
            failed.append(FailedStart(k, float(oe_["loss"]), "non-finite loss or parameters",
                                      dict(zip(r.covariance_names, th.tolist(), strict=True))))
        elif not oe_["converged"]:
            failed.append(FailedStart(k, float(oe_["loss"]), f"not converged ({oe_['status']})",
                                      dict(zip(r.covariance_names, th.tolist(), strict=True))))
        else:
            runs.append((float(oe_["loss"]), th))
            if best is None or oe_["loss"] < best.output_error["loss"]:
                best = r
    if best is None:
        return dataclasses.replace(first, failed_starts=tuple(failed), warnings=(
            *first.warnings, f"multi-start: none of the {n} starts converged; the first "
            "start's result is reported"), elapsed_s=time.perf_counter() - t0)
    optima = _distinct(runs, columns, lo, hi)
    failed = _in_basins(failed, optima, columns)
    return dataclasses.replace(best, optima=tuple(optima), failed_starts=tuple(failed),
                               notes=(*best.notes, _basins_note(n, len(runs), optima, failed)),
                               elapsed_s=time.perf_counter() - t0)


def _in_basins(failed, optima, columns) -> list[FailedStart]:
    """Failed starts whose end point is one of the converged optima (a solver stopped at
    its cap or short of its tolerance there) say so in their reason."""
    out = []
    atol = 1e-12 * max(max(abs(o.loss) for o in optima), 1.0)
    for f in failed:
        th = np.array([f.values.get(c.label, math.nan) for c in columns])
        k = next((k for k, o in enumerate(optima) if np.isfinite(f.loss) and _same_basin(
            f.loss, th, o.loss, np.array([o.values[c.label] for c in columns]), atol)), None)
        out.append(f if k is None else dataclasses.replace(
            f, reason=f"{f.reason}; it ended at optimum {k + 1}"))
    return out


def _basins_note(n: int, n_conv: int, optima, failed) -> str:
    """The multi-start's basins in one line: converged starts per optimum (loss x count),
    failed starts per kind of failure."""
    kinds: dict[str, int] = {}
    for f in failed:
        kind = f.reason.split(" (")[0].split(":")[0].split(";")[0]
        kinds[kind] = kinds.get(kind, 0) + 1
    shown = ", ".join(f"objective {o.loss:.6g} x {o.n_starts}" for o in optima[:5])
    more = f", {len(optima) - 5} more" if len(optima) > 5 else ""
    why = f" ({', '.join(f'{k} x {v}' for k, v in kinds.items())})" if kinds else ""
    return (f"multi-start: {n} starts, {n_conv} converged into {len(optima)} distinct optima "
            f"({shown}{more}), {len(failed)} failed{why}; the best (objective {optima[0].loss:.6g},"
            f" {optima[0].n_starts} start(s)) is reported")


def _distinct(runs, columns, lo, hi, rtol_loss: float = 1e-6,
              rtol_theta: float = 1e-3) -> list[Optimum]:
    """Runs grouped into optima: same loss (relative ``rtol_loss``, or round-off of the
    largest loss) and parameters within
    ``rtol_theta`` of their magnitude; best first."""
    runs = sorted(runs, key=lambda r: r[0])
    # zero losses differ by round-off
    atol = 1e-12 * max(max(abs(r[0]) for r in runs), 1.0)
    groups: list[list] = []
    for loss, th in runs:
        for g in groups:
            if _same_basin(loss, th, *g[0], atol, rtol_loss, rtol_theta):
                g.append((loss, th))
                break
        else:
            groups.append([(loss, th)])
    out = []
    for g in groups:
        T = np.array([t for _, t in g])
        out.append(Optimum(loss=float(g[0][0]), n_starts=len(g),
                           values={c.label: float(v) for c, v in zip(columns, T[0],
                                                                     strict=True)},
                           spread={c.label: float(s) for c, s in
                                   zip(columns, T.max(axis=0) - T.min(axis=0), strict=True)}))
    return out


def provenance(ds: Dataset, method: str, loss: str = "squared") -> dict:
    """Where a fit's values come from: the data file (and its SHA-256, which ``acid
    validate`` compares), method, loss, samples and their time span, the data's seed."""
    out = {"data_file": ds.source, "method": method, "loss": loss, "n_samples": len(ds),
           "time_span_s": [float(ds.time[0]), float(ds.time[-1])],
           "acid_version": __version__}
    if Path(ds.source).is_file():
        out["data_sha256"] = file_sha256(ds.source)
    if "seed" in ds.metadata:
        out["data_seed"] = ds.metadata["seed"]
    return out
