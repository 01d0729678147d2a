"""BatchPlant: B hifi plants at once equal the single HifiPlant member by member."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from acid.errors import ConfigError
from acid.plant.base import InputSchedule
from acid.plant.batch import BatchPlant
from acid.plant.config import PlantConfig
from acid.plant.hifi import HifiPlant
from acid.units import C2K

TOL = 1e-9  # K on temperatures; relative (to max(1, |x|)) on every other channel


def _scenarios():
    """Six members differing in ambient, sun, speed profile, length and protections."""
    base = PlantConfig()
    rng = np.random.default_rng(7)
    cfgs, scheds, inits = [], [], []
    # 0, 1: hot and warm days, random inputs at speed, different lengths
    for T, G, n in ((38.0, 900.0, 40), (27.0, 300.0, 31)):
        cfgs.append(dataclasses.replace(base, T_amb=C2K(T), G_solar=G))
        scheds.append(InputSchedule(rng.uniform(0.05, 0.15, n), C2K(rng.uniform(3, 10, n)),
                                    rng.uniform(0.0, 25.0, n)))
        inits.append(None)
    # 2: a mild night with a -5 degC evaporator set-point at standstill: frost protection
    # caps the speed (by up to 2,000 rpm against the same plant without it)
    cfgs.append(dataclasses.replace(base, T_amb=C2K(20.0), G_solar=0.0, T_cw0=C2K(20.0),
                                    T_ew0=C2K(20.0)))
    scheds.append(InputSchedule(np.full(36, 0.15), C2K(-5.0), 0.0))
    inits.append(None)
    # 3: starts above the cut-out head pressure: the compressor is cut out
    cfgs.append(base)
    scheds.append(InputSchedule(np.full(36, 0.12), C2K(4.0), 3.0))
    inits.append({"p_dis_last": 3.5e6})
    # 4: ambient per sample (a tunnel), ends first
    n = 20
    cfgs.append(base)
    scheds.append(InputSchedule(np.full(n, 0.1), C2K(5.0), np.linspace(0, 30, n),
                                T_amb=C2K(np.where(np.arange(n) < 10, 30.0, 22.0))))
    inits.append(None)
    # 5: the speed-blind counterfactual (front end and cabin at standstill at every speed)
    cfgs.append(dataclasses.replace(base, front_end_speed=False, cabin_speed=False))
    scheds.append(InputSchedule(np.full(24, 0.1), C2K(5.0), np.linspace(0, 30, 24)))
    inits.append(None)
    return cfgs, scheds, inits


def _single(cfg, mode, sched, init):
    p = HifiPlant(cfg, mode=mode)
    p.reset(init)
    rows = []
    for k in range(len(sched)):
        kw = {} if sched.T_amb is None else {"T_amb": sched.T_amb[k]}
        rows.append(p.step(sched.W_bl[k], sched.T_evap_set[k], sched.v_veh[k], **kw))
    return {name: np.array([r[name] for r in rows]) for name in rows[0]}


def _worst(a, b):
    return max(float(np.max(np.abs(a[k] - b[k]) / np.maximum(1.0, np.abs(a[k])))) for k in a)


@pytest.mark.parametrize("mode", ["direct", "nominal"])
def test_batch_equals_single_plants(mode):
    cfgs, scheds, inits = _scenarios()
    out = BatchPlant(cfgs, mode=mode).run(scheds, inits)
    for b in range(len(cfgs)):
        ref = _single(cfgs[b], mode, scheds[b], inits[b])
        assert len(out[b]["T_cab"]) == len(scheds[b])
        assert set(out[b]) == set(ref)
        assert _worst(ref, out[b]) < TOL, b
    if mode == "direct":
        # the protections act in their own member only
        frost = [np.min(o["T_e"]) < cfgs[b].T_e_min for b, o in enumerate(out)]
        assert frost == [False, False, True, False, False, False]
        cut = [bool(np.any(o["cut_out"][1:] > 0.5)) for o in out]
        assert cut == [False, False, False, True, False, False]


def test_batch_simulate_returns_datasets_like_the_single_plant():
    cfg = dataclasses.replace(PlantConfig(), T_amb=C2K(33.0))
    s = InputSchedule(np.full(8, 0.1), C2K(5.0), 10.0, spec={"seed": 3})
    one = HifiPlant(cfg).simulate(s)
    two = BatchPlant([cfg, cfg]).simulate([s, s])
    for d in two:
        assert d.units == one.units
        assert d.metadata["seed"] == 3
        for k, v in one.channels.items():
            np.testing.assert_allclose(d.channels[k], v, rtol=1e-12, atol=1e-12)


def test_batch_rejects_members_with_different_refrigerants():
    base = PlantConfig()
    with pytest.raises(ConfigError, match="share the refrigerant"):
        BatchPlant([base, dataclasses.replace(base, refrigerant="R1234yf")])


def test_batch_runs_the_shipped_vehicles_together_in_nominal_mode():
    """Members with different compressors and UA values (the two shipped vehicles) in one
    batch, the production loops on: each equals its own HifiPlant."""
    from acid.plant.vehicles import vehicle_config

    cfgs, scheds = [], []
    for name, T, n in (("default", 35.0, 30), ("paper", 35.0, 30), ("paper", 25.0, 22),
                       ("default", 28.0, 26)):
        c = vehicle_config(name)
        T = C2K(T)
        cfgs.append(c.replace(T_amb=T, T_cab0=T, T_int0=T, T_shell0=T, T_ew0=T, T_cw0=T))
        scheds.append(InputSchedule(np.zeros(n), c.T_ew_set, np.linspace(0.0, 20.0, n)))
    assert BatchPlant(cfgs, mode="nominal")._cyc.params.varying  # the cycles do differ
    out = BatchPlant(cfgs, mode="nominal").run(scheds)
    for b in range(len(cfgs)):
        ref = _single(cfgs[b], "nominal", scheds[b], None)
        assert _worst(ref, out[b]) < TOL, b
        assert np.max(ref["N_comp"]) > 0.0
