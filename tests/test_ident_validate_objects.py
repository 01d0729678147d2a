"""A validation result reads as a table (``summary()``, ``repr``) and a DataFrame."""

from __future__ import annotations

import numpy as np
import pytest
from test_ident_validate import _cabin3_record

from acid.ident.validate import declared_parameters, validate_model
from acid.models import load


def test_the_validation_reads_as_one_table_per_channel_and_a_frame():
    m = load("cabin3")
    ds = _cabin3_record(m.values.copy(), np.random.default_rng(0), n=300)
    r = validate_model(m, ds, declared_parameters(m), starts=6, horizon=50, warmup=150.0,
                       yardsticks=True)
    text = repr(r)
    assert text.startswith("DeclaredValidation(\ncabin3: 6 windows of 50 steps (250 s)")
    assert r.summary() in text and "persistence" in text and "note: " in text
    assert len(text.splitlines()) < 40                       # no arrays printed
    df = r.to_frame()
    assert set(df["predictor"]) == {"model", "persistence", "arx", "subspace"}
    row = df[(df.predictor == "persistence") & (df.channel == "T_cab")].iloc[0]
    assert row["rmse"] == pytest.approx(r.yardsticks["persistence"]["by_time"]["T_cab"]
                                        [f"{row['time_s']:g}"]["rmse_K"])
    assert (df[df.predictor == "model"]["rmse"] < 1e-9).all()   # its own parameters: exact


def test_the_horizon_curves_are_a_figure_of_every_step():
    import matplotlib

    matplotlib.use("Agg")
    m = load("cabin3")
    ds = _cabin3_record(m.values.copy(), np.random.default_rng(0), n=200)
    r = validate_model(m, ds, declared_parameters(m), starts=4, horizon=30, warmup=100.0,
                       yardsticks=True)
    fig = r.plot_horizon()
    assert len(fig.axes) == len(r.channels)
    lines = {ln.get_label(): ln for ln in fig.axes[0].get_lines()}
    assert set(lines) == {"model", "persistence", "arx", "subspace"}
    persistence = lines["persistence"].get_ydata()
    assert len(persistence) == 30
    np.testing.assert_allclose(persistence, r.by_step()["persistence"]["T_cab"]["rmse"])


def test_the_validation_round_trips_through_json_with_every_step():
    import json

    from acid.errors import DataError
    from acid.ident.validate import DeclaredValidation

    m = load("cabin3")
    ds = _cabin3_record(m.values.copy(), np.random.default_rng(1), n=200)
    r = validate_model(m, ds, declared_parameters(m), starts=4, horizon=30, warmup=100.0,
                       yardsticks=True, estimation=(0, 100), horizons=(1, 7, 30))
    d = json.loads(json.dumps(r.to_json_dict(), allow_nan=False))   # strict JSON
    back = DeclaredValidation.from_json_dict(d)
    assert back == r and back.to_json_dict() == d
    assert back.summary() == r.summary() and back.to_frame().equals(r.to_frame())
    assert [row["step"] for row in back.by_horizon] == [1, 7, 30]
    for who in ("model", "persistence", "arx", "subspace"):        # every step kept
        assert len(back.by_step()[who]["T_cab"]["rmse"]) == 30
    np.testing.assert_array_equal(back.starts, r.starts)
    np.testing.assert_array_equal(back.start_time, r.start_time)
    assert back.settings["hold"] == r.settings["hold"] and back.window_design == r.window_design
    # the CLI's --json holds the same keys beside its own: read back alike
    assert DeclaredValidation.from_json_dict({"command": "validate", **d}) == r
    # a changed figure is not equal
    d2 = json.loads(json.dumps(d))
    d2["by_step"]["arx"]["T_cab"]["rmse"][29] += 1e-9
    assert DeclaredValidation.from_json_dict(d2) != r
    with pytest.raises(DataError, match="not a validation summary"):
        DeclaredValidation.from_json_dict({"model": "cabin3"})
