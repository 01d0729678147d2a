"""``acid claims``: the registry as a table, the headline table of a run, one-line errors."""

from __future__ import annotations

import json

import pytest
from _claims import results, summary_of
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.claims import CLAIMS, headline_markdown
from acid_cli.main import app


def _summary(tmp_path) -> dict:
    return summary_of(tmp_path, results())


def test_lists_the_registry_and_writes_json(tmp_path):
    res = CliRunner().invoke(app, ["claims", "--json", str(tmp_path / "c.json")])
    assert res.exit_code == 0, res.output
    assert f"{len(CLAIMS)} claims" in res.output and "Claims of the paper" in res.output
    rows = json.loads((tmp_path / "c.json").read_text())["claims"]
    assert [r["id"] for r in rows] == [c.id for c in CLAIMS]


def test_prints_the_headline_table_of_a_summary(tmp_path):
    s = _summary(tmp_path)
    path = tmp_path / "summary.json"
    path.write_text(json.dumps(s))
    res = CliRunner().invoke(app, ["claims", str(path)])
    assert res.exit_code == 0, res.output
    assert res.output == headline_markdown(s)


def test_a_file_that_is_not_a_summary_is_refused_in_one_line(tmp_path):
    bad = tmp_path / "params.json"
    bad.write_text(json.dumps({"gamma": [1, 2]}))
    assert_one_line_error(CliRunner().invoke(app, ["claims", str(bad)]), "params.json",
                          "no 'claims' block")
    assert_one_line_error(CliRunner().invoke(app, ["claims", str(tmp_path / "none.json")]),
                          "none.json", "not found")


def _write(tmp_path, s: dict, name="tampered.json"):
    path = tmp_path / name
    path.write_text(json.dumps(s))
    return path


def test_a_tampered_verdict_is_judged_again_and_corrected_in_one_line(tmp_path):
    """Issue 24: the stored verdicts are never trusted; the registry judges the stored values
    again, and one line names what it corrected."""
    s = _summary(tmp_path)
    honest = headline_markdown(s)
    items = {i["id"]: i for i in s["claims"]["items"]}
    assert items["table1.ratio"]["verdict"] == "agrees"
    items["table1.ratio"]["verdict"] = "disagrees"
    items["cav.saving"]["verdict"] = "agrees"
    res = CliRunner().invoke(app, ["claims", str(_write(tmp_path, s))])
    assert res.exit_code == 0, res.output
    assert res.stdout == honest
    (line,) = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert line.startswith("warning:") and "2 stored verdicts" in line
    assert "table1.ratio (disagrees -> agrees)" in line and "cav.saving" in line


def test_a_tampered_value_is_judged_by_the_registry(tmp_path):
    s = _summary(tmp_path)
    s["stages"]["sweep"]["summary"]["ratio_last_first"] = 0.5   # the stored verdict: agrees
    res = CliRunner().invoke(app, ["claims", str(_write(tmp_path, s)), "--json",
                                   str(tmp_path / "h.json")])
    assert res.exit_code == 0, res.output
    assert "table1.ratio (agrees -> disagrees)" in res.stderr
    rows = json.loads((tmp_path / "h.json").read_text())
    assert rows["corrected"] == ["table1.ratio (agrees -> disagrees)"]
    ratio = next(r for r in rows["headline"] if r["result"].startswith("E(25 m/s) / E(0"))
    assert "0.500" in ratio["acid"] and ratio["verdict"].startswith("mixed")


@pytest.mark.parametrize(("tamper", "fragments"), [
    (lambda s: s["stages"]["sweep"]["summary"]["energy_MJ"].__setitem__(0, "1.3 MJ"),
     ("tampered.json", "sweep", "energy_MJ[0]", "expected a number")),
    (lambda s: s["stages"]["mpc"]["summary"].pop("timing"),
     ("tampered.json", "missing key 'timing'")),
    (lambda s: s["stages"]["validate"].__setitem__("summary", [1, 2]),
     ("tampered.json", "stages.validate.summary")),
    (lambda s: s.pop("stages"), ("tampered.json", "no 'stages' block")),
    (lambda s: s.__setitem__("options", "quick"), ("tampered.json", "'options'")),
])
def test_a_malformed_value_is_one_line_naming_the_key(tmp_path, tamper, fragments):
    s = _summary(tmp_path)
    tamper(s)
    res = CliRunner().invoke(app, ["claims", str(_write(tmp_path, s))])
    assert res.exit_code == 2
    assert_one_line_error(res, *fragments)


def test_a_non_finite_value_is_one_line_naming_the_key(tmp_path):
    path = _write(tmp_path, _summary(tmp_path))
    text = path.read_text().replace('"ratio_last_first": ', '"ratio_last_first": NaN, "x": ', 1)
    path.write_text(text)
    res = CliRunner().invoke(app, ["claims", str(path)])
    assert res.exit_code == 2
    assert_one_line_error(res, "tampered.json", "stages.sweep.summary.ratio_last_first",
                          "non-finite number")


def test_a_tampered_summary_is_one_line_naming_the_key(tmp_path):
    s = _summary(tmp_path)
    path = tmp_path / "summary.json"

    def tampered(edit) -> dict:
        d = json.loads(json.dumps(s))
        edit(d)
        return d

    cases = [
        (lambda d: d["claims"]["items"][0].update(verdict=7), "claims.items[0].verdict"),
        (lambda d: d["claims"]["items"][1].update(verdict="splendid"),
         "claims.items[1].verdict 'splendid' is not a verdict"),
        (lambda d: d["claims"]["items"][2].pop("acid_text"), "claims.items[2].acid_text"),
        (lambda d: d["claims"]["items"].insert(0, ["x"]), "claims.items[0] must be an object"),
        (lambda d: d["claims"].update(items={"a": 1}), "claims.items must be a list"),
        (lambda d: d["claims"]["counts"].update(agrees="3"), "claims.counts.'agrees'"),
        (lambda d: d["claims"].pop("counts"), "claims.counts must be an object"),
        (lambda d: d.update(claims=[1]), "no 'claims' block"),
    ]
    for edit, fragment in cases:
        path.write_text(json.dumps(tampered(edit)))
        res = CliRunner().invoke(app, ["claims", str(path)])
        assert res.exit_code == 2, (fragment, res.output)
        assert_one_line_error(res, "summary.json", fragment)
    path.write_text('{"claims": ' * 50_000 + "1" + "}" * 50_000)
    assert_one_line_error(CliRunner().invoke(app, ["claims", str(path)]), "summary.json",
                          "nests 50000 levels")
    path.write_text("[1, 2]")
    assert_one_line_error(CliRunner().invoke(app, ["claims", str(path)]), "summary.json",
                          "JSON object at the top level")
