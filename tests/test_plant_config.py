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
    ({"G_solar": -1.0}, "G_solar must not be negative"),
    ({"C_int_slow": -5.0}, "C_int_slow must be positive"),
    ({"p_derate": 4.0e6}, "bounds out of order: p_derate"),
    ({"T_ew_set_max": 270.0}, "bounds out of order: T_ew_set"),
    ({"k_ram": 0.03}, "generation-1 parameter"),
    ({"W_bl_min": 0.2}, "bounds out of order: W_bl_min"),
    ({"N_min": 9000.0}, "bounds out of order: N_min"),
    ({"T_amb": 30.0}, "temperatures are in kelvin"),
    ({"refrigerant": "R744"}, "refrigerant 'R744' not supported"),
    ({"RH_amb": 1.5}, "RH_amb must lie in"),
    ({"dt_int": 0.3}, "must divide Ts"),
    ({"eta_fan": 1.2}, "eta_fan must not exceed 1"),
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
    path.write_text('refrigerant = "R1234yf"\nT_amb = 35.0\n'
                    "[cabin]\nC_int = 70000\n[condenser]\nC_ram = 0.45\n")
    cfg = PlantConfig.from_toml(path)
    assert (cfg.refrigerant, cfg.T_amb, cfg.C_int, cfg.C_ram) == ("R1234yf", 308.15, 70000.0,
                                                                   0.45)
    assert isinstance(cfg.C_int, float)


