"""FMU plants (``acid.plant.fmi.plant``) and the exported plant FMU (``acid.plant.fmi.export``).

Real FMUs only: acid's own high-fidelity plant exported with pythonfmu (FMI 2.0, session
fixture ``exported_fmu``) and pythonfmu3 (FMI 3.0), and a small user FMU in other units
(``tests/fmu_slaves/CabinLag.py``: degC, kg/h, kW, instantaneous outputs).
"""

from __future__ import annotations

import dataclasses
import math
import re
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from acid.errors import ConfigError
from acid.excite import ExcitationSpec, excite
from acid.plant import make_plant
from acid.plant.fmi.plant import FmuError, FmuMap, FmuPlant
from acid.plant.hifi import HifiPlant
from acid.units import C2K

SLAVES = Path(__file__).parent / "fmu_slaves"


def _max_temperature_difference(a, b) -> dict[str, float]:
    return {c: float(np.max(np.abs(a[c] - b[c]))) for c in a.channels if a.units[c] == "degC"}


def _excite_both(fmu, fmu_map, spec):
    native = excite(make_plant("hifi", meas_noise_std=spec.noise, rng=spec.rng("noise")), spec)
    plant = make_plant(f"fmu:{fmu}", fmu_map=fmu_map, meas_noise_std=spec.noise,
                       rng=spec.rng("noise"))
    return native, excite(plant, spec)


# ----------------------------------------------------------------- exported plant
def test_exported_fmu_equals_the_native_plant_channel_for_channel(exported_fmu):
    fmu, fmu_map = exported_fmu
    spec = ExcitationSpec(seed=3, duration=600.0, noise=0.05)
    native, through = _excite_both(fmu, fmu_map, spec)
    assert set(native.channels) == set(through.channels)
    assert native.units == through.units
    diff = _max_temperature_difference(native, through)
    assert {"T_cab", "T_evap", "T_ain", "T_int", "T_shell"} <= set(diff)
    assert max(diff.values()) <= 1e-6, diff
    for c in ("P_comp", "P_bl", "W_bl", "COP", "N_comp"):
        np.testing.assert_allclose(through[c], native[c], rtol=1e-12, atol=1e-9)
    cfg = through.metadata["plant_config"]
    assert through.metadata["plant"] == "fmu" and cfg["fmi_version"] == "2.0"
    assert cfg["embedded"]["config"]["T_amb"] == pytest.approx(303.15)


def test_fmi3_export_and_sub_steps_equal_the_native_plant(tmp_path, exported_fmu):
    from acid.plant.fmi.export import export_fmu

    res = export_fmu(tmp_path / "p3.fmu", fmi_version=3, map_out=tmp_path / "p3.toml")
    spec = ExcitationSpec(seed=1, duration=300.0)
    fmu2, map2 = exported_fmu
    for fmu, m in ((res.fmu, res.fmu_map), (fmu2, map2)):
        halved = dataclasses.replace(FmuMap.from_file(m), step=2.5)  # two steps per sample
        native, through = _excite_both(fmu, halved, spec)
        diff = _max_temperature_difference(native, through)
        assert max(diff.values()) <= 1e-9, (fmu, diff)
        np.testing.assert_allclose(through["P_comp"], native["P_comp"], rtol=1e-12)
    assert make_plant(f"fmu:{res.fmu}", fmu_map=res.fmu_map).fmi_version.startswith("3.")


def test_initial_state_ambient_and_compressor_switch_reach_the_fmu(exported_fmu):
    fmu, fmu_map = exported_fmu
    init = {"T_cab": C2K(27.0), "T_evap": C2K(12.0), "T_int": C2K(30.0),
            "T_shell": C2K(33.0)}
    native, plant = HifiPlant(), make_plant(f"fmu:{fmu}", fmu_map=fmu_map)
    for p in (native, plant):
        p.reset(init)
    kws = [{"T_amb": C2K(35.0)}, {}, {"compressor_enabled": False}, {}, {"T_amb": C2K(25.0)}]
    for kw in kws * 3:
        a, b = native.step(0.1, C2K(4.0), 12.0, **kw), plant.step(0.1, C2K(4.0), 12.0, **kw)
        assert a.keys() == b.keys()
        assert max(abs(a[k] - b[k]) for k in a) <= 1e-9, kw
    assert native.measure() == pytest.approx(plant.measure(), abs=1e-9)
    # reset brings the FMU back to the hot soak, as the native plant
    assert plant.reset() == pytest.approx(HifiPlant().reset(), abs=1e-12)


