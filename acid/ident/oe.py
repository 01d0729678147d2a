"""Output error for any declared model: simulate windows of the data from estimated initial
states (latent ones included) and minimise the weighted simulation error of every measured
channel over the free parameters (per-experiment ones per experiment) and the initial
states, with ``scipy.optimize.least_squares`` (Levenberg-Marquardt when its optimum lies
inside the declared bounds, else trust-region reflective within them) and the exact
Jacobian of the window simulations from CasADi.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.optimize

from acid.errors import DataError
from acid.ident.data import ModelData
from acid.ident.hac import hac_meat, resolve_bandwidth, segment_ids
from acid.ident.linear import HUBER_M, robust_std
from acid.models.declaration import Model


@dataclass(frozen=True)
class Windows:
    """Consecutive windows of each experiment, padded to one length (``mask`` real samples)."""

    idx: np.ndarray      # (nw, L) sample indices
    mask: np.ndarray     # (nw, L)

    @classmethod
    def of(cls, segments, window: int) -> Windows:
        rows = []
        for a, b in segments:
            m = max(1, math.ceil((b - a) / window))
            rows += [np.arange(a, b)[part] for part in np.array_split(np.arange(b - a), m)]
        rows = [r for r in rows if r.size >= 2]
        if not rows:
            raise DataError("no experiment is long enough to simulate (need 2 samples each)")
        L = max(r.size for r in rows)
        return cls(idx=np.array([np.pad(r, (0, L - r.size), mode="edge") for r in rows]),
                   mask=np.array([np.arange(L) < r.size for r in rows]))


@functools.lru_cache(maxsize=16)
def _window_function(model: Model, L: int, free: tuple[int, ...] | None):
    """``W(x0, ud, p) -> Y`` ([x; y] over L samples of one window, (nx + ny, L)); with
    ``free`` (declared parameter indices) also its Jacobian w.r.t. [p[free], x0] (rows
    sample-major): forward directions only for what is estimated."""
    nx, nud = model.nx, model.nu + model.nd
    x, ud, p = ca.SX.sym("x", nx), ca.SX.sym("ud", nud), ca.SX.sym("p", model.np)
    xn, y = model.F(x, ud[:model.nu], ud[model.nu:], p)
    G = ca.Function("G", [x, ud, p], [xn, ca.vertcat(x, y)])
    acc = G.mapaccum("win", L)
    X0, UD, P = ca.MX.sym("x0", nx), ca.MX.sym("ud", nud, L), ca.MX.sym("p", model.np)
    if free is None:
        _, Y = acc(X0, UD, ca.repmat(P, 1, L))
        return ca.Function("window", [X0, UD, P], [Y])
    Pf = ca.MX.sym("pf", len(free))
    pos = {i: k for k, i in enumerate(free)}
    Pfull = ca.vertcat(*[Pf[pos[i]] if i in pos else P[i] for i in range(model.np)]) \
        if model.np else P
    _, Y = acc(X0, UD, ca.repmat(Pfull, 1, L))
    J = ca.jacobian(ca.vec(Y), ca.vertcat(Pf, X0))
    fn = ca.Function("window_jac", [X0, UD, P, Pf], [Y, J])
    return ca.Function("window", [X0, UD, P], fn(X0, UD, P, ca.vertcat(*[
        P[i] for i in free]) if free else ca.MX(0, 1)))


@functools.lru_cache(maxsize=32)
def _mapped(model: Model, L: int, free, nw: int):
    return _window_function(model, L, free).map(nw)


def simulate_windows(model: Model, data: ModelData, idx: np.ndarray, x0: np.ndarray,
                     P: np.ndarray, free: tuple[int, ...] | None = None):
    """Simulate windows ``idx`` (nw, L) from ``x0`` (nw, nx) with parameters ``P`` (nw, np).

    Returns ``Y`` (nw, L, nx + ny); with ``free`` (declared parameter indices, may be
    empty) also ``J`` (nw, L, nx + ny, len(free) + nx), the derivatives w.r.t. those
    parameters and the initial state.
    """
    nw, L = idx.shape
    free = None if free is None else tuple(int(i) for i in free)
    fn = _mapped(model, L, free, nw)
    ud = np.concatenate([data.u[idx], data.d[idx]], axis=-1)          # (nw, L, nud)
    out = fn(x0.T, ud.reshape(nw * L, -1).T, P.T)
    C = model.nx + model.ny
    Y = np.asarray(out[0] if free is not None else out).T.reshape(nw, L, C)
    if free is None:
        return Y
    J = np.asarray(out[1])                                            # (L C, nw (nf + nx))
    J = J.reshape(L, C, nw, len(free) + model.nx).transpose(2, 0, 1, 3)
    return Y, J


@dataclass(frozen=True)
class OEResult:
    theta: np.ndarray            # free parameter vector (layout of the fitter's columns)
    x0: np.ndarray               # (nw, nx) estimated initial states
    cov: np.ndarray
    stderr: np.ndarray
    loss: float
    status: str
    success: bool
    channel_rms: dict
    channel_fit: dict
    weights: np.ndarray
    n_windows: int
    window: int
    condition: float
    rank: int
    jacobian_scaled: np.ndarray  # parameter block, columns scaled (for identifiability)
    column_scale: np.ndarray
    bandwidth: int | None
    dof: int
    nfev: int = 0


class OEProblem:
    """Decision vector ``z = [theta (free columns), x0 of every window]``."""

    def __init__(self, model: Model, data: ModelData, columns, base_P: np.ndarray,
                 window: int, estimate_x0: bool = True):
        self.model, self.data, self.columns = model, data, columns
        self.w = Windows.of(data.segments, window)
        self.window = window
        nw = self.w.idx.shape[0]
        self.nw = nw
        self.win_exp = data.experiment[self.w.idx[:, 0]]
        self.base_P = base_P                                   # (nw, np) fixed values
        meas = data.observed()[self.w.idx]                              # (nw, L, C)
        self.chan = [c for c, _ in data.measured_channels(model)]
        self.chan_names = [n for _, n in data.measured_channels(model)]
        if not self.chan:
            raise DataError(f"{data.source}: no channel of model {model.name!r} is measured")
        meas = meas[..., self.chan]
        self.obs = np.isfinite(meas) & self.w.mask[..., None]
        self.meas = np.nan_to_num(meas)
        self.weights = np.array([max(float(np.nanstd(np.where(self.obs[..., i],
                                                              meas[..., i], np.nan))), 1e-9)
                                 for i in range(len(self.chan))])
        # map free columns -> window parameter vectors: P_w = base_P_w + E_w theta
        self.E = np.zeros((nw, model.np, len(columns)))
        for c, col in enumerate(columns):
            if col.experiment is None:
                self.E[:, col.index, c] = 1.0
            else:
                self.E[self.win_exp == col.experiment, col.index, c] = 1.0
        self.x0_start = data.initial_states(model, self.w.idx[:, 0])
        self.free = tuple(sorted({c.index for c in columns}))
        # initial states estimated per window: all, or (estimate_x0 False) the latent ones
        # only, the measured ones then start at their measurement
        self.x0_free = np.array([estimate_x0 or not s.measured for s in model.states],
                                dtype=bool)
        # declared priors (mean, sd) of the free columns: MAP rows (theta - mean) / sd
        pri = [(c, *model.parameters[col.index].prior) for c, col in enumerate(columns)
               if model.parameters[col.index].prior is not None]
        self.prior_cols = np.array([c for c, _, _ in pri], dtype=int)
        self.prior_mean = np.array([m for _, m, _ in pri], dtype=float)
        self.prior_sd = np.array([sd for _, _, sd in pri], dtype=float)

    @property
    def n_theta(self) -> int:
        return len(self.columns)

    def unpack(self, z):
        th = z[:self.n_theta]
        P = self.base_P + np.einsum("wpc,c->wp", self.E, th)
        x0 = self.x0_start.copy()
        x0[:, self.x0_free] = z[self.n_theta:].reshape(self.nw, int(self.x0_free.sum()))
        return th, P, x0

    def errors(self, z) -> np.ndarray:
        _, P, x0 = self.unpack(z)
        Y = simulate_windows(self.model, self.data, self.w.idx, x0, P)[..., self.chan]
        return Y - self.meas

    def residuals(self, z) -> np.ndarray:
        return (self.errors(z) / self.weights)[self.obs]

    def prior_residuals(self, z) -> np.ndarray:
        """The priors' rows of the MAP objective, ``(theta - mean) / sd`` (empty without)."""
        return (np.asarray(z)[self.prior_cols] - self.prior_mean) / self.prior_sd

    def prior_jacobian(self, n_z: int) -> np.ndarray:
        Jp = np.zeros((self.prior_cols.size, n_z))
        Jp[np.arange(self.prior_cols.size), self.prior_cols] = 1.0 / self.prior_sd
        return Jp

    def objective_residuals(self, z) -> np.ndarray:
        """Data rows, then prior rows: half their sum of squares is the negative log
        posterior (up to a constant) when the data rows are errors over their RMS."""
        return np.concatenate([self.residuals(z), self.prior_residuals(z)])

    def objective_jacobian(self, z) -> np.ndarray:
        J = self.jacobian(z)
        return np.vstack([J, self.prior_jacobian(J.shape[1])])

    def jacobian(self, z) -> np.ndarray:
        _, P, x0 = self.unpack(z)
        _, J = simulate_windows(self.model, self.data, self.w.idx, x0, P, free=self.free)
        J = J[:, :, self.chan, :] / self.weights[None, None, :, None]
        npar, nx = len(self.free), int(self.x0_free.sum())
        Jth = np.einsum("wlcp,wpk->wlck", J[..., :npar], self.E[:, list(self.free), :])
        Jx = np.zeros(J.shape[:3] + (self.nw * nx,))
        for w in range(self.nw):
            Jx[w, :, :, w * nx:(w + 1) * nx] = J[w, :, :, npar:][..., self.x0_free]
        return np.concatenate([Jth, Jx], axis=-1)[self.obs]


