"""acid.models.econ_params: the econ parameter file (the declaration's table) and its power map."""

from __future__ import annotations

import re

import numpy as np
import pytest

from acid.errors import DataError
from acid.models import load
from acid.models.econ_params import EconParams
from acid.units import C2K


def test_params_json_round_trip_and_family(econ_truth, tmp_path):
    from acid.models.econ_params import load_any_params
    from acid.models.params import paper

    path = econ_truth.to_json(tmp_path / "econ.json")
    back = EconParams.from_json(path)
    assert back.values == econ_truth.values and back.C_ew == econ_truth.C_ew
    assert back.power_map.coef == econ_truth.power_map.coef
    assert isinstance(load_any_params(path), EconParams)
    paper_file = paper().to_json(tmp_path / "paper.json")
    assert load_any_params(paper_file) == paper() and load_any_params("paper") == paper()
    with pytest.raises(DataError, match="parameters of model 'paper', not 'econ'"):
        EconParams.from_json(paper_file)
    bad = econ_truth.replace(C_cab=-1.0)   # the declaration's checks
    assert bad.problems() == ["C_cab must be positive, got -1"]
    with pytest.raises(DataError, match="C_cab must be positive"):
        load_any_params(bad.to_json(tmp_path / "bad.json"))
    assert load_any_params(tmp_path / "bad.json", allow_unstable=True).C_cab == -1.0


def test_files_written_before_the_one_format_still_load():
    """An econ parameter file as acid wrote it before (``"model": "econ"``, C_ew, beta and
    the power map at the top level) and the repository's params.json (gamma/tau/beta
    lists): the values are the file's, read here independently."""
    import json
    from pathlib import Path

    from acid.models.params import load_params

    root = Path(__file__).parents[1]
    path = root / "tests" / "references" / "econ_params_before_i19.json"
    d = json.loads(path.read_text())
    p = EconParams.from_json(path)
    assert p.values["C_cab"] == d["parameters"]["C_cab"]["value"]
    assert p.C_ew == d["C_ew"]["value"] and p.beta == tuple(d["beta"])
    assert p.power_map.coef == tuple(d["power_map"]["coef"])
    assert p.power_map.domain["Q_e"] == tuple(d["power_map"]["domain"]["Q_e"])
    assert p.power_map.quality == d["power_map"]["quality"] and p.name == d["name"]
    old = json.loads((root / "params.json").read_text())
    q = load_params(root / "params.json")
    assert q.gamma == tuple(old["gamma"]) and q.tau == tuple(old["tau"])
    assert q.beta == tuple(old["beta"]) and q.eta_cop == old["eta_cop"]


def test_the_vector_is_the_declared_table(econ_truth):
    m = load("econ")
    theta = econ_truth.theta_all
    assert theta.shape == (m.np,)
    assert theta[m.parameter_names.index("C_cab")] == econ_truth.C_cab
    assert theta[m.parameter_names.index("f_qt")] == econ_truth.power_map.coef[6]
    assert theta[m.parameter_names.index("beta2")] == econ_truth.beta[1]
    back = EconParams.from_vector(theta, power_map=econ_truth.power_map, name="truth")
    assert back == econ_truth and back.power_map.domain == econ_truth.power_map.domain


def test_power_map_names_what_it_extrapolates(econ_truth):
    pm = econ_truth.power_map
    assert pm.outside(v_veh=np.array([0.0, 20.0]), T_amb=np.array([C2K(30.0)])) == []
    msg = pm.outside(v_veh=np.array([40.0]))
    assert len(msg) == 1 and "v_veh up to 40" in msg[0]
    hot = pm.outside(T_amb=np.array([C2K(70.0)]))   # what the user reads is in degC
    assert len(hot) == 1 and re.search(r"T_amb up to 70 degC \(data [\d.]+-[\d.]+\)", hot[0])
