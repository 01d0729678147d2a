"""Output error as one sparse multiple-shooting NLP: the same problem as
:func:`acid.ident.oe.solve` (same windows, weights, free initial states of each window,
declared bounds, the reweighted second pass), written with every sample's state as a
shooting node and the model's step as equality constraints, solved by IPOPT (CasADi's
``nlpsol``, MUMPS, exact first derivatives from CasADi, the Gauss-Newton Hessian). Its cost
and its Jacobian/Hessian sparsity grow linearly with the data, where the dense
formulation's Jacobian (every window's parameters times every sample) and its QR grow
faster. The covariance and report come from
:func:`acid.ident.oe.summarise`, as for the dense solver.
"""

from __future__ import annotations

from types import SimpleNamespace

import casadi as ca
import numpy as np

from acid.errors import DataError
from acid.ident.oe import OEProblem, OEResult, simulate_windows, summarise

#: IPOPT's convergence tolerance (scaled NLP error): tight enough that the optimum equals
#: the dense Levenberg-Marquardt one to 1e-6 relative.
TOL = 1e-10
#: IPOPT stops as "Solved_To_Acceptable_Level" after 3 iterations in a row below this: a
#: channel fitted exactly (its weight floored) keeps the scaled error above TOL, where
#: IPOPT's restoration phase then fails at the optimum (paper model: same parameters to 2e-7).
ACCEPTABLE_TOL = 1e-6


