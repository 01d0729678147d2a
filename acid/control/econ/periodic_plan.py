"""The best known plan as a periodic optimum over several formulations and starts.

One cyclic whole-cycle NLP solved locally can stop in a poor local optimum, and one
transcription can favour one. Here the same problem (the econ model, ``x(n) = x(0)`` with
the start state free, the comfort band and the mean of :class:`PlanConfig`, so no end-state
credit is needed) is transcribed two independent ways and solved from several seeded starts:

* ``direct`` -- every sample's state a decision variable (:func:`best_known_plan`);
* ``shooting`` -- multiple shooting: only every ``m``-th state a decision variable, the
  samples between them simulated inside the NLP by chaining the econ model's interval map
  (a different NLP with other local optima and another conditioning).

Starts: ``constant`` (a constant mid-range coil simulated from a mild state), ``guess`` (a
caller's trajectory, e.g. the fixed coil's) and ``perturbed-i`` (the constant start's inputs
with seeded uniform noise of a quarter of their range). Each solution is replayed open loop
on a plant under periodic steady state (:func:`replay_periodic`: the plan's pass repeated
from its own periodic state until the pass-end states repeat; its energy the last pass's).
The plan is the solution with the least replayed periodic energy among those whose replay
keeps the band; the spread of the formulations (each at its best start) is
``100 (max - min) / min`` of their replayed energies. Temperatures in K, energies in J.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import casadi as ca
import numpy as np

from acid.control.econ.best_plan import PlanConfig, WholeCyclePlan, best_known_plan, interval_map
from acid.control.econ.problem import X_OFFSET, X_SCALE
from acid.errors import ConfigError, ExtrapolationWarning
from acid.models import econ
from acid.models.econ_params import EconParams
from acid.units import K2C

_NX, _NU = econ.model.nx, econ.model.nu
FORMULATIONS = ("direct", "shooting")


@dataclass(frozen=True)
class PeriodicReplay:
    """A plan replayed on a plant until periodic: the last pass's energy (J), mean and
    range of T_cab (K), the passes run and the last pass-end state step (K)."""

    energy_J: float
    mean_T_cab: float
    min_T_cab: float
    max_T_cab: float
    passes: int
    end_step_K: float


@dataclass(frozen=True)
class Candidate:
    """One formulation from one start: its model solution and its periodic replay."""

    formulation: str
    start: str
    plan: WholeCyclePlan
    replay: PeriodicReplay | None
    cyclic_residual_K: float

    @property
    def energy_J(self) -> float:
        """Replayed periodic energy when replayed, else the model energy."""
        return self.replay.energy_J if self.replay is not None else self.plan.energy_J

    def to_dict(self) -> dict:
        r = self.replay
        return {"formulation": self.formulation, "start": self.start,
                "model_energy_kJ": self.plan.energy_J / 1e3,
                "replay_energy_kJ": None if r is None else r.energy_J / 1e3,
                "model_mean_T_cab_degC": K2C(self.plan.mean_T_cab),
                "replay_mean_T_cab_degC": None if r is None else K2C(r.mean_T_cab),
                "replay_passes": None if r is None else r.passes,
                "cyclic_residual_K": self.cyclic_residual_K, "success": self.plan.success,
                "iterations": self.plan.iterations, "solve_time_s": self.plan.solve_time_s}


@dataclass(frozen=True)
class PeriodicPlanSet:
    """Every candidate, the winner (least replayed periodic energy in the band) and the
    formulations' spread."""

    candidates: tuple[Candidate, ...]
    winner: Candidate
    by_formulation: dict
    spread_pct: float
    solve_time_s: float

    def to_dict(self) -> dict:
        return {"winner": self.winner.to_dict(), "spread_pct": self.spread_pct,
                "by_formulation": {k: c.to_dict() for k, c in self.by_formulation.items()},
                "candidates": [c.to_dict() for c in self.candidates],
                "solve_time_s": self.solve_time_s}

    def summary(self) -> str:
        lines = [f"best known plan (periodic): {self.winner.formulation} from "
                 f"{self.winner.start}, {self.winner.energy_J / 1e3:.1f} kJ per cycle; "
                 f"formulations spread {self.spread_pct:.2f} %"]
        for k, c in self.by_formulation.items():
            lines.append(f"  {k:9s} {c.energy_J / 1e3:9.1f} kJ  mean T_cab "
                         f"{K2C(c.replay.mean_T_cab if c.replay else c.plan.mean_T_cab):.2f}"
                         f" degC  (start {c.start}, model {c.plan.energy_J / 1e3:.1f} kJ)")
        return "\n".join(lines)


