"""Nonlinear MPC of the A/C system (paper eqs. 7-13, Table II), solved with CasADi.

The optimal control problem solved at every update k (kelvin, kg/s, W, s inside):

.. math::

    \\min_{U, v_{sl}} \\sum_{i=0}^{N_p} P_c(i|k) + P_{bl}(i|k)
        + \\sum_{i=1}^{N_c} a_{sl}^\\top v_{sl}(i|k)                          \\quad (7)

subject to the control-oriented model, eqs. 1-3 (paper eqs. 8-9, from the declaration
``acid.models.paper``: one source of truth), the state bounds relaxed by non-negative
slacks ``x_min(i) - v_sl(i) <= x(i|k) <= x_max(i) + v_sl(i)`` (eqs. 10-12, one slack per state and
stage, penalty ``a_sl = 1e5`` W/K each), the input bounds (eq. 12) and ``x(0|k) = x(k)``
(eq. 13). Powers are eqs. 4-5 with ``T_ain`` from eq. 3.

Choices the paper leaves open, documented here
------------------------------------------------
* **Horizons.** ``Np = Nc = Nu = N`` (Table II: 6, ``Ts = 5 s``). The inputs are
  ``u(0|k) .. u(N-1|k)``; the cost term at ``i = N`` (eq. 7 sums to ``Np``) uses the predicted
  terminal state with the last input held, ``u(N|k) := u(N-1|k)``.
* **Slacks.** ``x(0|k)`` is fixed by eq. 13, so its slack would only add a constant to the
  objective; slacks are defined for ``i = 1 .. N`` (the states the inputs can influence).
  The NLP carries one slack per bound (upper and lower, of T_cab and T_evap) rather than
  one per state: since ``x_min < x_max`` at most one of the two is positive, so the optimum
  and eq. 7 are the same, and each slack then sits in one constraint only, which keeps the
  active sets of the SQP solver non-degenerate.
* **Eq. 4 sign.** ``P_c = c_p / eta_cop * W_bl * (T_amb - T_ain)`` is used as published. It
  turns negative if ``T_ain > T_amb`` (never within Table II's bounds with the paper's
  parameters: ``T_ain`` stays below 21 degC), so the optimiser cannot profit from it there.
* **Eq. 4 efficiency per stage.** ``eta_cop`` enters the NLP as a parameter per stage
  ``i = 0 .. N`` (default ``params.eta_cop`` everywhere: the paper's model); ``solve`` and
  ``make_step`` accept an ``eta_cop`` preview, used by the speed-aware controller of
  :mod:`acid.control.speed_model` (beyond the paper, whose assumption 3 leaves speed out).
* **Eq. 13, ``u(0|k) = u(k)``**, is ambiguous; both readings are supported
  (``NMPCConfig.first_move``):

  - ``"free"`` (default): ``u(0|k)`` is a decision variable and is the input applied over
    ``[t_k, t_k + Ts)``; eq. 13 merely names it. This is the usual receding-horizon MPC and
    it reacts to the measurement within the same sample.
  - ``"pinned"``: ``u(0|k)`` is fixed to the input already being applied over
    ``[t_k, t_k + Ts)`` (committed at the previous update), as in a controller whose
    computation takes up to one period; the solver chooses ``u(1|k) ..`` and ``u(1|k)`` is
    committed for the next period. ``make_step`` keeps the committed input.

Beyond the paper
----------------
* **Offset-free prediction** (``NMPCConfig.offset_free``, default on): eqs. 1-2 carry
  additive disturbances ``d = [d_cab, d_evap]`` (K per step), estimated in ``make_step`` by
  the Kalman filter of :mod:`acid.control.estimator` on the model augmented with them and held
  over the horizon, so that the plant, not only the model, rides an active bound. On the
  control-oriented model itself the estimate stays at zero (to rounding) and nothing
  changes.
* **Exact bounds.** Interior-point solvers relax every bound by ``1e-8 max(1, |bound|)`` in
  the NLP's units (IPOPT's ``bound_relax_factor``, set to 0 here; fatrop's is fixed). With
  ``T <= T_max`` written directly that is 2.7e-6 K at 300 K, at every stage. So every state
  bound is a constraint ``T - T_max - v_sl <= 0`` with the bound an NLP parameter and the
  limit exactly 0, and the inputs are offsets from the maximum-cooling corner in g/s and K:
  a relaxed bound moves the cabin by about 1e-9 K (measured: at most 1e-9 K above an
  active bound, against 2.7e-6 K before).
  The reported objective is eq. 7 evaluated at the applied plan: the predicted trajectory is
  recomputed from the plan (clipped to its bounds) with the declared model, the slacks are
  its actual violations.
* **Model parameters as NLP parameters.** gamma, tau, beta, c_p enter as parameters, so one
  built (and compiled) solver serves every parameter set of the same horizon and options.

Solver
------
The NLP is built once from a declared layout (:class:`acid.control.layout.BlockVector`: named
blocks per stage ``[x_0, u_0, s_1, x_1, u_1, s_2, ..., x_N]``; every index map is derived
from it). By default (``solver="sqp"``) an SQP method with exact Hessian and the active-set
QP solver qrqp (the algorithm of ``acid export-c``) solves it to ``SQP_TOL``, warm-started
from the previous primal and dual solution shifted by one stage, the plan's last
``WARM_START_HOLD`` stages held in place (its end arc stays at the horizon's end, where the
next optimum has it: 2.68 instead of 3.2 SQP iterations a step); an active-set method meets
active bounds exactly. When it fails (a degenerate active set can stall qrqp), the same
problem is solved from the same guess by CasADi's structure-exploiting interior-point
solver **fatrop** (``fallback_solver``; shipped in the casadi wheel, it detects the
optimal-control structure, ``structure_detection='auto'``), counted in
``NMPC.solver_fallbacks``. Both converge to the same optimum (measured on the 50 states of
``benchmarks/bench_mpc.py``: first moves within 7.7e-9 relative); SQP is about twice as
fast there. fatrop or IPOPT alone: ``solver="fatrop"`` / ``"ipopt"``. Exact derivatives
(CasADi AD) in all. :class:`acid.control.codegen.solver.NLPSolver` runs SQP and fatrop as
**generated
C**, compiled at first use into a per-user cache (``NMPCConfig.compiled``; without a C
compiler, inside CasADi with one notice: the same answers), with a wall-clock cap per
solve only when asked for (``NMPCConfig.max_solve_s``, an ECU-like run; a solve that
timed out is not retried by the fallback solver). Time-varying bounds, the initial state,
the disturbances and their estimates enter as NLP parameters, so nothing is rebuilt
between solves.

Inputs are checked before the solver: non-finite values are refused, and temperatures must
be plausible in kelvin (a state given in degC is refused with a message saying so).

If the solver fails, times out or its input is a non-finite measurement, ``make_step``
applies a safe fallback -- the rest of the last successful plan, shifted, else a
conservative input (maximum cooling) -- counts it in ``NMPC.fallbacks``, emits a
:class:`acid.errors.SolverWarning` and carries on.
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from acid.control.estimator import (
    BackoffConfig,
    ErrorBackoff,
    EstimatorConfig,
    OffsetFreeEstimator,
)
from acid.control.ocp import OCP, OCPSpec, SoftBound, disturbed_dynamics, stage_shift
from acid.errors import ConfigError, DataError, SolverWarning
from acid.executor import check_interrupt
from acid.paper import TABLE_II

__all__ = ["BackoffConfig", "MPCSolution", "NMPC", "NMPCConfig", "StepLog", "predict"]
from acid.control.codegen.build import CodegenError
from acid.control.codegen.solver import NLPResult, NLPSolver, StepSolver, step_function
from acid.models.paper import model as PAPER_MODEL
from acid.models.params import PARAMETER_TABLE, ModelParams, as_params
from acid.units import C2K

#: x = [T_cab, T_evap], u = [W_bl, T_evap_set] (the declaration's order)
_NX, _NU = PAPER_MODEL.nx, PAPER_MODEL.nu
#: The interior-point solvers relax every bound by 1e-8 max(1, |bound|) in the NLP's own
#: units (fatrop cannot be told not to). So the NLP's inputs are offsets from the maximum
#: cooling corner in g/s and K (``u_nlp = (u - [W_bl_max, T_evap_set_min]) * U_SCALE``) and
#: the state bounds are constraints with zero limits: a relaxed bound then moves the cabin
#: by about 1e-9 K, instead of 1e-7 K (W_bl in kg/s) or 3e-6 K (limits of ~300 K).
U_SCALE = np.array([1e3, 1.0])
SOLVERS = ("fatrop", "ipopt", "sqp")
DISTURBANCES = ("state", "inlet")
#: where the offset-free disturbances [d_cab, d_evap] act, per ``NMPCConfig.disturbance``:
#: named states (added to their next value) or outputs (eq. 3's inlet air, read by eq. 1)
DISTURBANCE_TARGETS = {"state": ("T_cab", "T_evap"), "inlet": ("T_ain", "T_evap")}
#: per-stage parameters of eq. 4 in the paper's stage cost
STAGE_PARAMETERS = ("T_amb", "eta_cop", "c_p")
#: plausible temperatures inside the model, K (-60 .. 150 degC): anything else is an error
T_PLAUSIBLE_K = (213.15, 423.15)
#: SQP tolerance on the constraint violation (K) and the scaled dual infeasibility: SQP
#: converges quadratically, so a tight tolerance costs about one iteration
SQP_TOL = 1e-10
#: what an SQP result must meet to count as converged (primal infeasibility in K, largest
#: entry of the scaled Lagrangian's gradient): the generated SQP also stops, reporting
#: success, at its iteration limit or on a step shorter than SQP_TOL
SQP_ACCEPT = (1e-8, 1e-8)
#: stages at the horizon's end held in place in the warm start: the paper's cost has no
#: terminal term, so its plans end in an arc tied to the horizon's end (T_evap_set at its
#: upper bound over the last two stages), which a plain shift moves one stage early. Held,
#: the SQP needs 2.68 instead of 3.2 iterations a step and its QPs 28 % less time on the
#: bench's states (``benchmarks/bench_mpc.py``), same moves to 2e-12
WARM_START_HOLD = 2


def _verify(solver: str) -> tuple[float, float] | None:
    """The convergence check ``NLPSolver`` applies to ``solver``'s results."""
    return SQP_ACCEPT if solver == "sqp" else None


