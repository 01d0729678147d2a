"""The best known plan (perfect information): a whole drive cycle as one optimisation on the
econ model.

Knowing the whole cycle (speed and ambient at every sample) in advance, the least energy the
econ model needs to keep the cabin in the comfort band at a given mean temperature::

    min  sum_k Ts (P_comp(k) + P_bl(k))
    s.t. x(k+1) = F(x(k), u(k), d(k))                   the econ model's interval map
         x(n) = x(0)                                     cyclic: the cycle repeats, so no
                                                         stored heat is borrowed or lent
         T_low <= T_cab(k) <= T_high,  k = 1..n          comfort band
         mean_k T_cab(k) = T_mean                        the same mean cabin temperature
         Q_e(k) >= 0                                     no negative refrigerant heat
         w_cab(k) <= w(T_cab(k), RH_max)                 optional humidity bound
         u_min <= u(k) <= u_max

``x(0)`` is free (the best periodic state), or fixed to a given state (``x_start``; with
``cyclic`` the plan then returns to it). ``pinned=True`` replaces the band and the mean by
``T_cab(k) = T_mean`` for every k: the difference between the two is what shifting cooling in
time can be worth at all (an upper estimate of speed preview's value on this model).

**Not a bound on the plant.** The NLP is nonconvex and solved locally on an identified model;
replayed open loop on the plant its plan is a feasible operation, an upper estimate of the
plant's optimum. ``acid cav-study`` therefore replays several independent optima and quotes
the least as the best known plan, their spread as its uncertainty.

It is one NLP of ``7 n + 5`` variables (CasADi ``Function.map`` over the cycle, exact
derivatives), solved with IPOPT (the cyclic and mean constraints couple the first and last
stages, which rules out fatrop's stage structure). :func:`replay` applies the plan open loop
to a plant (the plant's own inputs W_bl and T_evap_set) to show the energy is achievable.
Temperatures in K, energies in J.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from acid.control.econ.problem import X_OFFSET as _X_OFF
from acid.control.econ.problem import X_SCALE as _X_SCL
from acid.errors import ConfigError, ExtrapolationWarning
from acid.models import econ
from acid.models.econ_params import EconParams
from acid.psychro import humidity_ratio
from acid.units import C2K, K2C

_NX, _NU = econ.model.nx, econ.model.nu


@dataclass(frozen=True)
class PlanConfig:
    """Options of the whole-cycle plan (temperatures in K).

    Attributes
    ----------
    T_mean : required mean cabin temperature over samples 1..n, K.
    T_low, T_high : comfort band, K.
    pinned : hold ``T_cab = T_mean`` at every sample instead of band + mean.
    cyclic : ``x(n) = x(0)`` (otherwise ``x(0)`` is fixed to ``x_start`` and ``x(n)`` free).
    RH_max : optional cabin relative humidity bound (0-1).
    W_bl_min, W_bl_max, T_evap_set_min, T_evap_set_max : input bounds (paper Table II).
    tol, max_iter : IPOPT options.
    """

    T_mean: float
    T_low: float = C2K(22.0)
    T_high: float = C2K(26.0)
    pinned: bool = False
    cyclic: bool = True
    RH_max: float | None = None
    W_bl_min: float = 0.05
    W_bl_max: float = 0.15
    T_evap_set_min: float = C2K(3.0)
    T_evap_set_max: float = C2K(10.0)
    tol: float = 1e-8
    max_iter: int = 500

    def __post_init__(self):
        if not self.T_low < self.T_high:
            raise ConfigError(f"comfort band is empty: T_low {K2C(self.T_low):.2f} degC is not "
                              f"below T_high {K2C(self.T_high):.2f} degC")
        if not self.T_low <= self.T_mean <= self.T_high:
            raise ConfigError(f"mean cabin temperature {K2C(self.T_mean):.2f} degC lies outside "
                              f"the comfort band {K2C(self.T_low):.2f}-{K2C(self.T_high):.2f} "
                              "degC")

    def to_json_dict(self) -> dict:
        return {"T_mean_K": self.T_mean, "T_low_K": self.T_low, "T_high_K": self.T_high,
                "pinned": self.pinned, "cyclic": self.cyclic, "RH_max": self.RH_max,
                "W_bl_bounds_kg_s": [self.W_bl_min, self.W_bl_max],
                "T_evap_set_bounds_K": [self.T_evap_set_min, self.T_evap_set_max]}


@dataclass(frozen=True)
class WholeCyclePlan:
    """The optimal cycle on the model.

    Attributes
    ----------
    x : (n+1, 5) states; W_bl, T_evap_set : (n,) inputs; Q_e, P_comp, P_bl : (n,) W.
    energy_J : model energy sum Ts (P_comp + P_bl), J.
    mean_T_cab : model mean of T_cab(1..n), K.
    status, success, iterations, solve_time_s : IPOPT's report.
    config : the options.
    """

    x: np.ndarray
    W_bl: np.ndarray
    T_evap_set: np.ndarray
    Q_e: np.ndarray
    P_comp: np.ndarray
    P_bl: np.ndarray
    energy_J: float
    mean_T_cab: float
    status: str
    success: bool
    iterations: int
    solve_time_s: float
    config: PlanConfig

    @property
    def inputs(self) -> np.ndarray:
        """(n, 2) planned [W_bl, T_evap_set]."""
        return np.column_stack([self.W_bl, self.T_evap_set])

    def to_json_dict(self) -> dict:
        return {"energy_MJ": self.energy_J / 1e6, "mean_T_cab_K": self.mean_T_cab,
                "status": self.status, "success": self.success,
                "iterations": self.iterations, "solve_time_s": self.solve_time_s,
                "config": self.config.to_json_dict()}


def best_known_plan(params: EconParams, v_veh, T_amb, config: PlanConfig,
                    guess: tuple[np.ndarray, np.ndarray] | None = None,
                    x_start=None, terminal_price=None) -> WholeCyclePlan:
    """Solve the whole-cycle NLP (module docstring).

    Parameters
    ----------
    params : identified econ model.
    v_veh, T_amb : (n,) vehicle speed (m/s) and ambient (K) per sample.
    config : band, mean, options.
    guess : optional (x (n+1, 5), u (n, 2)) initial guess (e.g. a closed-loop run's).
    x_start : (5,) fixed initial state (required when ``config.cyclic`` is False; with
        ``cyclic`` the plan starts and ends there).
    terminal_price : (5,) J per unit state: with a non-cyclic plan from ``x_start``, the
        objective adds ``price . (x(n) - x_start)`` (the end state charged, e.g. at the
        optimal steady state's multipliers, :mod:`acid.control.econ.terminal`).

    Raises
    ------
    ConfigError
        The band or mean cannot be met on this model (IPOPT reports infeasibility), or
        ``x_start`` is missing for a non-cyclic plan.
    """
    import warnings

    v = np.asarray(v_veh, dtype=float).ravel()
    Ta = np.broadcast_to(np.asarray(T_amb, dtype=float), v.shape).copy()
    n, Ts, cfg = v.size, params.Ts, config
    if n < 2:
        raise ConfigError("the plan needs a cycle of at least 2 samples")
    for msg in params.power_map.outside(v_veh=v, T_amb=Ta):
        warnings.warn(f"plan: power map extrapolated: {msg}", ExtrapolationWarning,
                      stacklevel=2)
    F = interval_map(params, Ts, n)
    Z = ca.MX.sym("Z", _NX, n + 1)
    U = ca.MX.sym("U", _NU, n)
    xoff, xscl = ca.DM(_X_OFF), ca.DM(_X_SCL)
    X = ca.repmat(xoff, 1, n + 1) + ca.repmat(xscl, 1, n + 1) * Z
    D = ca.DM(np.vstack([v, Ta]))
    Xn, Q_e, P_c, P_b = F(X[:, :n], U, D)
    g = [ca.vec((Xn - X[:, 1:]) / ca.repmat(xscl, 1, n)), ca.vec(Q_e) / 1e3]
    lbg = [np.zeros(_NX * n), np.zeros(n)]
    ubg = [np.zeros(_NX * n), np.full(n, np.inf)]
    T_cab = X[0, 1:]
    if cfg.pinned:
        g.append(ca.vec(T_cab) - cfg.T_mean)
        lbg.append(np.zeros(n))
        ubg.append(np.zeros(n))
    else:
        g += [ca.vec(T_cab), ca.sum2(T_cab) / n - cfg.T_mean]
        lbg += [np.full(n, cfg.T_low), [0.0]]
        ubg += [np.full(n, cfg.T_high), [0.0]]
    if cfg.RH_max is not None:
        g.append(1e3 * ca.vec(X[4, 1:] - humidity_ratio(X[0, 1:], cfg.RH_max, params.p_atm)))
        lbg.append(np.full(n, -np.inf))
        ubg.append(np.zeros(n))
    if cfg.cyclic:
        g.append(Z[:, n] - Z[:, 0])
        lbg.append(np.zeros(_NX))
        ubg.append(np.zeros(_NX))
    elif x_start is None:
        raise ConfigError("a non-cyclic plan needs x_start")
    w = ca.vertcat(ca.vec(Z), ca.vec(U))
    energy = Ts * ca.sum2(P_c + P_b)
    cost = energy
    if terminal_price is not None:
        if x_start is None or cfg.cyclic:
            raise ConfigError("a terminal price needs a non-cyclic plan from x_start")
        lam = ca.DM(np.asarray(terminal_price, dtype=float))
        cost = energy + ca.dot(lam, X[:, n] - ca.DM(np.asarray(x_start, dtype=float)))
    nlp = {"x": w, "f": cost / 1e3, "g": ca.vertcat(*g)}
    opts = {"print_time": False, "ipopt": {"print_level": 0, "sb": "yes", "tol": cfg.tol,
                                           "max_iter": int(cfg.max_iter),
                                           "mu_strategy": "adaptive"}}
    solver = ca.nlpsol("acid_best_plan", "ipopt", nlp, opts)
    nz = _NX * (n + 1)
    lbx = np.full(w.shape[0], -np.inf)
    ubx = np.full(w.shape[0], np.inf)
    u_lo = np.array([cfg.W_bl_min, cfg.T_evap_set_min])
    u_hi = np.array([cfg.W_bl_max, cfg.T_evap_set_max])
    lbx[nz:] = np.tile(u_lo, n)
    ubx[nz:] = np.tile(u_hi, n)
    if x_start is not None:
        z0 = (np.asarray(x_start, dtype=float) - _X_OFF) / _X_SCL
        lbx[:_NX] = z0
        ubx[:_NX] = z0
    x_g, u_g = _initial_guess(params, v, Ta, cfg, guess, x_start)
    w0 = np.concatenate([((x_g - _X_OFF) / _X_SCL).ravel(), u_g.ravel()])
    t0 = time.perf_counter()
    res = solver(x0=w0, lbx=lbx, ubx=ubx, lbg=np.concatenate([np.ravel(a) for a in lbg]),
                 ubg=np.concatenate([np.ravel(a) for a in ubg]))
    elapsed = time.perf_counter() - t0
    st = solver.stats()
    status = str(st.get("return_status", ""))
    if "Infeasible" in status:
        raise ConfigError(
            f"whole-cycle plan infeasible on this model ({status}): the comfort band "
            f"{K2C(cfg.T_low):.2f}-{K2C(cfg.T_high):.2f} degC with mean "
            f"{K2C(cfg.T_mean):.2f} degC cannot be held with the inputs' bounds")
    wv = np.asarray(res["x"]).ravel()
    x = wv[:nz].reshape(n + 1, _NX) * _X_SCL + _X_OFF
    u = np.clip(wv[nz:].reshape(n, _NU), u_lo, u_hi)
    _, q, pc, pb = (np.asarray(a) for a in F(x[:n].T, u.T, D))
    for msg in params.power_map.outside(Q_e=q.ravel(), T_evap=0.5 * (x[:-1, 3] + x[1:, 3])):
        warnings.warn(f"plan: the optimal plan extrapolates the power map: {msg}",
                      ExtrapolationWarning, stacklevel=2)
    return WholeCyclePlan(x=x, W_bl=u[:, 0], T_evap_set=u[:, 1], Q_e=q.ravel(), P_comp=pc.ravel(),
                     P_bl=pb.ravel(), energy_J=float(Ts * np.sum(pc + pb)),
                     mean_T_cab=float(np.mean(x[1:, 0])), status=status,
                     success=bool(st.get("success", False)),
                     iterations=int(st.get("iter_count", -1)), solve_time_s=elapsed,
                     config=cfg)


def _initial_guess(params, v, Ta, cfg: PlanConfig, guess, x_start):
    """The given guess, else a simulation at a constant mid-range input from a mild state."""
    n = v.size
    if guess is not None:
        x, u = (np.asarray(a, dtype=float) for a in guess)
        if x.shape == (n + 1, _NX) and u.shape == (n, _NU):
            return x, u
    u = np.tile([0.08, cfg.T_evap_set_max], (n, 1))
    x0 = np.asarray(x_start, dtype=float) if x_start is not None else np.array(
        [cfg.T_mean, cfg.T_mean + 2.0, Ta.mean() + 3.0, cfg.T_evap_set_max, 0.008])
    x, _ = econ.model.simulate(x0, u, np.column_stack([v, Ta]), params.theta_all)
    return x, u


def interval_map(params: EconParams, Ts: float, n: int) -> ca.Function:
    """``(x (5, n), u (2, n), d (2, n)) -> (x_next, Q_e, P_comp, P_bl)``: the declaration's
    interval of ``Ts`` s (:func:`acid.models.econ.casadi_interval`, no disturbance) at the
    numbers of ``params``, mapped over ``n`` samples (P_comp unclipped)."""
    F = econ.casadi_interval(Ts)
    x, u, d = ca.SX.sym("x", _NX), ca.SX.sym("u", _NU), ca.SX.sym("d", F.size1_in(2))
    out = dict(zip(F.name_out(), F(x, u, d, ca.DM(params.theta_all), ca.DM.zeros(_NX)),
                   strict=True))
    names = ("x_next", "Q_e", "P_comp", "P_bl")
    return ca.Function("econ_plan_step", [x, u, d], [out[k] for k in names],
                       ["x", "u", "d"], list(names)).map(n)
