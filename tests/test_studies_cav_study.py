"""acid.studies.cav_study (where the energy is) and ``acid cav-study``."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.control.econ.nmpc import EconNMPCConfig
from acid.errors import ConfigError
from acid.models.params import paper
from acid.plant import make_plant
from acid.studies.cav_study import (
    CONTROLLERS,
    PLAN_VARIANTS,
    StudyConfig,
    initial_keys,
    plant_state,
    study_cycle,
    tune_mean,
)
from acid_cli.main import app

runner = CliRunner()
SHORT = StudyConfig(econ=EconNMPCConfig(intervals=(5.0,) * 6, compiled=False), warmup_s=1800.0,
                    modifier_hold_s=1800.0, tol_K=0.02, max_iter=8,
                    tail_s=120.0, stopgo_s=240.0)


@pytest.fixture(scope="module")
def study(econ_hifi_fit):
    return study_cycle(paper(), econ_hifi_fit.params, "stopgo", SHORT,
                       lambda: make_plant("hifi"))


def test_every_controller_ran_on_the_same_cycle(study):
    assert set(study.results) == set(CONTROLLERS)
    n = study.scenario.n
    for key, r in study.results.items():
        run = r.run
        assert run.n == n and np.all(np.isfinite(run.P_comp))
        assert r.energy_J == pytest.approx(float(np.sum(run.P_comp + run.P_bl)) * run.Ts)
        assert not run.fallback.any(), key
        assert r.tail_corrected_J == pytest.approx(r.energy_J + r.tail_end_J - r.tail_start_J)


def test_same_start_and_equal_mean_cabin_temperature(study):
    for key in ("A", "B", "D", "E", "P", "F"):
        run = study.results[key].run
        assert run.start == study.start_state
        assert run.T_cab[0] == pytest.approx(study.start_state["T_cab"])
    # the full plant state is carried, filtered by the plant's accepted keys
    assert set(study.start_state) == set(initial_keys(make_plant("hifi")))
    for key in ("A", "D", "E", "P", "F"):
        assert abs(study.results[key].run.mean_T_cab - study.target_mean_K) <= 0.05, key
    assert study.target_mean_K == pytest.approx(study.results["B"].run.mean_T_cab)


def test_savings_gaps_and_preview_share_are_what_they_say(study):
    A, E, D, F, bd = (study.results[k].tail_corrected_J for k in ("A", "E", "D", "F", "plan"))
    assert study.saving_pct("E") == pytest.approx(100 * (A - E) / A)
    assert study.saving_pct("E", ref="F") == pytest.approx(100 * (F - E) / F)
    assert study.gap_to_best_plan_pct("E") == pytest.approx(100 * (E - bd) / bd)
    assert study.preview_share_points == pytest.approx(study.saving_pct("E")
                                                       - study.saving_pct("D"))
    raw = study.results["E"].energy_J
    assert study.saving_pct("E", corrected=False) == pytest.approx(
        100 * (study.results["A"].energy_J - raw) / study.results["A"].energy_J)


def test_the_second_charge_is_fs_pi_loops_run_from_each_state(study):
    # an independent replay of the second continuation from E's end state: the plant's PI
    # loops at F's coil set-point and the target, the cycle's mean speed, as long as the tail
    from acid.control.pi_baselines import PlantPI
    from acid.psychro import P_ATM
    from acid.studies.cav_study import Scenario, run_on_plant

    E, F = study.results["E"], study.results["F"]
    sc, n_t = study.scenario, int(round(SHORT.tail_s / study.scenario.Ts))
    loops = make_plant("hifi").cfg
    ctrl = PlantPI(loops, sc.Ts, study.target_mean_K, F.extra["coil_set_point_K"],
                   float(getattr(loops, "p_atm", P_ATM)))
    tail = Scenario(name="tail", v=np.full(n_t, float(np.mean(sc.v))),
                    T_amb=np.resize(sc.T_amb, n_t), Ts=sc.Ts)
    again = run_on_plant(lambda: make_plant("hifi"), ctrl, E.run.end, tail, "tail")
    assert E.pi_tail_end_J == pytest.approx(again.energy_J, rel=1e-12)
    assert E.pi_tail_start_J == pytest.approx(F.pi_tail_start_J)   # the common start
    e_pi = E.energy_J + E.pi_tail_end_J - E.pi_tail_start_J
    f_pi = F.energy_J + F.pi_tail_end_J - F.pi_tail_start_J
    vs_f = study.saving_pct("E", ref="F", pi_charge=True)
    assert vs_f == pytest.approx(100 * (f_pi - e_pi) / f_pi)
    assert study.charge_back_spread_points("E") == pytest.approx(
        abs(study.saving_pct("E", ref="F") - vs_f))
    d = study.to_json_dict()
    assert d["econ_vs_best_pi_pi_charge_pct"]["E"] == pytest.approx(vs_f)
    assert d["controllers"]["E"]["tail_corrected_energy_pi_MJ"] == pytest.approx(e_pi / 1e6)


def test_json_has_the_issue_keys(study):
    d = study.to_json_dict()
    json.dumps(d)
    for key in CONTROLLERS:
        c = d["controllers"][key]
        for field in ("energy_MJ", "saving_tail_corrected_pct", "saving_vs_best_pi_pct",
                      "saving_vs_best_pi_pi_charge_pct", "gap_to_best_plan_pct",
                      "best_plan_spread_pct", "in_rh_band",
                      "pmv_mean", "rh_mean_pct", "mean_T_cab_K", "max_T_cab_K"):
            assert field in c, (key, field)
        assert -3.0 < c["pmv_mean"] < 3.0 and 0.0 < c["rh_mean_pct"] < 100.0
        assert not any("bound" in f for f in c if f != "upper_bound_K"), key
    assert "preview_share_points" in d and "bound" not in d["controllers"]
    b = d["controllers"]["plan"]
    assert math.isfinite(b["model_energy_MJ"]) and b["band_vs_pinned_pct"] >= -1e-6
    assert set(b["variants"]) == set(PLAN_VARIANTS)   # the modifier adds the 4th
    assert b["best_variant"] in b["variants"]


def test_the_best_known_plan_is_the_least_matched_variant_and_its_spread_is_stated(study):
    b = study.results["plan"]
    matched = {k: v for k, v in b.extra["variants"].items() if v["matched"]}
    if matched:   # the plan is the least tail-corrected energy among matched variants
        best = min(matched.values(), key=lambda v: v["tail_corrected_energy_MJ"])
        assert b.tail_corrected_J / 1e6 == pytest.approx(best["tail_corrected_energy_MJ"])
    if len(matched) > 1:
        e = [v["tail_corrected_energy_MJ"] for v in matched.values()]
        assert study.plan_spread_pct == pytest.approx(100 * (max(e) - min(e)) / min(e))


def test_the_fixed_coil_search_keeps_its_best_point_and_the_reset_rule(study):
    F = study.results["F"]
    search = F.extra["coil_search"]
    assert len(search) >= 4
    lo, hi = F.extra["coil_range_K"]
    assert all(lo <= s["coil_set_point_K"] <= hi for s in search)
    inside = [s for s in search if not s["outside_rh_band"]]
    best = min(inside, key=lambda s: s["tail_corrected_energy_MJ"])
    assert F.extra["coil_set_point_K"] == pytest.approx(best["coil_set_point_K"])
    assert F.tail_corrected_J / 1e6 == pytest.approx(best["tail_corrected_energy_MJ"])
    assert np.ptp(F.run.T_evap_set) == 0.0            # a fixed coil
    P = study.results["P"]
    assert np.ptp(P.run.T_evap_set) > 1.0 and "coil set-point" in P.extra["coil_rule"]


def test_a_controller_outside_the_rh_band_is_marked_and_not_ranked(study):
    narrow = dataclasses.replace(study, rh_band=(0.0, 0.01))   # every cabin is above 1 %
    d = narrow.to_json_dict()
    assert d["ranking_in_rh_band"] == []
    for c in d["controllers"].values():
        assert c["in_rh_band"] is False and c["rank"] is None
        assert c["rh_status"] == "outside RH band"
    ranked = study.ranking()
    E = [study.results[k].tail_corrected_J for k in ranked]
    assert E == sorted(E) and set(ranked) <= set(CONTROLLERS)


def test_economic_nmpc_is_not_worse_than_the_paper_nmpc(study):
    # at equal comfort, optimising an identified power map should not cost more than the
    # paper's eq. 4 (1 % allowed for model error)
    for key in ("D", "E"):
        assert study.saving_pct(key) > -1.0, key
    plan = study.results["plan"]
    assert abs(plan.extra["replay_vs_model_pct"]) < 25.0


def test_initial_keys_come_from_the_plant():
    class Declared:
        INITIAL_KEYS = ("T_cab", "w_cab")

        def measure(self):
            return {"T_cab": 300.0, "w_cab": 0.008, "T_int": 301.0, "T_amb": 303.0}

    class Undeclared(Declared):
        INITIAL_KEYS = None

    assert plant_state(Declared()) == {"T_cab": 300.0, "w_cab": 0.008}
    assert initial_keys(Undeclared()) == ("T_cab", "w_cab", "T_int")


def test_tuning_hits_the_target_of_a_monotone_map():
    b, payload, hist = tune_mean(lambda b: (0.9 * b + 30.0, b), 300.0, 290.0, 310.0, 1e-4, 10)
    assert 0.9 * b + 30.0 == pytest.approx(300.0, abs=1e-4)
    assert payload == b and len(hist) <= 4


@pytest.mark.parametrize("kw", [{"horizon": 1}, {"T_low": 300.0, "T_high": 299.0},
                                {"tol_K": 0.2}, {"rh_band": (0.6, 0.3)},
                                {"coil_tol_K": 0.0}])
def test_study_config_rejects_bad_options(kw):
    with pytest.raises(ConfigError):
        StudyConfig(**kw)


def test_a_cycle_shorter_than_the_horizon_is_refused(econ_hifi_fit):
    cfg = StudyConfig(stopgo_s=100.0)   # 100 s < the default 120 s horizon
    with pytest.raises(ConfigError, match="shorter than the economic NMPC's horizon"):
        study_cycle(paper(), econ_hifi_fit.params, "stopgo", cfg, lambda: make_plant("hifi"))


# ------------------------------------------------------------------------------- CLI
@pytest.fixture(scope="module")
def econ_file(econ_hifi_fit, tmp_path_factory):
    return econ_hifi_fit.params.to_json(tmp_path_factory.mktemp("econ") / "econ.json")


@pytest.mark.slow
def test_cli_writes_json_and_figures(econ_file, tmp_path):
    # the shortest economic horizon (10 s), the coldest coil limit (4 degC: F's coil search
    # over 1 K, 4 tuned runs instead of 8 over 7 K) and no coil modifier (its steady holds and
    # the plan variant on its model): the command's wiring; the study itself, modifier
    # included, is checked on the ``study`` fixture
    out, js = tmp_path / "figs", tmp_path / "cav.json"
    res = runner.invoke(app, ["cav-study", "--cycle", "nycc", "--econ-params", str(econ_file),
                              "--econ-horizon", "10", "--warmup", "60", "--tail", "60",
                              "--coil-max", "4", "--no-econ-modifier", "--no-compiled",
                              "--out", str(out), "--json", str(js)])
    assert res.exit_code == 0, res.output
    d = json.loads(js.read_text())
    assert d["command"] == "cav-study" and set(d["cycles"]) == {"nycc"}
    controllers = d["cycles"]["nycc"]["controllers"]
    assert set(controllers) == set(CONTROLLERS)
    assert controllers["F"]["coil_range_C"] == pytest.approx([3.0, 4.0])   # --coil-max in degC
    plan = controllers["plan"]   # no modifier: no variant on its model (one may fail, named)
    tried = set(plan["variants"]) | set(plan.get("failed_variants", {}))
    assert tried == set(PLAN_VARIANTS) - {"cyclic_corrected_model"}, plan.get("failed_variants")
    assert (out / "cav_nycc.png").stat().st_size > 10_000
    assert (out / "energy_nycc.png").stat().st_size > 5_000


@pytest.mark.parametrize("args, fragments", [
    (["--cycle", "marsrover"], ("--cycle", "marsrover", "udds", "stopgo")),
    (["--cycle", "nycc", "--econ-horizon", "900"], ("nycc", "shorter", "horizon (900 s")),
    (["--t-low", "26", "--t-high", "22"], ("--t-low", "comfort band is empty")),
    (["--rh-max", "150"], ("--rh-max",)),
])
def test_cli_bad_input_is_one_line(econ_file, args, fragments):
    res = runner.invoke(app, ["cav-study", "--econ-params", str(econ_file), "--no-figures",
                              "--no-compiled", *args])
    assert res.exit_code == 2
    assert_one_line_error(res, *fragments)


def test_json_carries_the_engine_verdict(study):
    """cav-study's E-vs-F verdict is the engine's rule: one cycle is no verdict."""
    from acid.studies.cav_study import CavStudyResult
    from acid.studies.compare import UNRESOLVED

    d = CavStudyResult(SHORT, {"stopgo": study}, "paper", {}, 0.0).to_json_dict()
    json.dumps(d)
    vs = {v["candidate"]: v for v in d["verdicts"]}
    assert {"E (paper charge)", "E (pi charge)"} <= set(vs)
    for v in vs.values():
        assert v["baseline"] == "F" and v["word"] == UNRESOLVED and len(v["scenarios"]) == 1
    assert "acid compare" in d["verdict_rule"]
