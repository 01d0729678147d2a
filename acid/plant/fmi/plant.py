"""Bring your own plant: an FMI 2.0 / 3.0 co-simulation FMU as an acid plant (through fmpy).

A user's high-fidelity A/C and cabin model (CoolSim in Simulink, Modelica/Dymola, GT-SUITE,
AMESim, or ``acid export-fmu``) is driven by every pipeline of acid through the plant protocol
of :mod:`acid.plant.base`. An *FMU map* (TOML, documented in ``datasets/FORMAT.md``) names the
FMU's variables for acid's channels and gives their units; acid converts at this edge, so
temperatures are kelvin inside as everywhere else.

Sample convention (row k of a dataset), as in :mod:`acid.plant.base`:

* ``[states]`` are read at the communication point t_k, before the step;
* ``[inputs]`` are set at t_k and held over [t_k, t_k + Ts);
* ``[outputs]`` are means over [t_k, t_k + Ts). The FMU is stepped ``Ts / step`` times with
  the communication step ``step`` (``Ts`` itself or a divisor of it). An output with
  ``sampling = "interval-mean"`` is already the mean over the FMU's last communication step
  (acid averages the sub-steps: exact); ``sampling = "instant"`` (the default for an FMU
  that reports instantaneous values) is averaged with the trapezoidal rule over the
  sub-step points t_k, t_k + step, ..., t_k + Ts.

Errors (a corrupt archive, a model-exchange-only FMU, a variable the FMU does not have, a
failed ``doStep``, an FMU that terminates the simulation, a non-finite value) raise
:class:`FmuError`: one line naming the FMU and the variable or call, with the FMU's own last
log message.
"""

from __future__ import annotations

import atexit
import collections
import difflib
import hashlib
import math
import os
import shutil
import tempfile
import weakref
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from acid.data import CHANNELS
from acid.errors import AcidError, ConfigError
from acid.plant.base import Measurement, Plant
from acid.units import BASE_DIMENSIONS, UNIT_SCALES, base_unit

__all__ = ["FmuError", "FmuMap", "FmuPlant", "VariableMap", "SAMPLINGS", "INPUT_CHANNELS",
           "fmi_unit_definition"]


class FmuError(AcidError):
    """An FMU cannot be used or failed while running (one line: FMU, variable, reason)."""


#: How an output's value relates to the communication step (see the module docstring).
SAMPLINGS = ("interval-mean", "instant")
#: Channels an FMU input may be mapped to: ``Plant.step``'s arguments and keywords.
INPUT_CHANNELS = ("W_bl", "T_evap_set", "v_veh", "T_amb", "T_int", "T_shell", "T_cab_set",
                  "compressor_enabled")
#: Inputs every map must give (what acid commands).
REQUIRED_INPUTS = ("W_bl", "T_evap_set")
#: States every map must give: the model's states and its measured disturbances.
REQUIRED_STATES = ("T_cab", "T_evap", "T_int", "T_shell")
#: Outputs every map must give: the model's output (eq. 3).
REQUIRED_OUTPUTS = ("T_ain",)
#: Sections of a map that name FMU variables.
VARIABLE_SECTIONS = ("inputs", "states", "outputs", "initial")
_MAP_KEYS = {"fmu", *VARIABLE_SECTIONS, "parameters", "modes"}
_BOOLEAN_INPUTS = ("compressor_enabled",)


# ------------------------------------------------------------------------------ units
#: FMI ``BaseUnit`` exponents (and factor) of acid's inside units, for the units an exported
#: FMU declares and for reading an FMU whose unit names acid does not know.
_FMI_BASE = BASE_DIMENSIONS  # the shared unit table's dimensions (acid.units)
_RPM_IN_RAD_PER_S = 2.0 * math.pi / 60.0
_DIMENSIONS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")


def fmi_unit_definition(unit: str) -> tuple[dict[str, int], float, float]:
    """``(exponents, factor, offset)`` of an FMI ``<BaseUnit>`` for an acid unit name.

    The FMI convention is ``value_SI = factor * value + offset``.
    """
    base, factor, offset = UNIT_SCALES[unit]
    if base == "rpm":
        factor *= _RPM_IN_RAD_PER_S
    return dict(_FMI_BASE[base]), float(factor), float(offset)


def _unit_from_fmi(defn) -> tuple[str, float, float] | None:
    """acid base unit, factor and offset of an fmpy ``Unit`` (None if acid has no match)."""
    bu = getattr(defn, "baseUnit", None)
    if bu is None:
        return None
    exps = {d: int(getattr(bu, d, 0) or 0) for d in _DIMENSIONS}
    exps = {d: e for d, e in exps.items() if e}
    factor, offset = float(bu.factor or 1.0), float(bu.offset or 0.0)
    for base, want in _FMI_BASE.items():
        if want == exps and base not in ("kg/kg",):
            if base == "rpm":
                return base, factor / _RPM_IN_RAD_PER_S, offset / _RPM_IN_RAD_PER_S
            return base, factor, offset
    return None


