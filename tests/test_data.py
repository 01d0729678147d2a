"""acid.data: the HDF5 layout, validation on read, atomic writes, CSV/MAT import."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from acid.data import FORMAT_NAME, ChannelMap, Dataset, from_csv, from_mat
from acid.errors import DataError


def _small(n: int = 50, Ts: float = 5.0) -> Dataset:
    t = np.arange(n) * Ts
    return Dataset(
        time=t,
        channels={"T_cab": 30 + np.sin(t / 100), "W_bl": np.full(n, 0.1),
                  "T_evap": np.linspace(4, 8, n), "pressure": np.full(n, 1e5)},
        units={"pressure": "Pa"}, Ts=Ts,
        metadata={"plant": "model", "seed": 3, "excitation": {"signal": "aprbs"}},
    )


def _write_raw(path, ds: Dataset, **overrides) -> None:
    """Write the layout by hand, so that readers see data the writer would never produce."""
    chans = dict(ds.channels)
    chans.update(overrides.pop("channels", {}))
    units = dict(ds.units)
    units.update(overrides.pop("units", {}))
    time = overrides.pop("time", ds.time)
    with h5py.File(path, "w") as f:
        f.attrs["format"] = FORMAT_NAME
        f.attrs["Ts"] = ds.Ts
        f.attrs["metadata"] = json.dumps({})
        f["time"] = time
        for name, v in chans.items():
            f[f"channels/{name}"] = v
            f[f"channels/{name}"].attrs["unit"] = units[name]


# ------------------------------------------------------------------ round trip
def test_hdf5_round_trip_keeps_values_units_roles_metadata(tmp_path):
    ds = _small()
    ds.experiment[25:] = 1
    path = ds.to_hdf5(tmp_path / "d.h5", created="2026-01-01T00:00:00+00:00")
    back = Dataset.from_hdf5(path)
    assert back.Ts == 5.0 and len(back) == 50
    np.testing.assert_array_equal(back.time, ds.time)
    np.testing.assert_array_equal(back.experiment, ds.experiment)
    for name, values in ds.channels.items():
        np.testing.assert_array_equal(back[name], values)
        assert back.units[name] == ds.units[name]
        assert back.roles[name] == ds.roles[name]
    assert back.units["T_cab"] == "degC" and back.units["pressure"] == "Pa"
    assert back.roles["T_cab"] == "state" and back.roles["W_bl"] == "input"
    assert back.metadata["seed"] == 3 and back.metadata["plant"] == "model"
    assert back.metadata["created"] == "2026-01-01T00:00:00+00:00"
    assert "acid_version" in back.metadata
    assert back.segments() == [(0, 25), (25, 50)]
    np.testing.assert_allclose(back.get("T_cab", "K"), ds["T_cab"] + 273.15)
    with h5py.File(path) as f:
        assert f.attrs["format"] == FORMAT_NAME
        assert f["time"].attrs["unit"] == "s"
        assert f["channels/T_cab"].attrs["unit"] == "degC"


def test_round_trip_of_model_dataset(tmp_path, model_dataset):
    back = Dataset.from_hdf5(model_dataset.to_hdf5(tmp_path / "m.h5"),
                             require=("T_cab", "T_int", "T_shell"), min_samples=1440)
    assert back.metadata["plant"] == "model"
    assert back.metadata["excitation"]["seed"] == 0
    np.testing.assert_array_equal(back["T_ain"], model_dataset["T_ain"])


# ------------------------------------------------------------- bad inputs on read
def _assert_one_line(exc_info, *words):
    msg = str(exc_info.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg


def test_missing_channel_names_file_and_channel(tmp_path):
    path = _small().to_hdf5(tmp_path / "d.h5")
    with pytest.raises(DataError) as e:
        Dataset.from_hdf5(path, require=("T_cab", "T_ain"))
    _assert_one_line(e, str(path), "'T_ain'", "missing")


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_nan_and_inf_are_refused(tmp_path, bad):
    ds = _small()
    v = ds["T_evap"].copy()
    v[7] = bad
    path = tmp_path / "d.h5"
    _write_raw(path, ds, channels={"T_evap": v})
    with pytest.raises(DataError) as e:
        Dataset.from_hdf5(path)
    _assert_one_line(e, str(path), "'T_evap'", "NaN/inf", "t = 35")


def test_non_monotonic_time_is_refused(tmp_path):
    ds = _small()
    t = ds.time.copy()
    t[10], t[11] = t[11], t[10]
    path = tmp_path / "d.h5"
    _write_raw(path, ds, time=t)
    with pytest.raises(DataError) as e:
        Dataset.from_hdf5(path)
    _assert_one_line(e, str(path), "time", "not strictly increasing")


def test_non_uniform_time_is_refused(tmp_path):
    ds = _small()
    t = ds.time.copy()
    t[20:] += 1.0  # one 6 s step
    path = tmp_path / "d.h5"
    _write_raw(path, ds, time=t)
    with pytest.raises(DataError) as e:
        Dataset.from_hdf5(path)
    _assert_one_line(e, str(path), "time", "not uniform", "Ts = 5")


def test_kelvin_values_labelled_degC_are_refused(tmp_path):
    ds = _small()
    path = tmp_path / "d.h5"
    _write_raw(path, ds, channels={"T_cab": ds["T_cab"] + 273.15})
    with pytest.raises(DataError) as e:
        Dataset.from_hdf5(path)
    _assert_one_line(e, str(path), "'T_cab'", "degC", "look like K")


def test_degC_values_labelled_kelvin_are_refused(tmp_path):
    ds = _small()
    path = tmp_path / "d.h5"
    _write_raw(path, ds, units={"T_evap": "K"})
    with pytest.raises(DataError) as e:
        Dataset.from_hdf5(path)
    _assert_one_line(e, str(path), "'T_evap'", "look like degC")


def test_unknown_unit_is_refused(tmp_path):
    path = tmp_path / "d.h5"
    _write_raw(path, _small(), units={"W_bl": "lb/min"})
    with pytest.raises(DataError) as e:
        Dataset.from_hdf5(path)
    _assert_one_line(e, str(path), "'W_bl'", "lb/min")


def test_too_short_record_is_refused(tmp_path):
    path = _small(n=50).to_hdf5(tmp_path / "d.h5")
    with pytest.raises(DataError) as e:
        Dataset.from_hdf5(path, min_samples=300)
    _assert_one_line(e, str(path), "too short", "50 samples", "300")


def test_not_an_acid_file_and_missing_file(tmp_path):
    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f["x"] = np.arange(3)
    with pytest.raises(DataError) as e:
        Dataset.from_hdf5(path)
    _assert_one_line(e, str(path), "not an acid dataset")
    with pytest.raises(DataError, match="not found"):
        Dataset.from_hdf5(tmp_path / "nope.h5")
    garbage = tmp_path / "garbage.h5"
    garbage.write_text("not hdf5")
    with pytest.raises(DataError) as e:
        Dataset.from_hdf5(garbage)
    _assert_one_line(e, str(garbage), "cannot read as HDF5")


# ----------------------------------------------------------------- atomic writes
def _interrupt_after(monkeypatch, n_ok: int) -> None:
    """Make h5py's create_dataset raise on its (n_ok + 1)-th call (a write cut midway)."""
    original = h5py.Group.create_dataset
    calls = {"n": 0}

    def flaky(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] > n_ok:
            raise KeyboardInterrupt("simulated interruption")
        return original(self, *args, **kwargs)

    monkeypatch.setattr(h5py.Group, "create_dataset", flaky)


