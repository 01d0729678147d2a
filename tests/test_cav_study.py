"""The drive-cycle CAV study (acid.mpc.cav_study) and ``acid cav-study``."""

from __future__ import annotations

import json

import numpy as np
import pytest
from _cli import assert_one_line_error
from typer.testing import CliRunner

from acid.errors import ConfigError
from acid.mpc.cav_study import (
    CASES,
    StudyConfig,
    _tune,
    cav_study,
    end_state_correction,
    heat_content,
)
from acid.mpc.speed_model import SpeedEfficiency
from acid.params import paper
from acid_cli.main import app

runner = CliRunner()
EFF = SpeedEfficiency(eta0=4.9, eta1=0.03)


@pytest.fixture(scope="module")
def study():
    cfg = StudyConfig(cycle="nycc", warmup_s=300.0, tail_s=60.0, speed_blind=False)
    return cav_study(paper(), cfg, efficiency=EFF)


def test_energy_bookkeeping_is_sum_of_power_times_Ts(study):
    for key in CASES:
        c = study.main.cases[key]
        run = c.run
        assert run.n_steps == study.v_step.size
        assert c.energy_J == pytest.approx(float(np.sum(run.P_comp + run.P_bl)) * run.Ts)
        assert np.all(np.isfinite(run.P_comp)) and not np.any(run.fallback)


def test_end_state_correction_is_consistent(study):
    st = study.main
    A = st.cases["A"]
    assert A.correction_J == 0.0
    assert st.cop_ref == pytest.approx(A.q_evap_J / (np.sum(A.run.P_comp) * A.run.Ts))
    for key in CASES:
        c = st.cases[key]
        assert c.heat_content_J == pytest.approx(heat_content(c.end_state, st.capacities))
        expect = end_state_correction(c.heat_content_J, A.heat_content_J, st.cop_ref)
        assert c.correction_J == pytest.approx(expect)
        assert c.corrected_energy_J == pytest.approx(c.energy_J + c.correction_J)
        assert c.end_state["T_cab"] == pytest.approx(c.run.T_cab[-1])
        assert np.isfinite(c.tail_energy_J) and c.tail_energy_J > 0
    s = st.savings_pct("B")
    B = st.cases["B"]
    assert s["raw"] == pytest.approx(100 * (A.energy_J - B.energy_J) / A.energy_J)
    assert s["corrected"] == pytest.approx(
        100 * (A.corrected_energy_J - B.corrected_energy_J) / A.corrected_energy_J)
    # warmer at the end means a positive correction (heat still to remove), and vice versa
    assert np.sign(B.correction_J) == np.sign(B.heat_content_J - A.heat_content_J)


def test_same_start_and_equal_mean_cabin_temperature(study):
    st = study.main
    for key in CASES:
        run = st.cases[key].run
        assert run.T_cab[0] == pytest.approx(st.start_state["T_cab"])
        assert run.T_int[0] == pytest.approx(st.start_state["T_int"])
    for key in ("A", "C"):
        c = st.cases[key]
        assert abs(c.mean_T_cab - st.target_mean_K) <= 0.05
        assert c.upper_bound_K is not None and c.tuning
    d = study.to_json_dict()
    json.dumps(d)
    assert set(d["hifi"]["cases"]) == set(CASES)


def test_tuning_hits_the_target_of_a_monotone_map():
    b, payload, hist = _tune(lambda b: (0.9 * b + 30.0, b), 300.0, 290.0, 310.0, 1e-4, 10)
    assert 0.9 * b + 30.0 == pytest.approx(300.0, abs=1e-4)
    assert payload == b and len(hist) <= 4


def test_study_config_rejects_bad_options():
    with pytest.raises(ConfigError):
        StudyConfig(horizon=1)
    with pytest.raises(ConfigError):
        StudyConfig(T_low=300.0, T_high=299.0)


def test_cli_writes_json_and_png(tmp_path):
    out, js = tmp_path / "figs", tmp_path / "cav.json"
    res = runner.invoke(app, ["cav-study", "--cycle", "nycc", "--warmup", "120", "--tail", "0",
                              "--no-speed-blind", "--identify-duration", "1800",
                              "--out", str(out), "--json", str(js)])
    assert res.exit_code == 0, res.output
    d = json.loads(js.read_text())
    assert d["command"] == "cav-study" and d["config"]["cycle"] == "nycc"
    assert set(d["hifi"]["cases"]) == {"A", "B", "C"}
    assert d["efficiency"]["eta1"] > 0
    assert (out / "cav_nycc.png").stat().st_size > 1000


def test_cli_rejects_an_unknown_cycle_in_one_line():
    res = runner.invoke(app, ["cav-study", "--cycle", "marsrover", "--no-figures"])
    assert res.exit_code == 2
    assert_one_line_error(res, "--cycle", "marsrover", "udds")


def test_tail_corrected_saving_charges_the_extra_tail_energy(study):
    st = study.main
    A, B = st.cases["A"], st.cases["B"]
    s = st.savings_pct("B")
    E_B = B.energy_J + B.tail_energy_J - A.tail_energy_J
    assert s["tail_corrected"] == pytest.approx(100 * (A.energy_J - E_B) / A.energy_J)
    assert s["tail_correction_MJ"] == pytest.approx((B.tail_energy_J - A.tail_energy_J) / 1e6)
