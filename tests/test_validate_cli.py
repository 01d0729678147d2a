"""``acid validate`` through the console script (typer's CliRunner)."""

from __future__ import annotations

import json

import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.models.params import paper
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
    assert d["n_starts"] == 20 and d["horizon"] == 120
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
                  "--out", tmp_path / "o", "--json", summary, "--no-figures")
    assert res.exit_code == 0, res.output
    assert not (tmp_path / "o").exists()     # --no-figures: no PNG, no folder
    d = json.loads(summary.read_text())
    assert d["figures"] == {} and "figures written" not in res.output
    n = d["settings"]["data_samples"]
    assert d["settings"]["sample_range"] == [n // 2, n]
    assert min(d["starts"]) >= n // 2
    assert d["held_out_fraction_source"] == "params provenance"
    assert d["settings"]["params"] == "fitted"


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
                           "no experiment is longer than warmup + horizon")
    assert not (tmp_path / "o").exists()


def test_params_fitted_on_another_file_validate_the_whole_record(data_file, tmp_path):
    params = tmp_path / "params.json"
    paper().replace(provenance={"estimation_fraction": 0.5, "data_sha256": "0" * 64}).to_json(
        params)
    summary = tmp_path / "s.json"
    res = _invoke(data_file, "--params", params, "--starts", 10, "--horizon", 100,
                  "--out", tmp_path / "o", "--json", summary, "--no-figures")
    assert res.exit_code == 0, res.output
    d = json.loads(summary.read_text())
    assert d["settings"]["sample_range"][0] == 0
    assert d["held_out_fraction_source"] == "whole record"


def test_yardsticks_window_design_and_residuals_are_reported(noisy_model_dataset, tmp_path):
    data = noisy_model_dataset.to_hdf5(tmp_path / "noisy.h5")
    params = tmp_path / "params.json"
    paper().replace(name="fitted", provenance={"estimation_fraction": 0.5}).to_json(params)
    out, summary = tmp_path / "figs", tmp_path / "s.json"
    res = _invoke(data, "--params", params, "--out", out, "--json", summary, "--starts", 20,
                  "--horizon", 120)
    assert res.exit_code == 0, res.output
    text = " ".join(res.output.split())
    assert "window design: 20 starts, starts 155..160 s apart" in text
    assert "horizon 600 s; consecutive windows share 74 % of their samples" in text
    assert "yardstick" in text
    assert "ARX and subspace fitted on samples 0..719 (the estimation part)" in text
    assert "One-step residuals on the validated samples" in text
    assert "noise on the measured state" in text
    # one table of errors vs prediction time (the yardsticks as its rows), said once
    assert text.count("Error vs prediction time") == 1 and "at prediction times" not in text
    assert text.count("window design:") == 1 and "held at their start values" not in text
    table = res.output[res.output.index("Error vs prediction time"):]
    assert all(f"{t} s" in table.split("\n")[2] for t in (5, 60, 300, 600))
    assert all(f" {w} " in table for w in ("model", "persistence", "arx", "subspace"))
    d = json.loads(summary.read_text())
    from acid.ident.validate import DeclaredValidation

    back = DeclaredValidation.from_json(summary)       # --json is the result's dict
    assert {k: d[k] for k in back.to_json_dict()} == back.to_json_dict()
    assert len(back.by_step()["subspace"]["T_ain"]["p90_abs"]) == 120
    assert set(d["yardsticks"]) == {"persistence", "arx", "subspace"}
    assert set(d["yardsticks_by_time"]["arx"]["T_cab"]["60"]) == {"rmse_K", "p90_K", "n"}
    assert d["window_design"]["max_windows_per_sample"] > 1
    assert set(d["residuals"]["interpretation"]) == {"T_cab", "T_evap", "T_ain", "P_bl"}
    assert (out / "fig6b_yardsticks.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # a model worse than persistence would show it: here the model (true parameters) wins
    for c in ("T_cab", "T_evap", "T_ain"):
        assert d["by_time"][c]["300"]["rmse_K"] < d["yardsticks_by_time"]["persistence"][c][
            "300"]["rmse_K"]


def test_non_overlapping_and_no_yardsticks(data_file, tmp_path):
    summary = tmp_path / "s.json"
    res = _invoke(data_file, "--non-overlapping", "--no-yardsticks", "--out", tmp_path / "o",
                  "--json", summary)
    assert res.exit_code == 0, res.output
    text = " ".join(res.output.split())
    assert "only 4 windows of 300 steps (1500 s) fit without overlap" in text
    assert "share 0 % of their samples, no sample lies in two windows (--non-overlapping)" in text
    assert "yardstick" not in text
    d = json.loads(summary.read_text())
    assert d["yardsticks"] == {} and d["window_design"]["non_overlapping"]
    assert d["n_starts"] == 4
    assert not (tmp_path / "o" / "fig6b_yardsticks.png").exists()


@pytest.mark.slow
def test_intervals_and_start_designs(data_file, tmp_path):
    summary = tmp_path / "s.json"
    res = _invoke(data_file, "--starts", 25, "--horizon", 40, "--intervals", "--resamples",
                  50, "--starts-design", "even,non-overlapping", "--out", tmp_path / "o",
                  "--json", summary, "--no-figures")
    assert res.exit_code == 0, res.output
    assert "two-level bootstrap" in res.output and "across start designs" in res.output
    d = json.loads(summary.read_text())
    assert [iv["design"] for iv in d["intervals"]] == ["even", "non-overlapping"]
    fig = d["intervals"][0]["figures"][0]
    assert fig["n_starts"] == 25 and fig["rmse_lo"] <= fig["rmse"] <= fig["rmse_hi"]
    assert len(d["by_step"]["model"]["T_cab"]["rmse"]) == 40
    bad = _invoke(data_file, "--starts-design", "diagonal")
    assert bad.exit_code == 2 and "--starts-design" in bad.output
