"""``acid fit --model FILE.py`` and ``acid validate --model FILE.py`` (typer's CliRunner) on a
short ``acid excite`` record of the high-fidelity plant."""

from __future__ import annotations

import json

import numpy as np
import pytest
from _catalogue import MODEL_FILE
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.excite import ExcitationSpec, excite
from acid.plant import make_plant
from acid_cli.main import app

runner = CliRunner()

#: a user's file: the cabin with a latent interior mass and a per-experiment heat load
USER_MODEL = MODEL_FILE.replace(
    '"T_m": s.a * (s.T_cab - s.T_m) / 1e5}',
    '"T_m": (s.a * (s.T_cab - s.T_m) + s.Q) / 1e5}').replace(
    'Parameter("b", "W/K", 50.0, 0.0, 1e3)]',
    'Parameter("b", "W/K", 50.0, 0.0, 1e3),\n'
    '                          Parameter("Q", "W", 0.0, -2e3, 2e3, per_experiment=True)]')


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    """300 samples (1500 s) of ``acid excite`` on the high-fidelity plant."""
    folder = tmp_path_factory.mktemp("declared")
    ds = excite(make_plant("hifi"), ExcitationSpec(duration=1500.0, seed=2))
    return ds.to_hdf5(folder / "d.h5")


def test_fit_and_validate_a_users_model_file(record, tmp_path):
    model = tmp_path / "my_cabin.py"
    model.write_text(USER_MODEL)
    out, summary = tmp_path / "p.json", tmp_path / "fit.json"
    res = runner.invoke(app, ["fit", str(record), "--model", str(model), "--out", str(out),
                              "--json", str(summary), "--oe-window", "150"])
    assert res.exit_code == 0, res.output
    text = " ".join(res.output.split())
    assert "method oe" in text and "latent: T_m" in text
    d = json.loads(out.read_text())
    assert d["format"] == "acid-declared-params" and d["model"] == "mine"
    assert set(d["parameters"]) == {"a", "b", "Q"} and d["per_experiment"]["Q"]["values"]
    assert d["provenance"]["model_file"] == str(model)
    rep = json.loads(summary.read_text())
    assert rep["output_error"]["converged"] and rep["method"] == "oe"
    assert {e["status"] for e in rep["parameters"]} == {"estimated (oe)"}
    assert not list(tmp_path.glob("__pycache__"))          # loading leaves nothing behind

    vjson = tmp_path / "val.json"
    res = runner.invoke(app, ["validate", str(record), "--model", str(model), "--params",
                              str(out), "--starts", "5", "--horizon", "100", "--warmup", "150",
                              "--json", str(vjson), "--no-figures"])
    assert res.exit_code == 0, res.output
    assert "in-sample" in " ".join(res.output.split())
    v = json.loads(vjson.read_text())
    assert "One-step residuals" in res.output        # resid for a declared model too
    r = v["residuals"]
    assert set(r["white"]) == {"T_cab"} and set(r["independent"]) == set()  # no inputs
    assert 0.0 <= r["ljung_box"]["T_cab"]["p_value"] <= 1.0
    assert v["model"] == "mine" and v["n_starts"] == 5 and v["horizon"] == 100
    assert set(v["channels"]) == {"T_cab"} and v["channels"]["T_cab"]["unit"] == "K"
    assert np.isfinite(v["channels"]["T_cab"]["rmse"])
    assert [r["step"] for r in v["by_horizon"]] == [1, 10, 25, 50, 100]
    assert {"persistence", "arx", "subspace"} <= set(v["yardsticks"])
    assert set(v["yardsticks"]["persistence"]["channels"]) == {"T_cab"}
    assert "yardstick" in res.output


def test_fix_holds_a_parameter_and_the_table_says_so(record, tmp_path):
    model = tmp_path / "my_cabin.py"
    model.write_text(USER_MODEL)
    out, summary = tmp_path / "p.json", tmp_path / "fit.json"
    res = runner.invoke(app, ["fit", str(record), "--model", str(model), "--out", str(out),
                              "--json", str(summary), "--oe-window", "150", "--fix", "b=80"])
    assert res.exit_code == 0, res.output
    rows = {e["name"]: e for e in json.loads(summary.read_text())["parameters"]}
    assert rows["b"]["status"] == "fixed" and rows["b"]["estimate"] == 80.0
    assert json.loads(out.read_text())["parameters"]["b"]["value"] == 80.0


def test_paper_only_options_are_refused_for_a_model_file(record, tmp_path):
    model = tmp_path / "my_cabin.py"
    model.write_text(USER_MODEL)
    res = runner.invoke(app, ["fit", str(record), "--model", str(model), "--out",
                              str(tmp_path / "p.json"), "--no-blower"])
    assert_one_line_error(res, "--no-blower", "--model paper")


def test_the_default_model_is_unchanged(record, tmp_path):
    res = runner.invoke(app, ["fit", str(record), "--out", str(tmp_path / "p.json")])
    assert res.exit_code == 0, res.output
    d = json.loads((tmp_path / "p.json").read_text())
    assert d["provenance"]["method"] == "ls" and len(d["gamma"]) == 7