def replay_periodic(plant, plan: WholeCyclePlan, v_veh, T_amb, Ts: float, *, max_passes: int = 30,
                    tol_K: float = 0.005, start: dict | None = None) -> PeriodicReplay:
    """Apply the plan's inputs open loop, pass after pass, until the plant's pass-end states
    move by less than ``tol_K`` (K, humidity scaled 1 g/kg = 1 K); the first pass starts
    from ``start`` or else the plan's own periodic state (the econ states of the plant; its
    other states its own). Only the econ model's states are compared between passes."""
    v = np.asarray(v_veh, dtype=float).ravel()
    Ta = np.broadcast_to(np.asarray(T_amb, dtype=float), v.shape)
    keys = [k for k in getattr(plant, "INITIAL_KEYS", econ.STATES)]
    init = dict(start) if start is not None else {
        k: float(x) for k, x in zip(econ.STATES, plan.x[0], strict=True) if k in keys}
    plant.reset(init)

    def state():
        m = plant.measure()
        return {k: float(m[k]) for k in econ.STATES if k in m}

    prev, step, p = state(), np.inf, 0
    T = np.empty(v.size)
    E = 0.0
    for p in range(1, max_passes + 1):
        E = 0.0
        for k in range(v.size):
            row = plant.step(plan.W_bl[k], plan.T_evap_set[k], v[k], T_amb=Ta[k])
            E += (float(row["P_comp"]) + float(row["P_bl"])) * Ts
            T[k] = float(row["T_cab"])
        now = state()
        step = max(abs(now[k] - prev[k]) * (1e3 if k == "w_cab" else 1.0) for k in now)
        prev = now
        if p >= 2 and step < tol_K:
            break
    return PeriodicReplay(E, float(T.mean()), float(T.min()), float(T.max()), p, float(step))


