"""Equation-error least squares derived from a declaration.

An equation (a state's next value, an output) is fitted by linear least squares when

* its target is measured, it reads no latent state and no output the data lack (an output
  it reads is substituted by the measured channel), and
* it is linear in its free parameters: CasADi's Jacobian with respect to them does not
  depend on them.

Then ``target - e(p_free = 0) = J p_free`` row by row (rows never span an experiment for a
state equation). Equations that share a free parameter are stacked into one regression. A
per-experiment parameter has one column per experiment. Collinear columns are not pinned:
the estimate closest (in scaled units) to the declared values is returned and the
combinations the data identify are reported (``"gamma1 + 0.98 gamma2 = 0.31"``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from acid.errors import ConfigError
from acid.ident.data import ModelData
from acid.ident.hac import hac_meat, resolve_bandwidth, segment_ids
from acid.ident.prior import prior_arrays, prior_note, prior_rows  # noqa: F401
from acid.models.declaration import Model

_RANK_RTOL = 1e-9
#: Huber threshold in robust standard deviations (95 % efficiency under normal errors).
HUBER_M = 1.345


@dataclass(frozen=True)
class Column:
    """A free parameter column: declared parameter ``index``, experiment (or None)."""

    index: int
    name: str
    experiment: int | None = None

    @property
    def label(self) -> str:
        return self.name if self.experiment is None else f"{self.name}@{self.experiment}"


@dataclass(frozen=True)
class EquationForm:
    """How one equation can be fitted: ``linear`` True when least squares applies, else
    ``reason`` says why not."""

    name: str
    linear: bool
    reason: str
    free: tuple[int, ...]       # declared parameter indices it depends on (free ones)
    expr: object = None         # CasADi SX (x, u, d, p, yr) with unmeasured outputs substituted


def equation_forms(model: Model, data: ModelData, free: tuple[int, ...]) -> list[EquationForm]:
    """Classify every equation of ``model`` on ``data`` (which channels exist)."""
    x, u, d, p, yr = model._x, model._u, model._d, model._p, model._yr
    h = model.h(x, u, d, p)
    measured_y = [bool(np.isfinite(data.y[:, j]).any()) for j in range(model.ny)]
    missing = [j for j in range(model.ny) if not measured_y[j]]
    pf = ca.vertcat(*[p[i] for i in free]) if free else ca.SX(0, 1)
    out = []
    for name, expr in model.equations_raw.items():
        if missing:
            expr = ca.substitute(expr, ca.vertcat(*[yr[j] for j in missing]),
                                 ca.vertcat(*[h[j] for j in missing]))
        deps = tuple(i for i in free if ca.depends_on(expr, p[i]))
        is_state = name in model.state_names
        col = model.state_names.index(name) if is_state else model.output_names.index(name)
        measured = (np.isfinite(data.x[:, col]).any() if is_state else measured_y[col])
        latent = [s.name for i, s in enumerate(model.states)
                  if not s.measured and ca.depends_on(expr, x[i])]
        reason = ""
        if not measured:
            reason = f"{name} is not measured"
        elif latent:
            reason = f"reads the latent state {latent[0]}"
        elif not deps:
            reason = "no free parameter"
        else:
            J = ca.jacobian(expr, pf)
            if ca.depends_on(J, pf):
                reason = "nonlinear in its parameters"
        out.append(EquationForm(name=name, linear=not reason, reason=reason, free=deps,
                                expr=expr))
    return out


def groups(forms: list[EquationForm]) -> list[list[EquationForm]]:
    """Linear equations joined when they share a free parameter (union-find)."""
    lin = [f for f in forms if f.linear]
    parent = list(range(len(lin)))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a in range(len(lin)):
        for b in range(a + 1, len(lin)):
            if set(lin[a].free) & set(lin[b].free):
                parent[root(a)] = root(b)
    out: dict[int, list[EquationForm]] = {}
    for i, f in enumerate(lin):
        out.setdefault(root(i), []).append(f)
    return list(out.values())


@dataclass(frozen=True)
class Regression:
    """``y = X theta`` over the free columns of a group of equations (rows: stacked
    equations; ``sample`` the dataset index of each row, ``eq`` its equation)."""

    names: tuple[str, ...]
    columns: tuple[Column, ...]
    X: np.ndarray
    y: np.ndarray
    sample: np.ndarray
    eq: np.ndarray


def regression(model: Model, data: ModelData, group: list[EquationForm], P: np.ndarray,
               per_experiment: set[int]) -> Regression:
    """The stacked regression of ``group`` at the parameter matrix ``P`` (N, np) whose free
    entries are ignored (set to zero for the offset)."""
    free = sorted({i for f in group for i in f.free})
    columns = []
    for i in free:
        name = model.parameters[i].name
        if i in per_experiment:
            columns += [Column(i, name, e) for e in range(data.n_experiments)]
        else:
            columns.append(Column(i, name))
    P0 = P.copy()
    P0[:, free] = 0.0
    Xs, ys, samples, eqs = [], [], [], []
    x, u, d, p, yr = model._x, model._u, model._d, model._p, model._yr
    for k, f in enumerate(group):
        fn = ca.Function("e", [x, u, d, p, yr], [f.expr, ca.jacobian(f.expr, p)])
        rows, target = equation_rows(model, data, f.name)
        if rows.size == 0:
            continue
        args = [np.nan_to_num(a[rows]).T for a in (data.x, data.u, data.d)]
        e0, J = fn.map(rows.size)(*args, P0[rows].T, np.nan_to_num(data.y[rows]).T)
        e0 = np.asarray(e0).ravel()
        J = np.asarray(J).reshape(rows.size, model.np) if model.np else np.zeros((rows.size, 0))
        bad = ~(np.isfinite(e0) & np.isfinite(J).all(axis=1))
        bad &= np.all([np.isfinite(a[rows]).all(axis=1) for a in (data.x, data.u, data.d)],
                      axis=0)   # data missing (read as 0) is not the equation's fault
        if bad.any():   # else the SVD fails ("did not converge"): name the equation instead
            raise ConfigError(
                f"{Path(model.source).name}: model {model.name!r}: equation {f.name!r} gives "
                f"NaN or inf on the data at sample {int(rows[np.argmax(bad)])} "
                f"({int(bad.sum())} of {rows.size}): an equation outside its domain (log or "
                "sqrt of a negative number, a division by zero) at these states and inputs")
        X = np.zeros((rows.size, len(columns)))
        for c, col in enumerate(columns):
            X[:, c] = J[:, col.index]
            if col.experiment is not None:
                X[:, c] *= data.experiment[rows] == col.experiment
        Xs.append(X)
        ys.append(target - e0)
        samples.append(rows)
        eqs.append(np.full(rows.size, k))
    return Regression(names=tuple(f.name for f in group), columns=tuple(columns),
                      X=np.vstack(Xs) if Xs else np.zeros((0, len(columns))),
                      y=np.concatenate(ys) if ys else np.zeros(0),
                      sample=np.concatenate(samples) if samples else np.zeros(0, int),
                      eq=np.concatenate(eqs) if eqs else np.zeros(0, int))


def equation_rows(model: Model, data: ModelData, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(rows, target) of equation ``name``: the samples k where its target is measured (a
    state's next value inside one experiment, an output at k) and that target."""
    if name in model.state_names:
        j = model.state_names.index(name)
        rows = np.flatnonzero(data.transition & np.isfinite(data.x[1:, j]))
        return rows, data.x[rows + 1, j]
    j = model.output_names.index(name)
    rows = np.flatnonzero(np.isfinite(data.y[:, j]))
    return rows, data.y[rows, j]