def test_add_record_makes_experiments(record, tmp_path):
    import shutil

    model = tmp_path / "my_cabin.py"
    model.write_text(USER_MODEL)
    second = tmp_path / "second.h5"
    shutil.copy(record, second)
    out = tmp_path / "p.json"
    res = runner.invoke(app, ["fit", str(record), "--add-record", str(second), "--model",
                              str(model), "--out", str(out), "--oe-window", "150"])
    assert res.exit_code == 0, res.output
    assert "2 experiment(s)" in " ".join(res.output.split())  # rich wraps long paths
    d = json.loads(out.read_text())
    q = d["per_experiment"]["Q"]
    assert q["experiments"] == [0, 1] and len(q["values"]) == 2
    # the same record twice: the same load in both experiments
    assert q["values"][0] == pytest.approx(q["values"][1], rel=1e-6)
    assert d["provenance"]["records"] == [str(record), str(second)]
    # the paper's model is a declaration too: its records become experiments alike
    res = runner.invoke(app, ["fit", str(record), "--add-record", str(second),
                              "--out", str(tmp_path / "q.json")])
    assert res.exit_code == 0, res.output
    assert "2 experiment(s)" in res.output
    res = runner.invoke(app, ["fit", str(record), "--add-record", str(second), "--model",
                              "econ", "--out", str(tmp_path / "r.json")])
    assert_one_line_error(res, "--add-record", "--model econ")


def test_fit_starts_take_the_built_in_families_through_the_declared_fitter(record, tmp_path):
    out, summary = tmp_path / "p.json", tmp_path / "fit.json"
    res = runner.invoke(app, ["fit", str(record), "--model", "paper", "--fit-starts", "3",
                              "--oe-window", "150", "--out", str(out), "--json", str(summary)])
    assert res.exit_code == 0, res.output
    text = " ".join(res.output.split())
    assert "Distinct optima of 3 starts" in text and "method oe" in text
    rep = json.loads(summary.read_text())
    optima = rep["optima"]
    assert sum(o["n_starts"] for o in optima) == 3
    assert [o["loss"] for o in optima] == sorted(o["loss"] for o in optima)
    assert set(optima[0]["values"]) == set(optima[0]["spread"]) >= {"gamma1", "tau1"}
    assert optima[0]["loss"] == pytest.approx(rep["output_error"]["loss"])
    d = json.loads(out.read_text())
    assert d["format"] == "acid-declared-params" and d["model"] == "paper"
    vjson = tmp_path / "val.json"                    # validated through the declaration
    res = runner.invoke(app, ["validate", str(record), "--model", "paper", "--params",
                              str(out), "--starts", "3", "--horizon", "40", "--json",
                              str(vjson), "--no-yardsticks", "--no-figures"])
    assert res.exit_code == 0, res.output
    assert json.loads(vjson.read_text())["model"] == "paper"
    # without those options too: one parameter file, read by the declared validator and
    # by the controllers (ModelParams) alike
    one = tmp_path / "one.json"
    res = runner.invoke(app, ["fit", str(record), "--model", "paper", "--out", str(one)])
    assert res.exit_code == 0, res.output
    d = json.loads(one.read_text())
    assert d["format"] == "acid-declared-params" and len(d["gamma"]) == 7
    from acid.models.params import ModelParams
    assert ModelParams.from_json(one).gamma == tuple(
        d["parameters"][f"gamma{i}"]["value"] for i in range(1, 8))
    res = runner.invoke(app, ["fit", str(record), "--model", "paper", "--fit-starts", "3",
                              "--method", "ls", "--out", str(tmp_path / "q.json")])
    assert_one_line_error(res, "--fit-starts 3", "--method oe")


def test_fix_takes_econ_through_its_declaration(record, tmp_path):
    res = runner.invoke(app, ["fit", str(record), "--model", "econ", "--fix", "zz=1",
                              "--out", str(tmp_path / "q.json")])
    assert_one_line_error(res, "'zz'", "econ")


def test_excite_drives_a_declared_model_as_the_plant(tmp_path):
    from acid.data import Dataset

    model = tmp_path / "my_cabin.py"
    model.write_text(MODEL_FILE)
    rec = tmp_path / "x.h5"
    res = runner.invoke(app, ["excite", "--plant", f"model:{model}", "--duration", "1000",
                              "--seed", "4", "--out", str(rec)])
    assert res.exit_code == 0, res.output
    ds = Dataset.from_hdf5(rec)
    assert len(ds) == 200 and {"T_cab", "T_m", "T_shell"} <= set(ds.channels)
    from acid.excite import make_schedule, spec_for_model

    sched = make_schedule(spec_for_model("paper", seed=4, duration=1000.0))
    np.testing.assert_allclose(ds.get("T_shell", "K"), sched.T_shell, rtol=1e-12)
    assert abs(sched.T_shell[0] - 303.15) > 1.0               # not the constant fallback
    assert ds.metadata["plant_config"]["model"] == "mine"
    # its parameters from a fit of the declared model: the plant runs with those values
    out = tmp_path / "p.json"
    res = runner.invoke(app, ["fit", str(rec), "--model", str(model), "--fix", "a=300",
                              "--fix", "b=20", "--out", str(out)])
    assert res.exit_code == 0, res.output
    rec2 = tmp_path / "y.h5"
    res = runner.invoke(app, ["excite", "--plant", f"model:{model}", "--params", str(out),
                              "--duration", "200", "--out", str(rec2)])
    assert res.exit_code == 0, res.output
    assert Dataset.from_hdf5(rec2).metadata["plant_config"]["parameters"] == {"a": 300.0,
                                                                              "b": 20.0}
