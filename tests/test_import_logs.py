"""Import of real vehicle logs (issue 20): map keys (sep, encoding, decimal, time unit,
resampling), gzip, several files as experiments, plausibility of units, clipped and
quantised sensors, assumed channels, every missing channel in one error; and the BMW i3
trips in ../shared/real-data with the shipped map (skipped where that folder is absent)."""

from __future__ import annotations

import gzip
import warnings
from pathlib import Path

import numpy as np
import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.data import (
    ChannelMap,
    Dataset,
    PlausibilityWarning,
    from_csv,
    import_logs,
)
from acid.errors import DataError
from acid.examples import resolve
from acid.logcheck import censored_across, held_extremes, quantisation
from acid_cli.main import app

REAL = Path(__file__).resolve().parents[1].parent / "shared" / "real-data" / "bmw-i3"
runner = CliRunner()

HEADER = ["Time [s]", "Velocity [km/h]", "AirCon Power [kW]", "Cabin Temperature [°C]"]


def car_log(path: Path, n: int = 3000, dt: float = 0.1, seed: int = 0, clip: float = 39.84,
            cabin0: float = 45.0, decimal: str = ".", sep: str = ";") -> dict:
    """A 10 Hz car log in the BMW's form (``;``, Latin-1 degree sign, km/h, kW), gzip'd when
    the name ends in .gz; returns the true values (SI)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    v_kmh = np.clip(55 + 30 * np.sin(t / 60.0) + rng.normal(0, 1, n), 0, None)
    p_kw = 1.5 + 0.5 * np.sin(t / 20.0)
    cabin = np.minimum(cabin0 - t / 30.0, clip)
    rows = [sep.join(HEADER)]
    for i in range(n):
        cells = [f"{t[i]:.1f}", f"{v_kmh[i]:.2f}", f"{p_kw[i]:.3f}", f"{cabin[i]:.2f}"]
        rows.append(sep.join(c.replace(".", decimal) for c in cells))
    data = ("\r\n".join(rows) + "\r\n").encode("latin-1")
    path.write_bytes(gzip.compress(data, mtime=0) if path.name.endswith(".gz") else data)
    return {"t": t, "v": v_kmh / 3.6, "P": p_kw * 1e3, "T_cab": np.round(cabin, 2)}


def car_map(**extra) -> ChannelMap:
    d = {"time": "Time [s]", "sep": ";", "encoding": "latin-1", "channels": {
        "v_veh": {"column": "Velocity [km/h]", "unit": "km/h"},
        "P_comp": {"column": "AirCon Power [kW]", "unit": "kW"},
        "T_cab": {"column": "Cabin Temperature [°C]", "unit": "degC"}}}
    chans = extra.pop("channels", {})
    d["channels"].update(chans)
    d.update(extra)
    return ChannelMap.from_dict(d)


# ----------------------------------------------------------------------- map keys
def test_sep_encoding_units_and_gzip_read_without_conversion_by_hand(tmp_path):
    truth = car_log(tmp_path / "trip.csv.gz")
    ds = from_csv(tmp_path / "trip.csv.gz", car_map())
    assert ds.units == {"v_veh": "m/s", "P_comp": "W", "T_cab": "degC"}
    assert np.allclose(ds["v_veh"], truth["v"], atol=0.01 / 3.6)
    assert np.allclose(ds["P_comp"], truth["P"], atol=0.5)
    assert ds.Ts == pytest.approx(0.1)
    car_log(tmp_path / "trip.csv")
    plain = from_csv(tmp_path / "trip.csv", car_map())
    assert np.array_equal(plain["v_veh"], ds["v_veh"])


def test_decimal_comma(tmp_path):
    truth = car_log(tmp_path / "comma.csv", decimal=",")
    ds = from_csv(tmp_path / "comma.csv", car_map(decimal=","))
    assert np.allclose(ds["P_comp"], truth["P"], atol=0.5)


def test_empty_rows_at_the_end_are_dropped_only_when_the_map_says_so(tmp_path):
    # a logger that stopped mid-row (the BMW i3 winter trips): empty cells in the last rows
    (tmp_path / "end.csv").write_text("t,T,P\n0,20,900\n1,21,900\n2,22,900\n3,23,\n4,,\n")
    d = {"time": "t", "channels": {"T_cab": {"column": "T", "unit": "degC"},
                                   "P_comp": {"column": "P", "unit": "W"}}}
    with pytest.raises(DataError, match="NaN"):
        from_csv(tmp_path / "end.csv", ChannelMap.from_dict(d))
    ds = from_csv(tmp_path / "end.csv", ChannelMap.from_dict({**d, "drop_incomplete_end": True}))
    assert ds.time.tolist() == [0.0, 1.0, 2.0] and ds["T_cab"].tolist() == [20.0, 21.0, 22.0]
    assert ds.metadata["dropped_incomplete_end"] == 2
    # an empty cell before the end is still refused
    (tmp_path / "mid.csv").write_text("t,T,P\n0,20,900\n1,,900\n2,22,900\n")
    with pytest.raises(DataError, match="NaN"):
        from_csv(tmp_path / "mid.csv", ChannelMap.from_dict({**d, "drop_incomplete_end": True}))
    with pytest.raises(DataError, match="drop_incomplete_end"):
        ChannelMap.from_dict({**d, "drop_incomplete_end": "yes"})


def test_time_column_in_a_stated_unit(tmp_path):
    (tmp_path / "ms.csv").write_text("t_ms,T\n0,20\n500,21\n1000,22\n1500,23\n")
    cmap = ChannelMap.from_dict({"time": {"column": "t_ms", "unit": "ms"},
                                 "channels": {"T_cab": {"column": "T", "unit": "degC"}}})
    ds = from_csv(tmp_path / "ms.csv", cmap)
    assert ds.Ts == 0.5 and ds.time[-1] == 1.5


def test_resampling_10_Hz_to_5_s_averages_power_and_samples_states(tmp_path):
    truth = car_log(tmp_path / "trip.csv.gz", n=3001)
    ds = from_csv(tmp_path / "trip.csv.gz", car_map(Ts=5.0))
    assert ds.Ts == 5.0 and len(ds) == 60
    k = 7
    window = (truth["t"] >= 5 * k) & (truth["t"] <= 5 * (k + 1))
    # power: the mean over [t_k, t_k + Ts) (trapezoid of the 10 Hz points: energy kept)
    assert ds["P_comp"][k] == pytest.approx(np.trapezoid(truth["P"][window],
                                                         truth["t"][window]) / 5.0, rel=1e-3)
    # a state: sampled at t_k
    assert ds["T_cab"][k] == pytest.approx(truth["T_cab"][50 * k], abs=1e-9)
    assert ds.metadata["resample"]["mode"] == "mean"


def test_centered_resampling_averages_states_around_t_k(tmp_path):
    t = np.arange(0, 600, 0.1)
    noise = np.random.default_rng(1).normal(0, 0.1, t.size)
    cabin = 20 + t / 100
    (tmp_path / "n.csv").write_text("t,T,P\n" + "\n".join(
        f"{a:.1f},{b:.6f},{c:.3f}" for a, b, c in zip(t, cabin + noise, 1000 + 0 * t,
                                                      strict=True)))
    d = {"time": "t", "Ts": 5.0, "channels": {"T_cab": "T",
                                               "P_comp": {"column": "P", "unit": "W"}}}
    sampled = from_csv(tmp_path / "n.csv", ChannelMap.from_dict(d))
    centered = from_csv(tmp_path / "n.csv", ChannelMap.from_dict({**d,
                                                                  "resample": "centered"}))
    truth = 20 + centered.time / 100
    err_s, err_c = sampled["T_cab"] - truth, centered["T_cab"] - truth
    assert np.std(err_c) < 0.3 * np.std(err_s)      # 50 samples averaged: ~0.14 of it
    assert abs(np.mean(err_c[1:-1])) < 0.01          # aligned with t_k: no lag
    assert np.allclose(centered["P_comp"], 1000.0)   # powers: means over [t_k, t_k + Ts)
    assert centered.metadata["resample"]["mode"] == "centered"


@pytest.mark.parametrize(("key", "value", "fragment"), [
    ("sep", ";;", "sep"), ("sep", ".", "sep"), ("decimal", ";", "decimal"),
    ("encoding", "klingon-8", "encoding"), ("encoding", 5, "encoding"),
    ("time", {"column": "t", "unit": "km"}, "time unit"),
    ("time", {"column": "t", "zone": "UTC"}, "zone"),
])
def test_bad_format_keys_are_one_line_errors(key, value, fragment):
    d = {"time": "t", "channels": {"T_cab": "T"}, key: value}
    with pytest.raises(DataError, match=fragment):
        ChannelMap.from_dict(d)


def test_wrong_encoding_and_separator_get_a_hint(tmp_path):
    car_log(tmp_path / "trip.csv")
    utf8 = ChannelMap.from_dict({"time": "Time [s]", "sep": ";", "channels": {
        "T_cab": {"column": "Cabin Temperature [°C]", "unit": "degC"}}})
    with pytest.raises(DataError, match="encoding") as e:
        from_csv(tmp_path / "trip.csv", utf8)
    assert "latin-1" in str(e.value)
    comma = ChannelMap.from_dict({"time": "Time [s]", "encoding": "latin-1", "channels": {
        "T_cab": {"column": "Cabin Temperature [°C]", "unit": "degC"}}})
    with pytest.raises(DataError, match="sep = ';'"):
        from_csv(tmp_path / "trip.csv", comma)


# -------------------------------------------------------------- several files
def test_several_files_are_experiments_with_names_and_sources(tmp_path):
    for i in range(3):
        car_log(tmp_path / f"Trip{i}.csv.gz", n=600 + 100 * i, seed=i)
    paths = [tmp_path / f"Trip{i}.csv.gz" for i in range(3)]
    ds = import_logs(paths, car_map(Ts=1.0))
    assert ds.experiment_names() == ["Trip0", "Trip1", "Trip2"]
    assert [len(range(*s)) for s in ds.segments()] == [59, 69, 79]
    assert int((~ds.transition_mask()).sum()) == 2          # no regressor crosses a file
    assert [r["source"] for r in ds.metadata["experiments"]] == [str(p) for p in paths]
    back = Dataset.from_hdf5(ds.to_hdf5(tmp_path / "trips.h5"))
    assert back.experiment_names() == ["Trip0", "Trip1", "Trip2"]
    assert back.window(60, 200).experiment_names() == ["Trip1", "Trip2"]


def test_cli_imports_several_files_in_one_call(tmp_path):
    for i in range(2):
        car_log(tmp_path / f"T{i}.csv.gz", n=700, seed=i)
    (tmp_path / "m.toml").write_text(
        'time = "Time [s]"\nTs = 1.0\nsep = ";"\nencoding = "latin-1"\n[channels]\n'
        'v_veh = { column = "Velocity [km/h]", unit = "km/h" }\n'
        'P_comp = { column = "AirCon Power [kW]", unit = "kW" }\n', encoding="utf-8")
    r = runner.invoke(app, ["import", str(tmp_path / "T0.csv.gz"), str(tmp_path / "T1.csv.gz"),
                            "--map", str(tmp_path / "m.toml"), "--out", str(tmp_path / "o.h5")])
    assert r.exit_code == 0, r.output
    assert "2 experiments" in " ".join(r.output.split())  # a long temporary path may wrap
    assert Dataset.from_hdf5(tmp_path / "o.h5").experiment_names() == ["T0", "T1"]
    r = runner.invoke(app, ["import", str(tmp_path / "T0.csv.gz"), str(tmp_path / "T0.csv.gz"),
                            "--map", str(tmp_path / "m.toml"), "--out", str(tmp_path / "p.h5")])
    assert_one_line_error(r, "T0.csv.gz", "twice")


# -------------------------------------------------------------- plausibility
def test_kmh_declared_as_ms_gets_a_warning_naming_channel_and_unit(tmp_path):
    car_log(tmp_path / "trip.csv.gz")
    bad = car_map(channels={"v_veh": {"column": "Velocity [km/h]", "unit": "m/s"}})
    with pytest.warns(PlausibilityWarning, match=r"'v_veh'.*'km/h'"):
        from_csv(tmp_path / "trip.csv.gz", bad)


def test_a_slow_kmh_trip_declared_as_ms_is_caught_by_its_accelerations(tmp_path):
    # a city trip below 70 km/h: its maximum fits m/s, its accelerations do not
    t = np.arange(0, 300, 0.1)
    v = np.clip(25 + 25 * np.sin(t / 3.0), 0, None)   # km/h, max 50, up to 2.3 m/s^2
    (tmp_path / "city.csv").write_text("t,v\n" + "\n".join(f"{a:.1f},{b:.2f}"
                                                           for a, b in zip(t, v, strict=True)))
    cmap = ChannelMap.from_dict({"time": "t", "channels": {"v_veh": {"column": "v",
                                                                      "unit": "m/s"}}})
    with pytest.warns(PlausibilityWarning, match=r"'v_veh'.*accelerations.*'km/h'"):
        from_csv(tmp_path / "city.csv", cmap)
    right = ChannelMap.from_dict({"time": "t", "channels": {"v_veh": {"column": "v",
                                                                       "unit": "km/h"}}})
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        from_csv(tmp_path / "city.csv", right)


def test_kw_declared_as_w_gets_a_warning(tmp_path):
    car_log(tmp_path / "trip.csv.gz")
    bad = car_map(channels={"P_comp": {"column": "AirCon Power [kW]", "unit": "W"}})
    with pytest.warns(PlausibilityWarning, match=r"'P_comp'.*'kW'"):
        ds = from_csv(tmp_path / "trip.csv.gz", bad)
    assert any(f["kind"] == "unit" and f["channel"] == "P_comp"
               for f in ds.metadata["checks"])


def test_right_units_give_no_plausibility_warning(tmp_path):
    car_log(tmp_path / "trip.csv.gz")
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        from_csv(tmp_path / "trip.csv.gz", car_map())


def test_cli_prints_the_plausibility_warning(tmp_path):
    car_log(tmp_path / "trip.csv.gz")
    (tmp_path / "m.toml").write_text(
        'time = "Time [s]"\nsep = ";"\nencoding = "latin-1"\n[channels]\n'
        'v_veh = { column = "Velocity [km/h]", unit = "m/s" }\n', encoding="utf-8")
    r = runner.invoke(app, ["import", str(tmp_path / "trip.csv.gz"), "--map",
                            str(tmp_path / "m.toml"), "--out", str(tmp_path / "o.h5")])
    assert r.exit_code == 0, r.output
    assert "warning:" in r.output and "'v_veh'" in r.output and "km/h" in r.output


# ------------------------------------------------------ clipped, quantised sensors
def test_declared_clipping_level_masks_censored_samples(tmp_path):
    truth = car_log(tmp_path / "trip.csv.gz", n=3001)
    cmap = car_map(Ts=1.0, channels={"T_cab": {"column": "Cabin Temperature [°C]",
                                               "unit": "degC", "censored_above": 39.84}})
    ds = from_csv(tmp_path / "trip.csv.gz", cmap)
    raw_censored = int((truth["T_cab"] >= 39.84).sum())
    assert ds.metadata["censored"]["T_cab"]["samples"] == raw_censored > 0
    mask = ds["T_cab_censored"]
    assert ds.units["T_cab_censored"] == "1" and set(np.unique(mask)) == {0.0, 1.0}
    # a 1 s sample is censored when any of its 10 Hz samples is
    first_free = int(np.argmax(truth["T_cab"] < 39.84))
    assert mask.sum() == np.ceil(first_free / 10)
    assert np.all(ds["T_cab"][mask == 1] >= 39.84 - 0.1)


def test_held_extremes_and_censoring_across_files():
    t = np.arange(0, 600, 0.1)
    clipped = np.minimum(45 - t / 20, 39.84)                   # at its max for 103 s
    held = held_extremes("T_cab", clipped, "degC", t)
    assert [(f["side"], f["level"]) for f in held] == [("max", 39.84)]
    assert held[0]["longest_s"] == pytest.approx(103.3, abs=0.2)
    assert held_extremes("T_cab", 30 - t / 100, "degC", t) == []      # never held
    assert held_extremes("v_veh", np.maximum(t - 300, 0), "m/s", t) == []   # standing car
    other = np.minimum(44 - t / 20, 39.84)                     # 83 s at the clip
    exps = [{"name": n, "extremes": {"T_cab": (float(v.min()), float(v.max()))},
             "checks": held_extremes("T_cab", v, "degC", t)}
            for n, v in (("A", clipped), ("B", other), ("C", 30 - t / 100))]
    found = censored_across(exps)
    assert [(f["channel"], f["level"], f["files"]) for f in found] == [
        ("T_cab", 39.84, ["A", "B"])]
    assert "censored_above = 39.84" in found[0]["message"]
    assert censored_across(exps[:1]) == []


def test_quantised_sensor_is_detected_with_its_step():
    t = np.arange(0, 600, 0.1)
    true = 20 + 3 * np.sin(t / 100)
    q = quantisation("T_amb", np.round(true * 2) / 2, "degC", t)
    assert q is not None and q["step"] == pytest.approx(0.5) and q["levels"] >= 10
    assert quantisation("T_amb", true, "degC", t) is None
    assert quantisation("T_amb", np.full_like(t, 20.0), "degC", t) is None
    toggling = np.tile([0.0, 0.5, 1.0, 0.5], t.size // 4)     # changes every sample
    few = quantisation("fan_speed", toggling, "1", t)
    assert few is not None and few["levels"] == 3 and few["step"] == pytest.approx(0.5)


def test_a_paused_logger_is_reported(tmp_path):
    t = np.concatenate((np.arange(0, 100, 0.1), np.arange(160, 260, 0.1)))
    (tmp_path / "gap.csv").write_text("t,T\n" + "\n".join(f"{a:.1f},20" for a in t))
    ds = from_csv(tmp_path / "gap.csv", ChannelMap.from_dict(
        {"time": "t", "Ts": 1.0, "channels": {"T_cab": "T"}}))
    found = [f for f in ds.metadata["checks"] if f["kind"] == "gap"]
    assert len(found) == 1 and found[0]["count"] == 1
    assert found[0]["longest_s"] == pytest.approx(60.1) and found[0]["first_at_s"] == 99.9


def test_same_file_name_in_two_folders_gives_two_experiment_names(tmp_path):
    for d in ("a", "b"):
        (tmp_path / d).mkdir()
        car_log(tmp_path / d / "Trip.csv.gz", n=400)
    ds = import_logs([tmp_path / "a" / "Trip.csv.gz", tmp_path / "b" / "Trip.csv.gz"],
                     car_map())
    assert ds.experiment_names() == ["Trip", "Trip-2"]


# ------------------------------------------------------------ assumed channels
def test_constant_and_derived_channels_are_recorded_as_assumed(tmp_path):
    truth = car_log(tmp_path / "trip.csv.gz")
    cmap = car_map(channels={
        "W_bl": {"constant": 360.0, "unit": "kg/h", "note": "blower level 1"},
        "T_ain": {"expr": "min(T_cab, 30) - 2 * (P_comp > 1500)", "unit": "degC"},
        "T_evap": {"expr": "T_ain - 1", "unit": "degC"}})
    ds = from_csv(tmp_path / "trip.csv.gz", cmap)
    assert np.all(ds["W_bl"] == 0.1) and ds.units["W_bl"] == "kg/s"
    expected = np.minimum(truth["T_cab"], 30) - 2 * (truth["P"] > 1500)
    assert np.allclose(ds["T_ain"], expected, atol=1e-9)
    assert np.allclose(ds["T_evap"], expected - 1, atol=1e-9)
    assert set(ds.assumed) == {"W_bl", "T_ain", "T_evap"}
    assert ds.assumed["W_bl"] == "constant 360 kg/h"
    back = Dataset.from_hdf5(ds.to_hdf5(tmp_path / "a.h5"))
    assert set(back.assumed) == {"W_bl", "T_ain", "T_evap"}
    assert back.metadata["assumed"]["W_bl"]["note"] == "blower level 1"
    assert "T_cab" not in back.assumed


@pytest.mark.parametrize(("expr", "fragment"), [
    ("__import__('os').system('true')", "call"), ("T_cab.real", "Attribute"),
    ("T_cab[0]", "Subscript"), ("lambda: 1", "Lambda"), ("'a'", "constant"),
    ("1 < T_cab < 2", "comparison"), ("min(T_cab)", "argument"), ("T_cab +", "parse"),
    ("T_nope + 1", "T_nope"), ("x" * 600, "longer"), ("True + 1", "constant"),
])
def test_expressions_are_not_python_eval(expr, fragment):
    with pytest.raises(DataError, match=fragment):
        ChannelMap.from_dict({"time": "t", "channels": {
            "T_cab": "c", "T_ain": {"expr": expr, "unit": "degC"}}})


def test_expression_cycles_and_conflicting_sources_are_refused():
    with pytest.raises(DataError, match="cycle"):
        ChannelMap.from_dict({"time": "t", "channels": {
            "T_ain": {"expr": "T_evap + 1", "unit": "degC"},
            "T_evap": {"expr": "T_ain - 1", "unit": "degC"}}})
    with pytest.raises(DataError, match="exactly one"):
        ChannelMap.from_dict({"time": "t", "channels": {
            "W_bl": {"column": "w", "constant": 0.1, "unit": "kg/s"}}})
    with pytest.raises(DataError, match="measured columns"):
        ChannelMap.from_dict({"time": "t", "channels": {
            "W_bl": {"constant": 0.1, "unit": "kg/s", "censored_above": 1.0}}})


# ---------------------------------------------------- missing channels: one error
def test_every_missing_column_in_one_error(tmp_path):
    car_log(tmp_path / "trip.csv")
    cmap = car_map(channels={"T_amb": {"column": "Ambient [°C]", "unit": "degC"},
                             "T_evap": {"column": "Evap [°C]", "unit": "degC"}})
    with pytest.raises(DataError) as e:
        from_csv(tmp_path / "trip.csv", cmap)
    msg = str(e.value)
    assert "\n" not in msg and "2 columns" in msg
    assert "'Ambient [°C]' (for 'T_amb')" in msg and "'Evap [°C]' (for 'T_evap')" in msg


def test_every_missing_channel_in_one_error_from_dataset_and_fit(tmp_path):
    car_log(tmp_path / "trip.csv.gz")
    ds = from_csv(tmp_path / "trip.csv.gz", car_map(Ts=5.0))
    with pytest.raises(DataError) as e:
        ds.validate(require=("T_cab", "T_evap", "T_ain", "W_bl"))
    assert "3 channels 'T_evap', 'T_ain', 'W_bl'" in str(e.value)
    ds.to_hdf5(tmp_path / "d.h5")
    r = runner.invoke(app, ["fit", str(tmp_path / "d.h5"), "--out", str(tmp_path / "p.json")])
    assert_one_line_error(r, "d.h5", "'T_evap'", "'T_ain'", "'W_bl'", "'T_evap_set'",
                          "'T_int'", "'T_shell'")


def test_import_require_names_every_channel_the_map_lacks_before_reading(tmp_path):
    car_log(tmp_path / "trip.csv.gz")
    (tmp_path / "m.toml").write_text(
        'time = "Time [s]"\nsep = ";"\nencoding = "latin-1"\n[channels]\n'
        'T_cab = { column = "Cabin Temperature [°C]", unit = "degC" }\n'
        'W_bl = { constant = 0.1, unit = "kg/s" }\n', encoding="utf-8")
    args = ["import", str(tmp_path / "trip.csv.gz"), "--map", str(tmp_path / "m.toml"),
            "--out", str(tmp_path / "o.h5")]
    r = runner.invoke(app, [*args, "--require", "model"])
    assert_one_line_error(r, "m.toml", "'T_evap'", "'T_ain'", "'T_evap_set'", "'T_int'",
                          "'T_shell'", "5 of the 7")
    assert not (tmp_path / "o.h5").exists()
    r = runner.invoke(app, [*args, "--require", "T_cab, W_bl"])
    assert r.exit_code == 0, r.output
    assert "W_bl is assumed" in r.output


# ------------------------------------------------------------- the sample log
def test_shipped_sample_log_imports_with_its_map(tmp_path):
    ds = from_csv(resolve("example:sample_log.csv.gz"),
                  ChannelMap.from_file(resolve("sample_log_map.toml")))
    assert len(ds) == 300 and ds.Ts == 5.0 and not ds.assumed
    assert ds.units["v_veh"] == "m/s" and 20 < ds["v_veh"].max() < 30     # UDDS: 91 km/h
    assert 200 < ds["P_comp"].max() < 6000 and ds["T_amb"][0] == 35.0
    ds.validate(require=("T_cab", "T_evap", "T_ain", "W_bl", "T_evap_set", "T_int",
                         "T_shell"))


def test_sample_log_writer_round_trips_a_dataset(model_dataset, tmp_path):
    from _sample_log import COLUMNS, car_log_bytes

    ds = model_dataset.window(0, 120)
    ds.channels["v_veh"] = np.linspace(0, 30, 120)
    ds.channels["P_comp"] = np.linspace(300, 2000, 120)
    ds.channels["P_bl"] = np.linspace(20, 250, 120)
    ds.channels["T_amb"] = np.full(120, 35.0)
    ds.units.update(v_veh="m/s", P_comp="W", P_bl="W", T_amb="degC")
    (tmp_path / "log.csv.gz").write_bytes(car_log_bytes(ds))
    back = from_csv(tmp_path / "log.csv.gz",
                    ChannelMap.from_file(resolve("example:sample_log_map.toml")))
    for name, (_, _, digits) in COLUMNS.items():
        tol = {"v_veh": 0.005 / 3.6, "W_bl": 0.05 / 3600, "P_comp": 0.5}.get(name,
                                                                          0.5 * 10 ** -digits)
        assert np.allclose(back[name], ds[name], atol=tol * 1.001), name


# --------------------------------------------------------- the BMW i3 trips
def _real_trips():
    if not REAL.is_dir():
        pytest.skip(f"real vehicle data not found at {REAL} (../shared/real-data beside the "
                    "repository; acid never ships it)")
    return sorted(REAL.glob("Trip*.csv.gz"))


def test_bmw_trips_import_with_the_shipped_map_and_no_conversion_by_hand(tmp_path):
    trips = _real_trips()
    picked = [p for p in trips if p.name in ("TripA01.csv.gz", "TripA11.csv.gz",
                                             "TripA26.csv.gz", "TripA32.csv.gz")]
    assert len(picked) == 4
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        ds = import_logs(picked, ChannelMap.from_file(resolve("example:bmw_i3_map.toml")))
    assert ds.experiment_names() == ["TripA01", "TripA11", "TripA26", "TripA32"]
    assert ds.Ts == 5.0
    # m/s, not km/h (A32 reaches 151.6 km/h = 42.1 m/s: the i3 tops out near 150 km/h)
    assert 0 <= ds["v_veh"].min() and ds["v_veh"].max() <= 45
    assert 10 < ds["v_veh"].max()
    assert 0 <= ds["P_comp"].min() and ds["P_comp"].max() <= 6000        # W, not kW
    assert 1000 < ds["P_comp"].max()
    assert 10 <= ds["T_cab"].min() and ds["T_cab"].max() <= 50
    # the cabin sensor clips at 39.84 degC: A11 and A26 start there, the mask says so
    mask = ds["T_cab_censored"]
    by_trip = {n: mask[a:b].sum() for n, (a, b) in zip(ds.experiment_names(),
                                                        ds.segments(), strict=True)}
    assert by_trip["TripA11"] > 10 and by_trip["TripA26"] > 10 and by_trip["TripA01"] == 0
    assert mask[ds.segments()[1][0]] == 1.0
    quantised = {f["channel"]: f["step"] for r in ds.metadata["experiments"]
                 for f in r["checks"] if f["kind"] == "quantised"}
    assert quantised["T_amb"] == pytest.approx(0.5) and quantised["T_evap"] == pytest.approx(0.5)
    assert quantised["T_cab"] == pytest.approx(1 / 6, abs=0.01)


def test_bmw_trip_declared_in_si_units_gets_warnings():
    trip = next(p for p in _real_trips() if p.name == "TripA01.csv.gz")
    cmap = ChannelMap.from_dict({"time": "Time [s]", "sep": ";", "encoding": "latin-1",
                                 "channels": {
                                     "v_veh": {"column": "Velocity [km/h]", "unit": "m/s"},
                                     "P_comp": {"column": "AirCon Power [kW]", "unit": "W"}}})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PlausibilityWarning)
        from_csv(trip, cmap)
    text = " ".join(str(w.message) for w in caught)
    assert "'v_veh'" in text and "'km/h'" in text and "'P_comp'" in text and "'kW'" in text
