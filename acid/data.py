"""Datasets: uniformly sampled signals with names, roles, units and provenance (HDF5 on disk).

One layout, documented in ``datasets/FORMAT.md``:

    /                attrs: format="acid-dataset", format_version, Ts [s], title,
                            acid_version, created (ISO 8601), metadata (JSON string:
                            plant, plant_config, excitation, seed, source, ...)
    /time            float64 (N,), attrs unit="s"
    /experiment      int32 (N,): experiment id per sample; regressors never cross a change
    /channels/<name> float64 (N,), attrs unit, role, description
    /fine/...        optional fine-step trace with its own /fine/time and channels

Temperatures are stored in degC (the edge); ``Dataset.get(name, "K")`` converts for models.
Writes are atomic (temporary file, then rename). Reading validates and refuses bad data with a
one-line ``DataError`` naming file and channel.
"""

from __future__ import annotations

import json
import math
import os
import re
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from acid import __version__
from acid._io import atomic_path
from acid.errors import DataError
from acid.expr import Expression
from acid.logcheck import (
    bridge,
    bridged_finding,
    censored_across,
    flag_samples,
    gaps,
    held_extremes,
    nonfinite_stretches,
    plausibility,
    quantisation,
)
from acid.units import (
    KNOWN_UNITS,
    UNIT_SCALES,
    base_unit,
    convert,
    is_temperature,
    storage_unit,
    temperature_unit_consistent,
    to_base,
)

FORMAT_NAME = "acid-dataset"
FORMAT_VERSION = 1

ROLES = ("input", "state", "output", "exogenous", "auxiliary")


@dataclass(frozen=True)
class ChannelSpec:
    """What a channel is: canonical unit, role in the model, description, and the physical
    range its values must lie in (in ``unit``; ``None``: unbounded on that side)."""

    unit: str
    role: str
    description: str
    lo: float | None = None
    hi: float | None = None


#: The channels acid knows by name (others are allowed, as auxiliary channels).
CHANNELS: dict[str, ChannelSpec] = {
    "T_cab": ChannelSpec("degC", "state", "cabin air temperature"),
    "T_evap": ChannelSpec("degC", "state", "evaporator wall temperature"),
    "T_ain": ChannelSpec("degC", "output", "cabin inlet (supply) air temperature"),
    "W_bl": ChannelSpec("kg/s", "input", "blower air mass flow", 0.0, 1.0),
    "T_evap_set": ChannelSpec("degC", "input", "evaporator wall temperature set-point"),
    "T_int": ChannelSpec("degC", "exogenous", "cabin interior (seats, dash) temperature"),
    "T_shell": ChannelSpec("degC", "exogenous", "cabin shell (roof, doors, glass) temperature"),
    "T_amb": ChannelSpec("degC", "exogenous", "ambient air temperature"),
    "v_veh": ChannelSpec("m/s", "exogenous", "vehicle speed", 0.0, 100.0),
    "N_comp": ChannelSpec("rpm", "auxiliary", "compressor speed", 0.0, None),
    "P_comp": ChannelSpec("W", "auxiliary", "compressor electrical power"),
    "P_bl": ChannelSpec("W", "auxiliary", "blower electrical power"),
    "P_fan": ChannelSpec("W", "auxiliary", "condenser fan electrical power"),
    "COP": ChannelSpec("1", "auxiliary", "cycle coefficient of performance Q_e / P_comp"),
    "recirc": ChannelSpec("1", "auxiliary", "recirculated fraction of blower air", 0.0, 1.0),
    "w_cab": ChannelSpec("kg/kg", "auxiliary", "cabin air humidity ratio", 0.0, 0.2),
    "Q_evap": ChannelSpec("W", "auxiliary", "evaporator refrigerant-side heat flow"),
    "Q_cond": ChannelSpec("W", "auxiliary", "condenser refrigerant-side heat flow"),
    "Q_lat": ChannelSpec("W", "auxiliary", "latent (condensation) part of the evaporator load"),
    "W_comp": ChannelSpec("W", "auxiliary", "compressor shaft (fluid) power"),
    "T_e": ChannelSpec("degC", "auxiliary", "evaporating (saturation) temperature"),
    "T_c": ChannelSpec("degC", "auxiliary", "condensing (saturation) temperature"),
    "T_cw": ChannelSpec("degC", "auxiliary", "condenser wall temperature"),
    "T_int_slow": ChannelSpec("degC", "auxiliary", "slow interior node (seat cores, dash body)"),
    "p_suc": ChannelSpec("Pa", "auxiliary", "compressor suction (low-side) pressure, absolute"),
    "p_dis": ChannelSpec("Pa", "auxiliary", "compressor discharge (head) pressure, absolute"),
    "m_r": ChannelSpec("kg/s", "auxiliary", "refrigerant mass flow"),
    "m_ca": ChannelSpec("kg/s", "auxiliary", "condenser face air mass flow"),
    "fan_speed": ChannelSpec("1", "auxiliary", "condenser fan speed fraction (0 off, 1 full)"),
}

#: Channels the identification and validation of eqs. 1-3 need.
MODEL_CHANNELS = ("T_cab", "T_evap", "T_ain", "W_bl", "T_evap_set", "T_int", "T_shell")

#: Most samples a dataset (or an imported column) may hold: checked before anything of that
#: size is allocated. 20 million samples are 3 years at Ts = 5 s or 55 h of a 0.01 s export.
MAX_SAMPLES = 20_000_000

#: Channel names: a letter, then letters, digits and underscores (safe as HDF5 names).
CHANNEL_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")


def check_sample_time(Ts, where: str) -> float:
    """``Ts`` as a float if it is a finite positive number (not a bool or a string)."""
    if isinstance(Ts, bool) or not isinstance(Ts, (int, float, np.integer, np.floating)):
        raise DataError(f"{where} must be a number of seconds, got {Ts!r}")
    Ts = float(Ts)
    if not (math.isfinite(Ts) and Ts > 0.0):
        raise DataError(f"{where} must be a finite positive number of seconds, got {Ts!r}")
    return Ts


def check_size(n: float, where: str) -> int:
    """Refuse more than ``MAX_SAMPLES`` samples before they are allocated."""
    if not n <= MAX_SAMPLES:
        raise DataError(f"{where}: {n:.3g} samples is more than acid handles "
                        f"({MAX_SAMPLES:.0e})")
    return int(n)


def _now_iso() -> str:
    return datetime.now(timezone.utc).replace(microsecond=0).isoformat()


