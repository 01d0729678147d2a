"""The report opens with the energy answer: the comparison engine's verdicts on held-out
scenarios, each with its interval, before the figures; the typed stage result round-trips."""

from __future__ import annotations

import math

from acid.claims.results import EngineStage, StudyResults, engine_key
from acid.report.html import Report, render_report
from acid.report.sections import sections_for
from acid.studies import compare as cmp
from acid.units import C2K


def _result() -> cmp.CompareResult:
    sset = cmp.default_set(("udds", "sc03", "hwfet", "us06", "stopgo"))
    names = [s.name for s in sset.held_out]
    base = [1.0e6, 0.5e6, 0.6e6, 0.25e6, 0.35e6]
    vs = (cmp.verdict("E", "F", names, [0.99 * b for b in base[:3]] + base[3:], base, seed=0,
                      n_boot=500),
          cmp.verdict("F", "own", names, base, [1.03 * b for b in base], seed=0, n_boot=500))
    runs = tuple(cmp.PeriodicRun(n, "E", 30.0, 1.0, 0.0, 0.4, C2K(24.0), 4, True, 0.0, 1.0,
                                 extrapolated=("Q_e",) if i < 2 else ())
                 for i, n in enumerate(names))
    return cmp.CompareResult(sset, 0.0, (), {"F": C2K(8.0), "E": 30.0, "own": math.nan},
                             runs, vs, {"econ_ref_offset_K": 0.07})


def test_engine_stage_round_trips_and_keys_its_savings():
    st = EngineStage.of(_result())
    again = EngineStage.from_json_dict(st.to_json_dict())
    assert again == st
    assert set(st.savings) == {engine_key("E", "F"), "F_vs_own"}
    e = st.savings["E_vs_F"]
    assert e.ci95_low <= e.value <= e.ci95_high
    assert st.extrapolated == {"E": tuple(sorted(st.held_out[:2]))}


def test_the_energy_answer_comes_first_with_every_verdict_and_its_interval():
    st = EngineStage.of(_result())
    secs = sections_for(StudyResults({"engine": st}))
    sec = next(s for s in secs if s.title.startswith("The energy answer"))
    assert sec.lead
    for v in st.verdicts:   # each verdict's word beside both of its intervals
        row = next(r for r in sec.rows if r[:2] == (v.candidate, v.baseline))
        assert v.word in row and row[4].startswith("[") and row[5].startswith("[")
    text = " ".join(sec.paragraphs)
    assert "held-out" in text and all(n in text for n in st.held_out + st.training)
    assert "left its econ model's identification data" in text
    html = render_report(Report(title="t", verdicts=(), sections=tuple(secs)))
    assert html.index("The energy answer") < html.index('id=figures')


def test_the_best_known_operation_is_the_cheaper_of_the_plan_and_F():
    res = _result()
    name = res.scenarios.held_out[0].name
    F = cmp.PeriodicRun(name, "F", C2K(8.0), 1.0e6, 0.0, 0.4, C2K(24.0), 4, True, 0.0, 1.0)
    res = cmp.CompareResult(res.scenarios, 0.0, (), res.tuned, res.held_out + (F,),
                            res.verdicts, res.settings)
    plan = {"scenario": name, "spread_pct": 0.4,
            "winner": {"formulation": "shooting", "start": "constant",
                       "replay_energy_kJ": 1012.0, "replay_mean_T_cab_degC": 24.01},
            "by_formulation": {"direct": {"replay_energy_kJ": 1016.0},
                               "shooting": {"replay_energy_kJ": 1012.0}},
            "E_at_F_kJ": 1005.0}
    st = EngineStage.of(res, {"udds": plan})
    b = st.best_plans["udds"]
    assert b.best == "F" and b.best_kJ == 1000.0
    assert abs(b.E_gap_pct - 0.5) < 1e-9 and abs(b.gaps_pct["plan"] - 1.2) < 1e-9
    cheaper = EngineStage.of(res, {"udds": {**plan, "E_at_F_kJ": 990.0}}).best_plans["udds"]
    assert cheaper.best == "E" and cheaper.E_gap_pct == 0.0   # E's operation is then the best
    assert EngineStage.from_json_dict(st.to_json_dict()) == st
    sec = next(s for s in sections_for(StudyResults({"engine": st}))
               if s.title.startswith("The energy answer"))
    assert "the best known operation is F" in " ".join(sec.paragraphs)
