"""Per-step time of acid's NMPC against do-mpc on the same problem, states and machine.

Run: ``/work/venv/bin/python benchmarks/bench_mpc.py [--repeats 3] [--json out.json]``
(do-mpc is a dev extra: ``pip install do-mpc``).

What is compared
----------------
1. acid's NMPC runs scenario (a) of ``acid mpc-check`` (125 s, both initial conditions) in
   closed loop on the control-oriented model; every measured state and bound preview is
   recorded.
2. The *same* problem (paper eqs. 7-13 with acid's documented choices: slacks on x(1..N),
   terminal power with u(N) = u(N-1), cost scaled by 1e-3 inside the NLP) is written in
   do-mpc: a discrete model with states [T_cab, T_evap, W_last] (W_last carries u(N-1) to
   the terminal cost), inputs [W_bl, T_evap_set], time-varying parameters [next upper
   bound, T_int, T_shell], soft nonlinear constraints on the *next* state with penalty a_sl
   (do-mpc puts one slack per constraint and step: equal optimum since the upper and lower
   cabin bounds are never violated together), IPOPT with exact Hessian.
3. Both controllers are replayed over the recorded sequence of states, in order (each
   warm-starts from its previous solution, as in closed loop); the whole ``make_step`` wall
   time is measured for each; first moves and objectives are compared.

With ``--acados-python PY`` (an interpreter with acados, e.g. ``pip install
comma-deps-acados`` in a Python 3.12 virtualenv: acados ships its own CasADi, so it is a
benchmark-only peer in its own environment), acados's SQP (exact Hessian, HPIPM, the same
tolerance) solves the same problem on the same states, interleaved
(``benchmarks/peer_acados.py``, its step timed inside its own process).

Prints median / p95 / max per-step time of acid with its solver as generated C (the default:
the whole step, guess, solve, convergence check and trajectory, is one C call; no wall-clock
cap), of the same with the solver, its check and the trajectory as 3 separate C calls, the
one C call alone (its share of the step), of acid with the same solver inside CasADi, of
acid with the ECU-like wall-clock cap (``max_solve_s=2.5``: the step in a worker thread),
and of do-mpc, measured interleaved on the same states in one run; the ratio do-mpc / acid;
and the largest relative differences of the first move and of the objective (acid against
do-mpc, both solved to 1e-10 without bound relaxation). Run with ``OMP_NUM_THREADS=1
OPENBLAS_NUM_THREADS=1`` so that IPOPT's linear algebra does not spin threads between the
timed calls.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import sys
import time
from pathlib import Path

import casadi as ca
import numpy as np

from acid.control.codegen.solver import NLPSolver
from acid.control.nmpc import NMPC, NMPCConfig
from acid.models.params import ModelParams, paper
from acid.studies.mpc_check.scenarios import (
    BOUND_STEPS,
    MODEL_T_INT,
    MODEL_T_SHELL,
    run_model_scenario,
    step_bound,
)

# the peer's model: the paper's eqs. 1-5 transcribed independently of acid's declaration
sys.path.insert(0, str(Path(__file__).parent.parent / "tests"))
from _paper_oracle import inlet_air as _inlet_air  # noqa: E402
from _paper_oracle import power as _power  # noqa: E402
from _paper_oracle import step as _step  # noqa: E402


def record_states(params: ModelParams, config: NMPCConfig):
    """Closed-loop states and bound previews of scenario (a) (both initial conditions)."""
    res = run_model_scenario(params, config)
    N = config.N
    cases = []
    for run in res.runs:
        n = run.n_steps
        # the bound preview the controller saw at step k: T_cab_max(t_k .. t_{k+N})
        full = step_bound(np.arange(n + N + 1) * params.Ts, BOUND_STEPS)
        for k in range(n):
            cases.append((np.array([run.T_cab[k], run.T_evap[k]]), full[k: k + N + 1].copy(),
                          k == 0))
    return cases


def build_dompc(params: ModelParams, config: NMPCConfig):
    """The same NLP in do-mpc; returns (mpc, set_preview) where set_preview(ub) sets the tvp."""
    import do_mpc

    p, cfg, N = params, config, config.N
    m = do_mpc.model.Model("discrete", "SX")
    T_cab = m.set_variable("_x", "T_cab")
    T_evap = m.set_variable("_x", "T_evap")
    W_last = m.set_variable("_x", "W_last")
    W_bl = m.set_variable("_u", "W_bl")
    T_set = m.set_variable("_u", "T_evap_set")
    ub_next = m.set_variable("_tvp", "T_cab_max_next")
    T_int = m.set_variable("_tvp", "T_int")
    T_shell = m.set_variable("_tvp", "T_shell")
    T_cab_n, T_evap_n, T_ain = _step(T_cab, T_evap, W_bl, T_set, T_int, T_shell, p)
    m.set_rhs("T_cab", T_cab_n)
    m.set_rhs("T_evap", T_evap_n)
    m.set_rhs("W_last", W_bl)
    m.setup()
    # after setup, build the cost and constraints from the model's own symbols
    T_cab, T_evap, W_last = m.x["T_cab"], m.x["T_evap"], m.x["W_last"]
    W_bl, T_set = m.u["W_bl"], m.u["T_evap_set"]
    ub_next, T_int, T_shell = m.tvp["T_cab_max_next"], m.tvp["T_int"], m.tvp["T_shell"]
    T_cab_n, T_evap_n, T_ain = _step(T_cab, T_evap, W_bl, T_set, T_int, T_shell, p)

    mpc = do_mpc.controller.MPC(m)
    mpc.settings.n_horizon = N
    mpc.settings.t_step = p.Ts
    mpc.settings.store_full_solution = False
    # the same accuracy as acid: IPOPT without bound relaxation (its default relaxes every
    # bound by 1e-8 |bound|, 3e-6 K on a cabin bound)
    mpc.settings.nlpsol_opts = {"ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": 0,
                                "ipopt.tol": cfg.tol, "ipopt.bound_relax_factor": 0.0}
    s = cfg.cost_scale

    def power(W, Ta):
        return _power(W, Ta, cfg.T_amb, p)

    lterm = power(W_bl, T_ain) * s
    mterm = power(W_last, _inlet_air(T_evap, W_last, p)) * s
    mpc.set_objective(lterm=lterm, mterm=mterm)
    mpc.set_rterm(W_bl=0.0, T_evap_set=0.0)
    mpc.bounds["lower", "_u", "W_bl"] = cfg.W_bl_min
    mpc.bounds["upper", "_u", "W_bl"] = cfg.W_bl_max
    mpc.bounds["lower", "_u", "T_evap_set"] = cfg.T_evap_set_min
    mpc.bounds["upper", "_u", "T_evap_set"] = cfg.T_evap_set_max
    pen = cfg.slack_penalty * s
    mpc.set_nl_cons("cab_hi", T_cab_n - ub_next, ub=0.0, soft_constraint=True,
                    penalty_term_cons=pen)
    mpc.set_nl_cons("cab_lo", cfg.T_cab_min - T_cab_n, ub=0.0, soft_constraint=True,
                    penalty_term_cons=pen)
    mpc.set_nl_cons("evap_hi", T_evap_n - cfg.T_evap_max, ub=0.0, soft_constraint=True,
                    penalty_term_cons=pen)
    mpc.set_nl_cons("evap_lo", cfg.T_evap_min - T_evap_n, ub=0.0, soft_constraint=True,
                    penalty_term_cons=pen)
    tvp = mpc.get_tvp_template()
    current = {"ub": np.full(N + 1, 300.0)}

    def tvp_fun(t_now):
        for k in range(N + 1):
            tvp["_tvp", k, "T_cab_max_next"] = current["ub"][min(k + 1, N)]
            tvp["_tvp", k, "T_int"] = MODEL_T_INT
            tvp["_tvp", k, "T_shell"] = MODEL_T_SHELL
        return tvp

    mpc.set_tvp_fun(tvp_fun)
    mpc.setup()

    def set_preview(ub):
        current["ub"] = np.asarray(ub, dtype=float)

    return mpc, set_preview


class AcadosPeer:
    """``benchmarks/peer_acados.py`` running under another interpreter (acados's own
    environment), one JSON line per message; ``step`` returns (moves (N, 2), ms, status)."""

    def __init__(self, python: str, params: ModelParams, config: NMPCConfig, build: str,
                 **options):
        import json
        import subprocess

        self._json = json
        self.proc = subprocess.Popen(
            [python, str(Path(__file__).parent / "peer_acados.py")], stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, text=True)
        par = {"gamma": [float(v) for v in params.gamma],
               "tau": [float(v) for v in params.tau], "beta": [float(v) for v in params.beta],
               "c_p": float(params.c_p), "eta_cop": float(params.eta_cop),
               "Ts": float(params.Ts)}
        cfg = {k: float(getattr(config, k)) for k in (
            "N", "cost_scale", "T_amb", "W_bl_min", "W_bl_max", "T_evap_set_min",
            "T_evap_set_max", "T_cab_min", "T_evap_min", "T_evap_max", "slack_penalty", "tol")}
        self._send({"params": par, "config": cfg, "T_int": MODEL_T_INT,
                    "T_shell": MODEL_T_SHELL, "build": build, **options})
        if not self._read().get("ready"):
            raise RuntimeError("acados peer did not start")

    def _send(self, msg):
        self.proc.stdin.write(self._json.dumps(msg) + "\n")
        self.proc.stdin.flush()

    def _read(self) -> dict:
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError("acados peer ended (see its messages above)")
        return self._json.loads(line)

    def step(self, x0, ub, reset: bool):
        self._send({"x": [float(v) for v in x0], "ub": [float(v) for v in ub],
                    "reset": bool(reset)})
        r = self._read()
        return np.array(r["U"]), float(r["ms"]), int(r["status"]), int(r["iterations"])

    def close(self):
        self.proc.stdin.close()
        self.proc.wait(timeout=60)


def dompc_solution(mpc, x0, ub, params: ModelParams, config: NMPCConfig):
    """(first move, objective in W) of do-mpc's last solve, evaluated like acid's."""
    N = config.N
    U = np.array([np.asarray(mpc.opt_x_num_unscaled["_u", k, 0]).ravel() for k in range(N)])
    return plan_objective(U, x0, ub, params, config)


def plan_objective(U, x0, ub, params: ModelParams, config: NMPCConfig):
    """(first move, objective in W) of a plan U (N, 2) from x0, by the paper's eqs. 1-5."""
    N = config.N
    T_cab, T_evap, T_ain = [float(x0[0])], [float(x0[1])], []
    for k in range(N):
        c, e, a = _step(T_cab[k], T_evap[k], U[k, 0], U[k, 1], MODEL_T_INT, MODEL_T_SHELL,
                        params)
        T_cab.append(c)
        T_evap.append(e)
        T_ain.append(a)
    T_cab, T_evap, T_ain = np.array(T_cab), np.array(T_evap), np.array(T_ain)
    P = _power(U[:, 0], T_ain, config.T_amb, params)
    P_N = _power(U[-1, 0], _inlet_air(T_evap[-1], U[-1, 0], params), config.T_amb, params)
    viol_c = np.maximum.reduce([np.zeros(N), T_cab[1:] - ub[1:], config.T_cab_min - T_cab[1:]])
    viol_e = np.maximum.reduce([np.zeros(N), T_evap[1:] - config.T_evap_max,
                                config.T_evap_min - T_evap[1:]])
    obj = float(P.sum() + P_N + config.slack_penalty * (viol_c.sum() + viol_e.sum()))
    return U[0], obj