@dataclass
class Dataset:
    """Uniformly sampled, unit-carrying signals plus metadata.

    Attributes
    ----------
    time : (N,) sample instants, s.
    channels : {name: (N,) float array} in the unit given by ``units[name]``.
    units : {name: unit string}, e.g. "degC", "kg/s".
    Ts : sample time, s.
    experiment : (N,) int experiment id per sample (0 for a single experiment).
    roles : {name: role}; defaults from ``CHANNELS``.
    metadata : provenance (plant, plant_config, excitation, seed, source, created, ...).
    fine : optional fine-step trace (another ``Dataset``) recorded alongside.
    """

    time: np.ndarray
    channels: dict[str, np.ndarray]
    units: dict[str, str]
    Ts: float
    experiment: np.ndarray | None = None
    roles: dict[str, str] = field(default_factory=dict)
    metadata: dict = field(default_factory=dict)
    fine: Dataset | None = None
    source: str = "<memory>"

    def __post_init__(self):
        self.time = np.asarray(self.time, dtype=float)
        self.channels = {k: np.asarray(v, dtype=float) for k, v in self.channels.items()}
        n = self.time.shape[0]
        if self.experiment is None:
            self.experiment = np.zeros(n, dtype=np.int32)
        self.experiment = np.asarray(self.experiment, dtype=np.int32)
        for name in self.channels:
            if name not in self.units:
                spec = CHANNELS.get(name)
                if spec is None:
                    raise DataError(f"{self.source}: channel {name!r} has no unit")
                self.units[name] = spec.unit
            if name not in self.roles:
                self.roles[name] = CHANNELS[name].role if name in CHANNELS else "auxiliary"
        self.Ts = float(self.Ts)

    # ---------------------------------------------------------------- access
    def __len__(self) -> int:
        return int(self.time.shape[0])

    def __contains__(self, name: str) -> bool:
        return name in self.channels

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self.channels:
            raise DataError(f"{self.source}: missing channel {name!r}")
        return self.channels[name]

    @property
    def duration(self) -> float:
        """Covered time span, s."""
        return float(len(self) * self.Ts)

    def get(self, name: str, unit: str | None = None) -> np.ndarray:
        """Channel values, converted to ``unit`` (e.g. ``"K"`` for models) when given."""
        values = self[name]
        if unit is None or unit == self.units[name]:
            return values
        try:
            return convert(values, self.units[name], unit)
        except ValueError:
            raise DataError(f"{self.source}: channel {name!r} is in {self.units[name]!r}, "
                            f"cannot convert to {unit!r}") from None

    def kelvin(self, *names: str) -> tuple[np.ndarray, ...] | np.ndarray:
        """Temperature channels in K (one array, or a tuple for several names)."""
        out = tuple(self.get(n, "K") for n in names)
        return out[0] if len(out) == 1 else out

    # ------------------------------------------------------------ structure
    def segments(self) -> list[tuple[int, int]]:
        """(start, stop) index ranges of contiguous experiments."""
        cut = np.flatnonzero(np.diff(self.experiment) != 0) + 1
        edges = np.concatenate(([0], cut, [len(self)]))
        return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True)]

    def transition_mask(self) -> np.ndarray:
        """(N-1,) bool: True where samples k and k+1 belong to the same experiment."""
        return self.experiment[:-1] == self.experiment[1:]

    def window(self, start: int, stop: int) -> Dataset:
        """Samples ``start .. stop-1`` as a new dataset (metadata shared)."""
        sl = slice(start, stop)
        return Dataset(
            time=self.time[sl].copy(),
            channels={k: v[sl].copy() for k, v in self.channels.items()},
            units=dict(self.units), Ts=self.Ts, experiment=self.experiment[sl].copy(),
            roles=dict(self.roles), metadata=dict(self.metadata), source=self.source,
        )

    def split(self, fraction: float = 0.5) -> tuple[Dataset, Dataset]:
        """Estimation and validation parts: the first ``fraction`` of samples, then the rest."""
        if not 0.0 < fraction < 1.0:
            raise DataError(f"split fraction must be in (0, 1), got {fraction}")
        k = int(round(len(self) * fraction))
        return self.window(0, k), self.window(k, len(self))

    def select(self, names: Iterable[str]) -> Dataset:
        """A dataset with only the named channels."""
        names = list(names)
        for n in names:
            self[n]
        return Dataset(self.time, {n: self.channels[n] for n in names},
                       {n: self.units[n] for n in names}, self.Ts, self.experiment,
                       {n: self.roles[n] for n in names}, dict(self.metadata), source=self.source)

    @staticmethod
    def concatenate(parts: list[Dataset]) -> Dataset:
        """Join datasets as separate experiments (ids renumbered, time made contiguous).

        The channels are the first part's; a mask channel (``<name>_censored``) that only
        some parts have is 0 (nothing masked) in the others."""
        if not parts:
            raise DataError("nothing to concatenate")
        masks = [n for p in parts for n in p.channels
                 if n.endswith(CENSORED_SUFFIX) and n not in parts[0].channels]
        names = list(parts[0].channels) + list(dict.fromkeys(masks))
        units = {**{n: "1" for n in masks}, **parts[0].units}
        roles = {**{n: "auxiliary" for n in masks}, **parts[0].roles}
        Ts = parts[0].Ts
        times, chans, exps = [], {n: [] for n in names}, []
        t0, eid = 0.0, 0
        for p in parts:
            if abs(p.Ts - Ts) > 1e-9:
                raise DataError(f"{p.source}: sample time {p.Ts} s differs from {Ts} s")
            for n in names:
                absent = n.endswith(CENSORED_SUFFIX) and n not in p.channels
                chans[n].append(np.zeros(len(p)) if absent else p.get(n, units[n]))
            times.append(t0 + (p.time - p.time[0]))
            t0 = times[-1][-1] + Ts
            ids = np.unique(p.experiment, return_inverse=True)[1]
            exps.append(ids + eid)
            eid += ids.max() + 1
        return Dataset(np.concatenate(times), {n: np.concatenate(v) for n, v in chans.items()},
                       units, Ts, np.concatenate(exps), roles, dict(parts[0].metadata))

    def to_pandas(self):
        """A DataFrame indexed by time (s), one column per channel, units in ``df.attrs``."""
        import pandas as pd

        df = pd.DataFrame(self.channels, index=pd.Index(self.time, name="time_s"))
        df["experiment"] = self.experiment
        df.attrs["units"] = dict(self.units)
        df.attrs["Ts"] = self.Ts
        return df

    @property
    def assumed(self) -> dict[str, str]:
        """Channels that were declared, not measured (a constant or an expression in the
        import map): {name: how}. Fits and validations may refuse or flag them."""
        declared = self.metadata.get("assumed") or {}
        if not isinstance(declared, Mapping):
            return {}
        return {n: str(v.get("how", v) if isinstance(v, Mapping) else v)
                for n, v in declared.items() if n in self.channels}

    def experiment_names(self) -> list[str]:
        """One name per experiment (the file names of an import; else ``"0"``, ``"1"``...)."""
        ids = np.unique(self.experiment)
        records = self.metadata.get("experiments")
        if isinstance(records, list) and all(isinstance(r, Mapping) and "name" in r
                                             for r in records) and \
                all(0 <= i < len(records) for i in ids):
            return [str(records[i]["name"]) for i in ids]
        return [str(i) for i in ids]

    # ------------------------------------------------------------ validation
    def require(self, names: Iterable[str]) -> Dataset:
        """Refuse a dataset that lacks any of ``names``: one line naming every missing one."""
        missing = [n for n in dict.fromkeys(names) if n not in self.channels]
        if len(missing) == 1:
            raise DataError(f"{self.source}: missing channel {missing[0]!r}")
        if missing:
            raise DataError(f"{self.source}: missing {len(missing)} channels "
                            f"{', '.join(map(repr, missing))} (a log that does not measure "
                            "one can declare it in the import map as a constant or an "
                            "expression, recorded as assumed)")
        return self

    def validate(self, require: Iterable[str] = (), min_samples: int = 2) -> Dataset:
        """Refuse data that cannot be trusted; returns ``self`` so calls chain.

        Checks: required channels present, values finite, time strictly increasing and
        uniform at ``Ts``, temperatures consistent with their declared unit, enough samples.
        """
        src = self.source
        check_sample_time(self.Ts, f"{src}: sample time Ts")
        self.require(require)
        n = len(self)
        if self.time.ndim != 1:
            raise DataError(f"{src}: time must be a vector, got shape {self.time.shape}")
        if self.experiment.shape != (n,):
            raise DataError(f"{src}: experiment ids have shape {self.experiment.shape}, "
                            f"time has {n} samples")
        for name, v in self.channels.items():
            if v.shape != (n,):
                raise DataError(f"{src}: channel {name!r} has {v.shape[0]} samples, time has {n}")
            bad = ~np.isfinite(v)
            if bad.any():
                i = int(np.argmax(bad))
                raise DataError(f"{src}: channel {name!r} has {int(bad.sum())} NaN/inf values "
                                f"(first at t = {self.time[i]:g} s)")
            unit = self.units[name]
            if unit not in KNOWN_UNITS:
                raise DataError(f"{src}: channel {name!r} has unknown unit {unit!r} "
                                f"(known: {', '.join(KNOWN_UNITS)})")
            if is_temperature(unit) and not temperature_unit_consistent(v, unit):
                other = "K" if unit == "degC" else "degC"
                raise DataError(f"{src}: channel {name!r} is declared in {unit} but its values "
                                f"({v.min():.1f} .. {v.max():.1f}) look like {other}")
            _check_physical(name, v, unit, self.time, src)
        if not np.all(np.isfinite(self.time)):
            raise DataError(f"{src}: time has NaN/inf values")
        if n >= 2:
            dt = np.diff(self.time)
            if np.any(dt <= 0):
                i = int(np.argmax(dt <= 0))
                raise DataError(f"{src}: time is not strictly increasing "
                                f"(at sample {i + 1}, t = {self.time[i + 1]:g} s)")
            if not np.allclose(dt, self.Ts, rtol=1e-6, atol=1e-6 * self.Ts):
                i = int(np.argmax(~np.isclose(dt, self.Ts, rtol=1e-6, atol=1e-6 * self.Ts)))
                raise DataError(f"{src}: time is not uniform at Ts = {self.Ts:g} s "
                                f"(step of {dt[i]:g} s at t = {self.time[i]:g} s)")
        if n < min_samples:
            raise DataError(f"{src}: record too short: {n} samples ({n * self.Ts:g} s), "
                            f"the study needs at least {min_samples} ({min_samples * self.Ts:g} s)")
        return self

    # -------------------------------------------------------------- HDF5 I/O
    def to_hdf5(self, path: str | os.PathLike, created: str | None = None) -> Path:
        """Write the documented HDF5 layout atomically; returns the path."""
        import h5py

        path = Path(path)
        meta = dict(self.metadata)
        meta.setdefault("acid_version", __version__)
        meta["created"] = created or meta.get("created") or _now_iso()
        # Built in memory, then written as bytes: a write that fails (a full disk, a file-size
        # limit, EFBIG) is then an OSError of Python's, one line through atomic_path, never a
        # failure inside the HDF5 library halfway through the file (which crashed the process).
        with h5py.File(f"{path.name}.in-memory", "w", driver="core", backing_store=False,
                       track_order=True) as f:
            _write_group(f, self, meta)
            if self.fine is not None:
                _write_group(f.create_group("fine"), self.fine, None)
            f.flush()
            image = f.id.get_file_image()
        with atomic_path(path) as tmp:
            tmp.write_bytes(image)
        return path

    @classmethod
    def from_hdf5(cls, path: str | os.PathLike, require: Iterable[str] = (),
                  min_samples: int = 2) -> Dataset:
        """Read and validate an acid dataset; ``DataError`` (one line) on any problem."""
        import h5py

        path = Path(path)
        if not path.is_file():
            raise DataError(f"{path}: dataset file not found")
        try:
            with h5py.File(path, "r") as f:
                if _attr_text(f, "format", str(path)) != FORMAT_NAME:
                    raise DataError(f"{path}: not an acid dataset (missing format={FORMAT_NAME!r};"
                                    " import CSV or MAT files with `acid import`)")
                ds = _read_group(f, str(path))
                if "fine" in f:
                    ds.fine = _read_group(_member(f, "fine", str(path), group=True),
                                          f"{path}:/fine")
        except DataError:
            raise
        except OSError as exc:
            raise DataError(f"{path}: cannot read as HDF5 ({_first_line(exc)})") from None
        except (KeyError, TypeError, ValueError, RuntimeError, AttributeError) as exc:
            # h5py's own refusals of a damaged or foreign file (the checks above name most)
            raise DataError(f"{path}: malformed acid dataset ({exc.__class__.__name__}: "
                            f"{_first_line(exc)})") from None
        return ds.validate(require=require, min_samples=min_samples)


