"""The prior weight: every declared prior's information times W (0: no prior, 1: as
declared), against the closed form of a model linear in its parameter, in least squares,
output error and through `acid fit --prior-weight`."""

from __future__ import annotations

import json

import numpy as np
import pytest
from _cli import assert_one_line_error
from _gain import gain_data, gain_model
from typer.testing import CliRunner

from acid.errors import ConfigError
from acid.ident.fit import fit_model
from acid_cli.main import app


def _ls_map(ds, mean, sd, weight) -> float:
    """MAP of y = k u with the prior's information times ``weight`` (noise scale: the
    residual sd of the fit without priors, as the least-squares prior rows take it)."""
    u, y = ds["u"], ds["y"]
    res = y - (u @ y) / (u @ u) * u
    lam = weight * (res @ res / (u.size - 1)) / sd**2
    return float((u @ y + mean * lam) / (u @ u + lam))


@pytest.mark.parametrize("weight", [0.0, 1 / 16, 0.25, 1.0, 4.0])
def test_least_squares_estimate_follows_the_weighted_prior(weight):
    ds = gain_data()
    k = fit_model(gain_model((1.5, 0.01)), ds, "ls", prior_weight=weight).estimates[0].value
    assert k == pytest.approx(_ls_map(ds, 1.5, 0.01, weight), abs=1e-9)


def test_output_error_weight_zero_is_the_fit_without_priors_and_one_the_declared():
    ds = gain_data()
    free = fit_model(gain_model(), ds, "oe").estimates[0].value
    zero = fit_model(gain_model((1.5, 0.01)), ds, "oe", prior_weight=0).estimates[0].value
    one = fit_model(gain_model((1.5, 0.01)), ds, "oe").estimates[0].value
    quarter = fit_model(gain_model((1.5, 0.01)), ds, "oe",
                        prior_weight=0.25).estimates[0].value
    assert zero == pytest.approx(free, rel=1e-9)
    assert 1.5 < one < quarter < free          # less weight: closer to the data's value


@pytest.mark.parametrize("weight", [-1.0, float("nan"), float("inf"), "heavy"])
def test_a_bad_weight_is_refused(weight):
    with pytest.raises(ConfigError, match="prior weight"):
        fit_model(gain_model((1.5, 0.01)), gain_data(), "ls", prior_weight=weight)


def test_cli_prior_weight_passes_through_and_refuses_a_negative_one(tmp_path):
    src = tmp_path / "gain.py"
    src.write_text("from _gain import gain_model\nmodel = gain_model()\n")
    ds = gain_data()
    ds.to_hdf5(tmp_path / "g.h5")
    runner = CliRunner()
    out = {}
    for w in ("0", "1"):
        r = runner.invoke(app, ["fit", str(tmp_path / "g.h5"), "--model", str(src),
                                "--method", "ls", "--prior", "k=1.5,0.01",
                                "--prior-weight", w, "--out", str(tmp_path / f"p{w}.json")])
        assert r.exit_code == 0, r.output
        out[w] = json.loads((tmp_path / f"p{w}.json").read_text())
    k0, k1 = (out[w]["parameters"]["k"]["value"] for w in ("0", "1"))
    assert k0 == pytest.approx(_ls_map(ds, 1.5, 0.01, 0.0), abs=1e-8)
    assert k1 == pytest.approx(_ls_map(ds, 1.5, 0.01, 1.0), abs=1e-8)
    assert not np.isclose(k0, k1)
    r = runner.invoke(app, ["fit", str(tmp_path / "g.h5"), "--model", str(src),
                            "--prior-weight", "-1", "--out", str(tmp_path / "x.json")])
    assert_one_line_error(r, "--prior-weight")


def test_car_select_refuses_a_negative_prior_weight(tmp_path):
    r = CliRunner().invoke(app, ["car", "select", str(tmp_path), "--prior-weight", "-0.5"])
    assert_one_line_error(r, "--prior-weight")
