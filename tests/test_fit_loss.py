"""A fit loss comparable across models: ``acid fit`` prints each fitted channel's mean squared
error (its unit squared) and NMSE (MSE / the channel's variance), not the optimiser's
objective as "loss"; the objective is kept, named, with what it is. Two structures fitted
on the same record: their objectives are both about half the number of samples (output
error weighs each channel by its own error scale), their MSEs differ as their fits do."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from typer.testing import CliRunner

import acid
from acid.ident.result import DeclaredFitResult
from acid_cli.main import app

N, TS = 400, 60.0

ROOM = """\
from acid.models import Model, Parameter, Signal, State

model = Model("{name}", states=[State("T", "K")], inputs=[Signal("u", "W", "heater")],
              disturbances=[Signal("T_out", "K", "outdoor")],
              parameters=[Parameter("C", "J/K", 4e5, 1e4, 1e7),
                          Parameter("UA", "W/K", {ua}, 0.0, 500.0{fixed})],
              Ts=60.0, ode=lambda s: {{"T": (s.UA * (s.T_out - s.T) + s.u) / s.C}})
"""


@pytest.fixture(scope="module")
def fits(tmp_path_factory):
    """{name: (JSON of `acid fit --json`, its printed output)} for the room with its loss
    coefficient fitted ("room") and without any loss ("sealed", UA fixed at 0), both fitted
    by output error on the same simulated record (UA 45 W/K, C 6e5 J/K, 0.05 K noise)."""
    d = tmp_path_factory.mktemp("loss")
    rng = np.random.default_rng(5)
    u = np.repeat(rng.uniform(0.0, 1500.0, N // 40), 40)
    t_out = 278.15 + 4.0 * np.sin(np.arange(N) * TS / 86400.0 * 2 * np.pi)
    T = np.empty(N)
    T[0] = 288.0
    for k in range(N - 1):
        x = T[k]
        for _ in range(10):
            x += TS / 10 * (45.0 * (t_out[k] - x) + u[k]) / 6e5
        T[k + 1] = x
    acid.Dataset(time=np.arange(N) * TS, Ts=TS,
                 channels={"T": T - 273.15 + rng.normal(0, 0.05, N), "u": u,
                           "T_out": t_out - 273.15},
                 units={"T": "degC", "u": "W", "T_out": "degC"}).to_hdf5(d / "r.h5")
    out = {}
    for name, ua, fixed in (("room", 20.0, ""), ("sealed", 0.0, ", fixed=True")):
        (d / f"{name}.py").write_text(ROOM.format(name=name, ua=ua, fixed=fixed))
        res = CliRunner().invoke(app, [
            "fit", str(d / "r.h5"), "--model", str(d / f"{name}.py"), "--method", "oe",
            "--estimation-fraction", "1", "--oe-window", str(N), "--out",
            str(d / f"{name}.json"), "--json", str(d / f"{name}-s.json")])
        assert res.exit_code == 0, res.output
        out[name] = (json.loads((d / f"{name}-s.json").read_text()),
                     " ".join(res.output.split()), d)
    return out


def test_fit_prints_mse_and_nmse_per_channel_not_the_objective_as_loss(fits):
    for js, text, _ in fits.values():
        assert " loss " not in text
        m = re.search(r"mean squared error per channel \(simulation; .*? variance: "
                      r"T ([0-9.e+-]+) K\^2 \(NMSE ([0-9.e+-]+)\)", text)
        assert m, text
        mse = js["mse_per_channel"]["T"]
        assert float(m.group(1)) == pytest.approx(mse["mse"], rel=1e-3)
        assert float(m.group(2)) == pytest.approx(mse["nmse"], rel=1e-3)
        assert mse["nmse"] == pytest.approx(mse["mse"] / mse["variance"], rel=1e-12)
        assert js["objective"]["what"].startswith("output error")
        assert f"objective {js['objective']['value']:.6g}" in text


def test_two_models_give_different_comparable_numbers(fits):
    (room, _, _), (sealed, _, _) = fits["room"], fits["sealed"]
    # the optimiser's objective is about N/2 for both: it cannot tell them apart
    assert room["objective"]["value"] == pytest.approx(N / 2, rel=0.05)
    assert sealed["objective"]["value"] == pytest.approx(N / 2, rel=0.05)
    # the MSE can: the room's is the sensor noise's (0.05 K)^2, the sealed room's far above
    assert room["mse_per_channel"]["T"]["mse"] == pytest.approx(0.05 ** 2, rel=0.3)
    assert sealed["mse_per_channel"]["T"]["mse"] > 20 * room["mse_per_channel"]["T"]["mse"]
    assert sealed["nmse"]["T"] > 20 * room["nmse"]["T"]
    # same record, same samples: the same variance beneath both NMSEs
    assert room["mse_per_channel"]["T"]["variance"] == pytest.approx(
        sealed["mse_per_channel"]["T"]["variance"], rel=1e-12)


def test_the_mse_is_the_simulation_error_recomputed_with_numpy(fits):
    from acid.models.loader import load

    js, _, d = fits["room"]
    m = load(str(d / "room.py"))
    ds = acid.Dataset.from_hdf5(d / "r.h5")
    T = ds["T"]                                                  # kelvin inside
    p = np.array([e["estimate"] for e in js["parameters"]])
    X, _ = m.simulate(np.array([T[0]]), ds["u"][:-1, None], ds["T_out"][:-1, None], p)
    assert js["mse_per_channel"]["T"]["mse"] == pytest.approx(np.mean((X[:, 0] - T) ** 2),
                                                              rel=1e-6)
    assert js["mse_per_channel"]["T"]["variance"] == pytest.approx(np.var(T), rel=1e-12)


def test_the_result_object_carries_them_and_round_trips(fits):
    js, _, _ = fits["room"]
    keys = {k: js[k] for k in js if k not in ("command", "acid_version", "inputs",
                                              "estimation_fraction", "out")}
    r = DeclaredFitResult.from_json_dict(keys)
    assert r.mse == {"T": js["mse_per_channel"]["T"]["mse"]}
    assert r.objective == js["objective"]["value"]
    assert "MSE (simulation): T" in r.summary() and "K^2" in r.summary()
    assert DeclaredFitResult.from_json_dict(r.to_dict()) == r


def test_prediction_error_scores_one_step_innovations():
    from _gain import gain_data, gain_model

    from acid.ident.fit import fit_model

    r = fit_model(gain_model(), gain_data(n=300), "pem")
    oe = r.output_error
    assert r.mse_scored == "one-step"
    for ch, v in r.channel_mse.items():
        assert v["scored"] == "one-step"
        assert v["mse"] == pytest.approx(oe["innovation_rms"][ch] ** 2, rel=1e-12)
        assert v["nmse"] == pytest.approx((1 - oe["one_step_fit_percent"][ch] / 100) ** 2)
    assert "MSE (one-step)" in r.summary()
    assert r.objective_text.startswith("prediction error: -2 log-likelihood")
    assert r.to_json_dict()["nmse_simulation"] == {}
