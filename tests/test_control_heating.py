"""The heating controllers (acid.control.heating) in closed loop on the heating plant."""


import numpy as np
import pytest

from acid.control.heating import (
    STATE_KEYS,
    heat_pump_map,
    heating_control_model,
)
from acid.models.heating_control import COP_FIT
from acid.plant.heating import HeatingPlant
from acid.plant.heating_config import winter_plant_config
from acid.units import C2K

T_AMB = C2K(0.0)


def test_control_model_follows_the_plant_open_loop():
    """The declared model, with values from the plant's configuration, predicts the plant's
    cabin and fogging margin over 10 min of heat pump, then 10 min of coolant heater."""
    m = heating_control_model()
    p = HeatingPlant(config=winter_plant_config(T_AMB), mode="direct")
    p.reset({"T_cab": C2K(21), "T_int": C2K(21), "T_int_slow": C2K(20), "T_shell": C2K(10),
             "T_glass": C2K(12), "T_icw": C2K(35), "T_cool": C2K(30)})
    s = p.measure()
    x = np.array([s[k] for k in STATE_KEYS])
    for k in range(120):
        N, P_h = (2000.0, 0.0) if k < 60 else (0.0, 2000.0)
        rows = [p.step(W_bl=0.07, v_veh=10.0, N_hp=N, recirc=0.5, P_heater=P_h)
                for _ in range(2)]
        Q = 0.5 * (rows[0]["Q_cond"] + rows[1]["Q_cond"])
        x, y = m.step(x, [Q, P_h, 0.5], [T_AMB, 10.0])
        assert abs(x[0] - rows[1]["T_cab"]) < 0.6
        assert abs(y[1] - rows[1]["fog_margin"]) < 0.5
        if N > 0:   # the COP law against the plant's compressor power, within 10 %
            P = 0.5 * (rows[0]["P_comp"] + rows[1]["P_comp"])
            assert abs(y[0] - P) < 0.1 * P


def test_declared_cop_law_is_the_fit_to_the_plant():
    """The COP law the control model declares (COP_FIT) is what heat_pump_map fits to the
    heating plant today (a changed plant shows here), within 5 % of power."""
    fit, rms, n = heat_pump_map()
    assert n > 50 and rms < 0.06
    for k, v in fit.items():
        assert COP_FIT[k] == pytest.approx(v, rel=0.02, abs=2e-4), k
