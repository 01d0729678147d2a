"""``--plant`` and ``--fmu-map``: the plant options every command that drives a plant shares.

One place for the options and the construction behind them, so that every command (excite,
mpc-check, cav-study, speed-sweep, plant-check, and those still to come) accepts the same
plants: ``hifi`` (acid's high-fidelity plant), ``model`` (paper eqs. 1-5, where a command
allows it) and ``fmu:PATH.fmu`` (an FMI 2.0 / 3.0 co-simulation FMU, with ``--fmu-map``)::

    plant: str = plant_option(),
    fmu_map: Path | None = fmu_map_option(),
    ...
    choice = plant_choice(plant, fmu_map, allowed=("hifi",))
    factory = choice.factory(mode="nominal")      # a fresh plant per call
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import typer

from acid.errors import ConfigError
from acid.plant import FMU_PREFIX, make_plant

_NAMES = {"hifi": "'hifi' (high-fidelity)", "model": "'model' (paper eqs. 1-5)"}


def plant_option(default: str = "hifi", allowed: tuple[str, ...] = ("hifi", "model")):
    """The ``--plant`` option (``allowed`` built-in plants, or ``fmu:PATH.fmu``)."""
    names = ", ".join(_NAMES[a] for a in allowed)
    return typer.Option(default, "--plant",
                        help=f"Plant: {names} or 'fmu:PATH.fmu' (your FMI 2.0/3.0 "
                             "co-simulation FMU, with --fmu-map).")


def fmu_map_option():
    """The ``--fmu-map`` option (the TOML map of an FMU plant)."""
    return typer.Option(None, "--fmu-map",
                        help="FMU map (TOML) for --plant fmu:...: which FMU variables are "
                             "acid's channels, their units, start values and parameters "
                             "(datasets/FORMAT.md).")


@dataclass(frozen=True)
class PlantChoice:
    """A validated ``--plant`` / ``--fmu-map`` pair.

    Attributes
    ----------
    spec : ``"hifi"``, ``"model"`` or ``"fmu:PATH"`` (what ``acid.plant.make_plant`` takes).
    fmu_map : the map of an FMU plant, else None.
    """

    spec: str
    fmu_map: Path | None = None

    @property
    def kind(self) -> str:
        """``"hifi"``, ``"model"`` or ``"fmu"``."""
        return "fmu" if self.spec.startswith(FMU_PREFIX) else self.spec

    @property
    def is_builtin_hifi(self) -> bool:
        return self.kind == "hifi"

    def make(self, **kwargs):
        """A new plant (keywords as ``acid.plant.make_plant``: rng, T_amb (K), mode, ...)."""
        return make_plant(self.spec, fmu_map=self.fmu_map, **kwargs)

    def factory(self, **kwargs) -> Callable:
        """A picklable callable returning a fresh plant on every call."""
        return functools.partial(make_plant, self.spec, fmu_map=self.fmu_map, **kwargs)

    def check(self, **kwargs) -> None:
        """Build the plant once and release it, so a bad FMU or map fails before long work."""
        if self.kind == "fmu":
            plant = self.make(**kwargs)
            plant.close()

    def to_json_dict(self) -> dict:
        return {"plant": self.spec,
                "fmu_map": None if self.fmu_map is None else str(self.fmu_map)}


def config_option():
    """The ``--plant-config`` option: a TOML file or a named vehicle (``acid.plant.vehicles``)."""
    return typer.Option(None, "--plant-config",
                        help="Plant configuration: a TOML file (temperatures in degC, or "
                             "tagged \"308.15 K\"), or a named vehicle: 'paper' (the Table I "
                             "calibration, example:table_i_20cc.toml) or 'default'.")


def ambient_option(default_text: str = "the plant configuration's"):
    """The ``--t-amb`` option: the ambient temperature, degC."""
    return typer.Option(None, "--t-amb",
                        help=f"Ambient temperature, degC (default: {default_text}).")


def refrigerant_option():
    """The ``--refrigerant`` option of acid's high-fidelity plant."""
    from acid.plant.config import REFRIGERANTS

    return typer.Option(None, "--refrigerant",
                        help=f"Refrigerant of the high-fidelity plant: {' or '.join(REFRIGERANTS)} "
                             "(default: the plant configuration's).")


