"""``acid excite --plant heating``: the heating plant run as the logged i3 for identification
(``acid/plant/heating_excite.py``): reproducible, within the coolant limit, with the declared
heating model's channels, identifiable by it."""

from __future__ import annotations

import numpy as np
import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.data import Dataset
from acid.excite import ExcitationSpec, excite
from acid.ident.data import ModelData
from acid.ident.fit import fit_model
from acid.models import load
from acid.plant.heating_excite import HeatingExcitation
from acid_cli.main import app

runner = CliRunner()


def _spec(**kw):
    base = dict(duration=2 * 3600.0, speed_bounds=(0.0, 30.0), T_amb_bounds=(-10.0, 10.0),
                min_dwell=60.0, max_dwell=900.0, seed=3)
    return ExcitationSpec(**{**base, **kw})


@pytest.fixture(scope="module")
def record():
    return excite(HeatingExcitation(), _spec())


def test_same_seed_same_bits_and_the_heater_within_its_limits(record):
    again = excite(HeatingExcitation(), _spec())
    for name in ("T_cab", "T_cool", "T_ain", "P_heater"):
        np.testing.assert_array_equal(record[name], again[name])
    other = excite(HeatingExcitation(), _spec(seed=4))
    assert not np.array_equal(record["P_heater"], other["P_heater"])
    P, T_cool = record.get("P_heater", "W"), record.get("T_cool")
    assert P.min() >= 0.0 and P.max() <= 3000.0 + 1e-9
    assert T_cool.max() < 85.0 + 1.0  # derated over the last 5 K below the 85 degC limit
    # the blower and recirculation held, no heat pump: what the model assumes of the car
    np.testing.assert_allclose(record["W_bl"], 0.08, rtol=1e-12)
    np.testing.assert_allclose(record["recirc"], 0.8, rtol=1e-12)
    assert np.all(record["P_comp"] == 0.0)
    meta = record.metadata
    assert meta["plant"] == "heating" and meta["excitation"]["generators"]["P_heater"]["unit"] \
        == "W"


def test_the_record_feeds_the_declared_heating_model_and_it_fits(record):
    m = load("heating")
    data = ModelData.of(m, record)
    assert np.isfinite(data.u).all() and np.isfinite(data.y).all()
    fix = {n: m.parameter(n).value for n in ("C_int", "C_shell", "UA_out", "UA_out_v")}
    res = fit_model(m, record.window(0, 360), "oe", fix=fix, oe_window=120, max_nfev=15)
    fit = res.output_error["channel_fit_percent"]
    assert fit["T_cab"] > 80.0 and fit["T_cool"] > 80.0, fit


def test_cli_writes_the_record_and_refuses_options_of_other_plants(tmp_path):
    out = tmp_path / "h.h5"
    res = runner.invoke(app, ["excite", "--plant", "heating", "--duration", "600", "--t-amb",
                              "0", "-o", str(out)])
    assert res.exit_code == 0, res.output
    ds = Dataset.from_hdf5(out)
    assert len(ds) == 120 and ds["T_amb"][0] == pytest.approx(0.0)
    res = runner.invoke(app, ["excite", "--plant", "heating", "--plant-config", "paper",
                              "-o", str(tmp_path / "x.h5")])
    assert res.exit_code == 2
    assert_one_line_error(res, "--plant-config", "heating")
