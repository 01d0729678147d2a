"""Prediction-error method with an extended Kalman filter, over any declared model.

Output error (``acid.ident.oe``) simulates windows open loop: an unmeasured load or a model
error accumulates along each window, so long records must be cut into short windows, each
with its own latent initial state. The prediction-error method instead runs an extended
Kalman filter over each whole experiment and minimises what the filter could not predict
one sample ahead (Ljung, *System Identification*, 2nd ed., 1999, sections 7.3 and 13.3;
Kristensen, Madsen, Jorgensen, "Parameter estimation in stochastic grey-box models",
Automatica 40 (2004) 225-237). The negative log-likelihood of the innovations,

.. math::

    J(\\theta) = \\sum_k \\log\\det S_k + e_k^T S_k^{-1} e_k,

with ``e_k`` the measured channels minus their one-step prediction and ``S_k`` its
covariance, is minimised over the free parameters (bounded): L-BFGS-B with its gradient
from CasADi's reverse mode through the whole filter recursion, then Newton steps with the
likelihood's Fisher information (from the innovations' and their covariances' first
derivatives, CasADi forward mode; nothing hand-derived; the exact Hessian, forward over
reverse, on request) until the Newton decrement is below
``acid.ident.ms.newton.DECREMENT_TOL`` (or the budget ends, and the status says why).

What the filter needs the declaration says (``acid.models.State``): ``noise`` (the state's
random increment per sample, a number or a parameter's name), ``spread`` (the standard
deviation of its initial value) and, for a measured state, ``sensor`` (the sensor's noise).
A latent state whose equation is zero with ``noise`` is a random walk: the filter estimates
an unmeasured load along the record. Parameters that only a noise names (``sigma_...``) are
estimated here even when declared ``fixed`` (output error cannot see them).

:func:`filter_states` runs the same filter over a stretch before each validation start
(``acid.ident.validate``'s ``warm_start="ekf"``): the latent states (and load) at the start
are the filter's estimate, then the prediction is open loop.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.optimize

from acid.errors import ConfigError, DataError
from acid.ident import linear
from acid.ident.data import ModelData
from acid.ident.ms.newton import newton
from acid.models.declaration import Model

#: Standard deviation (in the state's unit) of a filter's initial value when the
#: declaration gives no ``spread``: a measured state starts at its measurement.
DEFAULT_SPREAD_LATENT = 5.0
DEFAULT_SPREAD_MEASURED = 0.1
#: A measured state's sensor noise when the declaration gives no ``sensor``.
DEFAULT_SENSOR = 0.05
#: The normalised innovations' standard deviation within which a filter's noises count as
#: matching the data (1 when they do); outside it, with noises left at their defaults, the
#: fit warns.
NIS_CONSISTENT = (0.5, 2.0)


# ------------------------------------------------------------------ the filter's noises
def _noise_expr(model: Model, p, what: str) -> ca.SX:
    """The standard deviations ``what`` ("noise" or "sensor") of every state as
    expressions of the parameter vector ``p`` (0 where not declared)."""
    names = model.parameter_names
    out = []
    for s in model.states:
        v = getattr(s, what)
        if v is None:
            v = DEFAULT_SENSOR if what == "sensor" and s.measured else 0.0
        if isinstance(v, str):
            if v not in names:
                raise ConfigError(f"model {model.name!r}: state {s.name!r} {what}={v!r} "
                                  f"is not a parameter (parameters: {', '.join(names)})")
            out.append(p[names.index(v)])
        else:
            out.append(ca.SX(float(v)))
    return ca.vertcat(*out)


def noise_parameters(model: Model) -> tuple[str, ...]:
    """Parameters the states name as their noise or sensor (what only a filter sees)."""
    return tuple(dict.fromkeys(v for s in model.states for v in (s.noise, s.sensor)
                               if isinstance(v, str)))


def initial_spread(model: Model) -> np.ndarray:
    return np.array([s.spread if s.spread is not None else
                     (DEFAULT_SPREAD_MEASURED if s.measured else DEFAULT_SPREAD_LATENT)
                     for s in model.states], dtype=float)


@functools.lru_cache(maxsize=16)
def ekf_step(model: Model, chan: tuple[int, ...]) -> ca.Function:
    """One filter sample: update with the measured channels ``chan`` of [x | y] (``o``: 1
    where observed), then predict one sample ahead.

    ``(x, P, u, d, p, m, o) -> (x_next, P_next, cost, e, s2, x_filtered, S)``; ``cost``
    is this sample's ``log det S + e' S^-1 e`` (0 where nothing is observed), ``s2`` the
    innovations' variances, ``S`` their covariance (vectorised)."""
    nx, nc = model.nx, len(chan)
    x, u, d, p = (ca.SX.sym(n, k) for n, k in (("x", nx), ("u", model.nu),
                                                ("d", model.nd), ("p", model.np)))
    Pv = ca.SX.sym("P", nx * nx)
    m, o = ca.SX.sym("m", nc), ca.SX.sym("o", nc)
    P = ca.reshape(Pv, nx, nx)
    g = ca.vertcat(x, model.h(x, u, d, p))[list(chan)]
    H = ca.diag(o) @ ca.jacobian(g, x)
    r = _noise_expr(model, p, "sensor")
    rc = []
    for c in chan:       # sensor noise of the channel (outputs: the declared default)
        rc.append(r[c] if c < nx else ca.SX(DEFAULT_SENSOR))
    R = ca.diag(o * ca.vertcat(*rc) ** 2 + (1 - o))
    e = o * (m - g)
    S = H @ P @ H.T + R
    Si = ca.inv(S) if nc > 1 else 1.0 / S
    K = P @ H.T @ Si
    xf = x + K @ e
    IKH = ca.SX.eye(nx) - K @ H
    Pf = IKH @ P @ IKH.T + K @ R @ K.T                       # Joseph form
    cost = ca.log(ca.det(S)) + e.T @ Si @ e
    fx, _ = model.F(x, u, d, p)
    xn, A = ca.substitute([fx, ca.jacobian(fx, x)], [x], [xf])
    q = _noise_expr(model, p, "noise")
    Pn = A @ Pf @ A.T + ca.diag(q ** 2)
    Pn = 0.5 * (Pn + Pn.T)
    return ca.Function("ekf_step", [x, Pv, u, d, p, m, o],
                       [xn, ca.vec(Pn), cost, e, ca.diag(S), xf, ca.vec(S)])


