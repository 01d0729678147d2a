"""A long fit reports its progress: evaluations and loss, throttled, for every method that
iterates (output error, prediction error)."""

from __future__ import annotations

import pytest
from _gain import gain_data, gain_model

from acid.ident import fit as fit_mod
from acid.ident.fit import fit_model


def _gain():
    return gain_model(), gain_data(n=300)


@pytest.mark.parametrize("method, word", [("oe", "objective"), ("pem", "log likelihood")])
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

