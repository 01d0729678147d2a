"""``acid car fit|validate|control`` on a few real BMW i3 summer trips (linked from
``../shared/real-data``, skipped where absent) and their one-line refusals."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid_cli.main import app

ROOT = Path(__file__).resolve().parents[1]
REAL = next((p for p in (ROOT.parent / "shared" / "real-data" / "bmw-i3",
                         ROOT.parent.parent / "shared" / "real-data" / "bmw-i3") if p.is_dir()),
            ROOT.parent / "shared" / "real-data" / "bmw-i3")
needs_logs = pytest.mark.skipif(not REAL.is_dir(), reason=f"real vehicle data not found at "
                                f"{REAL} (the BMW i3 trips; acid does not ship them)")
#: three short trips with the A/C running (82-273 samples of 5 s)
TRIPS = ("TripA04", "TripA05", "TripA11")
runner = CliRunner()


@pytest.fixture
def logs(tmp_path):
    d = tmp_path / "logs"
    d.mkdir()
    for t in TRIPS:
        (d / f"{t}.csv.gz").symlink_to(REAL / f"{t}.csv.gz")
    return d


@needs_logs
def test_car_fit_writes_a_car_ac_file_and_scores_the_held_out_trip(logs, tmp_path):
    out, js = tmp_path / "car_ac.json", tmp_path / "fit.json"
    r = runner.invoke(app, ["car", "fit", str(logs), "--held-out", "TripA05", "--out",
                            str(out), "--json", str(js)])
    assert r.exit_code == 0, r.output
    params = json.loads(out.read_text())
    assert params["model"] == "car_ac"
    s = json.loads(js.read_text())
    assert s["held_out_trips"] == ["TripA05"] and s["estimation_trips"] == ["TripA04", "TripA11"]
    assert s["power_rows"]["k_ac"] == pytest.approx(params["parameters"]["k_ac"]["value"])
    assert 0.3 < s["held_out"]["energy_ratio"] < 3.0, s["held_out"]
    # the file it wrote is what `acid car control` (and validate) read back
    r = runner.invoke(app, ["car", "validate", str(logs), "--params", str(out), "--folds", "3"])
    assert r.exit_code == 0, r.output


@needs_logs
def test_car_validate_scores_each_trip_held_out_and_the_regressor_bound(logs, tmp_path):
    js = tmp_path / "val.json"
    r = runner.invoke(app, ["car", "validate", str(logs), "--json", str(js)])
    assert r.exit_code == 0, r.output
    s = json.loads(js.read_text())
    assert [t["trip"] for t in s["model"]["trips"]] == list(TRIPS)
    assert s["model"]["folds"] == 3 and s["bound"]["folds"] == 3
    lo, hi = s["model"]["r2_5s_ci90"]
    assert lo <= s["model"]["r2_5s"] <= hi
    assert 0.3 < s["model"]["energy_ratio"] < 3.0


@needs_logs
def test_car_control_runs_the_nmpc_on_a_trip_replay(logs, tmp_path):
    js = tmp_path / "ctl.json"
    r = runner.invoke(app, ["car", "control", str(logs), "--trip", "TripA04", "--horizon",
                            "12", "--json", str(js)])
    assert r.exit_code == 0, r.output
    s = json.loads(js.read_text())
    assert s["trip"] == "TripA04" and s["samples"] == 82
    assert s["nmpc"]["fallbacks"] == 0 and s["nmpc"]["energy_kJ"] > 0
    assert s["logged"]["energy_kJ"] == pytest.approx(301 * 82 * 5 / 1e3, rel=0.01)


def test_car_commands_refuse_in_one_line(tmp_path):
    missing = tmp_path / "nowhere"
    assert_one_line_error(runner.invoke(app, ["car", "fit", str(missing)]), "LOGS",
                          "not found")
    f = tmp_path / "a.csv"
    f.write_text("x\n")
    assert_one_line_error(runner.invoke(app, ["car", "validate", str(f)]), "LOGS",
                          "not a folder")
    empty = tmp_path / "empty"
    empty.mkdir()
    assert_one_line_error(runner.invoke(app, ["car", "control", str(empty), "--trip", "X"]),
                          "no *.csv")


@needs_logs
def test_car_commands_refuse_a_wrong_parameter_file_and_an_unknown_trip(logs, tmp_path):
    from acid.models import load
    from acid.models.values import ParameterValues

    heating = ParameterValues(model=load("heating")).to_json(tmp_path / "heating.json")
    assert_one_line_error(runner.invoke(app, ["car", "fit", str(logs), "--params",
                                              str(heating)]), "'heating'", "car_cabin")
    assert_one_line_error(runner.invoke(app, ["car", "control", str(logs), "--trip",
                                              "TripA04", "--params", str(heating)]),
                          "'heating'", "car_ac")
    assert_one_line_error(runner.invoke(app, ["car", "fit", str(logs), "--held-out",
                                              "TripZ9"]), "--held-out", "TripZ9")
    assert_one_line_error(runner.invoke(app, ["car", "control", str(logs), "--trip",
                                              "TripZ9"]), "TripZ9")


@needs_logs
def test_validate_car_ac_reads_the_car_fit_file_and_names_it_for_a_cabin_file(logs, tmp_path):
    from acid.models import load
    from acid.models.values import ParameterValues

    h5, out = tmp_path / "t.h5", tmp_path / "car_ac.json"
    cabin = ParameterValues(model=load("car_cabin")).to_json(tmp_path / "cabin.json")
    r = runner.invoke(app, ["import", str(logs / "TripA04.csv.gz"), "--map",
                            "example:bmw_i3_map.toml", "--out", str(h5)])
    assert r.exit_code == 0, r.output
    assert_one_line_error(runner.invoke(app, ["validate", str(h5), "--model", "car_ac",
                                              "--params", str(cabin)]),
                          "'car_cabin'", "acid car fit")
    r = runner.invoke(app, ["car", "fit", str(logs), "--params", str(cabin), "--out", str(out)])
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["validate", str(h5), "--model", "car_ac", "--params", str(out),
                            "--starts", "3", "--horizon", "12", "--out", str(tmp_path / "f"),
                            "--no-figures"])
    assert r.exit_code == 0, r.output