@pytest.mark.parametrize("text, message", [
    ("T_ambient = 300.0\n", "unknown key 'T_ambient'"),
    ("[cabin]\nC_kab = 1.0\n", "unknown key 'C_kab' in \\[cabin\\]"),
    ("[cabinet]\nC_cab = 1.0\n", "unknown section \\[cabinet\\]"),
    ("[cabin]\nT_amb = 30.0\n", "'T_amb' belongs in \\[ambient\\]"),
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


def test_every_parameter_cites_a_source_or_says_assumption():
    """Each field's source names a reference key of datasets/plant/SOURCES.md, the paper, a
    standard physical constant, or labels itself an assumption / calibrated."""
    import re
    from pathlib import Path

    sources = (Path(__file__).parents[1] / "datasets" / "plant" / "SOURCES.md").read_text()
    keys = set(re.findall(r"^\| \[([A-Za-z0-9.-]+)\]", sources, flags=re.M))
    for name, _unit, _section, source in PlantConfig.parameter_table():
        cited = re.findall(r"\[([A-Za-z0-9.-]+)\]", source)
        for key in cited:
            assert key in keys, f"{name}: [{key}] is not in SOURCES.md"
        assert cited or re.search(r"assumption|calibrated|reference|standard|fixed|latent|"
                                  r"paper|design|False|internal step", source), name


def test_solar_is_one_irradiance_times_cited_areas():
    cfg = PlantConfig()
    dark = cfg.replace(G_solar=0.0)
    assert dark.Q_solar_int == 0.0 and dark.Q_solar_shell == 0.0
    sun = cfg.replace(G_solar=1000.0)
    assert sun.Q_solar_int == pytest.approx(1000.0 * cfg.A_glass_sun * cfg.tau_glass)
    assert sun.Q_solar_shell == pytest.approx(1000.0 * cfg.A_shell_sun * cfg.alpha_shell)


def test_flat_plate_shell_convection_and_speed_blind_switches():
    cfg = PlantConfig()
    h25 = (cfg.hA_ext(25.0) - cfg.hA_ext0) / cfg.A_shell
    assert 40.0 < h25 < 65.0  # PLANT.md: 40-60 W/(m^2 K) at 25 m/s on top of the parked value
    blind = cfg.replace(k_ram=0.0, hA_ext_v=0.0)  # generation-1 names, as callers use them
    assert not blind.front_end_speed and not blind.cabin_speed
    assert blind.hA_ext(25.0) == blind.hA_ext0


def test_every_numeric_parameter_has_a_physical_range_holding_its_default():
    import dataclasses

    from acid.plant.config import RANGES

    numeric = {f.name for f in dataclasses.fields(PlantConfig) if f.metadata["unit"] != "-"}
    assert set(RANGES) == numeric
    c = PlantConfig()
    for name, (lo, hi, why) in RANGES.items():
        assert lo < hi and why and lo <= getattr(c, name) <= hi, name


@pytest.mark.parametrize("changes, fragments", [
    ({"V_disp": 1.0}, ["V_disp = 1 m^3", "physical range 5e-06..0.0005 m^3"]),
    ({"C_cab": 5.0e7}, ["C_cab = 5e+07 J/K", "500..100000 J/K"]),
    ({"P_rated": 1.0e9}, ["P_rated", "200..100000 W"]),
    ({"dt_int": 0.001, "Ts": 60.0}, ["60000 internal steps", "at most 10000"]),
])
def test_absurd_positive_values_are_refused_naming_the_key_and_its_range(changes, fragments):
    with pytest.raises(ConfigError) as err:
        PlantConfig().replace(**changes)
    assert all(f in str(err.value) for f in fragments), str(err.value)


def test_a_plant_toml_with_absurd_or_deep_values_is_one_line(tmp_path):
    f = tmp_path / "p.toml"
    f.write_text("[compressor]\nV_disp = 1.0\n")
    with pytest.raises(ConfigError, match=r"p.toml: V_disp = 1 m\^3 is outside"):
        PlantConfig.from_toml(f)
    f.write_text("[compressor]\nV_disp = " + "[" * 3000 + "]" * 3000 + "\n")
    with pytest.raises(ConfigError, match="p.toml: plant configuration nests 3000 levels"):
        PlantConfig.from_toml(f)
    f.write_text("[compressor]\nV_disp = { a = 1 }\n")
    with pytest.raises(ConfigError, match="p.toml: V_disp must be a number"):
        PlantConfig.from_toml(f)


# ------------------------------------------------------------- units in a plant file (issue 23)
@pytest.mark.parametrize("text, expected_K", [
    ("T_amb = 35.0\n", 308.15),                # a plain number is degC
    ('T_amb = "35 degC"\n', 308.15),
    ('T_amb = "308.15 K"\n', 308.15),          # kelvin only when tagged
    ('T_amb = "95 degF"\n', 308.15),
    ("T_amb = -5\n", 268.15),
])
def test_file_temperatures_are_degC_or_tagged(tmp_path, text, expected_K):
    path = tmp_path / "p.toml"
    path.write_text(text)
    assert PlantConfig.from_toml(path).T_amb == pytest.approx(expected_K, abs=1e-9)


def test_file_temperature_differences_are_K_plain_or_tagged(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text('[compressor]\nsuperheat = 6.0\nsubcool = "4 K"\n')
    cfg = PlantConfig.from_toml(path)
    assert (cfg.superheat, cfg.subcool) == (6.0, 4.0)


@pytest.mark.parametrize("text, message", [
    ("T_amb = 308.15\n", 'read in degC .* write T_amb = "308.15 K"'),   # untagged kelvin
    ("[initial]\nT_cab0 = 328.15\n", 'T_cab0 = 328.15 is read in degC'),
    ('T_amb = "35 C"\n', "T_amb = '35 C': give a number or \"NUMBER UNIT\""),
    ('T_amb = "warm degC"\n', "temperature unit"),
    ('T_amb = "35 W"\n', "temperature unit"),
    ("T_amb = 60.0\n", "T_amb = 60 degC is outside the refrigerant property tables"),
    ("T_amb = nan\n", "T_amb must be a finite number, got nan"),
    ("T_amb = 1" + "0" * 400 + "\n", "T_amb must be a finite number, got an integer too large"),
    ("[cabin]\nC_cab = 1" + "0" * 400 + "\n", "C_cab must be a finite number"),
])
def test_file_temperatures_refused_with_one_line_naming_key(tmp_path, text, message):
    path = tmp_path / "p.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message) as exc:
        PlantConfig.from_toml(path)
    assert str(exc.value).startswith(str(path)) and "\n" not in str(exc.value)


def test_file_dict_round_trips_and_speaks_degC():
    cfg = PlantConfig().replace(T_amb=313.15, superheat=6.0)
    d = cfg.to_file_dict()
    assert d["T_amb"] == pytest.approx(40.0) and d["T_cab0"] == pytest.approx(40.0)
    assert d["superheat"] == 6.0                      # a difference stays K
    assert PlantConfig.from_file_dict(d) == cfg


def test_the_shipped_paper_vehicle_is_written_in_degC():
    from acid.plant.vehicles import vehicle_config, vehicle_file

    text = vehicle_file("paper").read_text()
    assert "T_cab0 = 55.0" in text
    assert vehicle_config("paper").T_cab0 == pytest.approx(328.15)
