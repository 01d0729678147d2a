"""acid.control.pi_baselines (the PI baselines P and F of acid cav-study) and the RH band."""

from __future__ import annotations

import math

import numpy as np
import pytest

from acid.comfort import RH_BAND, rh_band_distance
from acid.control.pi_baselines import COIL_RANGE, CoilReset, PlantPI, golden_min
from acid.errors import ConfigError
from acid.plant import make_plant
from acid.plant.declared import econ_plant
from acid.psychro import humidity_ratio
from acid.units import C2K

RULE = CoilReset()


def test_the_reset_rule_runs_cold_on_a_pull_down_and_warm_when_settled():
    assert RULE.target(3.0, 0.4) == pytest.approx(RULE.T_cold)        # far above set-point
    assert RULE.target(0.0, 0.4) == pytest.approx(RULE.T_warm)        # settled
    mid = 0.5 * (RULE.e_cold + RULE.e_warm)
    assert RULE.target(mid, 0.4) == pytest.approx(0.5 * (RULE.T_cold + RULE.T_warm))
    # humidity overrides a settled cabin
    assert RULE.target(0.0, RULE.RH_high + RULE.RH_span) == pytest.approx(RULE.T_cold)
    assert RULE.T_cold < RULE.target(0.0, RULE.RH_high + 0.5 * RULE.RH_span) < RULE.T_warm
    assert "3 degC" in RULE.describe() and "11 degC" in RULE.describe()


def test_the_reset_is_rate_limited_and_the_blower_is_the_plants_pi():
    cfg = make_plant("hifi").cfg
    ctl = PlantPI(cfg, 5.0, C2K(24.0), RULE)
    meas = {"T_cab": C2K(24.0), "w_cab": humidity_ratio(C2K(24.0), 0.4)}
    sets = [ctl.make_step(meas, k)[1] for k in range(10)]
    steps = np.diff(np.concatenate(([RULE.T_cold], sets)))
    assert np.all(steps <= RULE.rate * 5.0 + 1e-12) and sets[-1] > sets[0]
    warm = PlantPI(cfg, 5.0, C2K(24.0), C2K(9.0))
    u_hot = warm.make_step({**meas, "T_cab": C2K(27.0)}, 0)
    u_cold = PlantPI(cfg, 5.0, C2K(24.0), C2K(9.0)).make_step({**meas, "T_cab": C2K(22.0)}, 0)
    assert u_hot[0] > u_cold[0] == pytest.approx(cfg.W_bl_min)       # more air when warm
    assert u_hot[1] == u_cold[1] == pytest.approx(C2K(9.0))


def test_bad_reset_rules_are_refused():
    with pytest.raises(ConfigError):
        CoilReset(T_cold=C2K(12.0), T_warm=C2K(11.0))


def test_golden_section_finds_the_minimum_and_ranks_the_band_first():
    x, payload, hist = golden_min(lambda x: ((x - 7.3) ** 2, x), 3.0, 12.0, tol=0.05,
                                  max_eval=30)
    assert x == pytest.approx(7.3, abs=0.05) and payload == x and len(hist) <= 30
    # infeasible above 9: the best admissible point is at the edge, not the free minimum
    x, _, _ = golden_min(lambda x: ((x > 9.0, (x - 10.5) ** 2), x), 3.0, 12.0, tol=0.05,
                         max_eval=30)
    assert 8.8 < x <= 9.0


def test_the_plant_holds_a_fixed_coil_and_a_warm_coil_costs_less_at_equal_cabin():
    cfg = make_plant("hifi").cfg
    power = {}
    for coil in (C2K(4.0), C2K(9.0)):
        plant = make_plant("hifi")
        plant.reset()
        ctl = PlantPI(cfg, plant.Ts, C2K(24.0), coil)
        rows = [plant.step(*ctl.make_step(plant.measure(), k), 8.8, T_amb=C2K(30.0))
                for k in range(720)]
        assert plant.measure()["T_cab"] == pytest.approx(C2K(24.0), abs=0.1)
        power[coil] = np.mean([r["P_comp"] + r["P_bl"] for r in rows[-120:]])
    assert power[C2K(9.0)] < power[C2K(4.0)]
    assert COIL_RANGE[0] <= C2K(4.0) and C2K(9.0) <= COIL_RANGE[1]