@dataclass(frozen=True)
class Solution:
    theta: np.ndarray
    cov: np.ndarray
    stderr: np.ndarray
    rank: int
    condition: float
    residual_std: float
    dof: int
    identified: tuple[bool, ...]            # False for columns in a collinear set
    combinations: tuple[str, ...]
    bandwidth: int | None
    active: tuple[str, ...] = ()
    status: str = "optimal (lstsq)"


def _svd(Z: np.ndarray):
    _, s, Vt = np.linalg.svd(Z, full_matrices=False)
    tol = _RANK_RTOL * (s[0] if s.size else 0.0)
    return s, Vt, s > tol


def combinations(Z: np.ndarray, scale: np.ndarray, labels: tuple[str, ...],
                 theta: np.ndarray, cov: np.ndarray) -> tuple[tuple[bool, ...], list[str]]:
    """Columns the data do not separate, and the combinations they identify.

    ``Z`` has columns scaled by ``scale`` (``Z = X / scale``). A column is in a collinear set
    when a null-space direction of ``Z`` involves it; for each set, the right singular
    vectors of its own columns with nonzero singular values give combinations
    ``sum_i c_i theta_i`` orthogonal to every null direction: the data fix their value.
    """
    s, Vt, keep = _svd(Z)
    null = Vt[~keep]
    if Z.shape[1] > Vt.shape[0]:
        extra = np.linalg.svd(Z, full_matrices=True)[2][Vt.shape[0]:]
        null = np.vstack([null, extra])
    if null.size == 0:
        return tuple(True for _ in labels), []
    involved = np.flatnonzero(np.abs(null).max(axis=0) > 1e-6)
    out = []
    _, s_i, Vt_i = np.linalg.svd(Z[:, involved], full_matrices=False)
    for v, si in zip(Vt_i, s_i, strict=True):
        if si <= _RANK_RTOL * s_i[0]:
            continue
        c = np.zeros(Z.shape[1])
        c[involved] = v * scale[involved]          # v . phi = sum v_j scale_j theta_j
        c /= c[np.argmax(np.abs(c))]
        value = float(c @ theta)
        se = float(np.sqrt(max(c @ cov @ c, 0.0)))
        terms = []
        for j in np.flatnonzero(np.abs(c) > 1e-9 * np.abs(c).max()):
            coef = c[j]
            mag = "" if abs(abs(coef) - 1) < 1e-9 else f"{abs(coef):.4g} "
            sign = "-" if coef < 0 else "+"
            terms.append((sign, f"{mag}{labels[j]}"))
        text = " ".join(f"{sg} {t}" for sg, t in terms).lstrip("+ ")
        if text.startswith("- "):
            text = "-" + text[2:]
        out.append(f"{text} = {value:.6g} +/- {se:.2g}")
    ident = tuple(j not in set(involved.tolist()) for j in range(Z.shape[1]))
    return ident, out