# -------------------------------------------------------------------------------- map
@dataclass(frozen=True)
class VariableMap:
    """One FMU variable mapped to an acid channel.

    Attributes
    ----------
    channel : acid's channel name (or initial-condition key).
    name : the FMU variable's name (as in its modelDescription.xml).
    unit : the unit the FMU variable is in (acid converts); None to take the FMU's declared
        unit.
    sampling : outputs only: "interval-mean" or "instant" (module docstring).
    """

    channel: str
    name: str
    unit: str | None = None
    sampling: str = "instant"

    def to_json_dict(self) -> dict:
        return {"name": self.name, "unit": self.unit, "sampling": self.sampling}


def _read_toml(path: Path, what: str) -> dict:
    from acid._readers import load_toml

    return load_toml(path, what, ConfigError)


@dataclass(frozen=True)
class FmuMap:
    """Which FMU variables are acid's channels, in which units; start values, parameters.

    Read with :meth:`from_file` (TOML, ``datasets/FORMAT.md``). ``Ts`` is acid's sample
    period (s); ``step`` the FMU communication step (s), ``Ts`` or a divisor of it (default
    ``Ts``). ``parameters`` are set before every initialisation (variable name -> value, or
    ``{value, unit}`` to have acid convert; a bare number is in the FMU's own unit);
    ``modes`` maps a plant mode (``"direct"``, ``"nominal"``) to more such settings.
    """

    inputs: Mapping[str, VariableMap]
    states: Mapping[str, VariableMap]
    outputs: Mapping[str, VariableMap]
    initial: Mapping[str, VariableMap] = field(default_factory=dict)
    parameters: Mapping[str, object] = field(default_factory=dict)
    modes: Mapping[str, Mapping[str, object]] = field(default_factory=dict)
    Ts: float = 5.0
    step: float | None = None
    label: str = "fmu"
    source: str = "FMU map"

    @classmethod
    def from_file(cls, path: str | os.PathLike) -> FmuMap:
        """Read and check a TOML map (one-line ``ConfigError`` naming file and key)."""
        path = Path(path)
        return cls.from_dict(_read_toml(path, "FMU map"), source=str(path))

    @classmethod
    def from_dict(cls, d: dict, source: str = "FMU map") -> FmuMap:
        unknown = sorted(set(d) - _MAP_KEYS)
        if unknown:
            raise ConfigError(f"{source}: unknown section [{unknown[0]}] "
                              f"(known: {', '.join(sorted(_MAP_KEYS))})")
        head = d.get("fmu", {})
        if not isinstance(head, Mapping):
            raise ConfigError(f"{source}: [fmu] must be a table")
        for key in head:
            if key not in ("Ts", "step", "label"):
                raise ConfigError(f"{source}: unknown key {key!r} in [fmu] "
                                  "(known: Ts, step, label)")
        Ts = _positive(head.get("Ts", 5.0), f"{source}: [fmu] Ts")
        step = head.get("step")
        step = None if step is None else _positive(step, f"{source}: [fmu] step")
        sections = {}
        for sec in VARIABLE_SECTIONS:
            table = d.get(sec, {})
            if not isinstance(table, Mapping):
                raise ConfigError(f"{source}: [{sec}] must be a table of channel = "
                                  "{ name = ..., unit = ... } entries")
            sections[sec] = {ch: _variable(sec, ch, spec, source) for ch, spec in table.items()}
        for ch in sections["inputs"]:
            if ch not in INPUT_CHANNELS:
                raise ConfigError(f"{source}: [inputs] {ch}: not an input acid drives "
                                  f"(one of {', '.join(INPUT_CHANNELS)})")
        for sec, required in (("inputs", REQUIRED_INPUTS), ("states", REQUIRED_STATES),
                              ("outputs", REQUIRED_OUTPUTS)):
            for ch in required:
                if ch not in sections[sec]:
                    raise ConfigError(f"{source}: [{sec}] must map {ch} "
                                      f"(required: {', '.join(required)})")
        both = set(sections["states"]) & set(sections["outputs"])
        if both:
            raise ConfigError(f"{source}: channel {sorted(both)[0]!r} is in both [states] "
                              "and [outputs]")
        params = d.get("parameters", {})
        modes = d.get("modes", {})
        if not isinstance(params, Mapping) or not isinstance(modes, Mapping):
            raise ConfigError(f"{source}: [parameters] and [modes.<mode>] must be tables")
        for mode, table in modes.items():
            if mode not in ("direct", "nominal") or not isinstance(table, Mapping):
                raise ConfigError(f"{source}: [modes.{mode}]: modes are 'direct' and "
                                  "'nominal', each a table of variable = value")
        return cls(inputs=sections["inputs"], states=sections["states"],
                   outputs=sections["outputs"], initial=sections["initial"],
                   parameters=dict(params), modes={k: dict(v) for k, v in modes.items()},
                   Ts=Ts, step=step, label=str(head.get("label", "fmu")), source=source)

    @property
    def communication_step(self) -> float:
        """The FMU communication step, s (``step`` or ``Ts``)."""
        return self.Ts if self.step is None else self.step

    def to_json_dict(self) -> dict:
        d = {"source": self.source, "Ts": self.Ts, "step": self.communication_step,
             "label": self.label, "parameters": dict(self.parameters),
             "modes": {k: dict(v) for k, v in self.modes.items()}}
        for sec in VARIABLE_SECTIONS:
            d[sec] = {ch: v.to_json_dict() for ch, v in getattr(self, sec).items()}
        return d


