"""The claims registry: one home for the paper's numbers, verdicts derived from it alone."""

from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path

import pytest

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
from acid.params import paper
from acid.pipeline import StageOutcome
from acid.report.numbers import format_number
from acid.reproduce import ReproduceOptions, write_outputs
from acid.stage_results import (
    CavComparisonSummary,
    CavStudyStage,
    ChannelErrors,
    ClosedLoopSummary,
    Estimate,
    FitStage,
    MpcStage,
    Savings,
    StudyResults,
    SweepStage,
    TimingSummary,
    ValidationStage,
)


# ------------------------------------------------------------- synthetic stage results
def _sweep(duration_s=TABLE_I.duration_s, scale=1.01) -> SweepStage:
    E = tuple(scale * e for e in TABLE_I.energy_MJ)
    km = tuple(math.nan if v == 0 else e / (v * duration_s / 1000.0)
               for v, e in zip(TABLE_I.speeds_mps, E, strict=True))
    return SweepStage(speeds_mps=TABLE_I.speeds_mps, duration_s=duration_s, energy_MJ=E,
                      energy_MJ_per_km=km, ratio_last_first=E[-1] / E[0],
                      max_energy_step_MJ=max(b - a for a, b in zip(E, E[1:], strict=False)),
                      efficiency_gain_pct=100 * (E[0] / E[-1] - 1))


def _fit() -> FitStage:
    names = [f"gamma{i}" for i in range(1, 8)] + [f"tau{i}" for i in range(1, 4)] + \
        [f"beta{i}" for i in range(1, 4)]
    theta = paper().theta * 0.9
    return FitStage(method="oe", covariance="hac", gamma=tuple(theta[:7]),
                    tau=tuple(theta[7:10]), beta=tuple(theta[10:]),
                    parameters={n: Estimate(v, 0.01, v - 0.02, v + 0.02)
                                for n, v in zip(names, theta, strict=True)},
                    ls_gamma=tuple(theta[:7]), ls_tau=tuple(theta[7:10]),
                    fit_percent_one_step={"T_cab": 98.0}, fit_percent_simulation={"T_cab": 90.0})


def _validation(p90=1.0) -> ValidationStage:
    ch = ChannelErrors(rmse=0.5, mean_abs=0.4, median_abs=0.3, p90_abs=p90, p95_abs=p90 + 0.1,
                       max_abs=2.5, fit_percent=60.0)
    return ValidationStage(starts=STUDIES.validation_starts, horizon=STUDIES.validation_horizon,
                           horizon_s=1500.0, channels={c: ch for c in ("T_cab", "T_evap",
                                                                       "T_ain")})


def _mpc(saving=20.0, difference=0.008) -> MpcStage:
    loop = ClosedLoopSummary(passed=True, criterion="", energy_MJ=0.1, max_violation_K=0.0,
                             ride_error_K=0.0)
    cav = CavComparisonSummary(window_s=STUDIES.cav_window_s, case1_energy_MJ=0.026,
                               case2_energy_MJ=0.034, energy_difference_MJ=difference,
                               saving_pct=saving, speed_blind_saving_pct=saving - 1.0,
                               saving_from_speed_pct=1.0, T_cab_end_difference_K=2.0)
    return MpcStage(passed=True, model=loop, plant=dataclasses.replace(loop,
                                                                       max_violation_K=0.3),
                    cav=loop, cav_paper=cav, cav_periodic=dataclasses.replace(cav, saving_pct=-0.3),
                    cycles=4, timing=TimingSummary(median_ms=1.0, p95_ms=1.5, max_ms=3.0,
                                                   steps=50, passed=True, criterion=""))


def _cav() -> CavStudyStage:
    s = Savings(raw=-1e-10, corrected=0.0, tail_corrected=-1e-12)   # signed zeros
    return CavStudyStage(cycle="udds", savings_pct={"B": Savings(5.0, 2.0, 1.0), "C": s},
                         saving_from_speed_pct={"B": Savings(1.0, 1.0, 1.0), "C": s},
                         eta_cop0=4.9, eta_cop1_per_mps=0.03, eta_cop_r2=0.5)


