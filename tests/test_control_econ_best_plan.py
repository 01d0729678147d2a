"""acid.control.econ.best_plan: the best known plan (perfect information), a whole-cycle optimum on
the
econ model."""

from __future__ import annotations

import numpy as np
import pytest

from acid.control.econ.best_plan import PlanConfig, best_known_plan
from acid.errors import ConfigError, ExtrapolationWarning
from acid.models import econ as econ_decl
from acid.plant.declared import econ_plant
from acid.studies.mpc_check.scenarios import stop_and_go_cycle
from acid.units import C2K

V = stop_and_go_cycle(np.arange(48) * 5.0 + 2.5)          # 240 s of stop-and-go
T_AMB = C2K(30.0)


@pytest.fixture(scope="module")
def plans(econ_truth):
    cfg = PlanConfig(T_mean=C2K(24.0), T_low=C2K(23.0), T_high=C2K(25.0))
    band = best_known_plan(econ_truth, V, T_AMB, cfg)
    pinned = best_known_plan(econ_truth, V, T_AMB, PlanConfig(T_mean=C2K(24.0), pinned=True),
                             guess=(band.x, band.inputs))
    return band, pinned


def test_constraints_hold_at_the_optimum(plans):
    band, pinned = plans
    assert band.success and pinned.success
    np.testing.assert_allclose(band.x[-1], band.x[0], atol=1e-6)            # cyclic
    assert band.mean_T_cab == pytest.approx(C2K(24.0), abs=1e-6)            # same mean
    assert C2K(23.0) - 1e-6 <= band.x[1:, 0].min() and band.x[1:, 0].max() <= C2K(25.0) + 1e-6
    np.testing.assert_allclose(pinned.x[1:, 0], C2K(24.0), atol=1e-6)
    assert np.all(band.Q_e >= -1e-6)
    assert band.W_bl.min() >= 0.05 - 1e-9 and band.T_evap_set.max() <= C2K(10.0) + 1e-9


def test_the_band_is_worth_at_most_what_pinning_costs(plans):
    band, pinned = plans
    assert band.energy_J <= pinned.energy_J * (1 + 1e-9)
    assert band.energy_J == pytest.approx(pinned.energy_J, rel=0.05)   # small, not huge


def test_replaying_the_plan_on_the_model_achieves_its_energy(plans, econ_truth):
    band, _ = plans
    plant = econ_plant(econ_truth.theta_all)
    plant.reset(dict(zip(econ_decl.STATES, band.x[0], strict=True)))
    E = 0.0
    for k in range(V.size):
        row = plant.step(band.W_bl[k], band.T_evap_set[k], V[k], T_amb=T_AMB)
        E += (row["P_comp"] + row["P_bl"]) * 5.0
    assert E == pytest.approx(band.energy_J, rel=1e-6)
    np.testing.assert_allclose(plant.x, band.x[0], atol=1e-4)   # back where it started


def test_an_unreachable_band_is_a_one_line_error(econ_truth):
    cfg = PlanConfig(T_mean=C2K(12.5), T_low=C2K(12.0), T_high=C2K(13.0), max_iter=100)
    with pytest.raises(ConfigError, match="infeasible") as exc:
        best_known_plan(econ_truth, V[:12], T_AMB, cfg)
    assert "\n" not in str(exc.value)


def test_mean_outside_the_band_and_extrapolation(econ_truth):
    with pytest.raises(ConfigError, match="outside the comfort band"):
        PlanConfig(T_mean=C2K(27.0))
    with pytest.warns(ExtrapolationWarning, match="T_amb up to"):
        best_known_plan(econ_truth, V[:12], C2K(50.0), PlanConfig(T_mean=C2K(24.0), max_iter=3))


def test_a_plan_from_a_given_state_starts_there_and_a_cyclic_one_returns(plans, econ_truth):
    band, _ = plans
    x0 = band.x[0] + np.array([0.2, 0.0, 0.0, 0.0, 0.0])   # not the periodic state
    cfg = PlanConfig(T_mean=C2K(24.0), T_low=C2K(23.0), T_high=C2K(25.0))
    back = best_known_plan(econ_truth, V, T_AMB, cfg, guess=(band.x, band.inputs), x_start=x0)
    np.testing.assert_allclose(back.x[0], x0, atol=1e-6)
    np.testing.assert_allclose(back.x[-1], x0, atol=1e-6)
    assert back.energy_J >= band.energy_J * (1 - 1e-6)   # the free periodic state is best


def test_a_terminal_price_charges_the_end_state(plans, econ_truth):
    band, _ = plans
    cfg = PlanConfig(T_mean=C2K(24.0), T_low=C2K(23.0), T_high=C2K(25.0), cyclic=False)
    free = best_known_plan(econ_truth, V, T_AMB, cfg, guess=(band.x, band.inputs),
                           x_start=band.x[0])
    price = np.array([0.0, 2e4, 0.0, 0.0, 0.0])    # J per K of interior left warm
    priced = best_known_plan(econ_truth, V, T_AMB, cfg, guess=(band.x, band.inputs),
                             x_start=band.x[0], terminal_price=price)
    # unpriced, the plan borrows the interior's cold; priced, it leaves it cooler
    assert priced.x[-1, 1] < free.x[-1, 1] - 1e-3
    assert free.energy_J < priced.energy_J
    with pytest.raises(ConfigError, match="terminal price"):
        best_known_plan(econ_truth, V, T_AMB, PlanConfig(T_mean=C2K(24.0)),
                        terminal_price=price)