def solve(prob: OEProblem, theta0: np.ndarray, lo: np.ndarray, hi: np.ndarray,
          reweight: bool = True, covariance: str = "hac", hac_bandwidth="auto",
          max_nfev: int = 100, loss: str = "squared", progress=None) -> OEResult:
    """Minimise from ``theta0`` (clipped into the bounds); ``reweight``: a second pass with
    each channel weighted by its error RMS of the first (channels in their own units).
    ``loss="huber"``: the second pass weights each channel by its robust standard deviation
    and minimises the Huber loss (threshold ``HUBER_M``), robust to outliers. ``progress``:
    ``progress(evaluations, None, label)`` at every residual evaluation."""
    nx = int(prob.x0_free.sum())
    z = np.concatenate([np.clip(theta0, lo, hi), prob.x0_start[:, prob.x0_free].ravel()])
    zlo = np.concatenate([lo, np.full(prob.nw * nx, -np.inf)])
    zhi = np.concatenate([hi, np.full(prob.nw * nx, np.inf)])
    # keep the start strictly inside (trf needs it)
    with np.errstate(invalid="ignore"):
        z[:len(lo)] = np.where(np.isfinite(lo) & (z[:len(lo)] <= lo),
                               lo + 1e-9 * (1 + abs(lo)), z[:len(lo)])
        z[:len(hi)] = np.where(np.isfinite(hi) & (z[:len(hi)] >= hi),
                               hi - 1e-9 * (1 + abs(hi)), z[:len(hi)])
    res = None
    floor = 1e-3 * prob.weights
    count = {"n": 0, "pass": 1}

    def residuals(v):
        r = prob.objective_residuals(v)
        count["n"] += 1
        if progress is not None:
            progress(count["n"], None, f"pass {count['pass']}, evaluation {count['n']}, "
                                       f"objective {0.5 * float(r @ r):.6g}")
        return r

    robust = loss == "huber"
    for it in range(2 if (reweight or robust) else 1):
        if it == 1:
            e = prob.errors(z)
            rms = np.array([robust_std(e[..., i][prob.obs[..., i]]) if robust else
                            np.sqrt(np.mean(e[..., i][prob.obs[..., i]] ** 2))
                            for i in range(len(prob.chan))])
            prob.weights = np.maximum(rms, floor)
        count["pass"] = it + 1
        kwargs = {"loss": "huber", "f_scale": HUBER_M} if robust and it == 1 else {}
        res = None
        with np.errstate(all="ignore"):
            if not kwargs and prob.residuals(z).size >= z.size:
                # MINPACK's Levenberg-Marquardt first (its own QR: no BLAS threads, which
                # slow SVDs 100-fold on a busy machine); kept when it ends inside the bounds
                res = scipy.optimize.least_squares(
                    residuals, z, jac=prob.objective_jacobian, method="lm",
                    x_scale="jac",
                    ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=2 * max_nfev)
                inside = np.all((res.x >= zlo) & (res.x <= zhi))
                if not (inside and res.status > 0 and np.all(np.isfinite(res.x))):
                    res = None
            if res is None:  # trust-region reflective inside the declared bounds
                res = scipy.optimize.least_squares(
                    residuals, z, jac=prob.objective_jacobian,
                    bounds=(zlo, zhi), method="trf",
                    x_scale="jac", ftol=1e-12, xtol=1e-12, gtol=1e-10, max_nfev=max_nfev,
                    **kwargs)
        z = res.x
    return summarise(prob, z, res, covariance, hac_bandwidth, loss)