@dataclass(frozen=True)
class AffineRows:
    """A declared constraint on a regression's columns: ``min <= A theta + b <= max``."""

    label: str
    A: np.ndarray      # (rows, columns)
    b: np.ndarray      # (rows,)
    min: float
    max: float


def affine_rows(model: Model, data: ModelData, columns: tuple[Column, ...],
                P: np.ndarray) -> list[AffineRows]:
    """The model's declared constraints whose free parameters are all ``columns``, as rows
    over the measured range of the signals each reads (``Constraint.GRID`` points each);
    ``P`` (np,) the values of the parameters that are not columns."""
    out = []
    signals = model.inputs + model.disturbances
    data_ud = np.hstack([data.u, data.d])
    for c, g, reads in model.constraints:
        ud = np.zeros((1, len(signals)))
        for name in reads:
            j = [r.name for r in signals].index(name)
            grid = np.linspace(np.nanmin(data_ud[:, j]), np.nanmax(data_ud[:, j]), c.GRID)
            ud = np.repeat(ud, grid.size, axis=0)
            ud[:, j] = np.tile(grid, ud.shape[0] // grid.size)
        p0 = np.array(P, dtype=float)
        p0[[col.index for col in columns]] = 0.0
        J = ca.Function("J", [model._p, model._u, model._d],
                        [ca.jacobian(g(model._p, model._u, model._d), model._p)])
        n = ud.shape[0]
        args = (ud[:, :model.nu].T, ud[:, model.nu:].T)
        a = np.asarray(J.map(n)(np.tile(p0, (n, 1)).T, *args)).reshape(n, model.np)
        b = np.asarray(g.map(n)(np.tile(p0, (n, 1)).T, *args)).ravel()
        used = np.flatnonzero(np.any(a != 0, axis=0))
        if used.size == 0 or not set(used) <= {col.index for col in columns}:
            continue
        exps = sorted({col.experiment for col in columns if col.index in used} - {None})
        for e in exps or [None]:
            A = np.column_stack([a[:, col.index] * (col.experiment in (None, e))
                                 for col in columns])
            out.append(AffineRows(c.description or "constraint", A, b, c.min, c.max))
    return out


def solve(reg: Regression, data: ModelData, reference: np.ndarray, covariance: str,
          hac_bandwidth, bounds: tuple[np.ndarray, np.ndarray] | None = None,
          solver: str | None = None, loss: str = "squared",
          constraints: tuple[AffineRows, ...] = (),
          prior: tuple[np.ndarray, np.ndarray] | None = None) -> Solution:
    """Least squares (CVXPY with ``bounds`` and ``constraints``), covariance (white or
    HAC), identifiability.

    ``reference`` (columns) is where a rank-deficient regression stays closest to.
    ``loss="huber"``: the Huber M-estimate (CVXPY, threshold ``HUBER_M`` robust standard
    deviations of the residuals, re-estimated once), robust to outliers; its covariance is
    the M-estimator's sandwich (scores psi(e) z, the bread divided by the share of
    unclipped residuals; "white": the robust sigma^2 (Z^T Z)^-1).
    ``prior`` (mean, sd per column): maximum a posteriori (``prior_rows``); covariance
    sigma^2 (Za^T Za)^-1 ("white") or the data's HAC sandwich plus the prior rows'.
    """
    X, y = reg.X, reg.y
    n, k = X.shape
    scale = np.linalg.norm(X, axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    Z = X / scale
    s, Vt, keep = _svd(Z)
    rank = int(keep.sum())
    Zd, yd = Z, y
    Z, y, Rp, sig_p = prior_rows(Z, y, scale, rank, prior)
    if Rp.shape[0]:
        s, Vt, keep = _svd(Z)
    cond = float(s[0] / s[-1]) if s.size and s[-1] > 0 else math.inf
    # minimum-norm correction from the reference (scaled units): unique where identified
    phi_ref = reference * scale
    U = np.linalg.svd(Z, full_matrices=False)[0]
    r0 = y - Z @ phi_ref
    phi = phi_ref + Vt[keep].T @ ((U[:, keep].T @ r0) / s[keep])
    status, active = "optimal (lstsq)", ()
    lo, hi = bounds if bounds is not None else (np.full(k, -np.inf), np.full(k, np.inf))
    if loss == "huber":
        phi, status, active = _solve_bounded(Z, y, scale, lo, hi, reg.columns, solver, phi,
                                             constraints, huber=True)
    elif bounds is not None:
        rows = [r.A @ (phi / scale) + r.b for r in constraints]
        if np.any(phi / scale < lo - 1e-12) or np.any(phi / scale > hi + 1e-12) or any(
                np.any(v < r.min - 1e-12) or np.any(v > r.max + 1e-12)
                for v, r in zip(rows, constraints, strict=True)):
            phi, status, active = _solve_bounded(Z, y, scale, lo, hi, reg.columns, solver, phi,
                                                 constraints)
    theta = phi / scale
    if Rp.shape[0]:
        status = status.replace("lstsq", "lstsq, maximum a posteriori")
    y = yd
    resid = y - X @ theta
    dof = max(n - rank, 1)
    bread = (Vt[keep].T / s[keep] ** 2) @ Vt[keep]
    bandwidth = None
    psi, frac = resid, 1.0
    if loss == "huber":  # M-estimator: scores psi(e) z, bread E[psi'] Z^T Z
        c = HUBER_M * max(robust_std(resid), 1e-12 * (1.0 + float(np.abs(y).max())))
        frac = max(float(np.mean(np.abs(resid) <= c)), 1.0 / n)
        psi = np.clip(resid, -c, c)
    if covariance == "hac":
        order = np.argsort(reg.sample, kind="stable")
        scores = Zd * psi[:, None]
        # rows of one instant (several equations) make one score
        uniq, inv = np.unique(reg.sample[order], return_inverse=True)
        h = np.zeros((uniq.size, k))
        np.add.at(h, inv, scores[order])
        g = segment_ids(uniq, data.segments)
        bandwidth = resolve_bandwidth(hac_bandwidth, _centred_scores(X, psi, reg.sample,
                                                                     order, inv, uniq.size), g)
        meat = hac_meat(h, g, bandwidth) + sig_p**2 * (Rp.T @ Rp) * dof / n
        cov_phi = n / dof * (bread @ meat @ bread) / frac**2
    elif Rp.shape[0]:       # the posterior curvature, in the data's noise scale
        cov_phi = sig_p**2 * bread
    elif loss == "huber":
        cov_phi = robust_std(resid) ** 2 * bread
    else:
        cov_phi = float(resid @ resid) / dof * bread
    cov = cov_phi / np.outer(scale, scale)
    labels = tuple(c.label for c in reg.columns)
    ident, combos = combinations(Z, scale, labels, theta, cov)
    stderr = np.sqrt(np.clip(np.diag(cov), 0, None))
    stderr = np.where(np.array(ident), stderr, np.nan)
    return Solution(theta=theta, cov=cov, stderr=stderr, rank=rank, condition=cond,
                    residual_std=float(np.sqrt(resid @ resid / dof)), dof=dof,
                    identified=ident, combinations=tuple(combos), bandwidth=bandwidth,
                    active=active, status=status)


def _centred_scores(X, resid, sample, order, inv, n_inst) -> np.ndarray:
    """Scores with the regressors centred when the regression has a constant column (the
    intercept then absorbs the means): what the automatic HAC lag is chosen from, so that
    it does not depend on where a temperature's zero lies (kelvin or degC). The sandwich
    itself is invariant to that reparametrisation."""
    std = X.std(axis=0)
    const = (std <= 1e-12 * np.maximum(np.abs(X).max(axis=0), 1e-300)) & (np.abs(X[0]) > 0)
    Xc = X - np.where(const, 0.0, X.mean(axis=0)) if const.any() else X
    h = np.zeros((n_inst, X.shape[1]))
    np.add.at(h, inv, (Xc * resid[:, None])[order])
    return h


def robust_std(r: np.ndarray) -> float:
    """1.4826 x median absolute deviation: a standard deviation immune to a few outliers."""
    return float(1.4826 * np.median(np.abs(r - np.median(r))))


def _solve_bounded(Z, y, scale, lo, hi, columns, solver, phi_start, constraints=(),
                   huber: bool = False):
    """min ||Z phi - y||^2 (``huber``: the Huber loss of the residuals in robust standard
    deviations, the scale estimated from ``phi_start``'s residuals and once more from the
    first solution) with lo <= phi / scale <= hi and the affine ``constraints`` (CVXPY).

    Solved for the step from ``phi_start`` in units of its residuals' scale, in the
    orthonormal basis of Z's columns (Z = Q R) when Z has full rank: a kelvin column beside
    the constant one leaves Z ill-conditioned and the residuals are 1e-5 of y; the
    problem CVXPY sees is neither.
    """
    import cvxpy as cp

    k = Z.shape[1]
    Q, R = np.linalg.qr(Z)
    dg = np.abs(np.diag(R))
    if dg.size and dg.min() > _RANK_RTOL * dg.max():
        to_phi, basis = np.linalg.solve(R, np.eye(k)), Q       # phi = R^-1 w, Z phi = Q w
        w0 = R @ phi_start
    else:
        to_phi, basis, w0 = np.eye(k), Z, phi_start
    r0 = y - basis @ w0
    s = max(float(np.sqrt(np.mean(r0**2))), 1e-3 * float(np.std(y)),
            1e-12 * (1.0 + float(np.abs(y).max())))
    step = cp.Variable(k)                                    # w = w0 + s step
    phi_expr = to_phi @ w0 + s * (to_phi @ step)
    cons = [phi_expr[j] >= lo[j] * scale[j] for j in range(k) if math.isfinite(lo[j])]
    cons += [phi_expr[j] <= hi[j] * scale[j] for j in range(k) if math.isfinite(hi[j])]
    for r in constraints:   # rows over the step, each scaled to unit norm
        G = s * (r.A / scale) @ to_phi
        norm = np.maximum(np.linalg.norm(G, axis=1), 1e-300)
        g0 = (r.A / scale) @ (to_phi @ w0) + r.b
        g = (G / norm[:, None]) @ step
        cons += ([g >= (r.min - g0) / norm] if math.isfinite(r.min) else []) + \
            ([g <= (r.max - g0) / norm] if math.isfinite(r.max) else [])
    phi_now = phi_start
    for _ in range(2 if huber else 1):
        r = r0 / s - basis @ step
        sigma = robust_std(Z @ phi_now - y) / s
        if huber and sigma > 1e-6:   # else the data are fitted exactly: no outlier to bound
            objective = cp.sum(cp.huber(r / sigma, HUBER_M))
        else:
            objective = cp.sum_squares(r)
        prob = cp.Problem(cp.Minimize(objective), cons)
        try:
            prob.solve(solver=solver)
        except cp.error.SolverError as exc:
            return phi_start, f"CVXPY failed ({exc}); least-squares estimate kept", ()
        if step.value is None:
            return phi_start, f"CVXPY {prob.status}; least-squares estimate kept", ()
        phi_now = to_phi @ (w0 + s * np.asarray(step.value, dtype=float).ravel())
    theta = phi_now / scale
    active = []
    for j, c in enumerate(columns):
        for bound, side in ((lo[j], "min"), (hi[j], "max")):
            if math.isfinite(bound) and abs(theta[j] - bound) <= 1e-6 * (1 + abs(bound)):
                active.append(f"{c.label} at its {side} {bound:g}")
                theta[j] = bound
    for r in constraints:
        g = r.A @ theta + r.b
        for bound, side in ((r.min, "min"), (r.max, "max")):
            if math.isfinite(bound) and np.any(np.abs(g - bound) <= 1e-6 * (1 + abs(bound))):
                active.append(f"{r.label}: at its {side} {bound:g}")
    word = "Huber loss" if huber else "declared bounds"
    return theta * scale, f"{prob.status} (CVXPY, {word})", tuple(active)
