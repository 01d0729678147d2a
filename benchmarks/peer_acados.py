"""The paper NMPC's problem in acados (SQP, exact Hessian, HPIPM): a benchmark-only peer.

acados is not a dependency of acid and does not install beside it (its Python interface
ships its own CasADi); it runs in its own environment, e.g.::

    python3.12 -m venv /tmp/acados-env && /tmp/acados-env/bin/pip install comma-deps-acados numpy

``benchmarks/bench_mpc.py --acados-python /tmp/acados-env/bin/python`` starts this file under
that interpreter and talks to it over stdin/stdout, one JSON line per message:

1. the set-up: ``{"params": {...}, "config": {...}, "T_int": .., "T_shell": .., "build": dir}``
   (the paper's parameters, the NMPC's bounds, penalty, cost scale, tolerance);
2. then per state: ``{"x": [T_cab, T_evap], "ub": [T_cab_max(0..N)], "reset": bool}``, answered
   with ``{"U": (N, 2) moves, "ms": the step's wall time, "status": acados status,
   "iterations": SQP iterations}``.

The problem is bench_mpc's do-mpc transcription: the paper's eqs. 1-5 from
``tests/_paper_oracle.py`` (independent of acid's declaration), states [T_cab, T_evap, W_last]
(W_last carries u(N-1) to the terminal power), eq. 4's power as the stage and terminal
cost scaled by ``cost_scale``, the cabin and evaporator bounds on x(1..N) soft with the L1
penalty ``slack_penalty * cost_scale`` (exact penalty: the same optimum), inputs bounded.
The step time covers what a controller does each sample: set x0 and the bound preview,
solve (warm-started from acados's previous solution), read the moves.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path
from types import SimpleNamespace

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from _paper_oracle import inlet_air, power, step  # noqa: E402


def build(msg: dict):
    """The acados solver of the set-up message."""
    import os

    import acados

    # the wheel's own install folder: headers, libraries, the template renderer
    os.environ.setdefault("ACADOS_SOURCE_DIR", acados.DIR)
    os.environ.setdefault("ACADOS_PYTHON_INTERFACE_PATH", acados.TEMPLATE_DIR)
    os.environ.setdefault("TERA_PATH", acados.TERA_PATH)
    import ctypes

    for lib in ("libblasfeo", "libhpipm", "libqpOASES_e", "libacados"):   # by soname later
        ctypes.CDLL(os.path.join(acados.LIB_DIR, lib + ".so"), mode=ctypes.RTLD_GLOBAL)
    import casadi as ca
    import numpy as np
    from acados.acados_template import AcadosModel, AcadosOcp, AcadosOcpSolver

    p = SimpleNamespace(**msg["params"])
    c = SimpleNamespace(**msg["config"])
    N, s = int(c.N), float(c.cost_scale)
    x = ca.SX.sym("x", 3)
    u = ca.SX.sym("u", 2)
    T_cab, T_evap, W_last = x[0], x[1], x[2]
    W, Tset = u[0], u[1]
    c_n, e_n, T_ain = step(T_cab, T_evap, W, Tset, msg["T_int"], msg["T_shell"], p)
    model = AcadosModel()
    model.name = "paper_nmpc"
    model.x, model.u = x, u
    model.disc_dyn_expr = ca.vertcat(c_n, e_n, W)
    model.cost_expr_ext_cost = power(W, T_ain, c.T_amb, p) * s
    model.cost_expr_ext_cost_e = power(W_last, inlet_air(T_evap, W_last, p), c.T_amb, p) * s
    ocp = AcadosOcp()
    ocp.model = model
    ocp.dims.N = N
    ocp.cost.cost_type = ocp.cost.cost_type_e = "EXTERNAL"
    con = ocp.constraints
    con.x0 = np.array([300.0, 280.0, 0.1])
    con.idxbu = np.array([0, 1])
    con.lbu = np.array([c.W_bl_min, c.T_evap_set_min])
    con.ubu = np.array([c.W_bl_max, c.T_evap_set_max])
    lo = np.array([c.T_cab_min, c.T_evap_min])
    hi = np.array([400.0, c.T_evap_max])
    con.idxbx = con.idxbx_e = np.array([0, 1])
    con.lbx = con.lbx_e = lo
    con.ubx = con.ubx_e = hi
    con.idxsbx = con.idxsbx_e = np.array([0, 1])
    pen = float(c.slack_penalty) * s
    for suffix in ("", "_e"):
        for name, val in (("zl", pen), ("zu", pen), ("Zl", 0.0), ("Zu", 0.0)):
            setattr(ocp.cost, name + suffix, np.full(2, val))
    opt = ocp.solver_options
    opt.tf = N * float(p.Ts)
    opt.integrator_type = "DISCRETE"
    opt.nlp_solver_type = "SQP"
    opt.hessian_approx = "EXACT"
    opt.regularize_method = msg.get("regularize", "PROJECT")
    if msg.get("globalization"):
        opt.globalization = msg["globalization"]
    opt.qp_solver = "PARTIAL_CONDENSING_HPIPM"
    opt.qp_solver_iter_max = 100
    opt.nlp_solver_max_iter = 100
    tol = float(c.tol)
    opt.nlp_solver_tol_stat = opt.nlp_solver_tol_eq = tol
    opt.nlp_solver_tol_ineq = opt.nlp_solver_tol_comp = tol
    opt.print_level = 0
    folder = Path(msg["build"])
    folder.mkdir(parents=True, exist_ok=True)
    ocp.code_export_directory = str(folder / "c_generated_code")
    cwd = os.getcwd()
    os.chdir(folder)   # acados writes its json and build output beside the cwd
    try:
        solver = AcadosOcpSolver(ocp, json_file=str(folder / "acados_ocp.json"), verbose=False)
    finally:
        os.chdir(cwd)
    return solver, N, lo, hi


def main() -> None:
    import numpy as np

    setup = json.loads(sys.stdin.readline())
    shift = bool(setup.get("shift", True))
    out = sys.stdout
    saved = os.dup(1)
    os.dup2(2, 1)   # whatever the build prints (compiler, acados) goes to stderr
    sys.stdout = sys.stderr
    try:
        solver, N, lo, hi = build(setup)
    finally:
        sys.stdout = out
        os.dup2(saved, 1)
        os.close(saved)
    out.write(json.dumps({"ready": True}) + "\n")
    out.flush()
    for line in sys.stdin:
        msg = json.loads(line)
        x0 = np.array([msg["x"][0], msg["x"][1], 0.1])
        ub = msg["ub"]
        if msg.get("reset"):
            solver.reset()
        t0 = time.perf_counter()
        if shift and not msg.get("reset"):   # the previous solution shifted by one stage
            X = [solver.get(k, "x") for k in range(N + 1)]
            U = [solver.get(k, "u") for k in range(N)]
            for k in range(N):
                solver.set(k, "x", X[k + 1])
                solver.set(k, "u", U[min(k + 1, N - 1)])
        solver.set(0, "lbx", x0)
        solver.set(0, "ubx", x0)
        for k in range(1, N + 1):
            solver.constraints_set(k, "ubx", np.array([ub[k], hi[1]]))
        status = solver.solve()
        U = [solver.get(k, "u") for k in range(N)]
        ms = (time.perf_counter() - t0) * 1e3
        out.write(json.dumps({"U": [list(map(float, uk)) for uk in U], "ms": ms,
                              "status": int(status),
                              "iterations": int(np.ravel(solver.get_stats("sqp_iter"))[0])}) + "\n")
        out.flush()


if __name__ == "__main__":
    main()
