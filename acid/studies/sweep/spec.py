"""Sweep specifications: a TOML file -> validated scenarios, controllers and tasks.

Everything is checked here, before any worker starts: unknown keys and values, ranges,
drive-cycle names, parameter files, plant overrides (each scenario's ``PlantConfig`` is
built), controllers and their configurations. Errors are ``ConfigError`` with one line that
names the file, the table and the key.

The format (edge units: degC, %, W/m2, m/s, s; plant overrides in SI and kelvin)::

    title = "ICM against a constant bound across climates"
    baseline = "nmpc"                  # savings are against this controller (default: first)
    plugins = []                       # modules that register more controllers

    [defaults]                         # every scenario starts from these
    cycle = "udds"                     # a drive cycle, or a constant speed in m/s (15.0)
    duration_s = 0                     # 0: one pass of the cycle (600 s at constant speed)
    ambient_C = 30.0
    humidity_pct = 50.0
    solar_W_m2 = 800.0                 # (default: the plant configuration's reference)
    refrigerant = "R134a"
    setpoint_C = 24.0
    band_C = [22.0, 26.0]              # comfort band
    warmup_s = 1800.0                  # common warm-up to a steady state (0: hot soak)
    tail_s = 0.0                       # common continuation charging back the end state
    params = "paper"                   # "paper", "identify" or a params.json (from acid fit)
    plant = { V_disp = 4.0e-5 }        # PlantConfig overrides (acid.plant.config)

    [grid]                             # cartesian product of these lists ...
    ambient_C = [25.0, 35.0, 45.0]
    cycle = ["udds", "nycc"]

    [[scenarios]]                      # ... and/or an explicit list (both: grid, then list)
    cycle = 20.0
    duration_s = 900.0

    [controllers.nmpc]                 # one table per controller; the label is the key,
    match = "icm"                      # the type defaults to it (type = "nmpc")
    [controllers.icm]

    [identify]                         # used by params = "identify", per plant configuration
    duration_s = 7200.0
    seed = 0
    method = "oe"
"""

from __future__ import annotations

import hashlib
import importlib
import itertools
import json
import math
import re
from dataclasses import asdict, dataclass, field
from pathlib import Path

from acid import __version__
from acid.errors import AcidError, ConfigError
from acid.plant.config import REFRIGERANTS, PlantConfig
from acid.studies.sweep.conditions import G_REF, RANGES, Conditions, plant_config_for

MAX_SCENARIOS = 100_000
MAX_DURATION_S = 86_400.0
#: most samples of one scenario (warm-up + run + tail at the plant's Ts: 3 days at 5 s is
#: 51840) and most internal plant steps (3 days at the default 0.5 s is 518400), checked when
#: the spec is read
MAX_SCENARIO_SAMPLES = 100_000
MAX_SCENARIO_STEPS = 2_000_000
#: a drive cycle pass counts as this long for that bound (the shipped cycles are shorter)
CYCLE_PASS_BOUND_S = 3600.0
MAX_SPEED_M_S = 45.0
DEFAULT_CONSTANT_DURATION_S = 600.0
DEFAULT_CONTROLLERS = ("nmpc", "icm")
FIT_METHODS = ("ls", "cvx", "oe")

TOP_KEYS = ("title", "baseline", "plugins", "defaults", "grid", "scenarios", "controllers",
            "identify")
SCENARIO_DEFAULTS = {"cycle": "udds", "duration_s": 0.0, "ambient_C": 30.0,
                     "humidity_pct": 50.0, "solar_W_m2": G_REF, "refrigerant": "R134a",
                     "setpoint_C": 24.0, "band_C": (22.0, 26.0), "warmup_s": 1800.0,
                     "tail_s": 0.0, "params": "paper", "plant": {}}
SCENARIO_KEYS = tuple(SCENARIO_DEFAULTS)
_LABEL = re.compile(r"^[A-Za-z][A-Za-z0-9_-]{0,31}$")


# -------------------------------------------------------------------------- data
@dataclass(frozen=True)
class IdentifySettings:
    """How ``params = "identify"`` identifies the model for a plant configuration: an APRBS
    excitation of ``duration_s`` (seed ``seed``) at ``speed_m_s``, fitted with ``method``
    on the whole record (``acid excite`` + ``acid fit``)."""

    duration_s: float = 7200.0
    seed: int = 0
    method: str = "oe"
    speed_m_s: float = 0.0

    def __post_init__(self):
        if not 600.0 <= self.duration_s <= MAX_DURATION_S:
            raise ConfigError(f"duration_s = {self.duration_s:g} must lie in 600..86400 s")
        if self.seed < 0:
            raise ConfigError(f"seed = {self.seed} must be >= 0")
        if self.method not in FIT_METHODS:
            raise ConfigError(f"method = {self.method!r} unknown (choose "
                              f"{', '.join(FIT_METHODS)})")
        if not 0.0 <= self.speed_m_s <= MAX_SPEED_M_S:
            raise ConfigError(f"speed_m_s = {self.speed_m_s:g} must lie in 0..45 m/s")