@dataclass(frozen=True)
class NMPCConfig:
    """Options of the NMPC (Table II defaults; temperatures in K).

    Attributes
    ----------
    N : prediction = constraint = control horizon ``Np = Nc = Nu`` (Table II: 6 steps).
    first_move : ``"free"`` (default) or ``"pinned"``, the two readings of eq. 13.
    solver : ``"sqp"`` (default: SQP with the active-set QP solver qrqp, warm-started from
        the shifted previous solution; the algorithm of the C export), ``"fatrop"``
        (structure-exploiting interior point) or ``"ipopt"``.
    fallback_solver : solves the same problem, from the same guess, when ``solver`` fails
        (default ``"fatrop"``; None, or the same as ``solver``: the controller's fallback
        input at once). Both converge to the same optimum (first move within about 1e-8).
    slack_penalty : ``a_sl``, W per K of violation, per state (paper: 1e5).
    T_amb : ambient temperature in eq. 4, K (Table II: 30 degC).
    T_cab_min : lower cabin bound, K (Table II: 20 degC); the upper bound is previewed.
    T_evap_min, T_evap_max : evaporator wall bounds, K (Table II: 0 and 12 degC).
    W_bl_min, W_bl_max : blower air flow bounds, kg/s (Table II: 0.05, 0.15).
    T_evap_set_min, T_evap_set_max : set-point bounds, K (Table II: 3, 10 degC).
    tol : convergence tolerance of fatrop and IPOPT (on the NLP with the objective scaled
        by ``cost_scale``); 1e-10 makes the first move agree with the SQP solver (and with
        ``acid export-c``) to about 1e-10 relative, for about one more iteration than 1e-8.
    max_iter : iteration limit of the solver.
    cost_scale : factor applied to the objective inside the NLP (kW instead of W) for
        conditioning; reported objectives are unscaled (W summed over the stages).
    fallback_input : conservative input (W_bl kg/s, T_evap_set K) when no plan is left:
        maximum cooling, by default.
    compiled : run the solver as generated C (``"auto"``: when a C compiler works, else
        inside CasADi with one notice; ``False``: always inside CasADi). IPOPT cannot be
        generated and always runs inside CasADi.
    max_solve_s : wall-clock cap per solve, s, for an ECU-like real-time run only; a solve
        still running then is abandoned and the fallback applied (the paper's budget is an
        *average* of Ts/8 = 0.625 s). The solve then runs in a worker thread (about 0.3 ms
        per step on an idle machine, far more when the other cores are busy) and the
        closed loop depends on the machine's load. Default None: no cap, the solve runs in
        the caller's thread (offline studies, tests, sweeps; the inputs are still checked,
        so no NaN reaches the solver).
    offset_free : estimate disturbances in ``make_step`` with a Kalman filter and predict
        with them (:class:`acid.control.estimator.OffsetFreeEstimator`).
    disturbance : where the disturbances enter, ``"state"`` (added to eqs. 1-2) or
        ``"inlet"`` (added to eq. 3's inlet air and to eq. 2); see :func:`predict`.
    estimator : tuning of that Kalman filter.
    backoff : tighten the cabin bounds in ``make_step`` by the recent one-step prediction
        errors of T_cab (:class:`acid.control.estimator.ErrorBackoff`); None (default): off, the
        paper's NMPC. Scenario (b) of ``acid mpc-check`` turns it on. It assumes the errors
        are the model's: with the compressor shut off open loop (the CAV case) they are
        not, and the margin would grow for nothing.
    warm_start_hold : stages at the horizon's end whose previous values the warm start
        keeps in place (``acid.control.ocp.stage_shift``), the ones before them shifted by
        one (default ``WARM_START_HOLD``; N - 1 or more: the previous solution unshifted).
    """

    N: int = TABLE_II.N
    first_move: str = "free"
    solver: str = "sqp"
    fallback_solver: str | None = "fatrop"
    slack_penalty: float = TABLE_II.slack_penalty
    T_amb: float = C2K(TABLE_II.T_amb_degC)
    T_cab_min: float = C2K(TABLE_II.T_cab_min_degC)
    T_evap_min: float = C2K(TABLE_II.T_evap_min_degC)
    T_evap_max: float = C2K(TABLE_II.T_evap_max_degC)
    W_bl_min: float = TABLE_II.W_bl_min
    W_bl_max: float = TABLE_II.W_bl_max
    T_evap_set_min: float = C2K(TABLE_II.T_evap_set_min_degC)
    T_evap_set_max: float = C2K(TABLE_II.T_evap_set_max_degC)
    tol: float = 1e-10
    max_iter: int = 200
    cost_scale: float = 1e-3
    fallback_input: tuple[float, float] | None = None
    compiled: bool | str = "auto"
    max_solve_s: float | None = None
    offset_free: bool = False
    disturbance: str = "state"
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)
    backoff: BackoffConfig | None = None
    warm_start_hold: int = WARM_START_HOLD

    def __post_init__(self):
        if self.first_move not in ("free", "pinned"):
            raise ConfigError(f"first_move must be 'free' or 'pinned', got {self.first_move!r}")
        if self.solver not in SOLVERS:
            raise ConfigError(f"solver must be one of {', '.join(SOLVERS)}, got "
                              f"{self.solver!r}")
        if self.fallback_solver is not None and self.fallback_solver not in SOLVERS:
            raise ConfigError(f"fallback_solver must be None or one of {', '.join(SOLVERS)}, "
                              f"got {self.fallback_solver!r}")
        if int(self.N) < 2:
            raise ConfigError(f"horizon N must be at least 2, got {self.N}")
        hold = self.warm_start_hold
        if isinstance(hold, bool) or not isinstance(hold, (int, np.integer)) or hold < 0:
            raise ConfigError(f"warm_start_hold must be a whole number of stages >= 0, got "
                              f"{self.warm_start_hold}")
        if not (self.W_bl_min < self.W_bl_max and self.T_evap_set_min < self.T_evap_set_max):
            raise ConfigError("input bounds must satisfy min < max")
        if self.compiled not in ("auto", True, False):
            raise ConfigError(f"compiled must be 'auto', True or False, got {self.compiled!r}")
        if self.disturbance not in DISTURBANCES:
            raise ConfigError(f"disturbance must be one of {', '.join(DISTURBANCES)}, got "
                              f"{self.disturbance!r}")
        if self.max_solve_s is not None and not (math.isfinite(self.max_solve_s)
                                                 and self.max_solve_s > 0):
            raise ConfigError(f"max_solve_s must be a positive number of seconds or None, "
                              f"got {self.max_solve_s}")
        for name in ("T_amb", "T_cab_min", "T_evap_min", "T_evap_max", "T_evap_set_min",
                     "T_evap_set_max"):
            _check_kelvin(getattr(self, name), f"NMPCConfig.{name}")

    @property
    def u_min(self) -> np.ndarray:
        """Lower input bounds [W_bl kg/s, T_evap_set K]."""
        return np.array([self.W_bl_min, self.T_evap_set_min])

    @property
    def u_max(self) -> np.ndarray:
        """Upper input bounds [W_bl kg/s, T_evap_set K]."""
        return np.array([self.W_bl_max, self.T_evap_set_max])

    @property
    def u_safe(self) -> np.ndarray:
        """The conservative fallback input (maximum cooling unless configured)."""
        if self.fallback_input is not None:
            return np.array(self.fallback_input, dtype=float)
        return np.array([self.W_bl_max, self.T_evap_set_min])

    def to_json_dict(self) -> dict:
        """The options, JSON-serialisable (temperatures in K)."""
        return {
            "N": self.N, "first_move": self.first_move, "solver": self.solver,
            "fallback_solver": self.fallback_solver,
            "slack_penalty_W_per_K": self.slack_penalty, "T_amb_K": self.T_amb,
            "T_cab_min_K": self.T_cab_min, "T_evap_min_K": self.T_evap_min,
            "T_evap_max_K": self.T_evap_max, "W_bl_min_kg_s": self.W_bl_min,
            "W_bl_max_kg_s": self.W_bl_max, "T_evap_set_min_K": self.T_evap_set_min,
            "T_evap_set_max_K": self.T_evap_set_max, "tol": self.tol,
            "max_iter": self.max_iter, "fallback_input": self.u_safe.tolist(),
            "compiled": self.compiled, "max_solve_s": self.max_solve_s,
            "offset_free": self.offset_free, "disturbance": self.disturbance,
            "estimator": self.estimator.to_json_dict(),
            "backoff": None if self.backoff is None else self.backoff.to_json_dict(),
            "warm_start_hold": self.warm_start_hold,
        }