def test_rh_band_distance():
    lo, hi = RH_BAND
    assert rh_band_distance(0.5 * (lo + hi)) == 0.0
    assert rh_band_distance(hi + 0.05) == pytest.approx(0.05)
    assert rh_band_distance(lo - 0.02) == pytest.approx(0.02)
    assert math.isclose(rh_band_distance(0.9, (0.3, 0.95)), 0.0)


# ------------------------------------------------------------------------- in a sweep
PI_SPEC = {"title": "pi", "baseline": "nmpc",
           "defaults": {"cycle": 10.0, "duration_s": 150.0, "warmup_s": 600.0,
                        "tail_s": 60.0},
           "grid": {"ambient_C": [30.0]},
           "controllers": {"nmpc": {},
                           "P": {"type": "pi", "coil": "reset", "match": "nmpc"},
                           "F": {"type": "pi", "coil": "search", "match": "nmpc",
                                 "coil_tol_K": 2.0}}}


def test_the_pi_baselines_run_in_a_sweep_at_the_paper_nmpcs_mean(tmp_path):
    from acid.executor import InlineExecutor
    from acid.studies.sweep import run_sweep, spec_from_dict

    res = run_sweep(spec_from_dict(PI_SPEC, "pi spec"), tmp_path, executor=InlineExecutor(),
                    figures=False)
    t = res.table.set_index("controller")
    assert set(t["status"]) == {"ok"}, t["error"].tolist()
    for key in ("P", "F"):
        assert abs(t.loc[key, "mean_T_cab_C"] - t.loc["nmpc", "mean_T_cab_C"]) <= 0.05, key


@pytest.mark.parametrize("bad, message", [
    ({"coil": "magic"}, "coil = 'magic' unknown"),
    ({"coil": "search"}, "needs match"),
    ({"coil": "fixed", "T_evap_set_C": 20.0}, "T_evap_set_C"),
])
def test_bad_pi_options_are_refused_before_anything_runs(bad, message):
    from acid.studies.sweep import spec_from_dict

    spec = {**PI_SPEC, "controllers": {"nmpc": {}, "X": {"type": "pi", **bad}}}
    with pytest.raises(ConfigError, match=message):
        spec_from_dict(spec, "pi spec")


def test_the_prediction_sweep_example_loads():
    from pathlib import Path

    from acid.studies.sweep.spec import load_spec

    path = Path(__file__).resolve().parents[1] / "datasets/examples/sweep_prediction.toml"
    spec = load_spec(path)
    assert [c.label for c in spec.controllers] == ["nmpc", "F", "P", "econ", "plan"]
    assert len(spec.scenarios) == 8


# ------------------------------------------------------------------- coil modifier
def test_the_coil_modifier_changes_nothing_when_the_plant_is_the_model(econ_truth):
    """Modifier adaptation on a plant that is the model itself: the measured and predicted
    gradients agree, so the correction is (numerically) zero; a map with a wrong slope is
    pulled back toward the truth's optimum."""
    import dataclasses

    from acid.control.econ.modifier import coil_modifier, model_steady_power
    from acid.models.econ_params import MAP_TERMS
    from acid.plant.config import PlantConfig

    v, Ta, Tc = 8.8, C2K(30.0), C2K(24.0)
    _, T_true, _ = model_steady_power(econ_truth, v, Ta, Tc)
    assert COIL_RANGE[0] <= T_true <= COIL_RANGE[1]
    def truth():
        return econ_plant(econ_truth.theta_all)

    m = coil_modifier(econ_truth, truth, PlantConfig(), v, Ta, Tc, iterations=1, hold_s=5400.0)
    assert abs(m.delta_t_coef) < 2e-3
    j = MAP_TERMS.index("t")
    coef = list(econ_truth.power_map.coef)
    coef[j] += 0.02                      # a warm coil priced too high
    wrong = dataclasses.replace(econ_truth, power_map=dataclasses.replace(
        econ_truth.power_map, coef=tuple(coef)))
    _, T_wrong, _ = model_steady_power(wrong, v, Ta, Tc)
    assert T_wrong < T_true - 0.5
    fixed = coil_modifier(wrong, truth, PlantConfig(), v, Ta, Tc, iterations=2, hold_s=5400.0)
    assert abs(fixed.steps[-1]["T_star_K"] - T_true) < 0.5 * abs(T_wrong - T_true)
    assert fixed.delta_t_coef < 0 and fixed.to_json_dict()["model_optimal_coil_K"][0] == T_wrong