def build(prob: OEProblem, theta_scale: np.ndarray):
    """The NLP of ``prob``: (nlp dict, helper namespace).

    Decision vector ``v = [t (theta / theta_scale), X (nx, nw L) column-major]``; parameter
    ``w``: the channels' weights (one NLP, hence one IPOPT set-up, for both passes)."""
    m = prob.model
    nx, nud, npar = m.nx, m.nu + m.nd, m.np
    nw, L = prob.w.idx.shape
    N = nw * L
    nth = prob.n_theta
    t = ca.MX.sym("t", nth)
    X = ca.MX.sym("X", nx, N)
    theta = t * ca.DM(theta_scale)
    # window parameters P (np, nw) = base + E theta (E: (nw, np, nth)) -> per sample
    M = ca.DM(prob.E.reshape(nw * npar, nth))             # row w * np + p
    Pw = ca.reshape(ca.DM(prob.base_P.reshape(-1)) + ca.mtimes(ca.sparsify(M), theta),
                    npar, nw)
    S = ca.DM(ca.Sparsity(nw, N, list(range(N + 1)),
                          [k // L for k in range(N)]), 1.0)   # window of each sample
    Pk = ca.mtimes(Pw, S)
    ud = np.concatenate([prob.data.u[prob.w.idx], prob.data.d[prob.w.idx]], axis=-1)
    UD = ca.DM(ud.reshape(N, nud).T)
    x, u, p = ca.SX.sym("x", nx), ca.SX.sym("ud", nud), ca.SX.sym("p", npar)
    xn, y = m.F(x, u[:m.nu], u[m.nu:], p)
    chan = [int(c) for c in prob.chan]
    G = ca.Function("G", [x, u, p], [xn, ca.vertcat(x, y)[chan]])
    XN, Yc = G.map(N)(X, UD, Pk)
    # continuity inside each window: X[:, k + 1] = F(X[:, k]) unless k + 1 starts a window
    nxt = [k for k in range(N) if k % L]
    g = ca.vec(X[:, nxt] - XN[:, [k - 1 for k in nxt]])
    meas = prob.meas.reshape(N, -1).T                      # (C, N)
    obs = prob.obs.reshape(N, -1).T.astype(float)
    wp = ca.MX.sym("w", len(chan))
    R = (Yc - ca.DM(meas)) * ca.DM(obs) * ca.repmat(1.0 / wp, 1, N)
    r = ca.vec(R)
    if prob.prior_cols.size:   # declared priors: the MAP rows (theta - mean) / sd
        r = ca.vertcat(r, (theta[[int(c) for c in prob.prior_cols]] - ca.DM(prob.prior_mean))
                       / ca.DM(prob.prior_sd))
    f = 0.5 * ca.sumsqr(r)
    v = ca.vertcat(t, ca.vec(X))
    return {"x": v, "p": wp, "f": f, "g": g}, SimpleNamespace(
        N=N, nw=nw, L=L, nx=nx, nth=nth, ng=int(g.numel()), r=r, v=v, g=g, w=wp)


def gauss_newton(nlp: dict, h) -> ca.Function:
    """IPOPT's ``hess_lag``: the Gauss-Newton Hessian ``lam_f J_r' J_r`` (upper triangle)
    of the weighted residuals, the constraints' curvature left out: positive semidefinite,
    its sparsity is the stages' blocks plus the parameter rows, built in linear time."""
    v, r = h.v, h.r
    Jr = ca.jacobian(r, v)
    lam_f = ca.MX.sym("lam_f")
    lam_g = ca.MX.sym("lam_g", h.ng)
    H = ca.triu(lam_f * ca.mtimes(Jr.T, Jr))
    return ca.Function("nlp_hess_l", [v, h.w, lam_f, lam_g], [H],
                       ["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"])


def _start_states(prob: OEProblem, theta: np.ndarray) -> np.ndarray:
    """(nx, nw L) the window simulations from their starting states: the initial guess of
    every shooting node (measured states where a simulation overflows)."""
    _, P, x0 = prob.unpack(np.concatenate([theta, prob.x0_start[:, prob.x0_free].ravel()]))
    with np.errstate(all="ignore"):
        Y = simulate_windows(prob.model, prob.data, prob.w.idx, x0, P)[..., :prob.model.nx]
    meas = np.nan_to_num(prob.data.x[prob.w.idx])
    Y = np.where(np.isfinite(Y), Y, meas)
    return Y.reshape(-1, prob.model.nx).T


def solve_ms(prob: OEProblem, theta0: np.ndarray, lo: np.ndarray, hi: np.ndarray,
             reweight: bool = True, covariance: str = "hac", hac_bandwidth="auto",
             max_iter: int = 300, loss: str = "squared") -> OEResult:
    """:func:`acid.ident.oe.solve` by IPOPT on the multiple-shooting NLP (``loss`` squared
    only); ``max_iter``: IPOPT iterations per pass."""
    if loss != "squared":
        raise DataError("the multiple-shooting output error minimises the squared loss only; "
                        "use the dense solver for the Huber loss")
    theta = np.clip(np.asarray(theta0, float), lo, hi)
    scale = np.maximum(np.abs(theta), 1e-6)
    X = _start_states(prob, theta)
    floor = 1e-3 * prob.weights
    nx = prob.model.nx
    res = None
    iters = 0
    # one NLP, one IPOPT set-up for both passes: the weights are the NLP's parameter
    nlp, h = build(prob, scale)
    # a state a window does not estimate starts at (is fixed to) its measurement
    lbx = np.full(h.nth + nx * h.N, -np.inf)
    ubx = np.full(h.nth + nx * h.N, np.inf)
    lbx[:h.nth], ubx[:h.nth] = lo / scale, hi / scale
    for w in range(h.nw):
        for s in np.flatnonzero(~prob.x0_free):
            k = h.nth + w * h.L * nx + s
            lbx[k] = ubx[k] = prob.x0_start[w, s]
    opts = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
            "ipopt.tol": TOL, "ipopt.acceptable_tol": ACCEPTABLE_TOL,
            "ipopt.acceptable_iter": 3,
            "ipopt.max_iter": int(max_iter), "ipopt.linear_solver": "mumps",
            "hess_lag": gauss_newton(nlp, h)}
    solver = ca.nlpsol("oe_ms", "ipopt", nlp, opts)
    for it in range(2 if reweight else 1):
        if it == 1:
            e = prob.errors(_z(prob, theta, X))
            rms = np.array([np.sqrt(np.mean(e[..., i][prob.obs[..., i]] ** 2))
                            for i in range(len(prob.chan))])
            prob.weights = np.maximum(rms, floor)
        v0 = np.concatenate([theta / scale, X.T.ravel()])
        v0[:h.nth] = np.clip(v0[:h.nth], lbx[:h.nth], ubx[:h.nth])
        # the second pass starts from the first's primal point, cold in its multipliers: a
        # warm start (IPOPT's warm_start_init_point, mu_init 1e-8) took as many iterations
        # and needs its own solver set-up (1.2 s at 16 h of data)
        out = solver(x0=v0, p=prob.weights, lbx=lbx, ubx=ubx, lbg=0, ubg=0)
        st = solver.stats()
        v = np.asarray(out["x"]).ravel()
        theta = v[:h.nth] * scale
        X = v[h.nth:].reshape(h.N, nx).T
        iters += int(st.get("iter_count", 0))
        ok = bool(st.get("success", False))
        res = SimpleNamespace(message=f"IPOPT: {st.get('return_status', '?')} "
                                      f"({iters} iterations)",
                              status=1 if ok else 0, nfev=iters)
    return summarise(prob, _z(prob, theta, X), res, covariance, hac_bandwidth, loss)


def _z(prob: OEProblem, theta: np.ndarray, X: np.ndarray) -> np.ndarray:
    """The dense solver's decision vector [theta, free initial states of every window]."""
    nw, L = prob.w.idx.shape
    x0 = X[:, ::L][:, :nw].T                                 # (nw, nx)
    return np.concatenate([theta, x0[:, prob.x0_free].ravel()])


def nlp_size(prob: OEProblem) -> dict:
    """Variables, constraints and the nonzeros of the constraint Jacobian and of the
    Gauss-Newton Hessian IPOPT factorises: they grow linearly with the samples."""
    nlp, h = build(prob, np.ones(prob.n_theta))
    H = gauss_newton(nlp, h).sparsity_out(0)
    return {"variables": int(h.v.numel()), "constraints": h.ng,
            "jacobian_nnz": int(ca.jacobian_sparsity(h.g, h.v).nnz()),
            "hessian_nnz": int(H.nnz())}
