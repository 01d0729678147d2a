"""acid.ident.econ.identify: the econ model identified by acid.ident's staged fit of its
declaration, on its own plant and on the hifi plant; ``acid fit --model econ``."""

from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np
import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.errors import DataError, IdentifiabilityWarning
from acid.ident.econ import identify
from acid.ident.fit import fit_model
from acid.ident.validate import validate
from acid.models.econ_params import NAMES, EconParams
from acid.models.params import fitted
from acid.plant.declared import econ_plant
from acid_cli.main import app

runner = CliRunner()


@pytest.fixture(scope="module")
def truth(econ_truth):
    """A truth away from the declared start values (where every stage starts)."""
    coef = np.array(econ_truth.power_map.coef) * 1.2 + 0.002
    return dataclasses.replace(
        econ_truth.replace(C_cab=5200.0, hA_int=160.0, Q_sh=600.0, tau_ew=14.0,
                           kappa_bl=0.2, k_rec=0.15, RH_amb=0.4),
        C_ew=2600.0, power_map=dataclasses.replace(econ_truth.power_map, coef=tuple(coef)))


@pytest.fixture(scope="module")
def econ_data(truth):
    from acid.excite import excite, spec_for_model

    return excite(econ_plant(truth.theta_all),
                  spec_for_model("econ", duration=2 * 3600.0, seed=1))


@pytest.fixture(scope="module")
def model_fit(econ_data):
    return identify(econ_data, covariance="white")


def test_recovers_the_true_parameters_of_its_own_model(model_fit, truth):
    p = model_fit.params
    for n in NAMES:
        assert p.values[n] == pytest.approx(truth.values[n], rel=1e-6, abs=1e-12), n
    assert p.C_ew == pytest.approx(truth.C_ew, rel=1e-6)
    np.testing.assert_allclose(p.power_map.coef, truth.power_map.coef, rtol=1e-6)
    assert model_fit.power_map_quality["rms_pct"] < 0.01
    assert {q.name: q.fit_percent for q in model_fit.fit.equations}["T_cab"] > 99.9
    # the domain the map was identified on is the excitation's
    assert p.power_map.domain["v_veh"] == (0.0, 36.0)


def test_result_reports_uncertainty_and_round_trips(model_fit, tmp_path):
    d = model_fit.to_json_dict()
    assert d["model"] == "econ" and len(d["parameters"]) == len(NAMES) + 1 + 15 + 3
    assert [q["method"] for q in d["equations"]] == ["ls"] + ["ee"] * 7
    assert {"C_cab", "C_ew", "f_qt", "beta1"} <= set(d["covariance"]["names"])
    row = next(e for e in model_fit.fit.estimates if e.name == "C_cab")
    assert row.ci95[0] <= row.value <= row.ci95[1] and row.stderr >= 0
    json.dumps(d)
    path = model_fit.params.to_json(tmp_path / "econ.json", extra={"fit": d})
    assert EconParams.from_json(path).values == model_fit.params.values


def test_hifi_plant_power_map_and_dynamics(econ_hifi_fit):
    q = econ_hifi_fit.power_map_quality
    assert q["rms_pct"] < 6.0 and q["steady_rms_pct"] < 5.0 and q["r2"] > 0.95
    assert {q.name: q.fit_percent for q in econ_hifi_fit.fit.equations}["T_cab"] > 95.0
    v = econ_hifi_fit.params.values
    assert 0.5 < v["r_max"] < 1.0 and v["C_int"] > 10 * v["C_cab"]   # a heavy interior
    assert 0.0 < v["RH_amb"] < 1.0 and not econ_hifi_fit.warnings


@pytest.mark.slow
def test_validates_beside_the_paper_model_on_held_out_data(econ_hifi_dataset, econ_hifi_fit):
    est, held = econ_hifi_dataset.split(0.75)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        paper = fitted(fit_model("paper", est, "oe"))
    kw = {"starts": 30, "horizon": 120}
    e = validate(held, econ_hifi_fit.params, **kw)
    p = validate(held, paper, **kw)
    assert e.settings["model"] == "econ" and p.settings["model"] == "paper"
    assert e.metrics["T_cab"]["median_abs"] < p.metrics["T_cab"]["median_abs"]
    for ch in ("T_cab", "T_evap", "T_ain"):        # the paper's "couple of degrees"
        assert e.metrics[ch]["median_abs"] < 1.5 and e.metrics[ch]["p90_abs"] < 5.0
    assert e.units[e.channels.index("w_cab")] == "kg/kg"
    assert e.metrics["w_cab"]["median_abs"] < 0.5e-3
    assert e.energy["P_comp"]["median_abs"] < 25.0


