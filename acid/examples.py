"""The bundled examples (sweep specifications, import and FMU maps, plant configurations, a
sample log), addressable from any folder as ``example:NAME``.

They are package data of ``acid.datasets`` (``datasets/examples`` and ``datasets/plant``
of the repository), found with ``importlib.resources``, so a wheel installed anywhere has
them. ``acid examples`` lists them and copies one; every command accepts ``example:NAME``
wherever it reads a file (``acid_cli._common`` resolves it through :func:`resolve`).
"""

from __future__ import annotations

from pathlib import Path

from acid.errors import ConfigError

PREFIX = "example:"

#: Folders of ``acid.datasets`` that hold examples, and what their files are.
FOLDERS = ("examples", "plant")

#: What each bundled file is: name -> (kind, one line).
DESCRIPTIONS: dict[str, tuple[str, str]] = {
    "sample_log.csv.gz": ("log", "a car-style log of acid's plant (UDDS, 35 degC; ';', "
                                 "decimal comma, Latin-1, km/h, kW): try `acid import`"),
    "sample_log_map.toml": ("import map", "the map of sample_log.csv.gz"),
    "bmw_i3_map.toml": ("import map", "the BMW i3 trips of TU Munich (doi:10.21227/6jr9-5235;"
                                      " the trips are not shipped)"),
    "bmw_i3_winter_map.toml": ("import map", "the BMW i3 winter trips (heater, coolant, "
                                             "outlets) for --model heating; not shipped"),
    "bmw_i3_summer_cabin.json": ("parameter file", "the summer cabin structure `acid car "
                                 "select` chose, fitted on the 26 BMW i3 summer trips"),
    "bmw_i3_winter_heating.json": ("parameter file", "the winter heating structure `acid car "
                                   "select` chose, fitted on the 22 BMW i3 winter trips"),
    "bmw_i3_winter_heat3n.json": ("parameter file", "car_heat3n (car_heat3 with its filter's "
                                  "noises) fitted by PEM on the 11 BMW i3 winter estimation "
                                  "trips: validate with --warm-start ekf-trip"),
    "coolsim_map.toml": ("import map", "a CoolSim (MATLAB/Simulink) run saved as a .mat"),
    "acid_hifi_fmu_map.toml": ("FMU map", "acid's plant exported with `acid export-fmu`"),
    "sweep_climates.toml": ("sweep spec", "ICM against NMPC across climates and drive cycles"),
    "sweep_econ.toml": ("sweep spec", "economic NMPC against NMPC across climates"),
    "sweep_prediction.toml": ("sweep spec", "where prediction pays: economic NMPC against the "
                                            "best fixed-coil PI across climates and cycles"),
    "table_i_20cc.toml": ("plant config", "the paper vehicle: a 20 cc electric scroll "
                                          "calibrated to Table I (--plant-config paper)"),
    "day.toml": ("day spec", "acid day's hot and cold day (Phoenix in July, Minneapolis in "
                             "January) and the time-of-use tariff, every value cited"),
}


def _root() -> Path:
    from acid.signals import datasets_dir  # importlib.resources: works from a wheel too

    return datasets_dir()


def available() -> dict[str, Path]:
    """{name: path} of every bundled example, sorted by folder then name."""
    out: dict[str, Path] = {}
    root = _root()
    for folder in FOLDERS:
        d = root / folder
        if not d.is_dir():
            continue
        for p in sorted(d.iterdir()):
            if p.is_file() and not p.name.startswith((".", "_")) and p.suffix != ".py" \
                    and p.name not in out and p.name.lower() not in ("sources.md",):
                out[p.name] = p
    return out


def describe(name: str) -> tuple[str, str]:
    """(kind, one line) of an example; files not in ``DESCRIPTIONS`` get their folder."""
    if name in DESCRIPTIONS:
        return DESCRIPTIONS[name]
    path = available().get(name)
    return (path.parent.name if path else "file", "")


def is_reference(value: object) -> bool:
    """Whether ``value`` (text or path) is an ``example:NAME`` reference."""
    return isinstance(value, (str, Path)) and str(value).startswith(PREFIX)


def resolve(ref: str | Path) -> Path:
    """The bundled file an ``example:NAME`` reference (or a bare NAME) names; a one-line
    ``ConfigError`` listing the examples for an unknown name."""
    name = str(ref)[len(PREFIX):] if is_reference(ref) else str(ref)
    found = available()
    if name not in found:
        import difflib

        close = difflib.get_close_matches(name, list(found), n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise ConfigError(f"{PREFIX}{name}: no such bundled example ({hint}known: "
                          f"{', '.join(found) or 'none'}; `acid examples` lists them)")
    return found[name]


def reference_of(path: str | Path) -> str:
    """``example:NAME`` for a bundled example's path, else the path as given: how a command
    names a file the user gave as a reference (not the installed package's folder)."""
    return f"{PREFIX}{Path(path).name}" if is_bundled(path) else str(path)


def is_bundled(path: str | Path) -> bool:
    """Whether ``path`` is one of the bundled examples (never to be overwritten)."""
    try:
        target = Path(path).resolve()
        return any(target == p.resolve() for p in available().values())
    except (OSError, RuntimeError, ValueError):
        return False
