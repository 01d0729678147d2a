"""One optimal-control problem over any declared model (:class:`acid.models.Model`).

The model's traced equations (``Model.F``: one sample, ``x_next`` and the outputs ``y``)
are the prediction model; nothing is written twice. Over a horizon of ``N`` samples the
builder stacks, stage by stage (the order fatrop's structure detection wants)::

    w = [x_0, u_0, s_0, x_1, u_1, s_1, ..., x_N]

    min  cost_scale * ( sum_{i<N} [ l(x_i, u_i, d_i, y_i, q_i) + sum_b a_b (s_hi + s_lo) ]
                        + [ l(x_N, u_{N-1}, d_{N-1}, y_N, q_N)     if terminal_stage ]
                        + [ lam^T (x_N - x_0)                       if terminal_price ] )
    s.t. x_0 = x(k)
         x_{i+1} = F(x_i, u_i, d_i, theta) + E_x dist              (dynamics, gap form)
         lo_b(i) - s_lo <= b(i) <= hi_b(i) + s_hi,  s >= 0          (soft bounds)
         u_min <= u_i <= u_max

* ``l`` is the stage cost: economic (any function of the declared names and of the
  stage parameters ``q``, e.g. an ambient and an efficiency previewed per stage) or
  tracking (:func:`tracking_cost`, weighted squares against previewed references).
* A soft bound ``b`` is a state (bounded at ``x_{i+1}``, i.e. every state the inputs can
  move) or an output (over interval ``i``); its limits are NLP parameters per stage, so
  time-varying bounds need no rebuild, and the constraint is written ``b - hi - s <= 0``
  with an exact zero limit (interior-point solvers relax bounds by ``1e-8 |bound|``).
* ``d_i`` are the model's declared disturbances, previewed per stage; ``theta`` its
  parameter table (values given by name), an NLP parameter, so one solver (and one compiled
  library) serves every parameter set.
* ``dist`` are the offset-free disturbances: each one acts on a named state (added to its
  next value) or on a named output (added to it, and substituted where the step reads it,
  e.g. the paper's inlet air in eq. 1). :meth:`OCP.dynamics` is the same map as a CasADi
  Function ``(x, u, v, d) -> x_next`` for :class:`acid.control.estimator.OffsetFreeEstimator`.
* The terminal price ``lam`` (J per unit state) comes from the model's optimal steady state
  (:func:`steady_state_problem` on the same declaration) or any other rule of the caller.
* Inputs (and states) enter the NLP scaled, ``u = u_offset + w / u_scale``, for
  conditioning and so that a relaxed bound moves nothing physical.

Units are the declaration's (kelvin inside). Every index map comes from the declared
layout (:class:`acid.control.layout.BlockVector`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from acid.control.layout import BlockVector
from acid.errors import ConfigError
from acid.models.declaration import Model

#: the stage function's inputs that are decision variables (states, inputs, slacks, next
#: state): the only ones it is differentiated by (CasADi ``is_diff_in``); previews,
#: parameters, disturbances and limits are NLP parameters, and leaving their seeds out of
#: the derivative functions makes the Lagrangian's Hessian and the constraint Jacobian
#: (most of an SQP step) cheaper
_DECISION_INPUTS = frozenset({"x", "u", "s", "xn"})


@dataclass(frozen=True)
class SoftBound:
    """A bound on a state or an output, relaxed by non-negative slacks.

    ``lower``/``upper``: default limits in the declared unit (None: that side is absent;
    the limits are NLP parameters, changed per solve and per stage). ``penalty``: cost
    per unit of violation and stage (W per K for the paper's a_sl), per second of the
    interval when ``per_second``. ``scale``: the constraint and its slack are in units of
    ``1 / scale`` (e.g. 1e-3: kW for a bound in W). ``expr``: bound a derived quantity
    instead of a declared name, ``expr(s)`` over the next state's names (and the stage's
    inputs, disturbances, parameters and constants); ``name`` then only labels it.
    """

    name: str
    lower: float | None = None
    upper: float | None = None
    penalty: float = 1e5
    scale: float = 1.0
    per_second: bool = False
    expr: Callable | None = None

    @property
    def sides(self) -> tuple[str, ...]:
        return tuple(s for s, v in (("hi", self.upper), ("lo", self.lower)) if v is not None)


@dataclass(frozen=True)
class OCPSpec:
    """What the optimal-control problem is, over a declared model (module docstring).

    Attributes
    ----------
    N : horizon, samples of the model's ``Ts`` (or of ``intervals``).
    stage_cost : ``cost(s) -> {term: expression}`` (summed; each term reported along the
        plan) where ``s.NAME`` is any declared name or stage parameter, and ``s.dt`` the
        interval's length, s.
    stage_parameters : names of scalar parameters previewed per stage that the cost reads.
    input_bounds : ``{input: (min, max)}`` in the declared unit (every input).
    soft_bounds : :class:`SoftBound` rows.
    disturbance_targets : the states and outputs the offset-free disturbances act on.
    terminal_stage : add the stage cost at ``x_N`` with the last input held (paper eq. 7
        sums to ``Np``).
    terminal_price : add ``lam^T (x_N - x_0)``, ``lam`` an NLP parameter.
    u_offset, u_scale : ``{input: value}``; the NLP's variable is ``(u - offset) * scale``.
    x_offset, x_scale : ``{state: value}``, likewise for the states.
    cost_scale : factor of the objective inside the NLP.
    constants : ``{name: value}`` numbers the cost reads besides the declaration's.
    intervals : interval lengths, s, one per stage (default ``N`` x the model's ``Ts``).
    interval_model : for grids other than the declared step: ``interval_model(dt)`` is a
        CasADi Function ``(x, u, d, p, dist) -> (x_next, OUT1, OUT2, ...)`` of the same
        declaration over ``dt`` s (scalar outputs named by the Function; ``dist`` the
        offset-free disturbances, one per ``disturbance_targets`` entry, as the Function
        applies them). Default: the declared step with :func:`disturbed_dynamics`.
    stage_functions : build the NLP from one CasADi Function per distinct stage, called at
        every stage (MX), instead of one expression inlining every stage (SX): the
        generated C holds each stage and its derivatives once (several times less code to
        compile for long horizons); the stage function is differentiated only by its
        decision variables (``is_diff_in``), so on the economic NMPC its SQP steps are also
        1.2x faster than inlined (``benchmarks/bench_compile.py``).
    """

    N: int
    stage_cost: Callable
    input_bounds: Mapping[str, tuple[float, float]]
    stage_parameters: tuple[str, ...] = ()
    soft_bounds: tuple[SoftBound, ...] = ()
    disturbance_targets: tuple[str, ...] = ()
    terminal_stage: bool = False
    terminal_price: bool = False
    u_offset: Mapping[str, float] = field(default_factory=dict)
    u_scale: Mapping[str, float] = field(default_factory=dict)
    x_offset: Mapping[str, float] = field(default_factory=dict)
    x_scale: Mapping[str, float] = field(default_factory=dict)
    cost_scale: float = 1.0
    constants: Mapping[str, float] = field(default_factory=dict)
    intervals: tuple[float, ...] | None = None
    interval_model: Callable | None = None
    stage_functions: bool = False


def tracking_cost(weights: Mapping[str, float]) -> tuple[Callable, tuple[str, ...]]:
    """A tracking stage cost ``sum_n w_n (n - ref_n)^2`` over declared names ``n`` (states,
    inputs, outputs) against references previewed per stage (stage parameters ``ref_n``).
    Returns ``(stage_cost, stage_parameters)`` for :class:`OCPSpec`."""
    weights = dict(weights)

    def cost(s):
        return {f"track_{n}": w * (s[n] - s[f"ref_{n}"]) ** 2 for n, w in weights.items()}

    return cost, tuple(f"ref_{n}" for n in weights)


class _Namespace:
    """``s.NAME`` over a dict of symbols; an unknown name is one line naming it."""

    def __init__(self, symbols: dict, where: str):
        self._symbols, self._where = symbols, where

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            return self._symbols[name]
        except KeyError:
            raise ConfigError(f"{self._where}: unknown name {name!r} (known: "
                              f"{', '.join(self._symbols)})") from None

    __getitem__ = __getattr__


def disturbed_dynamics(model: Model, targets: tuple[str, ...]) -> ca.Function:
    """``(x, u, d, p, dist) -> (x_next, y)``: the model's sample with additive disturbances
    on the named states (after the step) and outputs (substituted where the step reads
    them). A continuous-time model takes state targets only."""
    names_x, names_y = model.state_names, model.output_names
    for t in targets:
        if t not in names_x and t not in names_y:
            raise ConfigError(f"disturbance target {t!r} is neither a state nor an output of "
                              f"model {model.name!r}")
    dist = ca.SX.sym("dist", len(targets))
    Ex = ca.SX.zeros(model.nx)
    Ey = ca.SX.zeros(model.ny)
    for j, t in enumerate(targets):
        if t in names_x:
            Ex[names_x.index(t)] += dist[j]
        else:
            Ey[names_y.index(t)] += dist[j]
    x, u, d, p = model._x, model._u, model._d, model._p   # the declaration's own symbols
    if any(t in names_y for t in targets):
        if model.continuous:
            raise ConfigError(f"model {model.name!r} is continuous-time: offset-free "
                              "disturbances act on its states only")
        h = model.h(x, u, d, p)
        y_read = h + Ey
        raw = model.equations_raw
        x_next = ca.vertcat(*[raw[s] for s in names_x])
        x_next = ca.substitute(x_next, model._yr, y_read)
        y = ca.vertcat(*[y_read[k] if o in model.sampled_outputs
                         else ca.substitute(raw[o], model._yr, y_read) + Ey[k]
                         for k, o in enumerate(names_y)])
    else:
        x_next, y = model.F(x, u, d, p)
    return ca.Function("F_dist", [x, u, d, p, dist], [x_next + Ex, y],
                       ["x", "u", "d", "p", "dist"], ["x_next", "y"])


class OCP:
    """The NLP of an :class:`OCPSpec` over a declared model (module docstring).

    Attributes (after construction)
    ----------
    nlp : ``{"x", "f", "g", "p"}`` for :class:`acid.control.codegen.solver.NLPSolver`.
    w, g, par : the declared layouts (:class:`acid.control.layout.BlockVector`).
    lbx, ubx, lbg, ubg : constant bound vectors (input bounds, slacks >= 0, constraint
        sides); the soft bounds' limits are parameters (:meth:`parameters`).
    equality : per constraint, whether it is an equality (fatrop's ``equality`` option).
    """

    def __init__(self, model: Model, spec: OCPSpec):
        self.model, self.spec = model, spec
        self.N = N = int(spec.N)
        if N < 1:
            raise ConfigError(f"horizon N must be at least 1, got {N}")
        missing = [n for n in model.inputs if n.name not in spec.input_bounds]
        if missing:
            raise ConfigError(f"input_bounds: no bounds for input {missing[0].name!r}")
        self.ntarget = len(spec.disturbance_targets)
        self.intervals = (tuple(float(t) for t in spec.intervals) if spec.intervals
                          is not None else (model.Ts,) * N)
        if len(self.intervals) != N or min(self.intervals) <= 0:
            raise ConfigError(f"intervals: {N} positive lengths expected, got "
                              f"{self.intervals}")
        if spec.interval_model is None:
            if any(abs(t - model.Ts) > 1e-12 for t in self.intervals):
                raise ConfigError(f"intervals other than the declared Ts = {model.Ts:g} s "
                                  "need an interval_model")
            F = disturbed_dynamics(model, tuple(spec.disturbance_targets))
            self._out_names = model.output_names
            self._F = {model.Ts: lambda x, u, d, p, dist, F=F: tuple(F(x, u, d, p, dist))}
        else:
            self._F = {}
            for dt in sorted(set(self.intervals)):
                Fi = spec.interval_model(dt)
                self._out_names = tuple(Fi.name_out()[1:])
                self._F[dt] = lambda x, u, d, p, dist, F=Fi: (
                    F(x, u, d, p, dist)[0], ca.vertcat(*F(x, u, d, p, dist)[1:]))
        for b in spec.soft_bounds:
            if b.expr is None and b.name not in model.state_names + self._out_names:
                raise ConfigError(f"soft bound on {b.name!r}: not a state or output of "
                                  f"model {model.name!r}")
            if not b.sides:
                raise ConfigError(f"soft bound on {b.name!r} has neither side")
        un = [i.name for i in model.inputs]
        xn = list(model.state_names)
        self.u_offset = np.array([spec.u_offset.get(n, 0.0) for n in un], float)
        self.u_scale = np.array([spec.u_scale.get(n, 1.0) for n in un], float)
        self.x_offset = np.array([spec.x_offset.get(n, 0.0) for n in xn], float)
        self.x_scale = np.array([spec.x_scale.get(n, 1.0) for n in xn], float)
        self.u_min = np.array([spec.input_bounds[n][0] for n in un], float)
        self.u_max = np.array([spec.input_bounds[n][1] for n in un], float)
        if not np.all(self.u_min < self.u_max):
            raise ConfigError("input bounds must satisfy min < max")
        self._build()

    # ------------------------------------------------------------------------ build
    def _Fd(self, x, u, d, theta, dist, dt: float | None = None):
        """``(x_next, y)`` of one interval of ``dt`` s (default the declared step)."""
        return self._F[self.model.Ts if dt is None else dt](x, u, d, theta, dist)

    def _namespace(self, x, u, d, y, theta, q, dt: float | None = None) -> _Namespace:
        m = self.model
        sym = {}
        for names, vec in (((r.name for r in m.states), x), ((r.name for r in m.inputs), u),
                           ((r.name for r in m.disturbances), d), (self._out_names, y),
                           ((r.name for r in m.parameters), theta)):
            for k, name in enumerate(names):
                sym[name] = vec[k]
        for c in m.constants:
            sym[c.name] = float(c.value)
        sym.update({k: float(v) for k, v in self.spec.constants.items()})
        for k, n in enumerate(self.spec.stage_parameters):
            sym[n] = q[k]
        sym["dt"] = m.Ts if dt is None else float(dt)
        return _Namespace(sym, f"model {m.name!r}: stage cost")

    def _cost_terms(self, x, u, d, y, theta, q, dt: float | None = None) -> dict:
        out = self.spec.stage_cost(self._namespace(x, u, d, y, theta, q, dt))
        if not isinstance(out, Mapping) or not out:
            raise ConfigError("stage_cost must return a non-empty dict {term: expression}")
        return {k: ca.SX(v) for k, v in out.items()}

    def _bound_value(self, b: SoftBound, x_next, u, d, y, theta, q, dt):
        m = self.model
        if b.expr is not None:
            return b.expr(self._namespace(x_next, u, d, y, theta, q, dt))
        if b.name in m.state_names:
            return x_next[m.state_names.index(b.name)]
        return y[self._out_names.index(b.name)]

    def _stage(self, X, U, S, Di, theta, dist, Qi, QN, lims, Zn, dt, last) -> dict:
        """One stage's constraints and cost (SX): ``dyn`` (the gap), ``bounds`` (one entry
        per soft-bound side), ``cost``, the outputs ``y`` and the cost ``terms`` (with the
        stage N appended on the ``last`` stage of a ``terminal_stage`` problem)."""
        spec = self.spec
        xoff, xscl = ca.DM(self.x_offset), ca.DM(self.x_scale)
        x_next, y = self._Fd(X, U, Di, theta, dist, dt)
        terms = self._cost_terms(X, U, Di, y, theta, Qi, dt)
        cost = sum(terms.values())
        terms_N = {}
        if last:   # stage N with u(N) := u(N-1)
            y_N = self._Fd(x_next, U, Di, theta, dist, dt)[1]
            terms_N = self._cost_terms(x_next, U, Di, y_N, theta, QN, dt)
            cost += sum(terms_N.values())
        bounds, k = [], 0
        for b in spec.soft_bounds:
            val = self._bound_value(b, x_next, U, Di, y, theta, Qi, dt)
            for side in b.sides:
                sign = -1.0 if side == "hi" else 1.0
                bounds.append((val - lims[k]) * b.scale + sign * S[k])
                cost += b.penalty * (dt if b.per_second else 1.0) * S[k]
                k += 1
        return {"dyn": Zn - (x_next - xoff) / xscl, "bounds": bounds, "cost": cost, "y": y,
                "terms": terms, "terms_N": terms_N}

    def _stage_function(self, dt: float, last: bool) -> ca.Function:
        """:meth:`_stage` as one SX Function (the stage-function form), cached per kind."""
        key = (dt, last)
        if key not in self._stage_fns:
            m, nq = self.model, len(self.spec.stage_parameters)
            names = ("x", "u", "s", "d", "theta", "dist", "q", "qN", "lim", "xn")
            ins = [ca.SX.sym(n, k) for n, k in zip(names, (
                m.nx, m.nu, self.ns, m.nd, m.np, self.ntarget, nq, nq, self.ns, m.nx),
                strict=True)]
            X = ca.DM(self.x_offset) + ca.DM(self.x_scale) * ins[0]
            U = ca.DM(self.u_offset) + ins[1] / ca.DM(self.u_scale)
            r = self._stage(X, U, ins[2], ins[3], ins[4], ins[5], ins[6], ins[7], ins[8],
                            ins[9], dt, last)
            # common subexpressions eliminated: the same numbers (bit for bit) from about
            # half the operations, and so are its derivatives (the NLP's Jacobian and
            # Hessian, most of an SQP step) and its generated C
            self._stage_fns[key] = ca.Function(
                f"ocp_stage_{len(self._stage_fns)}", ins,
                [r["dyn"], ca.vertcat(*r["bounds"]), r["cost"], r["y"],
                 ca.vertcat(*r["terms"].values(), *r["terms_N"].values())],
                {"cse": True, "is_diff_in": [n in _DECISION_INPUTS for n in names]})
            self._stage_terms = (tuple(r["terms"]), tuple(r["terms_N"]))
        return self._stage_fns[key]

    def _build(self) -> None:
        m, spec, N = self.model, self.spec, self.N
        nq = len(spec.stage_parameters)
        kind = ca.MX if spec.stage_functions else ca.SX
        w, g, par = BlockVector("w", kind), BlockVector("g", kind), BlockVector("p", kind)
        x0 = par.sym("x0", 0, m.nx)
        theta = par.sym("theta", 0, m.np)
        dist = par.sym("dist", 0, self.ntarget)
        D = [par.sym("d", i, m.nd) for i in range(N)]
        nstage_q = N + 1 if spec.terminal_stage else N
        Q = [par.sym("q", i, nq) for i in range(nstage_q)]
        sides = [(b.name, side) for b in spec.soft_bounds for side in b.sides]
        lim = {bs: [par.sym(f"{bs[0]}_{bs[1]}", i, 1) for i in range(N)] for bs in sides}
        lam = par.sym("lam", 0, m.nx) if spec.terminal_price else None
        self.ns = ns = len(sides)
        self._stage_fns: dict = {}
        xoff, xscl = ca.DM(self.x_offset), ca.DM(self.x_scale)
        uoff, uscl = ca.DM(self.u_offset), ca.DM(self.u_scale)

        cost = 0
        Zx = w.sym("x", 0, m.nx)
        g.add("init", 0, Zx - (x0 - xoff) / xscl)
        terms_list, y_list = [], []
        for i in range(N):
            dt = self.intervals[i]
            last = spec.terminal_stage and i == N - 1
            Zu = w.sym("u", i, m.nu)
            S = w.sym("s", i, ns) if ns else kind(0, 1)
            Zn = kind.sym(f"x_{i + 1}", m.nx)
            lims = [lim[bs][i] for bs in sides]
            QN = Q[N] if last else kind.zeros(nq)
            if spec.stage_functions:
                F = self._stage_function(dt, last)
                dyn, bvec, c, y, tv = F(Zx, Zu, S, D[i], theta, dist, Q[i], QN,
                                        ca.vertcat(*lims) if lims else kind(0, 1), Zn)
                bounds = ca.vertsplit(bvec)
                names = self._stage_terms[0] + (self._stage_terms[1] if last else ())
                terms = dict(zip(names, ca.vertsplit(tv), strict=True))
            else:
                r = self._stage(xoff + xscl * Zx, uoff + Zu / uscl, S, D[i], theta, dist,
                                Q[i], QN, lims, Zn, dt, last)
                dyn, bounds, c, y = r["dyn"], r["bounds"], r["cost"], r["y"]
                terms = {**r["terms"], **{f"{k} (N)": v for k, v in r["terms_N"].items()}}
            n_first = len(terms) if not last else len(terms) // 2
            items = list(terms.values())
            terms_list.append(dict(zip(list(terms)[:n_first], items[:n_first], strict=True)))
            if last:
                terms_list.append(dict(zip(list(terms)[:n_first], items[n_first:],
                                           strict=True)))
            y_list.append(y)
            cost += c
            g.add("dyn", i, dyn)
            for bs, expr in zip(sides, bounds, strict=True):
                g.add(f"{bs[0]}_{bs[1]}", i, expr)
            w.add("x", i + 1, Zn)
            Zx = Zn
        X = xoff + xscl * Zx
        if spec.terminal_price:
            cost += ca.dot(lam, X - x0)
        self.nlp = {"x": w.vertcat(), "f": cost * spec.cost_scale, "g": g.vertcat(),
                    "p": par.vertcat()}
        self.w, self.g, self.par = w, g, par
        self.ns = ns
        self.term_names = tuple(terms_list[0])
        self.output_names = self._out_names
        # outputs and cost terms of the NLP's own stages (the states of w, not re-simulated)
        self.stage_values = ca.Function(
            "ocp_stage_values", [self.nlp["x"], self.nlp["p"]],
            [ca.horzcat(*y_list), ca.horzcat(*[ca.vertcat(*t.values()) for t in terms_list])],
            ["w", "p"], ["Y", "terms"])
        if spec.stage_functions:   # evaluated in Python every solve: SX, not the MX VM
            self.stage_values = self.stage_values.expand()
        self._ix, self._iu = w.index("x"), w.index("u")
        self._is = w.index("s") if ns else np.zeros((N, 0), dtype=int)
        self._ip = {b: par.index(b) for b in par.blocks}
        inf = np.inf
        self.lbx, self.ubx = np.full(w.size, -inf), np.full(w.size, inf)
        self.lbx[self._iu] = self.u_nlp(self.u_min)
        self.ubx[self._iu] = self.u_nlp(self.u_max)
        if ns:
            self.lbx[self._is.ravel()] = 0.0
        self.lbg, self.ubg = np.zeros(g.size), np.zeros(g.size)
        self.equality = np.zeros(g.size, dtype=bool)
        for blk in ("init", "dyn"):
            self.equality[g.index(blk).ravel()] = True
        for b in spec.soft_bounds:
            if "hi" in b.sides:
                self.lbg[g.index(f"{b.name}_hi").ravel()] = -inf
            if "lo" in b.sides:
                self.ubg[g.index(f"{b.name}_lo").ravel()] = inf
        # the plan's trajectory and cost terms (for the solution object), one Function
        Xs = [ca.SX.sym("x0t", m.nx)]
        Uplan = ca.SX.sym("U", m.nu, N)
        Dplan = ca.SX.sym("D", m.nd, N)
        Qplan = ca.SX.sym("Q", nq, nstage_q)
        th, ds = ca.SX.sym("th", m.np), ca.SX.sym("ds", self.ntarget)
        Ys, Ts = [], []
        for i in range(N):
            dt = self.intervals[i]
            xn, y = self._Fd(Xs[i], Uplan[:, i], Dplan[:, i], th, ds, dt)
            Ys.append(y)
            Ts.append(ca.vertcat(*self._cost_terms(Xs[i], Uplan[:, i], Dplan[:, i], y, th,
                                                   Qplan[:, i], dt).values()))
            Xs.append(xn)
        if spec.terminal_stage:
            dt = self.intervals[-1]
            y = self._Fd(Xs[N], Uplan[:, N - 1], Dplan[:, N - 1], th, ds, dt)[1]
            Ys.append(y)
            Ts.append(ca.vertcat(*self._cost_terms(Xs[N], Uplan[:, N - 1], Dplan[:, N - 1], y,
                                                   th, Qplan[:, N], dt).values()))
        self.trajectory = ca.Function(
            "ocp_trajectory", [Xs[0], Uplan, Dplan, Qplan, th, ds],
            [ca.horzcat(*Xs), ca.horzcat(*Ys), ca.horzcat(*Ts)],
            ["x0", "U", "D", "Q", "theta", "dist"], ["X", "Y", "terms"])
        self.shift_w = stage_shift(w)
        self.shift_g = stage_shift(g)

    def steady_state_nlp(self) -> dict:
        """The model's optimal steady state as an NLP (for a terminal price from its
        multipliers): over the scaled ``[x, u]``,

            min  cost_scale * l(x, u, d, y, q)   s.t.  (F(x, u, d) - x) / x_scale = 0,
                 the soft bounds as hard constraints at ``x`` (= x_next) and on ``y``

        of the first interval, parameters ``[d, theta, dist, q, limits]``; ``g`` starts with
        the ``nx`` fixed-point equations, then one row per bound side (``lbg``/``ubg``:
        :attr:`steady_state_sides`). Their multipliers divided by ``x_scale`` and
        ``cost_scale`` are the stationary costates (cost per unit state)."""
        m, spec, dt = self.model, self.spec, self.intervals[0]
        nq = len(spec.stage_parameters)
        z, wu = ca.SX.sym("z", m.nx), ca.SX.sym("w", m.nu)
        d, th = ca.SX.sym("d", m.nd), ca.SX.sym("theta", m.np)
        dist, q = ca.SX.sym("dist", self.ntarget), ca.SX.sym("q", nq)
        lims = ca.SX.sym("lim", self.ns)
        X = ca.DM(self.x_offset) + ca.DM(self.x_scale) * z
        U = ca.DM(self.u_offset) + wu / ca.DM(self.u_scale)
        x_next, y = self._Fd(X, U, d, th, dist, dt)
        g = [(x_next - X) / ca.DM(self.x_scale)]
        k = 0
        for b in spec.soft_bounds:
            val = self._bound_value(b, X, U, d, y, th, q, dt)   # at a fixed point x = x_next
            for _side in b.sides:
                g.append((val - lims[k]) * b.scale)
                k += 1
        cost = sum(self._cost_terms(X, U, d, y, th, q, dt).values())
        return {"x": ca.vertcat(z, wu), "p": ca.vertcat(d, th, dist, q, lims),
                "f": spec.cost_scale * cost, "g": ca.vertcat(*g)}

    @property
    def steady_state_sides(self) -> tuple[str, ...]:
        """``"hi"``/``"lo"`` of each bound row of :meth:`steady_state_nlp`, in order."""
        return tuple(side for b in self.spec.soft_bounds for side in b.sides)

    # ------------------------------------------------------------------ numerics
    def trajectory_evaluator(self, compiled: bool | str = "auto") -> Callable:
        """``f(x0, U (nu, N), D (nd, N), Q (nq, N[+1]), theta, dist) -> (X, Y, terms)``
        numpy arrays: :attr:`trajectory` as generated C when ``compiled`` allows and a
        compiler works (about 20x faster per call than inside CasADi), else inside CasADi."""
        return numeric_evaluator(self.trajectory, compiled)

    def stage_values_evaluator(self, compiled: bool | str = "auto") -> Callable:
        """``f(w, p) -> (Y, terms)`` numpy arrays: :attr:`stage_values` (the outputs and cost
        terms of the NLP's own stages) as generated C when ``compiled`` allows, else
        inside CasADi."""
        return numeric_evaluator(self.stage_values, compiled)

    def guess(self, x0, d, theta, u, previous: np.ndarray | None = None) -> np.ndarray:
        """An initial point for the NLP from the state ``x0`` (nx,): the ``previous`` solution
        shifted by one stage, else the model run over the previewed ``d`` (N, nd) with the
        input ``u`` (nu,) held (and parameters ``theta``)."""
        x = np.asarray(x0, dtype=float)
        if previous is not None:
            w = previous[self.shift_w].copy()
            w[self._ix[0]] = (x - self.x_offset) / self.x_scale
            return w
        w = np.zeros(self.w.size)
        w[self._ix[0]] = (x - self.x_offset) / self.x_scale
        for i in range(self.N):
            w[self._iu[i]] = self.u_nlp(u)
            x = self.model.step(x, u, d[i], theta)[0]
            w[self._ix[i + 1]] = (x - self.x_offset) / self.x_scale
        return w

    def u_nlp(self, u) -> np.ndarray:
        """Inputs (declared units) as the NLP's scaled variables."""
        return (np.asarray(u, dtype=float) - self.u_offset) * self.u_scale

    def plan(self, w: np.ndarray) -> np.ndarray:
        """(N, nu) planned inputs in declared units from an NLP vector."""
        return self.u_offset + w[self._iu] / self.u_scale

    def states(self, w: np.ndarray) -> np.ndarray:
        """(N+1, nx) predicted states from an NLP vector."""
        return self.x_offset + w[self._ix] * self.x_scale

    def theta(self, values: Mapping[str, float] | None = None) -> np.ndarray:
        """The parameter table's values by name (declared values for names not given);
        an unknown name is one line."""
        values = dict(values or {})
        names = self.model.parameter_names
        unknown = sorted(set(values) - set(names))
        if unknown:
            raise ConfigError(f"model {self.model.name!r} has no parameter {unknown[0]!r} "
                              f"(parameters: {', '.join(names)})")
        return np.array([float(values.get(p.name, p.value)) for p in self.model.parameters])

    def parameters(self, out: np.ndarray, *, x0=None, theta=None, dist=None, d=None, q=None,
                   bounds: Mapping[tuple[str, str], np.ndarray] | None = None,
                   lam=None) -> np.ndarray:
        """Fill the NLP's parameter vector ``out`` in place (only what is given): ``d``
        (N, nd) disturbance preview, ``q`` (N or N+1, nq) stage parameters, ``bounds``
        ``{(name, "hi"|"lo"): (N,) limits of x(1..N) / y(0..N-1)}``."""
        ip = self._ip
        if x0 is not None:
            out[ip["x0"].ravel()] = x0
        if theta is not None:
            out[ip["theta"].ravel()] = theta
        if dist is not None and self.ntarget:
            out[ip["dist"].ravel()] = dist
        if d is not None and self.model.nd:
            out[ip["d"]] = d
        if q is not None and self.spec.stage_parameters:
            out[ip["q"]] = q
        if lam is not None and "lam" in ip:
            out[ip["lam"].ravel()] = lam
        for (name, side), val in (bounds or {}).items():
            out[ip[f"{name}_{side}"].ravel()] = val
        return out

    def dynamics(self, theta: np.ndarray, name: str = "ocp_model") -> ca.Function:
        """``(x, u, v, d) -> x_next`` at fixed parameters: the prediction model with its
        offset-free disturbances ``d`` (for :class:`acid.control.estimator.OffsetFreeEstimator`;
        ``v`` the declared disturbances)."""
        m = self.model
        x, u, v, d = (ca.SX.sym(n, k) for n, k in (("x", m.nx), ("u", m.nu), ("v", m.nd),
                                                    ("d", self.ntarget)))
        return ca.Function(name, [x, u, v, d], [self._Fd(x, u, v, ca.DM(theta), d)[0]],
                           ["x", "u", "v", "d"], ["x_next"])


def numeric_evaluator(fn: ca.Function, compiled: bool | str = "auto") -> Callable:
    """``fn`` on numbers, returning numpy arrays of its outputs' shapes: generated C when
    ``compiled`` allows and a compiler works, else inside CasADi."""
    if compiled is not False:
        from acid.control.codegen.build import CodegenError, compile_function

        try:
            cf, _ = compile_function(fn)
        except CodegenError:
            cf = None   # the solver already noticed a missing compiler
        if cf is not None:
            shapes = [fn.size_out(i) for i in range(fn.n_out())]

            def evaluate(*args):
                for buf, a in zip(cf.inputs, args, strict=True):
                    buf[:] = np.asarray(a, dtype=float).ravel(order="F")
                if cf.call():
                    raise RuntimeError(f"{fn.name()}: the generated code failed")
                return tuple(o.reshape(sh, order="F").copy()
                             for o, sh in zip(cf.outputs, shapes, strict=True))

            return evaluate
    return lambda *args: tuple(np.asarray(a) for a in fn(*args))


def stage_shift(vec: BlockVector, hold: int = 0) -> np.ndarray:
    """Index permutation that shifts a stage-wise vector by one stage (``v[perm]``): each
    block at stage ``i`` takes its value at stage ``i + 1``; each block's last stage keeps
    its own value (the last input is repeated; the terminal state is kept).

    ``hold``: the last ``hold`` stages before each block's last one also keep their own
    values, and the stage before them is the one repeated. Without a terminal cost the
    optimal plan ends in an arc tied to the horizon's end (the cooling stops before it),
    which a plain shift moves one stage early, so the next solve spends its QP iterations
    moving it back; held in place, it is already where the next optimum has it."""
    perm = np.arange(vec.size)
    for b in vec.blocks:
        idx = vec.index(b)
        n = idx.shape[0] - 1 - int(hold)   # stages that take their successor's value
        if n > 0:
            perm[idx[:n]] = idx[1:n + 1]
    return perm