def test_interrupted_write_leaves_no_file(tmp_path, monkeypatch):
    target = tmp_path / "d.h5"
    _interrupt_after(monkeypatch, 3)
    with pytest.raises(KeyboardInterrupt):
        _small().to_hdf5(target)
    assert list(tmp_path.iterdir()) == []


def test_interrupted_write_keeps_existing_file(tmp_path, monkeypatch):
    target = tmp_path / "d.h5"
    old = _small(n=20)
    old.to_hdf5(target)
    before = target.read_bytes()
    _interrupt_after(monkeypatch, 2)
    with pytest.raises(KeyboardInterrupt):
        _small(n=60).to_hdf5(target)
    assert target.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["d.h5"]
    monkeypatch.undo()
    assert len(Dataset.from_hdf5(target)) == 20


def test_written_file_has_the_usual_permissions(tmp_path):
    import os

    mask = os.umask(0o022)
    try:
        path = _small().to_hdf5(tmp_path / "d.h5")
        assert path.stat().st_mode & 0o777 == 0o644  # not mkstemp's 0600
        path.chmod(0o640)
        _small().to_hdf5(path)  # replacing keeps the existing file's mode
        assert path.stat().st_mode & 0o777 == 0o640
    finally:
        os.umask(mask)


# ---------------------------------------------------------------------- import
def _cmap(**extra) -> ChannelMap:
    d = {"time": "t", "channels": {"T_cab": {"column": "Tcabin", "unit": "K"},
                                   "W_bl": {"column": "blower", "unit": "kg/s"},
                                   "T_evap": "Tevap"}}
    d.update(extra)
    return ChannelMap.from_dict(d)


