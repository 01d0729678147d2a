"""acid.excite and the ``acid excite`` / ``acid import`` commands."""

from __future__ import annotations

import json
import sys

import h5py
import numpy as np
import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.data import Dataset
from acid.errors import ConfigError
from acid.excite import ExcitationSpec, excite, make_schedule
from acid.plant import make_plant
from acid.units import C2K
from acid_cli.main import app

runner = CliRunner()


# ------------------------------------------------------------------- schedules
def test_schedule_respects_table_ii_bounds_in_kelvin():
    s = make_schedule(ExcitationSpec())
    assert len(s) == 1440 and s.Ts == 5.0
    assert s.W_bl.min() >= 0.05 and s.W_bl.max() <= 0.15
    assert s.T_evap_set.min() >= C2K(3.0) - 1e-9 and s.T_evap_set.max() <= C2K(10.0) + 1e-9
    assert s.T_int.min() >= C2K(25.0) and s.T_shell.max() <= C2K(50.0)
    assert s.T_shell.mean() > s.T_int.mean() - 5.0
    np.testing.assert_array_equal(s.v_veh, 0.0)
    assert s.spec["seed"] == 0 and s.spec["generators"]["W_bl"]["type"] == "aprbs"


def test_each_signal_has_its_own_stream():
    a = make_schedule(ExcitationSpec(seed=4))
    b = make_schedule(ExcitationSpec(seed=4, signal_T_evap_set="prbs", vary_exogenous=False))
    np.testing.assert_array_equal(a.W_bl, b.W_bl)  # changing one signal leaves the others
    assert not np.array_equal(a.T_evap_set, b.T_evap_set)
    c = make_schedule(ExcitationSpec(seed=5))
    assert not np.array_equal(a.W_bl, c.W_bl)


@pytest.mark.parametrize("signal", ["prbs", "multisine"])
def test_other_signals_and_drive_cycle(signal):
    s = make_schedule(ExcitationSpec(signal=signal, duration=3600, cycle="udds"))
    assert len(s) == 720
    assert s.W_bl.min() >= 0.05 - 1e-12 and s.W_bl.max() <= 0.15 + 1e-12
    assert s.v_veh.max() > 20 and s.spec["generators"]["v_veh"]["name"] == "udds"


@pytest.mark.parametrize("kw", [{"signal": "chirp"}, {"duration": 0}, {"duration": 5},
                                {"noise": -1}, {"speed": -3}, {"min_dwell": 50,
                                                                "max_dwell": 10}])
def test_spec_rejects_bad_options(kw):
    with pytest.raises(ConfigError):
        ExcitationSpec(**kw)


def test_excite_model_plant_metadata(model_dataset, model_spec):
    ds = model_dataset
    assert len(ds) == model_spec.n_samples
    ds.validate(require=("T_cab", "T_evap", "T_ain", "W_bl", "T_evap_set", "T_int", "T_shell"))
    meta = ds.metadata
    assert meta["plant"] == "model" and meta["seed"] == 0
    assert meta["plant_config"]["params"]["name"] == "paper"
    assert meta["excitation"]["duration"] == 7200.0
    # T_int/T_shell come from the schedule, starting at its first values
    sched = make_schedule(model_spec)
    np.testing.assert_allclose(ds.get("T_int", "K"), sched.T_int)
    # paper preset in kelvin: inlet air between 5 and 20 degC (SPEC section 1)
    assert 5.0 < ds["T_ain"].min() and ds["T_ain"].max() < 20.0


def test_noise_changes_only_the_measured_temperatures(model_dataset, noisy_model_dataset):
    d = noisy_model_dataset["T_cab"] - model_dataset["T_cab"]
    assert 0.03 < d.std() < 0.07
    np.testing.assert_array_equal(noisy_model_dataset["W_bl"], model_dataset["W_bl"])


