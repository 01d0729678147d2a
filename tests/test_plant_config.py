"""PlantConfig: documented defaults, replace/TOML construction, one-line refusals."""

from __future__ import annotations

import dataclasses
import json

import pytest

from acid.errors import ConfigError
from acid.plant.config import REFRIGERANTS, PlantConfig


def test_default_calibration_is_valid_and_documented():
    cfg = PlantConfig()
    assert cfg.refrigerant == "R134a"
    assert cfg.T_amb == pytest.approx(303.15)
    table = PlantConfig.parameter_table()
    assert [row[0] for row in table] == list(PlantConfig.field_names())
    for name, unit, section, source in table:
        assert unit and section and len(source) > 5, name


def test_paper_anchored_cabin_parameters():
    """C_cab, hA_int, hA_sh follow from the paper's gamma1-3 at Ts = 5 s."""
    cfg = PlantConfig()
    assert cfg.c_p_air * cfg.Ts / cfg.C_cab == pytest.approx(1.2999, rel=2e-3)
    assert cfg.hA_int * cfg.Ts / cfg.C_cab == pytest.approx(0.2451, rel=2e-3)
    assert cfg.hA_sh * cfg.Ts / cfg.C_cab == pytest.approx(0.0867, rel=2e-3)


def test_to_dict_is_json_serialisable_and_round_trips():
    cfg = PlantConfig()
    d = json.loads(json.dumps(cfg.to_dict()))
    assert PlantConfig.from_dict(d) == cfg


def test_frozen_and_replace():
    cfg = PlantConfig()
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.T_amb = 300.0
    hot = cfg.replace(T_amb=313.15, refrigerant="R1234yf")
    assert hot.T_amb == 313.15 and hot.refrigerant == "R1234yf" and cfg.T_amb == 303.15
    with pytest.raises(ConfigError, match="unknown parameter 'T_ambient'"):
        cfg.replace(T_ambient=300.0)


@pytest.mark.parametrize("changes, message", [
    ({"C_cab": -10.0}, "C_cab must be positive"),
    ({"C_int": 0.0}, "C_int must be positive"),
    ({"Q_solar_int": -1.0}, "Q_solar_int must not be negative"),
    ({"W_bl_min": 0.2}, "bounds out of order: W_bl_min"),
    ({"N_min": 9000.0}, "bounds out of order: N_min"),
    ({"T_amb": 30.0}, "temperatures are in kelvin"),
    ({"refrigerant": "R744"}, "refrigerant 'R744' not supported"),
    ({"RH_amb": 1.5}, "RH_amb must lie in"),
    ({"dt_int": 0.3}, "must divide Ts"),
    ({"eta_motor": 1.2}, "eta_motor must not exceed 1"),
])
def test_invalid_values_are_refused_in_one_line(changes, message):
    with pytest.raises(ConfigError, match=message) as exc:
        PlantConfig().replace(**changes)
    assert "\n" not in str(exc.value)


def test_refrigerant_options():
    assert set(REFRIGERANTS) == {"R134a", "R1234yf"}
    assert PlantConfig(refrigerant="R1234yf").refrigerant == "R1234yf"


def test_from_toml_flat_and_sectioned(tmp_path):
    path = tmp_path / "plant.toml"
    path.write_text('refrigerant = "R1234yf"\nT_amb = 308.15\n'
                    "[cabin]\nC_int = 70000\n[condenser]\nk_ram = 0.03\n")
    cfg = PlantConfig.from_toml(path)
    assert (cfg.refrigerant, cfg.T_amb, cfg.C_int, cfg.k_ram) == ("R1234yf", 308.15, 70000.0,
                                                                   0.03)
    assert isinstance(cfg.C_int, float)


@pytest.mark.parametrize("text, message", [
    ("T_ambient = 300.0\n", "unknown key 'T_ambient'"),
    ("[cabin]\nC_kab = 1.0\n", "unknown key 'C_kab' in \\[cabin\\]"),
    ("[cabinet]\nC_cab = 1.0\n", "unknown section \\[cabinet\\]"),
    ("[cabin]\nT_amb = 300.0\n", "'T_amb' belongs in \\[ambient\\]"),
    ("[cabin]\nC_cab = -3877.0\n", "C_cab must be positive"),
    ("C_cab = \"big\"\n", "C_cab must be a number"),
    ("anti_windup = 1\n", "anti_windup must be true or false"),
    ("C_cab = = 3\n", "not valid TOML"),
])
def test_from_toml_refuses_bad_files_naming_key_and_file(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message) as exc:
        PlantConfig.from_toml(path)
    assert str(exc.value).startswith(str(path))
    assert "\n" not in str(exc.value)


def test_from_toml_missing_file(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        PlantConfig.from_toml(tmp_path / "nope.toml")