@dataclass(frozen=True)
class ParamsSource:
    """Where a scenario's model parameters come from: ``"paper"``, ``"identify"`` or a
    parameter file (loaded and checked at spec time; ``sha256`` identifies it)."""

    spec: str
    kind: str
    params: object = None
    sha256: str = ""

    def identity(self) -> str:
        return {"paper": "paper", "identify": "identify"}.get(self.kind, f"file:{self.sha256}")


@dataclass(frozen=True)
class Scenario:
    """One closed-loop experiment (edge units).

    Attributes
    ----------
    conditions : climate and comfort.
    cycle : drive cycle name, or a constant speed in m/s.
    duration_s : run length, s (0: one pass of the cycle; 600 s at constant speed).
    warmup_s : common warm-up before the controllers start, s (0: from the hot soak).
    tail_s : common continuation after the run that charges back the end state, s.
    params : the spec's ``params`` value (see ``ParamsSource``).
    plant : sorted ``(field, value)`` overrides of ``PlantConfig`` (SI, K).
    origin : where in the spec it came from (for messages).
    """

    conditions: Conditions
    cycle: str | float = "udds"
    duration_s: float = 0.0
    warmup_s: float = 1800.0
    tail_s: float = 0.0
    params: str = "paper"
    plant: tuple = ()
    origin: str = ""

    @property
    def cycle_label(self) -> str:
        """``"udds"`` or ``"15 m/s"``."""
        return self.cycle if isinstance(self.cycle, str) else f"{self.cycle:g} m/s"

    @property
    def label(self) -> str:
        c = self.conditions
        return (f"{self.cycle_label}, {c.ambient_C:g} C, {c.humidity_pct:g} %, "
                f"{c.solar_W_m2:g} W/m2, {c.refrigerant}, set {c.setpoint_C:g} C")

    def plant_config(self) -> PlantConfig:
        """The high-fidelity plant's configuration for this scenario."""
        return plant_config_for(self.conditions, dict(self.plant))

    def to_dict(self) -> dict:
        """Canonical, JSON-ready description (the hash and the table columns)."""
        c = self.conditions
        return {"cycle": self.cycle_label, "duration_s": self.duration_s,
                "ambient_C": c.ambient_C, "humidity_pct": c.humidity_pct,
                "solar_W_m2": c.solar_W_m2, "refrigerant": c.refrigerant,
                "setpoint_C": c.setpoint_C, "band_low_C": c.band_C[0],
                "band_high_C": c.band_C[1], "warmup_s": self.warmup_s, "tail_s": self.tail_s,
                "params": self.params, "plant": dict(self.plant)}


@dataclass(frozen=True)
class ControllerEntry:
    """A controller of the spec: its label, registered type, configuration, constructor."""

    label: str
    kind: str
    config: object
    constructor: object

    def identity(self) -> dict:
        return {"label": self.label, "type": self.kind, "config": asdict(self.config)}


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: scenarios x controllers (spec order; ``run_order`` runs a
    ``match`` after its target), the baseline and the parameter sources."""

    title: str
    scenarios: tuple[Scenario, ...]
    controllers: tuple[ControllerEntry, ...]
    run_order: tuple[str, ...]
    baseline: str
    params: dict = field(default_factory=dict)
    identify: IdentifySettings = field(default_factory=IdentifySettings)
    plugins: tuple[str, ...] = ()
    path: Path | None = None
    allow_unstable: bool = False

    def scenario_key(self, s: Scenario) -> str:
        """Hash of the scenario, its controllers, parameters and acid's version (16 hex)."""
        src: ParamsSource = self.params[s.params]
        blob = {"scenario": s.to_dict(), "params": src.identity(),
                "identify": asdict(self.identify) if src.kind == "identify" else None,
                "controllers": [c.identity() for c in self.controllers],
                "baseline": self.baseline, "acid_version": __version__}
        return hashlib.sha256(json.dumps(blob, sort_keys=True).encode()).hexdigest()[:16]