@functools.lru_cache(maxsize=16)
def _run(model: Model, chan: tuple[int, ...], L: int, n: int) -> ca.Function:
    """The filter over ``n`` padded records of ``L`` samples each (``.map``)."""
    acc = ekf_step(model, chan).mapaccum("ekf", L, 2)
    return acc.map(n)


@dataclass(frozen=True)
class _Records:
    """Each experiment (or stretch) padded to one length; ``o`` 0 on the padding."""

    x0: np.ndarray     # (n, nx)
    P0: np.ndarray     # (n, nx * nx)
    u: np.ndarray      # (n, L, nu)
    d: np.ndarray
    m: np.ndarray      # (n, L, nc)
    o: np.ndarray
    idx: np.ndarray    # (n, L) sample indices (edge-padded)
    real: np.ndarray   # (n, L) True on real samples

    @classmethod
    def of(cls, model: Model, data: ModelData, chan, spans) -> _Records:
        L = max(b - a for a, b in spans)
        idx = np.array([np.pad(np.arange(a, b), (0, L - (b - a)), mode="edge")
                        for a, b in spans])
        real = np.array([np.arange(L) < b - a for a, b in spans])
        meas = data.observed()[idx][..., list(chan)]
        o = (np.isfinite(meas) & real[..., None]).astype(float)
        x0 = data.initial_states(model, idx[:, 0])
        P0 = np.tile(np.diag(initial_spread(model) ** 2).ravel(), (len(spans), 1))
        return cls(x0=x0, P0=P0, u=data.u[idx], d=data.d[idx], m=np.nan_to_num(meas), o=o,
                   idx=idx, real=real)

    def call(self, fn, P: np.ndarray):
        """``fn`` (``_run``) with parameters ``P`` (n, np): outputs as arrays."""
        n, L = self.idx.shape

        def cols(a):                           # (n, L, k) -> (k, n L)
            return a.reshape(n * L, a.shape[-1]).T
        Pm = np.repeat(P, L, axis=0).T
        return fn(self.x0.T, self.P0.T, cols(self.u), cols(self.d), Pm, cols(self.m),
                  cols(self.o))


