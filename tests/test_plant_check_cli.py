"""``acid plant-check``: table, figures and JSON; one-line errors on bad input."""

from __future__ import annotations

import json

from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid_cli.main import app

runner = CliRunner()


def test_plant_check_writes_json_and_figures(tmp_path):
    out, js = tmp_path / "out", tmp_path / "s.json"
    result = runner.invoke(app, ["plant-check", "--out", str(out), "--json", str(js)])
    d = json.loads(js.read_text())
    assert result.exit_code == (0 if d["passed"] else 1), result.output
    assert "cop_steady_30C_standstill" in result.output
    assert d["cop_gain_25_vs_0_equal_load_pct"] > 0 and len(d["checks"]) > 20
    for name in ("plant_check_energy", "plant_check_service"):
        assert (out / f"{name}.png").stat().st_size > 10_000
    assert json.loads((out / "plant_check.json").read_text())["checks"] == d["checks"]


def test_unknown_refrigerant_is_one_line_error(tmp_path):
    cfg = tmp_path / "r.toml"
    cfg.write_text('refrigerant = "R12"\n')
    result = runner.invoke(app, ["plant-check", "--plant-config", str(cfg), "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert_one_line_error(result, "refrigerant 'R12' not supported", str(cfg))


def test_negative_capacity_is_one_line_error(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text("[cabin]\nC_int = -35000.0\n")
    result = runner.invoke(app, ["plant-check", "--plant-config", str(cfg), "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert_one_line_error(result, "C_int must be positive", str(cfg))
    assert not (tmp_path / "plant_check.json").exists()


def test_ambient_outside_the_tables_is_one_line_error(tmp_path):
    result = runner.invoke(app, ["plant-check", "--t-amb", "80", "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert_one_line_error(result, "--t-amb 80", "property tables")


def test_ambient_in_a_config_outside_the_tables_is_one_line_error(tmp_path):
    cfg = tmp_path / "a.toml"
    cfg.write_text("T_amb = 66.85\n")
    result = runner.invoke(app, ["plant-check", "--plant-config", str(cfg), "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert_one_line_error(result, "T_amb = 66.85 degC", "property tables", str(cfg))


def test_plant_check_through_an_exported_fmu(tmp_path, exported_fmu):
    """The same checks through an FMU of acid's plant: Table I equals the native plant's;
    what needs the plant's internals or configuration is reported without a verdict."""
    fmu, fmu_map = exported_fmu
    js = tmp_path / "s.json"
    result = runner.invoke(app, ["plant-check", "--plant", f"fmu:{fmu}", "--fmu-map",
                                 str(fmu_map), "--out", str(tmp_path / "o"), "--json", str(js)])
    assert result.exit_code in (0, 1), result.output
    d = json.loads(js.read_text())
    by = {c["name"]: c for c in d["checks"]}
    assert by["Table I: E(0 m/s), 600 s"]["value"] > 1.0
    assert all(c["passed"] is None for c in d["checks"] if c["group"] in "bcdfg")
    assert d["plant"].startswith("fmu:")
