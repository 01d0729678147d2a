"""A long fit reports its progress: evaluations and loss, throttled, for every method that
iterates (output error, prediction error)."""

from __future__ import annotations

import numpy as np
import pytest

import acid
from acid.ident import fit as fit_mod
from acid.ident.fit import fit_model
from acid.models import Model, Parameter, Signal, State


def _gain() -> tuple[Model, acid.Dataset]:
    model = Model("gain", states=[State("x", "1", measured=False, initial=0.0)],
                  inputs=[Signal("u", "1")], outputs=[Signal("y", "1")],
                  parameters=[Parameter("k", "1", 1.0, -10.0, 10.0)], Ts=1.0,
                  ode=lambda s: {"x": -s.x}, output=lambda s: {"y": s.k * s.u})
    rng = np.random.default_rng(0)
    u = rng.normal(size=300)
    ds = acid.Dataset(time=np.arange(300.0), channels={"u": u, "y": 2 * u + 0.1 * rng.normal(
        size=300)}, units={"u": "1", "y": "1"}, Ts=1.0)
    return model, ds


@pytest.mark.parametrize("method, word", [("oe", "loss"), ("pem", "log likelihood")])
def test_fit_reports_evaluations_and_loss(monkeypatch, method, word):
    monkeypatch.setattr(fit_mod, "PROGRESS_EVERY_S", 0.0)      # every evaluation
    seen = []
    model, ds = _gain()
    fit_model(model, ds, method, progress=lambda d, t=None, label=None: seen.append((d, label)))
    assert len(seen) >= 2
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)   # the count only moves up
    assert all("evaluation" in lab and word in lab for _, lab in seen)


def test_progress_is_throttled(monkeypatch):
    seen = []
    model, ds = _gain()
    fit_model(model, ds, "oe", progress=lambda d, t=None, label=None: seen.append(d))
    assert len(seen) == 1          # a sub-second fit: the first report only
