"""The residual ARX on a declared model's open-loop residual (acid.ident.errmodel)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from acid.errors import DataError
from acid.ident.errmodel import corrected_errors, fit_residual_model


def _windows(rng, S=40, H=60):
    """A grey box that misses a first-order lag on its input: r(i) = 0.9 r(i-1) + 0.4 u(i)."""
    u = rng.normal(size=(S, H + 1, 1)).cumsum(axis=1) * 0.1
    r = np.zeros((S, H + 1))
    r[:, 0] = rng.normal(size=S)
    for i in range(1, H + 1):
        r[:, i] = 0.9 * r[:, i - 1] + 0.4 * u[:, i, 0]
    pred = rng.normal(size=(S, H + 1)) + 300.0
    meas = pred + r
    return SimpleNamespace(channels=("T_cab",), units=("K",), measured=meas[..., None],
                           predicted=pred[..., None], inputs=u,
                           errors={"T_cab": (pred - meas)[:, 1:]})


def test_residual_arx_recovers_what_the_grey_box_misses():
    rng = np.random.default_rng(3)
    em = fit_residual_model(_windows(rng), "T_cab")
    new = _windows(rng)                      # other windows than the fit's
    e0 = np.sqrt(np.mean(new.errors["T_cab"] ** 2))
    e1 = np.sqrt(np.mean(corrected_errors(new, em) ** 2))
    assert em.arx.stable
    assert e1 < 0.05 * e0, (e0, e1)


def test_too_few_windows_is_one_error():
    w = _windows(np.random.default_rng(0), S=2)
    with pytest.raises(DataError, match="at least 3"):
        fit_residual_model(w, "T_cab")



def test_cli_error_model_refusals(tmp_path):
    from typer.testing import CliRunner

    from acid_cli.main import app

    d = tmp_path / "d.h5"
    d.touch()
    r = CliRunner().invoke(app, ["validate", str(d), "--model", "car_cabin", "--error-model",
                                 "armax", "--error-model-data", str(d)])
    assert r.exit_code == 2 and "--error-model must be 'arx'" in r.output
    r = CliRunner().invoke(app, ["validate", str(d), "--model", "car_cabin",
                                 "--error-model", "arx"])
    assert r.exit_code == 2 and "needs --error-model-data" in r.output
