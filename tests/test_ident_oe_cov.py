"""The output error's covariance in time linear in the windows (``acid.ident.oe``): the
parameters' bread columns by eliminating each window's initial states equal the whole
pseudo-inverse's, and the degenerate cases fall back to it."""

from __future__ import annotations

import numpy as np

from acid.ident import oe


def _jacobian(rng, nth=3, nw=6, nxf=2, rows=25):
    """[theta | x0 of each window] with each window's rows reaching only its own x0."""
    J = np.zeros((nw * rows + 1, nth + nw * nxf))
    J[:, :nth] = rng.normal(size=(nw * rows + 1, nth))
    for w in range(nw):
        J[w * rows:(w + 1) * rows, nth + w * nxf:nth + (w + 1) * nxf] = rng.normal(
            size=(rows, nxf))
    J[-1, nxf:] = 0.0                       # a prior's row: on theta only
    win = np.repeat(np.arange(nw), rows)
    return J, win


def test_bread_by_window_elimination_equals_the_whole_pseudo_inverse(rng):
    J, win = _jacobian(rng)
    fast = oe._bread_columns(J, 3, win, 6, 2)
    full = oe._bread_full(J, 3)
    assert fast.shape == (J.shape[1], 3)
    np.testing.assert_allclose(fast, full, rtol=1e-9, atol=1e-12)
    # and it is the inverse of the normal matrix's columns
    np.testing.assert_allclose(fast, np.linalg.inv(J.T @ J)[:, :3], rtol=1e-8, atol=1e-12)


def test_a_window_whose_initial_state_the_data_do_not_see_falls_back_to_the_svd(rng):
    J, win = _jacobian(rng)
    J[:, 3] = 0.0                           # window 0's first state reaches nothing
    fast = oe._bread_columns(J, 3, win, 6, 2)
    np.testing.assert_allclose(fast, oe._bread_full(J, 3), rtol=1e-9, atol=1e-12)
    assert np.all(np.isfinite(fast))
