"""The API speaks the CLI's units: ``validate_model``'s ``warmup`` is seconds, as ``acid
validate --warmup`` (``horizon`` is steps in both), so on a record of Ts = 2 s the API and
the command give the same validation with the same arguments and with their defaults."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

import acid
from acid.errors import AcidError
from acid_cli.main import app

TS, N = 2.0, 600          # s, samples (20 min)

# a room (measured air T) and its wall (latent W): the warm-up stretch fits W at each start
MODEL = """\
from acid.models import Model, Parameter, Signal, State

model = Model(
    "room2", states=[State("T", "K"), State("W", "K", measured=False, initial=lambda s: s.T)],
    inputs=[Signal("u", "W", "heater")], disturbances=[Signal("T_out", "K", "outdoor")],
    parameters=[Parameter("C", "J/K", 2e4, 1e3, 1e6), Parameter("Cw", "J/K", 2e5, 1e3, 1e7),
                Parameter("h", "W/K", 40.0, 1.0, 500.0),
                Parameter("UA", "W/K", 10.0, 0.1, 500.0)],
    Ts=2.0, ode=lambda s: {"T": (s.h * (s.W - s.T) + s.u) / s.C,
                           "W": (s.h * (s.T - s.W) + s.UA * (s.T_out - s.W)) / s.Cw})
"""


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    """(model file, HDF5 record, the loaded model, the Dataset): the declared room
    simulated with a wall 3 K off the air at the start and 0.02 K sensor noise."""
    from acid.models.loader import load

    d = tmp_path_factory.mktemp("units")
    f = d / "room2.py"
    f.write_text(MODEL)
    m = load(str(f))
    rng = np.random.default_rng(7)
    u = np.repeat(rng.uniform(0.0, 800.0, N // 30 + 1), 30)[:N]
    t_out = np.full(N, 275.0)
    X, _ = m.simulate(np.array([293.0, 290.0]), u[:, None], t_out[:, None], m.values)
    ds = acid.Dataset(time=np.arange(N) * TS, Ts=TS,
                      channels={"T": X[:N, 0] - 273.15 + rng.normal(0, 0.02, N), "u": u,
                                "T_out": t_out - 273.15},
                      units={"T": "degC", "u": "W", "T_out": "degC"})
    ds.to_hdf5(d / "r.h5")
    return f, d / "r.h5", m, acid.Dataset.from_hdf5(d / "r.h5")


def _cli(record, tmp_path, *extra) -> dict:
    f, h5, _, _ = record
    out = tmp_path / "v.json"
    res = CliRunner().invoke(app, ["validate", str(h5), "--model", str(f), "--starts", "5",
                                   "--horizon", "30", "--no-yardsticks", "--no-figures",
                                   "--out", str(tmp_path / "figs"), "--json", str(out),
                                   *extra])
    assert res.exit_code == 0, res.output
    return json.loads(out.read_text())


@pytest.mark.parametrize("warmup_s", [None, 40.0])
def test_api_and_cli_give_the_same_validation_at_ts_2s(record, tmp_path, warmup_s):
    _, _, m, ds = record
    cli = _cli(record, tmp_path, *([] if warmup_s is None else ["--warmup", f"{warmup_s:g}"]))
    kw = {} if warmup_s is None else {"warmup": warmup_s}
    api = acid.validate_model(m, ds, starts=5, horizon=30, yardsticks=False, **kw)
    want = 300.0 if warmup_s is None else warmup_s           # s, the default is 300 s
    assert api.warmup == cli["warmup"] == int(want / TS)      # 150 or 20 samples of 2 s
    assert api.warmup_s == cli["warmup_s"] == want
    assert api.starts.tolist() == cli["starts"]
    for ch in api.channels:
        for k in ("rmse", "p90_abs", "max_abs"):
            assert api.metrics[ch][k] == pytest.approx(cli["channels"][ch][k], rel=1e-9)


def test_a_warmup_that_is_not_whole_samples_is_a_one_line_error(record):
    _, _, m, ds = record
    with pytest.raises(AcidError, match=r"^warmup 301 s is not a whole number of samples "
                                        r"of 2 s \(e\.g\. 300 s or 302 s\)$"):
        acid.validate_model(m, ds, starts=2, horizon=10, warmup=301.0, yardsticks=False)
    with pytest.raises(AcidError, match="warmup must be a duration >= 0 s"):
        acid.validate_model(m, ds, starts=2, horizon=10, warmup=-2.0, yardsticks=False)


def test_predict_compare_resid_take_the_warmup_in_seconds_too(record):
    _, _, m, ds = record
    pr = acid.predict(ds, None, 1, model=m, warmup=300.0)      # 150 samples of 2 s
    assert np.flatnonzero(np.isfinite(pr.predicted[:, 0]))[0] == 150 + 1
    with pytest.raises(AcidError, match=r"^predict: warmup 3 s is not a whole number"):
        acid.predict(ds, None, 1, model=m, warmup=3.0)


def test_the_default_warmup_needs_no_whole_samples_where_nothing_is_latent():
    from acid.models import Model, Parameter, Signal, State

    m = Model("lag7", states=[State("y", "V")], inputs=[Signal("u", "V")],
              parameters=[Parameter("a", "1/s", 0.01, 1e-4, 1.0)], Ts=7.0,
              ode=lambda s: {"y": s.a * (s.u - s.y)})
    n = 200
    u = np.repeat(np.random.default_rng(1).uniform(-1, 1, n // 20), 20)
    ds = acid.Dataset(time=np.arange(n) * 7.0, Ts=7.0, channels={"y": np.cumsum(u) * 0.01,
                                                                  "u": u},
                      units={"y": "V", "u": "V"})
    res = acid.validate_model(m, ds, starts=3, horizon=20, yardsticks=False)   # 300 s default
    assert res.warmup == 0 and res.starts.size == 3
