"""``acid.models.params``: the paper preset makes physical sense in kelvin; params.json is
checked."""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest

from acid.errors import DataError
from acid.models.paper import model
from acid.models.params import PAPER_BETA, PARAMETER_TABLE, ModelParams, load_params, paper
from acid.units import C2K, K2C


def test_paper_preset_holds_the_published_values():
    p = paper()
    assert p.gamma == (0.2451, 0.0867, 1.2999, 1.0047, -0.5176, 0.4553, 34.9579)
    assert p.tau == (-0.1842, -1.3226, 154.4995)
    assert p.beta == (24156.0, -1974.2, 49.318)
    assert (p.c_p, p.eta_cop, p.Ts) == (1008.0, 3.5, 5.0)
    assert len(PARAMETER_TABLE) == 13 and p.theta.shape == (13,)
    assert list(p.as_dict()) == [row[0] for row in PARAMETER_TABLE]


@pytest.mark.parametrize("T_set_C", [3.0, 6.0, 10.0])
def test_evaporator_settles_near_its_set_point(T_set_C):
    """Eq. 2 with the paper's values tracks the set-point in kelvin (the unit slip check)."""
    p = paper()
    T_set = C2K(T_set_C)
    # eq. 2 is affine in T_evap: T_evap(k+1) = a T_evap + b, fixed point b / (1 - a)
    b, a1 = (_declared_step(T_evap, T_set, p)["T_evap"] for T_evap in (0.0, 1.0))
    assert abs(b / (1.0 - (a1 - b)) - T_set) < 0.5
    x, _ = model.simulate([C2K(30.0), C2K(15.0)], np.tile([0.1, T_set], (60, 1)),
                          np.tile([C2K(35.0), C2K(40.0)], (60, 1)), p.theta)
    assert abs(x[-1, model.state_names.index("T_evap")] - T_set) < 0.5
    assert abs(p.gamma[3] + p.gamma[4]) < 1  # stable evaporator pole


@pytest.mark.parametrize("T_evap_C", [3.0, 5.0, 10.0])
def test_inlet_air_is_cool_at_nominal_blower_flow(T_evap_C):
    T_ain = K2C(_declared_step(C2K(T_evap_C), C2K(T_evap_C), paper())["T_ain"])
    assert 5.0 <= T_ain <= 20.0
    # the same formula fed with degC gives an absurd supply temperature: the paper's slip
    assert _declared_step(T_evap_C, T_evap_C, paper())["T_ain"] > 150.0


def _declared_step(T_evap, T_evap_set, p, W_bl=0.1):
    """The paper's declaration one step from T_cab = 30 degC, T_int = 35, T_shell = 40 degC:
    the next T_cab, T_evap and the outputs T_ain, P_bl by name, K and W."""
    x, y = model.step([C2K(30.0), T_evap], [W_bl, T_evap_set], [C2K(35.0), C2K(40.0)], p.theta)
    return {**dict(zip(model.state_names, x, strict=True)),
            **dict(zip(model.output_names, y, strict=True))}


def test_json_round_trip_keeps_values_units_and_provenance(tmp_path):
    p = paper().replace(provenance={"method": "ls", "data_file": "x.h5"})
    path = p.to_json(tmp_path / "params.json", extra={"fit": {"method": "ls"}})
    d = json.loads(path.read_text())
    assert d["model"] == "paper" and d["fit"] == {"method": "ls"}
    assert d["parameters"]["gamma3"] == {"value": 1.2999, "unit": "s/kg", "stderr": None,
                                         "meaning": PARAMETER_TABLE[2][2]}
    q = ModelParams.from_json(path)
    assert q == p and q.provenance == p.provenance
    assert load_params(path) == p and load_params("paper") == paper() and load_params(None)


def _write(tmp_path, text):
    path = tmp_path / "params.json"
    path.write_text(text)
    return path


@pytest.mark.parametrize("text,fragment", [
    ('{"tau": [0, 0, 0]}', "missing key 'gamma'"),
    ('{"gamma": [1, 2, 3, 4, 5, 6, 7]}', "missing key 'tau'"),
    ('{"gamma": [1, 2, 3], "tau": [0, 0, 0]}', "needs 7 numbers"),
    ('{"gamma": [1, 2, 3, 4, 5, 6, 7], "tau": [0, 0]}', "needs 3 numbers"),
    ('{"gamma": [1, 2, 3, 4, 5, 6, NaN], "tau": [0, 0, 0]}', "non-finite"),
    ('{"gamma": [1, 2, 3, 4, 5, 6, 7], "tau": ["a", 0, 0]}', "malformed"),
    ('{"gamma": 5, "tau": [0, 0, 0]}', "malformed"),
    ('{"gamma": [1, 2, 3, 4, 5, 6, 7], "tau": [0, 0, 0], "beta": [0, 0, 0], "eta_cop": -1}',
     "eta_cop = -1 is implausible"),
    ('{"gamma": [1, 2, 3, 4, 5, 6, 7], "tau": [0, 0, 0], "units": "degC (Celsius)"}',
     "Celsius"),
    ("[1, 2, 3]", "JSON object"),
    ("gamma = 1", "not valid JSON"),
])
def test_bad_params_json_is_a_one_line_data_error(tmp_path, text, fragment):
    path = _write(tmp_path, text)
    with pytest.raises(DataError, match=fragment) as info:
        ModelParams.from_json(path)
    msg = str(info.value)
    assert str(path) in msg and "\n" not in msg


