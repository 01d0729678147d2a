"""``acid reproduce``'s heating stage (issue 25): independent of the other stages, its typed
result read back from JSON, the report's heating section with verdicts only where a criterion
is stated, and its figure."""

from __future__ import annotations

import json

import pytest

from acid.claims.results import HeatingStage, StudyResults
from acid.report.sections import sections_for
from acid.studies.reproduce import HEATING_YEAR, ReproduceOptions, build_stages, stage_heating


@pytest.fixture(scope="module")
def heating(tmp_path_factory):
    folder = tmp_path_factory.mktemp("heating")
    calls = []
    summary = stage_heating(folder, {}, HEATING_YEAR, lambda done, total: calls.append(done))
    return folder, json.loads(json.dumps(summary)), calls


def test_the_stage_depends_on_no_other_and_runs_in_both_sizes():
    for opts in (ReproduceOptions(), ReproduceOptions.quick()):
        st = {s.name: s for s in build_stages(opts)}
        assert st["heating"].depends == ()
        assert st["heating"].config == HEATING_YEAR


def test_typed_result_reads_back_with_credentials_and_the_year(heating):
    folder, summary, calls = heating
    r = StudyResults.from_summaries({"heating": summary}).get(HeatingStage)
    assert r is not None and calls and calls[-1] == 3
    groups = {c.group for c in r.checks}
    assert {"h", "i", "j", "l", "m"} <= groups and "k" not in groups  # no logs: not run
    assert r.passed == all(c.passed is not False for c in r.checks)
    # three ambients: heat pump and heater alone below the switch-over, the A/C above
    by = {(p.T_amb_C, p.heating): p for p in r.year}
    assert set(by) == {(-10.0, "heat pump"), (-10.0, "heater only"), (5.0, "heat pump"),
                       (5.0, "heater only"), (30.0, "-")}
    for t in (-10.0, 5.0):  # the heat pump spends less than the heater alone
        assert by[(t, "heat pump")].E_climate_kWh < by[(t, "heater only")].E_climate_kWh
        assert 0.0 < by[(t, "heat pump")].share < by[(t, "heater only")].share < 1.0
    assert (folder / "year_share.png").is_file()
    assert json.loads((folder / "figures.json").read_text())[0]["file"] == "year_share.png"


def test_section_gives_verdicts_only_where_a_criterion_is_stated(heating):
    _, summary, _ = heating
    results = StudyResults.from_summaries({"heating": summary})
    (sec,) = [s for s in sections_for(results) if s.title.startswith("Winter")]
    verdicts = {row[4] for row in sec.rows}
    year = [row for row in sec.rows if row[0] == "year"]
    assert len(year) == 5 and {row[4] for row in year} == {"information"}
    assert {row[4] for row in sec.rows if row[0] != "year"} <= {"pass", "FAIL"}
    assert verdicts <= {"pass", "FAIL", "information"}
    # a quick run does not shorten this stage: it is judged there too
    (quick,) = [s for s in sections_for(results, quick=True) if s.title.startswith("Winter")]
    assert not quick.paragraphs[0].startswith("Not judged")