# -------------------------------------------------------------------------- parsing
class _Where:
    """Prefix of error messages: the spec file and the table."""

    def __init__(self, source: str):
        self.source = source

    def error(self, where: str, msg: str) -> ConfigError:
        return ConfigError(f"{self.source}: {where}: {msg}" if where else f"{self.source}: {msg}")


def _number(value, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{key} = {value!r} must be a number")
    return float(value)


def _check_value(key: str, value):
    """Normalised value of one scenario key, or ``ValueError`` with the reason."""
    if key == "cycle":
        if isinstance(value, str):
            from acid.signals import available_drive_cycles

            names = available_drive_cycles()
            if value not in names:
                raise ValueError(f"cycle = {value!r} is not a drive cycle (available: "
                                 f"{', '.join(names)}; or a constant speed in m/s)")
            return value
        v = _number(value, key)
        if not 0.0 <= v <= MAX_SPEED_M_S:
            raise ValueError(f"cycle = {v:g} m/s must lie in 0..{MAX_SPEED_M_S:g} m/s")
        return v
    if key in ("duration_s", "warmup_s", "tail_s"):
        v = _number(value, key)
        if not 0.0 <= v <= MAX_DURATION_S:
            raise ValueError(f"{key} = {v:g} must lie in 0..{MAX_DURATION_S:g} s")
        if key == "duration_s" and 0.0 < v < 10.0:
            raise ValueError(f"duration_s = {v:g} is shorter than two samples (10 s)")
        return v
    if key in RANGES:
        v = _number(value, key)
        lo, hi = RANGES[key]
        if not lo <= v <= hi:
            unit = {"ambient_C": "degC", "humidity_pct": "%", "solar_W_m2": "W/m2",
                    "setpoint_C": "degC"}[key]
            raise ValueError(f"{key} = {v:g} must lie in {lo:g}..{hi:g} {unit}")
        return v
    if key == "refrigerant":
        if value not in REFRIGERANTS:
            raise ValueError(f"refrigerant = {value!r} not supported (choose "
                             f"{' or '.join(REFRIGERANTS)})")
        return value
    if key == "band_C":
        if not isinstance(value, (list, tuple)) or len(value) != 2:
            raise ValueError(f"band_C = {value!r} must be [low, high] in degC")
        lo, hi = (_number(v, key) for v in value)
        if not (15.0 <= lo < hi <= 32.0):
            raise ValueError(f"band_C = [{lo:g}, {hi:g}] must satisfy 15 <= low < high <= 32 "
                             "degC")
        return (lo, hi)
    if key == "params":
        if not isinstance(value, str) or not value:
            raise ValueError(f"params = {value!r} must be 'paper', 'identify' or a file")
        return value
    if key == "plant":
        if not isinstance(value, dict):
            raise ValueError(f"plant = {_show(value)} must be a table of PlantConfig fields")
        for k, v in value.items():
            if isinstance(v, (dict, list)):
                raise ValueError(f"plant.{k} must be a value, got a "
                                 f"{'table' if isinstance(v, dict) else 'list'} (plant "
                                 "overrides are flat: { V_disp = 4.0e-5 })")
        return dict(value)
    raise KeyError(key)


def _check_table(w: _Where, where: str, table, grid: bool = False) -> dict:
    if not isinstance(table, dict):
        raise w.error(where, "must be a table")
    out = {}
    for key, value in table.items():
        if key not in SCENARIO_KEYS:
            raise w.error(where, f"unknown key {key!r} (known: {', '.join(SCENARIO_KEYS)})")
        values = value if grid else [value]
        if grid:
            if not isinstance(value, list):
                raise w.error(where, f"{key} must be a list of values to sweep")
            if not value:
                raise w.error(where, f"{key} is empty: the grid has no scenario")
        try:
            checked = [_check_value(key, v) for v in values]
        except ValueError as exc:
            raise w.error(where, str(exc)) from None
        out[key] = checked if grid else checked[0]
    return out


def _params_source(w: _Where, spec: str, base: Path, allow_unstable: bool = False
                   ) -> ParamsSource:
    if spec in ("paper", "identify"):
        if spec == "paper":
            from acid.models.params import paper

            return ParamsSource(spec, "paper", paper())
        return ParamsSource(spec, "identify")
    from acid._io import file_sha256
    from acid.models.params import ModelParams

    path = Path(spec)
    path = path if path.is_absolute() else base / path
    if not path.is_file():
        raise w.error("params", f"{spec!r}: parameter file not found (or use 'paper', "
                                "'identify')")
    try:
        p = ModelParams.from_json(path)
    except AcidError as exc:
        raise w.error("params", f"{spec!r}: {exc}") from None
    problems = [] if allow_unstable else p.stability_problems()
    if problems:
        raise w.error("params", f"{spec!r}: {problems[0]} (--allow-unstable uses them anyway)")
    return ParamsSource(spec, "file", p, file_sha256(path))


def _controllers(w: _Where, table, plugins) -> tuple[tuple[ControllerEntry, ...],
                                                    tuple[str, ...]]:
    """The controllers in spec order, and the order to run them (a ``match`` after its
    target)."""
    from acid.studies.sweep.controllers import build_config

    if table is None:
        table = {name: {} for name in DEFAULT_CONTROLLERS}
    if not isinstance(table, dict) or not table:
        raise w.error("controllers", "give at least one controllers.LABEL table")
    entries = {}
    for label, t in table.items():
        where = f"controllers.{label}"
        if not _LABEL.match(label):
            raise w.error(where, "a label is a letter then letters, digits, - or _ (<= 32)")
        if not isinstance(t, dict):
            raise w.error(where, "must be a table")
        t = dict(t)
        kind = t.pop("type", label)
        if not isinstance(kind, str):
            raise w.error(where, f"type = {kind!r} must be a controller name")
        entry, config = build_config(kind, t, f"{w.source}: {where}", plugins)
        entries[label] = ControllerEntry(label, kind, config, entry.constructor)
    # a controller that matches another runs after it
    order: list[str] = []

    def visit(label, path):
        if label in order:
            return
        if label in path:
            raise w.error(f"controllers.{label}", "match forms a cycle: "
                          + " -> ".join([*path, label]))
        target = getattr(entries[label].config, "match", "")
        if target:
            if target not in entries:
                raise w.error(f"controllers.{label}", f"match = {target!r} is not a "
                              f"controller of this spec (have: {', '.join(entries)})")
            visit(target, [*path, label])
        order.append(label)

    for label in entries:
        visit(label, [])
    return tuple(entries.values()), tuple(order)


def load_spec(path: str | Path, allow_unstable: bool = False) -> SweepSpec:
    """Read and validate a sweep specification (TOML); see the module docstring.

    Parameter files with unstable or implausible eqs. 1-3 are refused (as by every other
    command) unless ``allow_unstable``."""
    from acid._readers import load_toml

    path = Path(path)
    d = load_toml(path, "sweep specification", ConfigError)
    return spec_from_dict(d, str(path), base=path.parent, path=path,
                          allow_unstable=allow_unstable)


def spec_from_dict(d: dict, source: str = "sweep spec", base: Path | None = None,
                   path: Path | None = None, allow_unstable: bool = False) -> SweepSpec:
    """Validate a parsed specification (``source`` names it in messages; relative parameter
    files are read from ``base``; unstable parameter files refused unless
    ``allow_unstable``)."""
    w = _Where(source)
    base = base or Path.cwd()
    for key in d:
        if key not in TOP_KEYS:
            hint = " (scenario keys go in the defaults, grid or scenarios tables)" \
                if key in SCENARIO_KEYS else ""
            raise w.error("", f"unknown key {key!r}{hint} (known: {', '.join(TOP_KEYS)})")
    title = d.get("title", path.stem if path else "sweep")
    if not isinstance(title, str):
        raise w.error("title", "must be a string")
    plugins = d.get("plugins", [])
    if not isinstance(plugins, list) or not all(isinstance(p, str) for p in plugins):
        raise w.error("plugins", "must be a list of module names")
    for mod in plugins:
        try:
            importlib.import_module(mod)
        except Exception as exc:  # any failure to import is the user's plugin
            raise w.error("plugins", f"cannot import {mod!r} ({type(exc).__name__}: "
                                     f"{str(exc).splitlines()[0] if str(exc) else ''})") from None
    defaults = {**SCENARIO_DEFAULTS, **_check_table(w, "defaults", d.get("defaults", {}))}
    grid = _check_table(w, "grid", d.get("grid", {}), grid=True)
    listed = d.get("scenarios", [])
    if not isinstance(listed, list):
        raise w.error("scenarios", "must be an array of tables (one [[scenarios]] each)")
    listed = [_check_table(w, f"scenarios #{i + 1}", t) for i, t in enumerate(listed)]
    n_grid = math.prod(len(v) for v in grid.values()) if grid else 0
    if n_grid + len(listed) == 0:
        raise w.error("", "no scenarios: give a grid table of values and/or scenarios tables")
    if n_grid + len(listed) > MAX_SCENARIOS:
        raise w.error("grid", f"{n_grid + len(listed)} scenarios: at most {MAX_SCENARIOS}")

    raw = []
    if grid:
        keys = list(grid)
        for i, combo in enumerate(itertools.product(*(grid[k] for k in keys))):
            raw.append((f"grid scenario #{i + 1} (" + ", ".join(
                f"{k} = {_show(v)}" for k, v in zip(keys, combo, strict=True)) + ")",
                dict(zip(keys, combo, strict=True))))
    raw += [(f"scenarios #{i + 1}", t) for i, t in enumerate(listed)]

    sources: dict[str, ParamsSource] = {}
    configs: dict = {}
    scenarios = []
    for where, over in raw:
        m = {**defaults, **over, "plant": {**defaults["plant"], **over.get("plant", {})}}
        try:
            cond = Conditions(ambient_C=m["ambient_C"], humidity_pct=m["humidity_pct"],
                              solar_W_m2=m["solar_W_m2"], refrigerant=m["refrigerant"],
                              setpoint_C=m["setpoint_C"], band_C=tuple(m["band_C"]))
        except ConfigError as exc:
            raise w.error(where, str(exc)) from None
        if m["params"] not in sources:
            sources[m["params"]] = _params_source(w, m["params"], base, allow_unstable)
        s = Scenario(cond, cycle=m["cycle"], duration_s=m["duration_s"],
                     warmup_s=m["warmup_s"], tail_s=m["tail_s"], params=m["params"],
                     plant=tuple(sorted(m["plant"].items())), origin=where)
        ck = (cond, s.plant)
        if ck not in configs:
            try:
                configs[ck] = s.plant_config()
            except ConfigError as exc:
                raise w.error(where, str(exc).replace("plant overrides: ", "plant: ")) from None
        run_s = s.duration_s or (CYCLE_PASS_BOUND_S if isinstance(s.cycle, str)
                                 else DEFAULT_CONSTANT_DURATION_S)
        total, cfg = s.warmup_s + run_s + s.tail_s, configs[ck]
        for n, per, what, most in ((total / cfg.Ts, f"Ts = {cfg.Ts:g} s", "samples",
                                    MAX_SCENARIO_SAMPLES),
                                   (total / cfg.dt_int, f"dt_int = {cfg.dt_int:g} s",
                                    "internal steps", MAX_SCENARIO_STEPS)):
            if n > most:
                raise w.error(where, f"warmup_s + duration_s + tail_s = {total:g} s at the "
                                     f"plant's {per} is {n:.0f} {what} (at most {most})")
        scenarios.append(s)

    controllers, run_order = _controllers(w, d.get("controllers"), tuple(plugins))
    labels = [c.label for c in controllers]
    baseline = d.get("baseline", labels[0])
    if baseline not in labels:
        raise w.error("baseline", f"{baseline!r} is not a controller of this spec (have: "
                                  f"{', '.join(labels)})")
    ident = d.get("identify", {})
    if not isinstance(ident, dict):
        raise w.error("identify", "must be a table")
    kinds = {"duration_s": "number", "seed": "integer", "method": "string",
             "speed_m_s": "number"}
    for k, v in ident.items():
        if k not in kinds:
            raise w.error("identify", f"unknown key {k!r} (known: {', '.join(kinds)})")
        ok = {"number": isinstance(v, (int, float)) and not isinstance(v, bool),
              "integer": isinstance(v, int) and not isinstance(v, bool),
              "string": isinstance(v, str)}[kinds[k]]
        if not ok:
            raise w.error("identify", f"{k} = {v!r} must be a {kinds[k]}")
    try:
        identify = IdentifySettings(**{k: (float(v) if k in ("duration_s", "speed_m_s") else v)
                                       for k, v in ident.items()})
    except ConfigError as exc:
        raise w.error("identify", str(exc)) from None
    return SweepSpec(title=title, scenarios=tuple(scenarios), controllers=controllers,
                     run_order=run_order, baseline=baseline, params=sources,
                     identify=identify,
                     plugins=tuple(plugins), path=path, allow_unstable=allow_unstable)


def _show(v) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, tuple):
        return "[" + ", ".join(_show(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_show(x)}" for k, x in v.items()) + "}"
    return repr(v) if isinstance(v, str) else str(v)


__all__ = ["load_spec", "spec_from_dict", "SweepSpec", "Scenario", "ControllerEntry",
           "IdentifySettings", "ParamsSource"]