def test_missing_file_is_a_data_error(tmp_path):
    with pytest.raises(DataError, match="not found"):
        load_params(tmp_path / "absent.json")


def test_params_are_frozen_and_perturbation_is_seeded():
    p = paper()
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.gamma = (0.0,) * 7
    a = p.perturbed(0.1, np.random.default_rng(1))
    b = p.perturbed(0.1, np.random.default_rng(1))
    assert a == b and a != p and a.beta == PAPER_BETA
    # the dynamics (eqs. 1-3, eq. 3 substituted into eq. 1) are perturbed, in table order
    z = np.random.default_rng(1).standard_normal(10)
    assert np.allclose(a.theta[:10], p.theta[:10] * (1 + 0.1 * z), rtol=0, atol=1e-12)


def test_groups_constants_and_vectors_are_derived_from_the_table():
    p = paper()
    assert p.gamma == tuple(p.values[f"gamma{i}"] for i in range(1, 8))
    assert p.tau == (p.tau1, p.tau2, p.tau3) and p.beta[0] == p.beta1
    assert p.replace(eta_cop=2.5).eta_cop == 2.5 and p.eta_cop == 3.5
    with pytest.raises(DataError, match="eta_cop = 99 is implausible"):
        p.replace(eta_cop=99.0)
    with pytest.raises(DataError, match="no parameter, group or constant 'gamma8'"):
        p.replace(gamma8=1.0)
    theta = p.theta * 2.0
    q = p.with_theta(theta, name="doubled")
    assert np.array_equal(q.theta, theta) and q.name == "doubled" and q.c_p == p.c_p
    with pytest.raises(DataError, match="13 numbers"):
        p.with_theta(theta[:5])


# ----------------------------------------------------------------- plausibility
def _with_gamma(i: int, value: float):
    g = list(paper().gamma)
    g[i] = value
    return paper().replace(gamma=tuple(g))


def test_the_paper_parameters_are_stable_and_in_kelvin():
    assert paper().stability_problems() == []


@pytest.mark.parametrize("p,fragment", [
    (_with_gamma(3, 3.0), "|gamma4 + gamma5| < 1"),          # evaporator pole 2.48
    (_with_gamma(0, 50.0), "cabin pole"),                      # 1 - 50 - ... = -49
    (_with_gamma(0, 1e308), "cabin pole"),
    (_with_gamma(6, 1e308), "T_ain"),                          # stable but not a temperature
    (paper().replace(tau=(-0.1842, -300.0, 154.4995)), "steady T_evap"),
])
def test_unstable_or_non_kelvin_parameters_are_named(p, fragment):
    problems = p.stability_problems()
    assert problems and fragment in problems[0]
    with pytest.raises(DataError, match="allow-unstable"):
        p.check("p.json")


def test_load_params_refuses_unstable_files_unless_allowed(tmp_path):
    path = _with_gamma(3, 3.0).to_json(tmp_path / "p.json")
    with pytest.raises(DataError, match="gamma4"):
        load_params(path)
    assert load_params(path, allow_unstable=True).gamma[3] == 3.0


@pytest.mark.parametrize("key,value,fragment", [
    ("gamma", "1111111", "'gamma' must be a list"),
    ("gamma", {str(i): 0.1 for i in range(7)}, "'gamma' must be a list"),
    ("gamma", [0.1, 0.1, 0.1, True, 0.1, 0.1, 0.1], "'gamma[3]' must be a number"),
    ("c_p", "1008", "'c_p' must be a number"),
    ("c_p", 1.008, "c_p = 1.008 is implausible"),
    ("name", ["x"], "'name' must be a text"),
    ("provenance", [1], "'provenance' must be a JSON object"),
])
def test_values_of_the_wrong_type_are_refused_not_iterated(tmp_path, key, value, fragment):
    p = paper()   # the layout of the files before the one format: groups as lists
    d = {"gamma": list(p.gamma), "tau": list(p.tau), "beta": list(p.beta), "c_p": p.c_p}
    d[key] = value
    path = _write(tmp_path, json.dumps(d))
    with pytest.raises(DataError, match=re.escape(fragment)):
        ModelParams.from_json(path)
