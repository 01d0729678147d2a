"""The economic NMPC's optimal-control problem on the econ model: its configuration
(:class:`EconNMPCConfig`), the variables' scaling, the stage costs and :func:`ocp_spec`, the
configuration of :class:`acid.control.ocp.OCP` that the NMPC (:mod:`acid.control.econ.nmpc`),
its steady-state terminal price (:mod:`acid.control.econ.terminal`) and the best known plan
solve. Units: K, kg/kg, kg/s, W, s."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from acid.control.estimator import EstimatorConfig
from acid.control.ocp import OCPSpec, SoftBound
from acid.errors import ConfigError
from acid.models import econ
from acid.models.econ import STATES
from acid.psychro import humidity_ratio
from acid.units import C2K

#: Scaling of the NLPs' variables on the econ model, one source for the NMPC, its optimal
#: steady state and the best known plan: z = (x - X_OFFSET) / X_SCALE in ``STATES`` order,
#: w = (u - U_OFFSET) / U_SCALE in (W_bl, T_evap_set) order (K, kg/kg, kg/s)
X_OFFSET = np.array([293.15, 293.15, 293.15, 278.15, 0.008])
X_SCALE = np.array([1.0, 1.0, 1.0, 1.0, 1e-3])
U_OFFSET = np.array([0.1, 278.15])
U_SCALE = np.array([0.01, 1.0])
#: what the NMPC reads of the declaration's interval (``acid.models.econ.casadi_interval``)
INTERVAL_OUTPUTS = ("x_next", "T_ain", "Q_e", "P_comp", "P_bl")
#: solvers of the economic NMPC: SQP (sqpmethod + qrqp, warm-started with the shifted
#: multipliers, checked for convergence), fatrop, IPOPT (always inside CasADi)
ECON_SOLVERS = ("sqp", "fatrop", "ipopt")
#: the SQP with a convexified Hessian that finishes a failed exact-Hessian SQP solve
#: (``EconNMPCConfig.sqp_rescue``), before ``fallback_solver``
SQP_RESCUE = "sqp_convex"
#: iteration limit of the exact-Hessian SQP
SQP_MAX_ITER = 25
#: terminal costs of the horizon's end state (module docstring)
TERMINALS = ("heat", "steady", "none")


#: Kalman-filter tuning for the econ model's five states (K, K, K, K, kg/kg) and the
#: disturbances on their derivatives (K/s, kg/kg/s): per sample of 5 s, a few mK of model
#: noise, 0.05 K on the evaporator wall (on/off cycling), disturbances that may move by
#: about 1 K per minute on the cabin air.
ECON_ESTIMATOR = EstimatorConfig(sigma_x=(0.01, 0.01, 0.01, 0.05, 1e-5),
                                 sigma_d=(2e-3, 2e-4, 2e-4, 1e-2, 2e-6),
                                 sigma_y=(0.01, 0.01, 0.01, 0.05, 1e-5),
                                 sigma_d0=(1e-2, 1e-3, 1e-3, 5e-2, 1e-5))


@dataclass(frozen=True)
class EconNMPCConfig:
    """Options of the economic NMPC (temperatures in K).

    Attributes
    ----------
    intervals : interval lengths of the horizon, s (the first one must be the sample time).
    T_cab_min, T_cab_max : comfort band on the cabin air, K (default 22-26 degC).
    RH_max : optional upper bound on the cabin relative humidity (0-1).
    W_bl_min, W_bl_max : blower flow bounds, kg/s (paper Table II).
    T_evap_set_min, T_evap_set_max : set-point bounds, K (paper Table II: 3-10 degC).
    slack_penalty : a_sl, W per unit of violation (K, kW of Q_e, g/kg) and per second.
    preview : use the previewed speed and ambient (False: hold their current values).
    terminal : terminal cost of the horizon's end state, ``"heat"`` (the heat content at the
        marginal compressor price), ``"steady"`` (the optimal steady state's multipliers) or
        ``"none"`` (module docstring).
    solver : ``"sqp"`` (default: SQP with the active-set QP solver qrqp, warm-started from
        the shifted primal and dual solution, each result checked for convergence),
        ``"fatrop"`` (structure-exploiting interior point) or ``"ipopt"``.
    fallback_solver : solves the same problem from the same guess when ``solver`` fails
        (default ``"ipopt"``: inside CasADi, nothing more to compile; None: the
        controller's fallback input at once).
    tol, max_iter : solver tolerance and iteration limit.
    cost_scale : objective factor inside the NLP (kJ instead of J).
    fallback_input : input when no plan is left (default maximum cooling).
    compiled : run the solver as generated C (``acid.control.codegen.build``): ``"auto"`` when a C
        compiler works (else CasADi, one notice), ``True``, or ``False`` (CasADi). The econ
        parameters are NLP parameters, so one compiled solver (cached per user) serves every
        identified parameter set of the same horizon and options; the first build compiles
        for a minute or two.
    max_solve_s : wall-clock cap per solve, s (default None: none); a solve still running
        then is abandoned and the fallback applies. Only for an ECU-like real-time run:
        with a cap the result depends on the machine's load.
    offset_free : estimate the additive disturbances ``dist`` in ``make_step`` with the
        offset-free Kalman filter of :mod:`acid.control.estimator` (the model's RK4 interval map,
        disturbances on the five state derivatives) and predict with them held.
    estimator : its tuning (``ECON_ESTIMATOR``).
    stage_functions : build the NLP from one function per stage called over the horizon
        (default; :class:`acid.control.ocp.OCPSpec`): SQP compiled in 10 CPU-s (-O2)
        against 32 (-O1) inlined, steps 1.2x faster (``benchmarks/bench_compile.py``).
    sqp_rescue : with ``solver="sqp"``, finish a solve the exact-Hessian SQP did not
        converge with the same SQP on a convexified Hessian (``SQP_RESCUE``, from the same
        guess and multipliers, generated C too) before ``fallback_solver``. The failures
        are not NaNs: the exact Hessian is indefinite, the QPs nonconvex, and qrqp cycles on
        a bound or the steps jump between bounds.
    comfort_weight : price of the cabin's distance from a reference temperature, W per K^2
        and per second (0: none, the band alone). With it the stage cost gains
        ``dt comfort_weight (T_cab - T_cab_ref)^2``, ``T_cab_ref`` a per-stage NLP parameter
        (``solve``/``make_step``'s ``T_cab_ref``; the band stays a soft bound): comfort as a
        target held in mean, not an edge ridden at every instant (module docstring).
    T_cab_ref : the reference temperature when ``comfort_weight`` > 0 and none is passed, K.
    """

    intervals: tuple[float, ...] = (5.0,) * 24
    T_cab_min: float = C2K(22.0)
    T_cab_max: float = C2K(26.0)
    RH_max: float | None = None
    W_bl_min: float = 0.05
    W_bl_max: float = 0.15
    T_evap_set_min: float = C2K(3.0)
    T_evap_set_max: float = C2K(10.0)
    slack_penalty: float = 1e5
    preview: bool = True
    terminal: str = "steady"
    solver: str = "sqp"
    fallback_solver: str | None = "ipopt"
    tol: float = 1e-6
    max_iter: int = 200
    cost_scale: float = 1e-3
    fallback_input: tuple[float, float] | None = None
    compiled: bool | str = "auto"
    max_solve_s: float | None = None
    offset_free: bool = False
    estimator: EstimatorConfig = ECON_ESTIMATOR
    stage_functions: bool = True
    sqp_rescue: bool = True
    comfort_weight: float = 0.0
    T_cab_ref: float = C2K(24.0)

    def __post_init__(self):
        iv = tuple(float(t) for t in self.intervals)
        object.__setattr__(self, "intervals", iv)
        if len(iv) < 2 or min(iv) <= 0:
            raise ConfigError("econ NMPC: the horizon needs at least 2 positive intervals")
        if not self.T_cab_min < self.T_cab_max:
            raise ConfigError(f"comfort band is empty: T_cab_min {self.T_cab_min - 273.15:.2f} "
                              f"degC is not below T_cab_max {self.T_cab_max - 273.15:.2f} degC")
        if self.RH_max is not None and not 0.0 < self.RH_max <= 1.0:
            raise ConfigError(f"RH_max must lie in (0, 1], got {self.RH_max}")
        if not (self.W_bl_min < self.W_bl_max and self.T_evap_set_min < self.T_evap_set_max):
            raise ConfigError("econ NMPC: input bounds must satisfy min < max")
        if self.terminal not in TERMINALS:
            raise ConfigError(f"terminal must be one of {', '.join(TERMINALS)}, got "
                              f"{self.terminal!r}")
        for name in ("solver", "fallback_solver"):
            value = getattr(self, name)
            if value not in ECON_SOLVERS and (name == "solver" or value is not None):
                raise ConfigError(f"{name} must be one of {', '.join(ECON_SOLVERS)}, got "
                                  f"{value!r}")
        if self.compiled not in ("auto", True, False):
            raise ConfigError(f"compiled must be 'auto', True or False, got {self.compiled!r}")
        if self.max_solve_s is not None and not self.max_solve_s > 0:
            raise ConfigError(f"max_solve_s must be positive or None, got {self.max_solve_s}")
        if not (math.isfinite(self.comfort_weight) and self.comfort_weight >= 0.0):
            raise ConfigError(f"comfort_weight must be >= 0 W/K^2 per second, got "
                              f"{self.comfort_weight}")

    @property
    def N(self) -> int:
        """Number of intervals."""
        return len(self.intervals)

    @property
    def horizon_s(self) -> float:
        """Horizon length, s."""
        return float(sum(self.intervals))

    @property
    def u_min(self) -> np.ndarray:
        return np.array([self.W_bl_min, self.T_evap_set_min])

    @property
    def u_max(self) -> np.ndarray:
        return np.array([self.W_bl_max, self.T_evap_set_max])

    @property
    def u_safe(self) -> np.ndarray:
        """The fallback input (maximum cooling unless configured)."""
        if self.fallback_input is not None:
            return np.array(self.fallback_input, dtype=float)
        return np.array([self.W_bl_max, self.T_evap_set_min])

    def replace(self, **changes) -> EconNMPCConfig:
        """A copy with some options changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def to_json_dict(self) -> dict:
        return {"intervals_s": list(self.intervals), "horizon_s": self.horizon_s,
                "T_cab_min_K": self.T_cab_min, "T_cab_max_K": self.T_cab_max,
                "RH_max": self.RH_max, "W_bl_bounds_kg_s": [self.W_bl_min, self.W_bl_max],
                "T_evap_set_bounds_K": [self.T_evap_set_min, self.T_evap_set_max],
                "slack_penalty": self.slack_penalty, "preview": self.preview,
                "terminal": self.terminal, "solver": self.solver,
                "fallback_solver": self.fallback_solver, "tol": self.tol,
                "max_iter": self.max_iter, "compiled": self.compiled,
                "max_solve_s": self.max_solve_s, "offset_free": self.offset_free,
                "stage_functions": self.stage_functions, "sqp_rescue": self.sqp_rescue,
                "comfort_weight_W_K2": self.comfort_weight,
                "estimator": self.estimator.to_json_dict() if self.offset_free else None}


def stage_means(profile, k: int, intervals, Ts: float) -> np.ndarray:
    """Means of a per-sample profile over the horizon's intervals starting at sample ``k``.

    ``profile[j]`` holds over ``[j Ts, (j+1) Ts)``; past its end the last value holds.
    Interval edges are rounded to whole samples (at least one sample per interval).
    """
    a = np.asarray(profile, dtype=float).ravel()
    edges = k + np.concatenate(([0], np.maximum.accumulate(
        np.maximum(np.round(np.cumsum(intervals) / Ts).astype(int), 1))))
    idx = np.minimum(np.arange(edges[0], edges[-1]), a.size - 1)
    vals = a[idx]
    out = np.empty(len(intervals))
    for i in range(len(intervals)):
        lo, hi = edges[i] - k, max(edges[i + 1] - k, edges[i] - k + 1)
        out[i] = vals[lo:hi].mean()
    return out


def econ_interval(dt: float) -> ca.Function:
    """``(x[5], u[2], d[2], p[np], dist[5]) -> (x_next, T_ain, Q_e, P_comp, P_bl)``: one
    interval of ``dt`` s of the econ declaration (:func:`acid.models.econ.casadi_interval`:
    RK4 with inputs and disturbances held; means over the interval; ``dist`` additive terms
    on the state derivatives) with the outputs the NMPC names (``INTERVAL_OUTPUTS``)."""
    F = econ.casadi_interval(dt)
    args = [ca.SX.sym(n, F.size1_in(i)) for i, n in enumerate(F.name_in())]
    out = dict(zip(F.name_out(), F(*args), strict=True))
    return ca.Function("econ_interval", args, [out[n] for n in INTERVAL_OUTPUTS],
                       F.name_in(), list(INTERVAL_OUTPUTS))


def at_parameters(F: ca.Function, theta: np.ndarray) -> ca.Function:
    """``F(x, u, d, p, dist)`` at fixed parameters: ``(x, u, d, dist) -> F's outputs`` (the
    guess, the price and the offset-free estimator step the same interval map)."""
    x, u, d, w = (ca.SX.sym(n, F.size1_in(i)) for n, i in (("x", 0), ("u", 1), ("d", 2),
                                                            ("dist", 4)))
    return ca.Function(F.name() + "_at_p", [x, u, d, w], F(x, u, d, ca.DM(theta), w),
                       ["x", "u", "d", "dist"], F.name_out())


def econ_stage_cost(s) -> dict:
    """Electric energy of one interval, J: ``dt (P_comp + P_bl)``."""
    return {"E": s.dt * (s.P_comp + s.P_bl)}


def comfort_stage_cost(weight: float):
    """The energy plus the comfort price ``dt weight (T_cab - T_cab_ref)^2`` (J-equivalent;
    ``weight`` W/K^2 per second, ``T_cab_ref`` a stage parameter, K)."""
    w = float(weight)

    def cost(s) -> dict:
        return {**econ_stage_cost(s), "comfort": s.dt * w * (s.T_cab - s.T_cab_ref) ** 2}

    return cost


def ocp_spec(config: EconNMPCConfig) -> OCPSpec:
    """The economic NMPC (module docstring) as a configuration of the one optimal-control
    builder (:class:`acid.control.ocp.OCP`) over ``acid.models.econ.model``: the energy
    stage cost, the comfort band, ``Q_e >= 0`` (kW) and the optional humidity bound as soft
    bounds priced per second, the terminal price, the model's scaling."""
    cfg = config
    bounds = [SoftBound("T_cab", cfg.T_cab_min, cfg.T_cab_max, cfg.slack_penalty,
                        per_second=True),
              SoftBound("Q_e", lower=0.0, penalty=cfg.slack_penalty, scale=1e-3,
                        per_second=True)]
    if cfg.RH_max is not None:
        rh = float(cfg.RH_max)
        bounds.append(SoftBound("RH", upper=0.0, penalty=cfg.slack_penalty, scale=1e3,
                                per_second=True,
                                expr=lambda s: s.w_cab - humidity_ratio(s.T_cab, rh,
                                                                        s.p_atm)))
    states, inputs = STATES, ("W_bl", "T_evap_set")
    comfort = cfg.comfort_weight > 0.0
    return OCPSpec(
        N=cfg.N, stage_cost=comfort_stage_cost(cfg.comfort_weight) if comfort
        else econ_stage_cost, stage_parameters=("T_cab_ref",) if comfort else (),
        intervals=cfg.intervals,
        interval_model=econ_interval,
        input_bounds={"W_bl": (cfg.W_bl_min, cfg.W_bl_max),
                      "T_evap_set": (cfg.T_evap_set_min, cfg.T_evap_set_max)},
        soft_bounds=tuple(bounds), disturbance_targets=states,
        terminal_price=cfg.terminal != "none",
        u_offset=dict(zip(inputs, U_OFFSET, strict=True)),
        u_scale=dict(zip(inputs, 1.0 / U_SCALE, strict=True)),
        x_offset=dict(zip(states, X_OFFSET, strict=True)),
        x_scale=dict(zip(states, X_SCALE, strict=True)), cost_scale=cfg.cost_scale,
        stage_functions=cfg.stage_functions)
