"""acid.report.energy_bars: energy charts as differences against the best simple baseline."""

from __future__ import annotations

import math
from types import SimpleNamespace

import matplotlib
import pandas as pd
import pytest

from acid.report.energy_bars import (
    EnergyBars,
    cav_energy_bars,
    difference_figure,
    sweep_energy_bars,
)

matplotlib.use("Agg")

BARS = EnergyBars(groups=("udds", "sc03"), baseline={"udds": "F", "sc03": "P"},
                  energy_MJ={"udds": {"A": 2.10, "F": 2.00, "E": 1.90},
                             "sc03": {"A": 1.00, "P": 0.95, "E": 0.97}},
                  flagged={"sc03": ("E",)}, title="t", flag_meaning="outside the RH band",
                  labels={"udds": "UDDS", "sc03": "SC03"})


def test_differences_are_percent_of_the_baseline():
    assert BARS.difference_pct("udds", "E") == pytest.approx(-5.0)     # 1.90 vs 2.00
    assert BARS.difference_pct("udds", "A") == pytest.approx(5.0)
    assert BARS.difference_pct("sc03", "E") == pytest.approx(100 * 0.02 / 0.95)
    assert BARS.difference_pct("udds", "F") == 0.0
    assert math.isnan(BARS.difference_pct("sc03", "F"))                # F did not run there


def test_the_figure_draws_the_differences_not_the_energies():
    fig = difference_figure(BARS, ("A", "P", "F", "E"))
    ax = fig.axes[0]
    heights = {}
    for container in ax.containers:
        key = container.get_label()
        heights[key] = [b.get_height() for b in container if b.get_visible()]
    # each bar is the difference in %, the baseline of a group draws no bar there
    assert heights["E"] == pytest.approx([-5.0, 100 * 0.02 / 0.95])
    assert heights["A"] == pytest.approx([5.0, 100 * 0.05 / 0.95])
    assert "F" not in heights and "P" not in heights   # baselines only: no bars at all
    # a 5 % difference spans a readable share of the axis (a zero-based energy axis: 5 %)
    lo, hi = ax.get_ylim()
    assert 5.0 / (hi - lo) > 0.3
    ticks = [t.get_text() for t in ax.get_xticklabels()]
    assert ticks == ["UDDS\nF = 2 MJ", "SC03\nP = 0.95 MJ"]
    # value labels are horizontal and the legend sits outside the axes, clear of the bars
    assert all(t.get_rotation() == 0 for t in ax.texts) and len(ax.texts) == 4
    legend = ax.get_legend()
    assert legend.get_bbox_to_anchor().transformed(ax.transAxes.inverted()).x0 > 1.0
    assert "outside the RH band" in [t.get_text() for t in legend.get_texts()]
    hatched = [b for c in ax.containers if c.get_label() == "E" for b in c if b.get_hatch()]
    assert len(hatched) == 1


def _cycle(energies_MJ, outside=()):
    results = {k: SimpleNamespace(tail_corrected_J=e * 1e6) for k, e in energies_MJ.items()}
    return SimpleNamespace(results=results, in_rh_band=lambda k: k not in outside)


def test_the_cav_study_baseline_is_the_best_simple_controller_of_each_cycle():
    result = SimpleNamespace(cycles={
        "udds": _cycle({"A": 2.1, "P": 2.05, "F": 2.0, "E": 1.9, "plan": 1.85}),
        "hwfet": _cycle({"A": 1.2, "P": 1.1, "F": 1.15, "E": 1.0}, outside=("E",))})
    bars = cav_energy_bars(result)
    assert bars.baseline == {"udds": "F", "hwfet": "P"}
    assert bars.energy_MJ["udds"]["plan"] == pytest.approx(1.85)
    assert bars.flagged == {"udds": (), "hwfet": ("E",)}
    assert bars.labels["udds"] == "UDDS"
    with pytest.raises(ValueError, match="none of the baselines"):
        cav_energy_bars(SimpleNamespace(cycles={"x": _cycle({"E": 1.0})}))


def test_a_sweep_compares_each_cycle_mean_with_its_baseline():
    df = pd.DataFrame({
        "status": ["ok"] * 6 + ["error"],
        "cycle": ["10 m/s"] * 4 + ["5 m/s"] * 3,
        "controller": ["nominal", "icm", "nominal", "icm", "nominal", "icm", "icm"],
        "baseline": ["nominal"] * 7,
        "energy_MJ": [1.0, 0.9, 1.2, 1.0, 2.0, 1.9, 99.0]})
    bars = sweep_energy_bars(df, "nominal")
    assert bars.groups == ("10 m/s", "5 m/s")
    assert bars.difference_pct("10 m/s", "icm") == pytest.approx(100 * (0.95 - 1.1) / 1.1)
    assert bars.difference_pct("5 m/s", "icm") == pytest.approx(-5.0)   # the error row is out
