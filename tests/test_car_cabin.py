"""The shipped cabin model for what a car logs (``acid/models/car_cabin.py``, issue 20): its
declaration, recovery of its parameters by the declared fitter with latent interior and
shell, and identification and held-out validation on real BMW i3 trips
(``../shared/real-data``; skipped, with the reason, where that folder is absent)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from acid.data import ChannelMap, Dataset, import_logs
from acid.examples import resolve
from acid.ident.fit import fit_model
from acid.ident.validate import fitted_parameters, validate_model
from acid.models import load
from acid.models.values import ParameterValues

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT.parent / "shared" / "real-data" / "bmw-i3"
SOURCES = ROOT / "acid" / "models" / "SOURCES.md"


def test_declaration_loads_by_name_with_latent_interior_and_shell_and_cited_ranges():
    m = load("car_cabin")
    assert m.name == "car_cabin"
    assert [(s.name, s.measured) for s in m.states] == [
        ("T_cab", True), ("T_int", False), ("T_shell", False), ("Q_sol", False)]
    # the unlogged load is a random walk a filter follows (acid.ident.pem)
    assert m.states[3].noise == "sigma_Q" and m.states[3].spread > 0
    # only channels a car logs: no blower flow, no supply air
    assert {r.name for r in (*m.inputs, *m.disturbances)} == {"T_evap", "T_amb", "v_veh"}
    for p in m.parameters:
        assert p.min < p.max and p.min <= p.value <= p.max, p.name
    # every range is cited: the keys in the docstring are references in SOURCES.md
    doc = __import__("acid.models.car_cabin", fromlist=["x"]).__doc__
    keys = set(re.findall(r"\[([A-Za-z]+\d{4})", doc)) | set(re.findall(
        r", ([A-Za-z]+\d{4})", doc))
    text = SOURCES.read_text(encoding="utf-8")
    assert keys and all(f"**{k}**" in text for k in keys), keys


def _simulated(truth: dict, loads, rng, n=360) -> Dataset:
    """Noise-free trips of car_cabin itself: latent interior and shell (not in the data),
    the evaporator air switched between A/C on and off, speed and ambient varying."""
    m = load("car_cabin")
    names = m.parameter_names
    parts = []
    for i, q in enumerate(loads):
        dwell = 30
        T_ev = np.repeat(rng.uniform(278.0, 300.0, n // dwell + 1), dwell)[:n]
        Ta = 300.0 + 2.0 * np.sin(np.arange(n) / 80.0 + i)
        v = np.repeat(rng.uniform(0.0, 25.0, n // dwell + 1), dwell)[:n]
        p = m.values.copy()
        for k, val in truth.items():
            p[names.index(k)] = val
        X, _ = m.simulate(np.array([310.0, 315.0, 305.0, q]), T_ev[:, None], np.c_[Ta, v], p)
        ch = {"T_cab": X[:-1, 0] - 273.15, "T_evap": T_ev - 273.15, "T_amb": Ta - 273.15,
              "v_veh": v}
        parts.append(Dataset(np.arange(n) * 5.0, ch, {k: "m/s" if k == "v_veh" else "degC"
                                                    for k in ch}, 5.0))
    return Dataset.concatenate(parts)


def test_output_error_recovers_known_parameters_with_latent_states(rng):
    truth = {"C_cab": 15.0, "G_sup": 70.0, "UA_int": 120.0}
    ds = _simulated(truth, (200.0, 700.0), rng)
    assert "T_int" not in ds and "T_shell" not in ds
    # the capacities of the slow nodes and the shell's conductances held at their declared
    # values (which generated the data), and the load's dynamics; the fast ones, and the
    # load at each window's start, estimated
    fix = {n: load("car_cabin").parameter(n).value
           for n in ("C_int", "C_shell", "UA_shell", "UA_out", "UA_out_v", "Q_bar", "tau_Q")}
    res = fit_model("car_cabin", ds, "oe", fix=fix, oe_window=120)
    assert res.method == "oe" and res.output_error["converged"]
    for name, t in truth.items():
        assert res.value(name) == pytest.approx(t, rel=1e-3), name
    assert "latent: T_int" in " ".join(res.notes)


def test_validation_to_the_trips_end_scores_only_reached_horizons_and_yardsticks(rng):
    truth = {"C_cab": 15.0, "G_sup": 70.0, "UA_int": 120.0}
    est = _simulated(truth, (200.0, 700.0), rng, n=300)
    val = _simulated(truth, (450.0,), rng, n=200)
    m = load("car_cabin")
    p = m.values.copy()
    for k, v in truth.items():
        p[m.parameter_names.index(k)] = v
    ps = ParameterValues(p, model=m)
    with pytest.raises(Exception, match="longer than warmup"):
        validate_model(m, val, ps, starts=10, horizon=300, warmup=150.0)
    # the yardsticks fitted on the estimation trips, placed before the validation trip
    both, n_est = Dataset.concatenate([est, val]), len(est)
    res = validate_model(m, both, ps, starts=10, horizon=300, warmup=150.0, to_end=True,
                         yardsticks=True, estimation=(0, n_est), hold=(),
                         start_range=(n_est, len(both)))
    assert (res.starts >= n_est + 30).all()
    e = res.errors["T_cab"]
    # every start reaches its trip's end and no further
    reach = np.isfinite(e).sum(axis=1)
    np.testing.assert_array_equal(reach, len(both) - 1 - res.starts)
    # the model that made the data predicts it (latent states from the warm-up stretch)
    assert np.nanmax(np.abs(e)) < 0.05
    assert set(res.yardsticks) == {"persistence", "arx", "subspace"}
    model = res.by_time["T_cab"]
    assert model["60"]["n"] == res.starts.size
    assert "1500" not in model                          # no start reaches 1500 s
    pers = res.yardsticks["persistence"]["by_time"]["T_cab"]
    assert pers["300"]["n"] == model["300"]["n"] < res.starts.size
    assert pers["300"]["p90_K"] > model["300"]["p90_K"]
    d = res.to_json_dict()
    assert set(d["yardsticks_by_time"]) == {"persistence", "arx", "subspace"}
    assert set(d["yardsticks_by_time"]["arx"]["T_cab"]["60"]) == {"rmse_K", "p90_K", "n"}


# ------------------------------------------------------------------ real BMW i3 trips
#: Fitted on four trips, validated on four others (a hot-soak pull-down and a trip with the
#: A/C holding the cabin near its target in each).
EST_TRIPS = ("TripA07", "TripA12", "TripA01", "TripA14")
VAL_TRIPS = ("TripA08", "TripA11", "TripA05", "TripA13")
#: Bound on the held-out p90 |error| of T_cab at 600 s (K): 3.55 K measured (40 evaluations),
#: 3.56 K at the converged optimum (100); the 2.33 K of 2026-11-26 was an unconverged point.
P90_600_BOUND = 4.0


def _trips(names) -> Dataset:
    cmap = ChannelMap.from_file(resolve("example:bmw_i3_map.toml"))
    return import_logs([REAL / f"{n}.csv.gz" for n in names], cmap)


@pytest.mark.skipif(not REAL.is_dir(), reason=f"real vehicle data not found at {REAL} "
                    "(../shared/real-data beside the repository; acid does not ship it)")
def test_real_trips_prediction_error_fit_beats_persistence_on_held_out_trips():
    """The whole path on real logs, short: PEM (an EKF following the unlogged load) on four
    trips, then open-loop predictions on four others from the filter's state at each start
    (the filter run from the trip's start),
    beside persistence on the same windows (the full measurement: notes/i20-real-logs.md)."""
    est, val = _trips(EST_TRIPS), _trips(VAL_TRIPS)
    assert "T_cab_censored" in est       # the clipped hot-soak starts are masked
    res = fit_model("car_cabin", est, "pem", max_nfev=40)
    assert res.output_error["one_step_fit_percent"]["T_cab"] > 90.0
    for e in res.estimates:
        p = load("car_cabin").parameter(e.name)
        assert p.min <= e.value <= p.max, e.name
    both, n = Dataset.concatenate([est, val]), len(est)
    v = validate_model("car_cabin", both, fitted_parameters(res), starts=24, horizon=300,
                       warmup=300.0, to_end=True, yardsticks=True, estimation=(0, n),
                       start_range=(n, len(both)), warm_start="ekf-trip")
    model, pers = v.by_time["T_cab"], v.yardsticks["persistence"]["by_time"]["T_cab"]
    assert model["60"]["n"] == pers["60"]["n"] == v.starts.size
    # the filter's state (run from each trip's start) and the cabin's response beat holding
    # the value: measured 2026-11-26 (40 evaluations; model / persistence, p90 K): 0.43 /
    # 0.67 at 60 s (24 starts), 1.33 / 1.87 at 300 s (19), RMSE 1.56 / 2.39 K at 600 s (15)
    for t in ("60", "300"):
        assert model[t]["p90_K"] < pers[t]["p90_K"], (t, model, pers)
    assert model["600"]["rmse_K"] < pers["600"]["rmse_K"], (model, pers)
    # bounded with margin for another BLAS or CasADi (the p90 rests on 15 starts of 4 trips)
    assert model["600"]["p90_K"] < P90_600_BOUND, (model, pers)


def test_cli_fits_car_cabin_by_name_and_validates_to_the_trips_end_with_yardsticks(
        rng, tmp_path):
    import json

    from typer.testing import CliRunner

    from acid_cli.main import app

    truth = {"C_cab": 15.0, "G_sup": 70.0, "UA_int": 120.0}
    est, val = tmp_path / "est.h5", tmp_path / "val.h5"
    _simulated(truth, (200.0, 700.0), rng, n=300).to_hdf5(est)
    _simulated(truth, (450.0,), rng, n=200).to_hdf5(val)
    fixes = [f"--fix={n}={load('car_cabin').parameter(n).value}"
             for n in ("C_int", "C_shell", "UA_shell", "UA_out", "UA_out_v", "Q_bar", "tau_Q")]
    runner = CliRunner()
    res = runner.invoke(app, ["fit", str(est), "--model", "car_cabin", "--method", "oe",
                              "--oe-window", "120", *fixes, "--out", str(tmp_path / "p.json")])
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, ["validate", str(val), "--model", "car_cabin", "--params",
                              str(tmp_path / "p.json"), "--starts", "8", "--warmup", "150",
                              "--to-end", "--exogenous", "measured",
                              "--json", str(tmp_path / "v.json"), "--no-figures"])
    assert res.exit_code == 0, res.output
    assert "persistence" in res.output and "yardstick" in res.output
    d = json.loads((tmp_path / "v.json").read_text())
    assert set(d["yardsticks_by_time"]) == {"persistence", "arx", "subspace"}
    assert d["by_time"]["T_cab"]["60"]["p90_K"] < 0.05


def test_censored_samples_are_neither_fitted_nor_scored(rng):
    from acid.ident.data import ModelData

    truth = {"C_cab": 15.0, "G_sup": 70.0, "UA_int": 120.0}
    ds = _simulated(truth, (450.0,), rng, n=200)
    clipped = ds["T_cab"] > np.percentile(ds["T_cab"], 90)
    ch = {n: ds[n] for n in ("T_cab", "T_evap", "T_amb", "v_veh")}
    ch["T_cab"] = np.where(clipped, 10.0, ch["T_cab"])        # a wrong value where clipped
    ch["T_cab_censored"] = clipped.astype(float)
    bad = Dataset(ds.time, ch, {**{n: ds.units[n] for n in ch if n in ds.units},
                                "T_cab_censored": "1"}, 5.0)
    m = load("car_cabin")
    data = ModelData.of(m, bad)
    assert np.isnan(data.observed()[clipped, 0]).all()
    assert np.isfinite(data.observed()[~clipped, 0]).all()
    p = m.values.copy()
    for k, v in truth.items():
        p[m.parameter_names.index(k)] = v
    res = validate_model(m, bad, ParameterValues(p, model=m),
                         starts=5, horizon=40, warmup=150.0)
    e = res.errors["T_cab"]
    scored = ~clipped[res.starts[:, None] + np.arange(1, 41)[None, :]]
    assert np.isnan(e[~scored]).all() and np.nanmax(np.abs(e)) < 0.05
    assert any("censored" in n for n in res.notes)
