"""``acid day``: help, refusals, and a short real run writing its JSON and figure."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from acid_cli.main import app

runner = CliRunner()


def test_help_names_the_options():
    r = runner.invoke(app, ["day", "--help"])
    assert r.exit_code == 0
    for opt in ("--season", "--days", "--seed", "--jobs", "--quick", "--out", "--json",
                "--planner", "--soc-start"):
        assert opt in r.output


def test_an_unknown_season_is_one_line_exit_2(tmp_path):
    r = runner.invoke(app, ["day", "--season", "spring", "--out", str(tmp_path / "o")])
    assert r.exit_code == 2
    assert "--season" in r.output and "Traceback" not in r.output


def test_an_unknown_planner_is_one_line_exit_2(tmp_path):
    r = runner.invoke(app, ["day", "--planner", "oracle", "--out", str(tmp_path / "o")])
    assert r.exit_code == 2
    assert "--planner" in r.output and "Traceback" not in r.output


def test_a_state_of_charge_outside_1_to_100_percent_is_one_line_exit_2(tmp_path):
    for bad in ("0", "101", "nan"):
        r = runner.invoke(app, ["day", "--soc-start", bad, "--out", str(tmp_path / "o")])
        assert r.exit_code == 2, bad
        assert "--soc-start" in r.output and "Traceback" not in r.output


@pytest.mark.slow
def test_a_quick_summer_run_writes_json_and_figure(tmp_path):
    out, js = tmp_path / "o", tmp_path / "s.json"
    r = runner.invoke(app, ["day", "--quick", "--season", "summer", "--no-planner",
                            "--out", str(out), "--json", str(js)])
    assert r.exit_code == 0, r.output
    assert (out / "day.png").stat().st_size > 10_000
    s = json.loads(js.read_text())
    assert s["seasons"] == ["summer"] and s["n_test"] == 4
    assert f"{s['tuned_lead_min']['summer']:g}" in s["scan"]["summer"]  # to the minute
    words = {c["verdict"] for c in s["comparisons"]}
    assert words == {"not resolved"}  # 4 held-out days are below the resolved count
    assert "paired differences" in r.output
