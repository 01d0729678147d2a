"""Nonlinear MPC of the A/C system (paper eqs. 7-13, Table II), solved with CasADi.

The optimal control problem solved at every update k (kelvin, kg/s, W, s inside):

.. math::

    \\min_{U, v_{sl}} \\sum_{i=0}^{N_p} P_c(i|k) + P_{bl}(i|k)
        + \\sum_{i=1}^{N_c} a_{sl}^\\top v_{sl}(i|k)                          \\quad (7)

subject to the control-oriented model, eqs. 1-3 (paper eqs. 8-9, built from the functions
of :mod:`acid.model`: one source of truth), the state bounds relaxed by non-negative slacks
``x_min(i) - v_sl(i) <= x(i|k) <= x_max(i) + v_sl(i)`` (eqs. 10-12, one slack per state and
stage, penalty ``a_sl = 1e5`` W/K each), the input bounds (eq. 12) and ``x(0|k) = x(k)``
(eq. 13). Powers are eqs. 4-5 with ``T_ain`` from eq. 3.

Choices the paper leaves open, documented here
------------------------------------------------
* **Horizons.** ``Np = Nc = Nu = N`` (Table II: 6, ``Ts = 5 s``). The inputs are
  ``u(0|k) .. u(N-1|k)``; the cost term at ``i = N`` (eq. 7 sums to ``Np``) uses the predicted
  terminal state with the last input held, ``u(N|k) := u(N-1|k)``.
* **Slacks.** ``x(0|k)`` is fixed by eq. 13, so its slack would only add a constant to the
  objective; slacks are defined for ``i = 1 .. N`` (the states the inputs can influence).
* **Eq. 4 sign.** ``P_c = c_p / eta_cop * W_bl * (T_amb - T_ain)`` is used as published. It
  turns negative if ``T_ain > T_amb`` (never within Table II's bounds with the paper's
  parameters: ``T_ain`` stays below 21 degC), so the optimiser cannot profit from it there.
* **Eq. 4 efficiency per stage.** ``eta_cop`` enters the NLP as a parameter per stage
  ``i = 0 .. N`` (default ``params.eta_cop`` everywhere: the paper's model); ``solve`` and
  ``make_step`` accept an ``eta_cop`` preview, used by the speed-aware controller of
  :mod:`acid.mpc.speed_model` (beyond the paper, whose assumption 3 leaves speed out).
* **Eq. 13, ``u(0|k) = u(k)``**, is ambiguous; both readings are supported
  (``NMPCConfig.first_move``):

  - ``"free"`` (default): ``u(0|k)`` is a decision variable and is the input applied over
    ``[t_k, t_k + Ts)``; eq. 13 merely names it. This is the usual receding-horizon MPC and
    it reacts to the measurement within the same sample.
  - ``"pinned"``: ``u(0|k)`` is fixed to the input already being applied over
    ``[t_k, t_k + Ts)`` (committed at the previous update), as in a controller whose
    computation takes up to one period; the solver chooses ``u(1|k) ..`` and ``u(1|k)`` is
    committed for the next period. ``make_step`` keeps the committed input.

Solver
------
The NLP is built once, variables ordered stage by stage ``[x_0, u_0, s_1, x_1, u_1, s_2, ...,
x_N]`` so that CasADi's structure-exploiting interior-point solver **fatrop** (shipped in the
casadi wheel) detects the optimal-control structure (``structure_detection='auto'``); IPOPT
solves the identical NLP (``solver="ipopt"``). Exact derivatives (CasADi AD) in both. Each
solve is warm-started from the previous solution shifted by one stage (primal; the shifted
multipliers are passed too, IPOPT ignores them with its default cold dual start). Measured
on the scenario (a) states (``benchmarks/bench_mpc.py``): fatrop about 1 ms per whole step,
IPOPT about 5-6 ms, the same optimum to 3e-6.
Time-varying bounds enter as numeric ``lbg``/``ubg``, the initial state and disturbances
(``T_int``, ``T_shell``, ``T_amb``) as NLP parameters, so nothing is rebuilt between solves.

If the solver fails (or raises), ``make_step`` applies a safe fallback -- the rest of the last
successful plan, shifted, else a conservative input (maximum cooling) -- counts it in
``NMPC.fallbacks``, emits a :class:`acid.errors.SolverWarning` and carries on.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from acid import model
from acid.errors import ConfigError, SolverWarning
from acid.params import ModelParams
from acid.units import C2K

#: Variables per stage: x = [T_cab, T_evap], u = [W_bl, T_evap_set], s = [v_sl,cab, v_sl,evap]
_NX, _NU, _NS = 2, 2, 2
_NW = _NX + _NU + _NS
#: Constraints per stage: 2 dynamics (eqs. 1-2) + 4 slack-relaxed state bounds (eqs. 10-11)
_NG = 6


@dataclass(frozen=True)
class NMPCConfig:
    """Options of the NMPC (Table II defaults; temperatures in K).

    Attributes
    ----------
    N : prediction = constraint = control horizon ``Np = Nc = Nu`` (Table II: 6 steps).
    first_move : ``"free"`` (default) or ``"pinned"``, the two readings of eq. 13.
    solver : ``"fatrop"`` (default, structure-exploiting) or ``"ipopt"``.
    slack_penalty : ``a_sl``, W per K of violation, per state (paper: 1e5).
    T_amb : ambient temperature in eq. 4, K (Table II: 30 degC).
    T_cab_min : lower cabin bound, K (Table II: 20 degC); the upper bound is previewed.
    T_evap_min, T_evap_max : evaporator wall bounds, K (Table II: 0 and 12 degC).
    W_bl_min, W_bl_max : blower air flow bounds, kg/s (Table II: 0.05, 0.15).
    T_evap_set_min, T_evap_set_max : set-point bounds, K (Table II: 3, 10 degC).
    tol : solver convergence tolerance (on the objective scaled by ``cost_scale``).
    max_iter : iteration limit of the solver.
    cost_scale : factor applied to the objective inside the NLP (kW instead of W) for
        conditioning; reported objectives are unscaled (W summed over the stages).
    fallback_input : conservative input (W_bl kg/s, T_evap_set K) when no plan is left:
        maximum cooling, by default.
    """

    N: int = 6
    first_move: str = "free"
    solver: str = "fatrop"
    slack_penalty: float = 1e5
    T_amb: float = C2K(30.0)
    T_cab_min: float = C2K(20.0)
    T_evap_min: float = C2K(0.0)
    T_evap_max: float = C2K(12.0)
    W_bl_min: float = 0.05
    W_bl_max: float = 0.15
    T_evap_set_min: float = C2K(3.0)
    T_evap_set_max: float = C2K(10.0)
    tol: float = 1e-8
    max_iter: int = 200
    cost_scale: float = 1e-3
    fallback_input: tuple[float, float] | None = None

    def __post_init__(self):
        if self.first_move not in ("free", "pinned"):
            raise ConfigError(f"first_move must be 'free' or 'pinned', got {self.first_move!r}")
        if self.solver not in ("fatrop", "ipopt"):
            raise ConfigError(f"solver must be 'fatrop' or 'ipopt', got {self.solver!r}")
        if int(self.N) < 2:
            raise ConfigError(f"horizon N must be at least 2, got {self.N}")
        if not (self.W_bl_min < self.W_bl_max and self.T_evap_set_min < self.T_evap_set_max):
            raise ConfigError("input bounds must satisfy min < max")

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
            "slack_penalty_W_per_K": self.slack_penalty, "T_amb_K": self.T_amb,
            "T_cab_min_K": self.T_cab_min, "T_evap_min_K": self.T_evap_min,
            "T_evap_max_K": self.T_evap_max, "W_bl_min_kg_s": self.W_bl_min,
            "W_bl_max_kg_s": self.W_bl_max, "T_evap_set_min_K": self.T_evap_set_min,
            "T_evap_set_max_K": self.T_evap_set_max, "tol": self.tol,
            "max_iter": self.max_iter, "fallback_input": self.u_safe.tolist(),
        }


@dataclass(frozen=True)
class MPCSolution:
    """One NMPC solve: the first move and the whole predicted trajectory.

    Attributes
    ----------
    u : (2,) the input to apply over ``[t_k, t_k + Ts)`` -- [W_bl kg/s, T_evap_set K]. In
        ``"free"`` mode ``u(0|k)``; in ``"pinned"`` mode the pinned ``u(0|k)`` as well (the
        move the solve decided is ``W_bl[1], T_evap_set[1]``).
    T_cab, T_evap : (N+1,) predicted states x(0|k) .. x(N|k), K.
    T_ain : (N+1,) predicted inlet air (eq. 3), K, with ``u(N|k) = u(N-1|k)``.
    W_bl, T_evap_set : (N,) planned inputs u(0|k) .. u(N-1|k), kg/s and K.
    P_comp, P_bl : (N+1,) predicted powers (eqs. 4-5), W.
    slack_cab, slack_evap : (N,) slacks v_sl(1|k) .. v_sl(N|k), K (clipped at 0).
    objective : eq. 7 at the solution, W (powers summed over i = 0..N plus a_sl * slacks).
    status : solver return status (text).
    success : whether the solver reported convergence and the solution is finite.
    iterations : solver iterations.
    solve_time_s : wall time of the solver call, s.
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
    solutions : the MPC solutions (``None`` where the solver raised).
    fallback : whether each step used the fallback.
    step_time_s : wall time of each whole ``make_step`` call (Python overhead included), s.
    """

    u: list = field(default_factory=list)
    solutions: list = field(default_factory=list)
    fallback: list = field(default_factory=list)
    step_time_s: list = field(default_factory=list)


class NMPC:
    """The paper's NMPC (eqs. 7-13) on the control-oriented model.

    Parameters
    ----------
    params : model parameters (eqs. 1-5, kelvin convention), e.g. from ``load_params``.
    config : options (Table II defaults).

    Notes
    -----
    ``solve`` is stateless apart from the warm start; ``make_step`` is the closed-loop
    interface (do-mpc style ``u = mpc.make_step(x, ...)``), which handles the pinned first
    move, the fallback and the log. Build once, call many times.
    """

    def __init__(self, params: ModelParams, config: NMPCConfig | None = None):
        from acid.params import as_params

        self.params = as_params(params)  # ModelParams or a FitResult
        self.config = config or NMPCConfig()
        self.N = int(self.config.N)
        self._build()
        self.reset()

    # ----------------------------------------------------------------- build
    def _build(self) -> None:
        """Build the NLP once: symbols, cost (eq. 7) and constraints (eqs. 8-13)."""
        cfg, p, N = self.config, self.params, self.N
        x0 = ca.SX.sym("x0", _NX)
        T_int = ca.SX.sym("T_int", N)
        T_shell = ca.SX.sym("T_shell", N)
        T_amb = ca.SX.sym("T_amb")
        # per-stage eta_cop of eq. 4 (default p.eta_cop at every stage; a speed-aware
        # controller previews eta_cop(v(i|k)), see acid.mpc.speed_model)
        eta = ca.SX.sym("eta_cop", N + 1)
        X = [ca.SX.sym(f"x_{i}", _NX) for i in range(N + 1)]
        U = [ca.SX.sym(f"u_{i}", _NU) for i in range(N)]
        S = [ca.SX.sym(f"s_{i + 1}", _NS) for i in range(N)]

        def power(W_bl, T_ain, i):  # eqs. 4-5, W, with the stage-i eta_cop
            return p.c_p / eta[i] * W_bl * (T_amb - T_ain) + model.blower_power(W_bl, p)

        w, g, eq, cost = [], [], [], 0
        for i in range(N):
            T_cab, T_evap = X[i][0], X[i][1]
            W_bl, T_set = U[i][0], U[i][1]
            w += [X[i], U[i], S[i]]
            if i == 0:  # eq. 13: x(0|k) = x(k)
                g.append(X[0] - x0)
                eq += [True] * _NX
            T_cab_n, T_evap_n, T_ain = model.step(T_cab, T_evap, W_bl, T_set, T_int[i],
                                                  T_shell[i], p)  # eqs. 1-3
            cost += power(W_bl, T_ain, i) + cfg.slack_penalty * (S[i][0] + S[i][1])
            if i == N - 1:  # stage i = N of eq. 7, with u(N|k) := u(N-1|k)
                cost += power(W_bl, model.inlet_air(T_evap_n, W_bl, p), N)
            # dynamics (eqs. 8-9) as gap constraints x(i+1) - f(x(i), u(i)) = 0
            g.append(X[i + 1] - ca.vertcat(T_cab_n, T_evap_n))
            eq += [True] * _NX
            # eqs. 10-11 for x(i+1|k), written with stage-i variables (keeps the OCP structure):
            # T - s <= T_max and T + s >= T_min, the bounds themselves go into ubg / lbg
            g.append(ca.vertcat(T_cab_n - S[i][0], T_cab_n + S[i][0],
                                T_evap_n - S[i][1], T_evap_n + S[i][1]))
            eq += [False] * 4
        w.append(X[N])
        w = ca.vertcat(*w)
        g = ca.vertcat(*g)
        par = ca.vertcat(x0, T_int, T_shell, T_amb, eta)
        nlp = {"x": w, "f": cost * cfg.cost_scale, "g": g, "p": par}
        if cfg.solver == "fatrop":
            opts = {"structure_detection": "auto", "equality": eq, "print_time": False,
                    "fatrop": {"print_level": 0, "tol": cfg.tol, "max_iter": int(cfg.max_iter)}}
        else:
            opts = {"print_time": False,
                    "ipopt": {"print_level": 0, "sb": "yes", "tol": cfg.tol,
                              "max_iter": int(cfg.max_iter)}}
        self._solver = ca.nlpsol("acid_nmpc", cfg.solver, nlp, opts)
        self._n_w = int(w.shape[0])
        self._n_g = int(g.shape[0])

        # index maps into w and g
        base = np.arange(N) * _NW
        self._iT_cab = np.r_[base, N * _NW]
        self._iT_evap = self._iT_cab + 1
        self._iW = base + 2
        self._iTset = base + 3
        self._is_cab = base + 4
        self._is_evap = base + 5
        gbase = _NX + np.arange(N) * _NG
        self._ig_cab_hi = gbase + 2
        self._ig_cab_lo = gbase + 3
        self._ig_evap_hi = gbase + 4
        self._ig_evap_lo = gbase + 5

        # constant bound vectors, copied and filled per solve
        inf = np.inf
        lbx = np.full(self._n_w, -inf)
        ubx = np.full(self._n_w, inf)
        lbx[self._iW], ubx[self._iW] = cfg.W_bl_min, cfg.W_bl_max
        lbx[self._iTset], ubx[self._iTset] = cfg.T_evap_set_min, cfg.T_evap_set_max
        lbx[self._is_cab] = 0.0
        lbx[self._is_evap] = 0.0
        self._lbx0, self._ubx0 = lbx, ubx
        lbg = np.zeros(self._n_g)
        ubg = np.zeros(self._n_g)
        lbg[self._ig_cab_hi] = -inf
        ubg[self._ig_cab_lo] = inf
        lbg[self._ig_evap_hi] = -inf
        ubg[self._ig_evap_lo] = inf
        ubg[self._ig_evap_hi] = cfg.T_evap_max
        lbg[self._ig_evap_lo] = cfg.T_evap_min
        self._lbg0, self._ubg0 = lbg, ubg

    # ----------------------------------------------------------------- state
    def reset(self, u_initial=None) -> None:
        """Forget the warm start, the plan, the log and the fallback count.

        ``u_initial`` (W_bl kg/s, T_evap_set K) is the input applied over the first period in
        ``"pinned"`` mode (default: the conservative input).
        """
        self._w_prev = None
        self._lam_g_prev = None
        self._lam_x_prev = None
        self._plan = None  # (N, 2) last successful plan
        self._plan_age = 0
        self._committed = (np.array(u_initial, dtype=float) if u_initial is not None
                           else self.config.u_safe.copy())
        self.fallbacks = 0
        self.log = StepLog()

    # ----------------------------------------------------------------- solve
    def _preview(self, value, n: int, name: str) -> np.ndarray:
        a = np.asarray(value, dtype=float)
        if a.ndim == 0:
            return np.full(n, float(a))
        if a.shape[0] < n:
            raise ConfigError(f"{name}: preview needs {n} values, got {a.shape[0]}")
        return a[:n]

    def _initial_guess(self, x: np.ndarray, T_int: np.ndarray, T_shell: np.ndarray,
                       u_prev) -> np.ndarray:
        """Shifted previous solution, else a forward simulation with a mid-range input."""
        N = self.N
        if self._w_prev is not None:
            w = np.empty(self._n_w)
            w[: (N - 1) * _NW] = self._w_prev[_NW: N * _NW]
            w[(N - 1) * _NW: N * _NW] = self._w_prev[(N - 1) * _NW: N * _NW]
            w[(N - 1) * _NW: (N - 1) * _NW + _NX] = self._w_prev[N * _NW:]
            w[N * _NW:] = self._w_prev[N * _NW:]
            w[:_NX] = x
            return w
        cfg = self.config
        u = (np.clip(np.asarray(u_prev, dtype=float), cfg.u_min, cfg.u_max)
             if u_prev is not None else 0.5 * (cfg.u_min + cfg.u_max))
        T_cab, T_evap, _ = model.simulate(x, np.full(N, u[0]), np.full(N, u[1]), T_int,
                                          T_shell, self.params)
        w = np.zeros(self._n_w)
        w[self._iT_cab], w[self._iT_evap] = T_cab, T_evap
        w[self._iW], w[self._iTset] = u[0], u[1]
        return w

    def _shift_duals(self, lam: np.ndarray, head: int, n_total: int, stride: int) -> np.ndarray:
        out = lam.copy()
        N = self.N
        out[head: head + (N - 1) * stride] = lam[head + stride: head + N * stride]
        return out[:n_total]

    def solve(self, x, T_cab_max, T_int, T_shell, u_prev=None, T_cab_min=None,
              T_amb=None, eta_cop=None) -> MPCSolution:
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

        Returns
        -------
        MPCSolution (``success`` False when the solver failed; nothing is raised for a
        solver failure, but a CasADi evaluation error propagates as ``RuntimeError``).
        """
        cfg, N = self.config, self.N
        x = np.asarray(x, dtype=float).reshape(_NX)
        ub = self._preview(T_cab_max, N + 1, "T_cab_max")
        lb = self._preview(cfg.T_cab_min if T_cab_min is None else T_cab_min, N + 1,
                           "T_cab_min")
        Ti = self._preview(T_int, N, "T_int")
        Tsh = self._preview(T_shell, N, "T_shell")
        amb = cfg.T_amb if T_amb is None else float(T_amb)
        eta = self._preview(self.params.eta_cop if eta_cop is None else eta_cop, N + 1,
                            "eta_cop")
        if not np.all(eta > 0):
            raise ConfigError(f"eta_cop preview must be positive, got {eta}")
        lbx, ubx = self._lbx0, self._ubx0
        if cfg.first_move == "pinned":
            lbx, ubx = lbx.copy(), ubx.copy()
            if u_prev is None:
                raise ConfigError("first_move='pinned' needs u_prev, the input being applied")
            u0 = np.clip(np.asarray(u_prev, dtype=float), cfg.u_min, cfg.u_max)
            lbx[[2, 3]] = u0
            ubx[[2, 3]] = u0
        lbg, ubg = self._lbg0.copy(), self._ubg0.copy()
        ubg[self._ig_cab_hi] = ub[1:]
        lbg[self._ig_cab_lo] = lb[1:]
        w0 = self._initial_guess(x, Ti, Tsh, u_prev)
        args = {"x0": w0, "lbx": lbx, "ubx": ubx, "lbg": lbg, "ubg": ubg,
                "p": np.concatenate((x, Ti, Tsh, [amb], eta))}
        if self._lam_g_prev is not None:
            args["lam_g0"] = self._shift_duals(self._lam_g_prev, _NX, self._n_g, _NG)
            args["lam_x0"] = self._shift_duals(self._lam_x_prev, 0, self._n_w, _NW)
        t0 = time.perf_counter()
        res = self._solver(**args)
        dt = time.perf_counter() - t0
        stats = self._solver.stats()
        w = np.asarray(res["x"]).ravel()
        finite = bool(np.all(np.isfinite(w)))
        success = bool(stats.get("success", False)) and finite
        if success:
            self._w_prev = w
            self._lam_g_prev = np.asarray(res["lam_g"]).ravel()
            self._lam_x_prev = np.asarray(res["lam_x"]).ravel()
        return self._solution(w, amb, str(stats.get("return_status", "")), success,
                              int(stats.get("iter_count", -1)), dt, eta)

    def _solution(self, w, T_amb, status, success, iterations, dt, eta=None) -> MPCSolution:
        """Unpack the NLP vector and evaluate the cost terms (eqs. 3-5, 7) in W."""
        cfg, p = self.config, self.params
        W = np.clip(w[self._iW], cfg.W_bl_min, cfg.W_bl_max)
        Tset = np.clip(w[self._iTset], cfg.T_evap_set_min, cfg.T_evap_set_max)
        T_cab, T_evap = w[self._iT_cab], w[self._iT_evap]
        W_ext = np.append(W, W[-1])  # u(N|k) := u(N-1|k)
        T_ain = model.inlet_air(T_evap, W_ext, p)
        if eta is None:
            P_comp = model.compressor_power(W_ext, T_ain, T_amb, p)
        else:
            P_comp = p.c_p / np.asarray(eta, dtype=float) * W_ext * (T_amb - T_ain)
        P_bl = model.blower_power(W_ext, p)
        s_cab = np.maximum(w[self._is_cab], 0.0)
        s_evap = np.maximum(w[self._is_evap], 0.0)
        objective = float(np.sum(P_comp + P_bl) + cfg.slack_penalty * np.sum(s_cab + s_evap))
        return MPCSolution(u=np.array([W[0], Tset[0]]), T_cab=T_cab, T_evap=T_evap,
                           T_ain=T_ain, W_bl=W, T_evap_set=Tset, P_comp=P_comp, P_bl=P_bl,
                           slack_cab=s_cab, slack_evap=s_evap, objective=objective,
                           status=status, success=success, iterations=iterations,
                           solve_time_s=dt)

    # ------------------------------------------------------------ closed loop
    def make_step(self, x, T_cab_max, T_int, T_shell, T_cab_min=None, T_amb=None,
                  eta_cop=None) -> np.ndarray:
        """One closed-loop update: measure ``x``, return the input for ``[t_k, t_k + Ts)``.

        Never raises for a solver failure: the fallback (rest of the last successful plan,
        else ``config.u_safe``) is applied and counted in ``self.fallbacks``.

        Parameters are those of :meth:`solve` (without ``u_prev``: the controller knows
        the input it applies). Returns ``[W_bl kg/s, T_evap_set K]``.
        """
        t0 = time.perf_counter()
        cfg = self.config
        pinned = cfg.first_move == "pinned"
        sol = None
        try:
            sol = self.solve(x, T_cab_max, T_int, T_shell,
                             u_prev=self._committed if pinned else None,
                             T_cab_min=T_cab_min, T_amb=T_amb, eta_cop=eta_cop)
            ok = sol.success
        except (RuntimeError, ValueError, FloatingPointError) as exc:  # CasADi eval errors
            status = f"error: {str(exc).splitlines()[0][:120]}"
            ok = False
        else:
            status = sol.status
        if ok:
            self._plan, self._plan_age = sol.plan, 0
            if pinned:
                u, self._committed = self._committed.copy(), sol.plan[1].copy()
            else:
                u = sol.u.copy()
        else:
            self.fallbacks += 1
            warnings.warn(f"NMPC solve failed ({status}); fallback applied", SolverWarning,
                          stacklevel=2)
            self._w_prev = self._lam_g_prev = self._lam_x_prev = None  # cold start next
            nxt = self._plan_age + 1 + (1 if pinned else 0)
            if self._plan is not None and nxt < self.N:
                fallback_u = self._plan[nxt].copy()
                self._plan_age += 1
            else:
                fallback_u = cfg.u_safe.copy()
            if pinned:
                u, self._committed = self._committed.copy(), fallback_u
            else:
                u = fallback_u
        u = np.clip(u, cfg.u_min, cfg.u_max)
        self.log.u.append(u)
        self.log.solutions.append(sol)
        self.log.fallback.append(not ok)
        self.log.step_time_s.append(time.perf_counter() - t0)
        return u