def plant_overrides(t_amb: float | None = None, refrigerant: str | None = None) -> dict:
    """``--t-amb`` (degC) and ``--refrigerant`` as ``PlantConfig`` changes (kelvin inside);
    a refrigerant acid has no tables for is one line naming the option."""
    from acid.plant.config import RANGES, REFRIGERANTS
    from acid.units import C2K, K2C

    changes: dict = {}
    if t_amb is not None:
        lo, hi, why = RANGES["T_amb"]
        if not K2C(lo) <= float(t_amb) <= K2C(hi):
            raise ConfigError(f"--t-amb {t_amb:g} degC is outside {K2C(lo):.0f} to "
                              f"{K2C(hi):.0f} degC ({why})")
        changes["T_amb"] = C2K(float(t_amb))
    if refrigerant is not None:
        if refrigerant not in REFRIGERANTS:
            raise ConfigError(f"--refrigerant {refrigerant!r}: choose "
                              f"{' or '.join(REFRIGERANTS)}")
        changes["refrigerant"] = refrigerant
    return changes


def plant_identity(config, label: str) -> dict:
    """What a run says about the plant it drove (its table line and its JSON): the vehicle
    (a name or the configuration file), the refrigerant and the ambient in degC. ``config``
    is the ``PlantConfig`` run, or None for a plant without acid's refrigerant cycle (an FMU,
    the model plant): its refrigerant is then None."""
    from acid.units import K2C

    if config is None:
        return {"vehicle": label, "refrigerant": None, "T_amb_C": None}
    return {"vehicle": label, "refrigerant": config.refrigerant,
            "T_amb_C": round(float(K2C(config.T_amb)), 6)}


def recorded_identity(identity: dict, ds) -> dict:
    """``identity`` with the ambient the record ``ds`` ran at: when its ``T_amb`` channel
    varies (``acid excite --model econ``, ``--t-amb-range``), ``T_amb_C`` is None and
    ``T_amb_range_C`` gives the lowest and highest value recorded (degC), instead of the
    configuration's nominal ambient, which did not run."""
    if "T_amb" not in ds.channels:
        return identity
    t = np.asarray(ds.get("T_amb", "degC"), dtype=float)
    lo, hi = float(np.min(t)), float(np.max(t))
    if hi - lo < 0.05:
        return identity
    return {**identity, "T_amb_C": None, "T_amb_range_C": [round(lo, 3), round(hi, 3)]}


def identity_line(identity: dict) -> str:
    """``plant_identity`` as one line for the run's output."""
    amb = identity["T_amb_C"]
    span = identity.get("T_amb_range_C")
    refrigerant = identity["refrigerant"] or "not modelled by this plant"
    if amb is not None:
        ambient = f", ambient {amb:g} degC"
    elif span is not None:
        ambient = f", ambient varied {span[0]:.1f}..{span[1]:.1f} degC"
    else:
        ambient = ""
    return f"vehicle {identity['vehicle']}, refrigerant {refrigerant}{ambient}"


def config_input(spec) -> Path | None:
    """The file behind a plant configuration option (for ``check_paths``): the shipped file
    of a named vehicle, else the path given."""
    from acid.plant.vehicles import resolve_config

    return resolve_config(spec)


def plant_choice(plant: str, fmu_map: Path | None,
                 allowed: tuple[str, ...] = ("hifi", "model")) -> PlantChoice:
    """Check ``--plant`` and ``--fmu-map`` (one-line ``ConfigError`` naming the option)."""
    if plant.startswith(FMU_PREFIX):
        path = Path(plant[len(FMU_PREFIX):])
        if not str(path) or str(path) == ".":
            raise ConfigError("--plant fmu:PATH.fmu: the FMU path is missing")
        if not path.is_file():
            raise ConfigError(f"--plant: FMU not found: {path}")
        if fmu_map is None:
            raise ConfigError(f"--plant {plant}: an FMU plant needs --fmu-map MAP.toml "
                              "(see datasets/FORMAT.md)")
        if not Path(fmu_map).is_file():
            raise ConfigError(f"--fmu-map: file not found: {fmu_map}")
        return PlantChoice(spec=plant, fmu_map=Path(fmu_map))
    if plant not in allowed:
        names = " or ".join(f"'{a}'" for a in allowed)
        raise ConfigError(f"--plant: unknown plant {plant!r} (choose {names} or "
                          "'fmu:PATH.fmu')")
    if fmu_map is not None:
        raise ConfigError("--fmu-map applies to --plant fmu:PATH.fmu only")
    return PlantChoice(spec=plant)
