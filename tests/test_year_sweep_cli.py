"""``acid year-sweep``: its files (CSV in degC, JSON, figure) and its summary."""

from __future__ import annotations

import csv
import json

from typer.testing import CliRunner

from acid_cli.main import app

runner = CliRunner()


def test_year_sweep_writes_csv_json_and_figure(tmp_path):
    out, js = tmp_path / "year", tmp_path / "s.json"
    result = runner.invoke(app, ["year-sweep", "--t-amb", "0", "--t-amb", "30", "--cycle",
                                 "hwfet", "--plant-config", "paper", "--out", str(out),
                                 "--json", str(js)])
    assert result.exit_code == 0, result.output
    rows = list(csv.DictReader((out / "year.csv").open()))
    assert [(r["T_amb_C"], r["heating"]) for r in rows] == [
        ("0.0", "heat pump"), ("0.0", "heater only"), ("30.0", "-")]
    assert all(r["vehicle"] == "paper" and r["cycle"] == "hwfet" for r in rows)
    summary = json.loads(js.read_text())
    assert summary["switch_over_C"] == 18.0
    assert summary["points"][0]["T_amb_C"] == 0.0
    assert {c["cycle"] for c in summary["road_load_check"]} == {"udds", "hwfet"}
    assert (out / "year_share.png").stat().st_size > 10_000
    assert json.loads((out / "year.json").read_text())["points"] == summary["points"]
