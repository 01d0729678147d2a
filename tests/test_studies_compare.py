"""Independent cross-checks of the comparison engine (short stop-and-go cycles)."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from acid.studies import compare as cmp
from acid.units import C2K

SG = 160.0  # a two-period stop-and-go (80 s alternation): cheap passes


#: looser periodic tolerances and a shorter charge-back tail (600 s, not 2400 s) than the
#: default, to keep the tests fast (``--quick``'s settings; the full size runs in the README's
#: ``acid reproduce``)
S = cmp.RunSettings(tol_K=0.05, tol_w=1e-4, tol_E=2e-3, max_passes=30, tail_s=600.0)


def _sc(t_amb_c: float, **kw) -> cmp.Scenario:
    kw.setdefault("soak_K", C2K(25.0))
    return cmp.Scenario("stopgo", C2K(t_amb_c), stopgo_s=SG, **kw)


AMBIENTS = (28.0, 29.0, 30.0, 31.0, 32.0)


@pytest.fixture(scope="module")
def coils():
    """Fixed coils at 3 and 10 degC on five ambients (periodic steady state)."""
    return {c: [cmp.periodic_run(_sc(a), "F", C2K(c), settings=S).energy_J for a in AMBIENTS]
            for c in (3.0, 10.0)}


def test_a_controller_against_itself_is_no_resolvable_difference(coils):
    again = cmp.periodic_run(_sc(AMBIENTS[0]), "F", C2K(10.0), settings=S).energy_J
    assert again == coils[10.0][0]                                  # runs are deterministic
    v = cmp.verdict("F", "F", [str(a) for a in AMBIENTS], coils[10.0], coils[10.0], seed=1)
    assert v.word == cmp.NONE
    assert v.boot_lo <= 0.0 <= v.boot_hi


def test_a_clearly_worse_controller_costs(coils):
    names = [str(a) for a in AMBIENTS]
    v = cmp.verdict("F3", "F10", names, coils[3.0], coils[10.0], seed=1)
    assert v.word == cmp.COSTS, v.summary()
    assert v.boot_hi < 0.0 and v.t_hi < 0.0
    assert cmp.verdict("F10", "F3", names, coils[10.0], coils[3.0]).word == cmp.SAVES


def test_fewer_than_the_minimum_is_not_resolved():
    v = cmp.verdict("a", "b", ["1", "2", "3"], [1.0, 1.0, 1.0], [2.0, 2.1, 2.2])
    assert v.word == cmp.UNRESOLVED
    assert cmp.verdict("a", "b", list("12345"), [1.0] * 5,
                       [2.0, 2.1, 2.2, 2.3, 2.4]).word == cmp.SAVES


def test_bootstrap_is_seeded():
    d = np.random.default_rng(3).normal(0.1, 1.0, 12)
    assert cmp.paired_bootstrap(d, 7, 2000) == cmp.paired_bootstrap(d, 7, 2000)
    assert cmp.paired_bootstrap(d, 7, 2000) != cmp.paired_bootstrap(d, 8, 2000)


def test_periodic_state_converges_and_forgets_the_soak():
    hot = cmp.periodic_run(_sc(32.0, soak_K=None), "F", C2K(8.0))  # 40 degC start
    cool = cmp.periodic_run(_sc(32.0, soak_K=C2K(24.0)), "F", C2K(8.0))
    assert hot.converged and cool.converged and hot.passes >= 3
    assert hot.first_pass_J > 1.5 * hot.energy_J       # the pull-down is not in the figure
    assert abs(hot.energy_J - cool.energy_J) / hot.energy_J < 2e-3
    assert abs(hot.mean_T_cab - cool.mean_T_cab) < 0.01


def test_F_is_the_plant_own_loops_and_not_dearer_than_them():
    """F at the plant's configured coil is the plant's own loops; F's tuned coil at equal or
    better comfort costs no more than they do."""
    sc = _sc(34.0)
    own = cmp.periodic_run(sc, "own", math.nan, settings=S)
    coil = sc.plant_config().T_ew_set
    same = cmp.periodic_run(sc, "F", coil, settings=S)
    assert same.energy_J == pytest.approx(own.energy_J, rel=1e-9)
    warm = cmp.periodic_run(sc, "F", C2K(9.0), settings=S)
    assert warm.discomfort_Kmin <= own.discomfort_Kmin + 1e-9
    assert warm.energy_J < own.energy_J


def test_tune_knob_reads_the_front_at_the_level():
    P = cmp.FrontPoint
    pts = [P("F", 1.0, 10.0, 0.0, 0.4), P("F", 2.0, 9.0, 0.0, 0.4), P("F", 3.0, 8.0, 2.0, 0.4)]
    assert cmp.tune_knob(pts, 1.0) == pytest.approx(2.5)
    assert cmp.tune_knob(pts, 0.0) == pytest.approx(2.0)
    assert cmp.tune_knob(pts, 5.0) == pytest.approx(3.0)


def test_split_is_deterministic_and_covers_every_cycle():
    a = cmp.default_set(("udds", "stopgo"), (30.0, 38.0), seed=4)
    assert a == cmp.default_set(("udds", "stopgo"), (30.0, 38.0), seed=4)
    for c in ("udds", "stopgo"):
        assert [s.cycle for s in a.training].count(c) == 1
        assert [s.cycle for s in a.held_out].count(c) == 1
    assert not {s.name for s in a.training} & {s.name for s in a.held_out}


def test_compare_result_round_trips_json():
    sset = cmp.ScenarioSet((_sc(30.0),), (_sc(36.0),), "by hand")
    fams = (cmp.Family("F", "fixed", "coil", (C2K(6.0), C2K(10.0))),
            cmp.Family("own", "own", "none", (math.nan,)))
    r = cmp.compare(sset, fams, S, n_boot=200)
    assert r.verdicts and all(v.word == cmp.UNRESOLVED for v in r.verdicts)
    back = cmp.CompareResult.from_dict(json.loads(r.to_json()))
    assert back.to_dict() == r.to_dict()
    assert "held out: stopgo@36C" in r.summary() and "CompareResult(" in repr(r)
    assert "not resolved" in repr(r.verdicts[0])
    # the envelope's record survives JSON
    off = dataclasses.replace(r, held_out=(dataclasses.replace(r.held_out[0],
                                                               extrapolated=("Q_e", "T_evap")),))
    assert cmp.CompareResult.from_dict(json.loads(off.to_json())).held_out[0].extrapolated == (
        "Q_e", "T_evap")


def test_a_saving_bought_with_comfort_is_not_read_as_one():
    names, base = list("12345"), [2.0, 2.1, 2.2, 2.3, 2.4]
    assert cmp.verdict("a", "b", names, [1.0] * 5, base).word == cmp.SAVES
    assert cmp.verdict("a", "b", names, [1.0] * 5, base, T_cab_gap_K=0.3).word == cmp.UNEQUAL
    assert cmp.verdict("a", "b", names, [1.0] * 5, base,
                       discomfort_gap_Kmin=2.0).word == cmp.UNEQUAL
    assert cmp.verdict("b", "a", names, base, [1.0] * 5, T_cab_gap_K=0.3).word == cmp.COSTS


def test_single_pass_is_charged_back_under_both_conventions():
    """From a 40 degC soak the first pass carries the pull-down; charged by either common
    continuation (tail(end) - tail(start)) it lands near the periodic figure, not 3x it."""
    s = cmp.RunSettings(tol_K=0.05, tol_w=1e-4, tol_E=2e-3, max_passes=30, tail_s=600.0)
    hot = cmp.periodic_run(_sc(32.0, soak_K=None), "F", C2K(8.0), s, charge=True)
    assert hot.first_pass_J > 3.0 * hot.energy_J
    for charge in cmp.CHARGES:
        e = hot.single_charged_J(charge)
        assert abs(e - hot.energy_J) / hot.energy_J < 0.3, (charge, e, hot.energy_J)
    assert math.isnan(cmp.periodic_run(_sc(32.0), "F", C2K(8.0), S).single_own_J)


def test_verdict_json_has_the_fields_of_every_acid_verdict():
    """compare's verdict carries the field names heating-control and sweep write
    (acid.studies.verdict.Verdict) with the same numbers, and reads back."""
    from acid.studies.verdict import paired_verdict

    e_b = [2.0, 2.1, 2.2, 2.3, 2.4]
    e_c = [1.0, 1.2, 1.1, 1.3, 1.0]
    v = cmp.verdict("a", "b", list("12345"), e_c, e_b)
    d = v.to_dict()
    s = [100 * (b - c) / b for b, c in zip(e_b, e_c, strict=True)]
    ref = paired_verdict(s, decide="both").to_dict()
    for k in ("n", "mean", "lo", "hi", "boot_lo", "boot_hi", "level", "words"):
        assert d[k] == (pytest.approx(ref[k]) if isinstance(ref[k], float) else ref[k]), k
    assert cmp.Verdict.from_dict(json.loads(json.dumps(d))) == v
def _run(E: float, T: float, Kmin: float = 0.0) -> cmp.PeriodicRun:
    return cmp.PeriodicRun("s", "Fs", C2K(7.0), E, Kmin, 0.4, T, 3, True, 0.0, E)


def test_matching_interpolates_energy_to_the_baseline_mean_cabin_temperature():
    at, lowered = _run(1.00e6, C2K(24.10)), _run(1.06e6, C2K(23.80), Kmin=0.3)
    m = cmp.match_to_mean(at, lowered, C2K(24.00))
    assert m.mean_T_cab == C2K(24.00)
    assert m.energy_J == pytest.approx(1.02e6, rel=1e-12)            # a third of the span
    assert m.discomfort_Kmin == pytest.approx(0.1, rel=1e-9)
    assert cmp.match_to_mean(at, _run(1.0e6, C2K(24.105)), C2K(24.0)) is None  # no slope
    assert cmp.match_to_mean(at, lowered, C2K(23.0)) is None       # too far outside


def test_a_warmer_family_is_judged_again_at_the_baseline_mean():
    """Fs holds the cabin warmer than F (acid's sampled PI): the matched verdict compares it
    at F's mean cabin temperature, and its energy there is above its unmatched energy."""
    sset = cmp.ScenarioSet((_sc(29.0),), tuple(_sc(a) for a in AMBIENTS), "test")
    fams = (cmp.Family("F", "F", "coil, K", (C2K(8.0),)),
            cmp.Family("Fs", "Fs", "coil, K", (C2K(8.0),)))
    res = cmp.compare(sset, fams, S, n_boot=2000)
    names = {v.candidate: v for v in res.verdicts}
    raw, matched = names["Fs"], names["Fs" + cmp.MATCHED]
    assert raw.T_cab_gap_K > 0.01                       # warmer than F, as measured
    assert abs(matched.T_cab_gap_K) < 1e-9 and len(matched.scenarios) >= 4
    assert matched.mean_pct < raw.mean_pct              # the warmer cabin was part of the saving
    assert {r.family for r in res.held_out} == {"F", "Fs", "Fs" + cmp.LOWERED}


def test_a_shared_start_carries_no_other_controller_loop_memory():
    """Every run on a scenario starts from F's periodic state; the plant's own loops at their
    configured coil must not run their first pass at F's coil (the low-load reset's
    effective set-point was restored with the state: F and own read 0.00 % single-pass)."""
    from acid.plant.hifi import LOOP_KEYS, physical_state

    sc = _sc(34.0)
    warm = cmp.periodic_run(sc, "F", C2K(10.0), settings=S)
    assert warm.end["T_evap_set_eff"] > C2K(9.0)          # F's loop memory is in the state
    assert not set(LOOP_KEYS) & set(physical_state(warm.end))
    own = cmp.periodic_run(sc, "own", math.nan, settings=S, start=warm.end)
    F = cmp.periodic_run(sc, "F", C2K(10.0), settings=S, start=warm.end)
    # the configured coil (3 degC) cools harder from the first pass: it costs more
    assert own.first_pass_J > 1.01 * F.first_pass_J
    assert own.energy_J > 1.01 * F.energy_J


def test_the_engine_pieces_in_any_order_give_the_same_verdicts(monkeypatch):
    """``acid reproduce`` runs the engine as one task per scenario and hands the runs over in
    its own order: tuning and verdicts must not depend on it. The runs are the direct
    comparison's own (recorded as they ran; that a run is deterministic is checked above):
    the pieces get them again, the task lists made afresh and reversed."""
    ran: list[tuple] = []

    def recorded(*task):
        ran.append((task, cmp.periodic_run(*task)))
        return ran[-1][1]

    monkeypatch.setattr(cmp, "_task", recorded)
    sset = cmp.default_set(("stopgo",), (30.0, 31.0, 32.0, 33.0), stopgo_s=SG)
    fams = tuple(f for f in cmp.families(quick=True, econ=False) if f.key in ("F", "own"))
    direct = cmp.compare(sset, fams, S, min_scenarios=2, n_boot=200)

    def runs_of(tasks):   # each task's recorded run, the task made again by the pieces
        out = []
        for t in tasks:
            (run,) = [r for task, r in ran if task == t]
            out.append(run)
        return out

    allsc = sset.training + sset.held_out
    starts = {sc.name: r.end for sc, r in zip(allsc, runs_of(cmp.warm_tasks(allsc, fams, S)),
                                              strict=True)}
    tasks = cmp.training_tasks(sset.training, fams, S, None, starts)[::-1]
    tuning = cmp.tune(fams, tasks, runs_of(tasks), S)
    assert tuning.tuned == direct.tuned and tuning.fronts == direct.fronts
    held = cmp.held_out_tasks(sset.held_out, fams, tuning, S, None, starts)[::-1]
    again = cmp.assemble(sset, fams, S, tuning, held, runs_of(held), min_scenarios=2,
                         n_boot=200)
    assert again.verdicts == direct.verdicts


def test_a_repeated_tail_is_taken_from_the_cache_and_equals_a_fresh_one():
    """Every family's run from a scenario's common start prices the same start state: the
    second call is a cache hit, and its energy equals the continuation run afresh."""
    sc, st = _sc(30.0), dataclasses.replace(S, tail_s=120.0)
    start = cmp.periodic_run(sc, "F", C2K(8.0), settings=S).end
    cmp._tail_J.cache_clear()
    first = cmp.tail_J(sc, start, "pi", st)
    again = cmp.tail_J(sc, dict(reversed(list(start.items()))), "pi", st)
    assert cmp._tail_J.cache_info().hits == 1
    fresh = cmp._tail_J.__wrapped__(sc, tuple(sorted(start.items())), "pi", st.T_set, st.tail_s)
    assert first == again == fresh
    other = cmp.tail_J(sc, {**start, "T_cab": start["T_cab"] + 1.0}, "pi", st)
    assert other != first                     # another state is no hit
    with pytest.raises(cmp.ConfigError):
        cmp.tail_J(sc, start, "nonsense", st)