#: plausible kelvin range as two names (a step's fast test before _check_kelvin's)
_T_LO, _T_HI = T_PLAUSIBLE_K


def _check_kelvin(values, name: str) -> None:
    """Refuse non-finite or implausible temperatures (K) with a one-line message."""
    a = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(a)):
        raise DataError(f"{name} is not finite ({a.tolist()}): the NMPC needs measured "
                        "temperatures in K")
    lo, hi = T_PLAUSIBLE_K
    bad = (a < lo) | (a > hi)
    if np.any(bad):
        v = float(a[bad].flat[0])
        hint = (f" (it looks like degC: {v:g} degC is {C2K(v):g} K)"
                if -60.0 <= v <= 150.0 else "")
        raise DataError(f"{name} = {v:g} K is not a plausible temperature in K "
                        f"({lo:g}-{hi:g} K){hint}")


@dataclass(frozen=True)
class MPCSolution:
    """One NMPC solve: the first move and the whole predicted trajectory.

    Attributes
    ----------
    u : (2,) the input to apply over ``[t_k, t_k + Ts)`` -- [W_bl kg/s, T_evap_set K]. In
        ``"free"`` mode ``u(0|k)``; in ``"pinned"`` mode the pinned ``u(0|k)`` as well (the
        move the solve decided is ``W_bl[1], T_evap_set[1]``).
    T_cab, T_evap : (N+1,) predicted states x(0|k) .. x(N|k), K: the model (with the
        disturbance estimate) simulated along the plan.
    T_ain : (N+1,) predicted inlet air (eq. 3), K, with ``u(N|k) = u(N-1|k)``.
    W_bl, T_evap_set : (N,) planned inputs u(0|k) .. u(N-1|k), kg/s and K.
    P_comp, P_bl : (N+1,) predicted powers (eqs. 4-5), W.
    slack_cab, slack_evap : (N,) slacks v_sl(1|k) .. v_sl(N|k), K: the predicted
        trajectory's actual bound violations.
    objective : eq. 7 at the plan, W (powers summed over i = 0..N plus a_sl * slacks).
    status : solver return status (text).
    success : whether the solver reported convergence and the solution is finite.
    iterations : solver iterations (-1 where the generated solver does not report them).
    solve_time_s : wall time of the solver call, s.
    disturbance : (2,) disturbance estimate [d_cab, d_evap] used in the prediction, K/step.
    """

    u: np.ndarray
    T_cab: np.ndarray
    T_evap: np.ndarray
    T_ain: np.ndarray
    W_bl: np.ndarray
    T_evap_set: np.ndarray
    P_comp: np.ndarray
    P_bl: np.ndarray
    slack_cab: np.ndarray
    slack_evap: np.ndarray
    objective: float
    status: str
    success: bool
    iterations: int
    solve_time_s: float
    disturbance: np.ndarray = field(default_factory=lambda: np.zeros(2))

    @property
    def plan(self) -> np.ndarray:
        """(N, 2) planned inputs [W_bl, T_evap_set] for i = 0 .. N-1."""
        return np.column_stack([self.W_bl, self.T_evap_set])


@dataclass
class StepLog:
    """What ``NMPC.make_step`` did at each update (the controller's own record).

    Attributes
    ----------
    u : applied inputs, one (2,) array per step.
    solutions : the MPC solutions (``None`` where the solver raised or was not called).
    fallback : whether each step used the fallback.
    step_time_s : wall time of each whole ``make_step`` call (Python overhead included), s.
    disturbance : the disturbance estimate used at each step (see ``NMPCConfig``).
    margin : the cabin-bound back-off (below the upper, above the lower bound) at each
        step, K.
    """

    u: list = field(default_factory=list)
    solutions: list = field(default_factory=list)
    fallback: list = field(default_factory=list)
    step_time_s: list = field(default_factory=list)
    disturbance: list = field(default_factory=list)
    margin: list = field(default_factory=list)


