"""Sweep specifications: grid and list expansion, the scenario key, and one-line errors for
every kind of bad spec, before anything runs."""

from __future__ import annotations

import pytest

import acid.studies.sweep.spec as spec_mod
from acid.errors import ConfigError
from acid.plant.config import PlantConfig
from acid.studies.sweep import spec_from_dict
from acid.studies.sweep.spec import load_spec

GRID = {"grid": {"ambient_C": [25.0, 35.0, 45.0], "cycle": ["udds", "nycc"]}}


def test_grid_is_the_cartesian_product_then_the_list():
    s = spec_from_dict({**GRID, "scenarios": [{"cycle": 20.0, "duration_s": 900.0},
                                              {"humidity_pct": 80.0}]})
    assert len(s.scenarios) == 3 * 2 + 2
    got = [(x.conditions.ambient_C, x.cycle) for x in s.scenarios[:6]]
    assert got == [(25.0, "udds"), (25.0, "nycc"), (35.0, "udds"), (35.0, "nycc"),
                   (45.0, "udds"), (45.0, "nycc")]
    assert s.scenarios[6].cycle == 20.0 and s.scenarios[6].cycle_label == "20 m/s"
    assert s.scenarios[7].conditions.humidity_pct == 80.0
    assert [c.label for c in s.controllers] == ["nmpc", "icm"] and s.baseline == "nmpc"


def test_defaults_and_plant_overrides_merge():
    s = spec_from_dict({"defaults": {"setpoint_C": 23.0, "plant": {"V_disp": 4.0e-5}},
                        "grid": {"plant": [{"C_int": 50e3}, {"V_disp": 2.5e-5}]}})
    a, b = s.scenarios
    assert dict(a.plant) == {"V_disp": 4.0e-5, "C_int": 50e3} and dict(b.plant) == {
        "V_disp": 2.5e-5}
    assert a.plant_config().V_disp == 4.0e-5 and b.plant_config().C_int == PlantConfig().C_int
    assert a.conditions.setpoint_C == 23.0


def test_match_runs_after_its_target_and_rows_keep_spec_order():
    s = spec_from_dict({**GRID, "controllers": {"nmpc": {"match": "icm"}, "icm": {},
                                                "n12": {"type": "nmpc", "horizon": 12}}})
    assert [c.label for c in s.controllers] == ["nmpc", "icm", "n12"]
    assert s.run_order == ("icm", "nmpc", "n12")
    assert s.controllers[2].config.horizon == 12


def test_scenario_key_depends_on_scenario_controllers_and_acid_version(monkeypatch):
    s = spec_from_dict(GRID)
    keys = [s.scenario_key(x) for x in s.scenarios]
    assert len(set(keys)) == len(keys) and keys == [spec_from_dict(GRID).scenario_key(x)
                                                    for x in s.scenarios]
    other = spec_from_dict({**GRID, "controllers": {"nmpc": {"horizon": 8}}})
    assert other.scenario_key(other.scenarios[0]) != keys[0]
    monkeypatch.setattr(spec_mod, "__version__", "9.9.9")
    assert s.scenario_key(s.scenarios[0]) != keys[0]


def test_params_file_is_read_relative_to_the_spec(tmp_path):
    from acid.models.params import paper

    paper().replace(name="mine").to_json(tmp_path / "p.json")
    (tmp_path / "s.toml").write_text('[defaults]\nparams = "p.json"\n[grid]\n'
                                     'ambient_C = [30.0]\n')
    s = load_spec(tmp_path / "s.toml")
    src = s.params["p.json"]
    assert src.kind == "file" and src.params.name == "mine" and len(src.sha256) == 64


BAD = [
    ({"grid": {"ambient_C": []}}, "grid: ambient_C is empty"),
    ({"grid": {"humidity_pct": [50.0, -10.0]}}, "grid: humidity_pct = -10 must lie in 0..100"),
    ({"scenarios": [{"humidity_pct": 120.0}]}, "scenarios #1: humidity_pct = 120"),
    ({"title": "nothing"}, "no scenarios"),
    ({**GRID, "controllers": {"mpc9000": {}}}, "controllers.mpc9000: unknown controller "
                                               "'mpc9000'"),
    ({**GRID, "controllers": {"x": {"type": "warp"}}}, "unknown controller 'warp'"),
    ({**GRID, "controllers": {"nmpc": {"horizont": 6}}}, "unknown key 'horizont'"),
    ({**GRID, "controllers": {"nmpc": {"horizon": "six"}}}, "horizon = 'six' must be an"),
    ({**GRID, "controllers": {"nmpc": {"match": "icm"}}}, "match = 'icm' is not a controller"),
    ({**GRID, "baseline": "icm2"}, "baseline: 'icm2' is not a controller"),
    ({"grid": {"ambient_C": 30.0}}, "grid: ambient_C must be a list"),
    ({"grid": {"ambeint_C": [30.0]}}, "grid: unknown key 'ambeint_C'"),
    ({"humidity_pct": 50.0}, "unknown key 'humidity_pct' (scenario keys go in the defaults"),
    ({"defaults": {"cycle": "ftp75"}, **GRID}, "cycle = 'ftp75' is not a drive cycle"),
    ({"scenarios": [{"cycle": 60.0}]}, "cycle = 60 m/s must lie in 0..45"),
    ({"scenarios": [{"refrigerant": "R744"}]}, "refrigerant = 'R744' not supported"),
    ({"scenarios": [{"setpoint_C": 27.0}]}, "setpoint_C = 27 lies outside band_C"),
    ({"scenarios": [{"band_C": [26.0, 22.0]}]}, "band_C = [26, 22] must satisfy"),
    ({"scenarios": [{"solar_W_m2": 5000.0}]}, "solar_W_m2 = 5000 must lie in 0..1400"),
    ({"scenarios": [{"duration_s": 5.0}]}, "duration_s = 5 is shorter than two samples"),
    ({"scenarios": [{"plant": {"T_amb": 300.0}}]}, "'T_amb' is set by the scenario's "
                                                   "ambient_C"),
    ({"scenarios": [{"plant": {"V_disp": -1.0}}]}, "plant: V_disp must be positive"),
    ({"scenarios": [{"plant": {"bogus": 1.0}}]}, "unknown key 'bogus'"),
    ({"scenarios": [{"params": "nope.json"}]}, "params: 'nope.json': parameter file not found"),
    ({**GRID, "identify": {"method": "magic"}}, "identify: method = 'magic' unknown"),
    ({**GRID, "identify": {"seeds": 1}}, "identify: unknown key 'seeds'"),
    ({**GRID, "plugins": ["no_such_module_x"]}, "plugins: cannot import 'no_such_module_x'"),
]


@pytest.mark.parametrize("d, fragment", BAD, ids=[b[1][:40] for b in BAD])
def test_bad_specs_give_one_line_naming_the_key(d, fragment):
    with pytest.raises(ConfigError) as e:
        spec_from_dict(d, "s.toml")
    msg = str(e.value)
    assert msg.startswith("s.toml: ") and fragment in msg and "\n" not in msg, msg


def test_unreadable_files(tmp_path):
    with pytest.raises(ConfigError, match="sweep specification not found"):
        load_spec(tmp_path / "none.toml")
    (tmp_path / "bad.toml").write_text("x = [1\n")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_spec(tmp_path / "bad.toml")