#: Relative singular-value threshold of the bread's pseudo-inverse.
RANK_RTOL = 1e-10


def _bread_full(Js: np.ndarray, nth: int) -> np.ndarray:
    """Columns ``:nth`` of ``pinv(Js' Js)`` by one SVD of the whole (n, p) Jacobian."""
    _, s, Vt = np.linalg.svd(Js, full_matrices=False)
    keep = s > RANK_RTOL * s[0]
    return (Vt[keep].T / s[keep] ** 2) @ Vt[keep, :nth]


def _bread_columns(Js: np.ndarray, nth: int, win: np.ndarray, nw: int, nxf: int):
    """Columns ``:nth`` of ``pinv(Js' Js)`` (``Js`` column-scaled ``[theta | x0 of each
    window]``, rows of window ``win``; the rows past ``win.size`` are the priors', on theta
    only), in time linear in the windows: each window's initial states are eliminated by
    the QR of their block (``Js`` is block-diagonal there), leaving the parameters' Schur
    complement ``J_theta' (I - P_x) J_theta``; its inverse and ``-R^-1 Q' J_theta`` of each
    window are the columns. The whole SVD (``_bread_full``) where a block or the complement
    is close to singular, so that the rank truncation stays the pseudo-inverse's."""
    if nxf == 0 or nw <= 1:
        return _bread_full(Js, nth)
    cut = np.searchsorted(win, np.arange(nw + 1))        # rows sorted by window
    T = Js[:, :nth].copy()
    blocks = []
    for w in range(nw):
        a, b = cut[w], cut[w + 1]
        Q, R = np.linalg.qr(Js[a:b, nth + w * nxf:nth + (w + 1) * nxf])
        d = np.abs(np.diag(R))
        if b - a < nxf or not d.size or d.min() <= 1e-8 * max(d.max(), 1e-300):
            return _bread_full(Js, nth)
        QtT = Q.T @ T[a:b]
        T[a:b] -= Q @ QtT
        blocks.append((R, QtT))
    _, s, Vt = np.linalg.svd(T, full_matrices=False)
    if not s.size or s[-1] <= 1e-8 * s[0]:
        return _bread_full(Js, nth)
    Sinv = (Vt.T / s ** 2) @ Vt
    rows = [Sinv] + [-np.linalg.solve(R, QtT) @ Sinv for R, QtT in blocks]
    return np.vstack(rows)


