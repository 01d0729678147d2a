"""The nominal controller's loops in isolation (paper section II-A)."""

from __future__ import annotations

import pytest

from acid.plant.config import PlantConfig
from acid.plant.controller import BlowerLoop, CompressorLoop, recirculation


def test_recirculation_is_proportional_and_saturated():
    assert recirculation(313.15, 303.15, 0.1, 0.8) == 0.0
    assert recirculation(300.15, 303.15, 0.1, 0.8) == pytest.approx(0.3)
    assert recirculation(280.15, 303.15, 0.1, 0.8) == 0.8


def test_compressor_hysteresis_and_clamps():
    cfg = PlantConfig()
    loop = CompressorLoop(cfg)
    T_set = 276.15
    assert loop.update(T_set + 40.0, T_set, 0.5) == cfg.N_max  # 200 rpm/K x 40 K + I
    assert loop.update(T_set - 1.0, T_set, 0.5) == cfg.N_min  # on, clamped low
    assert loop.update(T_set - 2.1, T_set, 0.5) == 0.0 and not loop.on  # off below set - 2
    assert loop.update(T_set + 0.9, T_set, 0.5) == 0.0  # stays off inside the band
    assert loop.update(T_set + 1.1, T_set, 0.5) >= cfg.N_min and loop.on  # on above set + 1
    assert loop.update(T_set + 5.0, T_set, 0.5, enabled=False) == 0.0 and not loop.on


def test_conditional_integration_stops_in_saturation():
    aw = CompressorLoop(PlantConfig())
    wind = CompressorLoop(PlantConfig(anti_windup=False))
    for _ in range(200):
        aw.update(290.0, 276.15, 0.5)
        wind.update(290.0, 276.15, 0.5)
    assert aw.integ < PlantConfig().N_max < wind.integ


def test_blower_pi_bounds():
    cfg = PlantConfig()
    loop = BlowerLoop(cfg)
    assert loop.update(cfg.T_cab_set + 15.0, cfg.T_cab_set, 0.5) == cfg.W_bl_max
    loop.reset()
    assert loop.update(cfg.T_cab_set - 3.0, cfg.T_cab_set, 0.5) == cfg.W_bl_min