def test_speed_sweep_through_the_fmu_runs_its_nominal_controller(exported_fmu):
    from acid.plant.sweep import speed_sweep

    fmu, fmu_map = exported_fmu
    native = speed_sweep(speeds=(0.0, 25.0), duration=100.0)
    through = speed_sweep(speeds=(0.0, 25.0), duration=100.0, plant_factory=lambda: make_plant(
        f"fmu:{fmu}", fmu_map=fmu_map, mode="nominal"))
    np.testing.assert_allclose(through.energy_MJ, native.energy_MJ, rtol=1e-12)
    assert through.energy_MJ[1] < through.energy_MJ[0]  # ram air lowers the energy


def test_closed_loop_scenario_on_the_fmu_equals_the_native_plant(exported_fmu):
    from acid.models.params import paper
    from acid.studies.mpc_check.scenarios import run_plant_scenario

    fmu, fmu_map = exported_fmu
    native = run_plant_scenario(paper(), duration_s=40.0)
    through = run_plant_scenario(paper(), duration_s=40.0, plant_factory=lambda: make_plant(
        f"fmu:{fmu}", fmu_map=fmu_map))
    for a, b in zip(native.runs, through.runs, strict=True):
        np.testing.assert_allclose(b.T_cab, a.T_cab, atol=1e-9)
        np.testing.assert_allclose(b.P_comp, a.P_comp, rtol=1e-9)


def test_the_shipped_example_map_drives_the_exported_fmu(exported_fmu):
    from acid.plant.fmi.export import fmu_map_text, plant_interface

    fmu, _ = exported_fmu
    example = Path(__file__).parents[1] / "datasets" / "examples" / "acid_hifi_fmu_map.toml"
    plant = FmuPlant(fmu, example)
    assert {"T_cab", "T_evap", "T_int", "T_shell"} <= set(plant.measure())
    # the example is what export-fmu writes for the current plant (regenerate it if not)
    expected = fmu_map_text(plant_interface(), "plant.fmu", 2)
    assert _toml_body(example.read_text()) == _toml_body(expected)


def _toml_body(text: str) -> list[str]:
    return [ln for ln in text.splitlines() if ln.strip() and not ln.startswith("#")]


# --------------------------------------------------------------------- a user FMU
@pytest.fixture(scope="module")
def cabin_lag(tmp_path_factory):
    """A user FMU in degC, kg/h and kW with instantaneous outputs, and its map."""
    from pythonfmu.builder import FmuBuilder

    folder = tmp_path_factory.mktemp("cabinlag")
    saved = list(sys.path)
    try:
        fmu = FmuBuilder.build_FMU(SLAVES / "CabinLag.py", dest=folder / "CabinLag.fmu")
    finally:
        sys.path[:] = saved
        sys.modules.pop("CabinLag", None)
    fmu_map = folder / "cabin.toml"
    fmu_map.write_text("""
[fmu]
Ts = 5.0
step = 1.0
[inputs]
W_bl = { name = "W_bl_kgh", unit = "kg/h" }
T_evap_set = { name = "T_set_C", unit = "degC" }
[states]
T_cab = { name = "T_cab_C", unit = "degC" }
T_evap = { name = "T_evap_C", unit = "degC" }
T_int = { name = "T_int_C", unit = "degC" }
T_shell = { name = "T_shell_C", unit = "degC" }
[outputs]
T_ain = { name = "T_ain_C", unit = "degC" }
P_comp = { name = "P_comp_kW", unit = "kW" }
[initial]
T_cab = { name = "T_cab0_C", unit = "degC" }
[parameters]
tau = 50.0
""")
    return Path(fmu), fmu_map


def test_user_fmu_units_are_converted_and_instant_outputs_averaged(cabin_lag):
    fmu, fmu_map = cabin_lag
    plant = FmuPlant(fmu, fmu_map)
    s0 = plant.reset({"T_cab": C2K(30.0)})
    assert s0["T_cab"] == pytest.approx(C2K(30.0))
    row = plant.step(0.1, C2K(5.0))  # 360 kg/h, 5 degC
    assert row["T_cab"] == pytest.approx(C2K(30.0))          # state at t_k
    assert row["P_comp"] == pytest.approx(1000.0)             # 1 kW as W
    tau, Ts = 50.0, 5.0
    exact_mean = C2K(5.0 - 10.0 + 25.0 * tau / Ts * (1 - math.exp(-Ts / tau)))
    end_value = C2K(5.0 - 10.0 + 25.0 * math.exp(-Ts / tau))
    assert abs(row["T_ain"] - exact_mean) < 2e-3             # trapezoid over 1 s sub-steps
    assert abs(end_value - exact_mean) > 0.5                  # (not the end-point value)
    assert plant.measure()["T_cab"] == pytest.approx(C2K(5.0 + 25.0 * math.exp(-0.1)))
    assert plant.units()["T_cab"] == "K" and plant.units()["P_comp"] == "W"


