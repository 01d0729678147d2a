"""The plant protocol shared by both plants: reset / step / measure / simulate."""

from __future__ import annotations

import pytest

from acid.plant import make_plant
from acid.units import C2K


@pytest.mark.parametrize("name", ["model", "hifi"])
def test_measure_after_a_step_is_the_next_rows_state(name):
    plant = make_plant(name)
    first = plant.reset({"T_cab": C2K(35.0)})
    assert first["T_cab"] == pytest.approx(C2K(35.0))
    plant.step(0.12, C2K(5.0), 10.0)
    after = plant.measure()
    row = plant.step(0.12, C2K(5.0), 10.0)
    for ch in ("T_cab", "T_evap", "T_int", "T_shell"):
        assert after[ch] == pytest.approx(row[ch], abs=1e-12), ch


@pytest.mark.parametrize("name", ["model", "hifi"])
def test_simulate_stores_degC_with_units_and_plant_metadata(name):
    from acid.plant import InputSchedule

    plant = make_plant(name)
    ds = plant.simulate(InputSchedule(W_bl=[0.1] * 12, T_evap_set=C2K(5.0), v_veh=0.0))
    assert len(ds) == 12 and ds.Ts == plant.Ts
    assert ds.units["T_cab"] == "degC" and ds.units["W_bl"] == "kg/s"
    assert ds.metadata["plant"] == name and "plant_config" in ds.metadata
    assert 10.0 < ds["T_cab"][-1] < 40.0


@pytest.mark.parametrize("name", ["model", "hifi"])
def test_ambient_schedule_is_applied_per_sample(name):
    """A schedule's T_amb reaches the plant; the configured ambient reproduces the default."""
    import numpy as np

    from acid.plant import InputSchedule

    n = 60
    base = dict(W_bl=np.full(n, 0.1), T_evap_set=C2K(5.0), v_veh=0.0)
    default = make_plant(name).simulate(InputSchedule(**base))
    same = make_plant(name).simulate(InputSchedule(**base, T_amb=np.full(n, C2K(30.0))))
    hot = make_plant(name).simulate(InputSchedule(**base, T_amb=np.full(n, C2K(40.0))))
    assert np.array_equal(default["P_comp"], same["P_comp"])
    assert np.all(hot["T_amb"] == pytest.approx(40.0))
    assert hot["P_comp"][10:].sum() > default["P_comp"][10:].sum()


def test_hifi_refuses_an_ambient_in_celsius():
    from acid.errors import ConfigError

    plant = make_plant("hifi")
    with pytest.raises(ConfigError, match="T_amb"):
        plant.step(0.1, C2K(5.0), 0.0, T_amb=30.0)
