"""``--plant fmu:PATH --fmu-map MAP`` and ``acid export-fmu`` through Typer's CliRunner."""

from __future__ import annotations

import json

import numpy as np
from _cli import assert_one_line_error
from test_plant_fmu import _model_exchange_only
from typer.testing import CliRunner

from acid.data import Dataset
from acid_cli.main import app

runner = CliRunner()


def test_export_then_excite_through_the_fmu_matches_the_native_plant(tmp_path):
    fmu, fmu_map = tmp_path / "p.fmu", tmp_path / "p.toml"
    res = runner.invoke(app, ["export-fmu", "--out", str(fmu), "--json", str(tmp_path / "e.json")])
    assert res.exit_code == 0, res.output
    assert fmu.is_file() and fmu_map.is_file()
    assert json.loads((tmp_path / "e.json").read_text())["fmi_version"] == 2
    common = ["excite", "--seed", "3", "--duration", "300"]
    res = runner.invoke(app, [*common, "--plant", f"fmu:{fmu}", "--fmu-map", str(fmu_map),
                              "--out", str(tmp_path / "fmu.h5")])
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, [*common, "--out", str(tmp_path / "native.h5")])
    assert res.exit_code == 0, res.output
    a = Dataset.from_hdf5(tmp_path / "native.h5")
    b = Dataset.from_hdf5(tmp_path / "fmu.h5")
    temps = [c for c in a.channels if a.units[c] == "degC"]
    assert {"T_cab", "T_evap", "T_ain", "T_int", "T_shell", "T_amb"} <= set(temps)
    for c in temps:
        assert np.max(np.abs(a[c] - b[c])) <= 1e-6, c
    assert b.metadata["plant"] == "fmu" and b.metadata["seed"] == 3


def test_mpc_check_on_the_fmu_passes_model_and_plant_scenarios(exported_fmu, tmp_path):
    fmu, fmu_map = exported_fmu
    js = tmp_path / "check.json"
    res = runner.invoke(app, ["mpc-check", "--plant", f"fmu:{fmu}", "--fmu-map", str(fmu_map),
                              "--no-figures", "--json", str(js)])
    assert res.exit_code in (0, 1), res.output  # 1 only if this machine misses the timing
    d = json.loads(js.read_text())
    assert d["scenarios"]["model"]["passed"] is True
    assert d["scenarios"]["plant"]["passed"] is True
    assert d["scenarios"]["cav"]["skipped"] is None
    assert "speed_blind_plant" not in d["scenarios"]["cav"]  # an FMU has no speed-blind twin
    assert d["inputs"]["plant"] == f"fmu:{fmu}"


def test_corrupt_zip_model_exchange_and_missing_variable_are_one_line_errors(exported_fmu,
                                                                            tmp_path):
    fmu, fmu_map = exported_fmu
    out = tmp_path / "data.h5"
    out.write_bytes(b"previous results")
    corrupt = tmp_path / "corrupt.fmu"
    corrupt.write_bytes(b"PK\x03\x04 not really a zip")
    me = tmp_path / "me.fmu"
    _model_exchange_only(fmu, me)
    missing = tmp_path / "missing.toml"
    missing.write_text(fmu_map.read_text().replace('"state.T_shell"', '"state.T_hull"'))
    cases = [
        (corrupt, fmu_map, ("corrupt.fmu", "not a valid FMU")),
        (me, fmu_map, ("me.fmu", "model exchange only", "co-simulation")),
        (fmu, missing, ("missing.toml", "[states] T_shell", "'state.T_hull'",
                        "does not have")),
    ]
    for the_fmu, the_map, fragments in cases:
        res = runner.invoke(app, ["excite", "--plant", f"fmu:{the_fmu}", "--fmu-map",
                                  str(the_map), "--duration", "60", "--out", str(out)])
        assert res.exit_code == 2
        assert_one_line_error(res, *fragments)
    assert out.read_bytes() == b"previous results"  # nothing already written is lost


def test_a_failing_fmu_run_keeps_the_previous_output(exported_fmu, tmp_path):
    fmu, fmu_map = exported_fmu
    out = tmp_path / "data.h5"
    out.write_bytes(b"previous results")
    res = runner.invoke(app, ["excite", "--plant", f"fmu:{fmu}", "--fmu-map", str(fmu_map),
                              "--t-amb", "70", "--duration", "60", "--out", str(out)])
    assert res.exit_code == 2
    assert_one_line_error(res, fmu.name, "T_amb")
    assert out.read_bytes() == b"previous results"


def test_plant_options_are_checked_together(exported_fmu, tmp_path):
    fmu, fmu_map = exported_fmu
    res = runner.invoke(app, ["excite", "--plant", f"fmu:{fmu}", "--out", str(tmp_path / "x")])
    assert_one_line_error(res, "--fmu-map")
    res = runner.invoke(app, ["excite", "--fmu-map", str(fmu_map), "--out", str(tmp_path / "x")])
    assert_one_line_error(res, "--fmu-map applies to --plant fmu:PATH.fmu only")
    res = runner.invoke(app, ["speed-sweep", "--plant", "fmu:nowhere.fmu", "--fmu-map",
                              str(fmu_map)])
    assert_one_line_error(res, "--plant", "nowhere.fmu")
    res = runner.invoke(app, ["export-fmu", "--out", str(tmp_path / "p.zip")])
    assert_one_line_error(res, "--out", ".fmu")
