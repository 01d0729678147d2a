"""``acid claims``: the registry as a table, the headline table of a run, one-line errors."""

from __future__ import annotations

import json

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