def _measured(model: Model, data: ModelData) -> tuple[int, ...]:
    chan = tuple(c for c, _ in data.measured_channels(model))
    if not chan:
        raise DataError(f"{data.source}: no channel of model {model.name!r} is measured")
    return chan


# ----------------------------------------------------------------------- the fit
def _fisher(Z: ca.MX, J: ca.MX, J_prior: ca.MX, e: ca.MX, Sv: ca.MX, nc: int):
    """``z -> (J, g, F)``: the loss, its exact gradient and the Fisher information of
    ``J = -2 log L`` (Gauss-Newton for the innovations' likelihood),

    .. math::

        F_{ab} = \\sum_k 2\\,\\partial_a e_k^T S_k^{-1} \\partial_b e_k
                 + \\mathrm{tr}(S_k^{-1} \\partial_a S_k S_k^{-1} \\partial_b S_k),

    the expected Hessian of a Gaussian innovations' likelihood (Ljung 1999, section 9.2;
    Kristensen et al. 2004, section 2.3), plus the exact (constant) Hessian of the priors
    ``J_prior``. It needs only the first derivatives of the innovations ``e`` (nc, N) and
    their covariances ``Sv`` (nc*nc, N) over the parameters: one forward sweep through the
    filter per parameter direction (CasADi), where the exact Hessian takes a forward sweep
    over the whole reverse one per direction. Positive semidefinite, so each Newton step
    goes downhill; at the optimum of a well-specified model it equals the Hessian's
    expectation, and ``2 F^-1`` is the parameters' asymptotic covariance."""
    nz = Z.numel()
    fn = ca.Function("pem_fisher", [Z], [J, ca.gradient(J, Z), e, Sv,
                                         ca.jacobian(ca.vec(e), Z), ca.jacobian(ca.vec(Sv), Z),
                                         ca.hessian(J_prior, Z)[0]])

    def at(z):
        f, g, ev, sv, je, js, hp = fn(z)
        N = np.asarray(ev).shape[1]
        S = np.asarray(sv).T.reshape(N, nc, nc).transpose(0, 2, 1)        # column-major
        Je = np.asarray(je).reshape(N, nc, nz)
        Js = np.asarray(js).reshape(N, nc, nc, nz).transpose(0, 2, 1, 3)
        Si = np.linalg.inv(S)
        F = 2.0 * np.einsum("kia,kij,kjb->ab", Je, Si, Je, optimize=True)
        T = np.einsum("kij,kjla->kila", Si, Js, optimize=True)             # S^-1 dS_a
        F += np.einsum("kila,klib->ab", T, T, optimize=True)
        return float(f), np.asarray(g).ravel(), F + np.asarray(hp)
    return at


class _Cap(Exception):
    """The evaluation cap is reached."""


@dataclass(frozen=True)
class PEMResult:
    """What :func:`solve` found (the free columns' values and the filter's summary)."""

    theta: np.ndarray
    cov: np.ndarray
    stderr: np.ndarray
    loss: float                  # J at the optimum (negative log-likelihood x 2 + const)
    status: str
    success: bool
    nfev: int
    channel_rms: dict            # RMS of the one-step innovations per channel
    channel_fit: dict            # one-step fit % per channel
    innovations: np.ndarray      # (n_obs,) normalised innovations e / sqrt(s2), time order
    n_records: int
    condition: float             # of the curvature over the parameters inside their bounds
    identified: np.ndarray       # (n,) False: on a bound, or in a direction of no curvature