def _h5_contents(path) -> dict:
    """Every dataset and attribute of a file, except the creation time."""
    out = {}

    def visit(name, obj):
        for k, v in obj.attrs.items():
            if k == "created":
                continue
            if k == "metadata":
                v = json.loads(v)
                v.pop("created", None)
            out[f"{name}@{k}"] = v
        if isinstance(obj, h5py.Dataset):
            out[name] = obj[()]

    with h5py.File(path) as f:
        visit("/", f)
        f.visititems(visit)
    return out


def _assert_same_contents(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for k in a:
        if isinstance(a[k], np.ndarray):
            np.testing.assert_array_equal(a[k], b[k], err_msg=k)
        else:
            assert a[k] == b[k], k


def test_same_seed_gives_identical_hdf5(tmp_path):
    spec = ExcitationSpec(seed=11, duration=1800, noise=0.1, cycle="nycc")
    paths = []
    for i in range(2):
        plant = make_plant("model", meas_noise_std=spec.noise, rng=spec.rng("noise"))
        paths.append(excite(plant, spec).to_hdf5(tmp_path / f"run{i}.h5"))
    _assert_same_contents(_h5_contents(paths[0]), _h5_contents(paths[1]))
    other = make_plant("model", meas_noise_std=0.1, rng=spec.replace(seed=12).rng("noise"))
    ds = excite(other, spec.replace(seed=12))
    assert not np.array_equal(ds["W_bl"], Dataset.from_hdf5(paths[0])["W_bl"])


# ------------------------------------------------------------------------ CLI
def test_cli_help():
    for cmd in (["excite", "--help"], ["import", "--help"]):
        result = runner.invoke(app, cmd)
        assert result.exit_code == 0, result.output
        assert "--out" in result.output


def test_cli_excite_model_writes_valid_file(tmp_path):
    out, summary = tmp_path / "d.h5", tmp_path / "s.json"
    result = runner.invoke(app, ["excite", "--plant", "model", "--out", str(out),
                                 "--duration", "1200", "--seed", "3", "--cycle", "sc03",
                                 "--noise", "0.05", "--json", str(summary)])
    assert result.exit_code == 0, result.output
    ds = Dataset.from_hdf5(out, require=("T_cab", "T_int", "T_shell"), min_samples=240)
    assert len(ds) == 240 and ds.metadata["seed"] == 3 and ds.metadata["plant"] == "model"
    assert ds.metadata["excitation"]["cycle"] == "sc03"
    assert ds.metadata["plant_config"]["meas_noise_std_K"] == 0.05
    s = json.loads(summary.read_text())
    assert s["samples"] == 240 and s["ranges"]["W_bl"]["max"] <= 0.15
    assert "T_cab" in result.output


def test_cli_excite_same_seed_same_file(tmp_path):
    args = ["excite", "--plant", "model", "--duration", "600", "--signal", "prbs",
            "--noise", "0.1", "--seed", "9"]
    for name in ("a.h5", "b.h5"):
        assert runner.invoke(app, args + ["--out", str(tmp_path / name)]).exit_code == 0
    _assert_same_contents(_h5_contents(tmp_path / "a.h5"), _h5_contents(tmp_path / "b.h5"))


def test_cli_excite_params_file_and_no_exogenous(tmp_path):
    from acid.models.params import paper

    params = paper().replace(name="mine").to_json(tmp_path / "p.json")
    out = tmp_path / "d.h5"
    result = runner.invoke(app, ["excite", "--plant", "model", "--params", str(params),
                                 "--no-vary-exogenous", "--duration", "300", "--out",
                                 str(out)])
    assert result.exit_code == 0, result.output
    ds = Dataset.from_hdf5(out)
    assert ds.metadata["plant_config"]["params"]["name"] == "mine"
    assert np.ptp(ds["T_int"]) == 0.0


@pytest.mark.parametrize("args, words", [
    (["--signal", "chirp"], ["--signal", "chirp"]),
    (["--duration", "-5"], ["--duration"]),
    (["--cycle", "autobahn"], ["autobahn", "udds"]),
    (["--speed", "5", "--cycle", "udds"], ["--speed", "--cycle"]),
    (["--noise", "-0.1"], ["--noise"]),
    (["--plant", "lab"], ["--plant", "lab"]),
    (["--plant-config", "x.toml"], ["--plant-config"]),
    (["--params", "missing.json"], ["missing.json"]),
])
def test_cli_excite_bad_options_one_line(tmp_path, args, words):
    out = tmp_path / "d.h5"
    base = ["excite", "--out", str(out)]
    if "--plant" not in args:
        base += ["--plant", "model"]
    result = runner.invoke(app, base + args)
    assert_one_line_error(result, *words)
    assert not out.exists()


def test_cli_excite_hifi_unavailable_is_one_line(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "acid.plant.hifi", None)  # import raises ImportError
    result = runner.invoke(app, ["excite", "--plant", "hifi", "--out", str(tmp_path / "d.h5")])
    assert_one_line_error(result, "--plant hifi", "--plant model")


def test_cli_excite_default_plant_is_hifi():
    import inspect

    from acid_cli.excite import excite as command

    assert inspect.signature(command).parameters["plant"].default.default == "hifi"


def test_cli_excite_hifi_params_conflict(tmp_path):
    result = runner.invoke(app, ["excite", "--plant", "hifi", "--params", "p.json",
                                 "--out", str(tmp_path / "d.h5")])
    assert_one_line_error(result, "--params")


# ---------------------------------------------------------------------- import
def test_cli_import_csv_and_mat(tmp_path):
    import pandas as pd
    import scipy.io

    t = np.arange(0, 301.0, 1.0)
    cols = {"t": t, "Tc": 303.15 - 0.01 * t, "Wb": 0.1 + 0 * t}
    pd.DataFrame(cols).to_csv(tmp_path / "run.csv", index=False)
    scipy.io.savemat(tmp_path / "run.mat", {"sim": cols})
    (tmp_path / "map.toml").write_text(
        'time = "t"\nTs = 5.0\n[channels]\nT_cab = { column = "Tc", unit = "K" }\n'
        'W_bl = { column = "Wb", unit = "kg/s" }\n')
    (tmp_path / "mat.toml").write_text(
        'time = "sim.t"\nTs = 5.0\n[channels]\nT_cab = { column = "sim.Tc", unit = "K" }\n')
    for src, cmap in (("run.csv", "map.toml"), ("run.mat", "mat.toml")):
        out = tmp_path / f"{src}.h5"
        result = runner.invoke(app, ["import", str(tmp_path / src), "--map",
                                     str(tmp_path / cmap), "--out", str(out)])
        assert result.exit_code == 0, result.output
        ds = Dataset.from_hdf5(out)
        assert len(ds) == 60 and ds.units["T_cab"] == "degC"  # 300 s = 60 whole periods
        np.testing.assert_allclose(ds["T_cab"], 30.0 - 0.01 * ds.time, atol=1e-9)
        assert len(ds.metadata["source_sha256"]) == 64


def test_cli_import_errors_one_line(tmp_path):
    t = np.arange(10) * 5.0
    (tmp_path / "run.csv").write_text("t,Tc\n" + "\n".join(f"{x},{30 + 273.15}" for x in t))
    (tmp_path / "map.toml").write_text('time = "t"\n[channels]\nT_cab = "Tc"\n')
    (tmp_path / "miss.toml").write_text('time = "t"\n[channels]\nT_cab = "Tcab"\n')
    (tmp_path / "run.xlsx").write_text("x")
    out = tmp_path / "o.h5"
    cases = [
        (["run.csv", "map.toml"], ["'T_cab'", "look like K"]),
        (["run.csv", "miss.toml"], ["'Tcab'"]),
        (["run.xlsx", "map.toml"], [".xlsx"]),
        (["none.csv", "map.toml"], ["not found"]),
        (["run.csv", "none.toml"], ["none.toml", "not found"]),
    ]
    for (src, cmap), words in cases:
        result = runner.invoke(app, ["import", str(tmp_path / src), "--map",
                                     str(tmp_path / cmap), "--out", str(out)])
        assert_one_line_error(result, *words)
        assert not out.exists()


# ------------------------------------------------------------ econ model family needs
def test_econ_preset_varies_speed_and_ambient_with_steady_holds():
    from acid.excite import MODEL_PRESETS, spec_for_model

    spec = spec_for_model("econ", duration=6 * 3600.0, seed=2)
    s = make_schedule(spec)
    assert spec.duration == MODEL_PRESETS["econ"]["duration"]
    levels = np.unique(s.v_veh)
    assert levels.min() == 0.0 and levels.max() == 36.0 and levels.size == 7   # standstill too
    assert C2K(25.0) <= s.T_amb.min() and s.T_amb.max() <= C2K(40.0)
    assert np.ptp(s.T_amb) > 5.0
    # steady holds: some W_bl levels last at least the 600 s hold
    runs = np.diff(np.flatnonzero(np.diff(np.r_[np.nan, s.W_bl, np.nan]) != 0))
    assert runs.max() * spec.Ts >= 600.0
    assert s.spec["generators"]["W_bl"]["n_holds"] >= 1
    # the paper's preset draws the same inputs as before holds existed
    base = make_schedule(ExcitationSpec(seed=2))
    np.testing.assert_array_equal(base.W_bl, make_schedule(spec_for_model("paper", seed=2)).W_bl)
    assert base.T_amb is None


@pytest.mark.parametrize("kw", [{"speed_bounds": (5.0, 1.0)}, {"T_amb_bounds": (20.0, 80.0)},
                                {"steady_fraction": 1.0},
                                {"speed_bounds": (0.0, 30.0), "cycle": "udds"}])
def test_econ_options_are_validated(kw):
    with pytest.raises(ConfigError):
        ExcitationSpec(**kw)


def test_cli_excite_model_econ(tmp_path):
    out, js = tmp_path / "econ.h5", tmp_path / "econ.json"
    res = runner.invoke(app, ["excite", "--model", "econ", "--duration", "1800", "--out",
                              str(out), "--json", str(js), "--t-amb-range", "28", "35"])
    assert res.exit_code == 0, res.output
    ds = Dataset.from_hdf5(out)
    assert np.ptp(ds["v_veh"]) > 5.0 and 28.0 <= ds["T_amb"].min() <= ds["T_amb"].max() <= 35.0
    # the identity says the ambient that ran, not the configuration's nominal 30 degC
    lo, hi = float(ds["T_amb"].min()), float(ds["T_amb"].max())
    text = " ".join(res.output.split())
    assert f"ambient varied {lo:.1f}..{hi:.1f} degC" in text and "ambient 30 degC" not in text
    d = json.loads(js.read_text())
    assert d["T_amb_C"] is None and d["T_amb_range_C"] == pytest.approx([lo, hi], abs=1e-3)
    res = runner.invoke(app, ["excite", "--model", "thermal", "--out", str(tmp_path / "x.h5")])
    assert_one_line_error(res, "--model", "thermal")


def test_a_microsecond_sample_time_is_refused_before_anything_is_allocated():
    from acid.excite import MAX_SAMPLES

    with pytest.raises(ConfigError, match=r"--duration 7200 s at Ts = 1e-06 s gives 7.2e\+09 "
                                          r"samples \(at most 1000000\)"):
        ExcitationSpec(Ts=1e-6)
    assert ExcitationSpec(Ts=2.0, duration=2.0 * MAX_SAMPLES).n_samples == MAX_SAMPLES
    with pytest.raises(ConfigError, match="at most 1000000"):
        ExcitationSpec(Ts=1.0, duration=MAX_SAMPLES + 5.0)
