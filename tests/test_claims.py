"""The claims registry: one home for the paper's numbers, verdicts derived from it alone."""

from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path

import pytest
from _claims import fit, mpc, results, summary_of, sweep, validation

import acid
import acid.claims as claims_mod
from acid.claims import (
    CLAIMS,
    MODEL,
    STUDIES,
    TABLE_I,
    AtMost,
    Claim,
    Measured,
    SameSign,
    Verdict,
    Within,
    claim,
    contradictions,
    evaluate,
    headline_markdown,
    validate_registry,
)
from acid.claims.results import FitStage, MpcStage, StudyResults, SweepStage
from acid.models.params import paper
from acid.numbers import format_number


def _by_id(verdicts):
    return {v.claim.id: v for v in verdicts}


# ------------------------------------------------------------------------ the registry
def test_registry_is_consistent_and_paths_name_declared_fields():
    validate_registry()
    assert len({c.id for c in CLAIMS}) == len(CLAIMS)
    bad = Claim("x", "s", "q", None, Measured(SweepStage, "energy_kJ[0]"),
                claims_mod.BeyondThePaper())
    with pytest.raises(ValueError, match="no field 'energy_kJ'"):
        validate_registry((*CLAIMS, bad))
    with pytest.raises(ValueError, match="unknown claim"):
        validate_registry((*CLAIMS, dataclasses.replace(CLAIMS[0], id="y",
                                                        implies=("nope",))))


def test_no_number_of_the_paper_is_written_outside_the_registry():
    """The paper's results (Table I, identified parameters, CAV energies), as the paper
    prints them, appear in no source file of acid or its CLI but acid/paper.py."""
    numbers = {f"{e:.2f}" for e in TABLE_I.energy_MJ}
    numbers |= {f"{e:.3f}" for e in TABLE_I.energy_MJ_per_km if e is not None}
    numbers |= {repr(abs(v)).removesuffix(".0") for v in MODEL.gamma + MODEL.tau + MODEL.beta}
    numbers |= {f"{STUDIES.cav_case1_MJ:.3f}", f"{STUDIES.cav_case2_MJ:.3f}"}
    pattern = re.compile(r"(?<![\w.])(" + "|".join(re.escape(n) for n in numbers)
                         + r")(?![\w.]*\d)")
    root = Path(acid.__file__).resolve().parent
    home = root / "paper.py"
    files = [p for p in sorted(root.rglob("*.py")) + sorted((root.parent / "cli").rglob("*.py"))
             if p != home]
    hits = [f"{p.relative_to(root.parent)}:{i}: {line.strip()}" for p in files
            for i, line in enumerate(p.read_text().splitlines(), start=1)
            if pattern.search(line)]
    assert not hits, "paper numbers outside acid/paper.py:\n" + "\n".join(hits)


def test_parameter_preset_reads_the_registry():
    p = paper()
    assert p.gamma == MODEL.gamma and p.tau == MODEL.tau and p.beta == MODEL.beta
    assert p.c_p == claims_mod.TABLE_II.c_p and p.Ts == claims_mod.TABLE_II.Ts


# ------------------------------------------------------------------------ the verdicts
def test_verdicts_follow_the_rules_of_the_registry():
    v = _by_id(evaluate(results()))
    assert v["table1.energy.0mps"].verdict is Verdict.AGREES          # 1 % off, rule 5 %
    assert v["table1.falls_with_speed"].verdict is Verdict.DIRECTION
    assert v["identification.gamma1"].verdict is Verdict.NOT_COMPARABLE
    assert v["validation.T_cab"].verdict is Verdict.AGREES            # p90 1 K <= 2 K
    assert v["cav.case1_energy"].verdict is Verdict.DISAGREES         # 0.026 vs 0.113 MJ
    assert v["cav.case1_below_case2"].verdict is Verdict.DIRECTION
    assert v["cav.saving"].verdict is Verdict.DISAGREES               # 20 % vs 9 % +- 50 %
    assert v["cav.periodic_saving"].verdict is Verdict.BEYOND
    assert v["nmpc.computation"].verdict is Verdict.AGREES
    assert contradictions(list(v.values())) == []


def test_comparability_conditions_and_missing_stages():
    v = _by_id(evaluate(results(sweep=sweep(duration_s=300.0), validate=validation(5.0),
                                 mpc=None)))
    e0 = v["table1.energy.0mps"]
    assert e0.verdict is Verdict.NOT_COMPARABLE and "duration_s = 300" in e0.reason
    assert v["table1.falls_with_speed"].verdict is Verdict.DIRECTION   # needs no 600 s
    assert v["validation.T_ain"].verdict is Verdict.DISAGREES
    assert v["cav.saving"].verdict is Verdict.NOT_MEASURED
    assert "'mpc' did not run" in v["cav.saving"].reason