def test_a_terminating_fmu_is_a_one_line_error(cabin_lag, tmp_path):
    fmu, fmu_map = cabin_lag
    text = fmu_map.read_text().replace("tau = 50.0", "tau = 50.0\nstop_after = 12.0")
    m = tmp_path / "stop.toml"
    m.write_text(text)
    plant = FmuPlant(fmu, m)
    plant.step(0.1, C2K(5.0))
    plant.step(0.1, C2K(5.0))
    with pytest.raises(FmuError, match=r"CabinLag.fmu: the FMU terminated the simulation at "
                                       r"t = 12 s"):
        plant.step(0.1, C2K(5.0))


# -------------------------------------------------------------------------- errors
def test_failed_do_step_names_the_fmu_and_the_variable(exported_fmu):
    fmu, fmu_map = exported_fmu
    plant = make_plant(f"fmu:{fmu}", fmu_map=fmu_map)
    with pytest.raises(FmuError) as err:
        plant.step(0.1, C2K(5.0), 0.0, T_amb=500.0)
    msg = str(err.value)
    assert msg.startswith("plant.fmu: fmi2DoStep") and "T_amb" in msg and "\n" not in msg


def test_corrupt_and_model_exchange_only_fmus_are_refused(exported_fmu, tmp_path):
    fmu, fmu_map = exported_fmu
    bad = tmp_path / "corrupt.fmu"
    bad.write_bytes(fmu.read_bytes()[: 2000])
    with pytest.raises(FmuError, match="corrupt.fmu: not a valid FMU"):
        make_plant(f"fmu:{bad}", fmu_map=fmu_map)
    me = tmp_path / "me_only.fmu"
    _model_exchange_only(fmu, me)
    with pytest.raises(FmuError, match="me_only.fmu: the FMU supports model exchange only"):
        make_plant(f"fmu:{me}", fmu_map=fmu_map)


def _model_exchange_only(src: Path, dst: Path) -> None:
    """A copy of ``src`` whose modelDescription.xml declares model exchange only."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = re.sub(rb"<CoSimulation [^>]*?modelIdentifier=\"(\w+)\"[^>]*/>",
                              rb'<ModelExchange modelIdentifier="\1"/>', data)
                assert b"<ModelExchange" in data
            zout.writestr(item, data)


@pytest.mark.parametrize(("edit", "fragments"), [
    (('"state.T_cab"', '"state.T_cabin"'),
     ("[states] T_cab", "'state.T_cabin'", "plant.fmu does not have", "'state.T_cab'")),
    (('T_cab = { name = "state.T_cab", unit = "K" }',
      'T_cab = { name = "state.T_cab", unit = "degC" }'),
     ("[states] T_cab", "unit 'degC'", "declares 'K'")),
    (('unit = "kg/s"', 'unit = "furlong"'), ("[inputs] W_bl", "unknown unit 'furlong'")),
    (('T_ain = {', 'T_ain_x = {'), ("[outputs] must map T_ain",)),
    (("[fmu]", "[fmu]\nsteps = 1"), ("unknown key 'steps' in [fmu]",)),
    (('step = 5.0', 'step = 3.0'), ("step = 3 s must divide Ts = 5 s",)),
])
def test_bad_maps_are_one_line_errors_naming_key_and_variable(exported_fmu, tmp_path, edit,
                                                                fragments):
    fmu, fmu_map = exported_fmu
    text = fmu_map.read_text()
    assert edit[0] in text
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(edit[0], edit[1], 1))
    with pytest.raises((FmuError, ConfigError)) as err:
        make_plant(f"fmu:{fmu}", fmu_map=bad)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(str(bad))
    for f in fragments:
        assert f in msg, msg


def test_step_keywords_the_map_lacks_are_refused(cabin_lag):
    fmu, fmu_map = cabin_lag
    plant = FmuPlant(fmu, fmu_map)
    with pytest.raises(ConfigError, match="no \\[inputs\\] T_amb"):
        plant.step(0.1, C2K(5.0), 0.0, T_amb=C2K(30.0))
    with pytest.raises(ConfigError, match="no \\[inputs\\] v_veh"):
        plant.step(0.1, C2K(5.0), 10.0)
    with pytest.raises(ConfigError, match="no \\[initial\\] entry for 'T_int'"):
        plant.reset({"T_int": C2K(30.0)})
    with pytest.raises(ConfigError, match="no \\[modes.nominal\\]"):
        FmuPlant(fmu, fmu_map, mode="nominal")
    plant.step(0.1, C2K(5.0), 0.0, T_int=C2K(30.0))  # accepted and ignored, as HifiPlant


def test_the_configuration_is_baked_into_the_fmu(tmp_path):
    from acid.plant.config import PlantConfig
    from acid.plant.fmi.export import export_fmu

    cfg = PlantConfig().replace(T_amb=C2K(38.0), RH_amb=0.3)
    res = export_fmu(tmp_path / "hot.fmu", cfg, map_out=tmp_path / "hot.toml")
    plant = FmuPlant(res.fmu, res.fmu_map)
    assert plant.config()["embedded"]["config"]["T_amb"] == pytest.approx(C2K(38.0))
    native = HifiPlant(cfg)
    for _ in range(10):
        a, b = native.step(0.12, C2K(6.0), 5.0), plant.step(0.12, C2K(6.0), 5.0)
        assert max(abs(a[k] - b[k]) for k in a) <= 1e-9


# -------------------------------------------------- hostile archives (issue 24)
def _with_members(src: Path, dst: Path, members: dict[str, bytes],
                  compression=zipfile.ZIP_DEFLATED) -> Path:
    """A copy of the FMU ``src`` with more members."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", compression) as zout:
        for item in zin.infolist():
            zout.writestr(item, zin.read(item.filename))
        for name, data in members.items():
            zout.writestr(name, data)
    return dst


