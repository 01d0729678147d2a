"""Economic NMPC on the identified econ model (beyond the paper).

At every update k it solves, on the econ declaration :mod:`acid.models.econ` (the equations the
fit used), over a horizon of intervals ``dt_0 .. dt_{N-1}`` (default 24 x 5 s = 120 s; a
non-uniform grid such as 6 x 5 s + 3 x 10 s + 4 x 15 s is allowed, the model being
continuous-time)::

    min  sum_i dt_i (P_comp(i) + P_bl(i) + a_sl |s_i|_1)  +  lam^T (x_N - x_0)
    s.t. x_{i+1} = F_dt_i(x_i, u_i, d_i, dist)           RK4 interval map of the model
         T_cab_min(i) - s_lo <= T_cab(i+1) <= T_cab_max(i) + s_hi       comfort band
         Q_e(i) >= -s_q                                  no negative refrigerant heat
         w_cab(i+1) <= w(T_cab(i+1), RH_max) + s_rh      optional humidity bound
         u_min <= u_i <= u_max,  s_i >= 0,  x_0 = x(k)

``P_comp = Q_e f(Q_e, T_evap, v, T_amb)`` is the identified power map, ``P_bl`` paper eq. 5,
used where its data were: a previewed speed or ambient outside them, or a plan whose cooling
load or evaporator temperature leaves them (a hot pull-down beyond the loads the excitation
reached), raises an :class:`acid.errors.ExtrapolationWarning` (once per input and reset;
``extrapolation`` lists them) -- the map's data range is not a capacity limit, so the plan
is not cut to it.
``d_i = (v_i, T_amb_i)`` the previewed vehicle speed and ambient (interval means; with
``preview=False`` both are held at their current values: controller D of the study), ``dist``
additive disturbances on the state equations (zero unless an estimator feeds them).

**Terminal cost.** A 120 s horizon is short against the interior and shell (time constants
of several minutes), so what the plan leaves in the states at its end is priced linearly,
``lam`` J per unit state (K, kg/kg), recomputed every update (``terminal``):

* ``"heat"``: ``lam = pi dH/dx``, ``H`` the model's heat content
  (:func:`acid.models.econ.heat_content`) and ``pi`` the marginal electric energy per joule of
  cooling, ``dP_comp/dQ_e`` of the power map at the current operating point;
* ``"steady"`` (default): the multipliers of the model's optimal steady state at the horizon's
  mean speed and ambient (the economic-MPC terminal cost of the rotated-cost literature,
  :mod:`acid.control.econ.terminal`): each state priced at what the best steady operation pays
  for one unit more of it (D: the current speed, held; E: the previewed speeds' mean, a
  steadier estimate of the speeds after the horizon than its last interval's);
* ``"none"``: no terminal cost.

**One builder.** The NLP is this configuration (:func:`ocp_spec`) of the optimal-control
builder :class:`acid.control.ocp.OCP` over the econ declaration ``acid.models.econ.model``
(parameters by name in its table; :func:`econ_interval` the declaration's interval map for
any interval length, with the refrigerant heat and the derivative disturbances): the energy
stage cost, the band, ``Q_e >= 0`` and the humidity bound as soft bounds, the terminal
price; the paper's NMPC is another configuration of the same builder. First moves equal
those of the hand-written builder it replaced to about 1e-11
(``tests/test_control_ocp.py``).

**Solver.** By default (``solver="sqp"``) SQP with the active-set QP solver qrqp,
warm-started from the previous plan and multipliers shifted by one interval (about 3
iterations a step against 15-25 for fatrop), each result checked for convergence. A solve
the exact-Hessian SQP does not converge is finished by the same SQP on a convexified Hessian
(``sqp_rescue``, ``SQP_RESCUE``: per-block eigenvalues clipped, every QP convex; about 30
iterations, generated C too), from the same guess and multipliers, and only then by
``fallback_solver`` (IPOPT inside CasADi), after which SQP starts again from the primal plan
with zero multipliers. The failures are not NaNs: the exact Hessian is indefinite, so the
QPs are nonconvex and qrqp cycles on a bound or the steps jump between bounds; measured on
a UDDS replay on an identified model (274 states), 28 of 274 solves went to IPOPT before
the rescue, none after (8 rescued), every first move within 7.1e-6 of IPOPT's at 1e-10.
Measured (``benchmarks/bench_econ_nmpc.py``, the same replay,
quiet 2-core machine): median step 1.77 ms as generated C against IPOPT's 32 ms;
compiled and CasADi moves identical; moves within 1e-6 of IPOPT's at 1e-10
(``tests/test_control_econ_nmpc.py``). ``stage_functions=True`` (default) builds the NLP from one
function per stage called over the horizon, differentiated only by the decision variables:
its SQP compiles in 10 CPU-s at -O2 (it runs every step: ``hot``) against 32 at -O1 and
154 at -O2 inlined, and steps 1.2x faster than inlined (``benchmarks/bench_compile.py``).
``solver="fatrop"`` (the previous default) or ``"ipopt"``
solve the same NLP. The NLP is built once through
:func:`_make_solver`, which hands it to
:class:`acid.control.codegen.solver.NLPSolver`: generated C compiled at first use and
cached per user when a C compiler works (``compiled="auto"``; CasADi otherwise, the same algorithm),
with a wall-clock cap per solve only when ``max_solve_s`` asks for one. The identified
parameters are NLP *parameters* (the declaration's vector,
``EconParams.theta_all``), so one compiled
solver serves every parameter set
of the same horizon and options. Variables are ordered stage by stage ``[x_0, u_0, s_0, x_1,
...., x_N]`` and constraints per stage so that **fatrop** detects the optimal-control
structure; IPOPT solves the identical NLP. Warm start from the previous solution shifted by
one sample (interpolated on a non-uniform grid). The same fallback as
:class:`acid.control.nmpc.NMPC`: on a failed or timed-out solve, the rest of the last plan, else
maximum cooling, counted in ``fallbacks`` with a :class:`acid.errors.SolverWarning`.

In closed loop it applies ``W_bl`` and ``T_evap_set`` of the first interval: the plant's own
inputs. Temperatures in K, powers in W, energies in J.
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from acid.control.codegen.build import CodegenError
from acid.control.codegen.solver import NLPResult, NLPSolver, StepSolver, step_function
from acid.control.econ.problem import (  # noqa: F401 (the problem's names, read from here too)
    ECON_ESTIMATOR,
    ECON_SOLVERS,
    INTERVAL_OUTPUTS,
    SQP_MAX_ITER,
    SQP_RESCUE,
    TERMINALS,
    U_OFFSET,
    U_SCALE,
    X_OFFSET,
    X_SCALE,
    EconNMPCConfig,
    at_parameters,
    comfort_stage_cost,
    econ_interval,
    econ_stage_cost,
    ocp_spec,
    stage_means,
)
from acid.control.econ.terminal import SteadyStatePrice
from acid.control.estimator import OffsetFreeEstimator
from acid.control.nmpc import SQP_ACCEPT, SQP_TOL, sqp_options
from acid.control.ocp import OCP
from acid.errors import ConfigError, ExtrapolationWarning, SolverWarning
from acid.executor import check_interrupt
from acid.models import econ
from acid.models.econ import model as ECON_MODEL
from acid.models.econ_params import EconParams

_NX, _NU, _ND = ECON_MODEL.nx, ECON_MODEL.nu, ECON_MODEL.nd


def _per_interval(value, N: int) -> np.ndarray:
    """``value`` (a scalar or (N,) values) as (N,) floats (read-only when broadcast)."""
    a = np.asarray(value, dtype=float)
    return a if a.shape == (N,) else np.broadcast_to(a, (N,))


def _make_solver(nlp: dict, equality, config: EconNMPCConfig, solver: str,
                 after_sqp: bool = False) -> NLPSolver:
    """The one place the NLP becomes a solver: :class:`acid.control.codegen.solver.NLPSolver`
    (generated, compiled C when ``config.compiled`` allows and a compiler works, else CasADi; IPOPT
    always inside CasADi; a wall-clock cap per solve only when ``config.max_solve_s`` is
    set; SQP results checked for convergence, ``SQP_ACCEPT``).

    ``after_sqp``: IPOPT finishes a solve the SQP failed, so it solves to the SQP's accuracy
    (``SQP_TOL``, IPOPT's acceptable-level stop still applies). The economic cost is flat in
    the moves near its optimum: at IPOPT's ``config.tol`` (1e-6 on its scaled NLP) the
    first moves of the UDDS replay sit up to 9e-4 (relative) from the optimum, while the
    objective agrees to 1e-10; at 1e-10 IPOPT and the SQP agree to 2e-7."""
    if solver == "fatrop":
        plugin, opts = "fatrop", {
            "structure_detection": "auto", "equality": list(map(bool, equality)),
            "print_time": False, "calc_lam_p": False,
            "fatrop": {"print_level": 0, "tol": config.tol, "max_iter": int(config.max_iter),
                       "mu_init": 1e-1}}
    elif solver == "ipopt":
        plugin, opts = "ipopt", {
            "print_time": False, "calc_lam_p": False,
            "ipopt": {"print_level": 0, "sb": "yes",
                      "tol": min(config.tol, SQP_TOL) if after_sqp else config.tol,
                      "max_iter": int(config.max_iter), "bound_relax_factor": 0.0}}
    elif solver == SQP_RESCUE:
        # the Lagrangian's Hessian with its negative (and zero) eigenvalues raised to
        # convexify_margin, block by block: every QP convex, so qrqp neither cycles nor
        # jumps between bounds (the exact-Hessian SQP's failures); linear convergence
        # (about 30 iterations), hence a rescue only; qrqp needs more iterations from
        # zero multipliers (one per slack, to make the QP regular)
        plugin, opts = "sqpmethod", sqp_options(max_iter=min(int(config.max_iter), 100))
        opts["convexify_strategy"] = "eigen-clip"
        opts["qpsol_options"]["max_iter"] = 300
    else:
        # converged solves take 3-14 iterations (UDDS replay); a failing one stalls, so
        # 25 hands it on early
        plugin, opts = "sqpmethod", sqp_options(max_iter=min(int(config.max_iter),
                                                             SQP_MAX_ITER))
    return NLPSolver(f"acid_econ_nmpc{'' if solver == 'fatrop' else '_' + solver}", nlp,
                     plugin, opts, compiled=config.compiled,
                     verify=SQP_ACCEPT if solver in ("sqp", SQP_RESCUE) else None,
                     timeout_s=config.max_solve_s, kkt_name="acid_econ_nmpc_kkt",
                     hot=solver == "sqp")


@dataclass(frozen=True)
class EconSolution:
    """One solve: the first move and the predicted trajectory.

    Attributes
    ----------
    u : (2,) input for the first interval [W_bl kg/s, T_evap_set K].
    x : (N+1, 5) predicted states; t : (N+1,) their times from now, s.
    W_bl, T_evap_set : (N,) planned inputs.
    Q_e, P_comp, P_bl : (N,) interval means, W.
    slack : (N, ns) slacks (>= 0).
    terminal_prices : (5,) the terminal cost's prices, J per unit state (K, kg/kg).
    energy_J : sum dt (P_comp + P_bl) over the horizon, J.
    objective : the NLP objective (unscaled, J).
    status, success, iterations, solve_time_s : solver report.
    """

    u: np.ndarray
    x: np.ndarray
    t: np.ndarray
    W_bl: np.ndarray
    T_evap_set: np.ndarray
    Q_e: np.ndarray
    P_comp: np.ndarray
    P_bl: np.ndarray
    slack: np.ndarray
    terminal_prices: np.ndarray
    energy_J: float
    objective: float
    status: str
    success: bool
    iterations: int
    solve_time_s: float

    @property
    def plan(self) -> np.ndarray:
        """(N, 2) planned inputs."""
        return np.column_stack([self.W_bl, self.T_evap_set])


@dataclass
class EconStepLog:
    """What ``make_step`` did at each update: applied inputs, solutions, fallbacks, times,
    and the disturbances the prediction used (the estimate with ``offset_free``)."""

    u: list = field(default_factory=list)
    disturbance: list = field(default_factory=list)
    solutions: list = field(default_factory=list)
    fallback: list = field(default_factory=list)
    step_time_s: list = field(default_factory=list)


class EconNMPC:
    """Economic NMPC on the econ model (module docstring).

    Parameters
    ----------
    params : identified :class:`acid.models.econ_params.EconParams`.
    config : options.

    Notes
    -----
    Build once, call :meth:`make_step` every sample (do-mpc style); :meth:`solve` is the
    stateless part (apart from the warm start).
    """

    def __init__(self, params: EconParams, config: EconNMPCConfig | None = None):
        self.params = params
        self.config = config or EconNMPCConfig()
        if abs(self.config.intervals[0] - params.Ts) > 1e-9:
            raise ConfigError(f"econ NMPC: the first interval ({self.config.intervals[0]:g} s) "
                              f"must equal the sample time {params.Ts:g} s")
        self.N = self.config.N
        self._t = np.concatenate(([0.0], np.cumsum(self.config.intervals)))
        self._uniform = len(set(self.config.intervals)) == 1
        # the power map (a view rebuilt on each attribute access) and, per input, the range
        # inside which PowerMap.outside has nothing to say (its 2 % margin included)
        self._power_map = params.power_map
        self._map_ok = {}
        for name, (lo, hi) in self._power_map.domain.items():
            tol = max(0.02 * (hi - lo), 0.05)
            self._map_ok[name] = (lo - tol, hi + tol)
        from acid.ident.envelope import Envelope

        self.envelope = Envelope.of(params)   # the identification data's ranges
        self._build()
        self.reset()

    # ------------------------------------------------------------------ build
    def _build(self) -> None:
        """The NLP: this configuration (:func:`ocp_spec`) of the one optimal-control
        builder over the econ declaration."""
        cfg, p, N = self.config, self.params, self.N
        ocp = self._ocp = OCP(ECON_MODEL, ocp_spec(cfg))
        self._theta = ocp.theta(dict(zip(ECON_MODEL.parameter_names, p.theta_all,
                                         strict=True)))
        # the parameters and constants by name (numbers), as the declaration's functions read
        self._s = econ.parameters(p.theta_all)
        self._ns = ocp.ns
        self._stage_values = ocp.stage_values_evaluator(cfg.compiled)
        self._i_E, self._i_Q_e = ocp.term_names.index("E"), ocp.output_names.index("Q_e")
        # the steady terminal price's interval weights (mean speed and ambient)
        self._iv = np.asarray(cfg.intervals, dtype=float)
        self._iv_sum = self._iv.sum()
        self._uniform = len(set(cfg.intervals)) == 1
        # the SQP's step (warm-start shift or cold guess, solve, convergence check, the
        # stages' outputs) as one generated C call when it compiles
        self._step: StepSolver | None = None
        self._build_step()
        self._solver = _make_solver(ocp.nlp, ocp.equality,
                                    cfg if self._step is None else cfg.replace(compiled=False),
                                    cfg.solver)
        self._fallback_nlp: NLPSolver | None = None
        self._rescue_nlp: NLPSolver | None = None
        if cfg.max_solve_s is not None:  # a real-time run builds them now, not mid-run
            self._rescue_solver()
            self._fallback_solver()
        self._n_w = ocp.w.size
        self._ix, self._iu, self._is = ocp.w.index("x"), ocp.w.index("u"), ocp._is
        self._lbx, self._ubx = ocp.lbx, ocp.ubx
        self._lbg0, self._ubg0 = ocp.lbg, ocp.ubg
        self._pvec = ocp.parameters(np.zeros(ocp.par.size), theta=self._theta, bounds={
            ("Q_e", "lo"): np.zeros(N), **({("RH", "hi"): np.zeros(N)}
                                           if cfg.RH_max is not None else {})})
        # terminal price dP_comp/dQ_e at an operating point (CasADi derivative of the map)
        q, te, vv, ta = (ca.SX.sym(n) for n in ("Q_e", "T_evap", "v", "T_amb"))
        P = econ.compressor_power(self._s, q, te, vv, ta)
        self._dPdQ = ca.Function("dPdQ", [q, te, vv, ta], [ca.jacobian(P, q)])
        xs = ca.SX.sym("x", _NX)
        self._dH = ca.Function("dH", [xs, vv], [ca.gradient(
            econ.heat_content(self._s, ca.vertsplit(xs), vv), xs)])
        self._steady = (SteadyStatePrice(p, cfg.u_min, cfg.u_max,
                                         comfort_weight=cfg.comfort_weight)
                        if cfg.terminal == "steady" else None)
        self._steps = {dt: at_parameters(econ_interval(dt), self._theta)
                       for dt in sorted(set(cfg.intervals))}
        self._step0 = self._steps[cfg.intervals[0]]
        self.estimator = None
        if cfg.offset_free:  # f(x, u, v, d) -> x_next: one sample of the model, d = dist
            xs, us, vs, ds = (ca.SX.sym(n, k) for n, k in (("x", _NX), ("u", _NU),
                                                          ("v", _ND), ("d", _NX)))
            f = ca.Function("econ_f", [xs, us, vs, ds], [self._step0(xs, us, vs, ds)[0]])
            self.estimator = OffsetFreeEstimator(f, config=cfg.estimator,
                                                 compiled=cfg.compiled)

    def _build_step(self) -> None:
        """``self._step``: one generated C function per step (SQP, uniform intervals,
        generated C allowed and compiling); None otherwise (the separate calls)."""
        cfg, ocp, N = self.config, self._ocp, self.N
        if cfg.solver != "sqp" or cfg.compiled is False or not self._uniform:
            return
        ip = ocp._ip
        w, p = ca.SX.sym("w", ocp.w.size), ca.SX.sym("p", ocp.par.size)
        ug, x0 = ca.SX.sym("u_guess", _NU), ca.SX.sym("x0", _NX)

        def block(name, rows):
            idx = ip[name]
            return ca.reshape(p[idx.ravel().tolist()], idx.shape[1], rows) if idx.size \
                else ca.SX.zeros(idx.shape[1] if idx.ndim > 1 else 0, rows)

        th, dist = p[ip["theta"].ravel().tolist()], p[ip["dist"].ravel().tolist()]
        D, Q = block("d", N), block("q", N)
        xm = p[ip["x0"].ravel().tolist()]
        ix, iu = ocp.w.index("x"), ocp.w.index("u")
        uc = ca.fmin(ca.fmax(ug, ca.DM(cfg.u_min)), ca.DM(cfg.u_max))
        Xc = ocp.trajectory(xm, ca.repmat(uc, 1, N), D, Q, th, dist)[0]
        wc = ca.SX.zeros(ocp.w.size)
        wc[ix.ravel().tolist()] = ca.vec((Xc - ca.repmat(ca.DM(X_OFFSET), 1, N + 1))
                                         / ca.repmat(ca.DM(X_SCALE), 1, N + 1))
        wc[iu.ravel().tolist()] = ca.repmat((uc - ca.DM(U_OFFSET)) / ca.DM(U_SCALE), N, 1)
        cold = ca.Function("acid_econ_cold", [x0, p, ug], [wc])
        Y, terms = ocp.stage_values(w, p)
        post = ca.Function("acid_econ_post", [w, p], [Y, terms], ["w", "p"], ["Y", "terms"])
        plugin, opts = "sqpmethod", sqp_options(max_iter=min(int(cfg.max_iter), SQP_MAX_ITER))
        fn = step_function("acid_econ_nmpc_step", ocp.nlp, plugin,
                           dict(opts, error_on_fail=True), lbg=ocp.lbg, ubg=ocp.ubg,
                           shift_w=ocp.shift_w, shift_g=ocp.shift_g, ix0=ix[0], cold=cold,
                           post=post)
        try:
            self._step = StepSolver(fn, timeout_s=cfg.max_solve_s)
        except CodegenError:   # the separate calls (the solver notices why)
            self._step = None
            return
        self._step.inputs["lbx"][:] = ocp.lbx
        self._step.inputs["ubx"][:] = ocp.ubx
        self._Y_shape = ocp.stage_values.size_out(0)
        self._terms_shape = ocp.stage_values.size_out(1)

    def _solve_step(self, x, par, u_guess):
        """One call of the fused step: (the result, Y, terms); Y and terms None when the
        solve failed."""
        st = self._step
        t0 = time.perf_counter()
        inp = st.inputs
        warm = self._w_prev is not None
        if warm and self._w_prev is not inp["w_prev"]:   # found by another solver
            lam_g, lam_x = self._lam_prev if self._lam_prev is not None else (0.0, 0.0)
            st.load(self._w_prev, lam_x, lam_g)
        inp["x0"][:] = (x - X_OFFSET) / X_SCALE
        inp["p"][:] = par
        if not warm:
            inp["u_guess"][:] = u_guess
        finished, flag = st.step(warm)
        dt = time.perf_counter() - t0
        if not finished:
            nan = np.full(inp["w_prev"].size, np.nan)
            return NLPResult(x=nan, f=float("nan"), lam_x=nan,
                             lam_g=np.full(inp["lam_g_prev"].size, np.nan), success=False,
                             status="timeout", iterations=-1, solve_time_s=dt), None, None
        o = st.outputs
        pr, du = float(o["pr_inf"][0]), float(o["du_inf"][0])
        tol_pr, tol_du = SQP_ACCEPT
        ok = not flag and pr <= tol_pr and du <= tol_du and bool(np.isfinite(o["w"].sum()))
        if not ok:
            status = (f"failed (code {flag})" if flag else
                      f"not converged (primal {pr:.1e}, dual {du:.1e}; Solve_Succeeded)")
            return NLPResult(x=o["w"].copy(), f=float(o["f"][0]), lam_x=o["lam_x"].copy(),
                             lam_g=o["lam_g"].copy(), success=False, status=status,
                             iterations=-1, solve_time_s=dt), None, None
        f = float(o["f"][0])
        Y = o["Y"].reshape(self._Y_shape, order="F").copy()
        terms = o["terms"].reshape(self._terms_shape, order="F").copy()
        st.commit()   # this solution becomes the next step's warm start (no copy)
        inp = st.inputs
        return NLPResult(x=inp["w_prev"], f=f, lam_x=inp["lam_x_prev"],
                         lam_g=inp["lam_g_prev"], success=True, status="Solve_Succeeded",
                         iterations=-1, solve_time_s=dt), Y, terms

    @property
    def backend(self) -> str:
        """``"compiled"`` (generated C) or ``"casadi"``."""
        return "compiled" if self._step is not None else self._solver.backend

    def _fallback_solver(self) -> NLPSolver | None:
        """The solver of ``config.fallback_solver`` (None when there is none), built at its
        first use."""
        cfg = self.config
        if cfg.fallback_solver in (None, cfg.solver):
            return None
        if self._fallback_nlp is None:
            self._fallback_nlp = _make_solver(self._ocp.nlp, self._ocp.equality, cfg,
                                              cfg.fallback_solver,
                                              after_sqp=cfg.solver == "sqp")
        return self._fallback_nlp

    def _rescue_solver(self) -> NLPSolver | None:
        """The convexified SQP (``SQP_RESCUE``) when ``config.sqp_rescue`` asks for it,
        built at its first use."""
        cfg = self.config
        if not (cfg.sqp_rescue and cfg.solver == "sqp"):
            return None
        if self._rescue_nlp is None:
            self._rescue_nlp = _make_solver(self._ocp.nlp, self._ocp.equality, cfg,
                                            SQP_RESCUE)
        return self._rescue_nlp

    # ------------------------------------------------------------------ state
    def reset(self) -> None:
        """Forget the warm start, the plan, the log, the fallback count and the warnings."""
        self._w_prev = None
        self._lam_prev = None
        self.solver_fallbacks = 0
        self.solver_rescues = 0
        self._plan = None
        self._plan_age = 0
        self.fallbacks = 0
        self.log = EconStepLog()
        self.extrapolation: list[str] = []
        from acid.ident.envelope import Excursion

        self._env_n, self._env_out = 0, Excursion()   # read as envelope_steps
        self._applied = None  # (u, d) applied over the last period, for the estimator
        if getattr(self, "estimator", None) is not None:
            self.estimator.reset()

    def _scaled_guess(self, x0: np.ndarray, v, Ta, dist, u_guess) -> np.ndarray:
        """Shifted previous solution (interpolated in time), else a forward simulation."""
        cfg, N = self.config, self.N
        w = np.zeros(self._n_w)
        if self._w_prev is not None and self._uniform:   # the same as interpolating
            w = self._w_prev[self._ocp.shift_w]
            w[self._ix[0]] = (x0 - X_OFFSET) / X_SCALE
            return w
        if self._w_prev is not None:
            wp = self._w_prev
            Xp = wp[self._ix] * X_SCALE + X_OFFSET
            Up = wp[self._iu] * U_SCALE + U_OFFSET
            Sp = wp[self._is]
            tn = self._t + cfg.intervals[0]
            for j in range(_NX):
                w[self._ix[:, j]] = (np.interp(tn, self._t, Xp[:, j]) - X_OFFSET[j]) / X_SCALE[j]
            for j in range(_NU):
                w[self._iu[:, j]] = (np.interp(tn[:-1], self._t[:-1], Up[:, j])
                                     - U_OFFSET[j]) / U_SCALE[j]
            for j in range(self._ns):
                w[self._is[:, j]] = np.interp(tn[:-1], self._t[:-1], Sp[:, j])
            w[self._ix[0]] = (x0 - X_OFFSET) / X_SCALE
            return w
        u = np.clip(np.asarray(u_guess, dtype=float), cfg.u_min, cfg.u_max)
        x = x0.copy()
        w[self._ix[0]] = (x - X_OFFSET) / X_SCALE
        for i in range(N):
            w[self._iu[i]] = (u - U_OFFSET) / U_SCALE
            step = self._steps[cfg.intervals[i]]
            x = np.asarray(step(x, u, [v[i], Ta[i]], dist)[0]).ravel()
            w[self._ix[i + 1]] = (x - X_OFFSET) / X_SCALE
        return w

    def terminal_prices(self, x0, u, v, Ta, T_cab_min: float, T_cab_max: float, dist,
                        T_cab_ref: float | None = None) -> np.ndarray:
        """(5,) prices of the terminal cost ``lam^T (x_N - x_0)``, J per unit state.

        ``"heat"``: ``pi dH/dx`` (the heat content's gradient at the last interval's speed);
        ``"steady"``: the multipliers of the optimal steady state at the horizon's mean
        speed and ambient and its last band (:mod:`acid.control.econ.terminal`);
        ``"none"``: zeros. ``T_cab_ref``: the comfort price's reference (``comfort_weight``).
        """
        term = self.config.terminal
        if term == "heat":
            pi = self.price(x0, u, v[0], Ta[0], dist)
            return pi * np.asarray(self._dH(x0, v[-1])).ravel()
        if term == "steady":
            iv, n = self._iv, self._iv_sum
            return self._steady(float(iv @ v) / n, float(iv @ Ta) / n,
                                float(T_cab_min), float(T_cab_max), T_cab_ref=T_cab_ref)
        return np.zeros(_NX)

    def price(self, x0, u, v0: float, Ta0: float, dist) -> float:
        """Terminal price pi = dP_comp/dQ_e at the current operating point, W/W (>= 0.05)."""
        out = self._step0(x0, u, [v0, Ta0], dist)
        Q_e = float(out[2])
        q_lo, q_hi = self._power_map.domain.get("Q_e", (Q_e, Q_e))
        Q_e = float(np.clip(Q_e, max(q_lo, 1.0), q_hi))
        T_ev = 0.5 * (float(x0[3]) + float(np.asarray(out[0]).ravel()[3]))
        return float(max(float(self._dPdQ(Q_e, T_ev, v0, Ta0)), 0.05))

    # ------------------------------------------------------------------ solve
    def solve(self, x, v_preview, T_amb_preview, T_cab_max=None, T_cab_min=None,
              dist=None, u_guess=None, T_cab_ref=None) -> EconSolution:
        """Solve once from the measured state.

        Parameters
        ----------
        x : (5,) state [T_cab, T_int, T_shell, T_evap, w_cab] (K, kg/kg).
        v_preview, T_amb_preview : speed (m/s) and ambient (K) per interval, scalars or (N,).
        T_cab_max, T_cab_min : comfort band per interval end, scalars or (N,) (default:
            the configured band).
        dist : (5,) additive disturbances on the state derivatives (default zero).
        u_guess : input used for a cold initial guess (default: maximum cooling when the
            cabin is above its band, else mid-range).
        T_cab_ref : the comfort price's reference, K, scalar or (N,) (``comfort_weight`` > 0;
            default ``config.T_cab_ref``).
        """
        cfg, N = self.config, self.N
        x = np.asarray(x, dtype=float).reshape(_NX)
        v = _per_interval(v_preview, N).copy()
        Ta = _per_interval(T_amb_preview, N).copy()
        ub = _per_interval(cfg.T_cab_max if T_cab_max is None else T_cab_max, N)
        lb = _per_interval(cfg.T_cab_min if T_cab_min is None else T_cab_min, N)
        if np.any(lb >= ub):
            raise ConfigError("comfort band is empty: T_cab_min must be below T_cab_max")
        dist = np.zeros(_NX) if dist is None else np.asarray(dist, dtype=float).reshape(_NX)
        self._warn_outside(v_veh=v, T_amb=Ta)
        if u_guess is None:  # a cold start: full cooling when the cabin is above its band
            u_guess = cfg.u_safe if x[0] > ub[0] else 0.5 * (cfg.u_min + cfg.u_max)
        u0 = self._plan[0] if self._plan is not None else u_guess
        ref = None
        if cfg.comfort_weight > 0.0:
            ref = np.broadcast_to(np.asarray(cfg.T_cab_ref if T_cab_ref is None else T_cab_ref,
                                             dtype=float), (N,)).reshape(N, 1)
        lam = self.terminal_prices(x, u0, v, Ta, lb[-1], ub[-1], dist,
                                   T_cab_ref=None if ref is None else float(ref[-1, 0]))
        lbg, ubg = self._lbg0, self._ubg0
        par = self._ocp.parameters(self._pvec.copy(), x0=x, dist=dist,
                                   d=np.column_stack((v, Ta)), lam=lam, q=ref,
                                   bounds={("T_cab", "hi"): ub, ("T_cab", "lo"): lb})
        lam_g0 = lam_x0 = None
        Y = terms = w0 = None
        if self._step is not None:   # one C call: guess, solve, check, the stages' outputs
            res, Y, terms = self._solve_step(x, par, u_guess)
        if self._step is None or not res.success:   # the guess of the separate solvers
            if self._lam_prev is not None and self._uniform:
                lam_g0, lam_x0 = self._lam_prev
                if cfg.solver == "sqp":   # the multipliers shifted with the plan
                    lam_g0, lam_x0 = lam_g0[self._ocp.shift_g], lam_x0[self._ocp.shift_w]
            w0 = self._scaled_guess(x, v, Ta, dist, u_guess)
        if self._step is None:
            res = self._solver.solve(w0, par, self._lbx, self._ubx, lbg, ubg, lam_x0=lam_x0,
                                     lam_g0=lam_g0)
        rescue = self._rescue_solver() if not res.success and res.status != "timeout" \
            else None
        if rescue is not None:   # the same problem, guess and multipliers, convex QPs
            first = res
            res = rescue.solve(w0, par, self._lbx, self._ubx, lbg, ubg, lam_x0=lam_x0,
                               lam_g0=lam_g0)
            self.solver_rescues += 1
            res = dataclasses.replace(
                res, status=f"{res.status} ({SQP_RESCUE} after {cfg.solver}: "
                            f"{first.status})",
                solve_time_s=first.solve_time_s + res.solve_time_s)
        fallback = self._fallback_solver() if not res.success and res.status != "timeout" \
            else None
        if fallback is not None:   # the same problem from the same guess
            first = res
            res = fallback.solve(w0, par, self._lbx, self._ubx, lbg, ubg)
            self.solver_fallbacks += 1
            res = dataclasses.replace(
                res, status=f"{res.status} ({cfg.fallback_solver} after {cfg.solver}: "
                            f"{first.status})",
                solve_time_s=first.solve_time_s + res.solve_time_s)
        w = res.x
        ok = res.success
        if ok:
            self._w_prev = w
            # an interior point's multipliers are nowhere exactly zero: an active-set SQP
            # started from them takes every bound as active, so it starts from zero duals
            self._lam_prev = (res.lam_g, res.lam_x) if fallback is None else None
        if not np.all(np.isfinite(w)):  # a timeout: report the initial guess's trajectory
            w = self._scaled_guess(x, v, Ta, dist, u_guess)
        if Y is None or not ok:   # the fused step computed them for its own solution
            Y, terms = (np.asarray(a) for a in self._stage_values(w, par))
        energy = float(terms[self._i_E].sum())   # not the comfort price
        Q_e = Y[self._i_Q_e]
        X = w[self._ix] * X_SCALE + X_OFFSET
        Uc = np.minimum(np.maximum(w[self._iu] * U_SCALE + U_OFFSET, cfg.u_min), cfg.u_max)
        Q_e = np.asarray(Q_e).ravel()
        P_bl = econ.blower_power(self._s, Uc[:, 0])
        T_ev = 0.5 * (X[:-1, 3] + X[1:, 3])
        P_c = np.asarray(econ.compressor_power(self._s, Q_e, T_ev, v, Ta))
        if ok:
            self._warn_outside(Q_e=Q_e, T_evap=T_ev)
        step = {"Q_e": float(Q_e[0]), "T_evap": float(T_ev[0]), "T_cab": float(X[0, 0]),
                "W_bl": float(Uc[0, 0]), "T_amb": float(Ta[0])}
        self._env_n += 1
        if not self.envelope.inside(**step):
            self._env_out = self._env_out.merged(self.envelope.check(**step))
        return EconSolution(
            u=Uc[0].copy(), x=X, t=self._t.copy(), W_bl=Uc[:, 0], T_evap_set=Uc[:, 1], Q_e=Q_e,
            P_comp=P_c, P_bl=P_bl, slack=np.maximum(w[self._is], 0.0), terminal_prices=lam,
            energy_J=float(energy), objective=float(res.f) / cfg.cost_scale,
            status=res.status, success=ok, iterations=res.iterations,
            solve_time_s=res.solve_time_s)

    @property
    def envelope_steps(self):
        """The applied (first) interval of every solve since the reset against the model's
        envelope (``acid.ident.envelope.Excursion``: count, steps outside, worst)."""
        return dataclasses.replace(self._env_out, n=self._env_n)

    def _warn_outside(self, **inputs) -> None:
        """One ExtrapolationWarning per power-map input (per reset) that leaves its data.

        Inputs already warned about, and inputs inside their range (the cheap test, each
        step), are not passed to PowerMap.outside (which formats the messages)."""
        check = {}
        for name, vals in inputs.items():
            ok = self._map_ok.get(name)
            if ok is None or vals is None or name in self.extrapolation:
                continue
            v = np.asarray(vals, dtype=float)
            if v.size and not (ok[0] <= v.min() and v.max() <= ok[1]):
                check[name] = v
        if not check:
            return
        for msg in self._power_map.outside(**check):
            name = msg.split(" ")[0]
            if name not in self.extrapolation:
                self.extrapolation.append(name)
                warnings.warn(f"econ NMPC: power map extrapolated: {msg}",
                              ExtrapolationWarning, stacklevel=4)

    # ------------------------------------------------------------ closed loop
    def make_step(self, x, v_preview, T_amb_preview, T_cab_max=None, T_cab_min=None,
                  dist=None, T_cab_ref=None) -> np.ndarray:
        """One closed-loop update: the input [W_bl, T_evap_set] for the next sample.

        Never raises for a solver failure: the fallback (rest of the last plan, else
        ``config.u_safe``) is applied and counted. With ``config.preview`` False, the
        speed and ambient previews are replaced by their first values (held). With
        ``config.offset_free`` the state and disturbances are estimated from ``x`` (and
        ``dist``, if given, is ignored); the estimate is in ``log.disturbance``.
        """
        check_interrupt()  # a Ctrl-C its last solve swallowed stops here
        t0 = time.perf_counter()
        cfg = self.config
        v = np.atleast_1d(np.asarray(v_preview, dtype=float))
        Ta = np.atleast_1d(np.asarray(T_amb_preview, dtype=float))
        if not cfg.preview:
            v, Ta = v[:1], Ta[:1]
        sol = None
        x = np.asarray(x, dtype=float).reshape(_NX)
        if self.estimator is not None:
            x, dist = self.estimator.update(x, *(self._applied or (None, None)))
        try:
            sol = self.solve(x, v, Ta, T_cab_max, T_cab_min, dist, T_cab_ref=T_cab_ref)
            ok = sol.success
            status = sol.status
        except (RuntimeError, ValueError, FloatingPointError) as exc:
            status, ok = f"error: {str(exc).splitlines()[0][:120]}", False
        if ok:
            self._plan, self._plan_age = sol.plan, 0
            u = sol.u.copy()
        else:
            self.fallbacks += 1
            check_interrupt()  # the failure was the interrupt: say only that
            warnings.warn(f"econ NMPC solve failed ({status}); fallback applied",
                          SolverWarning, stacklevel=2)
            self._w_prev = self._lam_prev = None
            nxt = self._plan_age + 1
            if self._plan is not None and nxt < self.N:
                u = self._plan[nxt].copy()
                self._plan_age += 1
            else:
                u = cfg.u_safe.copy()
        u = np.minimum(np.maximum(u, cfg.u_min), cfg.u_max)   # np.clip, faster
        self._applied = (u, np.array([v[0], Ta[0]]))
        self.log.disturbance.append(None if dist is None else np.asarray(dist, float).copy())
        self.log.u.append(u)
        self.log.solutions.append(sol)
        self.log.fallback.append(not ok)
        self.log.step_time_s.append(time.perf_counter() - t0)
        return u
