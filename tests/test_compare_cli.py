"""``acid compare``: options, one-line errors and a tiny run's table and JSON."""

from __future__ import annotations

import json

from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid_cli.main import app


def test_help_names_the_options():
    r = CliRunner().invoke(app, ["compare", "--help"])
    assert r.exit_code == 0
    for opt in ("--t-amb", "--cycle", "--plant-config", "--json", "--out", "--jobs", "--seed",
                "--quick", "--econ-params"):
        assert opt in r.output


def test_one_ambient_is_a_one_line_error():
    r = CliRunner().invoke(app, ["compare", "--t-amb", "30", "--no-econ"])
    assert r.exit_code == 2
    assert_one_line_error(r, "--t-amb")


def test_unknown_cycle_is_a_one_line_error():
    r = CliRunner().invoke(app, ["compare", "--cycle", "moon", "--no-econ"])
    assert r.exit_code == 2
    assert_one_line_error(r, "--cycle", "moon")


def test_a_tiny_run_is_not_resolved_and_writes_json(tmp_path):
    js = tmp_path / "c.json"
    r = CliRunner().invoke(app, ["compare", "--cycle", "stopgo", "--t-amb", "30,34",
                                 "--quick", "--no-econ", "--json", str(js),
                                 "--out", str(tmp_path / "o")])
    assert r.exit_code == 0, r.output
    assert "not resolved" in r.output and "held out: stopgo@" in r.output
    d = json.loads(js.read_text())
    assert {v["word"] for v in d["verdicts"]} == {"not resolved"}
    assert (tmp_path / "o" / "fronts.png").stat().st_size > 0


def test_identify_records_bad_values_are_one_line_errors(tmp_path):
    for bad in ("0,0", "a", "-1", ""):
        r = CliRunner().invoke(app, ["compare", "--identify-records", bad])
        assert r.exit_code == 2, (bad, r.output)
        assert_one_line_error(r, "--identify-records")
    p = tmp_path / "e.json"
    p.write_text("{}")
    r = CliRunner().invoke(app, ["compare", "--identify-records", "0,1", "--econ-params", str(p)])
    assert r.exit_code == 2
    assert_one_line_error(r, "--identify-records")


def test_a_verdict_across_records_holds_only_where_every_record_agrees():
    from acid.studies import compare as cmp

    names = ["a", "b", "c", "d", "e"]
    base = [1.0, 2.0, 3.0, 4.0, 5.0]

    def result(factor):
        v = cmp.verdict("E", "F", names, [factor * b for b in base], base, n_boot=200)
        return cmp.CompareResult(cmp.ScenarioSet((), (), ""), 0.0, (), verdicts=(v,))

    saves, same = result(0.9), result(1.0)
    assert cmp.across_records([saves, saves], "E", "F")[0] == "saves"
    word, vs = cmp.across_records([saves, same], "E", "F")
    assert word == cmp.RECORD_DEPENDENT and [v.word for v in vs] == ["saves",
                                                                     "no resolvable difference"]
