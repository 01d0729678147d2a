"""Staged fitting over any declaration: the parameters fitted in groups, each group on its own
equations with the groups before it held at their fitted values (MATLAB's ``nlgreyest`` with
some parameters fixed, run in sequence). The econ model's recipe (``acid.models.econ.
FIT_STAGES``): the blower curve by least squares, its thermal part by one-step prediction
error of the five states and the supply air, then the power map and C_ew on P_comp.

A stage's method is one of :func:`acid.ident.fit.fit_model`'s (``ls``, ``cvx``, ``oe``) or
``"ee"``: nonlinear equation error, i.e. one-step prediction error. Each equation's target (a
state one sample later, an output over the interval) is predicted by the declaration from the
measured signals at sample k (an output that reads the interval's end state, ``s.next``,
reads the measured one); the weighted residuals are minimised over the stage's
parameters (``scipy.optimize.least_squares``, declared bounds, CasADi Jacobian), each
equation weighted by its residual standard deviation, re-estimated while one moves by more
than 3x. Covariance: white or the Newey-West sandwich over instants (equations summed, lags
inside experiments). ``skip_s`` leaves the first seconds of every experiment out of ``ee``
stages (e.g. a hot-soak pull-down a recirculation model does not describe).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.optimize

from acid.data import Dataset
from acid.errors import ConfigError, DataError
from acid.ident.data import ModelData
from acid.ident.fit import DeclaredFitResult, EquationReport, Estimate, fit_model
from acid.ident.hac import hac_meat, resolve_bandwidth, segment_ids
from acid.models.declaration import Model
from acid.models.loader import load


@dataclass(frozen=True)
class Stage:
    """Fit ``parameters`` on ``equations`` by ``method`` (``ee``, ``ls``, ``cvx``, ``oe``)."""

    parameters: tuple[str, ...]
    equations: tuple[str, ...]
    method: str = "ee"


@dataclass(frozen=True)
class EquationError:
    """What an ``ee`` stage found (free parameters in the stage's order)."""

    theta: np.ndarray
    cov: np.ndarray
    stderr: np.ndarray
    weights: dict
    fit_percent: dict
    rows: np.ndarray
    status: str
    success: bool
    bandwidth: int | None
    dof: int


def one_step(model: Model, data: ModelData, equations, free: list[int], values: np.ndarray):
    """``(Y, F)``: targets (n_eq, N) of ``equations``, and a CasADi Function
    ``F(theta_free, x, u, d, y, x_next) -> (predictions, Jacobian)``; the other parameters at
    ``values``. An output that reads the interval's end state (``s.next``) reads the
    measured one."""
    x, u, d, p, yr = model._x, model._u, model._d, model._p, model._yr
    th = ca.SX.sym("theta", len(free))
    full = ca.vertcat(*[th[free.index(i)] if i in free else values[i]
                        for i in range(model.np)])
    e = ca.substitute(ca.vertcat(*[model.equations_next.get(n, model.equations_raw[n])
                                   for n in equations]), p, full)
    f = ca.Function("one_step", [th, x, u, d, yr, model._xn], [e, ca.jacobian(e, th)])
    Y = []
    for n in equations:
        if n in model.state_names:
            j = model.state_names.index(n)
            Y.append(np.r_[data.x[1:, j], np.nan])
        else:
            Y.append(data.y[:, model.output_names.index(n)])
    return np.array(Y), f


def solve_equation_error(model: Model, data: ModelData, equations, free: list[int],
                         values: np.ndarray, skip: int, covariance: str,
                         hac_bandwidth, max_nfev: int = 200) -> EquationError:
    """The ``ee`` stage (module docstring): ``free`` declared parameter indices, started at
    ``values``; ``skip`` samples left out at the start of every experiment."""
    Y, f = one_step(model, data, equations, free, values)
    keep = np.zeros(len(data), dtype=bool)
    for a, b in data.segments:
        keep[a + skip: b - 1] = True
    keep &= np.all(np.isfinite(Y), axis=0) & np.all(np.isfinite(np.c_[data.u, data.d]), axis=1)
    keep &= np.all(np.isfinite(data.x[:, [s.measured for s in model.states]]), axis=1)
    rows = np.flatnonzero(keep)
    if rows.size <= len(free):
        raise DataError(f"{data.source}: {rows.size} usable samples for {len(free)} parameters "
                        f"of {', '.join(equations)} (after {skip} skipped per experiment)")
    F = f.map(rows.size, "serial")
    args = [np.nan_to_num(a[rows]).T for a in (data.x, data.u, data.d, data.y)] + [
        np.nan_to_num(data.x[rows + 1]).T]
    Yk = Y[:, rows]
    cache: dict = {}

    def predict(t):
        key = np.asarray(t, dtype=float).tobytes()
        if cache.get("key") != key:
            out, jac = F(t, *args)
            cache.update(key=key, out=np.asarray(out),
                         J=np.asarray(jac).reshape(len(equations), rows.size, len(free)))
        return cache["out"], cache["J"]

    def std(t):
        return np.maximum((predict(t)[0] - Yk).std(axis=1), 1e-12)

    lo = np.array([model.parameters[i].min for i in free])
    hi = np.array([model.parameters[i].max for i in free])
    t = np.clip(values[free], lo, hi)
    w = std(t)
    res = None
    for _ in range(3):  # again only while an equation's residual std moves by more than 3x
        wk = w.copy()
        res = scipy.optimize.least_squares(
            lambda z, wk=wk: ((predict(z)[0] - Yk) / wk[:, None]).ravel(), t,
            jac=lambda z, wk=wk: (predict(z)[1] / wk[:, None, None]).reshape(-1, len(free)),
            bounds=(lo, hi), x_scale="jac", ftol=1e-9, xtol=1e-9, gtol=1e-9,
            max_nfev=max_nfev)
        t = res.x
        w = std(t)
        if np.max(np.abs(np.log(w / wk))) < np.log(3.0):
            break
    out, J = predict(t)
    r = ((out - Yk) / w[:, None]).ravel()
    Jw = (J / w[:, None, None]).reshape(-1, len(free))
    cov, lag = sandwich(Jw, r, len(equations), rows, data.segments, covariance, hac_bandwidth)
    fits = {}
    for i, n in enumerate(equations):
        den = np.linalg.norm(Yk[i] - Yk[i].mean())
        fits[n] = float(100 * (1 - np.linalg.norm(out[i] - Yk[i]) / den)) if den > 0 else \
            math.nan
    return EquationError(theta=t, cov=cov, stderr=np.sqrt(np.clip(np.diag(cov), 0, None)),
                         weights=dict(zip(equations, w.tolist(), strict=True)),
                         fit_percent=fits, rows=rows, status=str(res.message),
                         success=bool(res.success), bandwidth=lag,
                         dof=max(r.size - len(free), 1))


def sandwich(J: np.ndarray, r: np.ndarray, n_ch: int, sample: np.ndarray, segments,
             kind: str, bandwidth_spec) -> tuple[np.ndarray, int | None]:
    """Covariance of least-squares estimates: white ``s^2 (J^T J)^-1`` or Newey-West HAC.

    ``J`` (n_ch n, p) and ``r`` (n_ch n,) channel-major; the HAC score of one instant sums
    its channels; ``sample`` (n,) the instants in time order, ``segments`` the experiments.
    """
    m, p = J.shape
    n = m // n_ch
    dof = max(m - p, 1)
    colnorm = np.linalg.norm(J, axis=0)
    colnorm[colnorm == 0] = 1.0
    _, s, Vt = np.linalg.svd(J / colnorm, full_matrices=False)
    s_inv2 = np.where(s > 1e-12 * s[0], 1.0 / s**2, 0.0)
    bread = ((Vt.T * s_inv2) @ Vt) / np.outer(colnorm, colnorm)
    if kind == "white":
        return float(r @ r) / dof * bread, None
    h = (J * r[:, None]).reshape(n_ch, n, p).sum(axis=0)
    groups = segment_ids(sample, segments)
    lag = resolve_bandwidth(bandwidth_spec, h, groups)
    return m / dof * (bread @ hac_meat(h, groups, lag) @ bread), lag


def fit_stages(model: Model | str, ds: Dataset, stages, *, covariance: str = "hac",
               hac_bandwidth="auto", skip_s: float = 0.0,
               fix: dict | None = None) -> DeclaredFitResult:
    """Fit ``model`` to ``ds`` stage by stage (module docstring); parameters in no stage keep
    their declared values (or ``fix``). One result: each parameter's row, standard error and
    covariance block from the stage that fitted it, equations reported by their stage."""
    t0 = time.perf_counter()
    model = load(model)
    if fix:
        model = model.with_parameters(fix)
    names = model.parameter_names
    data = ModelData.of(model, ds)
    values = model.values.copy()
    if not (math.isfinite(skip_s) and skip_s >= 0):
        raise ConfigError(f"skip_s must be >= 0 s, got {skip_s}")
    skip = int(round(skip_s / data.Ts))
    rows: dict[str, Estimate] = {}
    reports: dict[str, EquationReport] = {}
    blocks: list[tuple[list[str], np.ndarray]] = []
    notes: list[str] = []
    warn: list[str] = []
    bandwidths: dict = {}
    for k, st in enumerate(stages, start=1):
        for n in st.parameters:
            model.parameter(n)
        free = [names.index(n) for n in st.parameters if not model.parameter(n).fixed]
        label = f"stage {k} ({st.method}: {', '.join(st.equations)})"
        if st.method != "ee":
            others = {n: v for n, v in zip(names, values, strict=True)
                      if names.index(n) not in free}
            sub = fit_model(model, ds, st.method, fix=others, covariance=covariance,
                            hac_bandwidth=hac_bandwidth)
            for i in free:
                values[i] = sub.values[i]
            rows.update({e.name: e for e in sub.estimates if names.index(e.name) in free})
            reports.update({q.name: q for q in sub.equations if q.name in st.equations})
            blocks.append((list(sub.covariance_names), np.asarray(sub.covariance)))
            notes += [f"{label}: {m}" for m in sub.notes]
            warn += [f"{label}: {m}" for m in sub.warnings]
            bandwidths.update({f"stage {k} {b}": v for b, v in sub.hac_bandwidth.items()})
            continue
        res = solve_equation_error(model, data, st.equations, free, values, skip, covariance,
                                   hac_bandwidth)
        values[free] = res.theta
        import scipy.stats  # here, not at the top: ~0.6 s off the CLI's start-up

        q = scipy.stats.t.ppf(0.975, res.dof)
        for i, v, se in zip(free, res.theta, res.stderr, strict=True):
            p = model.parameters[i]
            rows[p.name] = Estimate(p.name, p.unit, p.value, float(v), float(se),
                                    (float(v - q * se), float(v + q * se)), "estimated (ee)")
        for n in st.equations:
            reports[n] = EquationReport(n, "ee", "", tuple(names[i] for i in free),
                                        residual_std=res.weights[n], n_rows=int(res.rows.size),
                                        fit_percent=res.fit_percent[n])
        blocks.append(([names[i] for i in free], res.cov))
        if res.bandwidth is not None:
            bandwidths[f"stage {k}"] = res.bandwidth
        lo_hit = [names[i] for i, v in zip(free, res.theta, strict=True)
                  for b in (model.parameters[i].min, model.parameters[i].max)
                  if math.isfinite(b) and abs(v - b) <= 1e-6 * (1 + abs(b))]
        if lo_hit:
            notes.append(f"{label}: at a declared bound: {', '.join(lo_hit)}")
        if not res.success:
            warn.append(f"{label}: did not converge ({res.status})")
        notes.append(f"{label}: one-step prediction error over {res.rows.size} samples "
                     f"({skip} skipped at each experiment's start), {res.status}")
    cov_names = [n for b, _ in blocks for n in b]
    cov = np.full((len(cov_names),) * 2, 0.0)
    a = 0
    for b, c in blocks:
        cov[a:a + len(b), a:a + len(b)] = c
        a += len(b)
    estimates = tuple(rows.get(p.name) or Estimate(
        p.name, p.unit, p.value, p.value, math.nan, (math.nan, math.nan), "fixed")
        for p in model.parameters)
    return DeclaredFitResult(
        model=model.name, model_source=model.source, method="staged", declaration=model,
        estimates=estimates, equations=tuple(reports.values()), values=values,
        per_experiment={}, experiment_ids=data.experiment_ids, covariance=cov,
        covariance_names=tuple(cov_names), covariance_kind=covariance,
        hac_bandwidth=bandwidths, output_error={}, optima=(), combinations=(),
        notes=tuple(notes), warnings=tuple(warn), n_samples=len(ds), data_source=ds.source,
        elapsed_s=time.perf_counter() - t0)