def test_energy_row_and_saving_row_cannot_contradict_each_other():
    """A saving that agrees while Case 1 uses *more* energy is flagged, not printed."""
    v = evaluate(results(mpc=mpc(saving=9.0, difference=-0.001)))
    assert _by_id(v)["cav.saving"].verdict is Verdict.AGREES
    assert contradictions(v) == ["cav.saving agrees but cav.case1_below_case2, which it "
                                 "implies, disagrees"]


@pytest.mark.parametrize(("rule", "acid", "verdict"), [
    (Within(rel=0.1), 1.05, Verdict.AGREES), (Within(rel=0.1), 1.2, Verdict.DISAGREES),
    (Within(abs=0.3), 0.75, Verdict.AGREES), (AtMost(), 1.0, Verdict.AGREES),
    (AtMost(limit=0.5), 0.6, Verdict.DISAGREES), (SameSign("up"), 3.0, Verdict.DIRECTION),
    (SameSign("up"), -3.0, Verdict.DISAGREES), (SameSign("up", deadband=0.1), 0.05,
                                                Verdict.DISAGREES)])
def test_rules(rule, acid, verdict):
    assert rule.judge(1.0, acid)[0] is verdict


def test_estimates_carry_their_intervals_and_signed_zeros_print_as_zero():
    v = _by_id(evaluate(results()))
    g1 = v["identification.gamma1"]
    assert "±" in g1.acid_text and "[" in g1.acid_text
    assert v["energy.udds.preview_share"].acid_text == "0.00 points"
    assert format_number(-1e-10, ".2f") == "0.00" and format_number(-0.004, "+.2f") == "0.00"
    assert format_number(-0.01, ".2f") == "-0.01" and format_number(math.nan) == "n/a"


# ------------------------------------------------ summary.json and the headline table
def test_summary_verdicts_are_derived_from_the_registry(tmp_path, monkeypatch):
    """Changing one tolerance in the registry changes that verdict in summary.json."""
    before = summary_of(tmp_path / "a", results())
    items = {i["id"]: i for i in before["claims"]["items"]}
    assert items["table1.energy.0mps"]["verdict"] == "agrees"
    assert items["table1.energy.0mps"]["rule_text"] == "within 5 %"

    tight = claim("table1.energy.0mps")
    tight = dataclasses.replace(tight, rule=Within(rel=0.001))
    monkeypatch.setattr(claims_mod.registry, "CLAIMS", tuple(tight if c.id == tight.id else c
                                                             for c in CLAIMS))
    after = summary_of(tmp_path / "b", results())
    items = {i["id"]: i for i in after["claims"]["items"]}
    assert items["table1.energy.0mps"]["verdict"] == "disagrees"
    assert items["table1.energy.0mps"]["rule_text"] == "within 0.1 %"
    assert after["claims"]["counts"]["disagrees"] == before["claims"]["counts"]["disagrees"] + 1


def test_summary_round_trips_the_typed_stageresults(tmp_path):
    s = summary_of(tmp_path, results())
    back = StudyResults.from_summaries({k: v["summary"] for k, v in s["stages"].items()})
    assert back.get(SweepStage) == sweep() and back.get(FitStage) == fit()
    assert back.get(MpcStage) == mpc()
    re_judged = [v.to_json_dict()["verdict"] for v in evaluate(back)]
    assert re_judged == [i["verdict"] for i in s["claims"]["items"]]


def test_report_shows_sections_of_the_stages_that_ran(tmp_path):
    summary_of(tmp_path, results())
    html = (tmp_path / "report.html").read_text()
    assert "Where the energy is" in html and "Conclusion (from the numbers)" in html
    assert "the econ model beside the paper" in html
    assert 'data-claim="cav.saving"' in html and "-0.00" not in html
    summary_of(tmp_path / "b", results(cav=None))
    assert "Where the energy is" not in (tmp_path / "b" / "report.html").read_text()


def test_headline_markdown_is_rendered_from_summary_json(tmp_path):
    md = headline_markdown(summary_of(tmp_path, results()))
    lines = md.splitlines()
    assert lines[0] == "| result | paper | acid | verdict |"
    row = next(line for line in lines
               if line.startswith("| Table I on the paper vehicle: A/C energy"))
    assert "1.33 MJ" in row and "agrees (each within 5 %)" in row
    assert "| CAV saving | 9 % | 20.0 % | disagrees (rule: within 50 %) |" in md
    assert re.search(r"\d+ claims agree, \d+ agree in direction only, \d+ disagree", md)