def _write_csv(path, t, **cols) -> None:
    import pandas as pd

    pd.DataFrame({"t": t, **cols}).to_csv(path, index=False)


def test_csv_import_resamples_and_converts_kelvin(tmp_path):
    t = np.arange(0, 100.5, 0.5)  # 2 Hz
    src = tmp_path / "run.csv"
    _write_csv(src, t, Tcabin=300 + 0.01 * t, blower=0.1 + 0 * t, Tevap=5 + 0 * t,
               comment=["x"] * t.size)
    ds = from_csv(src, _cmap(Ts=5.0))
    assert ds.Ts == 5.0 and len(ds) == 20  # 100 s hold 20 whole sample periods
    np.testing.assert_allclose(ds.time, np.arange(20) * 5.0)
    assert ds.units["T_cab"] == "degC"
    np.testing.assert_allclose(ds["T_cab"], 300 + 0.01 * ds.time - 273.15)
    assert ds.units["T_evap"] == "degC"  # short form takes the standard unit
    assert ds.metadata["imported_from"] == "csv"


def test_csv_import_without_resampling_needs_uniform_time(tmp_path):
    t = np.array([0.0, 5.0, 10.0, 16.0, 20.0])
    src = tmp_path / "run.csv"
    _write_csv(src, t, Tcabin=300 + 0 * t, blower=0.1 + 0 * t, Tevap=5 + 0 * t)
    with pytest.raises(DataError) as e:
        from_csv(src, _cmap())
    _assert_one_line(e, str(src), "not uniform")


def test_csv_import_missing_column_names_column_and_channel(tmp_path):
    t = np.arange(10) * 5.0
    src = tmp_path / "run.csv"
    _write_csv(src, t, Tcabin=300 + 0 * t, blower=0.1 + 0 * t)
    with pytest.raises(DataError) as e:
        from_csv(src, _cmap())
    _assert_one_line(e, str(src), "'Tevap'", "'T_evap'")


def test_csv_import_kelvin_labelled_degC_is_refused(tmp_path):
    t = np.arange(10) * 5.0
    src = tmp_path / "run.csv"
    _write_csv(src, t, Tcabin=300 + 0 * t, blower=0.1 + 0 * t, Tevap=278 + 0 * t)
    with pytest.raises(DataError) as e:
        from_csv(src, _cmap())
    _assert_one_line(e, str(src), "'T_evap'", "look like K")


