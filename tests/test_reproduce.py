"""``acid reproduce --quick``: report, every figure, finite physical numbers, the cache."""

from __future__ import annotations

import json
import math
import re

import pytest
from typer.testing import CliRunner

from acid_cli.main import app

pytestmark = pytest.mark.slow

FIGURES = ("stages/sweep/fig3_speed_sweep.png", "stages/validate/fig5_prediction.png",
           "stages/validate/fig6_errors.png", "stages/mpc/fig7_model.png",
           "stages/mpc/fig8_plant.png", "stages/mpc/fig9_cav_bound.png",
           "stages/mpc/fig10_cav_comparison.png", "stages/cav/cav_nycc.png",
           "stages/cav/energy.png", "stages/econ/fig_econ_errors.png")


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    res = CliRunner().invoke(app, ["reproduce", "--quick", "--out", str(out), "--jobs", "1"])
    assert res.exit_code == 0, res.output
    return out, res


def _numbers(obj):
    if isinstance(obj, dict):
        for v in obj.values():
            yield from _numbers(v)
    elif isinstance(obj, list):
        for v in obj:
            yield from _numbers(v)
    elif isinstance(obj, float):
        yield obj


def test_report_and_every_figure_exist(quick_run):
    out, _ = quick_run
    html = (out / "report.html").read_text()
    for rel in FIGURES:
        assert (out / rel).stat().st_size > 10_000, rel
    # every figure is embedded, so the page stands alone
    assert len(re.findall(r'<img src="data:image/png;base64,', html)) >= len(FIGURES)
    assert "Table I" in html and "CAV case" in html


def test_summary_numbers_are_finite_and_physical(quick_run):
    out, _ = quick_run
    s = json.loads((out / "summary.json").read_text())
    assert all(math.isfinite(x) for x in _numbers(s))
    st = s["stages"]
    E = st["sweep"]["summary"]["energy_MJ"]
    assert all(0.2 < e < 3.0 for e in E) and all(b < a for a, b in zip(E, E[1:], strict=False))
    p = st["fit"]["summary"]
    g = p["gamma"]
    assert 0 < g[0] < 1 and 0 < g[1] < 1 and abs(g[3] + g[4]) < 1
    for ch in ("T_cab", "T_evap", "T_ain"):
        m = st["validate"]["summary"]["channels"][ch]
        assert 0 <= m["median_abs"] <= m["max_abs"] < 20.0
    mpc = st["mpc"]["summary"]
    assert 0 <= mpc["scenarios"]["model"]["max_violation_K"] < 0.01
    cav = mpc["scenarios"]["cav"]
    assert 0 < cav["case1_energy_MJ"] < 1 and 0 < cav["case2_energy_MJ"] < 1
    assert s["agreement"]["agree"] > 0
    energy = st["cav"]["summary"]["cycles"]["nycc"]["controllers"]
    assert set(energy) == {"A", "B", "D", "E", "bound"}
    assert all(0 < c["energy_MJ"] < 1 for c in energy.values())
    assert any(r["section"] == "Where the energy is" and r["quantity"].startswith("conclusion")
               for r in s["comparison"])


def test_second_run_reuses_every_stage(quick_run):
    out, _ = quick_run
    res = CliRunner().invoke(app, ["reproduce", "--quick", "--out", str(out), "--jobs", "1"])
    assert res.exit_code == 0, res.output
    s = json.loads((out / "summary.json").read_text())
    assert all(v["cached"] for v in s["stages"].values())
