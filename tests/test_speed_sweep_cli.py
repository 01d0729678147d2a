"""``acid speed-sweep``: table, figure and JSON; one-line errors."""

from __future__ import annotations

import json

from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid_cli.main import app

runner = CliRunner()


def test_speed_sweep_writes_table_figure_and_json(tmp_path):
    out, js = tmp_path / "out", tmp_path / "summary.json"
    result = runner.invoke(app, ["speed-sweep", "--out", str(out), "--json", str(js)])
    assert result.exit_code == 0, result.output
    assert "paper (MJ)" in result.output and "1.33" in result.output
    assert (out / "speed_sweep.png").stat().st_size > 10_000
    d = json.loads(js.read_text())
    assert {"speeds_mps", "energy_MJ", "energy_MJ_per_km", "paper"} <= set(d)
    assert d["energy_MJ_per_km"][0] is None and len(d["energy_MJ"]) == 6
    assert d["plant_config"]["refrigerant"] == "R134a" and d["acid_version"]
    assert json.loads((out / "speed_sweep.json").read_text())["energy_MJ"] == d["energy_MJ"]


def test_speed_sweep_with_config_and_duration(tmp_path):
    cfg = tmp_path / "plant.toml"
    cfg.write_text('refrigerant = "R1234yf"\n')
    result = runner.invoke(app, ["speed-sweep", "--config", str(cfg), "--duration", "60",
                                 "--out", str(tmp_path / "o"), "--json", str(tmp_path / "s.json")])
    assert result.exit_code == 0, result.output
    d = json.loads((tmp_path / "s.json").read_text())
    assert d["duration_s"] == 60.0 and d["plant_config"]["refrigerant"] == "R1234yf"
    assert d["config_sha256"]


def test_speed_sweep_bad_config_is_one_line_error(tmp_path):
    cfg = tmp_path / "bad.toml"
    cfg.write_text("[cabin]\nC_cab = -1.0\n")
    result = runner.invoke(app, ["speed-sweep", "--config", str(cfg), "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert_one_line_error(result, "C_cab must be positive", str(cfg))
    assert not (tmp_path / "speed_sweep.png").exists()


def test_speed_sweep_bad_duration(tmp_path):
    result = runner.invoke(app, ["speed-sweep", "--duration", "-5", "--out", str(tmp_path)])
    assert result.exit_code == 2 and "--duration" in result.output
