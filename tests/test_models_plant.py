"""acid.plant.declared: any declaration as a plant for acid.excite; its data fit back."""

from __future__ import annotations

import numpy as np
import pytest

from acid.errors import ConfigError
from acid.excite import ExcitationSpec, excite
from acid.ident.fit import fit_model
from acid.models import load
from acid.plant.declared import DeclaredPlant, econ_plant


def test_excite_a_declared_model_and_fit_it_back():
    m = load("cabin3")
    truth = m.values * np.array([0.8, 1.3, 0.9, 1.2, 0.7, 1.0, 1.5, 1.1, 1.4])
    truth[m.parameter_names.index("dT_evap")] = 0.4
    plant = DeclaredPlant(m, truth, initial={"T_cab": 310.0, "T_int_lumped": 316.0,
                                             "T_evap": 290.0})
    ds = excite(plant, ExcitationSpec(duration=1500.0, seed=1))
    assert ds.units["T_int_lumped"] == "degC" and len(ds) == 300
    assert ds.metadata["plant_config"]["model"] == "cabin3"
    res = fit_model(m, ds, oe_window=150)            # the recorded latent state is not read
    for name, t in zip(m.parameter_names, truth, strict=True):
        assert res.value(name) == pytest.approx(t, rel=1e-3), name


def test_a_signal_no_schedule_gives_is_one_line():
    m = load("paper")
    plant = DeclaredPlant(m)
    with pytest.raises(ConfigError, match="no schedule gives 'T_int'"):
        plant.step(0.1, 280.0)
    held = DeclaredPlant(m, constant={"T_int": 305.0, "T_shell": 310.0})
    row = held.step(0.1, 280.0)
    assert row["T_int"] == 305.0 and set(row) >= {"T_cab", "T_evap", "T_ain", "P_bl"}
    with pytest.raises(ConfigError, match="initial condition 'T_x' unknown"):
        held.reset({"T_x": 1.0})


def test_a_floor_holds_an_output_where_the_smooth_model_goes_below_it():
    from acid.models import econ

    # the wall warming fast towards a far set-point: the refrigerant heat Q_e is negative
    kw = {"initial": {**econ.HOT_SOAK, "T_cab": 295.0, "T_evap": 275.0}}
    raw = DeclaredPlant("econ", **kw).step(0.1, 300.0, 10.0, T_amb=300.0)
    floored = econ_plant(**kw).step(0.1, 300.0, 10.0, T_amb=300.0)
    assert raw["P_comp"] < 0.0 and floored["P_comp"] == 0.0
    assert floored["T_cab"] == raw["T_cab"] and floored["T_ain"] == raw["T_ain"]
    with pytest.raises(ConfigError, match="floor of 'P_com', not an output"):
        DeclaredPlant("econ", floor={"P_com": 0.0})
