"""A fit result is a first-class object: a table (``summary()``, ``repr``) and a DataFrame."""

from __future__ import annotations

import pytest
from _gain import gain_data, gain_model

from acid.ident.fit import fit_model


def test_the_result_reads_as_a_table_and_a_frame():
    model, ds = gain_model(), gain_data(n=300)
    r = fit_model(model, ds, "oe")
    df = r.to_frame()
    assert list(df["name"]) == ["k"] and df["value"].iloc[0] == pytest.approx(2.0, abs=0.03)
    text = repr(r)
    assert "gain: oe fit of 300 samples" in text and "k" in text and "error RMS: y" in text
    assert r.summary() in text