def _positive(value, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
            math.isfinite(value) and value > 0):
        raise ConfigError(f"{what} must be a positive number of seconds, got {value!r}")
    return float(value)


def _variable(section: str, channel: str, spec, source: str) -> VariableMap:
    where = f"{source}: [{section}] {channel}"
    if isinstance(spec, str):
        spec = {"name": spec}
    if not isinstance(spec, Mapping) or "name" not in spec:
        raise ConfigError(f"{where}: needs {{ name = \"<FMU variable>\", unit = \"...\" }}")
    extra = set(spec) - {"name", "unit", "sampling"}
    if extra:
        raise ConfigError(f"{where}: unknown key {sorted(extra)[0]!r} "
                          "(known: name, unit, sampling)")
    unit = spec.get("unit")
    if unit is not None and unit not in UNIT_SCALES:
        raise ConfigError(f"{where}: unknown unit {unit!r} (known: {', '.join(UNIT_SCALES)})")
    sampling = spec.get("sampling", "instant")
    if sampling not in SAMPLINGS:
        raise ConfigError(f"{where}: sampling must be one of {', '.join(SAMPLINGS)}, "
                          f"got {sampling!r}")
    if "sampling" in spec and section != "outputs":
        raise ConfigError(f"{where}: sampling applies to [outputs] only")
    return VariableMap(channel=str(channel), name=str(spec["name"]),
                       unit=None if unit is None else str(unit), sampling=str(sampling))


# ------------------------------------------------------------------- FMU archives
#: (path, size, mtime) -> (model description, extracted folder): an FMU is read, validated
#: and unpacked once per process however many plants are built from it
_EXTRACTED: dict[tuple, tuple] = {}


def _cleanup_extracted() -> None:
    for _md, folder in _EXTRACTED.values():
        shutil.rmtree(folder, ignore_errors=True)
    _EXTRACTED.clear()


atexit.register(_cleanup_extracted)


def _file_key(path: Path) -> tuple:
    st = path.stat()
    return (str(path.resolve()), st.st_size, st.st_mtime_ns)


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _open_fmu(path: Path):
    """(model description, extracted folder) of an FMU; one-line errors for bad archives."""
    if not path.is_file():
        raise FmuError(f"{path}: FMU not found")
    key = _file_key(path)
    cached = _EXTRACTED.get(key)
    if cached is not None and os.path.isdir(cached[1]):
        return cached
    import zipfile

    try:
        from fmpy import read_model_description
    except ImportError:
        raise FmuError(f"{path}: FMU plants need fmpy (pip install 'acid[fmi]')") from None
    if not zipfile.is_zipfile(path):
        raise FmuError(f"{path}: not a valid FMU (not a zip archive)")
    try:
        with zipfile.ZipFile(path) as z:
            check_archive(path, z.infolist())
    except (zipfile.BadZipFile, OSError, ValueError) as exc:
        raise FmuError(f"{path}: not a valid FMU ({type(exc).__name__})") from None
    try:
        md = read_model_description(str(path), validate=True)
    except Exception as exc:
        msg = " ".join(str(exc).split()) or type(exc).__name__
        raise FmuError(f"{path}: not a valid FMU (modelDescription.xml: {msg[:300]})") from None
    if not str(md.fmiVersion).startswith(("2.", "3.")):
        raise FmuError(f"{path}: FMI {md.fmiVersion} is not supported (acid runs FMI 2.0 and "
                       "3.0 co-simulation FMUs)")
    if md.coSimulation is None:
        kinds = "model exchange" if md.modelExchange is not None else "no co-simulation"
        raise FmuError(f"{path}: the FMU supports {kinds} only; acid needs an FMI "
                       f"{md.fmiVersion} co-simulation FMU (export it with co-simulation)")
    folder = _extract(path)
    _EXTRACTED[key] = (md, folder)
    return md, folder


#: most members and uncompressed bytes an FMU may hold (a large FMU with all platforms'
#: binaries and tables is some hundred MB and a few thousand files)
MAX_FMU_MEMBERS = 10_000
MAX_FMU_BYTES = 1 << 30


def check_archive(path: Path, members) -> None:
    """Refuse (``FmuError``) an archive with too many members, too many uncompressed bytes
    (a zip bomb: checked from the central directory before anything is extracted) or a
    member whose path escapes the extraction folder (absolute, ``..``, a drive letter)."""
    if len(members) > MAX_FMU_MEMBERS:
        raise FmuError(f"{path}: the FMU holds {len(members)} files (at most "
                       f"{MAX_FMU_MEMBERS})")
    total = sum(max(int(m.file_size), 0) for m in members)
    if total > MAX_FMU_BYTES:
        raise FmuError(f"{path}: the FMU unpacks to {total / 2**20:.0f} MB (at most "
                       f"{MAX_FMU_BYTES >> 20} MB)")
    for m in members:
        name = m.filename.replace("\\", "/")
        parts = [p for p in name.split("/") if p not in ("", ".")]
        if name.startswith("/") or ".." in parts or (parts and ":" in parts[0]):
            raise FmuError(f"{path}: the FMU member {m.filename!r} escapes its folder")


