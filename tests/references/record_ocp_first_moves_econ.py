"""Re-record the econ rows from the replaced econ builder (``git show 2876781:acid/mpc/econ_nmpc.py > /tmp/old_econ_nmpc.py``), IPOPT without bound relaxation."""
import sys, json, warnings, importlib.util, numpy as np
sys.path.insert(0, "tests")
from conftest import ECON_TRUTH, ECON_MAP
from acid.econ.params import EconParams, PowerMap
spec = importlib.util.spec_from_file_location("old_econ", "/tmp/old_econ_nmpc.py"); old = importlib.util.module_from_spec(spec); sys.modules["old_econ"] = old; spec.loader.exec_module(old)
orig = old._make_solver
def ms(nlp, opts, cfg):
    opts = dict(opts); opts["ipopt"] = dict(opts["ipopt"], bound_relax_factor=0.0)
    return orig(nlp, opts, cfg)
old._make_solver = ms
domain = {"Q_e": (-500.0, 6000.0), "T_evap": (270.0, 290.0), "v_veh": (0.0, 35.0), "T_amb": (290.0, 320.0)}
ep = EconParams(values=dict(ECON_TRUTH), C_ew=2000.0, power_map=PowerMap(coef=ECON_MAP, domain=domain), name="truth")
path = "tests/references/ocp_first_moves.json"
R = json.load(open(path))
for r in R["econ"]:
    cfg = old.EconNMPCConfig(intervals=tuple(r["intervals"]), T_cab_min=r["T_cab_min"], T_cab_max=r["T_cab_max"], compiled=False, terminal=r["terminal"], solver="ipopt", tol=1e-10)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = old.EconNMPC(ep, cfg).solve(np.array(r["x"]), r["v_veh"], r["T_amb"])
    assert s.success
    r.update(u=s.u.tolist(), terminal_prices=s.terminal_prices.tolist(), objective=s.objective, energy_J=s.energy_J)
R["recorded_from"] = ("acid/mpc/nmpc.py and econ_nmpc.py at 2876781 (before the one OCP builder), CasADi-hosted "
                      "solvers, tol 1e-10; the econ rows with IPOPT's bound_relax_factor 0 (its default relaxes the "
                      "band edges, which the old builder put in lbg/ubg, by 3e-6 K)")
json.dump(R, open(path, "w"), indent=1)
