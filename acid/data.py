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
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from acid import __version__
from acid._io import atomic_path
from acid.errors import DataError
from acid.units import KNOWN_UNITS, convert, is_temperature, temperature_unit_consistent

FORMAT_NAME = "acid-dataset"
FORMAT_VERSION = 1

ROLES = ("input", "state", "output", "exogenous", "auxiliary")


@dataclass(frozen=True)
class ChannelSpec:
    """What a channel is: canonical unit, role in the model, description."""

    unit: str
    role: str
    description: str


#: The channels acid knows by name (others are allowed, as auxiliary channels).
CHANNELS: dict[str, ChannelSpec] = {
    "T_cab": ChannelSpec("degC", "state", "cabin air temperature"),
    "T_evap": ChannelSpec("degC", "state", "evaporator wall temperature"),
    "T_ain": ChannelSpec("degC", "output", "cabin inlet (supply) air temperature"),
    "W_bl": ChannelSpec("kg/s", "input", "blower air mass flow"),
    "T_evap_set": ChannelSpec("degC", "input", "evaporator wall temperature set-point"),
    "T_int": ChannelSpec("degC", "exogenous", "cabin interior (seats, dash) temperature"),
    "T_shell": ChannelSpec("degC", "exogenous", "cabin shell (roof, doors, glass) temperature"),
    "T_amb": ChannelSpec("degC", "exogenous", "ambient air temperature"),
    "v_veh": ChannelSpec("m/s", "exogenous", "vehicle speed"),
    "N_comp": ChannelSpec("rpm", "auxiliary", "compressor speed"),
    "P_comp": ChannelSpec("W", "auxiliary", "compressor electrical power"),
    "P_bl": ChannelSpec("W", "auxiliary", "blower electrical power"),
    "P_fan": ChannelSpec("W", "auxiliary", "condenser fan electrical power"),
    "COP": ChannelSpec("1", "auxiliary", "cycle coefficient of performance Q_e / P_comp"),
    "recirc": ChannelSpec("1", "auxiliary", "recirculated fraction of blower air"),
    "w_cab": ChannelSpec("kg/kg", "auxiliary", "cabin air humidity ratio"),
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
        """Join datasets as separate experiments (ids renumbered, time made contiguous)."""
        if not parts:
            raise DataError("nothing to concatenate")
        names = list(parts[0].channels)
        Ts = parts[0].Ts
        times, chans, exps = [], {n: [] for n in names}, []
        t0, eid = 0.0, 0
        for p in parts:
            if abs(p.Ts - Ts) > 1e-9:
                raise DataError(f"{p.source}: sample time {p.Ts} s differs from {Ts} s")
            for n in names:
                chans[n].append(p.get(n, parts[0].units[n]))
            times.append(t0 + (p.time - p.time[0]))
            t0 = times[-1][-1] + Ts
            ids = np.unique(p.experiment, return_inverse=True)[1]
            exps.append(ids + eid)
            eid += ids.max() + 1
        return Dataset(np.concatenate(times), {n: np.concatenate(v) for n, v in chans.items()},
                       dict(parts[0].units), Ts, np.concatenate(exps), dict(parts[0].roles),
                       dict(parts[0].metadata))

    def to_pandas(self):
        """A DataFrame indexed by time (s), one column per channel, units in ``df.attrs``."""
        import pandas as pd

        df = pd.DataFrame(self.channels, index=pd.Index(self.time, name="time_s"))
        df["experiment"] = self.experiment
        df.attrs["units"] = dict(self.units)
        df.attrs["Ts"] = self.Ts
        return df

    # ------------------------------------------------------------ validation
    def validate(self, require: Iterable[str] = (), min_samples: int = 2) -> Dataset:
        """Refuse data that cannot be trusted; returns ``self`` so calls chain.

        Checks: required channels present, values finite, time strictly increasing and
        uniform at ``Ts``, temperatures consistent with their declared unit, enough samples.
        """
        src = self.source
        for name in require:
            if name not in self.channels:
                raise DataError(f"{src}: missing channel {name!r}")
        n = len(self)
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
        with atomic_path(path) as tmp:
            with h5py.File(tmp, "w", track_order=True) as f:
                _write_group(f, self, meta)
                if self.fine is not None:
                    _write_group(f.create_group("fine"), self.fine, None)
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
                if f.attrs.get("format") != FORMAT_NAME:
                    raise DataError(f"{path}: not an acid dataset (missing format={FORMAT_NAME!r};"
                                    " import CSV or MAT files with `acid import`)")
                ds = _read_group(f, str(path))
                if "fine" in f:
                    ds.fine = _read_group(f["fine"], f"{path}:/fine")
        except OSError as exc:
            raise DataError(f"{path}: cannot read as HDF5 ({exc})") from None
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


def _read_group(g, source: str) -> Dataset:
    if "time" not in g:
        raise DataError(f"{source}: missing /time")
    if "channels" not in g:
        raise DataError(f"{source}: missing /channels group")
    Ts = g.attrs.get("Ts")
    if Ts is None:
        raise DataError(f"{source}: missing attribute Ts (sample time)")
    channels, units, roles = {}, {}, {}
    for name, d in g["channels"].items():
        unit = d.attrs.get("unit")
        if unit is None:
            raise DataError(f"{source}: channel {name!r} has no unit attribute")
        channels[name] = d[()]
        units[name] = unit.decode() if isinstance(unit, bytes) else str(unit)
        roles[name] = str(d.attrs.get("role", "auxiliary"))
    meta = {}
    if "metadata" in g.attrs:
        try:
            meta = json.loads(g.attrs["metadata"])
        except json.JSONDecodeError:
            raise DataError(f"{source}: metadata attribute is not valid JSON") from None
    exp = g["experiment"][()] if "experiment" in g else None
    time = g["time"][()]
    if exp is not None and exp.shape != time.shape:
        raise DataError(f"{source}: /experiment has {exp.shape[0]} samples, "
                        f"time has {time.shape[0]}")
    return Dataset(time=time, channels=channels, units=units, Ts=float(Ts), experiment=exp,
                   roles=roles, metadata=meta, source=source)


# ------------------------------------------------------------------ importers
@dataclass(frozen=True)
class ChannelMap:
    """How columns of a foreign file become acid channels.

    ``time``: name of the time column (s); ``channels``: {acid name: (column, unit)}.
    Loaded from TOML or JSON::

        time = "t"
        Ts = 5.0            # optional: resample onto this grid by linear interpolation
        [channels]
        T_cab = { column = "CabinAirTemp", unit = "degC" }
        W_bl  = { column = "BlowerFlow", unit = "kg/s" }
    """

    time: str
    channels: Mapping[str, tuple[str, str]]
    Ts: float | None = None

    @classmethod
    def from_file(cls, path: str | os.PathLike) -> ChannelMap:
        path = Path(path)
        if not path.is_file():
            raise DataError(f"{path}: channel map not found")
        try:
            if path.suffix.lower() == ".json":
                d = json.loads(path.read_text())
            else:
                try:
                    import tomllib
                except ModuleNotFoundError:  # Python < 3.11
                    import tomli as tomllib
                d = tomllib.loads(path.read_text())
        except Exception as exc:
            raise DataError(f"{path}: cannot parse channel map ({exc})") from None
        return cls.from_dict(d, str(path))

    @classmethod
    def from_dict(cls, d: dict, source: str = "channel map") -> ChannelMap:
        if "time" not in d or "channels" not in d:
            raise DataError(f"{source}: needs 'time' and a [channels] table")
        if not isinstance(d["channels"], Mapping):
            raise DataError(f"{source}: [channels] must be a table of channel = column entries")
        chans = {}
        for name, spec in d["channels"].items():
            if isinstance(spec, str):
                spec = {"column": spec}
            if not isinstance(spec, Mapping):
                raise DataError(f"{source}: channel {name!r} must be a column name or "
                                f"{{ column = ..., unit = ... }}, got {spec!r}")
            col = spec.get("column")
            unit = spec.get("unit", CHANNELS[name].unit if name in CHANNELS else None)
            if col is None or unit is None:
                raise DataError(f"{source}: channel {name!r} needs 'column' and 'unit'")
            if unit not in KNOWN_UNITS:
                raise DataError(f"{source}: channel {name!r} has unknown unit {unit!r}")
            chans[name] = (str(col), str(unit))
        Ts = d.get("Ts")
        return cls(time=str(d["time"]), channels=chans, Ts=None if Ts is None else float(Ts))


def _assemble(columns: Mapping[str, np.ndarray], cmap: ChannelMap, source: str,
              metadata: dict) -> Dataset:
    if cmap.time not in columns:
        raise DataError(f"{source}: missing time column {cmap.time!r}")
    time = np.asarray(columns[cmap.time], dtype=float).ravel()
    chans, units = {}, {}
    for name, (col, unit) in cmap.channels.items():
        if col not in columns:
            raise DataError(f"{source}: missing column {col!r} (for channel {name!r})")
        v = np.asarray(columns[col], dtype=float).ravel()
        if v.shape != time.shape:
            raise DataError(f"{source}: column {col!r} has {v.size} values, time has {time.size}")
        chans[name], units[name] = v, unit
    if cmap.Ts is not None:
        bad = ~np.isfinite(time)
        if bad.any() or np.any(np.diff(time) <= 0):
            raise DataError(f"{source}: time column {cmap.time!r} is not strictly increasing")
        chans = _resample(time, chans, cmap.Ts, source)
        time, Ts = np.arange(len(next(iter(chans.values())))) * cmap.Ts + time[0], cmap.Ts
    else:
        Ts = float(np.median(np.diff(time))) if time.size > 1 else 1.0
    meta = {"source": source, "channel_map": {k: list(v) for k, v in cmap.channels.items()}}
    meta.update(metadata)
    return Dataset(time=time, channels=chans, units=units, Ts=Ts, metadata=meta, source=source)


def _is_interval_mean(name: str) -> bool:
    """Outputs and powers are means over each sample interval (the sample convention)."""
    spec = CHANNELS.get(name)
    return (spec is not None and spec.role == "output") or name.startswith(("P_", "Q_"))


def _resample(time: np.ndarray, chans: dict[str, np.ndarray], Ts: float,
              source: str) -> dict[str, np.ndarray]:
    """Resample a finely sampled record onto a Ts grid following the sample convention.

    States, inputs and exogenous signals are sampled at t_k (linear interpolation); outputs
    and powers become their mean over [t_k, t_k + Ts), from the cumulative trapezoidal
    integral, so energies are preserved (a CoolSim export at 0.01 s keeps its P * dt).
    """
    from scipy.integrate import cumulative_trapezoid

    n = int(np.floor((time[-1] - time[0]) / Ts + 1e-9))
    if n < 1:
        raise DataError(f"{source}: record shorter than one sample period Ts = {Ts:g} s")
    edges = time[0] + Ts * np.arange(n + 1)
    out = {}
    for name, v in chans.items():
        if _is_interval_mean(name):
            integral = np.interp(edges, time, cumulative_trapezoid(v, time, initial=0.0))
            out[name] = np.diff(integral) / Ts
        else:
            out[name] = np.interp(edges[:-1], time, v)
    return out


def _to_degC(ds: Dataset) -> Dataset:
    """Store temperatures in degC (the layout's convention) once they passed validation."""
    for name, unit in list(ds.units.items()):
        if unit == "K":
            ds.channels[name] = convert(ds.channels[name], "K", "degC")
            ds.units[name] = "degC"
    return ds


def from_csv(path: str | os.PathLike, cmap: ChannelMap) -> Dataset:
    """Import a CSV file (header row of column names) through an explicit channel map."""
    import pandas as pd

    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: CSV file not found")
    try:
        df = pd.read_csv(path)
    except Exception as exc:
        raise DataError(f"{path}: cannot parse CSV ({exc.__class__.__name__})") from None
    cols = {}
    for c in df.columns:
        try:
            cols[str(c).strip()] = pd.to_numeric(df[c], errors="raise").to_numpy(dtype=float)
        except (ValueError, TypeError):
            continue  # non-numeric columns are only an error if the map asks for them
    return _to_degC(_assemble(cols, cmap, str(path), {"imported_from": "csv"}).validate())


def from_mat(path: str | os.PathLike, cmap: ChannelMap) -> Dataset:
    """Import a MATLAB .mat file (v5 via scipy, v7.3 via h5py) through a channel map.

    Columns are variable names; ``struct.field`` reaches into a struct (as CoolSim's
    "To Workspace" blocks export). Each variable must be a vector.
    """
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: MAT file not found")
    import scipy.io

    wanted = [cmap.time] + [c for c, _ in cmap.channels.values()]
    try:
        major, _ = scipy.io.matlab.matfile_version(path)
        cols = _read_mat73(path, wanted) if major == 2 else _read_mat5(path, wanted)
    except (ValueError, OSError) as exc:
        raise DataError(f"{path}: cannot read as a MAT file ({exc})") from None
    return _to_degC(_assemble(cols, cmap, str(path), {"imported_from": "mat"}).validate())


def _read_mat5(path: Path, wanted: list[str]) -> dict[str, np.ndarray]:
    """Variables (``struct.field`` paths) of a MATLAB v4/v5/v7 file, via scipy."""
    import scipy.io

    mat = scipy.io.loadmat(path, squeeze_me=True, struct_as_record=False)
    cols = {}
    for key in wanted:
        obj, ok = mat, True
        for part in key.split("."):
            ok = part in obj if isinstance(obj, dict) else hasattr(obj, part)
            obj = obj.get(part) if isinstance(obj, dict) else getattr(obj, part, None)
            if not ok:
                break
        if ok:
            cols[key] = np.asarray(obj, dtype=float).ravel()
    return cols


def _read_mat73(path: Path, wanted: list[str]) -> dict[str, np.ndarray]:
    """Variables of a MATLAB v7.3 file (HDF5 inside; structs are groups), via h5py."""
    import h5py

    cols = {}
    with h5py.File(path, "r") as f:
        for key in wanted:
            h5key = key.replace(".", "/")
            if h5key in f:
                cols[key] = np.asarray(f[h5key][()], dtype=float).ravel()
    return cols
