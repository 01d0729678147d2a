"""The day planner on a declared model (``acid.models.parked_cabin``,
``acid.studies.dayplan``): identified on the plant's parked records, its optimal-control
plan (price, charger limit, battery, comfort at departure) and its replay on the plant."""

from __future__ import annotations

import numpy as np
import pytest

from acid.errors import ConfigError
from acid.models.parked_cabin import parked_cabin_model
from acid.studies import day as D
from acid.studies.dayplan import ParkedRecord, identify, plan_power
from acid.studies.dayplan.planner import simulate
from acid.units import C2K


@pytest.fixture(scope="module")
def summer_fit():
    recs = [r for d in D.make_days("summer", 1, 0) for r in D.parked_records(d)]
    return recs, identify("summer", recs)


def test_parked_records_are_the_plants_soak_and_pull_down(summer_fit):
    recs, _ = summer_fit
    morning = recs[0]   # 04:00 to the morning departure, the timer's 30 min at the end
    assert morning.H > 150 and morning.T_cab.size == morning.H + 1
    on = np.flatnonzero(morning.P > 0)
    assert on.size >= 29 and on[-1] == morning.H - 1 and np.all(np.diff(on) == 1)
    # switched off the cabin follows the sun; on, the production controller pulls it down
    assert morning.T_cab[on[0]] > morning.T_cab[on[0] + 5] + 5.0
    assert np.all(morning.P[on] > 300.0) and np.all(morning.P[:on[0]] == 0.0)


def test_the_identified_cabin_reproduces_the_records_better_than_its_start(summer_fit):
    recs, fit = summer_fit
    start = parked_cabin_model("summer").values
    rms0 = np.sqrt(np.mean(np.concatenate([simulate("summer", start, r) - r.T_cab[1:]
                                           for r in recs]) ** 2))
    assert fit.rms_K < 1.5 and fit.rms_K < 0.5 * rms0
    v = dict(fit.values)
    # a hot cabin loads the compressor more: the full-power line rises with the cabin
    assert v["P_cap1"] > 0.0 and 500.0 < v["P_cap0"] < 5000.0
    with pytest.raises(ConfigError, match="no pull-down"):
        identify("summer", [ParkedRecord(r.T_cab, 0.0 * r.P, r.T_amb, r.G) for r in recs])


def _plan(fit, price=lambda t: 0.27, cap_W=6364.0, v_bat=0.64, E_avail=7.0):
    clim = D.load_climate("summer")
    return plan_power(fit, C2K(50.0), 16.0 * 3600, 17.5 * 3600,
                      lambda t: (clim.T_amb_K(t), clim.G_solar(t)), price, C2K(26.0),
                      cap_W=cap_W, eta_charger=0.86, v_bat=v_bat, E_avail_kWh=E_avail,
                      margin_min=5.0, margin_K=1.0)


def test_the_plan_meets_comfort_at_departure_within_the_limits(summer_fit):
    _, fit = summer_fit
    plan = _plan(fit)
    assert plan.status == "Solve_Succeeded"
    assert plan.t_s[-1] == 17.5 * 3600 - 60.0 and plan.t_s.size == 90
    # the last 5 minutes within the band by the margin; the cabin hot before the plan
    assert np.all(plan.T_cab_K[-6:] <= C2K(25.0) + 1e-3)
    assert plan.T_cab_K[0] > C2K(40.0)
    assert np.all(plan.P_W <= plan.P_cap_W + 1.0) and np.all(plan.P_grid_W <= 6364.0 + 1e-3)
    # pre-cooling only at the end: nothing in the first hour of the window
    assert np.all(plan.P_W[:60] < 1.0) and plan.P_W[-1] > 0.5 * plan.P_cap_W[-1]
    blocks = plan.on_blocks()
    assert len(blocks) == 1 and blocks[0][1] == 17.5 * 3600


def test_a_small_charger_makes_the_plan_draw_on_the_battery(summer_fit):
    _, fit = summer_fit
    full = _plan(fit)
    small = _plan(fit, cap_W=500.0)
    assert np.all(small.P_grid_W <= 500.0 + 1e-3)
    assert np.sum(small.P_W - small.P_grid_W) > 1000.0       # the rest from the battery
    assert np.sum(full.P_W - full.P_grid_W) < 50.0            # the plug suffices: none
    # no battery energy left: the plan stays on the plug and pays in comfort (slack)
    dry = _plan(fit, cap_W=500.0, E_avail=0.0)
    assert np.sum(dry.P_W - dry.P_grid_W) * 60 / 3.6e6 < 1e-3
    assert dry.T_cab_K[-1] > small.T_cab_K[-1] + 0.5


@pytest.mark.slow
def test_the_declared_model_planner_replayed_on_the_plant(summer_fit):
    _, fit = summer_fit
    d = D.make_days("summer", 1, 0, first_index=1000)[0]
    none = D.run_day(d, D.NoPreconditioning())
    plan = D.run_day(d, D.ModelPlanner(fit, margin_K=1.0))
    long = D.run_day(d, D.Timer(40.0))
    assert plan.Kmin_plugged < 0.2 * none.Kmin_plugged
    assert plan.cost_USD < long.cost_USD
    lead = plan.trips[0].lead_s
    assert 0.0 < lead < 40 * 60.0
    # a larger margin starts earlier
    more = D.run_day(d, D.ModelPlanner(fit, margin_K=4.0))
    assert more.trips[0].lead_s > lead