def _write_group(g, ds: Dataset, meta: dict | None) -> None:
    g.attrs["format"] = FORMAT_NAME
    g.attrs["format_version"] = FORMAT_VERSION
    g.attrs["Ts"] = ds.Ts
    if meta is not None:
        g.attrs["acid_version"] = str(meta.get("acid_version", __version__))
        g.attrs["created"] = str(meta["created"])
        g.attrs["metadata"] = json.dumps(meta, sort_keys=True, default=_json_safe)
    t = g.create_dataset("time", data=ds.time, track_times=False)
    t.attrs["unit"] = "s"
    g.create_dataset("experiment", data=ds.experiment.astype(np.int32), track_times=False)
    ch = g.create_group("channels", track_order=True)
    for name, values in ds.channels.items():
        if "/" in name or name in ("", ".", ".."):
            raise DataError(f"{ds.source}: channel name {name!r} cannot be stored in HDF5")
        d = ch.create_dataset(name, data=values, track_times=False)
        d.attrs["unit"] = ds.units[name]
        d.attrs["role"] = ds.roles.get(name, "auxiliary")
        spec = CHANNELS.get(name)
        d.attrs["description"] = spec.description if spec else ""


def _json_safe(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    return str(obj)


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else exc.__class__.__name__


def _attr(obj, name: str, source: str):
    """An HDF5 attribute, or None when absent; ``DataError`` when it cannot be read."""
    try:
        if name not in obj.attrs:
            return None
        return obj.attrs[name]
    except Exception as exc:  # noqa: BLE001 - h5py raises many types for foreign attributes
        raise DataError(f"{source}: attribute {name!r} cannot be read "
                        f"({exc.__class__.__name__})") from None


def _scalar(value):
    """A one-element array as its element; anything else unchanged."""
    if isinstance(value, np.ndarray) and value.size == 1:
        return value.reshape(()).item() if value.dtype.kind != "O" else value.reshape(())[()]
    return value


def _attr_text(obj, name: str, source: str) -> str | None:
    """A text attribute (str or UTF-8 bytes), or None when absent or not text."""
    value = _scalar(_attr(obj, name, source))
    if isinstance(value, (bytes, np.bytes_)):
        try:
            return bytes(value).decode("utf-8")
        except UnicodeDecodeError:
            return None
    return str(value) if isinstance(value, str) else None


def _member(g, name: str, source: str, group: bool = False):
    """``g[name]`` as a dataset (or a group with ``group``), else a one-line ``DataError``."""
    import h5py

    where = f"{g.name.rstrip('/')}/{name}"
    try:
        obj = g.get(name)
    except Exception as exc:  # noqa: BLE001 - broken links, foreign objects
        raise DataError(f"{source}: {where} cannot be opened ({exc.__class__.__name__})") from None
    kind = h5py.Group if group else h5py.Dataset
    if obj is None:
        return None
    if not isinstance(obj, kind):
        raise DataError(f"{source}: {where} must be {'a group' if group else 'an array'}")
    return obj


def _read_vector(d, what: str, source: str, integer: bool = False) -> np.ndarray:
    """A 1-D numeric HDF5 array as float (or int) values, checked before it is read."""
    if d.ndim != 1:
        raise DataError(f"{source}: {what} must be a vector, got shape {d.shape}")
    if d.dtype.kind not in ("iu" if integer else "biuf"):
        raise DataError(f"{source}: {what} must hold {'integers' if integer else 'numbers'}, "
                        f"got {d.dtype}")
    check_size(d.shape[0], f"{source}: {what}")
    try:
        values = d[()]
    except Exception as exc:  # noqa: BLE001 - damaged chunks, missing filters
        raise DataError(f"{source}: {what} cannot be read ({_first_line(exc)})") from None
    return np.asarray(values, dtype=np.int64 if integer else float)


def _read_group(g, source: str) -> Dataset:
    time_d = _member(g, "time", source)
    if time_d is None:
        raise DataError(f"{source}: missing /time")
    chan_g = _member(g, "channels", source, group=True)
    if chan_g is None:
        raise DataError(f"{source}: missing /channels group")
    raw_Ts = _scalar(_attr(g, "Ts", source))
    if raw_Ts is None:
        raise DataError(f"{source}: missing attribute Ts (sample time)")
    Ts = check_sample_time(raw_Ts, f"{source}: attribute Ts (sample time)")
    time = _read_vector(time_d, "/time", source)
    channels, units, roles = {}, {}, {}
    for name in chan_g:
        where = f"channel {name!r}"
        d = _member(chan_g, name, source)
        unit = _attr_text(d, "unit", source)
        if unit is None:
            raise DataError(f"{source}: {where} has no text unit attribute")
        role = _attr_text(d, "role", source)
        if role is None:
            role = CHANNELS[name].role if name in CHANNELS else "auxiliary"
        if role not in ROLES:
            raise DataError(f"{source}: {where} has unknown role {role!r} "
                            f"(known: {', '.join(ROLES)})")
        channels[name] = _read_vector(d, where, source)
        units[name], roles[name] = unit, role
    meta = {}
    if _attr(g, "metadata", source) is not None:
        text = _attr_text(g, "metadata", source)
        try:
            meta = json.loads(text) if text is not None else None
        except (json.JSONDecodeError, RecursionError):
            meta = None
        if not isinstance(meta, dict):
            raise DataError(f"{source}: attribute metadata is not a JSON object")
    exp_d = _member(g, "experiment", source)
    exp = None if exp_d is None else _read_vector(exp_d, "/experiment", source, integer=True)
    if exp is not None:
        if exp.shape != time.shape:
            raise DataError(f"{source}: /experiment has {exp.shape[0]} samples, "
                            f"time has {time.shape[0]}")
        if exp.size and (exp.min() < np.iinfo(np.int32).min or exp.max() > np.iinfo(np.int32).max):
            raise DataError(f"{source}: /experiment ids must fit in 32 bits")
    return Dataset(time=time, channels=channels, units=units, Ts=Ts, experiment=exp,
                   roles=roles, metadata=meta, source=source)


def _check_physical(name: str, v: np.ndarray, unit: str, time: np.ndarray, src: str) -> None:
    """A known channel must carry its unit (any temperature unit for a temperature) and lie
    inside its physical range (``ChannelSpec.lo``/``hi``)."""
    spec = CHANNELS.get(name)
    if spec is None:
        return
    if unit != spec.unit and not (is_temperature(spec.unit) and is_temperature(unit)):
        raise DataError(f"{src}: channel {name!r} is declared in {unit!r}, expected "
                        f"{spec.unit!r} ({spec.description})")
    if unit != spec.unit or v.size == 0:
        return
    for bound, bad in ((spec.lo, v < spec.lo if spec.lo is not None else None),
                       (spec.hi, v > spec.hi if spec.hi is not None else None)):
        if bad is not None and bad.any():
            i = int(np.argmax(bad))
            side = "below" if bound == spec.lo else "above"
            when = f"t = {time[i]:g} s" if time.shape == v.shape else f"sample {i}"
            span = f"[{_fmt_bound(spec.lo, '-inf')}, {_fmt_bound(spec.hi, 'inf')}]"
            raise DataError(f"{src}: channel {name!r} has {int(bad.sum())} values {side} its "
                            f"physical range {span} {spec.unit} (first {v[i]:g} at {when})")


def _fmt_bound(v: float | None, unbounded: str) -> str:
    return unbounded if v is None else f"{v:g}"


# ------------------------------------------------------------------ importers
#: How a channel map brings a record onto its ``Ts`` grid (``ChannelMap.resample``).
RESAMPLE_MODES = ("mean", "centered", "sample", "none")

#: Keys a channel map may have.
MAP_KEYS = ("time", "Ts", "resample", "channels", "description", "sep", "encoding", "decimal",
            "drop_incomplete_end", "max_gap_s")

#: Keys of one channel entry of a map.
CHANNEL_KEYS = ("column", "unit", "constant", "expr", "note", "censored_above",
                "censored_below", "max_gap_s")

#: Suffix of the mask channel that marks censored samples of a channel (1 = censored).
CENSORED_SUFFIX = "_censored"

#: File types the import reads (``read_log``), by suffix.
CSV_SUFFIXES = (".csv", ".txt", ".csv.gz", ".txt.gz")
MAT_SUFFIXES = (".mat",)


class PlausibilityWarning(UserWarning):
    """An imported channel's values contradict its declared unit (a speed in km/h declared
    as m/s, an A/C power in kW declared as W)."""


class LogQualityWarning(PlausibilityWarning):
    """An imported channel's sensor looks faulty at some samples (empty cells bridged,
    glitches, impossible jumps, values out of physical range): they are masked, not fitted
    or scored."""


@dataclass(frozen=True)
class ChannelSource:
    """Where one channel of a map comes from: a ``column`` of the file, a ``constant`` or an
    ``expr`` of other channels (the last two are *assumed*, not measured); its ``unit``; the
    levels at which its sensor clips (``censored_above`` / ``censored_below``, in ``unit``)."""

    unit: str
    column: str | None = None
    constant: float | None = None
    expr: Expression | None = None
    note: str = ""
    censored_above: float | None = None
    censored_below: float | None = None
    #: Longest stretch of NaN/inf (empty cells) bridged, s; ``None``: the map's.
    max_gap_s: float | None = None

    @property
    def assumed(self) -> bool:
        return self.column is None

    def describe(self) -> str:
        if self.constant is not None:
            return f"constant {self.constant:g} {self.unit}"
        if self.expr is not None:
            return f"expr {self.expr.text} [{self.unit}]"
        return f"column {self.column!r} [{self.unit}]"


@dataclass(frozen=True)
class ChannelMap:
    """How columns of a foreign file become acid channels.

    ``time``: name of the time column, in ``time_unit`` (s unless the map says
    ``time = { column = "...", unit = "ms" }``; a map with ``Ts`` may leave it out: the rows
    are then one ``Ts`` apart from 0 s); ``channels``: {acid name:
    :class:`ChannelSource`}; ``Ts``: the sample time of the dataset, s (``None``: the file's
    own, which must be uniform); ``sep``, ``encoding``, ``decimal``: how a CSV file is
    written (default ``","``, ``"utf-8"``, ``"."``; ``.gz`` files are decompressed);
    ``resample``: how the record gets onto the ``Ts`` grid:

    * ``"mean"``: the sample convention: states, inputs and exogenous channels sampled at
      t_k, outputs and powers averaged over [t_k, t_k + Ts) (energy kept);
    * ``"centered"``: as ``"mean"``, but states, inputs and exogenous channels are their mean
      over [t_k - Ts/2, t_k + Ts/2) (a quantised or noisy sensor's steps averaged out, still
      aligned with t_k);
    * ``"sample"``: every channel sampled at t_k (linear interpolation);
    * ``"none"``: no resampling; the file must already be uniform at ``Ts``;
    * not given: ``"mean"``, unless the file is already sampled every ``Ts``: then it is
      taken as it is (averaging again would smear outputs and powers), with a note in
      ``metadata["resample"]``.

    Units come from ``acid.units.UNIT_SCALES`` (the table FMU maps use): km/h, kW, kg/h,
    degF, bar, W/m2, %RH, ...; the dataset stores each channel in acid's unit (degC, m/s, W,
    kg/s, ...). Loaded from TOML or JSON::

        time = "t"
        Ts = 5.0             # optional
        resample = "mean"    # optional: "mean", "sample" or "none"
        sep = ";"            # optional CSV format keys
        encoding = "latin-1"
        decimal = ","
        [channels]
        T_cab = { column = "CabinAirTemp", unit = "degC", censored_above = 39.84 }
        v_veh = { column = "Speed", unit = "km/h" }
        W_bl  = { constant = 0.1, unit = "kg/s", note = "blower level 1" }    # assumed
        T_ain = { expr = "T_evap + 2", unit = "degC" }                          # assumed
    """

    time: str | None      # None: no time column, the rows are one Ts apart
    channels: Mapping[str, ChannelSource]
    Ts: float | None = None
    resample: str | None = None
    source: str = field(default="channel map", compare=False)
    time_unit: str = "s"
    sep: str = ","
    encoding: str = "utf-8"
    decimal: str = "."
    description: str = ""
    #: Drop the rows at a record's end where a read column is empty (a logger that stopped
    #: mid-row); empty values anywhere else are still refused.
    drop_incomplete_end: bool = False
    #: Bridge stretches of NaN/inf (empty cells) of a measured channel up to this long, s
    #: (0: refuse any); a channel's own ``max_gap_s`` overrides it. Continuous channels are
    #: interpolated linearly, set-points and commands (inputs) hold their last value; the
    #: bridged samples are masked in ``<channel>_censored`` (not fitted or scored). A longer
    #: stretch refuses the file, naming channel and time.
    max_gap_s: float = 0.0

    def gap_limit(self, name: str) -> float:
        """The longest NaN/inf stretch of channel ``name`` bridged, s."""
        own = self.channels[name].max_gap_s
        return self.max_gap_s if own is None else own

    @property
    def columns(self) -> list[str]:
        """The file's columns the map reads: time first, then the measured channels."""
        return [self.time] + [s.column for s in self.channels.values() if s.column is not None]

    @classmethod
    def from_file(cls, path: str | os.PathLike) -> ChannelMap:
        path = Path(path)
        if not path.is_file():
            raise DataError(f"{path}: channel map not found")
        try:
            text = path.read_text(encoding="utf-8")
            if path.suffix.lower() == ".json":
                d = json.loads(text)
            else:
                try:
                    import tomllib
                except ModuleNotFoundError:  # Python < 3.11
                    import tomli as tomllib
                d = tomllib.loads(text)
        except Exception as exc:  # noqa: BLE001 - any parser failure is the file's fault
            raise DataError(f"{path}: cannot parse channel map ({_first_line(exc)})") from None
        return cls.from_dict(d, str(path))

    @classmethod
    def from_dict(cls, d: dict, source: str = "channel map") -> ChannelMap:
        if not isinstance(d, Mapping):
            raise DataError(f"{source}: a channel map is a table with 'time' and [channels], "
                            f"got {type(d).__name__}")
        unknown = [k for k in d if k not in MAP_KEYS]
        if unknown:
            raise DataError(f"{source}: unknown key {unknown[0]!r} (known: {', '.join(MAP_KEYS)})")
        if "channels" not in d or ("time" not in d and d.get("Ts") is None):
            raise DataError(f"{source}: needs 'time' (or Ts, for rows one Ts apart) and a "
                            "[channels] table")
        # no time column: the rows are one Ts apart from 0 s
        time_col, time_unit = _time_entry(d["time"], source) if "time" in d else (None, "s")
        if not isinstance(d["channels"], Mapping):
            raise DataError(f"{source}: [channels] must be a table of channel = column entries")
        chans = {name: _channel_entry(name, spec, source)
                 for name, spec in d["channels"].items()}
        _order_derived(chans, source)
        Ts = d.get("Ts")
        if Ts is not None:
            Ts = check_sample_time(Ts, f"{source}: Ts")
        resample = d.get("resample")
        if resample is not None:
            if not isinstance(resample, str) or resample not in RESAMPLE_MODES:
                raise DataError(f"{source}: resample must be one of "
                                f"{', '.join(map(repr, RESAMPLE_MODES))}, got {resample!r}")
            if Ts is None:
                raise DataError(f"{source}: resample = {resample!r} needs Ts (the grid to "
                                "resample onto)")
        sep, decimal = (_one_char(d, k, default, source)
                        for k, default in (("sep", ","), ("decimal", ".")))
        if decimal not in (".", ","):
            raise DataError(f"{source}: decimal must be '.' or ',', got {decimal!r}")
        if sep == decimal or sep in ('"', "\n", "\r"):
            raise DataError(f"{source}: sep {sep!r} cannot separate columns"
                            + (" (it is also the decimal mark)" if sep == decimal else ""))
        encoding = d.get("encoding", "utf-8")
        if not isinstance(encoding, str) or not _known_encoding(encoding):
            raise DataError(f"{source}: unknown encoding {encoding!r} (e.g. 'utf-8', "
                            "'latin-1', 'cp1252')")
        description = d.get("description", "")
        if not isinstance(description, str):
            raise DataError(f"{source}: description must be a text")
        drop_end = d.get("drop_incomplete_end", False)
        if not isinstance(drop_end, bool):
            raise DataError(f"{source}: drop_incomplete_end must be true or false")
        max_gap = _gap_seconds(d.get("max_gap_s", 0.0), f"{source}: max_gap_s")
        return cls(time=time_col, channels=chans, Ts=Ts, resample=resample, source=source,
                   time_unit=time_unit, sep=sep, encoding=encoding, decimal=decimal,
                   description=description, drop_incomplete_end=drop_end, max_gap_s=max_gap)


def _gap_seconds(value, where: str) -> float:
    v = _number(value, where)
    if v < 0:
        raise DataError(f"{where} must be a number of seconds >= 0, got {value!r}")
    return v


def _time_entry(value, source: str) -> tuple[str, str]:
    """``time = "col"`` or ``time = { column = "col", unit = "ms" }``."""
    unit = "s"
    if isinstance(value, Mapping):
        extra = [k for k in value if k not in ("column", "unit")]
        if extra:
            raise DataError(f"{source}: time has unknown key {extra[0]!r} (known: column, unit)")
        unit = value.get("unit", "s")
        value = value.get("column")
        if not isinstance(unit, str) or unit not in UNIT_SCALES or base_unit(unit) != "s":
            raise DataError(f"{source}: time unit must be a unit of time (s, ms, min, h), "
                            f"got {unit!r}")
    if not isinstance(value, str) or not value:
        raise DataError(f"{source}: 'time' must be the name of the time column, got {value!r}")
    return value, unit


def _one_char(d: Mapping, key: str, default: str, source: str) -> str:
    value = d.get(key, default)
    if not isinstance(value, str) or len(value) != 1:
        raise DataError(f"{source}: {key} must be one character, got {value!r}")
    return value


def _known_encoding(name: str) -> bool:
    import codecs

    try:
        return codecs.lookup(name).name not in ("", None)
    except (LookupError, ValueError, TypeError):
        return False


def _number(value, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or \
            not math.isfinite(float(value)):
        raise DataError(f"{where} must be a finite number, got {value!r}")
    return float(value)


def _channel_entry(name, spec, source: str) -> ChannelSource:
    if not isinstance(name, str) or not CHANNEL_NAME.fullmatch(name):
        raise DataError(f"{source}: channel name {name!r} must be a letter followed by "
                        "letters, digits or underscores")
    if isinstance(spec, str):
        spec = {"column": spec}
    if not isinstance(spec, Mapping):
        raise DataError(f"{source}: channel {name!r} must be a column name or "
                        f"{{ column = ..., unit = ... }}, got {spec!r}")
    extra = [k for k in spec if k not in CHANNEL_KEYS]
    if extra:
        raise DataError(f"{source}: channel {name!r} has unknown key {extra[0]!r} "
                        f"(known: {', '.join(CHANNEL_KEYS)})")
    kinds = [k for k in ("column", "constant", "expr") if k in spec]
    if len(kinds) != 1:
        raise DataError(f"{source}: channel {name!r} needs exactly one of 'column', "
                        f"'constant' or 'expr'" + (f", got {' and '.join(kinds)}" if kinds else ""))
    where = f"{source}: channel {name!r}"
    unit = spec.get("unit", CHANNELS[name].unit if name in CHANNELS else None)
    if unit is None:
        raise DataError(f"{where} needs 'column' and 'unit'" if "column" in spec
                        else f"{where} needs a 'unit'")
    if not isinstance(unit, str) or unit not in UNIT_SCALES:
        raise DataError(f"{where} has unknown unit {unit!r} (known: {', '.join(UNIT_SCALES)})")
    expected = CHANNELS[name].unit if name in CHANNELS else None
    if expected is not None and storage_unit(unit) != expected:
        raise DataError(f"{where} is declared in {unit!r}, which does not measure what "
                        f"{name} is ({CHANNELS[name].description}, {expected})")
    if name.endswith(CENSORED_SUFFIX) and name[:-len(CENSORED_SUFFIX)]:
        raise DataError(f"{where}: names ending in {CENSORED_SUFFIX!r} are kept for the "
                        "masks of censored channels")
    note = spec.get("note", "")
    if not isinstance(note, str):
        raise DataError(f"{where}: 'note' must be a text")
    levels = {k: _number(spec[k], f"{where}: {k!r}") for k in ("censored_above",
                                                                  "censored_below") if k in spec}
    if levels and "column" not in spec:
        raise DataError(f"{where}: censored levels apply to measured columns only")
    if "max_gap_s" in spec and "column" not in spec:
        raise DataError(f"{where}: max_gap_s applies to measured columns only")
    if "column" in spec:
        col = spec["column"]
        if not isinstance(col, str) or not col:
            raise DataError(f"{where}: 'column' must be a column name, got {col!r}")
        gap = (_gap_seconds(spec["max_gap_s"], f"{where}: 'max_gap_s'")
               if "max_gap_s" in spec else None)
        return ChannelSource(unit=unit, column=col, note=note, max_gap_s=gap, **levels)
    if "constant" in spec:
        return ChannelSource(unit=unit, constant=_number(spec["constant"],
                                                         f"{where}: 'constant'"), note=note)
    return ChannelSource(unit=unit, expr=Expression.parse(spec["expr"], where), note=note)


def _order_derived(chans: dict[str, ChannelSource], source: str) -> None:
    """Refuse expressions over unknown channels or in a cycle (reordering ``chans`` so that
    every expression follows the channels it reads)."""
    for name, s in chans.items():
        if s.expr is not None:
            unknown = sorted(s.expr.names - set(chans))
            if unknown:
                raise DataError(f"{source}: channel {name!r}: expression {s.expr.text!r} reads "
                                f"{', '.join(map(repr, unknown))}, not a channel of the map "
                                f"(known: {', '.join(chans)})")
    done: list[str] = []
    pending = dict(chans)
    while pending:
        ready = [n for n, s in pending.items()
                 if s.expr is None or s.expr.names <= set(done)]
        if not ready:
            raise DataError(f"{source}: expressions of {', '.join(map(repr, pending))} read "
                            "each other in a cycle")
        for n in ready:
            done.append(n)
            del pending[n]
    ordered = {n: chans[n] for n in done}
    chans.clear()
    chans.update(ordered)


def _numeric_column(values, name: str, source: str) -> np.ndarray:
    """A foreign column or variable as a float vector, or a one-line ``DataError``."""
    if isinstance(values, Mapping) or hasattr(values, "_fieldnames"):
        fields = list(values) if isinstance(values, Mapping) else list(values._fieldnames)
        hint = f", e.g. '{name}.{fields[0]}'" if fields else ""
        raise DataError(f"{source}: variable {name!r} is a struct, not a vector; name one of "
                        f"its fields{hint}")
    try:
        arr = np.asarray(values)
    except Exception:  # noqa: BLE001 - ragged or foreign objects
        raise DataError(f"{source}: column {name!r} is not a numeric vector") from None
    if arr.dtype.kind not in "biuf":
        what = {"O": "objects (a cell or struct array?)", "U": "text", "S": "text",
                "c": "complex numbers"}.get(arr.dtype.kind, str(arr.dtype))
        raise DataError(f"{source}: column {name!r} is not numeric (it holds {what})")
    if sum(s > 1 for s in arr.shape) > 1:
        raise DataError(f"{source}: column {name!r} is a {'x'.join(map(str, arr.shape))} "
                        "array, expected a vector")
    check_size(arr.size, f"{source}: column {name!r}")
    return arr.astype(float).ravel()


def _missing_columns(columns: Mapping[str, object], cmap: ChannelMap, source: str,
                     hint: str = "") -> None:
    """One error naming every column of the map the file lacks (and its channel)."""
    wanted = [(cmap.time, "time")] * (cmap.time is not None) + [
        (s.column, repr(n)) for n, s in cmap.channels.items() if s.column is not None]
    missing = [(c, n) for c, n in wanted if c not in columns]
    if not missing:
        return
    import difflib

    parts = []
    for col, name in missing:
        close = difflib.get_close_matches(col, [str(k) for k in columns], n=1)
        parts.append(f"{col!r} (for {name}" + (f"; the file has {close[0]!r})" if close
                                                else ")"))
    what = "column" if len(missing) == 1 else f"{len(missing)} columns"
    raise DataError(f"{source}: missing {what} {', '.join(parts)}{hint}")


def _assemble(columns: Mapping[str, np.ndarray], cmap: ChannelMap, source: str,
              metadata: dict, hint: str = "") -> Dataset:
    """Columns of one file -> a checked dataset: units converted to acid's, assumed channels
    evaluated, censored samples masked, sensors checked, the record resampled."""
    _missing_columns(columns, cmap, source, hint)
    if cmap.time is not None:
        time = to_base(_numeric_column(columns[cmap.time], cmap.time, source), cmap.time_unit)
    else:   # rows one Ts apart (the map's Ts is required without a time column)
        n = len(next(iter(columns.values()))) if columns else 0
        time = np.arange(n) * float(cmap.Ts)
    raw: dict[str, np.ndarray] = {}
    for name, s in cmap.channels.items():
        if s.column is None:
            continue
        v = _numeric_column(columns[s.column], s.column, source)
        if v.shape != time.shape:
            raise DataError(f"{source}: column {s.column!r} has {v.size} values, "
                            f"time has {time.size}")
        raw[name] = v
    if cmap.drop_incomplete_end and time.size:
        complete = np.isfinite(time) & np.logical_and.reduce(
            [np.isfinite(v) for v in raw.values()] or [np.ones(time.size, bool)])
        keep = int(np.nonzero(complete)[0][-1]) + 1 if complete.any() else 0
        if keep < time.size:
            metadata["dropped_incomplete_end"] = int(time.size - keep)
            time = time[:keep]
            raw = {name: v[:keep] for name, v in raw.items()}
    checks: list[dict] = []
    bridged = _bridge_gaps(raw, cmap, time, source, checks)
    chans, units, masks, censored = {}, {}, {}, {}
    for name, s in cmap.channels.items():
        stored = storage_unit(s.unit)
        if s.column is not None:
            v = raw[name]
            if base_unit(s.unit) == "K" and np.isfinite(v).all() and v.size and \
                    not temperature_unit_consistent(v, s.unit):
                other = "K" if s.unit != "K" else "degC"
                raise DataError(f"{source}: channel {name!r} is declared in {s.unit} but its "
                                f"values ({v.min():.1f} .. {v.max():.1f}) look like {other}")
            mask = _censor_mask(v, s)
            if mask is not None:
                masks[name + CENSORED_SUFFIX] = mask
                censored[name] = {k: getattr(s, k) for k in ("censored_above",
                                                              "censored_below")
                                  if getattr(s, k) is not None}
                censored[name].update(unit=s.unit, samples=int(mask.sum()))
            for f in plausibility(name, v, s.unit, time):
                checks.append(f)
                warnings.warn(PlausibilityWarning(f"{source}: {f['message']}"), stacklevel=3)
            v = convert(v, s.unit, stored) if stored != s.unit else v
            flagged, found = flag_samples(name, v, stored, time)
            for f in found:
                checks.append(f)
                warnings.warn(LogQualityWarning(f"{source}: {f['message']}"), stacklevel=3)
            if flagged.any():
                v = bridge(v, flagged, time, hold=_held_by_design(name))
            bad = flagged | bridged.get(name, False)
            if np.any(bad):
                key = name + CENSORED_SUFFIX
                masks[key] = np.maximum(masks.get(key, 0.0), bad.astype(float))
            chans[name] = v
        elif s.constant is not None:
            chans[name] = np.full(time.shape, convert(s.constant, s.unit, stored))
        else:
            values = s.expr.evaluate(chans, time.size)
            chans[name] = convert(values, s.unit, stored) if stored != s.unit else values
        units[name] = stored
    extremes = _sensor_checks(cmap, chans, units, time, checks)
    chans.update(masks)
    units.update({m: "1" for m in masks})
    resample_record = None
    if cmap.Ts is not None:
        if not np.all(np.isfinite(time)) or np.any(np.diff(time) <= 0):
            raise DataError(f"{source}: time column {cmap.time!r} is not strictly increasing "
                            "and finite")
        mode, note = _resample_mode(time, cmap, source)
        resample_record = {"mode": mode, "Ts": cmap.Ts, "automatic": cmap.resample is None}
        if note:
            resample_record["note"] = note
        if mode != "none":
            chans = _resample(time, chans, cmap.Ts, source, mean=mode in ("mean", "centered"),
                              centered=mode == "centered")
            time = np.arange(len(next(iter(chans.values())))) * cmap.Ts + time[0]
        Ts = cmap.Ts
    else:
        Ts = float(np.median(np.diff(time))) if time.size > 1 else 1.0
        if not (math.isfinite(Ts) and Ts > 0):
            raise DataError(f"{source}: time column {cmap.time!r} is not strictly increasing "
                            "and finite")
    meta = {"source": source,
            "channel_map": {k: s.describe() for k, s in cmap.channels.items()},
            "checks": checks, "extremes": extremes}
    assumed = {k: {"how": s.describe(), "note": s.note}
               for k, s in cmap.channels.items() if s.assumed}
    if assumed:
        meta["assumed"] = assumed
    if censored:
        meta["censored"] = censored
    if resample_record is not None:
        meta["resample"] = resample_record
    meta.update(metadata)
    return Dataset(time=time, channels=chans, units=units, Ts=Ts, metadata=meta, source=source)


def _sensor_checks(cmap: ChannelMap, chans: Mapping[str, np.ndarray],
                   units: Mapping[str, str], time: np.ndarray, checks: list[dict]
                   ) -> dict[str, tuple[float, float]]:
    """Gaps in time, quantised sensors and channels held at an extreme (measured channels,
    in the dataset's units, at the file's own rate) appended to ``checks``; returns each
    measured channel's (min, max) for the censoring check across files."""
    jump = gaps(time, cmap.Ts)
    if jump is not None:
        checks.append(jump)
    extremes = {}
    for name, s in cmap.channels.items():
        if s.column is None:
            continue
        v = chans[name]
        if v.size and np.isfinite(v).all():
            extremes[name] = (float(v.min()), float(v.max()))
        found = held_extremes(name, v, units[name], time)
        q = quantisation(name, v, units[name], time)
        found = ([q] if q is not None else []) + found
        why = _why_held(name, v, chans, cmap) if found else None
        for f in found:
            if why:
                f["by_design"] = why
            checks.append(f)
    return extremes


def _why_held(name: str, v: np.ndarray, chans: Mapping[str, np.ndarray],
              cmap: ChannelMap) -> str | None:
    """Why a channel that holds levels does so by design, or None (then it may be a sensor
    that clips or reports on a few levels): a set-point or command, or a channel whose
    changes (at least 90 % of them, within one sample) are those of a measured one."""
    if _held_by_design(name):
        return "a set-point or command, held between its changes"
    mine = np.flatnonzero(np.diff(v) != 0)
    if mine.size == 0:
        return None
    for other, s in cmap.channels.items():
        if other == name or s.column is None or not _held_by_design(other):
            continue
        theirs = np.flatnonzero(np.diff(chans[other]) != 0)
        if theirs.size == 0:
            continue
        at = np.searchsorted(theirs, mine)
        gap = np.minimum(np.abs(theirs[np.clip(at - 1, 0, theirs.size - 1)] - mine),
                         np.abs(theirs[np.clip(at, 0, theirs.size - 1)] - mine))
        near = gap <= 1
        if near.mean() >= 0.9:
            return f"follows {other}, a set-point or command"
    return None


#: Channels that are set-points or commands by role or nature: held between their changes.
HELD_BY_DESIGN = ("recirc", "fan_speed")


def _held_by_design(name: str) -> bool:
    """A set-point or command (an input, a recirculation flap, a fan stage): it holds a level
    between its changes by design, so a missing stretch holds the last value."""
    spec = CHANNELS.get(name)
    return (spec is not None and spec.role == "input") or name in HELD_BY_DESIGN


def _bridge_gaps(raw: dict[str, np.ndarray], cmap: ChannelMap, time: np.ndarray,
                 source: str, checks: list[dict]) -> dict[str, np.ndarray]:
    """Bridge each measured channel's NaN/inf stretches up to its ``max_gap_s`` (in place in
    ``raw``), with a finding and a warning; refuse a longer one (one line naming file,
    channel and time). Returns {channel: bool mask of the bridged samples}."""
    out = {}
    if time.size < 2 or not np.isfinite(time).all():
        return out
    for name, v in raw.items():
        bad = ~np.isfinite(v)
        if not bad.any():
            continue
        starts, lengths, durations = nonfinite_stretches(v, time)
        limit = cmap.gap_limit(name)
        worst = int(np.argmax(durations))
        if durations[worst] > limit * (1 + 1e-9) or bad.all():
            first = float(time[starts[0]])
            if limit <= 0:
                raise DataError(f"{source}: channel {name!r} has {int(bad.sum())} NaN/inf "
                                f"values (first at t = {first:g} s, longest stretch "
                                f"{durations[worst]:.3g} s); max_gap_s in the map bridges "
                                "stretches up to that long")
            raise DataError(f"{source}: channel {name!r} has a {durations[worst]:.3g} s "
                            f"stretch of NaN/inf values at t = {time[starts[worst]]:g} s, "
                            f"longer than max_gap_s = {limit:g} s ({cmap.source})")
        hold = _held_by_design(name)
        raw[name] = bridge(v, bad, time, hold)
        f = bridged_finding(name, starts, lengths, time, hold, limit)
        checks.append(f)
        warnings.warn(LogQualityWarning(f"{source}: {f['message']}"), stacklevel=4)
        out[name] = bad
    return out


def _censor_mask(v: np.ndarray, s: ChannelSource) -> np.ndarray | None:
    """1.0 where a measured value sits at or beyond a declared clipping level, else 0.0."""
    if s.censored_above is None and s.censored_below is None:
        return None
    mask = np.zeros(v.shape, dtype=bool)
    for level, above in ((s.censored_above, True), (s.censored_below, False)):
        if level is not None:
            tol = 1e-9 * max(1.0, abs(level))
            mask |= (v >= level - tol) if above else (v <= level + tol)
    return mask.astype(float)


def _resample_mode(time: np.ndarray, cmap: ChannelMap, source: str) -> tuple[str, str | None]:
    """The resampling a map asks for on this record, and a note when it was decided here."""
    Ts = cmap.Ts
    if time.size < 2:
        raise DataError(f"{source}: record too short to resample ({time.size} sample)")
    dt = np.diff(time)
    at_Ts = bool(np.allclose(dt, Ts, rtol=1e-6, atol=1e-6 * Ts))
    step = float(np.median(dt))
    if cmap.resample == "none":
        return "none", None
    if at_Ts:
        if cmap.resample in ("mean", "centered"):
            raise DataError(f"{source}: resample = {cmap.resample!r} in {cmap.source} on data "
                            f"already "
                            f"sampled every Ts = {Ts:g} s would average outputs and powers a "
                            "second time; set resample = 'none'")
        if cmap.resample is None:
            return "none", (f"data already sampled every Ts = {Ts:g} s: taken as they are, not "
                            "resampled (set resample = 'mean' or 'sample' in the map to change)")
        return cmap.resample, None
    if step > Ts * (1 + 1e-6):
        raise DataError(f"{source}: Ts = {Ts:g} s in {cmap.source} is finer than the data's "
                        f"own step ({step:g} s); acid resamples onto a coarser grid only")
    check_size((time[-1] - time[0]) / Ts, f"{source}: resampling onto Ts = {Ts:g} s "
               f"({cmap.source})")
    return cmap.resample or "mean", None


def _is_interval_mean(name: str) -> bool:
    """Outputs and powers are means over each sample interval (the sample convention)."""
    spec = CHANNELS.get(name)
    return (spec is not None and spec.role == "output") or name.startswith(("P_", "Q_"))


def _resample(time: np.ndarray, chans: dict[str, np.ndarray], Ts: float,
              source: str, mean: bool = True, centered: bool = False
              ) -> dict[str, np.ndarray]:
    """Resample a finely sampled record onto a Ts grid following the sample convention.

    States, inputs and exogenous signals are sampled at t_k (linear interpolation); with
    ``mean``, outputs and powers become their mean over [t_k, t_k + Ts), from the cumulative
    trapezoidal integral, so energies are preserved (a CoolSim export at 0.01 s keeps its
    P * dt); without it they are sampled at t_k too. With ``centered``, states, inputs and
    exogenous signals are their mean over [t_k - Ts/2, t_k + Ts/2) instead (clipped to the
    record at its ends): still aligned with t_k, with a quantised or noisy sensor's steps
    averaged out. A censoring mask is 1 on every interval that holds a censored sample.
    """
    from scipy.integrate import cumulative_trapezoid

    n = int(np.floor((time[-1] - time[0]) / Ts + 1e-9))
    if n < 1:
        raise DataError(f"{source}: record shorter than one sample period Ts = {Ts:g} s")
    edges = time[0] + Ts * np.arange(n + 1)
    out = {}
    for name, v in chans.items():
        if name.endswith(CENSORED_SUFFIX):
            hits = np.concatenate(([0.0], np.cumsum(v)))
            idx = np.searchsorted(time, edges, side="left")
            out[name] = (np.diff(hits[idx]) > 0).astype(float)
        elif mean and _is_interval_mean(name):
            integral = np.interp(edges, time, cumulative_trapezoid(v, time, initial=0.0))
            out[name] = np.diff(integral) / Ts
        elif centered:
            lo = np.maximum(edges[:-1] - Ts / 2, time[0])
            hi = np.minimum(edges[:-1] + Ts / 2, time[-1])
            integral = cumulative_trapezoid(v, time, initial=0.0)
            out[name] = (np.interp(hi, time, integral) - np.interp(lo, time, integral)) / (hi - lo)
        else:
            out[name] = np.interp(edges[:-1], time, v)
    return out


def _read_csv_columns(path: Path, cmap: ChannelMap) -> tuple[dict[str, object], str]:
    """The columns of a CSV file (``.gz`` decompressed) as the map says it is written, and a
    hint for a missing-column error (a separator or encoding that looks wrong)."""
    import pandas as pd

    try:
        df = pd.read_csv(path, sep=cmap.sep, encoding=cmap.encoding, decimal=cmap.decimal,
                         compression="gzip" if path.name.lower().endswith(".gz") else None,
                         low_memory=False)
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: cannot parse CSV: not {cmap.encoding} text (byte "
                        f"0x{exc.object[exc.start]:02x} at {exc.start}); set encoding in the "
                        f"map (e.g. encoding = \"latin-1\")") from None
    except Exception as exc:  # noqa: BLE001 - any parser failure is the file's fault
        raise DataError(f"{path}: cannot parse CSV ({exc.__class__.__name__}: "
                        f"{_first_line(exc)})") from None
    wanted = set(cmap.columns)
    cols: dict[str, object] = {}
    for c in df.columns:
        key = str(c).strip()
        if key in cols and key in wanted:
            raise DataError(f"{path}: column {key!r} appears more than once")
        if key not in wanted:
            cols.setdefault(key, None)
            continue
        try:
            cols[key] = pd.to_numeric(df[c], errors="raise").to_numpy(dtype=float)
        except (ValueError, TypeError):
            cols[key] = df[c].to_numpy(dtype=object)  # refused by name if the map uses it
    hint = ""
    if len(df.columns) == 1:
        header = str(df.columns[0])
        for sep in (";", "\t", ",", "|"):
            if sep != cmap.sep and sep in header:
                hint = f" (the header holds {sep!r}: set sep = {sep!r} in the map)"
                break
    return cols, hint


def _to_degC(ds: Dataset) -> Dataset:
    """Store temperatures in degC (the layout's convention) once they passed validation."""
    for name, unit in list(ds.units.items()):
        if unit == "K":
            ds.channels[name] = convert(ds.channels[name], "K", "degC")
            ds.units[name] = "degC"
    return ds


def from_csv(path: str | os.PathLike, cmap: ChannelMap) -> Dataset:
    """Import a CSV file (header row of column names; ``.gz`` read transparently) through an
    explicit channel map."""
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: CSV file not found")
    cols, hint = _read_csv_columns(path, cmap)
    cols = {k: v for k, v in cols.items() if v is not None}
    return _to_degC(_assemble(cols, cmap, str(path), {"imported_from": "csv"}, hint).validate())


def from_mat(path: str | os.PathLike, cmap: ChannelMap) -> Dataset:
    """Import a MATLAB .mat file (v5 via scipy, v7.3 via h5py) through a channel map.

    Columns are variable names; ``struct.field`` reaches into a struct (as CoolSim's
    "To Workspace" blocks export). Each variable must be a numeric vector.
    """
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: MAT file not found")
    import scipy.io

    wanted = cmap.columns
    try:
        major, _ = scipy.io.matlab.matfile_version(path)
        cols = _read_mat73(path, wanted) if major == 2 else _read_mat5(path, wanted)
    except DataError:
        raise
    except Exception as exc:  # noqa: BLE001 - scipy/h5py raise many types on foreign files
        raise DataError(f"{path}: cannot read as a MAT file ({exc.__class__.__name__}: "
                        f"{_first_line(exc)})") from None
    return _to_degC(_assemble(cols, cmap, str(path), {"imported_from": "mat"}).validate())


def log_kind(path: str | os.PathLike) -> str:
    """``"csv"`` or ``"mat"`` from a file's suffix; ``DataError`` for anything else."""
    name = Path(path).name.lower()
    if name.endswith(CSV_SUFFIXES):
        return "csv"
    if name.endswith(MAT_SUFFIXES):
        return "mat"
    suffix = "".join(Path(path).suffixes[-2:]) or "(none)"
    raise DataError(f"{path}: unknown file type {suffix!r} "
                    f"(expected {', '.join(CSV_SUFFIXES + MAT_SUFFIXES)})")


def experiment_name(path: str | os.PathLike) -> str:
    """A file's name without its log suffixes (``TripA01.csv.gz`` -> ``TripA01``)."""
    name = Path(path).name
    for suffix in sorted(CSV_SUFFIXES + MAT_SUFFIXES, key=len, reverse=True):
        if name.lower().endswith(suffix):
            return name[:-len(suffix)] or name
    return name


def import_logs(paths: Iterable[str | os.PathLike], cmap: ChannelMap,
                names: Iterable[str] | None = None) -> Dataset:
    """Import several logs through one map as one dataset, one experiment per file.

    Each experiment keeps its name (the file name without suffixes, or ``names``), source,
    first time stamp and the findings of its checks in ``metadata["experiments"]``;
    ``metadata["censoring"]`` holds the levels found censored across the files
    (:func:`acid.logcheck.censored_across`). Regressors never cross an experiment.
    """
    paths = [Path(p) for p in paths]
    if not paths:
        raise DataError("no log to import")
    names = list(names) if names is not None else [experiment_name(p) for p in paths]
    if len(names) != len(paths):
        raise DataError(f"{len(names)} names for {len(paths)} files")
    for i, n in enumerate(names):  # the same file name in two folders: keep both apart
        if n in names[:i]:
            names[i] = f"{n}-{names[:i + 1].count(n)}"
    parts, records = [], []
    for name, path in zip(names, paths, strict=True):
        ds = from_csv(path, cmap) if log_kind(path) == "csv" else from_mat(path, cmap)
        parts.append(ds)
        checks = ds.metadata.get("checks", [])
        records.append({"name": name, "source": str(path), "samples": len(ds),
                        "duration_s": ds.duration, "t_start_s": float(ds.time[0]),
                        "imported_from": ds.metadata.get("imported_from"),
                        "resample": ds.metadata.get("resample"),
                        "censored": ds.metadata.get("censored", {}),
                        "extremes": ds.metadata.get("extremes", {}),
                        "checks": checks, "quality": quality_table(checks)})
    out = Dataset.concatenate(parts) if len(parts) > 1 else parts[0]  # masks made common
    first = parts[0].metadata
    meta = {k: first[k] for k in ("imported_from", "channel_map", "assumed", "resample")
            if k in first}
    meta.update(source=str(paths[0]) if len(paths) == 1 else f"{len(paths)} files",
                experiments=records, censoring=censored_across(records))
    declared = {n: {k: getattr(s, k) for k in ("censored_above", "censored_below")
                    if getattr(s, k) is not None} | {"unit": s.unit}
                for n, s in cmap.channels.items()
                if s.censored_above is not None or s.censored_below is not None}
    if declared:
        meta["censored"] = declared
    if cmap.description:
        meta["description"] = cmap.description
    out.metadata = meta
    out.source = meta["source"]
    return out


#: Kinds of finding that mark samples as not measurements (masked at import).
QUALITY_KINDS = ("bridged", "glitch", "jump", "range")


def quality_table(checks: list[dict]) -> list[dict]:
    """One row per channel and kind of flag of a file's checks: {channel, kind, count,
    samples, first_at_s} (count: stretches or events; times in the file's own clock)."""
    return [{k: f[k] for k in ("channel", "kind", "count", "samples", "first_at_s")}
            for f in checks if f.get("kind") in QUALITY_KINDS]


def _read_mat5(path: Path, wanted: list[str]) -> dict[str, object]:
    """Variables (``struct.field`` paths) of a MATLAB v4/v5/v7 file, via scipy."""
    import scipy.io

    mat = scipy.io.loadmat(path, squeeze_me=True, struct_as_record=False)
    cols = {}
    for key in wanted:
        obj, ok = mat, True
        for part in key.split("."):
            ok = part in obj if isinstance(obj, dict) else (
                hasattr(obj, "_fieldnames") and part in obj._fieldnames)
            obj = obj.get(part) if isinstance(obj, dict) else getattr(obj, part, None)
            if not ok:
                break
        if ok:
            cols[key] = obj
    return cols


def _read_mat73(path: Path, wanted: list[str]) -> dict[str, object]:
    """Variables of a MATLAB v7.3 file (HDF5 inside; structs are groups), via h5py."""
    import h5py

    cols: dict[str, object] = {}
    with h5py.File(path, "r") as f:
        for key in wanted:
            h5key = key.replace(".", "/")
            if not h5key or h5key.startswith("/") or "//" in h5key or h5key not in f:
                continue
            obj = f[h5key]
            if isinstance(obj, h5py.Group):
                cols[key] = {name: None for name in obj}  # a struct: refused by name
            elif obj.dtype.kind not in "biuf":
                cols[key] = np.empty(0, dtype=object)  # references (cells), text: refused
            else:
                check_size(obj.size, f"{path}: variable {key!r}")
                cols[key] = obj[()]
    return cols
