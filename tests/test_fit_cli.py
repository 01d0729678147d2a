"""``acid fit`` through the console script (typer's CliRunner)."""

from __future__ import annotations

import json

import h5py
import numpy as np
import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.models.params import ModelParams, paper
from acid_cli.main import app

runner = CliRunner()


@pytest.fixture
def data_file(model_dataset, tmp_path):
    return model_dataset.to_hdf5(tmp_path / "model.h5")


def _invoke(*args):
    return runner.invoke(app, ["fit", *map(str, args)])


def test_writes_params_json_with_the_required_keys(data_file, tmp_path):
    out, summary = tmp_path / "params.json", tmp_path / "summary.json"
    res = _invoke(data_file, "--out", out, "--json", summary)
    assert res.exit_code == 0, res.output
    d = json.loads(out.read_text())
    assert len(d["gamma"]) == 7 and len(d["tau"]) == 3 and len(d["beta"]) == 3
    assert "kelvin" in d["units"]
    prov = d["provenance"]
    assert prov["data_file"] == str(data_file) and len(prov["data_sha256"]) == 64
    assert prov["method"] == "ls" and prov["estimation_fraction"] == 1.0
    assert d["fit"]["method"] == "ls" and len(d["fit"]["parameters"]) >= 13
    p = ModelParams.from_json(out)
    assert np.allclose(p.gamma, paper().gamma, rtol=1e-3)
    text = " ".join(res.output.split())
    assert "paper" in text and "gamma7" in text and "34.958" in text and "cond" in text
    assert json.loads(summary.read_text())["command"] == "fit"


def test_output_error_on_the_estimation_part(data_file, tmp_path):
    out = tmp_path / "p.json"
    res = _invoke(data_file, "--out", out, "--method", "oe", "--estimation-fraction", 0.5)
    assert res.exit_code == 0, res.output
    d = json.loads(out.read_text())
    assert d["provenance"]["estimation_fraction"] == 0.5
    assert d["fit"]["n_samples"] == 720 and d["fit"]["method"] == "oe"
    assert np.allclose(d["gamma"], paper().gamma, rtol=1e-3)


def test_cvx_huber_runs(data_file, tmp_path):
    res = _invoke(data_file, "--out", tmp_path / "p.json", "--method", "cvx", "--loss", "huber")
    assert res.exit_code == 0, res.output


@pytest.mark.parametrize("content,fragment", [
    ('{"gamma": [1, 2, 3, 4, 5, 6, 7]}', "missing key 'tau'"),
    ("not json at all", "not valid JSON"),
    ('{"gamma": [1, 2], "tau": [1, 2, 3]}', "7 numbers"),
])
def test_bad_reference_params_give_a_one_line_error(data_file, tmp_path, content, fragment):
    bad = tmp_path / "bad.json"
    bad.write_text(content)
    res = _invoke(data_file, "--out", tmp_path / "p.json", "--reference", bad)
    assert_one_line_error(res, fragment)
    assert not (tmp_path / "p.json").exists()


def test_bad_data_paths_and_options_give_a_one_line_error(data_file, tmp_path):
    assert_one_line_error(_invoke(tmp_path / "nope.h5", "--out", tmp_path / "p.json"),
                           "not found")
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["x"] = np.arange(3.0)
    assert_one_line_error(_invoke(other, "--out", tmp_path / "p.json"), "not an acid dataset")
    assert_one_line_error(_invoke(data_file, "--method", "magic"), "magic")
    assert_one_line_error(_invoke(data_file, "--estimation-fraction", 1.5),
                           "--estimation-fraction")
    assert_one_line_error(_invoke(data_file, "--loss", "cauchy"), "--loss", "cauchy")


def test_unexcited_parameter_warns_or_refuses_with_strict(model_dataset, tmp_path):
    ds = model_dataset.window(0, len(model_dataset))
    ds.channels["W_bl"] = np.full(len(ds), 0.1)
    path = ds.to_hdf5(tmp_path / "flat.h5")
    res = _invoke(path, "--out", tmp_path / "p.json")
    assert res.exit_code == 0, res.output
    assert "warning:" in res.output and "gamma7" in res.output
    assert_one_line_error(_invoke(path, "--out", tmp_path / "q.json", "--strict"), "gamma7")
