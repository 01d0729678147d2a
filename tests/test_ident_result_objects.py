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


def test_the_nmse_is_the_simulation_mse_over_the_channel_variance():
    import numpy as np

    model, ds = gain_model(), gain_data(n=300, noise=0.5)
    r = fit_model(model, ds, "oe")
    u, y = np.asarray(ds["u"]), np.asarray(ds["y"])
    expected = np.mean((y - r.value("k") * u) ** 2) / np.var(y)   # a static gain: exact
    assert r.nmse["y"] == pytest.approx(expected, rel=1e-6)
    assert 0.03 < r.nmse["y"] < 0.1                     # noise 0.5 on a signal of sd 2
    assert "NMSE (simulation, MSE / variance): y" in r.summary()
    assert r.to_json_dict()["nmse_simulation"]["y"] == pytest.approx(expected, rel=1e-6)


def test_an_overflow_in_the_hac_covariance_is_a_note_not_a_terminal_line():
    import warnings

    import numpy as np

    from acid.ident import hac

    model, ds = gain_model(), gain_data(n=300)

    def overflowing(*a, **kw):   # a fit whose scores overflow float64 in the HAC meat
        hac.hac_meat(np.full((4, 2), 1e200), np.zeros(4, int), 2)
        warnings.warn("kept", UserWarning, stacklevel=1)
        return fit_model(*a, **kw)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = hac.warnings_as_note(overflowing)(model, ds, "oe")
    assert [str(w.message) for w in caught] == ["kept"]      # others pass through
    assert any("overflow" in n and "standard errors" in n for n in r.notes)


def test_the_result_round_trips_through_json():
    import json

    import numpy as np

    from acid.ident.result import DeclaredFitResult

    model = gain_model()
    r = fit_model(model, gain_data(n=200), "oe")
    back = DeclaredFitResult.from_json_dict(json.loads(json.dumps(r.to_json_dict())))
    assert back == r and back.value("k") == r.value("k")
    np.testing.assert_array_equal(back.covariance, r.covariance)
    assert back.estimates == r.estimates and back.summary() == r.summary()
    other = fit_model(model, gain_data(n=200, noise=0.3), "oe")
    assert other != r