def paper_stage_cost(s) -> dict:
    """Eq. 7's stage terms, W: eq. 4 ``P_c = c_p / eta_cop * W_bl * (T_amb - T_ain)`` with
    ``T_ain`` the declared eq. 3 and ``eta_cop``, ``T_amb``, ``c_p`` stage parameters, and
    eq. 5's declared blower power."""
    return {"P_comp": s.c_p / s.eta_cop * s.W_bl * (s.T_amb - s.T_ain), "P_bl": s.P_bl}


def ocp_spec(config: NMPCConfig) -> OCPSpec:
    """The paper's NMPC (eqs. 7-13) as a configuration of the one optimal-control builder
    (:class:`acid.control.ocp.OCP`) over ``acid.models.paper.model``: the economic stage
    cost of eqs. 4-5, the stage ``i = N`` with the last input held, soft bounds on both
    states (the upper cabin bound previewed), inputs scaled as offsets from the
    maximum-cooling corner (``U_SCALE``)."""
    cfg = config
    corner = {"W_bl": cfg.W_bl_max, "T_evap_set": cfg.T_evap_set_min}
    return OCPSpec(
        N=int(cfg.N), stage_cost=paper_stage_cost, stage_parameters=STAGE_PARAMETERS,
        input_bounds={"W_bl": (cfg.W_bl_min, cfg.W_bl_max),
                      "T_evap_set": (cfg.T_evap_set_min, cfg.T_evap_set_max)},
        soft_bounds=(SoftBound("T_cab", cfg.T_cab_min, cfg.T_cab_min + 10.0,
                               cfg.slack_penalty),
                     SoftBound("T_evap", cfg.T_evap_min, cfg.T_evap_max, cfg.slack_penalty)),
        disturbance_targets=DISTURBANCE_TARGETS[cfg.disturbance], terminal_stage=True,
        u_offset=corner, u_scale=dict(zip(corner, U_SCALE, strict=True)),
        cost_scale=cfg.cost_scale)


def theta_vector(p: ModelParams) -> np.ndarray:
    """The declaration's parameter vector (``acid.models.paper``'s table, by name) of a
    parameter set."""
    values = dict(zip((n for n, _, _ in PARAMETER_TABLE), p.theta, strict=True))
    return np.array([values[n] for n in PAPER_MODEL.parameter_names])


_DYNAMICS: dict[str, ca.Function] = {}


def _dynamics(disturbance: str) -> ca.Function:
    if disturbance not in _DYNAMICS:
        _DYNAMICS[disturbance] = disturbed_dynamics(PAPER_MODEL,
                                                    DISTURBANCE_TARGETS[disturbance])
    return _DYNAMICS[disturbance]


def predict(T_cab, T_evap, W_bl, T_evap_set, T_int, T_shell, d, p, disturbance="state"):
    """One step of the NMPC's prediction model: the declared eqs. 1-3 with the disturbances
    ``d`` (``acid.models.paper``).

    ``disturbance="state"``: ``d = [d_cab, d_evap]`` added to eqs. 1-2 (K per step).
    ``disturbance="inlet"``: ``d[0]`` added to eq. 3's inlet air (K), so that it acts on
    the cabin through the air flow as the inlet air does; ``d[1]`` added to eq. 2.
    Floats or CasADi symbols. Returns (T_cab+, T_evap+, T_ain), K.
    """
    F = _dynamics(disturbance)
    pairs = ((T_cab, T_evap), (W_bl, T_evap_set), (T_int, T_shell), (d[0], d[1]))
    if not any(isinstance(v, (ca.SX, ca.MX)) for pair in pairs for v in pair):
        x, u, v, dd = (np.array(pair, dtype=float) for pair in pairs)
        x_next, y = F(x, u, v, theta_vector(p), dd)
        x_next, y = x_next.full().ravel(), y.full().ravel()
        return float(x_next[0]), float(x_next[1]), float(y[0])
    x_next, y = F(*(ca.vertcat(*pair) for pair in pairs[:3]), theta_vector(p),
                  ca.vertcat(*pairs[3]))
    return x_next[0], x_next[1], y[0]


def model_function(p, disturbance: str = "state", name: str = "acid_model") -> ca.Function:
    """The prediction model as a CasADi function ``(x, u, v, d) -> x_next`` with
    ``x = [T_cab, T_evap]``, ``u = [W_bl, T_evap_set]``, ``v = [T_int, T_shell]`` (K, kg/s)
    and the disturbances ``d`` of :func:`predict` (for the estimator)."""
    F = _dynamics(disturbance)
    x, u, v, d = (ca.SX.sym(n, 2) for n in ("x", "u", "v", "d"))
    return ca.Function(name, [x, u, v, d], [F(x, u, v, ca.DM(theta_vector(p)), d)[0]],
                       ["x", "u", "v", "d"], ["x_next"])


