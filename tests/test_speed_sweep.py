"""The speed-sensitivity study (PLANT.md behaviour 1, paper Table I) and its figure."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from matplotlib.figure import Figure

from acid.errors import ConfigError
from acid.plant.config import PlantConfig
from acid.plant.sweep import PAPER_TABLE_I, SweepResult, speed_sweep
from acid.report.plant import sweep_figure


@pytest.fixture(scope="module")
def sweep() -> SweepResult:
    return speed_sweep()


def test_b1_energy_falls_with_speed_with_shrinking_decrements(sweep):
    E = sweep.energy_MJ
    dec = -np.diff(E)
    assert np.all(dec > 0), E
    assert np.all(np.diff(dec) < 0), dec
    assert 0.75 <= sweep.ratio_last_first <= 0.85
    assert E[0] == pytest.approx(1.33, rel=0.10)


def test_matches_paper_table_i_row(sweep):
    """The frozen calibration lands within 3 % of every Table I entry."""
    np.testing.assert_allclose(sweep.energy_MJ, PAPER_TABLE_I["energy_MJ"], rtol=0.03)
    np.testing.assert_allclose(sweep.energy_MJ_per_km[1:], PAPER_TABLE_I["energy_MJ_per_km"][1:],
                               rtol=0.03)
    assert math.isnan(sweep.energy_MJ_per_km[0])


def test_energy_parts_and_traces(sweep):
    np.testing.assert_allclose(sweep.energy_MJ, sweep.energy_comp_MJ + sweep.energy_bl_MJ)
    assert np.all(sweep.energy_fan_MJ == pytest.approx(PlantConfig().P_fan * 600 / 1e6))
    assert sweep.traces["T_cab"].shape == (6, 120) and sweep.time[-1] == 595.0
    E = sweep.traces["P_comp"].sum(axis=1) * 5 / 1e6
    np.testing.assert_allclose(E, sweep.energy_comp_MJ)


def test_json_dict_uses_null_for_nan(sweep):
    d = json.loads(json.dumps(sweep.to_json_dict(), allow_nan=False))
    assert d["energy_MJ_per_km"][0] is None and d["paper"]["energy_MJ_per_km"][0] is None
    assert d["speeds_mps"] == [0.0, 5.0, 10.0, 15.0, 20.0, 25.0]
    assert d["paper"]["energy_MJ"] == list(PAPER_TABLE_I["energy_MJ"])


def test_sweep_options_and_refusals():
    res = speed_sweep(speeds=(0, 20), duration=100.0)
    assert res.energy_MJ.shape == (2,) and res.duration_s == 100.0
    seen = []
    speed_sweep(speeds=(0, 10), duration=10.0, progress=lambda d, t: seen.append((d, t)))
    assert seen == [(1, 2), (2, 2)]
    with pytest.raises(ConfigError, match="non-negative"):
        speed_sweep(speeds=(-5,))
    with pytest.raises(ConfigError, match="shorter than one sample"):
        speed_sweep(duration=1.0)


def test_figure_has_units_on_every_axis(sweep):
    fig = sweep_figure(sweep)
    assert isinstance(fig, Figure)
    for ax in fig.axes:
        assert "(" in ax.get_ylabel() and "(" in ax.get_xlabel(), ax.get_ylabel()