def _results(**over) -> StudyResults:
    stages = {"sweep": _sweep(), "fit": _fit(), "validate": _validation(), "mpc": _mpc(),
              "cav": _cav()}
    stages.update(over)
    return StudyResults({k: v for k, v in stages.items() if v is not None})


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
    prints them, appear in no source file of acid or its CLI but the registry."""
    numbers = {f"{e:.2f}" for e in TABLE_I.energy_MJ}
    numbers |= {f"{e:.3f}" for e in TABLE_I.energy_MJ_per_km if e is not None}
    numbers |= {repr(abs(v)).removesuffix(".0") for v in MODEL.gamma + MODEL.tau + MODEL.beta}
    numbers |= {f"{STUDIES.cav_case1_MJ:.3f}", f"{STUDIES.cav_case2_MJ:.3f}"}
    pattern = re.compile(r"(?<![\w.])(" + "|".join(re.escape(n) for n in numbers)
                         + r")(?![\w.]*\d)")
    root = Path(acid.__file__).resolve().parent
    files = [p for p in sorted(root.rglob("*.py")) + sorted((root.parent / "cli").rglob("*.py"))
             if p.name != "claims.py"]
    hits = [f"{p.relative_to(root.parent)}:{i}: {line.strip()}" for p in files
            for i, line in enumerate(p.read_text().splitlines(), start=1)
            if pattern.search(line)]
    assert not hits, "paper numbers outside acid/claims.py:\n" + "\n".join(hits)


def test_parameter_preset_reads_the_registry():
    p = paper()
    assert p.gamma == MODEL.gamma and p.tau == MODEL.tau and p.beta == MODEL.beta
    assert p.c_p == claims_mod.TABLE_II.c_p and p.Ts == claims_mod.TABLE_II.Ts


# ------------------------------------------------------------------------ the verdicts
def test_verdicts_follow_the_rules_of_the_registry():
    v = _by_id(evaluate(_results()))
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
    v = _by_id(evaluate(_results(sweep=_sweep(duration_s=300.0), validate=_validation(5.0),
                                 mpc=None)))
    e0 = v["table1.energy.0mps"]
    assert e0.verdict is Verdict.NOT_COMPARABLE and "duration_s = 300" in e0.reason
    assert v["table1.falls_with_speed"].verdict is Verdict.DIRECTION   # needs no 600 s
    assert v["validation.T_ain"].verdict is Verdict.DISAGREES
    assert v["cav.saving"].verdict is Verdict.NOT_MEASURED
    assert "'mpc' did not run" in v["cav.saving"].reason


def test_energy_row_and_saving_row_cannot_contradict_each_other():
    """A saving that agrees while Case 1 uses *more* energy is flagged, not printed."""
    v = evaluate(_results(mpc=_mpc(saving=9.0, difference=-0.001)))
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
    v = _by_id(evaluate(_results()))
    g1 = v["identification.gamma1"]
    assert "±" in g1.acid_text and "[" in g1.acid_text
    assert v["cycle.C.raw"].acid_text == "0.00 %"
    assert format_number(-1e-10, ".2f") == "0.00" and format_number(-0.004, "+.2f") == "0.00"
    assert format_number(-0.01, ".2f") == "-0.01" and format_number(math.nan) == "n/a"


# ------------------------------------------------ summary.json and the headline table
def _outcomes(tmp_path, results: StudyResults) -> dict[str, StageOutcome]:
    out = {}
    for name, r in results.by_stage.items():
        d = tmp_path / "stages" / name
        d.mkdir(parents=True)
        out[name] = StageOutcome(name, name, d, r.to_json_dict(), 0.1, False, "k")
    return out


def _summary(tmp_path, results: StudyResults) -> dict:
    _, path, _ = write_outputs(tmp_path, _outcomes(tmp_path, results), ReproduceOptions(), 1.0)
    return json.loads(path.read_text())


def test_summary_verdicts_are_derived_from_the_registry(tmp_path, monkeypatch):
    """Changing one tolerance in the registry changes that verdict in summary.json."""
    before = _summary(tmp_path / "a", _results())
    items = {i["id"]: i for i in before["claims"]["items"]}
    assert items["table1.energy.0mps"]["verdict"] == "agrees"
    assert items["table1.energy.0mps"]["rule_text"] == "within 5 %"

    tight = claim("table1.energy.0mps")
    tight = dataclasses.replace(tight, rule=Within(rel=0.001))
    monkeypatch.setattr(claims_mod, "CLAIMS", tuple(tight if c.id == tight.id else c
                                                    for c in CLAIMS))
    after = _summary(tmp_path / "b", _results())
    items = {i["id"]: i for i in after["claims"]["items"]}
    assert items["table1.energy.0mps"]["verdict"] == "disagrees"
    assert items["table1.energy.0mps"]["rule_text"] == "within 0.1 %"
    assert after["claims"]["counts"]["disagrees"] == before["claims"]["counts"]["disagrees"] + 1


def test_summary_round_trips_the_typed_stage_results(tmp_path):
    s = _summary(tmp_path, _results())
    back = StudyResults.from_summaries({k: v["summary"] for k, v in s["stages"].items()})
    assert back.get(SweepStage) == _sweep() and back.get(FitStage) == _fit()
    assert back.get(MpcStage) == _mpc()
    re_judged = [v.to_json_dict()["verdict"] for v in evaluate(back)]
    assert re_judged == [i["verdict"] for i in s["claims"]["items"]]


def test_headline_markdown_is_rendered_from_summary_json(tmp_path):
    md = headline_markdown(_summary(tmp_path, _results()))
    lines = md.splitlines()
    assert lines[0] == "| result | paper | acid | verdict |"
    row = next(line for line in lines if line.startswith("| Table I: A/C energy"))
    assert "1.33 MJ" in row and "agrees (each within 5 %)" in row
    assert "| CAV saving | 9 % | 20.0 % | disagrees (rule: within 50 %) |" in md
    assert re.search(r"\d+ claims agree, \d+ agree in direction only, \d+ disagree", md)


def test_claims_command_prints_the_headline_table(tmp_path, capsys):
    s = _summary(tmp_path, _results())
    (tmp_path / "s.json").write_text(json.dumps(s))
    assert claims_mod.main([str(tmp_path / "s.json")]) == 0
    assert capsys.readouterr().out == headline_markdown(s)
    assert claims_mod.main([str(tmp_path / "missing.json")]) == 2
    assert claims_mod.main([]) == 0
    assert "table1.energy.0mps" in capsys.readouterr().out
