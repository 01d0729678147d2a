"""Named vehicles: plant configurations passed by name wherever a plant configuration is
accepted (``--plant-config paper``, ``make_plant("hifi",
config_path="paper")``).

``paper``
    **The paper vehicle**: the Table I calibration shipped as
    ``datasets/plant/table_i_20cc.toml`` (a 20 cc electric scroll at 7000 rpm from a
    sun-soaked cabin, evaporator and condenser calibrated for the idle service chart). The
    paper's Table I is judged on it (``acid reproduce``, ``acid speed-sweep``).
``default``
    acid's default vehicle, ``PlantConfig()`` (a 33 cc, 8000 rpm scroll from a 40 degC soak):
    the plant of every other study, shown beside the paper vehicle.

Why two: Table I's level (its E(0)) and flatness (its E(25)/E(0)) together need a
compressor that is capacity-limited through the 600 s, so that the energy is its maximum
power and only the head pressure moves it with speed. The default compressor never
saturates in the test (at most 78 % of N_max); its energy follows load / COP, and its COP
rises from 2.42 to 3.68 at the test's 4.6 kW, which with a 10 % lower load gives
E(25)/E(0) = 0.63. A name is resolved before a file of the same name (as ``--params paper``).
"""

from __future__ import annotations

import os
from pathlib import Path

#: name -> (shipped file under ``datasets/``, or None for ``PlantConfig()``; description)
VEHICLES: dict[str, tuple[str | None, str]] = {
    "paper": ("plant/table_i_20cc.toml",
              "the paper vehicle: Table I calibration, 20 cc scroll at 7000 rpm, 55 degC soak"),
    "default": (None, "acid's default vehicle: PlantConfig(), 33 cc scroll at 8000 rpm, "
                      "40 degC soak"),
}

#: the vehicle Table I is judged on, and the one shown beside it
PAPER_VEHICLE, DEFAULT_VEHICLE = "paper", "default"


def is_vehicle(spec) -> bool:
    """True when ``spec`` is the name of a shipped vehicle (not a path)."""
    return isinstance(spec, (str, os.PathLike)) and str(spec) in VEHICLES


def vehicle_file(name: str) -> Path | None:
    """The shipped configuration file of vehicle ``name`` (None: ``PlantConfig()``)."""
    from acid.errors import ConfigError
    from acid.signals import datasets_dir

    if name not in VEHICLES:
        raise ConfigError(f"unknown vehicle {name!r} (choose {', '.join(VEHICLES)})")
    rel = VEHICLES[name][0]
    return None if rel is None else datasets_dir() / rel


def resolve_config(spec) -> Path | None:
    """A plant configuration given as a vehicle name or a path -> the file to read
    (None for ``None`` and for the default vehicle)."""
    if spec is None:
        return None
    return vehicle_file(str(spec)) if is_vehicle(spec) else Path(spec)


def vehicle_config(spec=None):
    """The ``PlantConfig`` of a vehicle name or a TOML path (``None``: the default)."""
    from acid.plant.config import PlantConfig

    path = resolve_config(spec)
    return PlantConfig() if path is None else PlantConfig.from_toml(path)


def vehicle_label(spec) -> str:
    """How a configuration is named in tables and JSON: the vehicle name, else the path."""
    if spec is None:
        return DEFAULT_VEHICLE
    return str(spec)


__all__ = ["DEFAULT_VEHICLE", "PAPER_VEHICLE", "VEHICLES", "is_vehicle", "resolve_config",
           "vehicle_config", "vehicle_file", "vehicle_label"]