def test_mat_import_with_struct_fields(tmp_path):
    import scipy.io

    t = np.arange(0, 60.01, 0.01)
    sim = {"time": t, "T_cabin_air": 303.15 - 0.05 * t, "m_dot_blower": 0.05 + 0.001 * t,
           "T_evap_wall": 280.0 + 0 * t}
    src = tmp_path / "run.mat"
    scipy.io.savemat(src, {"sim": sim})
    cmap = ChannelMap.from_dict({"time": "sim.time", "Ts": 5.0, "channels": {
        "T_cab": {"column": "sim.T_cabin_air", "unit": "K"},
        "W_bl": {"column": "sim.m_dot_blower", "unit": "kg/s"},
        "T_evap": {"column": "sim.T_evap_wall", "unit": "K"}}})
    ds = from_mat(src, cmap)
    assert len(ds) == 12 and ds.Ts == 5.0
    np.testing.assert_allclose(ds["T_cab"], 30.0 - 0.05 * ds.time, atol=1e-9)
    np.testing.assert_allclose(ds["W_bl"], 0.05 + 0.001 * ds.time)
    assert ds.metadata["imported_from"] == "mat"
    bad = ChannelMap.from_dict({"time": "sim.time", "channels": {
        "T_cab": {"column": "sim.T_missing", "unit": "K"}}})
    with pytest.raises(DataError) as e:
        from_mat(src, bad)
    _assert_one_line(e, str(src), "'sim.T_missing'", "'T_cab'")


def test_channel_map_from_toml_and_errors(tmp_path):
    from acid.signals import datasets_dir

    cmap = ChannelMap.from_file(datasets_dir() / "examples" / "coolsim_map.toml")
    assert cmap.time == "sim.time" and cmap.Ts == 5.0
    assert (cmap.channels["T_cab"].column, cmap.channels["T_cab"].unit) == ("sim.T_cabin_air",
                                                                            "K")
    bad = tmp_path / "bad.toml"
    bad.write_text('time = "t"\n[channels]\nT_cab = { column = "x", unit = "furlong" }\n')
    with pytest.raises(DataError) as e:
        ChannelMap.from_file(bad)
    _assert_one_line(e, "'T_cab'", "furlong")
    with pytest.raises(DataError, match="not found"):
        ChannelMap.from_file(tmp_path / "none.toml")
    broken = tmp_path / "broken.toml"
    broken.write_text("time = \n")
    with pytest.raises(DataError, match="cannot parse"):
        ChannelMap.from_file(broken)


# ------------------------------------------------------------------- structure
def test_window_split_concatenate(model_dataset):
    est, val = model_dataset.split(0.5)
    assert len(est) == len(val) == 720
    joined = Dataset.concatenate([est, val])
    assert joined.segments() == [(0, 720), (720, 1440)]
    assert not joined.transition_mask()[719]
    joined.validate()


def test_channel_map_malformed_entries():
    with pytest.raises(DataError, match="needs 'time'"):
        ChannelMap.from_dict({"channels": {}})
    with pytest.raises(DataError, match="must be a table"):
        ChannelMap.from_dict({"time": "t", "channels": "T_cab"})
    with pytest.raises(DataError, match="'T_cab' must be a column name"):
        ChannelMap.from_dict({"time": "t", "channels": {"T_cab": 3}})
    with pytest.raises(DataError, match="'extra' needs 'column' and 'unit'"):
        ChannelMap.from_dict({"time": "t", "channels": {"extra": "col"}})


def test_resampling_averages_outputs_and_powers_over_each_period(tmp_path):
    """Outputs and powers become interval means (energy kept), states are point samples."""
    t = np.arange(0, 100.01, 0.01)
    power = 1000.0 + 500.0 * np.sin(2 * np.pi * t / 7.0)
    src = tmp_path / "run.csv"
    _write_csv(src, t, Tcabin=300 + 0.01 * t, blower=0.1 + 0 * t, Tevap=5 + 0 * t, Pc=power)
    cmap = ChannelMap.from_dict({"time": "t", "Ts": 5.0, "channels": {
        "T_cab": {"column": "Tcabin", "unit": "K"}, "W_bl": "blower", "T_evap": "Tevap",
        "P_comp": {"column": "Pc", "unit": "W"}}})
    ds = from_csv(src, cmap)
    energy_fine = np.trapezoid(power, t)
    assert abs(ds["P_comp"].sum() * ds.Ts - energy_fine) < 1e-6 * energy_fine
    np.testing.assert_allclose(ds["T_cab"], 300 + 0.01 * ds.time - 273.15)


