"""PLANT.md behaviour 16: the paper's 2-state model, fitted to plant data, predicts 1500 s.

Two hours of APRBS excitation of the high-fidelity plant for estimation, two more hours
(another seed) held out; 60 open-loop predictions of 300 steps with T_int and T_shell held
at their initial values, as in the paper. Criterion: median |error| < 1.5 K and 90th
percentile < 5 K for T_cab, T_evap and T_ain.
"""

from __future__ import annotations

import numpy as np
import pytest

from acid.excite import ExcitationSpec, excite
from acid.ident.fit import fit_model
from acid.ident.validate import validate
from acid.models.params import fitted
from acid.plant import make_plant

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def plant_records():
    est = excite(make_plant("hifi"), ExcitationSpec(duration=7200.0, seed=1))
    held = excite(make_plant("hifi"), ExcitationSpec(duration=7200.0, seed=2))
    return est, held


@pytest.mark.parametrize("method", ["ls", "oe"])
def test_fitted_model_predicts_1500_s_within_the_bands(plant_records, method):
    est, held = plant_records
    res = validate(held, fitted(fit_model("paper", est, method)), starts=60, horizon=300)
    for ch in ("T_cab", "T_evap", "T_ain"):
        m = res.metrics[ch]
        assert m["median_abs"] < 1.5, f"{method} {ch}: median |error| {m['median_abs']:.2f} K"
        assert m["p90_abs"] < 5.0, f"{method} {ch}: p90 |error| {m['p90_abs']:.2f} K"


def test_identified_model_is_physical(plant_records):
    """Signs the physics demands: conductances positive, a stable evaporator pole."""
    p = fitted(fit_model("paper", plant_records[0], "oe"))
    g = np.array(p.gamma)
    assert (g[[0, 1, 2, 5]] > 0).all(), p.gamma
    assert abs(g[3] + g[4]) < 1.0, "evaporator pole gamma4 + gamma5 must be stable"
