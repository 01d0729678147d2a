"""``acid heating-check``: the heating credentials against their references and the i3 logs."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.errors import DataError
from acid.studies.credentials.heating import check_warmup, heating_check, read_trip
from acid.studies.credentials.plant import CheckRow
from acid_cli.main import app

ROOT = Path(__file__).parents[1]
LOGS = ROOT.parent / "shared" / "real-data" / "bmw-i3-winter"
needs_logs = pytest.mark.skipif(not LOGS.is_dir(), reason=f"winter logs absent ({LOGS})")
runner = CliRunner()


@pytest.fixture(scope="module")
def result():
    return heating_check(None)


def test_rows_cite_their_references_and_pass(result):
    sources = (ROOT / "datasets/plant/SOURCES.md").read_text()
    groups = {r.group for r in result.rows}
    assert {"h", "i", "j", "k", "l"} <= groups
    for r in result.rows:
        assert isinstance(r, CheckRow) and r.reference, r
        for key in re.findall(r"\[([A-Za-z0-9.\-]+)\]", r.reference):
            assert f"[{key}]" in sources, (r.name, key)
    ran = [r for r in result.rows if r.passed is not None and r.group in "hijl"]
    assert len(ran) >= 13 and all(r.passed for r in ran), [r for r in ran if not r.passed]
    skipped = [r for r in result.rows if r.passed is None]
    assert skipped and all(r.group == "k" and r.note for r in skipped)
    assert result.passed == all(r.passed for r in result.rows if r.passed is not None)
    assert json.loads(json.dumps(result.to_json_dict()))["checks"][0]["name"] == \
        result.rows[0].name


def test_cop_falls_with_ambient_and_sits_in_the_published_bands(result):
    cop = {float(k): v["COP"] for k, v in result.cop.items()}
    assert cop[-10.0] < cop[0.0] < cop[10.0]
    assert 1.7 <= cop[-10.0] <= 3.3 and 1.9 <= cop[0.0] <= 3.6


def test_frost_penalty_shows(result):
    f = result.frost
    assert f["defrosts"] >= 1 and f["penalty_pct"] > 0.0 and f["cop_wet"] < f["cop_dry"]


def test_cold_chamber_against_the_adac_test(result):
    rows = {r.name: r for r in result.rows if r.group == "m"}
    assert len(rows) == 6
    d = result.cold_chamber
    assert rows["cold chamber: power to hold 20 degC at -10 degC (60-90 min)"].passed
    assert rows["cold chamber: cabin 40 min after a -10 degC soak (coolant heater)"].passed
    # switched off, the cabin cools: no warmer than the best-insulated cars
    assert d["T_off_C"][30] < d["T_off_C"][5] < 20.0
    assert rows["cold chamber: cabin 30 min after switching off"].passed
    assert rows["cold chamber: cabin 5 min after switching off"].passed
    assert d["E20_kWh"] > 0.0 and d["t20_min"] > 0.0
    # the energy as the ADAC counted it: the heat-up ends at 20 degC or after 40 min
    if d["reached_in_heatup"]:
        assert d["E20_kWh"] == d["E_to_20_kWh"] and d["t20_min"] <= 40.0
    else:
        assert d["t20_min"] > 40.0 and d["T40_C"] < 20.0
        assert d["E20_kWh"] < d["E_to_20_kWh"]
    assert rows["cold chamber: electric energy of the heat-up to 20 degC"].passed


@needs_logs
def test_warmup_against_the_i3_winter_logs():
    rows, trips = check_warmup(LOGS)
    assert len(trips) >= 8
    by = {r.name.split(": ")[1]: r for r in rows}
    t20 = by["time to 20 degC (median plant/log)"]
    p10 = by["heater power, first 10 min (median plant/log)"]
    hold = by["heater power after 15 min (median plant/log)"]
    # the winter envelope (trim behind the inner film) holds the cabin on the i3's power
    assert t20.passed and p10.passed and hold.passed, (t20, p10, hold)
    assert hold.value is not None and math.isfinite(hold.value)
    for t in trips:
        assert t["P10_plant"] > 0 and t["t20_log"] > 0


def test_unreadable_trip_is_a_data_error(tmp_path):
    bad = tmp_path / "TripB99.csv.gz"
    bad.write_bytes(b"not gzip")
    with pytest.raises(DataError, match="TripB99.csv.gz"):
        read_trip(bad)


def test_cli_bad_logs_folder_is_one_line_error(tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("x")
    res = runner.invoke(app, ["heating-check", "--logs", str(afile)])
    assert res.exit_code == 2
    assert_one_line_error(res, "--logs", "afile")
    res = runner.invoke(app, ["heating-check", "--logs", str(tmp_path)])
    assert res.exit_code == 2
    assert_one_line_error(res, "--logs", "no Trip*.csv.gz")


def test_cli_runs_and_writes_json(tmp_path, monkeypatch):
    monkeypatch.setenv("ACID_WINTER_LOGS", str(tmp_path / "none"))
    js = tmp_path / "h.json"
    res = runner.invoke(app, ["heating-check", "--json", str(js)])
    d = json.loads(js.read_text())
    assert res.exit_code == (0 if d["passed"] else 1), res.output
    assert "acid heating-check" in res.output and "COP" in res.output
    assert d["logs"] is None and len(d["checks"]) >= 16
