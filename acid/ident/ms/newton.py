"""Bounded Newton iterations with a curvature matrix (the exact Hessian from CasADi, or the
likelihood's Fisher information), converged by the Newton decrement: the prediction-error
fit's last phase (:mod:`acid.ident.pem`), after L-BFGS-B has brought it near the optimum."""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

#: Converged when the Newton decrement ``g' H^-1 g`` over the parameters inside their bounds
#: (twice the further decrease of -2 log L a Newton step predicts) is below this and no
#: parameter on a bound is pulled inwards: the likelihood is then flat to far below its
#: statistical resolution (a change of 1 in -2 log L).
DECREMENT_TOL = 1e-6
#: Curvature below this fraction of the largest counts as this fraction in the decrement
#: (a direction the data do not fix; the Fisher information is singular there).
CURVATURE_FLOOR = 1e-12


@dataclass
class Newton:
    """Where :func:`newton` ended and how close to converged it was."""

    z: np.ndarray
    loss: float
    H: np.ndarray
    decrement: float         # g' H^-1 g over the free parameters at z
    pgrad: float             # largest |projected gradient| at z (scaled parameters)
    rel_change: float        # relative change of the loss at the last step
    hessians: int
    converged: bool
    why: str = ""            # why it stopped short of converged ("" when converged)
    kind: str = "exact Hessians"     # what the curvature evaluations were

    def status(self, nfev: int, cap: int, cap_hessians: int) -> str:
        """One line: ``converged: ...`` or ``not converged after ...: <why>; ...``."""
        how = (f"Newton decrement {self.decrement:.2g} (converged below {DECREMENT_TOL:g}), "
               f"projected gradient {self.pgrad:.2g}, " + (
                   f"last relative loss change {self.rel_change:.2g}" if self.hessians > 1
                   else "no Newton step taken"))
        lb = (f"{nfev} gradient evaluations (cap {cap}) and {self.hessians} {self.kind} "
              f"(cap {cap_hessians})")
        if self.converged:
            return f"converged: {how}; {lb}"
        return f"not converged after {lb}: {self.why or 'budget spent'}; {how}"


def newton(hess, cost: ca.Function, z: np.ndarray, zlo, zhi,
            max_hessians: int, report=None, kind: str = "exact Hessians") -> Newton:
    """Bounded Newton iterations from ``z``: ``hess(z) -> (J, g, H)`` (``H`` the exact
    Hessian or a positive semidefinite stand-in such as the Fisher information; ``kind``
    names it in the status), ``cost(z) -> J`` for the trial steps. A parameter on a bound
    with the gradient pushing it out stays there; the others take the Newton step, damped
    (Levenberg-Marquardt) until the loss decreases, clipped into the bounds."""
    z = np.asarray(z, float).copy()

    def at(v):
        f, g, H = hess(v)
        H = np.asarray(H)
        return float(f), np.asarray(g).ravel(), 0.5 * (H + H.T)

    f, g, H = at(z)
    n_h, lam, rel = 1, 0.0, math.nan
    while True:
        pinned = ((z <= zlo + 1e-10) & (g > 0)) | ((z >= zhi - 1e-10) & (g < 0))
        free = ~pinned
        Hf, gf = H[np.ix_(free, free)], g[free]
        pgrad = float(np.max(np.abs(gf), initial=0.0))
        dec, convex = 0.0, True
        if gf.size and np.all(np.isfinite(Hf)):
            w, V = np.linalg.eigh(Hf)
            floor = CURVATURE_FLOOR * max(abs(w).max(), 1e-300)
            convex = bool(w.min() > -floor)
            # directions of (almost) no curvature (a parameter the data do not fix) count
            # with the curvature floored: finite, and small only if the gradient is too
            dec = float(np.sum((V.T @ gf) ** 2 / np.maximum(w, floor))) if convex \
                else math.inf
        elif gf.size:
            dec, convex = math.inf, False
        done = math.isfinite(f) and dec <= DECREMENT_TOL
        if done or n_h >= max_hessians or not math.isfinite(f):
            why = ("" if done else "the loss is not finite (the filter diverged)"
                   if not math.isfinite(f) else
                   "budget spent")
            return Newton(z, f, H, dec, pgrad, rel, n_h, bool(done), why, kind)
        # damped step on the free set: (H + lam D) dz = -g, D the curvature's scale
        D = np.abs(np.diag(Hf))
        D = np.maximum(D, 1e-12 * max(float(D.max()), 1.0))
        lam = lam if convex else max(lam, 1e-3)
        for _ in range(30):
            dz = np.zeros_like(z)
            try:
                dz[free] = np.linalg.solve(Hf + lam * np.diag(D), -gf)
            except np.linalg.LinAlgError:
                lam = max(10 * lam, 1e-6)
                continue
            zn = np.clip(z + dz, zlo, zhi)
            fn = float(cost(zn))
            if math.isfinite(fn) and fn < f:
                break
            lam = max(10 * lam, 1e-6)
        else:      # no decrease along any damping: the loss is flat at round-off here
            return Newton(z, f, H, dec, pgrad, rel, n_h, False,
                          "no damped Newton step lowers the loss (flat at round-off)", kind)
        lam = lam / 10 if lam > 1e-8 else 0.0
        rel = abs(fn - f) / max(abs(f), 1.0)
        z = zn
        f, g, H = at(z)
        n_h += 1
        if report is not None:
            report(f"Newton step {n_h - 1}, -2 log likelihood {f:.6g}")
