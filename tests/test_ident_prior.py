"""Declared priors: output error maximises the posterior (MAP), against the closed form of a
model linear in its parameter; a prior fixes what the data leave open; bad priors refused."""

from __future__ import annotations

import numpy as np
import pytest
from _cli import assert_one_line_error
from _gain import gain_data, gain_model
from typer.testing import CliRunner

from acid.errors import ConfigError
from acid.ident.fit import fit_model
from acid.models.declaration import DeclarationError
from acid_cli.main import app


def _model(prior=None, split: bool = False):
    return gain_model(prior, split)


def _data():
    return gain_data()


def _closed_form(ds, w, mean, sd) -> float:
    u, y = ds["u"], ds["y"]
    return float((u @ y + mean * w**2 / sd**2) / (u @ u + w**2 / sd**2))


@pytest.mark.parametrize("solver", ["dense", "ms"])
def test_map_equals_the_closed_form_of_a_linear_gain(solver):
    ds = _data()
    r = fit_model(_model(prior=(1.5, 0.01)), ds, "oe", oe_solver=solver)
    k = r.estimates[0].value
    w = r.output_error["weights"]["y"]
    assert k == pytest.approx(_closed_form(ds, w, 1.5, 0.01), rel=1e-6)
    assert 1.5 < k < 1.99                     # pulled from the data's 2.0 towards 1.5
    free = fit_model(_model(), ds, "oe").estimates[0].value
    assert free == pytest.approx(_closed_form(ds, 1.0, 0.0, np.inf), rel=1e-6)
    assert any("prior 1.5 +- 0.01" in n for n in r.notes)


def test_a_prior_fixes_what_the_data_leave_open():
    """y = (a + b) u: the data fix a + b only; a prior on b puts b at its mean and a + b
    where the data say."""
    r = fit_model(_model(prior=(0.7, 0.05), split=True), _data(), "oe")
    v = {e.name: e.value for e in r.estimates}
    assert v["b"] == pytest.approx(0.7, abs=1e-3)
    assert v["a"] + v["b"] == pytest.approx(2.0, abs=0.02)
    assert all(np.isfinite(e.stderr) for e in r.estimates)   # both identified, with the prior


@pytest.mark.parametrize("prior", [(1.0, 0.0), (1.0, -1.0), (float("nan"), 1.0), (1.0,),
                                   "wide"])
def test_a_bad_prior_is_refused_naming_the_parameter(prior):
    with pytest.raises(DeclarationError, match="parameter 'k': prior"):
        _model(prior=prior)


def test_least_squares_refuses_priors_it_cannot_honour():
    with pytest.raises(ConfigError, match="priors on k"):
        fit_model(_model(prior=(1.5, 0.1)), _data(), "ls")


def test_the_cli_prior_option(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("from acid.models import Model, Parameter, Signal, State\n"
                 "model = Model('gain', states=[State('x', '1', measured=False, initial=0.0)],"
                 " inputs=[Signal('u', '1')], outputs=[Signal('y', '1')],"
                 " parameters=[Parameter('k', '1', 1.0, -10.0, 10.0)], Ts=1.0,"
                 " ode=lambda s: {'x': -s.x}, output=lambda s: {'y': s.k * s.u})\n")
    _data().to_hdf5(tmp_path / "d.h5")
    runner = CliRunner()
    args = ["fit", str(tmp_path / "d.h5"), "--model", str(f), "--method", "oe",
            "--estimation-fraction", "1", "--out", str(tmp_path / "p.json")]
    ok = runner.invoke(app, [*args, "--prior", "k=1.5,0.01"])
    assert ok.exit_code == 0, ok.output
    assert "prior 1.5 +- 0.01" in " ".join(ok.output.split())
    bad = runner.invoke(app, [*args, "--prior", "k=1.5"])
    assert bad.exit_code == 2
    assert_one_line_error(bad, "--prior", "k=1.5")
    unknown = runner.invoke(app, [*args, "--prior", "q=1,1"])
    assert unknown.exit_code == 2
    assert_one_line_error(unknown, "q")


def test_prediction_error_takes_the_prior_too():
    r = fit_model(_model(prior=(0.7, 0.05), split=True), _data(), "pem", max_nfev=200)
    v = {e.name: e.value for e in r.estimates}
    assert v["b"] == pytest.approx(0.7, abs=1e-3)
    assert v["a"] + v["b"] == pytest.approx(2.0, abs=0.02)
    assert any("prior 0.7 +- 0.05" in n for n in r.notes)
