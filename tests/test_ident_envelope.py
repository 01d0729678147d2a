"""acid.ident.envelope: the ranges of an econ model's identification data, and the steps
outside them (counted by the economic NMPC)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from acid.ident.envelope import CHANNELS, Envelope, Excursion, envelope_ranges
from acid.units import C2K

RANGES = {"Q_e": (0.0, 3200.0), "T_evap": (C2K(2.0), C2K(11.0)),
          "T_cab": (C2K(22.0), C2K(38.0)), "W_bl": (0.05, 0.15), "T_amb": (C2K(25.0),
                                                                          C2K(40.0))}


def test_envelope_flags_a_step_outside_and_measures_the_worst():
    env = Envelope(RANGES)
    Q = np.array([1000.0, 3000.0, 6100.0, 3250.0])        # 3250 W: inside the 2 % margin
    T_ev = np.array([C2K(5.0), C2K(24.0), C2K(8.0), C2K(10.0)])
    flags = env.flags(Q_e=Q, T_evap=T_ev)
    assert flags.tolist() == [False, True, True, False]
    ex = env.check(Q_e=Q, T_evap=T_ev)
    assert (ex.n, ex.n_outside) == (4, 2)
    # 24 degC is (24 - 11.18) / 9 = 1.42 ranges out; 6.1 kW (6100 - 3264) / 3200 = 0.89
    assert ex.channel == "T_evap" and ex.value == pytest.approx(C2K(24.0))
    assert ex.relative == pytest.approx((24.0 - 11.0 - 0.18) / 9.0)
    assert ex.by_channel == {"Q_e": 1, "T_evap": 1}
    line = ex.summary(env)
    assert line.startswith("2 of 4 steps outside the model's envelope; worst T_evap 24 degC")
    assert "data 2 degC to 11 degC" in line
    inside = env.check(Q_e=[100.0], T_cab=[C2K(25.0)], W_bl=[0.1])
    assert inside.n_outside == 0 and inside.summary() == \
        "0 of 1 steps outside the model's envelope"


def test_counts_merge_step_by_step():
    env, total = Envelope(RANGES), Excursion()
    for q in (1000.0, 5000.0, 4000.0):
        total = total.merged(env.check(Q_e=[q], W_bl=[0.2 if q == 4000.0 else 0.1]))
    assert (total.n, total.n_outside) == (3, 2)
    assert total.channel == "Q_e" and total.value == 5000.0
    assert total.by_channel == {"Q_e": 2, "W_bl": 1}
    assert json.loads(json.dumps(total.to_dict()))["n_outside"] == 2


def test_ranges_and_unknown_channel():
    r = envelope_ranges(Q_e=[3.0, np.nan, -1.0], W_bl=[0.1])
    assert r == {"Q_e": (-1.0, 3.0), "W_bl": (0.1, 0.1)}
    assert {n for n, _ in CHANNELS} == set(RANGES)
    with pytest.raises(KeyError, match="P_comp"):
        envelope_ranges(P_comp=[1.0])
    assert "Q_e 0 kW to 3.2 kW" in Envelope(RANGES).describe()


def test_the_model_carries_its_envelope_through_its_file(econ_truth, tmp_path):
    from acid.models.econ_params import EconParams

    assert Envelope.of(econ_truth).ranges["Q_e"] == (-500.0, 6000.0)   # old file: the domain
    assert "T_cab" not in Envelope.of(econ_truth).ranges
    pm = econ_truth.power_map
    p = econ_truth.replace(power_map=type(pm)(coef=pm.coef, domain=pm.domain,
                                              envelope=RANGES))
    p.to_json(tmp_path / "e.json")
    back = EconParams.from_json(tmp_path / "e.json")
    assert Envelope.of(back).ranges == Envelope(RANGES).ranges


def test_econ_nmpc_counts_its_steps_outside_the_envelope(econ_truth):
    from acid.control.econ.nmpc import EconNMPC, EconNMPCConfig

    pm = econ_truth.power_map
    narrow = econ_truth.replace(power_map=type(pm)(
        coef=pm.coef, domain=pm.domain, envelope={**RANGES, "T_cab": (C2K(22.0), C2K(26.0))}))
    cfg = EconNMPCConfig(intervals=(5.0,) * 6, T_cab_min=C2K(22.0), T_cab_max=C2K(24.0),
                         compiled=False)
    hot = np.array([C2K(35.0), C2K(38.0), C2K(45.0), C2K(20.0), 0.010])
    mpc = EconNMPC(narrow, cfg)
    mpc.make_step(hot, 10.0, C2K(30.0))
    ex = mpc.envelope_steps
    assert (ex.n, ex.n_outside) == (1, 1) and ex.channel in ("T_cab", "T_evap", "Q_e")
    assert ex.by_channel["T_cab"] == 1
    mpc.reset()
    assert mpc.envelope_steps.n == 0
    cool = np.array([C2K(24.0), C2K(27.0), C2K(35.0), C2K(8.0), 0.008])
    mpc.make_step(cool, 10.0, C2K(30.0))
    assert mpc.envelope_steps.by_channel.get("T_cab", 0) == 0


@pytest.mark.slow
def test_identify_stores_the_data_ranges(econ_hifi_fit, econ_hifi_dataset):
    env = Envelope.of(econ_hifi_fit.params)
    assert set(env.ranges) == {n for n, _ in CHANNELS}
    est = econ_hifi_dataset.split(0.75)[0]
    lo, hi = env.ranges["W_bl"]
    assert est["W_bl"].min() <= lo < hi <= est["W_bl"].max()
    assert env.ranges["Q_e"] == econ_hifi_fit.params.power_map.domain["Q_e"]
    lo, hi = env.ranges["T_cab"]
    assert C2K(est["T_cab"].min()) <= lo < hi <= C2K(est["T_cab"].max())
