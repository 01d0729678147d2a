"""acid.ident.analysis: predict, compare and resid for any declared model, through
acid.ident.analysis's result objects; checked against the model's own one-sample map."""

from __future__ import annotations

import numpy as np
import pytest

from acid.errors import ConfigError
from acid.excite import ExcitationSpec, excite
from acid.ident.analysis import compare, predict, predict_model, resid
from acid.ident.fit import fit_model
from acid.models import load
from acid.models.values import ParameterValues
from acid.plant.declared import DeclaredPlant

CABIN3 = load("cabin3")


@pytest.fixture(scope="module")
def record():
    """300 samples of the three-state cabin (latent interior) driven by acid.excite."""
    plant = DeclaredPlant(CABIN3)                    # every state starts at T_amb: the
    return excite(plant, ExcitationSpec(duration=1500.0, seed=3))   # declared initial rule


def wrong() -> ParameterValues:
    v = CABIN3.values * np.array([1.3, 0.8, 1.2, 0.9, 1.4, 1.0, 0.7, 1.0, 1.2])
    return ParameterValues(v, model=CABIN3, source="perturbed")


def manual(ds, values, k: int) -> np.ndarray:
    """k-step predictions by the model's ``step`` in a plain loop: the latent state by a
    forced run from the declared initial rule, each prediction from the state at n - k."""
    m = CABIN3
    x_meas = np.column_stack([ds.get(s.name, "K") if s.measured else np.full(len(ds), np.nan)
                              for s in m.states])
    u = np.column_stack([ds.get(r.name, r.unit) for r in m.inputs])
    d = np.column_stack([ds.get(r.name, r.unit) for r in m.disturbances])
    lat = [i for i, s in enumerate(m.states) if not s.measured]
    X = x_meas.copy()
    x = x_meas[0].copy()
    x[lat] = x_meas[0, 0]                                   # initial rule: T_cab
    for n in range(len(ds)):
        X[n, lat] = x[lat]
        x = np.where(np.isfinite(x_meas[n]), x_meas[n], x)
        x = np.asarray(m.step(x, u[n], d[n], values)[0]).ravel()
    out = np.full((len(ds), 3), np.nan)                     # T_cab, T_evap, T_ain
    for n in range(k, len(ds)):
        x = X[n - k].copy()
        for j in range(n - k, n):
            x = np.asarray(m.step(x, u[j], d[j], values)[0]).ravel()
        y = np.asarray(m.step(x, u[n], d[n], values)[1]).ravel()
        out[n] = [x[0], x[2], y[0]]
    return out


def test_k_step_prediction_equals_a_plain_loop_over_the_model(record):
    ps = wrong()
    pr = predict_model(record, ps, 4, model=CABIN3)
    assert pr.channels == ("T_cab", "T_evap", "T_ain") and pr.units == ("K", "K", "K")
    ref = manual(record, ps.theta, 4)
    assert np.all(np.isnan(pr.predicted[:4])) and pr.valid[4:].all()
    np.testing.assert_allclose(pr.predicted[4:], ref[4:], rtol=0, atol=1e-9)
    assert max(pr.fit_percent.values()) < 99.9               # the perturbed model errs


def test_true_parameters_predict_the_plant_exactly(record):
    for k in (1, 7, None):
        pr = predict_model(record, None, k, model=CABIN3)
        m = pr.valid
        assert m.sum() >= len(record) - 7
        np.testing.assert_allclose(pr.predicted[m], pr.measured[m], rtol=0, atol=1e-7)


def test_resid_and_compare_through_acid_analysis(record, tmp_path):
    ps = wrong()
    r = resid(record, (CABIN3, ps), max_lag=10)
    assert r.inputs == ("W_bl", "T_evap_set") and r.channels == ("T_cab", "T_evap", "T_ain")
    assert r.autocorrelation.shape == (11, 3) and r.cross_correlation.shape == (21, 2, 3)
    e = r.residuals[r.prediction.valid, 0]
    e = e - e.mean()
    assert r.autocorrelation[3, 0] == pytest.approx(np.sum(e[3:] * e[:-3]) / np.sum(e * e),
                                                    rel=1e-9)
    assert set(r.interpretation) == {"T_cab", "T_evap", "T_ain"}
    fit = fit_model(CABIN3, record, oe_window=150)
    path = fit.write(tmp_path / "p.json", CABIN3)
    c = compare(record, str(path), (CABIN3, ps), labels=["fitted", "perturbed"])
    fp = c.fit_percent
    assert all(fp["fitted"][ch] > fp["perturbed"][ch] for ch in ("T_cab", "T_ain"))
    assert fp["fitted"]["T_cab"] > 99.0
    df = c.predictions["fitted"].to_frame()
    assert df["T_cab"].iloc[0] == pytest.approx(record.get("T_cab", "degC")[0])
    import matplotlib

    matplotlib.use("Agg")
    c.plot()
    r.plot()
    pr = predict(record, fit, 1)                           # a fit result routes here too
    assert pr.model == "cabin3 (fit-oe)" and pr.fit_percent["T_cab"] > 99.0


def test_econ_gains_resid_with_every_channel_and_its_units():
    from acid.ident.validate import declared_parameters

    econ = load("econ")
    plant = DeclaredPlant(econ, initial={"w_cab": 0.01},
                          constant={"T_amb": 305.0, "v_veh": 10.0})
    ds = excite(plant, ExcitationSpec(duration=600.0, seed=1))
    r = resid(ds, (econ, declared_parameters(econ)), max_lag=5)
    assert r.channels == ("T_cab", "T_int", "T_shell", "T_evap", "w_cab", "T_ain", "P_comp",
                          "P_bl")
    assert r.prediction.units[4:] == ("kg/kg", "K", "W", "W")
    assert r.prediction.to_frame()["P_comp"].iloc[5] == pytest.approx(ds.get("P_comp")[5])


def test_bad_horizon_and_warmup_are_one_line(record):
    with pytest.raises(ConfigError, match="horizon k"):
        predict_model(record, None, 0, model=CABIN3)
    with pytest.raises(ConfigError, match="warmup"):
        predict_model(record, None, 1, model=CABIN3, warmup=-1)