@pytest.fixture
def private_tmp(tmp_path, monkeypatch):
    """A temporary-files folder of this test's own, to see what an FMU left behind."""
    import tempfile

    folder = tmp_path / "tmp"
    folder.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    return folder


def test_a_zip_bomb_is_refused_before_anything_is_extracted(exported_fmu, tmp_path,
                                                            monkeypatch, private_tmp):
    import acid.plant.fmi.plant as fmu_module

    fmu, fmu_map = exported_fmu
    with zipfile.ZipFile(fmu) as z:
        real = sum(m.file_size for m in z.infolist())
    # the limit scaled down to this FMU's size: 8 MB of zeros compress to about 8 kB
    monkeypatch.setattr(fmu_module, "MAX_FMU_BYTES", real + (1 << 20))
    bomb = _with_members(fmu, tmp_path / "bomb.fmu", {"resources/zeros.bin": bytes(8 << 20)})
    assert bomb.stat().st_size < fmu.stat().st_size + (1 << 20)
    with pytest.raises(FmuError, match=r"bomb.fmu: the FMU unpacks to \d+ MB \(at most"):
        make_plant(f"fmu:{bomb}", fmu_map=fmu_map)
    monkeypatch.setattr(fmu_module, "MAX_FMU_MEMBERS", 40)
    many = _with_members(fmu, tmp_path / "many.fmu", {f"resources/f{i}": b"" for i in range(50)})
    with pytest.raises(FmuError, match=r"many.fmu: the FMU holds \d+ files \(at most 40\)"):
        make_plant(f"fmu:{many}", fmu_map=fmu_map)
    assert list(private_tmp.iterdir()) == []


@pytest.mark.parametrize("name", ["../escape.txt", "/abs/escape.txt", "resources/../../x",
                                  "C:/escape.txt", "..\\escape.txt"])
def test_a_member_escaping_the_folder_is_refused(exported_fmu, tmp_path, private_tmp, name):
    fmu, fmu_map = exported_fmu
    bad = _with_members(fmu, tmp_path / "bad.fmu", {name: b"x"})
    with pytest.raises(FmuError, match="bad.fmu: the FMU member .* escapes its folder"):
        make_plant(f"fmu:{bad}", fmu_map=fmu_map)
    assert list(private_tmp.iterdir()) == [] and not (tmp_path / "escape.txt").exists()


def test_an_fmu_failing_during_extraction_leaves_no_temporary_folder(exported_fmu, tmp_path,
                                                                      private_tmp):
    fmu, fmu_map = exported_fmu
    payload = b"acid-payload-" * 20
    bad = _with_members(fmu, tmp_path / "crc.fmu", {"resources/data.bin": payload},
                        compression=zipfile.ZIP_STORED)
    raw = bytearray(bad.read_bytes())
    at = raw.index(payload)
    raw[at] ^= 0xFF  # the stored data no longer matches its CRC
    bad.write_bytes(bytes(raw))
    with pytest.raises(FmuError, match="crc.fmu: cannot extract the FMU"):
        make_plant(f"fmu:{bad}", fmu_map=fmu_map)
    assert list(private_tmp.iterdir()) == []


def test_an_fmu_rejected_after_unpacking_leaves_no_temporary_folder(exported_fmu, tmp_path,
                                                                    private_tmp):
    """The map names a variable the FMU lacks: refused after extraction, folder removed."""
    import shutil

    fmu, fmu_map = exported_fmu
    own = tmp_path / "own.fmu"
    shutil.copy(fmu, own)  # a file of its own: nothing cached for it
    bad_map = tmp_path / "bad.toml"
    bad_map.write_text(fmu_map.read_text().replace('"state.T_cab"', '"state.T_nowhere"'))
    with pytest.raises(FmuError, match="own.fmu does not have"):
        make_plant(f"fmu:{own}", fmu_map=bad_map)
    assert list(private_tmp.iterdir()) == []