def summarise(prob: OEProblem, z, res, covariance: str, hac_bandwidth,
              loss: str = "squared") -> OEResult:
    J = prob.jacobian(z)
    r = prob.residuals(z)
    rp = prob.prior_residuals(z)
    loss_value = float(0.5 * (r @ r + rp @ rp))
    # the curvature (bread, rank, identifiability) carries the priors' rows; the scores
    # (HAC meat, the residual variance) the data's only
    Ja = np.vstack([J, prob.prior_jacobian(J.shape[1])])
    n, p = J.shape
    dof = max(n - p, 1)
    frac = 1.0
    if loss == "huber":  # the last pass minimised Huber(r, f_scale=HUBER_M): scores psi(r)
        frac = max(float(np.mean(np.abs(r) <= HUBER_M)), 1.0 / r.size)
        r = np.clip(r, -HUBER_M, HUBER_M)
    colnorm = np.linalg.norm(Ja, axis=0)
    colnorm = np.where(colnorm > 0, colnorm, 1.0)
    nth = prob.n_theta
    win = np.broadcast_to(np.arange(prob.nw)[:, None, None], prob.obs.shape)[prob.obs]
    # the parameters' columns of the bread (its other columns never reach their covariance)
    bread = _bread_columns(Ja / colnorm, nth, win, prob.nw, int(prob.x0_free.sum()))
    bread = bread / np.outer(colnorm, colnorm[:nth])
    bandwidth = None
    if covariance == "hac":
        # one score per instant (its channels summed), lags in time inside experiments;
        # the meat is bilinear in the scores, so B' meat(h) B = meat(h B): the scores are
        # projected on the parameters' bread columns first (nth columns, not nth + nw nx)
        inst = np.broadcast_to(prob.w.idx[..., None], prob.obs.shape)[prob.obs]
        uniq, inv = np.unique(inst, return_inverse=True)
        h = np.zeros((uniq.size, p))
        np.add.at(h, inv, J * r[:, None])
        g = segment_ids(uniq, prob.data.segments)
        bandwidth = resolve_bandwidth(hac_bandwidth, h[:, :nth], g)
        cov = n / dof * hac_meat(h @ bread, g, bandwidth) / frac**2
    else:
        cov = float(r @ r) / dof * bread[:nth] / frac**2
    Jth = Ja[:, :nth]
    cs = np.linalg.norm(Jth, axis=0)
    cs = np.where(cs > 0, cs, 1.0)
    sv = np.linalg.svd(Jth / cs, compute_uv=False) if nth else np.zeros(0)
    rank = int((sv > 1e-9 * sv[0]).sum()) if nth else 0
    e = prob.errors(z)
    meas = prob.meas
    rms, fit = {}, {}
    for i, name in enumerate(prob.chan_names):
        o = prob.obs[..., i]
        rms[name] = float(np.sqrt(np.mean(e[..., i][o] ** 2)))
        m = meas[..., i][o]
        den = np.linalg.norm(m - m.mean())
        fit[name] = float(100.0 * (1.0 - np.linalg.norm(e[..., i][o]) / den)) if den > 0 \
            else math.nan
    theta, _, x0 = prob.unpack(z)
    return OEResult(theta=theta.copy(), x0=x0.copy(), cov=cov,
                    stderr=np.sqrt(np.clip(np.diag(cov), 0, None)),
                    loss=loss_value, status=str(res.message) if res else "",
                    success=bool(res.status > 0) if res else False, channel_rms=rms,
                    channel_fit=fit, weights=prob.weights.copy(), n_windows=prob.nw,
                    window=prob.window,
                    condition=float(sv[0] / sv[-1]) if nth and sv[-1] > 0 else math.inf,
                    rank=rank, jacobian_scaled=Jth / cs, column_scale=cs,
                    bandwidth=bandwidth, dof=dof,
                    nfev=int(res.nfev) if res else 0)