class NMPC:
    """The paper's NMPC (eqs. 7-13) on the control-oriented model.

    Parameters
    ----------
    params : model parameters (eqs. 1-5, kelvin convention), e.g. from ``load_params``.
    config : options (Table II defaults).

    Notes
    -----
    ``solve`` is stateless apart from the warm start; ``make_step`` is the closed-loop
    interface (do-mpc style ``u = mpc.make_step(x, ...)``), which handles the disturbance
    estimate, the pinned first move, the fallback and the log. Build once, call many times.
    ``backend`` tells whether the solver runs as compiled C or inside CasADi.
    """

    def __init__(self, params: ModelParams, config: NMPCConfig | None = None):
        self.params = as_params(params)  # ModelParams or a FitResult
        self.config = config or NMPCConfig()
        self.N = int(self.config.N)
        self._theta = theta_vector(self.params)
        self._build()
        self.estimator = (OffsetFreeEstimator(model_function(self.params,
                                                             self.config.disturbance),
                                              config=self.config.estimator,
                                              compiled=self.config.compiled)
                          if self.config.offset_free else None)
        self.backoff = (ErrorBackoff(self.config.backoff) if self.config.backoff is not None
                        else None)
        self.reset()

    @property
    def backend(self) -> str:
        """``"compiled"`` (generated C) or ``"casadi"``."""
        return "compiled" if self._step is not None else self._nlp.backend

    # ----------------------------------------------------------------- build
    def _build(self) -> None:
        """Build the NLP once: eqs. 7-13 as the paper's configuration of the one
        optimal-control builder (:func:`ocp_spec`) over ``acid.models.paper.model``."""
        cfg = self.config
        ocp = self._ocp = OCP(PAPER_MODEL, ocp_spec(cfg))
        self._w, self._g, self._p = ocp.w, ocp.g, ocp.par
        self._nlp_dict = ocp.nlp
        self._fallback_nlp: NLPSolver | None = None
        if cfg.max_solve_s is not None:  # a real-time run builds it now, not mid-run
            self._fallback_solver()
        self._iT_cab = ocp.w.index("x", 0)
        self._iT_evap = ocp.w.index("x", 1)
        self._iu = ocp.w.index("u")
        self._u_ref = ocp.u_offset
        self._lbx0, self._ubx0 = ocp.lbx, ocp.ubx
        self._lbg, self._ubg = ocp.lbg, ocp.ubg
        N = self.N
        self._pvec = ocp.parameters(
            np.zeros(ocp.par.size), theta=self._theta,
            bounds={("T_evap", "hi"): np.full(N, cfg.T_evap_max),
                    ("T_evap", "lo"): np.full(N, cfg.T_evap_min)})
        # warm start: the previous primal/dual solution shifted by one stage, its last
        # ``warm_start_hold`` stages held in place
        self._shift_w = stage_shift(ocp.w, cfg.warm_start_hold)
        self._shift_g = stage_shift(ocp.g, cfg.warm_start_hold)
        self._trajectory = ocp.trajectory_evaluator(cfg.compiled)
        # what every step reads, computed once (a step's Python overhead is a third of it)
        self._u_lo, self._u_hi = cfg.u_min, cfg.u_max
        self._i_T_ain = PAPER_MODEL.output_names.index("T_ain")
        self._i_P = tuple(ocp.term_names.index(n) for n in ("P_comp", "P_bl"))
        # the stage parameters [T_amb, eta_cop, c_p] of a step given neither T_amb nor
        # eta_cop (the paper's case): the same every step, so built (and read-only) once
        eta = self._preview(self.params.eta_cop, N + 1, "eta_cop")
        self._eta_default = eta.copy()
        self._Q_default = np.column_stack((np.full(N + 1, cfg.T_amb), eta,
                                           np.full(N + 1, self.params.c_p)))
        self._eta_default.setflags(write=False)
        self._eta_ok = bool(eta.min() > 0 and np.isfinite(eta.max()))
        self._lb_default = np.full(N + 1, float(cfg.T_cab_min))
        self._lb_default.setflags(write=False)
        self._Q_default.setflags(write=False)
        # the SQP's whole step (guess, solve, convergence check, plan and trajectory) as
        # one generated C call when it compiles; the separate solver is then CasADi's (it
        # only serves a build without a compiler)
        self._step: StepSolver | None = None
        self._build_step()
        self._nlp = NLPSolver("acid_nmpc", ocp.nlp, *self._solver_options(cfg.solver),
                              compiled=cfg.compiled if self._step is None else False,
                              verify=_verify(cfg.solver), timeout_s=cfg.max_solve_s)

    def _build_step(self) -> None:
        """``self._step``: one generated C function per step (:func:`step_function`) for the
        SQP when generated C is allowed and compiles; None otherwise."""
        cfg, ocp, N = self.config, self._ocp, self.N
        if cfg.solver != "sqp" or cfg.compiled is False:
            return
        w, p = ca.SX.sym("w", ocp.w.size), ca.SX.sym("p", ocp.par.size)
        ug, x0 = ca.SX.sym("u_guess", _NU), ca.SX.sym("x0", _NX)
        ip = ocp._ip
        th, dist = p[ip["theta"].ravel().tolist()], p[ip["dist"].ravel().tolist()]
        D = ca.reshape(p[ip["d"].ravel().tolist()], ip["d"].shape[1], N)
        Q = ca.reshape(p[ip["q"].ravel().tolist()], ip["q"].shape[1], ip["q"].shape[0])
        xm = p[ip["x0"].ravel().tolist()]   # the measured state, K
        ix, iu = ocp.w.index("x"), self._iu
        xoff, xscl = ca.DM(ocp.x_offset), ca.DM(ocp.x_scale)
        uoff, uscl = ca.DM(ocp.u_offset), ca.DM(ocp.u_scale)
        # the cold guess: the model run with u_guess held (as _initial_guess)
        Xc = ocp.trajectory(xm, ca.repmat(ug, 1, N), D, Q, th, dist)[0]
        wc = ca.SX.zeros(ocp.w.size)
        wc[ix.ravel().tolist()] = ca.vec((Xc - ca.repmat(xoff, 1, N + 1))
                                         / ca.repmat(xscl, 1, N + 1))
        wc[iu.ravel().tolist()] = ca.repmat((ug - uoff) * uscl, N, 1)
        cold = ca.Function("acid_nmpc_cold", [x0, p, ug], [wc])
        # what a step reports (as _solution): the clipped plan and its trajectory
        U = ca.repmat(uoff, 1, N) + ca.reshape(w[iu.ravel().tolist()], _NU, N) \
            / ca.repmat(uscl, 1, N)
        U = ca.fmin(ca.fmax(U, ca.repmat(ca.DM(self._u_lo), 1, N)),
                    ca.repmat(ca.DM(self._u_hi), 1, N))
        X, Y, terms = ocp.trajectory(xm, U, D, Q, th, dist)
        T_cab, T_evap = X[0, 1:].T, X[1, 1:].T
        s_cab = ca.fmax(ca.fmax(T_cab - p[ip["T_cab_hi"].ravel().tolist()],
                                p[ip["T_cab_lo"].ravel().tolist()] - T_cab), 0)
        s_evap = ca.fmax(ca.fmax(T_evap - p[ip["T_evap_hi"].ravel().tolist()],
                                 p[ip["T_evap_lo"].ravel().tolist()] - T_evap), 0)
        P_comp, P_bl = terms[self._i_P[0], :].T, terms[self._i_P[1], :].T
        objective = ca.sum1(P_comp) + ca.sum1(P_bl) \
            + cfg.slack_penalty * (ca.sum1(s_cab) + ca.sum1(s_evap))
        names = ["W_bl", "T_evap_set", "T_cab", "T_evap", "T_ain", "P_comp", "P_bl",
                 "slack_cab", "slack_evap", "objective"]
        parts = [U[0, :].T, U[1, :].T, X[0, :].T, X[1, :].T, Y[self._i_T_ain, :].T, P_comp,
                 P_bl, s_cab, s_evap, objective]
        # one output vector (one copy a step); its pieces as slices
        ends = np.cumsum([e.numel() for e in parts])
        self._report = dict(zip(names, (slice(a, b) for a, b in
                                        zip(np.r_[0, ends[:-1]], ends, strict=True)),
                                strict=True))
        post = ca.Function("acid_nmpc_post", [w, p], [ca.vertcat(*parts)], ["w", "p"],
                           ["report"])
        plugin, opts = self._solver_options(cfg.solver)
        fn = step_function("acid_nmpc_step", ocp.nlp, plugin, dict(opts, error_on_fail=True),
                           lbg=self._lbg, ubg=self._ubg, shift_w=self._shift_w,
                           shift_g=self._shift_g, ix0=ix[0], cold=cold, post=post)
        try:
            self._step = StepSolver(fn, timeout_s=cfg.max_solve_s)
        except CodegenError:   # the separate calls (NLPSolver notices why)
            self._step = None
        self._lbx_in = None   # the lbx the step's input buffer holds (None: unknown)
        self._views_of = self._views = None   # see _step_views

    def _fallback_solver(self) -> NLPSolver | None:
        """The solver of ``config.fallback_solver`` (None when there is none), built at its
        first use (most closed loops never need it)."""
        cfg = self.config
        if cfg.fallback_solver in (None, cfg.solver):
            return None
        if self._fallback_nlp is None:
            self._fallback_nlp = NLPSolver(
                f"acid_nmpc_{cfg.fallback_solver}", self._nlp_dict,
                *self._solver_options(cfg.fallback_solver), compiled=cfg.compiled,
                verify=_verify(cfg.fallback_solver), timeout_s=cfg.max_solve_s)
        return self._fallback_nlp

    def _solver_options(self, solver: str) -> tuple[str, dict]:
        """(plugin, options) of ``solver``: no bound relaxation anywhere."""
        cfg = self.config
        if solver == "fatrop":
            return "fatrop", {
                "structure_detection": "auto", "equality": self._ocp.equality.tolist(),
                "print_time": False,
                "fatrop": {"print_level": 0, "tol": cfg.tol, "max_iter": int(cfg.max_iter)}}
        if solver == "ipopt":
            return "ipopt", {"print_time": False,
                             "ipopt": {"print_level": 0, "sb": "yes", "tol": cfg.tol,
                                       "max_iter": int(cfg.max_iter),
                                       "bound_relax_factor": 0.0}}
        return "sqpmethod", sqp_options(max_iter=int(cfg.max_iter))

    def _u_nlp(self, u) -> np.ndarray:
        """Inputs [W_bl kg/s, T_evap_set K] as the NLP's scaled variables."""
        return self._ocp.u_nlp(u)

    def _u_plan(self, w: np.ndarray) -> np.ndarray:
        """(N, 2) planned inputs [W_bl kg/s, T_evap_set K] from the NLP vector."""
        return self._ocp.plan(w)

    # ----------------------------------------------------------------- state
    def reset(self, u_initial=None) -> None:
        """Forget the warm start, the plan, the estimate, the log and the fallback count.

        ``u_initial`` (W_bl kg/s, T_evap_set K) is the input applied over the first period in
        ``"pinned"`` mode (default: the conservative input).
        """
        self._w_prev = None
        self._lam_g_prev = None
        self._lam_x_prev = None
        self._plan = None  # the last successful solution (MPCSolution: its plan)
        self._plan_age = 0
        self._committed = (np.array(u_initial, dtype=float) if u_initial is not None
                           else self.config.u_safe.copy())
        self._applied = None  # (u, v) applied over the last period, for the estimator
        self._predicted = None  # T_cab(k+1) the model predicted, for the back-off
        if self.estimator is not None:
            self.estimator.reset()
        if self.backoff is not None:
            self.backoff.reset()
        self.fallbacks = 0
        self.solver_fallbacks = 0
        self.log = StepLog()

    # ----------------------------------------------------------------- solve
    def _preview(self, value, n: int, name: str) -> np.ndarray:
        a = np.asarray(value, dtype=float)
        if a.ndim == 0:
            return np.full(n, float(a))
        if a.shape[0] < n:
            raise ConfigError(f"{name}: preview needs {n} values, got {a.shape[0]}")
        return a[:n]

    def _initial_guess(self, x: np.ndarray, D: np.ndarray, Q: np.ndarray, u_prev,
                       d: np.ndarray) -> np.ndarray:
        """Shifted previous solution, else a forward simulation with a mid-range input."""
        if self._w_prev is not None:
            w = self._w_prev[self._shift_w]
            w[: _NX] = x
            return w
        cfg = self.config
        u = (np.clip(np.asarray(u_prev, dtype=float), cfg.u_min, cfg.u_max)
             if u_prev is not None else 0.5 * (cfg.u_min + cfg.u_max))
        X = self._trajectory(x, np.tile(u[:, None], self.N), D.T, Q.T, self._theta, d)[0]
        w = np.zeros(self._w.size)
        w[self._ocp.w.index("x")] = X.T
        w[self._iu] = self._u_nlp(u)
        return w

    def solve(self, x, T_cab_max, T_int, T_shell, u_prev=None, T_cab_min=None,
              T_amb=None, eta_cop=None, disturbance=None) -> MPCSolution:
        """Solve eqs. 7-13 once from the measured state.

        Parameters
        ----------
        x : (2,) measured state x(k) = [T_cab, T_evap], K (eq. 13).
        T_cab_max : upper cabin bound previewed over the horizon, K: a scalar or an array
            whose entries ``0 .. N`` are the bounds at ``t_k + i Ts``, i = 0 .. N (entry 0
            is not used: x(0|k) is given).
        T_int, T_shell : interior and shell temperatures, K, scalars or (N,) previews
            (held at their measured values when scalars, as in the paper).
        u_prev : (2,) input being applied [W_bl kg/s, T_evap_set K]; required in
            ``"pinned"`` mode (u(0|k) is fixed to it), otherwise only an initial guess.
        T_cab_min : lower cabin bound, K, scalar or (N+1,) preview (default: config).
        T_amb : ambient temperature for eq. 4, K (default: config).
        eta_cop : efficiency of eq. 4 per stage i = 0 .. N, scalar or (N+1,) preview
            (default: ``params.eta_cop`` at every stage, the paper's model).
        disturbance : (2,) additive disturbances [d_cab, d_evap] on eqs. 1-2, K per step,
            held over the horizon (default: zero, the paper's model).

        Returns
        -------
        MPCSolution (``success`` False when the solver failed or timed out; nothing is
        raised for that). Non-finite or implausible inputs raise DataError (one line),
        malformed previews ConfigError; a CasADi evaluation error propagates as
        RuntimeError.
        """
        cfg, N = self.config, self.N
        x = np.asarray(x, dtype=float).reshape(_NX)
        ub = self._preview(T_cab_max, N + 1, "T_cab_max")
        lb = (self._lb_default if T_cab_min is None
              else self._preview(T_cab_min, N + 1, "T_cab_min"))
        Ti = self._preview(T_int, N, "T_int")
        Tsh = self._preview(T_shell, N, "T_shell")
        amb = cfg.T_amb if T_amb is None else float(T_amb)
        eta = (self._eta_default if eta_cop is None
               else self._preview(eta_cop, N + 1, "eta_cop"))
        d = np.zeros(_NX) if disturbance is None else np.asarray(disturbance, float)
        lbx, ubx = self._lbx0, self._ubx0
        if cfg.first_move == "pinned":
            lbx, ubx = lbx.copy(), ubx.copy()
            if u_prev is None:
                raise ConfigError("first_move='pinned' needs u_prev, the input being applied")
            u0 = np.clip(np.asarray(u_prev, dtype=float), cfg.u_min, cfg.u_max)
            lbx[self._iu[0]] = self._u_nlp(u0)
            ubx[self._iu[0]] = self._u_nlp(u0)
        default_q = T_amb is None and eta_cop is None
        views = self._step_views() if self._step is not None else None
        if views is not None:   # the parameters written straight into the call's buffer
            pv, D, Q = self._fill_step(views, x, ub, lb, Ti, Tsh, amb, eta, d, default_q)
        else:
            self._check_inputs(x, ub, lb, Ti, Tsh, amb, eta, d)
            D = np.empty((N, 2))   # [T_int, T_shell] per stage
            D[:, 0], D[:, 1] = Ti, Tsh
            Q = self._stage_q(default_q, amb, eta)
            pv = self._ocp.parameters(self._pvec, x0=x, dist=d, d=D, q=Q, bounds={
                ("T_cab", "hi"): ub[1:], ("T_cab", "lo"): lb[1:]})
        w0 = lam_x0 = lam_g0 = None
        if self._step is not None:   # one C call: guess, solve, check, plan, trajectory
            sol, res = self._solve_step(x, pv, lbx, ubx, u_prev, d)
            if sol is not None:
                return sol
            if views is not None:   # the rare path below reads them as arrays
                pv, D, Q = pv.copy(), views["d"].copy(), views["q"].copy()
        else:
            w0 = self._initial_guess(x, D, Q, u_prev, d)
            if self._lam_g_prev is not None:
                lam_g0 = self._lam_g_prev[self._shift_g]
                lam_x0 = self._lam_x_prev[self._shift_w]
            res = self._nlp.solve(w0, pv, lbx, ubx, self._lbg, self._ubg, lam_x0, lam_g0)
        fallback = (self._fallback_solver() if not res.success and res.status != "timeout"
                    else None)
        if fallback is not None:
            if w0 is None:   # the fused step's guess, recomputed (a rare path)
                w0 = self._initial_guess(x, D, Q, u_prev, d)
                if self._lam_g_prev is not None:
                    lam_g0 = self._lam_g_prev[self._shift_g]
                    lam_x0 = self._lam_x_prev[self._shift_w]
            first = res
            res = fallback.solve(w0, pv, lbx, ubx, self._lbg, self._ubg, lam_x0,
                                           lam_g0)
            self.solver_fallbacks += 1
            res = dataclasses.replace(
                res, status=f"{res.status} ({cfg.fallback_solver} after {cfg.solver}: "
                            f"{first.status})",
                solve_time_s=first.solve_time_s + res.solve_time_s)
        if res.success:
            self._w_prev = res.x
            self._lam_g_prev = res.lam_g
            self._lam_x_prev = res.lam_x
        return self._solution(res.x, x, D, Q, ub, lb, d, res.status, res.success,
                              res.iterations, res.solve_time_s)

    def _stage_q(self, default: bool, amb: float, eta: np.ndarray) -> np.ndarray:
        """(N+1, 3) stage parameters [T_amb, eta_cop, c_p] (the shared read-only default
        when neither T_amb nor eta_cop is given)."""
        if default:
            return self._Q_default
        return np.column_stack((np.full(self.N + 1, amb), eta,
                                np.full(self.N + 1, self.params.c_p)))

    def _step_views(self) -> dict | None:
        """Views of the one call's parameter buffer by block (``x0``, ``d``, ``q``,
        ``T_cab_hi``, ...; the buffer holds the constant blocks from the first use on),
        rebuilt when the buffer is new (a reload after a timeout); None when a block is
        not contiguous in the parameter vector (the parameters are then filled as a whole,
        as for the separate solver)."""
        buf = self._step.inputs["p"]
        if self._views_of is buf:
            return self._views
        self._views_of, self._views = buf, None
        views = {}
        for name, idx in self._ocp._ip.items():
            flat = idx.ravel()
            a = int(flat[0]) if flat.size else 0
            if not np.array_equal(flat, np.arange(a, a + flat.size)):
                return None
            views[name] = buf[a:a + flat.size].reshape(idx.shape)
        if not {"x0", "dist", "d", "q", "T_cab_hi", "T_cab_lo"} <= views.keys():
            return None
        ip = self._ocp._ip
        # the temperatures _check_inputs checks, as positions in the buffer: x, T_int and
        # T_shell (d), the cabin bounds, T_amb (the stage parameters' first column)
        self._temps_at = np.concatenate([ip["x0"].ravel(), ip["d"].ravel(),
                                         ip["T_cab_hi"].ravel(), ip["T_cab_lo"].ravel(),
                                         ip["q"][:, 0].ravel()])
        buf[:] = self._pvec
        self._q_in = self._lb_in = None   # what the buffer's blocks hold (None: unknown)
        self._views = views
        return views

    def _fill_step(self, views: dict, x, ub, lb, Ti, Tsh, amb, eta, d,
                   default_q: bool) -> tuple:
        """Write a step's parameters into the one call's buffer, then check them (as
        :meth:`_check_inputs`: one test on the buffer's temperatures, the named error when it
        fails). Returns (the buffer, the ``d`` and ``q`` blocks)."""
        if d.shape != (_NX,):
            self._check_inputs(x, ub, lb, Ti, Tsh, amb, eta, d)   # raises with the name
        views["x0"][0] = x
        views["dist"][0] = d
        D = views["d"]
        D[:, 0], D[:, 1] = Ti, Tsh
        views["T_cab_hi"][:, 0] = ub[1:]
        if lb is not self._lb_in:   # the default lower bound is written once
            views["T_cab_lo"][:, 0] = lb[1:]
        self._lb_in = None
        if default_q:
            if self._q_in is not self._Q_default:
                views["q"][:] = self._Q_default
        else:
            views["q"][:] = self._stage_q(False, amb, eta)
        self._q_in = None
        buf = self._views_of
        temps = buf[self._temps_at]
        lo, hi = T_PLAUSIBLE_K
        if not (lo <= temps.min() and temps.max() <= hi and math.isfinite(d[0])
                and math.isfinite(d[1]) and eta is self._eta_default and self._eta_ok):
            self._check_inputs(x, ub, lb, Ti, Tsh, amb, eta, d)   # raises with the name
        self._lb_in = lb if lb is self._lb_default else None
        self._q_in = self._Q_default if default_q else None
        return buf, D, views["q"]

    def _solve_step(self, x, pv, lbx, ubx, u_prev, d) -> tuple[MPCSolution | None, NLPResult]:
        """One call of the fused step (:attr:`_step`): (the solution, None) when it
        converged, else (None, the failed result for the fallback solver)."""
        st = self._step
        t0 = time.perf_counter()
        inp = st.inputs
        warm = self._w_prev is not None
        if warm and self._w_prev is not inp["w_prev"]:   # found by the fallback solver
            st.load(self._w_prev, self._lam_x_prev, self._lam_g_prev)
        inp["x0"][:] = x   # the paper NLP's states are not scaled
        if pv is not inp["p"]:
            inp["p"][:] = pv
        if lbx is not self._lbx_in:   # the bounds change only with a pinned first move
            inp["lbx"][:] = lbx
            inp["ubx"][:] = ubx
            self._lbx_in = lbx if lbx is self._lbx0 else None
        if not warm:
            cfg = self.config
            inp["u_guess"][:] = (np.clip(np.asarray(u_prev, dtype=float), cfg.u_min, cfg.u_max)
                                 if u_prev is not None else 0.5 * (cfg.u_min + cfg.u_max))
        finished, flag = st.step(warm)
        dt = time.perf_counter() - t0
        if not finished:
            nan = np.full(inp["w_prev"].size, np.nan)
            return None, NLPResult(x=nan, f=float("nan"), lam_x=nan,
                                   lam_g=np.full(inp["lam_g_prev"].size, np.nan),
                                   success=False, status="timeout", iterations=-1,
                                   solve_time_s=dt)
        o = st.outputs
        pr, du = float(o["pr_inf"][0]), float(o["du_inf"][0])
        tol_pr, tol_du = SQP_ACCEPT
        if flag or not (pr <= tol_pr and du <= tol_du and np.isfinite(o["w"].sum())):
            status = (f"failed (code {flag})" if flag else
                      f"not converged (primal {pr:.1e}, dual {du:.1e}; Solve_Succeeded)")
            return None, NLPResult(x=o["w"].copy(), f=float(o["f"][0]),
                                   lam_x=o["lam_x"].copy(), lam_g=o["lam_g"].copy(),
                                   success=False, status=status, iterations=-1,
                                   solve_time_s=dt)
        r, k = o["report"].copy(), self._report
        W, Tset = r[k["W_bl"]], r[k["T_evap_set"]]
        sol = MPCSolution(u=np.array([W[0], Tset[0]]), T_cab=r[k["T_cab"]],
                          T_evap=r[k["T_evap"]], T_ain=r[k["T_ain"]], W_bl=W,
                          T_evap_set=Tset, P_comp=r[k["P_comp"]], P_bl=r[k["P_bl"]],
                          slack_cab=r[k["slack_cab"]], slack_evap=r[k["slack_evap"]],
                          objective=float(r[k["objective"]][0]), status="Solve_Succeeded",
                          success=True, iterations=-1, solve_time_s=dt, disturbance=d.copy())
        st.commit()   # this solution becomes the next step's warm start (no copy)
        inp = st.inputs
        self._w_prev, self._lam_x_prev = inp["w_prev"], inp["lam_x_prev"]
        self._lam_g_prev = inp["lam_g_prev"]
        return sol, None

    def _check_inputs(self, x, ub, lb, Ti, Tsh, amb, eta, d) -> None:
        """Finite, plausible kelvin temperatures and positive efficiencies, or an error."""
        temps = np.concatenate((x, ub[1:], lb[1:], Ti, Tsh, (amb,)))
        lo, hi = T_PLAUSIBLE_K
        if not (lo <= temps.min() and temps.max() <= hi):  # False for NaN too
            for val, name in ((x, "state x = [T_cab, T_evap]"), (ub[1:], "T_cab_max"),
                              (lb[1:], "T_cab_min"), (Ti, "T_int"), (Tsh, "T_shell"),
                              (amb, "T_amb")):
                _check_kelvin(val, name)
        if not (eta.min() > 0 and np.isfinite(eta.max())):
            raise ConfigError(f"eta_cop preview must be positive, got {eta}")
        if d.shape != (_NX,) or not np.isfinite(d.sum()):
            raise DataError(f"disturbance must be 2 finite values (K per step), got {d}")

    def _solution(self, w, x, D, Q, ub, lb, d, status, success, iterations,
                  dt) -> MPCSolution:
        """Eq. 7 at the plan: the trajectory recomputed from the (clipped) plan with the
        declared model, the slacks its actual violations (eqs. 3-5, 7 in W)."""
        cfg = self.config
        plan = np.minimum(np.maximum(self._u_plan(w), self._u_lo), self._u_hi)
        W, Tset = plan[:, 0], plan[:, 1]
        X, Y, terms = self._trajectory(x, plan.T, D.T, Q.T, self._theta, d)
        T_cab, T_evap = X[0], X[1]
        T_ain = Y[self._i_T_ain]
        P_comp, P_bl = terms[self._i_P[0]], terms[self._i_P[1]]
        s_cab = np.maximum(np.maximum(T_cab[1:] - ub[1:], lb[1:] - T_cab[1:]), 0.0)
        s_evap = np.maximum(np.maximum(T_evap[1:] - cfg.T_evap_max,
                                       cfg.T_evap_min - T_evap[1:]), 0.0)
        objective = float(P_comp.sum() + P_bl.sum()
                          + cfg.slack_penalty * (s_cab.sum() + s_evap.sum()))
        return MPCSolution(u=plan[0].copy(), T_cab=T_cab, T_evap=T_evap,
                           T_ain=T_ain, W_bl=W, T_evap_set=Tset, P_comp=P_comp, P_bl=P_bl,
                           slack_cab=s_cab, slack_evap=s_evap, objective=objective,
                           status=status, success=success, iterations=iterations,
                           solve_time_s=dt, disturbance=d.copy())

    # ------------------------------------------------------------ closed loop
    def make_step(self, x, T_cab_max, T_int, T_shell, T_cab_min=None, T_amb=None,
                  eta_cop=None) -> np.ndarray:
        """One closed-loop update: measure ``x``, return the input for ``[t_k, t_k + Ts)``.

        Never raises for a solver failure, a timeout or a non-finite measurement: the
        fallback (rest of the last successful plan, else ``config.u_safe``) is applied and
        counted in ``self.fallbacks``, with a SolverWarning. A finite but implausible
        temperature (e.g. degC where K is expected) raises DataError: that is a wiring
        error, not a sensor drop-out.

        Parameters are those of :meth:`solve` (without ``u_prev``: the controller knows
        the input it applies; without ``disturbance``: the controller estimates it when
        ``config.offset_free``). Returns ``[W_bl kg/s, T_evap_set K]``.
        """
        check_interrupt()  # a Ctrl-C its last solve swallowed stops here
        t0 = time.perf_counter()
        cfg = self.config
        pinned = cfg.first_move == "pinned"
        x = np.asarray(x, dtype=float).reshape(_NX)
        # T_int, T_shell over the first step (eq. 1's v), K
        v = np.array([T_int if isinstance(T_int, float) else np.ravel(T_int)[0],
                      T_shell if isinstance(T_shell, float) else np.ravel(T_shell)[0]],
                     dtype=float)
        sol, d, x_hat = None, np.zeros(_NX), x
        margin = (0.0, 0.0)
        x0, x1, v0, v1 = float(x[0]), float(x[1]), float(v[0]), float(v[1])
        measured = (math.isfinite(x0) and math.isfinite(x1) and math.isfinite(v0)
                    and math.isfinite(v1))
        if not measured:
            status, ok = f"non-finite measurement (x = {x.tolist()}, v = {v.tolist()})", False
        else:
            if not (_T_LO <= x0 <= _T_HI and _T_LO <= x1 <= _T_HI):  # x is finite here
                _check_kelvin(x, "state x = [T_cab, T_evap]")
            if self.estimator is not None:
                u_v = self._applied if self._applied is not None else (None, None)
                x_hat, d = self.estimator.update(x, *u_v)
            ub, lb = T_cab_max, T_cab_min   # None: the config's lower bound
            if self.backoff is not None:
                if self._predicted is not None:
                    self.backoff.update(self._predicted, x[0])
                margin = (self.backoff.upper, self.backoff.lower)
                lb = cfg.T_cab_min if lb is None else lb
                ub, lb = np.asarray(ub, float) - margin[0], np.asarray(lb, float) + margin[1]
            try:
                sol = self.solve(x_hat, ub, T_int, T_shell,
                                 u_prev=self._committed if pinned else None,
                                 T_cab_min=lb, T_amb=T_amb, eta_cop=eta_cop,
                                 disturbance=d)
                ok = sol.success
                status = sol.status
            except DataError as exc:  # a non-finite preview: no solve, fall back
                status, ok = str(exc), False
            except (RuntimeError, ValueError, FloatingPointError) as exc:  # CasADi errors
                status, ok = f"error: {str(exc).splitlines()[0][:120]}", False
        if ok:
            self._plan, self._plan_age = sol, 0   # its plan is read only on a fallback
            if pinned:
                u, self._committed = self._committed.copy(), sol.plan[1].copy()
            else:
                u = sol.u.copy()
        else:
            u = self._fallback(status, pinned)
        u = np.minimum(np.maximum(u, self._u_lo), self._u_hi)
        self._applied = (u, v) if measured else None
        # the model's T_cab one step ahead under the applied input (for the back-off)
        self._predicted = (predict(x_hat[0], x_hat[1], u[0], u[1], v[0], v[1], d, self.params,
                                   cfg.disturbance)[0]
                           if measured and self.backoff is not None else None)
        self.log.u.append(u)
        self.log.solutions.append(sol)
        self.log.fallback.append(not ok)
        self.log.disturbance.append(d)
        self.log.margin.append(margin)
        self.log.step_time_s.append(time.perf_counter() - t0)
        return u

    def _fallback(self, status: str, pinned: bool) -> np.ndarray:
        """The input when the solve failed: the shifted last plan, else ``u_safe``."""
        self.fallbacks += 1
        check_interrupt()  # the failure was the interrupt: say only that
        warnings.warn(f"NMPC solve failed ({status}); fallback applied", SolverWarning,
                      stacklevel=3)
        self._w_prev = self._lam_g_prev = self._lam_x_prev = None  # cold start next
        nxt = self._plan_age + 1 + (1 if pinned else 0)
        if self._plan is not None and nxt < self.N:
            fallback_u = self._plan.plan[nxt].copy()
            self._plan_age += 1
        else:
            fallback_u = self.config.u_safe.copy()
        if pinned:
            u, self._committed = self._committed.copy(), fallback_u
            return u
        return fallback_u


# ------------------------------------------------------------------------- helpers
def sqp_options(tol: float = SQP_TOL, max_iter: int = 100) -> dict:
    """Options of the SQP method (sqpmethod with the active-set QP solver qrqp, exact
    Hessian): the NMPC's ``solver="sqp"`` and the solver of ``acid export-c``.

    The Hessian of eq. 7's Lagrangian is indefinite (paper: "C is symmetric and
    indefinite"), but the reduced Hessian at the solutions is positive, and the exact
    Hessian keeps the quadratic convergence (about 5 iterations from a cold start). On
    nearly degenerate active sets qrqp can stall ("lbz violated with zero step"); ``min_lam``
    and a cap of 50 QP iterations keep it from cycling for its default 1000 (the SQP step
    that follows recovers). An active-set method meets active bounds exactly.
    """
    return {"qpsol": "qrqp", "print_time": False, "print_header": False,
            "print_iteration": False, "print_status": False, "max_iter": max_iter,
            "tol_pr": tol, "tol_du": tol,
            "qpsol_options": {"print_iter": False, "print_header": False,
                              "print_info": False, "error_on_fail": False,
                              "min_lam": 1e-12, "max_iter": 50}}
