"""Offset-free estimation: a Kalman filter on a model augmented with integrating disturbances.

A prediction model never matches the plant exactly; an NMPC that rides a constraint with a
biased model sits beside it by the bias (paper Fig. 8: "slight violations"). The standard
cure (Muske & Badgwell 2002; Pannocchia & Rawlings 2003, "offset-free MPC") augments the
discrete-time model with disturbances that are constant in the model's eyes,

.. math::

    x(k+1) = f(x(k), u(k), v(k)) + B_d\\, d(k), \\qquad d(k+1) = d(k), \\qquad
    y(k) = C\\, x(k) + e(k),

estimates ``(x, d)`` from the measurements ``y`` with a Kalman filter, and predicts with the
estimated ``d`` held over the horizon. Where the plant settles, the one-step prediction
error is driven to zero, so a constraint the NMPC rides is ridden by the plant too. The
augmented system is observable when ``[[I - A, -B_d], [C, 0]]`` has full column rank (for
acid's model, ``B_d = C = I``: a disturbance on each measured state equation, always).

:class:`OffsetFreeEstimator` is written over any CasADi discrete-time model ``f(x, u, v)``
(``v``: measured exogenous inputs), a disturbance input matrix ``B_d`` and a measurement
matrix ``C``: an *extended* Kalman filter, the linearisation ``A = d[f + B_d d; d]/d[x; d]``
by CasADi's AD (nothing hand-derived), the covariance update in Joseph form. The filter step
is one CasADi function, run as generated C when a compiler is available
(:mod:`acid.control.codegen.build`), else inside CasADi. Tuning is by standard deviations in the
model's units (:class:`EstimatorConfig`): a disturbance random walk large against the
process noise makes ``d`` follow the latest prediction errors quickly.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from acid.control.codegen.build import CodegenError, compile_function
from acid.errors import ConfigError


@dataclass(frozen=True)
class EstimatorConfig:
    """Tuning of the offset-free Kalman filter (standard deviations in the states' units;
    kelvin for acid's model).

    Attributes
    ----------
    Each is a number (the same for every state, disturbance or output) or a tuple with one
    value per state, disturbance or output.

    sigma_x : process noise of each state equation per step.
    sigma_d : random-walk step of each disturbance per step (how fast ``d`` may move).
    sigma_y : measurement noise of each measured output.
    sigma_d0 : initial standard deviation of the disturbances (their initial value is 0).
    """

    sigma_x: float | tuple = 0.01
    sigma_d: float | tuple = 0.1
    sigma_y: float | tuple = 0.01
    sigma_d0: float | tuple = 0.5

    def __post_init__(self):
        for name in ("sigma_x", "sigma_d", "sigma_y", "sigma_d0"):
            v = np.atleast_1d(np.asarray(getattr(self, name), dtype=float))
            if v.ndim != 1 or not np.all(np.isfinite(v) & (v > 0)):
                raise ConfigError(f"estimator {name} must be positive numbers, got "
                                  f"{getattr(self, name)}")
            if v.size > 1:
                object.__setattr__(self, name, tuple(float(a) for a in v))

    def std(self, name: str, n: int) -> np.ndarray:
        """``name`` as one standard deviation per entry (n of them)."""
        v = np.atleast_1d(np.asarray(getattr(self, name), dtype=float))
        if v.size not in (1, n):
            raise ConfigError(f"estimator {name} needs 1 or {n} values, got {v.size}")
        return np.broadcast_to(v, (n,)).copy()

    def to_json_dict(self) -> dict:
        return {k: getattr(self, k) for k in ("sigma_x", "sigma_d", "sigma_y", "sigma_d0")}


def ekf_step_function(f: ca.Function, B_d: np.ndarray, C: np.ndarray,
                      config: EstimatorConfig, name: str = "acid_ekf") -> ca.Function:
    """One predict-correct step of the extended Kalman filter as a CasADi function.

    ``(z, P, u, v, y) -> (z_post, P_post)`` with ``z = [x; d]`` the augmented state after the
    previous correction, ``P`` its covariance (column-major, n_z x n_z), ``u`` and ``v`` the
    input and exogenous values applied since, and ``y`` the new measurement.
    """
    nx, ny = f.size1_out(0), C.shape[0]
    nd = f.size1_in(3) if B_d is None else B_d.shape[1]
    nz = nx + nd
    z = ca.SX.sym("z", nz)
    P = ca.SX.sym("P", nz, nz)
    u = ca.SX.sym("u", f.size1_in(1))
    v = ca.SX.sym("v", f.size1_in(2))
    y = ca.SX.sym("y", ny)
    x, d = z[:nx], z[nx:]
    x_next = f(x, u, v, d) if B_d is None else f(x, u, v) + ca.DM(B_d) @ d
    z_pred = ca.vertcat(x_next, d)
    A = ca.jacobian(z_pred, z)
    Q = ca.diag(ca.DM(np.r_[config.std("sigma_x", nx), config.std("sigma_d", nd)] ** 2))
    R = ca.diag(ca.DM(config.std("sigma_y", ny) ** 2))
    H = ca.horzcat(ca.DM(C), ca.DM.zeros(ny, nd))
    P_pred = A @ P @ A.T + Q
    S = H @ P_pred @ H.T + R
    K = P_pred @ H.T @ ca.inv(S)
    z_post = z_pred + K @ (y - H @ z_pred)
    IKH = ca.DM.eye(nz) - K @ H
    P_post = IKH @ P_pred @ IKH.T + K @ R @ K.T  # Joseph form: stays symmetric positive
    return ca.Function(name, [z, P, u, v, y], [z_post, P_post],
                       ["z", "P", "u", "v", "y"], ["z_post", "P_post"])


class OffsetFreeEstimator:
    """Extended Kalman filter for ``x+ = f(x, u, v) + B_d d``, ``d+ = d``, ``y = C x + e``.

    Parameters
    ----------
    f : CasADi function ``(x, u, v) -> x_next`` (one sample of the discrete-time model).
    B_d : (n_x, n_d) disturbance input matrix (default: identity, a disturbance on every
        state equation).
    C : (n_y, n_x) measurement matrix (default: identity, every state measured).
    config : filter tuning.
    compiled : run the filter step as generated C (``"auto"``: when a compiler works).

    Attributes
    ----------
    x, d : current estimates (None before the first :meth:`update`).
    P : covariance of ``[x; d]``.
    """

    def __init__(self, f: ca.Function, B_d=None, C=None, config: EstimatorConfig | None = None,
                 compiled: bool | str = "auto"):
        self.config = config or EstimatorConfig()
        self.nx = int(f.size1_out(0))
        if f.n_in() == 4:  # the disturbance is an argument of the model
            self.B_d = None
            self.nd = int(f.size1_in(3))
        else:
            self.B_d = np.eye(self.nx) if B_d is None else np.atleast_2d(np.asarray(B_d, float))
            self.nd = int(self.B_d.shape[1])
        self.C = np.eye(self.nx) if C is None else np.atleast_2d(np.asarray(C, float))
        if (self.B_d is not None and self.B_d.shape[0] != self.nx) or self.C.shape[1] != self.nx:
            raise ConfigError(f"estimator: B_d must have {self.nx} rows and C {self.nx} "
                              f"columns, got {None if self.B_d is None else self.B_d.shape} "
                              f"and {self.C.shape}")
        self._fn = ekf_step_function(f, self.B_d, self.C, self.config)
        self._compiled = None
        if compiled is not False:
            try:
                self._compiled, _ = compile_function(self._fn)
            except CodegenError:
                self._compiled = None  # the NLP solver already noticed the missing compiler
        self.reset()

    def reset(self, d0=None) -> None:
        """Forget the estimate; the next :meth:`update` starts from its measurement and
        ``d0`` (default zero)."""
        self.x = None
        self.d = np.zeros(self.nd) if d0 is None else np.asarray(d0, dtype=float).copy()
        cfg = self.config
        nz = self.nx + self.nd
        sy = cfg.std("sigma_y", self.C.shape[0]).max()
        self.P = np.diag(np.r_[np.full(self.nx, sy ** 2), cfg.std("sigma_d0", self.nd) ** 2])
        self._z = np.zeros(nz)

    def update(self, y, u=None, v=None) -> tuple[np.ndarray, np.ndarray]:
        """Correct with the measurement ``y`` after ``u``, ``v`` were applied for a sample.

        The first call after :meth:`reset` (or with ``u`` None) only initialises the state
        from ``y`` (least squares through ``C``). Returns ``(x, d)``.
        """
        y = np.asarray(y, dtype=float)
        if self.x is None or u is None:
            self.x = np.linalg.lstsq(self.C, y, rcond=None)[0]
            return self.x.copy(), self.d.copy()
        self._z[: self.nx], self._z[self.nx:] = self.x, self.d
        if self._compiled is not None:
            cf = self._compiled
            for buf, a in zip(cf.inputs, (self._z, self.P.ravel(order="F"), u, v, y),
                              strict=True):
                buf[:] = a
            cf.call()
            z, P = cf.outputs[0], cf.outputs[1]
        else:
            out = self._fn(self._z, self.P, u, v, y)
            z, P = np.asarray(out[0]).ravel(), np.asarray(out[1]).ravel()
        if not (np.all(np.isfinite(z)) and np.all(np.isfinite(P))):
            self.reset(self.d)  # a broken update must not poison the next ones
            return self.update(y)
        self.x, self.d = z[: self.nx].copy(), z[self.nx:].copy()
        self.P = P.reshape(self.nx + self.nd, self.nx + self.nd, order="F").copy()
        return self.x.copy(), self.d.copy()


# ----------------------------------------------------------------- constraint back-off
@dataclass(frozen=True)
class BackoffConfig:
    """Constraint back-off from the controller's own one-step prediction errors.

    An energy-minimising NMPC rides its comfort bound, so every one-step prediction error
    of the wrong sign is a violation of about its size. The back-off tightens the bound by
    ``kappa`` standard deviations of the recent errors of that sign (a chance constraint
    on a Gaussian error: ``kappa = 2`` keeps the violation probability per step near 2 %).

    Attributes
    ----------
    kappa : margin in standard deviations.
    memory : forgetting factor per step of the error statistics (0.9: about 10 steps).
    sigma0 : prior standard deviation of the one-step error before any is measured, K
        (0: no margin until the model is seen to err, e.g. on its own model).
    max_margin : cap on the margin, K.
    """

    kappa: float = 2.0
    memory: float = 0.9
    sigma0: float = 0.0
    max_margin: float = 1.0

    def __post_init__(self):
        for name in ("kappa", "sigma0", "max_margin"):
            v = float(getattr(self, name))
            if not (np.isfinite(v) and v >= 0):
                raise ConfigError(f"back-off {name} must be a number >= 0, got {v}")
        if not (0.0 <= self.memory < 1.0):
            raise ConfigError(f"back-off memory must be in [0, 1), got {self.memory}")

    def to_json_dict(self) -> dict:
        return {"kappa": self.kappa, "memory": self.memory, "sigma0_K": self.sigma0,
                "max_margin_K": self.max_margin}


class ErrorBackoff:
    """Margins for the upper and lower bounds of one predicted quantity, from its one-step
    prediction errors ``e = measured - predicted``.

    Positive errors (the plant ends above the prediction) tighten the upper bound, negative
    ones the lower bound: ``margin = min(kappa * s, max_margin)`` with ``s^2`` an
    exponentially weighted mean of ``max(+-e, 0)^2`` started at ``sigma0^2``.
    """

    def __init__(self, config: BackoffConfig | None = None):
        self.config = config or BackoffConfig()
        self.reset()

    def reset(self) -> None:
        s2 = self.config.sigma0 ** 2
        self._s2 = np.array([s2, s2])  # [above, below]

    def update(self, predicted: float, measured: float) -> None:
        """Record one error (skipped when either value is not finite)."""
        e = float(measured) - float(predicted)
        if not np.isfinite(e):
            return
        lam = self.config.memory
        self._s2 = lam * self._s2 + (1.0 - lam) * np.array([max(e, 0.0), max(-e, 0.0)]) ** 2

    @property
    def upper(self) -> float:
        """Margin below an upper bound, K."""
        return float(min(self.config.kappa * np.sqrt(self._s2[0]), self.config.max_margin))

    @property
    def lower(self) -> float:
        """Margin above a lower bound, K."""
        return float(min(self.config.kappa * np.sqrt(self._s2[1]), self.config.max_margin))