def _extract(path: Path) -> str:
    """Unpack an FMU into a new temporary folder (removed again on every failure)."""
    import zipfile

    folder = tempfile.mkdtemp(prefix="acid-fmu-")
    try:
        try:
            with zipfile.ZipFile(path) as z:
                members = z.infolist()
                check_archive(path, members)
                for m in members:
                    z.extract(m, folder)
        except (zipfile.BadZipFile, OSError, ValueError, RuntimeError, EOFError,
                NotImplementedError) as exc:
            msg = " ".join(str(exc).split()) or type(exc).__name__
            raise FmuError(f"{path}: cannot extract the FMU ({msg[:200]})") from None
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return folder


# ---------------------------------------------------------------- FMI instances
class _Instance:
    """One instantiated co-simulation FMU (FMI 2.0 or 3.0) with a captured log."""

    def __init__(self, md, folder: str, fmu_name: str, instance_name: str):
        self.md, self.folder, self.fmu_name = md, folder, fmu_name
        self.version = 3 if str(md.fmiVersion).startswith("3.") else 2
        self.log: collections.deque[str] = collections.deque(maxlen=20)
        ident = md.coSimulation.modelIdentifier
        try:
            if self.version == 3:
                from fmpy.fmi3 import FMU3Slave

                self.fmu = FMU3Slave(guid=md.instantiationToken, unzipDirectory=folder,
                                     modelIdentifier=ident, instanceName=instance_name)
            else:
                from fmpy.fmi2 import FMU2Slave

                self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                                     modelIdentifier=ident, instanceName=instance_name)
        except Exception as exc:
            raise FmuError(f"{fmu_name}: cannot load the FMU's binary for this platform "
                           f"({' '.join(str(exc).split())})") from None
        self.alive = False
        self.broken = False
        self._instantiate()

    # -- logging callbacks (kept referenced so that ctypes does not free them)
    def _remember(self, status: int, category, message) -> None:
        text = message.decode("utf-8", "replace") if isinstance(message, bytes) else str(message)
        self.log.append(" ".join(text.split()))

    def last_message(self) -> str:
        return self.log[-1] if self.log else ""

    def _instantiate(self) -> None:
        try:
            if self.version == 3:
                self._cb = lambda env, status, category, message: self._remember(
                    status, category, message)
                self.fmu.instantiate(loggingOn=True, logMessage=self._cb)
            else:
                from ctypes import byref

                from fmpy import calloc, free
                from fmpy.fmi2 import (
                    fmi2CallbackAllocateMemoryTYPE,
                    fmi2CallbackFreeMemoryTYPE,
                    fmi2CallbackFunctions,
                    fmi2CallbackLoggerTYPE,
                )

                cb = fmi2CallbackFunctions()
                cb.logger = fmi2CallbackLoggerTYPE(
                    lambda env, name, status, category, message: self._remember(
                        status, category, message))
                cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
                cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
                try:
                    from fmpy.logging import addLoggerProxy

                    addLoggerProxy(byref(cb))
                except Exception:  # the proxy only formats printf arguments
                    pass
                self._cb = cb
                self.fmu.instantiate(callbacks=cb, loggingOn=True)
        except Exception as exc:
            raise self.error("instantiation failed", exc) from None
        self.alive = True

    def error(self, what: str, exc: Exception | None = None) -> FmuError:
        said = self.last_message()
        detail = f" (FMU says: {said[-400:]})" if said else (
            f" ({' '.join(str(exc).split())})" if exc is not None else "")
        return FmuError(f"{self.fmu_name}: {what}{detail}")

    def call(self, what: str, fn, *args):
        try:
            return fn(*args)
        except FmuError:
            raise
        except Exception as exc:
            if getattr(exc, "status", 3) >= 3:  # error or fatal: no further FMI calls
                self.broken = True
            raise self.error(what, exc) from None

    # -- FMI calls, version-independent
    def initialize(self, start_time: float = 0.0) -> None:
        if self.version == 3:
            self.call("fmi3EnterInitializationMode failed",
                      lambda: self.fmu.enterInitializationMode(startTime=start_time))
            self.call("fmi3ExitInitializationMode failed", self.fmu.exitInitializationMode)
        else:
            self.call("fmi2SetupExperiment failed",
                      lambda: self.fmu.setupExperiment(startTime=start_time))
            self.call("fmi2EnterInitializationMode failed", self.fmu.enterInitializationMode)
            self.call("fmi2ExitInitializationMode failed", self.fmu.exitInitializationMode)

    def reset(self) -> None:
        try:
            self.fmu.reset()
        except Exception:  # an FMU without a working reset: instantiate anew
            self.log.clear()
            free = self.fmu.fmi3FreeInstance if self.version == 3 else \
                self.fmu.fmi2FreeInstance
            try:
                free(self.fmu.component)
            except Exception:
                pass
            self._instantiate()

    def get_real(self, vrs: list[int]) -> list[float]:
        fn = self.fmu.getFloat64 if self.version == 3 else self.fmu.getReal
        return fn(vrs)

    def set_real(self, vrs: list[int], values: list[float]) -> None:
        fn = self.fmu.setFloat64 if self.version == 3 else self.fmu.setReal
        fn(vrs, values)

    def set_value(self, var, value) -> None:
        """Set one variable of any type (parameters and start values)."""
        t = var.type
        vr = [var.valueReference]
        if t in ("Real", "Float64", "Float32"):
            (self.fmu.setFloat32 if t == "Float32" else
             (self.fmu.setFloat64 if self.version == 3 else self.fmu.setReal))(vr, [float(value)])
        elif t == "Boolean":
            self.fmu.setBoolean(vr, [bool(value)])
        elif t in ("Integer", "Int32", "Enumeration"):
            (self.fmu.setInt32 if self.version == 3 and t == "Int32" else
             (self.fmu.setInt64 if self.version == 3 and t == "Enumeration" else
              self.fmu.setInteger))(vr, [int(value)])
        elif t == "String":
            self.fmu.setString(vr, [str(value)])
        else:
            raise FmuError(f"{self.fmu_name}: cannot set variable {var.name!r} of type {t}")

    def do_step(self, t: float, h: float) -> None:
        fn = "fmi3DoStep" if self.version == 3 else "fmi2DoStep"
        try:
            result = self.fmu.doStep(t, h)
        except Exception as exc:
            status = getattr(exc, "status", None)
            if status is None or status >= 3:  # error or fatal: no further FMI calls
                self.broken = True
            if self.version == 2 and status == 2 and self._terminated():
                raise self.error(f"the FMU terminated the simulation at t = {t:g} s") from None
            label = {1: "warning", 2: "discard", 3: "error", 4: "fatal"}.get(status, "failed")
            raise self.error(f"{fn} from t = {t:g} s over {h:g} s failed ({label})",
                             exc) from None
        if self.version == 3 and result is not None:
            _event, terminate, early, last = result
            if terminate:
                raise self.error(f"the FMU terminated the simulation at t = {t:g} s")
            if early:
                raise self.error(f"{fn} returned early at t = {last:g} s (acid needs whole "
                                 "communication steps)")

    def _terminated(self) -> bool:
        try:
            from fmpy.fmi2 import fmi2Terminated

            return bool(self.fmu.getBooleanStatus(fmi2Terminated))
        except Exception:
            return False

    def close(self) -> None:
        """Terminate and free the instance; the shared library stays loaded (unloading a
        library that embeds Python, as pythonfmu's do, can crash the process). After an
        error or fatal status FMI forbids further calls: the instance is then left alone."""
        if not self.alive:
            return
        self.alive = False
        if self.broken:
            return
        free = self.fmu.fmi3FreeInstance if self.version == 3 else self.fmu.fmi2FreeInstance
        for fn in (self.fmu.terminate, lambda: free(self.fmu.component)):
            try:
                fn()
            except Exception:
                pass


