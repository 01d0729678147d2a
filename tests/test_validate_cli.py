"""``acid validate`` through the console script (typer's CliRunner)."""

from __future__ import annotations

import json

import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.params import paper
from acid_cli.main import app

runner = CliRunner()


@pytest.fixture
def data_file(model_dataset, tmp_path):
    return model_dataset.to_hdf5(tmp_path / "model.h5")


def _invoke(*args):
    return runner.invoke(app, ["validate", *map(str, args)])


def test_writes_summary_json_and_both_figures(data_file, tmp_path):
    out, summary = tmp_path / "figs", tmp_path / "summary.json"
    res = _invoke(data_file, "--starts", 20, "--horizon", 120, "--exogenous", "measured",
                  "--out", out, "--json", summary)
    assert res.exit_code == 0, res.output
    assert "T_cab" in res.output and "RMSE" in res.output
    d = json.loads(summary.read_text())
    for name in ("T_cab", "T_evap", "T_ain"):
        for key in ("rmse", "max_abs", "p95_abs", "fit_percent"):
            assert key in d["channels"][name]
        assert d["channels"][name]["max_abs"] <= 1e-9
    assert d["settings"]["starts"] == 20 and d["settings"]["horizon_steps"] == 120
    assert d["inputs"]["params"] == "paper" and len(d["inputs"]["data_sha256"]) == 64
    for png in ("fig5_prediction.png", "fig6_errors.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert (out / png).stat().st_size > 10_000


def test_params_provenance_selects_the_held_out_part(data_file, tmp_path):
    params = tmp_path / "params.json"
    p = paper().replace(name="fitted", provenance={"estimation_fraction": 0.5})
    p.to_json(params)
    summary = tmp_path / "s.json"
    res = _invoke(data_file, "--params", params, "--starts", 10, "--horizon", 100,
                  "--out", tmp_path / "o", "--json", summary)
    assert res.exit_code == 0, res.output
    d = json.loads(summary.read_text())
    n = d["settings"]["data_samples"]
    assert d["settings"]["sample_range"] == [n // 2, n]
    assert min(d["starts"]["index"]) >= n // 2
    assert d["held_out_fraction_source"] == "params provenance"
    assert d["settings"]["params_name"] == "fitted"


def test_bad_params_json_is_a_one_line_error(data_file, tmp_path):
    bad = tmp_path / "params.json"
    bad.write_text("{not json")
    assert_one_line_error(_invoke(data_file, "--params", bad, "--out", tmp_path / "o"),
                           "params.json", "not valid JSON")
    bad.write_text(json.dumps({"gamma": [1, 2], "tau": [0, 0, 0]}))
    assert_one_line_error(_invoke(data_file, "--params", bad, "--out", tmp_path / "o"),
                           "gamma")


def test_missing_file_is_a_one_line_error(tmp_path):
    assert_one_line_error(_invoke(tmp_path / "nope.h5", "--out", tmp_path / "o"),
                           "nope.h5", "not found")


def test_missing_channel_is_a_one_line_error(model_dataset, tmp_path):
    path = model_dataset.select(["T_cab", "T_evap", "T_ain", "W_bl", "T_evap_set",
                                 "T_shell"]).to_hdf5(tmp_path / "no_tint.h5")
    assert_one_line_error(_invoke(path, "--out", tmp_path / "o"), "no_tint.h5", "T_int")


def test_too_short_record_is_a_one_line_error(model_dataset, tmp_path):
    path = model_dataset.window(0, 100).to_hdf5(tmp_path / "short.h5")
    assert_one_line_error(_invoke(path, "--out", tmp_path / "o"), "short.h5",
                           "record too short: 100 samples")
    assert not (tmp_path / "o").exists()


def test_params_fitted_on_another_file_validate_the_whole_record(data_file, tmp_path):
    params = tmp_path / "params.json"
    paper().replace(provenance={"estimation_fraction": 0.5, "data_sha256": "0" * 64}).to_json(
        params)
    summary = tmp_path / "s.json"
    res = _invoke(data_file, "--params", params, "--starts", 10, "--horizon", 100,
                  "--out", tmp_path / "o", "--json", summary)
    assert res.exit_code == 0, res.output
    d = json.loads(summary.read_text())
    assert d["settings"]["sample_range"][0] == 0
    assert d["held_out_fraction_source"] == "whole record"