def test_claims_command_prints_the_headline_table(tmp_path, capsys):
    s = summary_of(tmp_path, results())
    (tmp_path / "s.json").write_text(json.dumps(s))
    assert claims_mod.main([str(tmp_path / "s.json")]) == 0
    assert capsys.readouterr().out == headline_markdown(s)
    assert claims_mod.main([str(tmp_path / "missing.json")]) == 2
    assert claims_mod.main([]) == 0
    assert "table1.energy.0mps" in capsys.readouterr().out


# ------------------------------------------------ quick runs, one criterion per quantity
def test_a_quick_run_judges_only_the_stages_it_does_not_shorten(tmp_path):
    """Issue 21: a --quick run's shortened stages are "not judged (quick run)", values kept;
    its NMPC checks (the same scenarios as the study) are judged."""
    from acid.studies.reproduce import ReproduceOptions

    v = _by_id(evaluate(results(), quick=True))
    for cid in ("table1.energy.0mps", "table1.ratio", "validation.T_cab",
                "energy.udds.E.saving", "energy.sc03.E.gap_to_best_plan", "econ.power_map_rms"):
        assert v[cid].verdict is Verdict.NOT_JUDGED, cid
        assert "--quick" in v[cid].reason and math.isfinite(v[cid].value)
    assert v["identification.gamma1"].verdict is Verdict.NOT_COMPARABLE
    assert v["nmpc.plant.violation"].verdict is Verdict.AGREES
    assert v["cav.saving"].verdict is Verdict.DISAGREES
    # the same results as a full run: verdicts
    full = _by_id(evaluate(results()))
    assert full["table1.ratio"].verdict is Verdict.AGREES
    assert full["energy.udds.E.saving"].verdict is Verdict.BEYOND

    s = summary_of(tmp_path, results(), ReproduceOptions.quick())
    assert s["mode"] == "quick"
    items = {i["id"]: i for i in s["claims"]["items"]}
    assert items["energy.udds.E.saving"]["verdict"] == "not judged (quick run)"
    assert s["claims"]["counts"]["not judged (quick run)"] >= 30
    md = headline_markdown(s)
    row = next(line for line in md.splitlines() if "economic NMPC with preview" in line)
    assert row.rstrip(" |").split("| ")[-1].startswith("not judged (quick run)")
    assert "not judged (quick run)" in md.splitlines()[-1]
    html = (tmp_path / "report.html").read_text()
    assert "Not judged (quick run)" in html and "Conclusion (from the numbers)" not in html
    assert summary_of(tmp_path / "full", results())["mode"] == "full"


def test_the_plant_violation_has_one_criterion_for_the_claim_and_mpc_check():
    """Issue 21: a 0.187 K avoidable violation is not "agrees" in the report while acid
    mpc-check calls it FAIL: both read the registry's limit."""
    from acid.claims import judge_value
    from acid.claims.registry import PLANT_VIOLATION_TOL_K
    from acid.studies.mpc_check import scenarios

    assert scenarios.PLANT_TOL_K == claim("nmpc.plant.violation").rule.limit
    assert scenarios.PLANT_TOL_K == PLANT_VIOLATION_TOL_K
    assert scenarios.MODEL_TOL_K == claim("nmpc.model.violation").rule.limit
    assert claim("nmpc.plant.violation").measured.path == "plant.max_avoidable_violation_K"
    v = _by_id(evaluate(results(mpc=mpc(avoidable=0.187))))
    assert v["nmpc.plant.violation"].verdict is Verdict.DISAGREES
    assert judge_value("nmpc.plant.violation", 0.187)[0] is Verdict.DISAGREES
    assert not 0.187 <= scenarios.PLANT_TOL_K  # mpc-check's scenario (b) criterion: FAIL
    assert judge_value("nmpc.plant.violation", 0.03)[0] is Verdict.AGREES


def test_table_i_is_judged_on_the_paper_vehicle_with_the_default_beside(tmp_path):
    v = _by_id(evaluate(results()))
    assert "paper vehicle" in claim("table1.energy.0mps").note
    d = v["table1.default_vehicle.ratio"]
    assert d.verdict is Verdict.BEYOND and d.value == pytest.approx(sweep().beside_ratio_last_first)
    summary_of(tmp_path, results())
    html = (tmp_path / "report.html").read_text()
    assert "Table I: the paper vehicle and acid&#x27;s default vehicle" in html
    assert "not exhaustive" in html and "capacity-limited compressor" in html
