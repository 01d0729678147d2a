"""``acid speed-sweep``: table, figure and JSON; one-line errors."""

from __future__ import annotations

import json

from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid_cli.main import app

runner = CliRunner()


def test_speed_sweep_judges_table_i_on_the_paper_vehicle_beside_the_default(tmp_path):
    """Issue 21: the paper vehicle by default, verdicts by the registry's rules, acid's default
    vehicle beside it in the table and the JSON."""
    out, js = tmp_path / "out", tmp_path / "summary.json"
    result = runner.invoke(app, ["speed-sweep", "--out", str(out), "--json", str(js)])
    assert result.exit_code == 0, result.output
    assert "Table I" in result.output and "1.33" in result.output
    assert "paper vehicle" in result.output and "default vehicle" in result.output
    assert (out / "speed_sweep.png").stat().st_size > 10_000
    d = json.loads(js.read_text())
    assert {"speeds_mps", "energy_MJ", "energy_MJ_per_km", "paper"} <= set(d)
    assert d["energy_MJ_per_km"][0] is None and len(d["energy_MJ"]) == 6
    assert d["vehicle"] == "paper" and d["config_path"].endswith("table_i_20cc.toml")
    assert d["plant_config"]["V_disp"] == 20e-6 and d["acid_version"]
    # the paper vehicle meets Table I; the default vehicle falls further with speed
    assert set(d["verdicts"].values()) == {"agrees"}
    assert 0.775 <= d["ratio_last_first"] <= 0.835
    b = d["beside"]
    assert b["vehicle"] == "default" and b["plant_config"]["V_disp"] == 33e-6
    assert b["ratio_last_first"] < 0.7 and len(b["energy_MJ"]) == 6
    assert json.loads((out / "speed_sweep.json").read_text())["energy_MJ"] == d["energy_MJ"]


def test_speed_sweep_on_the_default_vehicle_has_nothing_beside_it(tmp_path):
    js = tmp_path / "s.json"
    result = runner.invoke(app, ["speed-sweep", "--plant-config", "default", "--out",
                                 str(tmp_path / "o"), "--json", str(js)])
    assert result.exit_code == 0, result.output
    d = json.loads(js.read_text())
    assert d["vehicle"] == "default" and "beside" not in d and d["config_path"] is None
    assert d["verdicts"]["ratio"] == "disagrees"


def test_speed_sweep_with_config_and_duration(tmp_path):
    cfg = tmp_path / "plant.toml"
    cfg.write_text('refrigerant = "R1234yf"\n')
    result = runner.invoke(app, ["speed-sweep", "--plant-config", str(cfg), "--duration", "60",
                                 "--out", str(tmp_path / "o"), "--json", str(tmp_path / "s.json")])
    assert result.exit_code == 0, result.output
    d = json.loads((tmp_path / "s.json").read_text())
    assert d["duration_s"] == 60.0 and d["plant_config"]["refrigerant"] == "R1234yf"
    assert d["config_sha256"]


def test_speed_sweep_bad_config_is_one_line_error(tmp_path):
    cfg = tmp_path / "bad.toml"
    cfg.write_text("[cabin]\nC_cab = -1.0\n")
    result = runner.invoke(app, ["speed-sweep", "--plant-config", str(cfg), "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert_one_line_error(result, "C_cab must be positive", str(cfg))
    assert not (tmp_path / "speed_sweep.png").exists()


def test_speed_sweep_bad_duration(tmp_path):
    result = runner.invoke(app, ["speed-sweep", "--duration", "-5", "--out", str(tmp_path)])
    assert result.exit_code == 2 and "--duration" in result.output
