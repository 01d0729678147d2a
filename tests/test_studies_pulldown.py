"""acid.studies.pulldown: the closed loop on a pull-down (the engine's F, the econ NMPC with
its envelope count) and ``acid pulldown``'s options."""

from __future__ import annotations

import math

import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.studies import pulldown as study
from acid.studies.compare import RunSettings, periodic_run
from acid.units import C2K

#: a short cycle (SC03, 600 s) from a 40 degC soak at 30 degC ambient
SHORT = study.PulldownSettings(cycle="sc03", horizon_s=20.0)


def test_fixed_coil_is_the_engines_run_with_its_trace():
    r = study.fixed_coil(C2K(7.0), SHORT)
    sc = study.scenario(SHORT)
    assert sc.start()["T_cab"] == C2K(40.0) and sc.T_amb == C2K(30.0)
    engine = periodic_run(sc, "F", C2K(7.0), RunSettings(max_passes=1), start=sc.start())
    assert r.energy_J == engine.first_pass_J
    assert r.discomfort_Kmin == pytest.approx(engine.discomfort_Kmin, rel=1e-12)
    # from 40 degC the cabin spends minutes above 25 degC, then reaches it
    assert 60.0 < r.time_to_reach_s < 600.0 and r.above_Kmin > 5.0
    assert r.above_Kmin <= r.discomfort_Kmin + 1e-12


def test_at_equal_comfort_interpolates_inside_es_span_only():
    def run(name, d, E):
        return study.LoopResult(name, E, d, d, 100.0, C2K(24.0))

    front = [run("F a", 5.0, 100.0), run("F b", 8.0, 90.0), run("F c", 20.0, 80.0)]
    e = [run("E 1", 4.0, 110.0), run("E 2", 12.0, 70.0)]
    out = study.at_equal_comfort(front, e)
    assert [q["F"] for q in out] == ["F a", "F b"]       # 20 K min: outside E's span
    assert out[0]["E_J"] == pytest.approx(105.0) and out[1]["E_J"] == pytest.approx(90.0)
    assert out[0]["saving_pct"] == pytest.approx(-5.0) and out[1]["saving_pct"] == 0.0


@pytest.mark.slow
def test_econ_run_counts_steps_outside_the_models_envelope(econ_truth):
    r = study.econ_run(econ_truth, 300.0, SHORT)
    assert r.envelope["n"] == 120                  # every applied step checked
    # the known model's data end at 17 degC evaporator: the soaked coil (40 degC) is out
    assert r.envelope["n_outside"] >= 1 and r.envelope["worst_channel"] == "T_evap"
    assert r.envelope_line.startswith(f"{r.envelope['n_outside']} of 120 steps outside")
    assert math.isfinite(r.energy_J) and r.energy_J > 0


def test_cli_pulldown_refuses_a_soak_below_the_ambient(tmp_path):
    from acid_cli.main import app

    result = CliRunner().invoke(app, ["pulldown", "--t-amb", "35", "--soak", "30"])
    assert_one_line_error(result, "--soak")
    ok = CliRunner().invoke(app, ["pulldown", "--help"])
    assert ok.exit_code == 0 and "envelope" in ok.output and "--set" in ok.output
