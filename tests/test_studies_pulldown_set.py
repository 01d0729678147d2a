"""acid.studies.pulldown.cases: the pull-down set (training and held-out cases apart), the
engine's tuning rule on training runs, E matched to F's comfort, one pull-down run."""

from __future__ import annotations

import math

import pytest

from acid.studies.pulldown import cases
from acid.units import C2K


def _run(fam, knob, E, d, name="c"):
    return cases.CaseRun(name, fam, knob, E, E, d, d, 100.0, C2K(24.0))


def test_the_set_keeps_training_and_held_out_apart_and_in_the_declared_ranges():
    train = {tuple(t) for t in cases.TRAINING}
    held = {tuple(t) for t in cases.HELD_OUT}
    assert not train & held and len(held) >= 6      # the engine resolves from 5 pairs
    for _cycle, amb, soak, sun in train | held:
        assert 35.0 <= soak <= 45.0 and 28.0 <= amb <= 38.0 and 600.0 <= sun <= 1000.0
        assert soak > amb                            # a hot soak: a pull-down
    names = {cases.case_name(cases.case(*h)) for h in held}
    assert len(names) == len(held)                   # paired by name: no two alike
    sc = cases.case("sc03", 35.0, 45.0, 1000.0)
    assert sc.start()["T_cab"] == C2K(45.0) and sc.G_solar == 1000.0


def test_tuning_is_the_engines_rule_on_the_training_fronts():
    # two training cases; own's mean discomfort 8 K min is the level
    runs = [_run("own", math.nan, 100.0, 7.0), _run("own", math.nan, 100.0, 9.0)]
    for c, E, d in ((C2K(5.0), 99.0, 6.0), (C2K(7.0), 97.0, 10.0), (C2K(10.0), 95.0, 14.0)):
        runs += [_run("F", c, E, d), _run("F", c, E, d)]
    for w, E, d in ((30.0, 90.0, 12.0), (300.0, 96.0, 6.0), (3000.0, 98.0, 5.0)):
        runs += [_run("E", w, E, d), _run("E", w, E, d)]
    t = cases.tune_on(runs)
    assert t.level_Kmin == 8.0
    # F: 5 degC meets 8 K min, 7 degC is cheaper and does not: halfway in discomfort
    assert t.coil_K == pytest.approx(C2K(6.0))
    # E: 300 meets it, 30 is cheaper: a third of the way from 300 to 30
    assert t.weight == pytest.approx(300.0 - 270.0 / 3.0)


def test_e_is_matched_to_the_baselines_mean_cabin_by_the_engines_rule():
    def run(E, T_C):
        return cases.CaseRun("c", "E", 300.0, math.nan, E, 5.0, 5.0, 100.0, C2K(T_C))

    at, low = run(100.0, 24.4), run(104.0, 24.0)
    m = cases.matched(at, low, run(0.0, 24.1))
    assert m.charged_J == pytest.approx(103.0) and m.mean_T_cab == C2K(24.1)
    assert cases.matched(at, low, run(0.0, 24.75)) is not None   # inside one span out
    assert cases.matched(at, low, run(0.0, 25.0)) is None        # 1.5 spans out: refused
    assert cases.matched(at, run(104.0, 24.395), run(0.0, 24.1)) is None   # no slope


def test_a_pull_down_run_of_f_at_the_configured_coil_is_the_plants_own_loops():
    sc = cases.case("sc03", 35.0, 45.0, 1000.0)
    own = cases.run_case(sc, "own")
    coil = sc.plant_config().T_ew_set
    f = cases.run_case(sc, "F", coil)
    assert f.energy_J == pytest.approx(own.energy_J, rel=1e-9)
    # from 45 degC: minutes above the band, then 25 degC reached; the continuation charged
    assert 60.0 < own.time_to_reach_s < 600.0 and own.above_Kmin > 5.0
    assert own.charged_J > own.energy_J
    warmer = cases.run_case(cases.case("sc03", 35.0, 40.0, 1000.0), "F", C2K(7.0))
    hotter = cases.run_case(sc, "F", C2K(7.0))
    assert hotter.energy_J > warmer.energy_J and hotter.above_Kmin > warmer.above_Kmin
    with pytest.raises(Exception, match="unknown pull-down family"):
        cases.run_case(sc, "X")


def test_the_sets_json_is_strict_with_nan_knobs_unreached_comfort_and_unmatched_cases():
    import json

    from acid.studies.compare import verdict
    from acid_cli.pulldown import set_summary

    own = _run("own", math.nan, 100.0, 5.0)
    e = cases.CaseRun("c", "E", 300.0, 90.0, 95.0, 5.0, 5.0, math.inf, C2K(24.3))
    held = [{"case": "c", "own": own, "F": own, "E": e, "E_lowered": e,
             "E at F's T_cab": None}]
    res = {"tuning": cases.tune_on([own, _run("F", C2K(5.0), 1.0, 1.0),
                                    _run("E", 30.0, 1.0, 1.0)]),
           "held_out": held, "training": [own, e],
           "verdicts": {"E vs F": verdict("E", "F", ["c"], [95.0], [100.0]),
                        "E at F's T_cab vs F": None}, "unmatched": ["c"]}
    s = set_summary(res)
    text = json.dumps(s, allow_nan=False)                 # no NaN, no Infinity
    assert s["held_out"][0]["own"]["knob"] is None
    assert s["held_out"][0]["E"]["time_to_reach_s"] is None
    assert s["verdicts"]["E vs F"]["words"] == "not resolved" and "unmatched" in text
