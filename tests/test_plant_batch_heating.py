"""BatchHeatingPlant: B heating plants at once equal the single HeatingPlant member by member."""

from __future__ import annotations

import numpy as np
import pytest

from acid.errors import ConfigError
from acid.plant.batch.heating import BatchHeatingPlant
from acid.plant.heating import HeatingPlant
from acid.plant.heating_config import HeatingConfig, winter_plant_config
from acid.plant.vehicles import vehicle_config
from acid.signals import drive_cycle
from acid.units import C2K

TOL = 1e-9  # K on temperatures; relative (to max(1, |x|)) on every other channel


def _single(hc, cfg, mode, v, inputs, init):
    p = HeatingPlant(hc, cfg, mode=mode)
    p.reset(init)
    rows = []
    for k, x in enumerate(v):
        kw = {name: (val[k] if np.ndim(val) else val) for name, val in inputs.items()
              if name != "W_bl"}
        if "pump" in kw:
            kw["pump"] = bool(kw["pump"])
        W = inputs.get("W_bl", 0.0)
        rows.append(p.step(W[k] if np.ndim(W) else W, 0.0, float(x), **kw))
    return {name: np.array([r[name] for r in rows]) for name in rows[0]}


def _worst(a, b):
    return max(float(np.max(np.abs(a[k] - b[k]) / np.maximum(1.0, np.abs(a[k])))) for k in a)


def _nominal_members():
    """Eight members: both vehicles, heat pump and heater only, below the heat pump's lowest
    ambient, a coil at the edge of its defrost, a humid cabin that fogs the glass without the
    anti-fog rule, different lengths."""
    v, _ = drive_cycle("udds", Ts=5.0, repeat=False)
    v = np.asarray(v, float)
    out = []
    for T, hp, veh, n, init, fog in (
            (-10.0, True, "default", 60, None, True),
            (-5.0, False, "default", 50, None, True),  # heater only
            (2.0, True, "default", 60, {"M_frost": 0.59, "T_cab": C2K(15.0)}, True),  # defrost
            (-25.0, True, "paper", 40, None, True),  # below T_hp_min: the heater alone
            (5.0, True, "paper", 60, None, True),
            (10.0, False, "paper", 45, None, True),
            (0.0, True, "default", 55, {"w_cab": 0.008}, False),  # fogs, no anti-fog
            (15.0, True, "default", 60, None, True)):
        hc = HeatingConfig(heat_pump=hp, anti_fog=fog)
        out.append((hc, winter_plant_config(C2K(T), base=vehicle_config(veh)), v[:n], init))
    return out


def test_batch_heating_equals_single_plants_nominal():
    members = _nominal_members()
    hcs, cfgs, vs, inits = (list(x) for x in zip(*members, strict=True))
    out = BatchHeatingPlant(hcs, cfgs, mode="nominal").run(vs, initial=inits)
    refs = [_single(hc, cfg, "nominal", v, {}, init) for hc, cfg, v, init in members]
    for b, ref in enumerate(refs):
        assert set(out[b]) == set(ref)
        assert len(out[b]["T_cab"]) == len(vs[b])
        assert _worst(ref, out[b]) < TOL, b
    # the runs do reach the branches: a defrost that starts and ends, heater-only members,
    # a fogged glass, the heat pump running
    d = refs[2]["defrosting"]
    assert d.max() == 1.0 and d[-1] == 0.0
    assert [bool(r["N_comp"].max() > 0.0) for r in refs] == [True, False, True, False, True,
                                                              False, True, True]
    assert refs[6]["fog"].sum() > 0.0 and refs[1]["P_heater"].max() > 0.0


def test_batch_heating_equals_single_plants_direct():
    n = 30
    rng = np.random.default_rng(3)
    v = rng.uniform(0.0, 25.0, n)
    members = [
        (HeatingConfig(), winter_plant_config(C2K(-3.0)),
         {"W_bl": rng.uniform(0.04, 0.12, n), "N_hp": np.where(np.arange(n) < 20, 5000.0, 0.0),
          "P_heater": 1500.0, "recirc": 0.5}),
        (HeatingConfig(), winter_plant_config(C2K(4.0)),  # the pump stopped half way
         {"W_bl": 0.08, "P_heater": 4000.0, "pump": (np.arange(n) < 15).astype(float),
          "T_amb": C2K(np.where(np.arange(n) < 10, 4.0, -2.0))}),
        (HeatingConfig(heat_pump=False), winter_plant_config(C2K(-8.0)),
         {"W_bl": 0.1, "N_hp": 6000.0, "f_def": 0.6, "T_cab_set": C2K(21.0)}),
    ]
    hcs, cfgs, inputs = (list(x) for x in zip(*members, strict=True))
    out = BatchHeatingPlant(hcs, cfgs, mode="direct").run([v] * 3, inputs)
    for b, (hc, cfg, inp) in enumerate(members):
        ref = _single(hc, cfg, "direct", v, inp, None)
        assert _worst(ref, out[b]) < TOL, b
    assert out[0]["N_comp"].max() > 0.0 and out[2]["N_comp"].max() == 0.0


def test_batch_heating_refuses_bad_members():
    with pytest.raises(ConfigError, match="share the refrigerant"):
        BatchHeatingPlant(configs=[winter_plant_config(),
                                   winter_plant_config(refrigerant="R1234yf")])
    with pytest.raises(ConfigError, match="3 plant configs for 2 batch members"):
        BatchHeatingPlant([HeatingConfig()] * 2, [winter_plant_config()] * 3)