def _curvature_covariance(H: np.ndarray, z, zlo, zhi, rtol: float = 1e-8):
    """Covariance 2 H^-1 (J is -2 log L + const) over the parameters inside their bounds;
    NaN for a parameter on a bound or with weight in a direction the loss does not curve
    (the data do not fix it)."""
    k = z.size
    cov = np.full((k, k), np.nan)
    inner = ~(np.isclose(z, zlo, rtol=0, atol=1e-6) | np.isclose(z, zhi, rtol=0, atol=1e-6))
    ident = inner.copy()
    if not inner.any():
        return cov, ident, math.nan
    w, V = np.linalg.eigh(H[np.ix_(inner, inner)])
    keep = w > rtol * max(w.max(), 0.0)
    flat = (np.abs(V[:, ~keep]) > 1e-3).any(axis=1)
    sub = 2.0 * (V[:, keep] / w[keep]) @ V[:, keep].T
    sub[flat, :] = np.nan
    sub[:, flat] = np.nan
    cov[np.ix_(inner, inner)] = sub
    ident[np.flatnonzero(inner)[flat]] = False
    return cov, ident, float(w.max() / w[keep].min()) if keep.any() else math.inf


#: ``max_nfev`` split: L-BFGS-B gets max_nfev // LBFGS_SHARE gradient evaluations, the Newton
#: phase max_nfev // HESSIAN_SHARE curvature matrices (Fisher or exact). A third for
#: L-BFGS-B was faster on the paper model (1 / 4 h: 3.2 / 12.9 CPU-s against 4.6 / 18.0
#: with all) but with a small budget (car_cabin, 4 real trips, 40 evaluations) it ended
#: farther from the optimum and predicted held-out trips worse (p90 2.01 K at 300 s against
#: persistence's 1.87); with all of them the Newton steps only lower the loss L-BFGS-B alone
#: reached before.
LBFGS_SHARE = 1
HESSIAN_SHARE = 10
#: The same for Fisher matrices (the default curvature): cheaper than an exact Hessian (car_cabin,
#: 13 summer trips: 2.0 against 4.4 CPU-s) but converging only linearly where the model
#: misses part of the data, so more of them: with max_nfev // 10 car_cabin stopped at
#: Newton decrement 0.026, with max_nfev // 4 at 3.9e-6 (the exact Hessian: 2.3e-7 after 8).
FISHER_SHARE = 3