def shooting_plan(params: EconParams, v_veh, T_amb, config: PlanConfig, *, m: int = 4,
                  guess: tuple[np.ndarray, np.ndarray] | None = None) -> WholeCyclePlan:
    """The cyclic plan by multiple shooting: decision states every ``m`` samples (``m``
    divides n; the nearest smaller divisor is taken), the samples between them simulated
    inside the NLP; band, mean, ``Q_e >= 0`` and the cycle as in :func:`best_known_plan`
    (the humidity bound and the pinned mode are not offered here)."""
    v = np.asarray(v_veh, dtype=float).ravel()
    Ta = np.broadcast_to(np.asarray(T_amb, dtype=float), v.shape).copy()
    n, Ts, cfg = v.size, params.Ts, config
    if n < 2:
        raise ConfigError("the plan needs a cycle of at least 2 samples")
    if cfg.pinned or cfg.RH_max is not None or not cfg.cyclic:
        raise ConfigError("the shooting plan is cyclic with a band only")
    m = max(d for d in range(1, max(1, min(m, n)) + 1) if n % d == 0)
    S = n // m
    step = econ.casadi_interval(Ts)
    xs, us, ds = ca.SX.sym("x", _NX), ca.SX.sym("u", _NU, m), ca.SX.sym("d", step.size1_in(2), m)
    th, w0 = ca.DM(params.theta_all), ca.DM.zeros(_NX)
    x, Xs, Qs, Ps = xs, [], [], []
    for j in range(m):
        out = dict(zip(step.name_out(), step(x, us[:, j], ds[:, j], th, w0), strict=True))
        x = out["x_next"]
        Xs.append(x)
        Qs.append(out["Q_e"])
        Ps.append(out["P_comp"] + out["P_bl"])
    seg = ca.Function("econ_plan_segment", [xs, us, ds],
                      [ca.horzcat(*Xs), ca.horzcat(*Qs), ca.horzcat(*Ps)]).map(S)
    xoff, xscl = ca.DM(X_OFFSET), ca.DM(X_SCALE)
    Z = ca.MX.sym("Z", _NX, S)                         # node S == node 0 (cyclic)
    U = ca.MX.sym("U", _NU, n)
    Xn = ca.repmat(xoff, 1, S) + ca.repmat(xscl, 1, S) * Z
    D = ca.DM(np.vstack([v, Ta]))
    # the map's copy s takes the columns s m .. s m + m - 1 of U and D: time order
    Xall, Q, P = seg(Xn, U, D)
    ends = Xall[:, [m * s + m - 1 for s in range(S)]]
    nxt = ca.horzcat(Xn[:, 1:], Xn[:, 0])
    T_cab = Xall[0, :]
    g = [ca.vec((ends - nxt) / ca.repmat(xscl, 1, S)), ca.vec(Q) / 1e3, ca.vec(T_cab),
         ca.sum2(T_cab) / n - cfg.T_mean]
    lbg = np.concatenate([np.zeros(_NX * S), np.zeros(n), np.full(n, cfg.T_low), [0.0]])
    ubg = np.concatenate([np.zeros(_NX * S), np.full(n, np.inf), np.full(n, cfg.T_high), [0.0]])
    w = ca.vertcat(ca.vec(Z), ca.vec(U))
    opts = {"print_time": False, "ipopt": {"print_level": 0, "sb": "yes", "tol": cfg.tol,
                                           "max_iter": int(cfg.max_iter),
                                           "mu_strategy": "adaptive"}}
    solver = ca.nlpsol("acid_shooting_plan", "ipopt",
                       {"x": w, "f": Ts * ca.sum2(P) / 1e3, "g": ca.vertcat(*g)}, opts)
    u_lo = np.array([cfg.W_bl_min, cfg.T_evap_set_min])
    u_hi = np.array([cfg.W_bl_max, cfg.T_evap_set_max])
    nz = _NX * S
    lbx = np.concatenate([np.full(nz, -np.inf), np.tile(u_lo, n)])
    ubx = np.concatenate([np.full(nz, np.inf), np.tile(u_hi, n)])
    x_g, u_g = _guess(params, v, Ta, cfg, guess)
    w0v = np.concatenate([((x_g[:n:m] - X_OFFSET) / X_SCALE).ravel(), u_g.ravel()])
    t0 = time.perf_counter()
    res = solver(x0=w0v, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
    elapsed = time.perf_counter() - t0
    st = solver.stats()
    status = str(st.get("return_status", ""))
    if "Infeasible" in status:
        raise ConfigError(f"whole-cycle plan infeasible on this model ({status}) by shooting")
    u = np.clip(np.asarray(res["x"]).ravel()[nz:].reshape(n, _NU), u_lo, u_hi)
    z0 = np.asarray(res["x"]).ravel()[:_NX] * X_SCALE + X_OFFSET
    # the plan's trajectory: the model simulated from the first node (exactly the NLP's)
    F = interval_map(params, Ts, 1)
    xtraj = np.empty((n + 1, _NX))
    xtraj[0] = z0
    q, pc, pb = np.empty(n), np.empty(n), np.empty(n)
    for k in range(n):
        a, b, c, d = (np.asarray(t).ravel() for t in F(xtraj[k], u[k], D[:, k]))
        xtraj[k + 1], q[k], pc[k], pb[k] = a, b[0], c[0], d[0]
    return WholeCyclePlan(x=xtraj, W_bl=u[:, 0], T_evap_set=u[:, 1], Q_e=q, P_comp=pc, P_bl=pb,
                          energy_J=float(Ts * np.sum(pc + pb)),
                          mean_T_cab=float(np.mean(xtraj[1:, 0])), status=status,
                          success=bool(st.get("success", False)),
                          iterations=int(st.get("iter_count", -1)), solve_time_s=elapsed,
                          config=cfg)


def _guess(params, v, Ta, cfg, guess):
    n = v.size
    if guess is not None:
        x, u = (np.asarray(a, dtype=float) for a in guess)
        if x.shape == (n + 1, _NX) and u.shape == (n, _NU):
            return x, u
    u = np.tile([0.08, cfg.T_evap_set_max], (n, 1))
    return _simulate(params, v, Ta, cfg, u), u


def _simulate(params, v, Ta, cfg, u):
    x0 = np.array([cfg.T_mean, cfg.T_mean + 2.0, Ta.mean() + 3.0, cfg.T_evap_set_max, 0.008])
    x, _ = econ.model.simulate(x0, u, np.column_stack([v, Ta]), params.theta_all)
    return x


def periodic_plans(params: EconParams, v_veh, T_amb, config: PlanConfig, *,
                   plant_factory=None, guess: tuple[np.ndarray, np.ndarray] | None = None,
                   n_random: int = 1, seed: int = 0, formulations=FORMULATIONS,
                   shooting_m: int = 4, band_tol_K: float = 0.05, match_rounds: int = 4,
                   match_tol_K: float = 0.02) -> PeriodicPlanSet:
    """Solve every formulation from every start, replay each on ``plant_factory()`` (a new
    plant per replay; ``None``: no replay, the model energy decides) and pick the plan
    (module docstring). With a plant, each plan's model mean is re-set (at most
    ``match_rounds`` solves) until its replayed periodic mean T_cab is ``config.T_mean``
    within ``match_tol_K``, the model's band moved with it (the model's cabin offset from the
    plant's): equal comfort on the plant."""
    cfg = config if config.cyclic else _replace(config, cyclic=True)
    v = np.asarray(v_veh, dtype=float).ravel()
    Ta = np.broadcast_to(np.asarray(T_amb, dtype=float), v.shape).copy()
    rng = np.random.default_rng(seed)
    n = v.size
    u_c = np.tile([0.08, cfg.T_evap_set_max], (n, 1))
    starts = {"constant": (_simulate(params, v, Ta, cfg, u_c), u_c)}
    if guess is not None:
        starts["guess"] = tuple(np.asarray(a, dtype=float) for a in guess)
    lo = np.array([cfg.W_bl_min, cfg.T_evap_set_min])
    hi = np.array([cfg.W_bl_max, cfg.T_evap_set_max])
    for i in range(n_random):
        u_r = np.clip(u_c + 0.25 * (hi - lo) * rng.uniform(-1, 1, u_c.shape), lo, hi)
        starts[f"perturbed-{i}"] = (_simulate(params, v, Ta, cfg, u_r), u_r)
    t0 = time.perf_counter()
    cands = []
    for form in formulations:
        for name, g in starts.items():
            if form not in FORMULATIONS:
                raise ConfigError(f"unknown plan formulation {form!r}: "
                                  f"choose from {', '.join(FORMULATIONS)}")
            T_req, pc, plan, rep = cfg.T_mean, cfg, None, None
            for _ in range(max(1, match_rounds) if plant_factory is not None else 1):
                sh = float(T_req - cfg.T_mean)    # the model's cabin offset: band moved too
                pc = _replace(cfg, T_mean=cfg.T_mean + sh, T_low=cfg.T_low + sh,
                              T_high=cfg.T_high + sh)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", ExtrapolationWarning)
                    try:
                        plan = (best_known_plan(params, v, Ta, pc, guess=g) if form == "direct"
                                else shooting_plan(params, v, Ta, pc, m=shooting_m, guess=g))
                    except ConfigError:
                        break
                    rep = (replay_periodic(plant_factory(), plan, v, Ta, params.Ts)
                           if plant_factory is not None else None)
                if rep is None or abs(rep.mean_T_cab - cfg.T_mean) <= match_tol_K:
                    break
                # the model and the plant disagree on the cabin: re-set the model's mean
                # until the plant's periodic mean is the required one (equal comfort)
                T_req = pc.T_mean - (rep.mean_T_cab - cfg.T_mean)
                g = (plan.x, plan.inputs)
            if plan is None:
                continue
            resid = float(np.max(np.abs(plan.x[-1, :4] - plan.x[0, :4])))
            cands.append(Candidate(form, name, plan, rep, resid))
    if not cands:
        raise ConfigError("no plan formulation found a feasible periodic plan")

    def in_band(c: Candidate) -> bool:
        if c.replay is None:
            return c.plan.success
        return (c.replay.min_T_cab >= cfg.T_low - band_tol_K
                and c.replay.max_T_cab <= cfg.T_high + band_tol_K)

    ok = [c for c in cands if in_band(c)] or cands
    if plant_factory is not None:      # equal comfort: the plant's mean at the required one
        ok = [c for c in ok if abs(c.replay.mean_T_cab - cfg.T_mean) <= match_tol_K] or ok
    best = {}
    for c in ok:
        if c.formulation not in best or c.energy_J < best[c.formulation].energy_J:
            best[c.formulation] = c
    winner = min(best.values(), key=lambda c: c.energy_J)
    es = [c.energy_J for c in best.values()]
    spread = 100.0 * (max(es) - min(es)) / min(es)
    return PeriodicPlanSet(tuple(cands), winner, best, float(spread),
                           time.perf_counter() - t0)


def _replace(cfg: PlanConfig, **kw) -> PlanConfig:
    from dataclasses import replace

    return replace(cfg, **kw)
