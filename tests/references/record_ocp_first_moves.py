"""Record first moves of today's NMPC builders (before the one-builder refactor)."""
import json, sys, warnings
import numpy as np
sys.path.insert(0, "benchmarks")
from bench_mpc import record_states
from acid.mpc.nmpc import NMPC, NMPCConfig
from acid.mpc.scenarios import MODEL_T_INT, MODEL_T_SHELL
from acid.params import paper
from acid.units import C2K

p = paper()
cfg = NMPCConfig(compiled=False)
cases = record_states(p, cfg)
idx = np.linspace(0, len(cases) - 1, 16).round().astype(int)
out = {"paper": [], "econ": []}
variants = [
    ("free", dict(), dict()),
    ("pinned", dict(first_move="pinned"), dict(u_prev=[0.09, C2K(6.0)])),
    ("state_disturbance", dict(), dict(disturbance=[0.05, -0.02])),
    ("inlet_disturbance", dict(disturbance="inlet"), dict(disturbance=[0.4, -0.02])),
    ("eta_preview", dict(), dict(eta_cop=np.linspace(3.0, 4.0, 7), T_amb=C2K(33.0))),
]
for name, ckw, skw in variants:
    mpc = NMPC(p, NMPCConfig(compiled=False, **ckw))
    for j in idx:
        x, ub, _ = cases[j]
        sol = mpc.solve(x, ub, MODEL_T_INT, MODEL_T_SHELL, **skw)
        assert sol.success, sol.status
        out["paper"].append({"variant": name, "x": x.tolist(), "T_cab_max": ub.tolist(),
                             "T_int": MODEL_T_INT, "T_shell": MODEL_T_SHELL,
                             "solve": {k: np.asarray(v).tolist() for k, v in skw.items()},
                             "config": ckw, "u": sol.u.tolist(), "plan": sol.plan.tolist(),
                             "objective": sol.objective})
# econ
sys.path.insert(0, "tests")
from conftest import ECON_TRUTH, ECON_MAP
from acid.econ.params import EconParams, PowerMap
from acid.mpc.econ_nmpc import EconNMPC, EconNMPCConfig
domain = {"Q_e": (-500.0, 6000.0), "T_evap": (270.0, 290.0), "v_veh": (0.0, 35.0),
          "T_amb": (290.0, 320.0)}
ep = EconParams(values=dict(ECON_TRUTH), C_ew=2000.0, power_map=PowerMap(coef=ECON_MAP, domain=domain), name="truth")
X = [[C2K(24.5), C2K(27.0), C2K(35.0), C2K(8.0), 0.008],
     [C2K(30.0), C2K(33.0), C2K(40.0), C2K(15.0), 0.010],
     [C2K(23.0), C2K(24.0), C2K(30.0), C2K(5.0), 0.007]]
for term in ("steady", "heat", "none"):
    ecfg = EconNMPCConfig(intervals=(5.0,) * 8, T_cab_min=C2K(22.0), T_cab_max=C2K(24.0),
                          compiled=False, terminal=term, solver="ipopt", tol=1e-10)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for x in X:
            mpc = EconNMPC(ep, ecfg)
            sol = mpc.solve(x, 12.0, C2K(30.0))
            assert sol.success, sol.status
            out["econ"].append({"terminal": term, "x": x, "v_veh": 12.0, "T_amb": C2K(30.0),
                                "intervals": list(ecfg.intervals), "T_cab_min": C2K(22.0),
                                "T_cab_max": C2K(24.0), "u": sol.u.tolist(),
                                "terminal_prices": sol.terminal_prices.tolist(),
                                "objective": sol.objective, "energy_J": sol.energy_J})
out["recorded_from"] = "acid/mpc/nmpc.py and econ_nmpc.py at 2876781 (before the one OCP builder), CasADi-hosted solvers, tol 1e-10"
json.dump(out, open("tests/references/ocp_first_moves.json", "w"), indent=1)
print(len(out["paper"]), len(out["econ"]))