def test_mat_v73_import_reads_hdf5_inside(tmp_path):
    """MATLAB v7.3 files are HDF5 with a 512-byte MAT header; structs are groups."""
    import h5py

    src = tmp_path / "run73.mat"
    t = np.arange(0, 60.01, 0.5)
    with h5py.File(src, "w", userblock_size=512) as f:
        g = f.create_group("sim")
        g["time"] = t
        g["T_cabin_air"] = 303.15 - 0.05 * t
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: test HDF5 schema 1.00 ."
    with open(src, "r+b") as fh:
        fh.write(header.ljust(116, b" ") + b"\0" * 8 + b"\x00\x02" + b"IM")
    cmap = ChannelMap.from_dict({"time": "sim.time", "Ts": 5.0, "channels": {
        "T_cab": {"column": "sim.T_cabin_air", "unit": "K"}}})
    ds = from_mat(src, cmap)
    assert len(ds) == 12 and ds.metadata["imported_from"] == "mat"
    np.testing.assert_allclose(ds["T_cab"], 30.0 - 0.05 * ds.time, atol=1e-9)


# ------------------------------------------------------------- resampling, ranges
def _at_5s(tmp_path, n: int = 40):
    t = np.arange(n) * 5.0
    src = tmp_path / "run.csv"
    _write_csv(src, t, Tcabin=300 + 0.01 * t, blower=0.1 + 0 * t, Tevap=5 + 0 * t,
               Pc=1000 + 100 * np.sin(t / 20))
    return src, t


def _pmap(**extra):
    return ChannelMap.from_dict({"time": "t", **extra, "channels": {
        "T_cab": {"column": "Tcabin", "unit": "K"}, "W_bl": "blower", "T_evap": "Tevap",
        "P_comp": {"column": "Pc", "unit": "W"}}})


def test_data_already_at_Ts_are_not_averaged_again(tmp_path):
    src, t = _at_5s(tmp_path)
    ds = from_csv(src, _pmap(Ts=5.0))
    np.testing.assert_array_equal(ds["P_comp"], 1000 + 100 * np.sin(t / 20))
    assert ds.metadata["resample"]["mode"] == "none"
    assert "already sampled every Ts = 5 s" in ds.metadata["resample"]["note"]
    with pytest.raises(DataError) as e:
        from_csv(src, _pmap(Ts=5.0, resample="mean"))
    _assert_one_line(e, "resample = 'mean'", "second time")


def test_resample_sample_interpolates_outputs_too(tmp_path):
    t = np.arange(0, 100.01, 0.5)
    src = tmp_path / "run.csv"
    _write_csv(src, t, Tcabin=300 + 0 * t, blower=0.1 + 0 * t, Tevap=5 + 0 * t, Pc=10 * t)
    ds = from_csv(src, _pmap(Ts=5.0, resample="sample"))
    np.testing.assert_allclose(ds["P_comp"], 10 * ds.time)  # point samples, not means
    mean = from_csv(src, _pmap(Ts=5.0, resample="mean"))
    np.testing.assert_allclose(mean["P_comp"], 10 * (ds.time + 2.5))  # interval means


@pytest.mark.parametrize("Ts,fragment", [("5", "number"), (0, "positive"), (float("nan"),
                                         "positive"), ([5.0], "number"), (True, "number")])
def test_channel_map_Ts_must_be_a_positive_number(Ts, fragment):
    with pytest.raises(DataError, match=fragment):
        _pmap(Ts=Ts)


def test_channel_map_Ts_finer_than_the_data_is_refused(tmp_path):
    src, _ = _at_5s(tmp_path)
    with pytest.raises(DataError) as e:
        from_csv(src, _pmap(Ts=1e-9))
    _assert_one_line(e, "Ts = 1e-09 s", "finer than the data's own step (5 s)")