def solve(model: Model, data: ModelData, columns, base: np.ndarray, theta0: np.ndarray,
          lo: np.ndarray, hi: np.ndarray, max_nfev: int = 100, progress=None,
          curvature: str = "fisher") -> PEMResult:
    """Minimise the innovations' negative log-likelihood over the free ``columns``
    (``acid.ident.linear.Column``; per-experiment ones by experiment) from ``theta0``,
    within [lo, hi]; ``base`` (E, np) the values of everything else per experiment.
    ``curvature``: what the second phase's Newton steps (and the covariance) use,
    ``"fisher"`` (the likelihood's Fisher information from the innovations' first
    derivatives, :func:`_fisher`) or ``"exact"`` (CasADi's exact Hessian: forward over
    reverse through the whole filter, too slow on many long records)."""
    if curvature not in ("fisher", "exact"):
        raise ConfigError(f"curvature must be 'fisher' or 'exact', not {curvature!r}")
    chan = _measured(model, data)
    rec = _Records.of(model, data, chan, data.segments)
    n, L = rec.idx.shape
    exp = data.experiment[rec.idx[:, 0]]
    Emap = np.zeros((n, model.np, len(columns)))
    for c, col in enumerate(columns):
        Emap[(exp == col.experiment) if col.experiment is not None else slice(None),
             col.index, c] = 1.0
    # theta = a + b zeta, zeta in [0, 1] where both bounds are finite
    fin = np.isfinite(lo) & np.isfinite(hi)
    a = np.where(fin, lo, 0.0)
    b = np.where(fin, hi - lo, np.maximum(np.abs(theta0), 1.0))
    zlo = np.where(np.isfinite(lo), (lo - a) / b, -np.inf)
    zhi = np.where(np.isfinite(hi), (hi - a) / b, np.inf)

    Z = ca.MX.sym("z", len(columns))
    th = ca.DM(a) + ca.DM(b) * Z
    Pbase = ca.DM(np.repeat(base[exp], L, axis=0).T)
    Emx = np.repeat(Emap, L, axis=0)                           # (n L, np, nc)
    cols = []
    for c in range(len(columns)):
        cols.append(ca.DM(Emx[:, :, c].T) * th[c])
    Pm = Pbase + sum(cols) if cols else Pbase

    def flat(v):
        return ca.DM(v.reshape(n * L, v.shape[-1]).T)
    out = _run(model, chan, L, n)(ca.DM(rec.x0.T), ca.DM(rec.P0.T), flat(rec.u),
                                   flat(rec.d), Pm, flat(rec.m), flat(rec.o))
    J = Jdata = ca.sum2(out[2])
    pri = [(c, *model.parameters[col.index].prior) for c, col in enumerate(columns)
           if model.parameters[col.index].prior is not None]
    if pri:   # declared priors: -2 log of each Gaussian prior (J is -2 log L + const)
        J = J + ca.sumsqr((ca.vertcat(*[th[c] for c, _, _ in pri])
                           - ca.DM([m for _, m, _ in pri])) / ca.DM([sd for _, _, sd in pri]))
    fg = ca.Function("pem_cost", [Z], [J, ca.gradient(J, Z)])
    ev = ca.Function("pem_out", [Z], [out[3], out[4]])
    count = {"n": 0}
    best = [math.inf, None]
    # the budget: max_nfev gradient evaluations for L-BFGS-B, then up to max_nfev / 10
    # Fisher matrices (or exact Hessians; each ~2 gradients on the paper model)
    n_grad = max(1, int(max_nfev) // LBFGS_SHARE)
    n_hess = max(1, int(max_nfev) // (HESSIAN_SHARE if curvature == "exact" else FISHER_SHARE))

    def fun(z):
        if count["n"] >= n_grad:          # the cap holds inside a line search too
            raise _Cap
        count["n"] += 1
        f, g = fg(z)
        f = float(f)
        if not math.isfinite(f):   # the filter diverged (e.g. an unstable step): far uphill,
            ref, zb = (best[0], best[1]) if best[1] is not None else (0.0, z0)
            return ref + 1e6 * (1 + abs(ref)), 1e6 * (1 + abs(ref)) * (z - zb)  # back
        if f < best[0]:
            best[:] = [f, z.copy()]
        if progress is not None:
            progress(count["n"], n_grad, f"evaluation {count['n']} of at most {n_grad}, "
                                           f"-2 log likelihood {best[0]:.6g}")
        return f, np.asarray(g).ravel()

    z0 = np.clip((np.asarray(theta0, float) - a) / b, zlo, zhi)
    # L-BFGS-B first (an evaluation is one gradient), then Newton steps with the exact
    # Hessian (CasADi, forward over reverse through the filter) until the Newton decrement
    # says the optimum is reached: quadratic convergence where L-BFGS-B crawls
    try:
        res = scipy.optimize.minimize(fun, z0, jac=True, method="L-BFGS-B",
                                      bounds=list(zip(zlo, zhi, strict=True)),
                                      options={"maxfun": n_grad,
                                               "maxiter": n_grad, "ftol": 1e-12,
                                               "gtol": 1e-8})
        z = res.x
    except _Cap:
        z = best[1] if best[1] is not None else z0
    if curvature == "exact":
        hess = ca.Function("pem_hess", [Z], [J, ca.gradient(J, Z), ca.hessian(J, Z)[0]])
    else:
        hess = _fisher(Z, J, J - Jdata, out[3], out[6], len(chan))
    newton_ = newton(hess, ca.Function("pem_loss", [Z], [J]), z, zlo, zhi,
                     max_hessians=n_hess, report=None if progress is None else (
                         lambda label: progress(count["n"], None, label)),
                     kind="exact Hessians" if curvature == "exact" else "Fisher matrices")
    # the covariance from the curvature at the end point (J is -2 log L + const)
    z, loss, H = newton_.z, newton_.loss, newton_.H
    status, success = newton_.status(count["n"], n_grad, n_hess), newton_.converged
    cov, identified, cond = _curvature_covariance(H, z, zlo, zhi)
    cov = cov * np.outer(b, b)
    e, s2 = (np.asarray(v).reshape(len(chan), n, L) for v in ev(z))
    obs = rec.o.transpose(2, 0, 1) > 0
    rms, fit = {}, {}
    names = [n_ for c, n_ in data.measured_channels(model)]
    for i, name in enumerate(names):
        ei = e[i][obs[i]]
        mi = rec.m[..., i][obs[i].reshape(n, L)]
        rms[name] = float(np.sqrt(np.mean(ei ** 2))) if ei.size else math.nan
        den = np.linalg.norm(mi - mi.mean()) if mi.size else 0.0
        fit[name] = float(100 * (1 - np.linalg.norm(ei) / den)) if den > 0 else math.nan
    innov = (e / np.sqrt(np.maximum(s2, 1e-300)))[obs]
    return PEMResult(theta=a + b * z, cov=cov, stderr=np.sqrt(np.diag(cov)),
                     loss=loss, status=status, success=success,
                     nfev=count["n"], channel_rms=rms, channel_fit=fit, innovations=innov,
                     n_records=n, condition=cond, identified=identified)


def columns_for(model: Model, data: ModelData, fix: dict | None = None):
    """The free columns of a PEM fit: the free parameters (per-experiment ones per
    experiment) and the noise parameters the states name, unless ``fix`` holds them."""
    fix = dict(fix or {})
    noise = set(noise_parameters(model)) - set(fix)
    cols = []
    for i, p in enumerate(model.parameters):
        if p.fixed and p.name not in noise:
            continue
        if p.per_experiment:
            cols += [linear.Column(i, p.name, e) for e in range(data.n_experiments)]
        else:
            cols.append(linear.Column(i, p.name))
    return tuple(cols)


# ---------------------------------------------------------------- validation starts
def filter_states(model: Model, data: ModelData, P: np.ndarray, k0: np.ndarray,
                  W) -> np.ndarray:
    """(len(k0), nx): the filter's estimate of the state at each start ``k0`` (the
    measurement at ``k0`` included), run over the ``W`` samples before it (a number, or one
    per start) from the declared initial rules; ``P`` (len(k0), np) the parameters of each
    start."""
    chan = _measured(model, data)
    k0 = np.asarray(k0, dtype=int)
    W = np.broadcast_to(np.asarray(W, dtype=int), k0.shape)
    rec = _Records.of(model, data, chan, [(k - w, k + 1) for k, w in zip(k0, W,
                                                                        strict=True)])
    n, L = rec.idx.shape
    out = rec.call(_run(model, chan, L, n), P)
    xf = np.asarray(out[5]).reshape(model.nx, n, L)
    return xf[:, np.arange(n), W].T          # each stretch's last real sample


def fit_pem(model: Model, ds, *, fix: dict | None = None, max_nfev: int = 100,
            t0: float | None = None, progress=None, curvature: str = "fisher"):
    """``fit_model(..., method="pem")``: the declared table fitted by the prediction-error
    method over each whole experiment; a ``DeclaredFitResult`` (standard errors from the
    likelihood's curvature, 95 % normal intervals)."""
    import time

    from acid.ident.result import DeclaredFitResult, Estimate

    t0 = time.perf_counter() if t0 is None else t0
    data = ModelData.of(model, ds)
    E = data.n_experiments
    columns = columns_for(model, data, fix)
    declared = model.values
    lo = np.array([model.parameters[c.index].min for c in columns])
    hi = np.array([model.parameters[c.index].max for c in columns])
    base = np.tile(declared, (E, 1))
    for c in columns:
        base[:, c.index] = 0.0
    res = solve(model, data, columns, base, declared[[c.index for c in columns]], lo, hi,
                max_nfev=max_nfev, progress=progress, curvature=curvature)
    values = declared.copy()
    names = model.parameter_names
    per = {p.name: np.full(E, p.value) for p in model.parameters if p.per_experiment}
    for k, c in enumerate(columns):
        if c.experiment is None:
            values[c.index] = res.theta[k]
        else:
            per[c.name][c.experiment] = res.theta[k]
    for nm, v in per.items():
        values[names.index(nm)] = float(np.mean(v))
    estimates = []
    for i, p in enumerate(model.parameters):
        ks = [k for k, c in enumerate(columns) if c.index == i]
        if not ks:
            rows = [None] + (list(range(E)) if p.per_experiment else [])
            estimates += [Estimate(p.name, p.unit, p.value, p.value, math.nan,
                                   (math.nan, math.nan), "fixed", e) for e in rows]
            continue
        for k in ks:
            se = float(res.stderr[k])
            ci = (res.theta[k] - 1.96 * se, res.theta[k] + 1.96 * se)
            estimates.append(Estimate(p.name, p.unit, p.value, float(res.theta[k]), se, ci,
                                      "estimated (pem)" if res.identified[k] else
                                      "not fixed by the data", columns[k].experiment))
    latent = [s.name for s in model.states if not s.measured]
    walks = [s.name for s in model.states if s.noise is not None]
    notes = [f"prediction-error method: an extended Kalman filter over {res.n_records} "
             "whole experiments, the innovations' negative log-likelihood minimised "
             "(L-BFGS-B, then Newton steps with the "
             + ("exact Hessian" if curvature == "exact" else "Fisher information")
             + "; CasADi derivatives)"
             + (f"; latent: {', '.join(latent)}" if latent else "")
             + (f"; states with process noise: {', '.join(walks)}" if walks else "")]
    if linear.prior_note(model, columns, res.theta):
        notes.append(linear.prior_note(model, columns, res.theta))
    at = [f"{c.label} at its {w} {bd:g}" for c, t, a, z in zip(columns, res.theta, lo, hi,
                                                                strict=True)
          for bd, w in ((a, "min"), (z, "max"))
          if math.isfinite(bd) and abs(t - bd) <= 1e-6 * (1 + abs(bd))]
    # the parameters on a bound are named by the result's on_bounds (the CLI prints them)
    warn = [] if res.success else [f"prediction-error fit did not converge ({res.status})"]
    loose = [c.label for c, ok in zip(columns, res.identified, strict=True) if not ok]
    if loose:
        warn.append("prediction error: on a bound or not fixed by the data (no standard "
                    f"error): {', '.join(loose)}")
    nis = float(np.std(res.innovations)) if res.innovations.size else math.nan
    undeclared = [s.name for s in model.states
                  if (s.measured and s.sensor is None) or s.noise is None]
    if undeclared and math.isfinite(nis) and not (NIS_CONSISTENT[0] <= nis <= NIS_CONSISTENT[1]):
        unit = {s.name: s.unit for s in model.states + model.outputs}
        warn.append(
            f"prediction error: the filter's noises do not match the data (normalised "
            f"innovations' std {nis:.3g}, 1 when they do); the states {', '.join(undeclared)} "
            f"take the defaults (sensor {DEFAULT_SENSOR:g} in a measured state's unit, no "
            "process noise): declare State(..., sensor=..., noise=...) in the model's units "
            "(the one-step errors' RMS: " + ", ".join(
                f"{k} {v:.3g} {unit.get(k, '')}".rstrip() for k, v in res.channel_rms.items())
            + ") or fit by output error (--method oe)")
    summary = {"records": res.n_records, "loss": res.loss, "status": res.status,
               "converged": res.success, "nfev": res.nfev,
               "innovation_rms": res.channel_rms, "one_step_fit_percent": res.channel_fit,
               "normalised_innovation_std": float(np.std(res.innovations))
               if res.innovations.size else math.nan,
               "condition": res.condition, "n_parameters": len(columns)}
    return DeclaredFitResult(
        model=model.name, model_source=model.source, method="pem", declaration=model,
        estimates=tuple(estimates), equations=(), values=values, per_experiment=per,
        experiment_ids=data.experiment_ids, covariance=res.cov,
        covariance_names=tuple(c.label for c in columns), covariance_kind="hessian",
        hac_bandwidth={}, output_error=summary, optima=(), combinations=(),
        notes=tuple(notes), warnings=tuple(warn), n_samples=len(ds),
        data_source=ds.source, elapsed_s=time.perf_counter() - t0, on_bounds=tuple(at))