# ---------------------------------------------------------------------- the plant
@dataclass(frozen=True)
class _Resolved:
    """A mapped variable resolved against the FMU: value reference and unit conversion."""

    channel: str
    var: object
    unit: str          # the FMU-side unit (acid name or the FMU's declared name)
    base: str          # acid's inside unit
    factor: float      # acid = fmu * factor + offset
    offset: float
    sampling: str = "instant"

    @property
    def vr(self) -> int:
        return int(self.var.valueReference)

    def to_acid(self, value: float) -> float:
        return value * self.factor + self.offset

    def to_fmu(self, value: float) -> float:
        return (value - self.offset) / self.factor


class FmuPlant(Plant):
    """An FMI 2.0 / 3.0 co-simulation FMU driven through the plant protocol.

    Parameters
    ----------
    path : the ``.fmu`` file.
    fmu_map : an :class:`FmuMap` or the path of its TOML file.
    mode : "direct" (acid commands W_bl and T_evap_set) or "nominal" (the FMU's own
        controller; the map's ``[modes.nominal]`` settings select it).
    meas_noise_std : std of white noise added to the recorded T_cab, T_evap, T_ain, K (as
        ``HifiPlant`` does, same draws from ``rng``).
    rng : random generator for the noise.
    T_amb : ambient temperature, K, set on the mapped ``T_amb`` input before every
        initialisation (None: the FMU's own).

    Notes
    -----
    ``reset`` re-initialises the FMU (``fmi2Reset``/``fmi3Reset``, or a new instance);
    ``close`` frees it (also done when the plant is garbage-collected).
    """

    name = "fmu"

    def __init__(self, path: str | os.PathLike, fmu_map: FmuMap | str | os.PathLike,
                 mode: str = "direct", meas_noise_std: float = 0.0,
                 rng: np.random.Generator | None = None, T_amb: float | None = None,
                 instance_name: str = "acid"):
        if mode not in ("direct", "nominal"):
            raise ConfigError(f"plant mode {mode!r} unknown (choose 'direct' or 'nominal')")
        if meas_noise_std < 0:
            raise ConfigError(f"meas_noise_std must not be negative, got {meas_noise_std}")
        self.path = Path(path)
        self.fmu_name = self.path.name
        self.map = fmu_map if isinstance(fmu_map, FmuMap) else FmuMap.from_file(fmu_map)
        self.mode = mode
        self.meas_noise_std = float(meas_noise_std)
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.T_amb_override = None if T_amb is None else float(T_amb)
        self.Ts = float(self.map.Ts)
        h = self.map.communication_step
        n_sub = round(self.Ts / h)
        if n_sub < 1 or abs(n_sub * h - self.Ts) > 1e-9 * self.Ts:
            raise ConfigError(f"{self.map.source}: [fmu] step = {h:g} s must divide "
                              f"Ts = {self.Ts:g} s")
        self.h, self.n_sub = float(h), int(n_sub)
        if mode == "nominal" and "nominal" not in self.map.modes:
            raise ConfigError(f"{self.map.source}: no [modes.nominal] table: the FMU's own "
                              "(nominal) controller cannot be selected")
        fresh = self.path.is_file() and _file_key(self.path) not in _EXTRACTED
        self.md, folder = _open_fmu(self.path)
        try:
            self.fmi_version = str(self.md.fmiVersion)
            self._vars = {v.name: v for v in self.md.modelVariables}
            self._units = {u.name: u for u in (self.md.unitDefinitions or [])}
            self._resolve_all()
            self._embedded = self._read_embedded(folder)
            self._inst = _Instance(self.md, folder, self.fmu_name, instance_name)
        except BaseException:  # a rejected FMU (map, binary): its unpacked copy goes now
            if fresh:
                _EXTRACTED.pop(_file_key(self.path), None)
                shutil.rmtree(folder, ignore_errors=True)
            raise
        self._finalizer = weakref.finalize(self, self._inst.close)
        self._finalizer.atexit = False  # no FMI calls while the interpreter shuts down
        self._state: dict[str, float] = {}
        self._inputs_now: dict[str, float] = {}
        self.t = 0.0
        self.reset()

    # ------------------------------------------------------------ resolution
    def _lookup(self, section: str, vmap: VariableMap):
        var = self._vars.get(vmap.name)
        if var is None:
            close = difflib.get_close_matches(vmap.name, list(self._vars), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise FmuError(f"{self.map.source}: [{section}] {vmap.channel} names variable "
                           f"{vmap.name!r}, which {self.fmu_name} does not have{hint}")
        return var

    def _declared_unit(self, var) -> str | None:
        unit = getattr(var, "unit", None)
        if unit is None and getattr(var, "declaredType", None) is not None:
            unit = getattr(var.declaredType, "unit", None)
        return unit or None

    def _conversion(self, section: str, vmap: VariableMap, var) -> _Resolved:
        where = f"{self.map.source}: [{section}] {vmap.channel} ({self.fmu_name} {var.name!r})"
        declared = self._declared_unit(var)
        if declared is not None and declared in UNIT_SCALES:
            fmu_side = (declared, *UNIT_SCALES[declared])
        elif declared is not None and declared in self._units:
            conv = _unit_from_fmi(self._units[declared])
            fmu_side = None if conv is None else (declared, *conv)
        else:
            fmu_side = None
        if vmap.unit is not None:
            mine = (vmap.unit, *UNIT_SCALES[vmap.unit])
            if fmu_side is not None and (fmu_side[1] != mine[1] or not (
                    math.isclose(fmu_side[2], mine[2]) and math.isclose(fmu_side[3], mine[3],
                                                                       abs_tol=1e-9))):
                raise FmuError(f"{where}: the map says unit {vmap.unit!r} but the FMU "
                               f"declares {declared!r}")
            unit, base, factor, offset = mine
        elif fmu_side is not None:
            unit, base, factor, offset = fmu_side
        else:
            said = f"declares {declared!r}, which acid does not know" if declared else \
                "declares no unit"
            raise FmuError(f"{where}: give its unit in the map (unit = \"...\"); the FMU "
                           f"{said}")
        expected = self._expected_base(vmap.channel)
        if expected is not None and base != expected:
            raise FmuError(f"{where}: unit {unit!r} measures {base}, but {vmap.channel} is "
                           f"in {expected}")
        return _Resolved(channel=vmap.channel, var=var, unit=unit, base=base,
                         factor=float(factor), offset=float(offset), sampling=vmap.sampling)

    @staticmethod
    def _expected_base(channel: str) -> str | None:
        spec = CHANNELS.get(channel)
        if spec is not None:
            return base_unit(spec.unit)
        if channel in ("T_cab_set", "T_cw"):
            return "K"
        return None

    def _resolve_all(self) -> None:
        real = ("Real", "Float64", "Float32")
        self._in: dict[str, _Resolved] = {}
        self._bool_in: dict[str, object] = {}
        for ch, vm in self.map.inputs.items():
            var = self._lookup("inputs", vm)
            if ch in _BOOLEAN_INPUTS:
                if var.type != "Boolean":
                    raise FmuError(f"{self.map.source}: [inputs] {ch}: {self.fmu_name} "
                                   f"variable {var.name!r} is {var.type}, not Boolean")
                self._bool_in[ch] = var
                continue
            self._check_settable("inputs", vm, var, inputs=True)
            self._in[ch] = self._conversion("inputs", vm, var)
        self._st = {ch: self._conversion("states", vm, self._lookup("states", vm))
                    for ch, vm in self.map.states.items()}
        self._out = {ch: self._conversion("outputs", vm, self._lookup("outputs", vm))
                     for ch, vm in self.map.outputs.items()}
        self._init = {}
        for ch, vm in self.map.initial.items():
            var = self._lookup("initial", vm)
            self._check_settable("initial", vm, var)
            self._init[ch] = self._conversion("initial", vm, var)
        for sec, table in (("states", self._st), ("outputs", self._out)):
            for ch, r in table.items():
                if r.var.type not in real:
                    raise FmuError(f"{self.map.source}: [{sec}] {ch}: {self.fmu_name} "
                                   f"variable {r.var.name!r} is {r.var.type}, not Real")
        self._settings = {"parameters": self._resolve_settings("parameters",
                                                               self.map.parameters)}
        for mode, table in self.map.modes.items():
            self._settings[mode] = self._resolve_settings(f"modes.{mode}", table)
        # keywords of ``step`` that hold for one step only (as in ``HifiPlant.step``): when
        # not given, their FMU input returns to its start value
        self._per_step_defaults = {}
        if "compressor_enabled" in self._bool_in:
            self._per_step_defaults["compressor_enabled"] = True
        r = self._in.get("T_cab_set")
        if r is not None and r.var.start is not None:
            self._per_step_defaults["T_cab_set"] = r.to_acid(float(r.var.start))
        self._read = list(self._st.values()) + list(self._out.values())
        self._read_vrs = [r.vr for r in self._read]
        self._instant = [i for i, r in enumerate(self._read)
                         if r.channel in self._out and r.sampling == "instant"]

    def _check_settable(self, section: str, vm: VariableMap, var, inputs: bool = False) -> None:
        ok = var.causality == "input" if inputs else (
            var.causality in ("parameter", "input") or var.initial in ("exact", "approx"))
        if not ok:
            kind = "an input" if inputs else "a parameter or start value"
            raise FmuError(f"{self.map.source}: [{section}] {vm.channel}: {self.fmu_name} "
                           f"variable {var.name!r} is not {kind} (causality "
                           f"{var.causality})")

    def _resolve_settings(self, section: str, table: Mapping) -> list[tuple[object, object]]:
        out = []
        for name, value in table.items():
            var = self._lookup(section, VariableMap(channel=name, name=name))
            self._check_settable(section, VariableMap(channel=name, name=name), var)
            if isinstance(value, Mapping):
                if "value" not in value:
                    raise ConfigError(f"{self.map.source}: [{section}] {name}: needs "
                                      "{ value = ..., unit = ... }")
                unit = value.get("unit")
                val = value["value"]
                if unit is not None:
                    if unit not in UNIT_SCALES:
                        raise ConfigError(f"{self.map.source}: [{section}] {name}: unknown "
                                          f"unit {unit!r}")
                    conv = self._conversion(section, VariableMap(channel=name, name=name),
                                            var)
                    _, f, o = UNIT_SCALES[unit]
                    val = conv.to_fmu(float(val) * f + o)
                value = val
            out.append((var, value))
        return out

    @staticmethod
    def _read_embedded(folder: str) -> dict | None:
        spec = Path(folder) / "resources" / "acid_plant.json"
        if not spec.is_file():
            return None
        from acid._readers import load_json

        try:
            d = load_json(spec, "embedded plant description", FmuError)
        except AcidError:
            return None
        return {"acid_version": d.get("acid_version"), "config": d.get("config")}

    # -------------------------------------------------------------- protocol
    def config(self) -> dict:
        md = self.md
        d = {"fmu": str(self.path), "fmu_sha256": _sha256(self.path),
             "fmi_version": self.fmi_version, "model_name": md.modelName,
             "model_identifier": md.coSimulation.modelIdentifier,
             "generation_tool": md.generationTool, "guid": md.guid or
             getattr(md, "instantiationToken", None), "mode": self.mode,
             "communication_step_s": self.h, "substeps": self.n_sub,
             "meas_noise_std_K": self.meas_noise_std, "T_amb_K": self.T_amb_override,
             "map": self.map.to_json_dict()}
        if self._embedded is not None:
            d["embedded"] = self._embedded
        return d

    def units(self) -> dict[str, str]:
        """Inside units of the mapped states and outputs (temperatures in K)."""
        return {ch: r.base for ch, r in {**self._st, **self._out}.items()}

    def close(self) -> None:
        """Terminate and free the FMU instance (the plant cannot be used afterwards)."""
        self._finalizer()

    def reset(self, initial: dict[str, float] | None = None) -> Measurement:
        """Re-initialise the FMU: parameters, mode settings, ambient and start values (K)."""
        initial = dict(initial or {})
        for key, value in initial.items():
            if key not in self._init:
                raise ConfigError(f"{self.map.source}: no [initial] entry for {key!r}: the "
                                  f"FMU's start value for it is not mapped (mapped: "
                                  f"{', '.join(self._init) or 'none'})")
            value = float(value)
            if self._init[key].base == "K" and not 200.0 < value < 400.0:
                raise ConfigError(f"initial {key} = {value} K is implausible (temperatures "
                                  "are in kelvin)")
        if self.T_amb_override is not None and "T_amb" not in self._in:
            raise ConfigError(f"{self.map.source}: the ambient temperature is set but the "
                              "map has no [inputs] T_amb")
        inst = self._inst
        if not inst.alive or inst.broken:
            raise FmuError(f"{self.fmu_name}: the FMU instance was closed or failed; "
                           "create a new plant")
        if self.t > 0.0 or self._state:
            inst.reset()
        settings = list(self._settings["parameters"]) + list(self._settings.get(self.mode, []))
        for var, value in settings:
            inst.call(f"cannot set parameter {var.name!r}", inst.set_value, var, value)
        if self.T_amb_override is not None:
            r = self._in["T_amb"]
            inst.call(f"cannot set input {r.var.name!r}", inst.set_real, [r.vr],
                      [r.to_fmu(self.T_amb_override)])
        for key, value in initial.items():
            r = self._init[key]
            inst.call(f"cannot set start value {r.var.name!r}", inst.set_real, [r.vr],
                      [r.to_fmu(float(value))])
        inst.initialize(0.0)
        self.t = 0.0
        self._inputs_now = {}
        values = self._read_all()
        self._state = {ch: values[i] for i, ch in enumerate(self._st)}
        return self.measure()

    def measure(self) -> Measurement:
        """The mapped states at the current communication point (K)."""
        m = dict(self._state)
        if "T_amb" not in m and "T_amb" in self._inputs_now:
            m["T_amb"] = self._inputs_now["T_amb"]
        return m

    def _read_all(self) -> list[float]:
        inst = self._inst
        raw = inst.call(f"cannot read outputs at t = {self.t:g} s", inst.get_real,
                        self._read_vrs)
        values = [r.to_acid(v) for r, v in zip(self._read, raw, strict=True)]
        for r, v in zip(self._read, values, strict=True):
            if not math.isfinite(v):
                raise FmuError(f"{self.fmu_name}: variable {r.var.name!r} ({r.channel}) is "
                               f"{v} at t = {self.t:g} s")
        return values

    def step(self, W_bl: float, T_evap_set: float, v_veh: float = 0.0, **kw) -> Measurement:
        """Set the inputs, advance the FMU by Ts (in ``Ts / step`` communication steps) and
        return row k: states at t_k, the inputs, outputs as means over the step (K inside).

        Keywords: ``T_amb`` (K), ``compressor_enabled``, ``T_cab_set`` (K) where the map has
        them; ``T_int`` and ``T_shell`` are accepted and ignored unless mapped.
        """
        if not self._inst.alive or self._inst.broken:
            raise FmuError(f"{self.fmu_name}: the FMU instance was closed or failed; "
                           "create a new plant")
        values = {"W_bl": W_bl, "T_evap_set": T_evap_set, "v_veh": v_veh}
        values.update(self._per_step_defaults)  # keywords hold for one step only
        for key, value in kw.items():
            if key not in INPUT_CHANNELS:
                raise ConfigError(f"FmuPlant.step: unknown keyword {key!r}")
            values[key] = value
        inst = self._inst
        vrs, vals = [], []
        for ch, value in values.items():
            if ch in self._bool_in:
                var = self._bool_in[ch]
                inst.call(f"cannot set input {var.name!r}", inst.fmu.setBoolean,
                          [var.valueReference], [bool(value)])
                continue
            if ch == "compressor_enabled":
                if not bool(value):
                    raise ConfigError(f"{self.map.source}: the compressor is switched off but "
                                      "the map has no [inputs] compressor_enabled")
                continue
            value = float(value)
            if not math.isfinite(value):
                raise ConfigError(f"non-finite input {ch} = {value}")
            if ch in self._in:
                r = self._in[ch]
                vrs.append(r.vr)
                vals.append(r.to_fmu(value))
                self._inputs_now[ch] = value
            elif ch in ("T_int", "T_shell") or (ch == "v_veh" and value == 0.0):
                continue
            else:
                raise ConfigError(f"{self.map.source}: step gives {ch} but the map has no "
                                  f"[inputs] {ch}")
        if vrs:
            inst.call("cannot set inputs " + ", ".join(repr(self._vars_by_vr(v)) for v in vrs),
                      inst.set_real, vrs, vals)
        row: dict[str, float] = dict(self._state)
        for ch in ("W_bl", "T_evap_set", "v_veh"):
            row[ch] = float(values[ch])
        if "T_amb" in values or ("T_amb" not in row and "T_amb" in self._inputs_now):
            row["T_amb"] = self._inputs_now["T_amb"]  # the ambient over this step
        n_st = len(self._st)
        acc = np.zeros(len(self._read))
        if self._instant:
            now = self._read_all()
            for i in self._instant:
                acc[i] += 0.5 * now[i]
        for j in range(self.n_sub):
            t = self.t + j * self.h
            inst.do_step(t, self.h)
            now = np.asarray(self._read_all())
            acc += now
            if self._instant and j == self.n_sub - 1:
                acc[self._instant] -= 0.5 * now[self._instant]
        self.t += self.n_sub * self.h
        mean = acc / self.n_sub
        self._state = {ch: float(now[i]) for i, ch in enumerate(self._st)}
        for i, ch in enumerate(self._out):
            row[ch] = float(mean[n_st + i])
        if self.meas_noise_std:
            e = self.rng.standard_normal(3) * self.meas_noise_std
            for name, err in zip(("T_cab", "T_evap", "T_ain"), e, strict=True):
                if name in row:
                    row[name] += err
        return row

    def _vars_by_vr(self, vr: int) -> str:
        for r in self._in.values():
            if r.vr == vr:
                return r.var.name
        return str(vr)