def test_refuses_data_that_cannot_identify_it(econ_model_dataset):
    ds = econ_model_dataset.window(0, 1000)
    flat = ds.window(0, len(ds))
    flat.channels["W_bl"] = np.full(len(flat), 0.1)
    with pytest.raises(DataError, match="W_bl is"):
        identify(flat)
    del flat.channels["w_cab"], flat.units["w_cab"]
    with pytest.raises(DataError, match="w_cab"):
        identify(flat)


def test_warns_when_speed_is_not_excited(econ_truth):
    from acid.excite import excite, spec_for_model

    ds = excite(econ_plant(econ_truth.theta_all),
                spec_for_model("econ", duration=2400.0, speed_bounds=None, speed=10.0,
                               T_amb_bounds=None))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        identify(ds)
    lines = [str(w.message) for w in caught if w.category is IdentifiabilityWarning]
    assert any("v_veh varies" in m for m in lines) and any("T_amb varies" in m for m in lines)


# ------------------------------------------------------------------------------- CLI
@pytest.fixture(scope="module")
def econ_file(econ_model_dataset, tmp_path_factory):
    return econ_model_dataset.to_hdf5(tmp_path_factory.mktemp("econ") / "econ.h5")


def test_cli_fit_model_econ_then_validate_beside_the_paper(econ_file, tmp_path):
    out, js = tmp_path / "econ.json", tmp_path / "fit.json"
    res = runner.invoke(app, ["fit", str(econ_file), "--model", "econ", "--out", str(out),
                              "--estimation-fraction", "0.6", "--json", str(js)])
    assert res.exit_code == 0, res.output
    assert "power map" in res.output and "RMS error" in res.output
    d = json.loads(out.read_text())
    assert d["model"] == "econ" and d["provenance"]["estimation_fraction"] == 0.6
    assert json.loads(js.read_text())["model"] == "econ"
    vj = tmp_path / "val.json"
    res = runner.invoke(app, ["validate", str(econ_file), "--params", str(out), "--beside",
                              "paper", "--starts", "8", "--horizon", "60", "--out",
                              str(tmp_path / "figs"), "--json", str(vj), "--no-figures",
                              "--no-yardsticks"])
    assert res.exit_code == 0, res.output
    v = json.loads(vj.read_text())
    assert v["settings"]["model"] == "econ" and "w_cab" in v["channels"]
    n = v["settings"]["data_samples"]
    assert v["settings"]["sample_range"] == [round(0.6 * n), n]
    assert v["held_out_fraction_source"] == "params provenance"
    assert {"T_cab", "T_evap", "T_ain"} <= set(v["beside"]["channels"])
    assert "T_int" not in v["beside"]["channels"]      # the paper's model, beside
    # the same file named with --model: one reader, the same numbers
    vm = tmp_path / "val_model.json"
    res = runner.invoke(app, ["validate", str(econ_file), "--model", "econ", "--params",
                              str(out), "--starts", "8", "--horizon", "60", "--out",
                              str(tmp_path / "figs2"), "--json", str(vm),
                              "--no-figures", "--no-yardsticks"])
    assert res.exit_code == 0, res.output
    assert json.loads(vm.read_text())["channels"] == v["channels"]


@pytest.mark.parametrize("args, fragments", [
    (["--model", "thermal"], ("--model", "thermal", "econ")),
    (["--model", "econ", "--method", "oe"], ("--method", "not for --model econ")),
])
def test_cli_fit_bad_model_options(econ_file, tmp_path, args, fragments):
    res = runner.invoke(app, ["fit", str(econ_file), "--out", str(tmp_path / "p.json"), *args])
    assert res.exit_code == 2
    assert_one_line_error(res, *fragments)