def _stats(ms):
    ms = np.asarray(ms)
    return {"median": float(np.median(ms)), "p95": float(np.percentile(ms, 95)),
            "max": float(ms.max()), "n": int(ms.size)}


#: the targets: whole-step median, speed-up over do-mpc, the same optimum
TARGET_MEDIAN_MS = 0.35
TARGET_RATIO = 30.0
TARGET_RATIO_ACADOS = 4.0
TARGET_SAME_OPTIMUM = 1e-6


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="replays of the state sequence")
    ap.add_argument("--solver", default="sqp", choices=("fatrop", "ipopt", "sqp"))
    ap.add_argument("--json", default=None, help="write the results here")
    ap.add_argument("--acados-python", default=None,
                    help="an interpreter with acados (comma-deps-acados): adds acados's SQP "
                         "with HPIPM as a peer (benchmarks/peer_acados.py)")
    ap.add_argument("--acados-build", default="/tmp/acid-bench-acados",
                    help="folder for the acados peer's generated solver")
    args = ap.parse_args(argv)

    params = paper()
    config = NMPCConfig(solver=args.solver)
    cases = record_states(params, config)
    separate = NMPC(params, config)   # the solver, its check and the trajectory: 3 C calls
    if separate._step is not None:
        separate._step = None
        separate._nlp = NLPSolver("acid_nmpc", separate._ocp.nlp,
                                  *separate._solver_options(args.solver), compiled=True,
                                  verify=separate._nlp.verify)
    ours = {"compiled": NMPC(params, config), "separate": separate,
            "casadi": NMPC(params, dataclasses.replace(config, compiled=False)),
            "capped": NMPC(params, dataclasses.replace(config, max_solve_s=2.5)),
            "fatrop": NMPC(params, dataclasses.replace(config, solver="fatrop"))}
    theirs, set_preview = build_dompc(params, config)
    acados = (AcadosPeer(args.acados_python, params, config, args.acados_build)
              if args.acados_python else None)
    t_acados, du_a, dobj_a, st_a, it_a = [], [], [], [], []

    # one untimed call each: first-call set-up (allocation, do-mpc's data structures)
    set_preview(cases[0][1])
    for mpc in ours.values():
        mpc.make_step(cases[0][0], cases[0][1], MODEL_T_INT, MODEL_T_SHELL)
    theirs.make_step(np.array([cases[0][0][0], cases[0][0][1], 0.1]))
    t_ours = {k: [] for k in ours}
    # the C call alone inside the compiled step (the rest of make_step is Python)
    t_call: list[float] = []
    step = ours["compiled"]._step
    if step is not None:
        call = step.step

        def timed(warm, call=call):
            t0 = time.perf_counter()
            out = call(warm)
            t_call.append((time.perf_counter() - t0) * 1e3)
            return out

        step.step = timed
    t_call.clear()
    t_theirs, du, dobj, dcomp, du_f, dobj_f, dsep = [], [], [], [], [], [], []
    n_fb = 0  # SQP solves that fatrop had to finish
    order = list(ours.items())
    for _ in range(args.repeats):
        for x0, ub, first in cases:
            sols = {}
            # interleaved: the same machine load for all; the order turns by one each state
            # (the first after do-mpc finds the shared Python code's caches coldest)
            order = order[1:] + order[:1]
            for key, mpc in order:
                if first:
                    n_fb += mpc.solver_fallbacks if key == "compiled" else 0
                    mpc.reset()
                t0 = time.perf_counter()
                mpc.make_step(x0, ub, MODEL_T_INT, MODEL_T_SHELL)
                t_ours[key].append((time.perf_counter() - t0) * 1e3)
                sols[key] = mpc.log.solutions[-1]
            sol = sols["compiled"]
            dcomp.append(float(np.max(np.abs(sol.u - sols["casadi"].u))))
            dsep.append(float(np.max(np.abs(sol.u - sols["separate"].u))))
            ref = sols["fatrop"]  # fatrop, fully converged: the optimum to meet
            du_f.append(float(np.max(np.abs(sol.u - ref.u) / np.abs(ref.u))))
            dobj_f.append(abs(sol.objective - ref.objective) / abs(ref.objective))

            set_preview(ub)
            x_dm = np.array([x0[0], x0[1], 0.1])
            t0 = time.perf_counter()
            theirs.make_step(x_dm)
            t_theirs.append((time.perf_counter() - t0) * 1e3)
            u_dm, obj_dm = dompc_solution(theirs, x0, ub, params, config)
            du.append(float(np.max(np.abs(sol.u - u_dm) / np.abs(u_dm))))
            dobj.append(abs(sol.objective - obj_dm) / abs(obj_dm))
            if acados is not None:
                U_a, ms, status, its = acados.step(x0, ub, first)
                t_acados.append(ms)
                st_a.append(status)
                it_a.append(its)
                u_a, obj_a = plan_objective(U_a, x0, ub, params, config)
                du_a.append(float(np.max(np.abs(sol.u - u_a) / np.abs(u_a))))
                dobj_a.append(abs(sol.objective - obj_a) / abs(obj_a))

    load = os.getloadavg()[0]
    if acados is not None:
        acados.close()
    so, sc, st = _stats(t_ours["compiled"]), _stats(t_ours["casadi"]), _stats(t_theirs)
    su = _stats(t_ours["capped"])
    ssep = _stats(t_ours["separate"])
    sc_call = _stats(t_call) if t_call else None
    sf = _stats(t_ours["fatrop"])
    same = bool(max(du) <= TARGET_SAME_OPTIMUM and max(dobj) <= TARGET_SAME_OPTIMUM)
    out = {
        "machine": platform.processor() or platform.machine(),
        "python": platform.python_version(), "casadi": ca.__version__,
        "solver": args.solver, "backend": ours["compiled"].backend,
        "states": len(cases), "repeats": args.repeats,
        "acid_ms": so, "acid_mean_ms": float(np.mean(t_ours["compiled"])),
        "acid_c_call_ms": sc_call, "acid_separate_calls_ms": ssep,
        "c_call_share_median": (sc_call["median"] / so["median"]) if sc_call else None,
        "acid_casadi_ms": sc, "acid_capped_ms": su, "acid_fatrop_ms": sf,
        "do_mpc_ms": st,
        "ratio_median": st["median"] / so["median"], "ratio_p95": st["p95"] / so["p95"],
        "ratio_casadi_median": st["median"] / sc["median"],
        "ratio_separate_median": st["median"] / ssep["median"],
        "ratio_capped_median": st["median"] / su["median"],
        "ratio_fatrop_median": st["median"] / sf["median"],
        "solver_fallbacks": int(n_fb + ours["compiled"].solver_fallbacks),
        "max_rel_diff_first_move_vs_fatrop": float(max(du_f)),
        "max_rel_diff_objective_vs_fatrop": float(max(dobj_f)),
        "max_abs_diff_compiled_vs_casadi": float(max(dcomp)),
        "max_abs_diff_one_call_vs_separate": float(max(dsep)),
        "max_rel_diff_first_move": float(max(du)), "max_rel_diff_objective": float(max(dobj)),
        "same_optimum": same, "load": load,
        "targets": {"median_ms": TARGET_MEDIAN_MS, "ratio": TARGET_RATIO,
                    "same_optimum_rel": TARGET_SAME_OPTIMUM},
    }
    print(f"{len(cases)} closed-loop states x {args.repeats} replays, whole make_step (ms):")
    for name, s in ((f"acid ({args.solver}, {out['backend']}, one C call)", so),
                    (f"acid ({args.solver}, 3 C calls a step)", ssep),
                    (f"acid ({args.solver}, casadi)", sc),
                    (f"acid ({args.solver}, {out['backend']}, capped)", su),
                    (f"acid (fatrop, {ours['fatrop'].backend})", sf),
                    ("do-mpc (ipopt)", st)):
        print(f"  {name:<34} median {s['median']:7.3f}  p95 {s['p95']:7.3f}  "
              f"max {s['max']:7.3f}")
    if sc_call:
        print(f"  the one C call: median {sc_call['median']:.3f} ms, "
              f"{100 * out['c_call_share_median']:.0f} % of the step's median; step mean "
              f"{out['acid_mean_ms']:.3f} ms")
    print(f"  do-mpc / acid: {out['ratio_median']:.1f}x (median, target >= {TARGET_RATIO:g}x), "
          f"{out['ratio_p95']:.1f}x (p95); 3 C calls {out['ratio_separate_median']:.1f}x; "
          f"inside CasADi {out['ratio_casadi_median']:.1f}x; "
          f"with the wall-clock cap {out['ratio_capped_median']:.1f}x; fatrop "
          f"{out['ratio_fatrop_median']:.1f}x")
    print(f"  vs fatrop's optimum: first move max rel diff "
          f"{out['max_rel_diff_first_move_vs_fatrop']:.1e}, objective "
          f"{out['max_rel_diff_objective_vs_fatrop']:.1e}; solves finished by the fallback "
          f"solver: {out['solver_fallbacks']}")
    print(f"  acid median {so['median']:.3f} ms (target <= {TARGET_MEDIAN_MS} ms on a quiet "
          "machine)")
    print("  compiled vs CasADi first move: max abs diff "
          f"{out['max_abs_diff_compiled_vs_casadi']:.1e}; one C call vs 3 C calls: "
          f"{out['max_abs_diff_one_call_vs_separate']:.1e}")
    print(f"  same optimum: first move max rel diff {out['max_rel_diff_first_move']:.1e}, "
          f"objective {out['max_rel_diff_objective']:.1e} -> {same} "
          f"(<= {TARGET_SAME_OPTIMUM:g})")
    if acados is not None:
        sa = _stats(t_acados)
        out["acados_ms"] = sa
        out["ratio_acados_median"] = sa["median"] / so["median"]
        out["acados_failed"] = int(sum(1 for v in st_a if v != 0))
        out["acados_iterations_mean"] = float(np.mean(it_a))
        out["max_rel_diff_first_move_vs_acados"] = float(max(du_a))
        out["max_rel_diff_objective_vs_acados"] = float(max(dobj_a))
        print(f"  acados (SQP, exact Hessian, HPIPM; own env)  median {sa['median']:7.3f}  "
              f"p95 {sa['p95']:7.3f}  max {sa['max']:7.3f}; acados / acid "
              f"{out['ratio_acados_median']:.1f}x (median, target >= {TARGET_RATIO_ACADOS:g}x); "
              f"{out['acados_iterations_mean']:.2f} SQP iterations a step, "
              f"{out['acados_failed']} not converged")
        within = {f"{t:g}": [int(np.sum(np.asarray(du_a) <= t)),
                              int(np.sum(np.asarray(dobj_a) <= t))] for t in (1e-8, 1e-6)}
        out["acados_states_within"] = within   # [first move, objective]
        out["acados_rel_diff_quantiles"] = {
            "first_move": [float(q) for q in np.quantile(du_a, [0.5, 0.9, 0.99])],
            "objective": [float(q) for q in np.quantile(dobj_a, [0.5, 0.9, 0.99])]}
        q = out["acados_rel_diff_quantiles"]
        print(f"  same optimum vs acados: first move max rel diff "
              f"{out['max_rel_diff_first_move_vs_acados']:.1e}, objective "
              f"{out['max_rel_diff_objective_vs_acados']:.1e}; states within 1e-8: first move "
              f"{within['1e-08'][0]}, objective {within['1e-08'][1]} of {len(du_a)} (1e-6: "
              f"{within['1e-06'][0]}, {within['1e-06'][1]}); median / p90 / p99 first move "
              + " / ".join(f"{v:.1e}" for v in q["first_move"]) + ", objective "
              + " / ".join(f"{v:.1e}" for v in q["objective"]))
    met = {"median": so["median"] <= TARGET_MEDIAN_MS and out["backend"] == "compiled",
           "ratio": out["ratio_median"] >= TARGET_RATIO, "optimum": same}
    out["targets_met"] = met
    print(f"VERDICT paper NMPC: median {so['median']:.3f} ms ({out['backend']}), "
          f"target <= {TARGET_MEDIAN_MS} ms -> {'MET' if met['median'] else 'NOT MET'}; "
          f"{out['ratio_median']:.1f}x do-mpc, target >= {TARGET_RATIO:g}x -> "
          f"{'MET' if met['ratio'] else 'NOT MET'}; same optimum (<= "
          f"{TARGET_SAME_OPTIMUM:g}) -> {'MET' if same else 'NOT MET'}"
          + (f"; {out['ratio_acados_median']:.1f}x acados, target >= {TARGET_RATIO_ACADOS:g}x "
             f"-> {'MET' if out['ratio_acados_median'] >= TARGET_RATIO_ACADOS else 'NOT MET'}"
             if acados is not None else "")
          + f"; load {load:.1f} on {os.cpu_count()} cores")
    if args.json:
        from acid._io import write_json

        write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
