"""The whole-year sweep (``acid.plant.year``): a quick grid makes physical sense."""

from __future__ import annotations

import pytest

from acid.errors import ConfigError
from acid.plant.year import HEAT_PUMP, HEATER_ONLY, year_sweep
from acid.units import K2C


@pytest.fixture(scope="module")
def quick():
    """-10 and 0 degC heated, 25 and 35 degC cooled, UDDS, acid's default vehicle."""
    return year_sweep((-10.0, 0.0, 25.0, 35.0), ("udds",), ("default",), jobs=1)


def _by(result, heating):
    return {K2C(p.T_amb_K): p for p in result.select("udds", "default", heating)}


def test_heating_falls_and_cooling_rises_with_ambient(quick):
    for heating in (HEAT_PUMP, HEATER_ONLY):
        pts = _by(quick, heating)
        assert pts[-10.0].mode == pts[0.0].mode == "heating"
        assert pts[25.0].mode == pts[35.0].mode == "cooling"
        assert pts[-10.0].E_climate_kWh > pts[0.0].E_climate_kWh > 0.0
        assert 0.0 < pts[25.0].E_climate_kWh < pts[35.0].E_climate_kWh
        assert pts[25.0].E_ac_kWh > 0.0 and pts[25.0].E_heater_kWh == 0.0
        assert pts[25.0].E_hp_kWh == 0.0
        for p in pts.values():
            assert 0.0 < p.share < 1.0
            assert p.share == pytest.approx(
                p.E_climate_kWh / (p.E_traction_kWh + p.E_base_kWh + p.E_climate_kWh))


def test_the_heat_pump_uses_less_than_the_heater_alone_at_equal_or_better_comfort(quick):
    hp, heater = _by(quick, HEAT_PUMP)[0.0], _by(quick, HEATER_ONLY)[0.0]
    assert hp.E_hp_kWh > 0.0 and heater.E_hp_kWh == 0.0
    assert hp.E_climate_kWh < 0.5 * heater.E_climate_kWh
    assert hp.T_cab_mean_K >= heater.T_cab_mean_K - 0.5
    assert hp.E_traction_kWh == heater.E_traction_kWh


def test_cooling_points_serve_both_heating_systems_and_a_rerun_is_bit_identical(quick):
    assert sum(p.mode == "cooling" for p in quick.points) == 2
    again = year_sweep((-10.0, 0.0, 25.0, 35.0), ("udds",), ("default",), jobs=1)
    assert again.points == quick.points


def test_rows_are_in_degC(quick):
    row = quick.rows()[0]
    assert row["T_amb_C"] == -10.0 and "T_amb_K" not in row
    assert 15.0 < row["T_cab_end_C"] < 30.0


@pytest.mark.parametrize("kw, option", [({"ambients_C": (300.0,)}, "--t-amb"),
                                        ({"cycles": ("moon",)}, "--cycle"),
                                        ({"vehicles": ("papr",)}, "--plant-config"),
                                        ({"ambients_C": ()}, "--t-amb")])
def test_a_bad_grid_is_refused_before_any_run(kw, option):
    with pytest.raises(ConfigError, match=option):
        year_sweep(**kw)


@pytest.mark.slow
def test_a_dask_cluster_gives_the_same_points_as_this_process(quick):
    from acid.executor import dask_available

    if not dask_available():
        pytest.skip("dask.distributed is not installed")
    on_dask = year_sweep((-10.0, 0.0, 25.0, 35.0), ("udds",), ("default",), jobs=2)
    assert on_dask.points == quick.points


def test_batched_sweep_equals_one_plant_per_run():
    """The batched plants (both vehicles, both cycles and both plants mixed in their batches,
    a member ending first) give the points of one plant per run, to rounding."""
    import dataclasses

    from acid.plant.year import plan_batches, plan_tasks

    grid = ((-25.0, 0.0, 30.0), ("nycc", "sc03"), ("default", "paper"))
    chunks = plan_batches(plan_tasks(*grid, 18.0), batch_min=1)
    assert sorted(len(c) for c in chunks) == [4, 16]  # one batch per plant
    batched = year_sweep(*grid, jobs=1, batch_min=1)
    single = year_sweep(*grid, jobs=1, batch_min=None)
    assert len(batched.points) == len(single.points) == 20
    for p, q in zip(batched.points, single.points, strict=True):
        for f in dataclasses.fields(p):
            x, y = getattr(p, f.name), getattr(q, f.name)
            if isinstance(x, float):
                assert abs(x - y) <= 1e-9 * max(1.0, abs(y)), (f.name, q)
            else:
                assert x == y


def test_batches_are_split_for_the_workers_and_capped():
    from acid.plant.year import plan_batches, plan_tasks

    tasks = plan_tasks((-10.0, 0.0, 5.0, 25.0, 30.0), ("udds", "hwfet"), ("default",), 18.0)
    one = plan_batches(tasks, jobs=1, batch_min=4)
    two = plan_batches(tasks, jobs=2, batch_min=4)
    capped = plan_batches(tasks, jobs=1, size=5, batch_min=4)
    small = plan_batches(tasks, jobs=2, batch_min=13)  # one plant per run: a chunk each
    assert [len(c) for c in one] == [12, 4]
    assert [len(c) for c in two] == [6, 6, 4]  # the cooling group is too small to split
    assert max(len(c) for c in capped) <= 5 and len(capped) == 4
    assert [len(c) for c in small] == [1] * 16
    for plan in (one, two, capped, small):
        assert sorted(map(id, (t for c in plan for t in c))) == sorted(map(id, tasks))
        assert all(len({t.mode for t in c}) == 1 for c in plan)