def test_negative_blower_flow_is_refused_with_the_channel_named(tmp_path):
    ds = _small()
    ds.channels["W_bl"] = -ds.channels["W_bl"]
    path = ds.to_hdf5(tmp_path / "d.h5")
    with pytest.raises(DataError) as e:
        Dataset.from_hdf5(path)
    _assert_one_line(e, "'W_bl'", "below its physical range [0, 1] kg/s")


@pytest.mark.parametrize("edit,fragment", [
    (lambda f: f.attrs.__setitem__("Ts", "5"), "Ts"),
    (lambda f: f.attrs.__setitem__("Ts", np.array([5.0, 5.0])), "Ts"),
    (lambda f: f["channels/T_cab"].attrs.__setitem__("unit", np.array([1, 2])), "'T_cab'"),
    (lambda f: f.attrs.__setitem__("metadata", "[1]"), "metadata"),
])
def test_foreign_attribute_types_are_one_line_errors(tmp_path, edit, fragment):
    path = _small().to_hdf5(tmp_path / "d.h5")
    with h5py.File(path, "r+") as f:
        edit(f)
    with pytest.raises(DataError) as e:
        Dataset.from_hdf5(path)
    _assert_one_line(e, str(path), fragment)


def test_mat_struct_variable_names_its_fields(tmp_path):
    import scipy.io

    t = np.arange(0, 60.0, 1.0)
    src = tmp_path / "run.mat"
    scipy.io.savemat(src, {"sim": {"time": t, "T": 300 + 0 * t}})
    cmap = ChannelMap.from_dict({"time": "sim.time", "Ts": 5.0, "channels": {
        "T_cab": {"column": "sim", "unit": "K"}}})
    with pytest.raises(DataError) as e:
        from_mat(src, cmap)
    _assert_one_line(e, "'sim' is a struct", "'sim.")


def test_every_map_key_is_read_and_documented(tmp_path):
    from acid.data import CHANNEL_KEYS, MAP_KEYS, import_logs

    d = {"description": "my car", "time": {"column": "t_ms", "unit": "ms"}, "Ts": 1.0,
         "resample": "centered", "sep": ";", "encoding": "cp1252", "decimal": ",",
         "drop_incomplete_end": True,   # this log ends complete: nothing is dropped
         "max_gap_s": 5.0,              # nor empty: nothing is bridged
         "channels": {
             "T_cab": {"column": "Cabin °C", "unit": "degC", "censored_above": 39.0,
                       "censored_below": 10.0, "note": "roof sensor", "max_gap_s": 2.0},
             "W_bl": {"constant": 0.1, "unit": "kg/s"},
             "T_ain": {"expr": "T_cab - 10", "unit": "degC"}}}
    assert set(d) == set(MAP_KEYS)
    assert set(d["channels"]["T_cab"]) | {"constant", "expr"} == set(CHANNEL_KEYS)
    cmap = ChannelMap.from_dict(d)
    assert (cmap.time, cmap.time_unit, cmap.sep, cmap.encoding, cmap.decimal) == (
        "t_ms", "ms", ";", "cp1252", ",")
    src = tmp_path / "log.csv"
    rows = [f"{k * 100};{40 - k * 0.1:.2f}".replace(".", ",") for k in range(400)]
    src.write_bytes(("t_ms;Cabin °C\r\n" + "\r\n".join(rows) + "\r\n").encode("cp1252"))
    ds = import_logs([src], cmap)
    assert ds.metadata["description"] == "my car" and ds.Ts == 1.0 and len(ds) == 39
    assert ds.metadata["censored"]["T_cab"] == {"censored_above": 39.0,
                                                "censored_below": 10.0, "unit": "degC"}
    assert ds["T_cab_censored"][:3].tolist() == [1.0, 1.0, 0.0]   # 39.0 at t = 1.0 s
    assert set(ds.assumed) == {"W_bl", "T_ain"}
    doc = (Path(__file__).parents[1] / "datasets" / "FORMAT.md").read_text()
    section = doc[doc.index("## Importing your own data"):doc.index("## FMU maps")]
    for key in (*MAP_KEYS, *CHANNEL_KEYS):
        assert f"{key} =" in section or f"`{key}`" in section or f"[{key}]" in section, key
