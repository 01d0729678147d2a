"""Random inputs for every reader of acid (property-based, hypothesis).

Each reader is a ``Reader``: a hypothesis strategy of files (mostly *almost* valid ones: a
valid layout with random damage, plus arbitrary bytes) and a ``read(path)`` that calls
acid's reader. The property: reading never raises anything but ``AcidError``.

``tests/test_readers_property.py`` runs them (100-200 examples per reader in the suite;
``--hypothesis-profile=acid-thorough`` for 1,500). As a script this module counts escapes
instead of stopping at the first, e.g. to compare acid versions:

    python tests/_fuzz.py 1500          # escapes per reader over 1,500 examples each
"""

from __future__ import annotations

import json
import math
import sys
import tempfile
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from hypothesis import strategies as st

MODEL = ("T_cab", "T_evap", "T_ain", "W_bl", "T_evap_set", "T_int", "T_shell")


@dataclass(frozen=True)
class Reader:
    """A reader under test: ``files`` draws a writer ``(path) -> None``; ``read`` reads."""

    name: str
    suffix: str
    files: st.SearchStrategy
    read: Callable[[Path], object]


# --------------------------------------------------------------------- building blocks
finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
any_float = st.floats(width=64)
odd_float = st.sampled_from([0.0, -0.0, 5.0, -5.0, 1e-9, 1e308, -1e308, math.nan, math.inf,
                             -math.inf, 1e-320])
small_text = st.text(max_size=12)

json_scalar = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6), any_float,
                        small_text)
json_value = st.recursive(json_scalar, lambda kids: st.one_of(
    st.lists(kids, max_size=8), st.dictionaries(small_text, kids, max_size=6)), max_leaves=25)


def raw_bytes(prefix: bytes = b"") -> st.SearchStrategy:
    """A writer of arbitrary bytes (optionally after a magic prefix)."""
    return st.binary(max_size=300).map(lambda b: _bytes_writer(prefix + b))


def _bytes_writer(data: bytes) -> Callable[[Path], None]:
    def write(path: Path) -> None:
        path.write_bytes(data)
    return write


def _text_writer(text: str) -> Callable[[Path], None]:
    def write(path: Path) -> None:
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
    return write


def damaged(text: str) -> st.SearchStrategy:
    """``text`` with up to three random edits (insert, delete, replace a character)."""
    @st.composite
    def edit(draw):
        s = text
        for _ in range(draw(st.integers(1, 3))):
            i = draw(st.integers(0, len(s)))
            op = draw(st.sampled_from(["ins", "del", "rep"]))
            ch = draw(st.sampled_from(list('[]{}="\n,.#0-9eE+-aZ \\') + ["nan", "inf", "'"]))
            if op == "ins":
                s = s[:i] + ch + s[i:]
            elif op == "del":
                s = s[:i] + s[i + 1:]
            else:
                s = s[:i] + ch + s[i + 1:]
        return _text_writer(s)
    return edit()


# ---------------------------------------------------------------------------- TOML
def toml_value(v) -> str:
    """A TOML literal for a Python value (bool, int, float, str, list, dict)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{toml_value(k)} = {toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(type(v))


def toml_document(d: dict) -> str:
    """Top-level keys first, then ``[table]`` sections for dict values."""
    lines = [f"{toml_value(k)} = {toml_value(v)}" for k, v in d.items()
             if not isinstance(v, dict)]
    for k, v in d.items():
        if isinstance(v, dict):
            lines.append(f"[{toml_value(k)}]")
            lines += [f"{toml_value(kk)} = {toml_value(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


toml_scalar = st.one_of(st.booleans(), st.integers(-2**63, 2**63 - 1), any_float, small_text)
toml_any = st.recursive(toml_scalar, lambda kids: st.one_of(
    st.lists(kids, max_size=4), st.dictionaries(small_text, kids, max_size=4)), max_leaves=12)


# ---------------------------------------------------------------------------- HDF5
weird_attr = st.one_of(
    small_text, st.binary(max_size=8), any_float, odd_float, st.integers(-2**31, 2**31),
    st.booleans(),
    st.lists(any_float, max_size=3).map(lambda v: np.array(v, dtype=float)),
    st.lists(small_text.filter(lambda s: "\x00" not in s), min_size=1, max_size=3),
)


@st.composite
def weird_array(draw, n: int):
    kind = draw(st.sampled_from(["float", "int", "bool", "bytes", "2d", "scalar", "short",
                                 "empty", "complex", "huge"]))
    if kind == "float":
        return np.array(draw(st.lists(any_float, min_size=n, max_size=n)), dtype=float)
    if kind == "int":
        return np.array(draw(st.lists(st.integers(-2**40, 2**40), min_size=n, max_size=n)),
                        dtype=np.int64)
    if kind == "bool":
        return np.ones(n, dtype=bool)
    if kind == "bytes":
        return np.array([b"x"] * n)
    if kind == "2d":
        return np.zeros((n, 2))
    if kind == "scalar":
        return np.float64(draw(any_float))
    if kind == "short":
        return np.zeros(max(n - 1, 0))
    if kind == "complex":
        return np.zeros(n, dtype=complex)
    if kind == "huge":
        return np.full(n, draw(st.sampled_from([1e308, -1e308, 1e30])))
    return np.zeros(0)


GOOD_VALUE = {"W_bl": 0.1, "v_veh": 0.0, "recirc": 0.5, "P_comp": 500.0}
GOOD_UNIT = {"W_bl": "kg/s", "v_veh": "m/s", "recirc": "1", "P_comp": "W"}
HDF5_PARTS = ("format", "Ts", "metadata", "time", "experiment", "channels", "fine", "unit",
              "role", "data", "names")


@st.composite
def hdf5_files(draw):
    """A valid dataset file in acid's layout with one to three parts damaged at random."""
    n = draw(st.integers(0, 40))
    Ts = 5.0
    bad = draw(st.sets(st.sampled_from(HDF5_PARTS), max_size=3))

    def pick(part, good, weird):
        return draw(weird) if part in bad else good

    plan: dict = {
        "format": pick("format", "acid-dataset", st.one_of(weird_attr, st.none(),
                                                           st.just(b"acid-dataset"))),
        "Ts": pick("Ts", Ts, st.one_of(weird_attr, st.none())),
        "metadata": pick("metadata", "{}", st.one_of(json_value.map(json.dumps), weird_attr)),
        "time": pick("time", np.arange(n) * Ts, st.one_of(weird_array(n), st.none())),
        "experiment": pick("experiment", np.zeros(n, dtype=np.int32),
                           st.one_of(weird_array(n), st.none())),
        "channels_is_group": "channels" not in bad or draw(st.booleans()),
        "fine": "fine" in bad,
    }
    names = list(MODEL) + draw(st.lists(st.sampled_from(["v_veh", "P_comp", "x", "recirc"]),
                                        max_size=2, unique=True))
    if "names" in bad:
        names = draw(st.lists(st.sampled_from(names), max_size=len(names), unique=True))
    chans = []
    for name in names:
        good = np.full(n, GOOD_VALUE.get(name, 20.0))
        data = draw(st.one_of(weird_array(n), st.just(-good))) if (
            "data" in bad and draw(st.booleans())) else good
        unit = GOOD_UNIT.get(name, "degC")
        if "unit" in bad and draw(st.booleans()):
            unit = draw(st.one_of(st.sampled_from(["degC", "K", "kg/s", "m/s", "W", "1"]),
                                  weird_attr, st.none()))
        role = draw(st.one_of(st.none(), weird_attr)) if "role" in bad else None
        chans.append((name, data, unit, role))
    extra_group = "channels" in bad and draw(st.booleans())

    def write(path: Path) -> None:
        import h5py

        with h5py.File(path, "w") as f:
            _set(f, "format", plan["format"])
            _set(f, "Ts", plan["Ts"])
            _set(f, "metadata", plan["metadata"])
            if plan["time"] is not None:
                f.create_dataset("time", data=plan["time"])
            if plan["experiment"] is not None:
                f.create_dataset("experiment", data=plan["experiment"])
            if plan["channels_is_group"]:
                g = f.create_group("channels")
                for name, data, unit, role in chans:
                    d = g.create_dataset(name, data=data)
                    _set(d, "unit", unit)
                    _set(d, "role", role)
                if extra_group:
                    g.create_group("sub")
            else:
                f.create_dataset("channels", data=np.zeros(3))
            if plan["fine"]:
                fg = f.create_group("fine")
                _set(fg, "Ts", draw_fine_Ts)
                fg.create_dataset("time", data=np.arange(3.0))
    draw_fine_Ts = draw(st.one_of(st.just(1.0), weird_attr))
    return write


def _set(obj, key: str, value) -> None:
    if value is None:
        return
    try:
        obj.attrs[key] = value
    except (TypeError, ValueError, OverflowError):
        pass  # h5py cannot store this value: the file simply lacks the attribute


def _read_hdf5(path: Path):
    from acid.data import MODEL_CHANNELS, Dataset

    return Dataset.from_hdf5(path, require=MODEL_CHANNELS[:3], min_samples=2)


# ----------------------------------------------------------------------------- CSV
csv_cell = st.one_of(finite.map(lambda v: f"{v:.6g}"), st.sampled_from(
    ["", "nan", "inf", "-inf", "1e400", "x", '"', '"a,b"', "0x10", " 5 ", "1,5", "TRUE"]),
    st.text(alphabet=st.characters(blacklist_characters="\n\r", codec="utf-8"), max_size=5))


@st.composite
def csv_files(draw):
    """A CSV export with the mapped columns, sometimes damaged cells, columns or steps."""
    if draw(st.integers(0, 9)) == 0:
        return draw(raw_bytes())
    cols = ["t", "Tcab", "Wbl", "Tevap", "other"]
    if draw(st.integers(0, 3)) == 0:
        cols = draw(st.lists(st.sampled_from(cols + ["t ", "Tcab"]), max_size=6))
    n = draw(st.integers(0, 40))
    dt = draw(st.sampled_from([5.0, 5.0, 1.0, 0.5, 0.01, 2.5, 10.0, -1.0, 0.0]))
    damage = draw(st.integers(0, 3)) == 0
    level = {c: draw(st.sampled_from(["0.1", "0.1", "-0.1", "3"] if c == "Wbl" else
                                     ["20", "21.5", "20", "300", "-400"])) for c in cols}
    rows = []
    for i in range(n):
        row = []
        for c in cols:
            if damage and draw(st.integers(0, 8)) == 0:
                row.append(draw(csv_cell))
            elif c.strip() == "t":
                row.append(f"{i * dt:g}")
            else:
                row.append(level[c])
        rows.append(",".join(row))
    text = ",".join(cols) + "\n" + "\n".join(rows) + "\n"
    form = draw(st.sampled_from(["plain", "plain", "car", "gzip", "gzip-garbage"]))
    if form == "plain":
        return _text_writer(text)
    # a car's log: ';' between columns, decimal comma, a Latin-1 degree sign, maybe gzip'd
    car = text.replace(",", ";").replace(".", ",").replace("Tcab", "Tcab \u00b0C", 0)
    data = car.encode("latin-1", errors="replace") if form == "car" else text.encode()
    if form == "gzip":
        import gzip

        data = gzip.compress(car.encode("latin-1", errors="replace"), mtime=0)
        if draw(st.booleans()):
            data = data[:draw(st.integers(0, len(data)))]
    elif form == "gzip-garbage":
        data = b"\x1f\x8b" + draw(st.binary(max_size=60))
    return _bytes_writer(data)


csv_maps = st.builds(
    lambda Ts, resample, tunit, fmt, extra: {
        "time": "t", **({"Ts": Ts} if Ts is not None else {}),
        **({"resample": resample} if resample and Ts else {}), **fmt,
        "channels": {"T_cab": {"column": "Tcab", "unit": tunit},
                     "W_bl": {"column": "Wbl", "unit": "kg/s"}, "T_evap": "Tevap", **extra}},
    st.sampled_from([None, 5.0, 1.0, 0.5, 100.0, 1e-3]),
    st.sampled_from([None, "mean", "centered", "sample", "none"]),
    st.sampled_from(["degC", "degC", "K", "degF"]),
    st.sampled_from([{}, {}, {"sep": ";", "decimal": ",", "encoding": "latin-1"},
                     {"sep": ";", "encoding": "utf-8"}, {"decimal": ","}]),
    st.sampled_from([{}, {"T_ain": {"expr": "T_evap + 1", "unit": "degC"}},
                     {"T_ain": {"expr": "log(T_cab) / (T_evap - T_evap)", "unit": "degC"}},
                     {"v_veh": {"constant": 10.0, "unit": "km/h"}},
                     {"P_comp": {"column": "other", "unit": "kW", "censored_above": 1.0}},
                     {"T_int": {"column": "other", "unit": "degC", "censored_below": 20}}]))


@st.composite
def csv_with_map(draw):
    return draw(csv_files()), draw(csv_maps)


# ------------------------------------------------------------------------------ MAT
@st.composite
def mat_value(draw, depth: int = 0):
    kind = draw(st.sampled_from(["vec", "col", "mat", "scalar", "int", "bool", "complex",
                                 "text", "empty", "cell"] + (["struct"] if depth < 2 else [])))
    k = draw(st.integers(0, 12))
    if kind == "vec":
        return np.array(draw(st.lists(any_float, min_size=k, max_size=k)))
    if kind == "col":
        return np.arange(k, dtype=float).reshape(-1, 1)
    if kind == "mat":
        return np.zeros((k, 3))
    if kind == "scalar":
        return draw(any_float)
    if kind == "int":
        return np.arange(k, dtype=np.int16)
    if kind == "bool":
        return np.ones(k, dtype=bool)
    if kind == "complex":
        return np.ones(k, dtype=complex)
    if kind == "text":
        return draw(st.text(alphabet="abc xyz", max_size=6))
    if kind == "empty":
        return np.zeros(0)
    if kind == "cell":
        cell = np.empty(2, dtype=object)
        cell[0], cell[1] = np.arange(3.0), "x"
        return cell
    return {name: draw(mat_value(depth + 1))
            for name in draw(st.lists(st.sampled_from(["t", "Tcab", "Wbl", "sub"]),
                                      max_size=3, unique=True))}


@st.composite
def mat_files(draw):
    """A MATLAB file (v5 via scipy or v7.3 via h5py): a valid CoolSim-like export whose
    variables are sometimes replaced by random ones, sometimes damaged on disk."""
    variant = draw(st.sampled_from(["v5", "v5", "v5", "v73", "bytes"]))
    if variant == "bytes":
        return draw(raw_bytes(draw(st.sampled_from([b"", b"MATLAB 5.0 MAT-file" + b" " * 97
                                                     + b"\x00\x01IM"]))))
    k = draw(st.integers(0, 40))
    t = np.arange(k) * draw(st.sampled_from([1.0, 5.0, 0.5]))
    sim = {"t": t, "Tcab": 300.0 + 0 * t, "Wbl": 0.1 + 0 * t}
    variables: dict = {"sim": sim, "t": t, "Tcab": 300.0 + 0 * t}
    for name in draw(st.lists(st.sampled_from(["t", "Tcab", "Wbl", "sim", "x", "sim.t",
                                               "sim.Tcab"]), max_size=3, unique=True)):
        target = sim if name.startswith("sim.") else variables
        target[name.split(".")[-1]] = draw(mat_value())
    damage = draw(st.integers(0, 3)) == 0
    cut = draw(st.one_of(st.none(), st.integers(0, 2000))) if damage else None
    flip = draw(st.one_of(st.none(), st.tuples(st.integers(0, 4000), st.integers(0, 255)))) \
        if damage else None

    def write(path: Path) -> None:
        if variant == "v5":
            import scipy.io

            try:
                scipy.io.savemat(path, variables)
            except Exception:  # noqa: BLE001 - a value scipy cannot store: write a stub
                path.write_bytes(b"")
        else:
            _write_mat73(path, variables)
        data = bytearray(path.read_bytes())
        if flip is not None and flip[0] < len(data):
            data[flip[0]] = flip[1]
        if cut is not None:
            data = data[:cut]
        path.write_bytes(bytes(data))
    return write


def _write_mat73(path: Path, variables: dict) -> None:
    import h5py

    def put(g, name, value):
        if isinstance(value, dict):
            sub = g.create_group(name)
            for k, v in value.items():
                put(sub, k, v)
        else:
            try:
                g.create_dataset(name, data=value)
            except (TypeError, ValueError):
                pass

    with h5py.File(path, "w", userblock_size=512) as f:
        for name, value in variables.items():
            put(f, name, value)
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: fuzz HDF5 schema 1.00 ."
    with open(path, "r+b") as fh:
        fh.write(header.ljust(116, b" ") + b"\0" * 8 + b"\x00\x02" + b"IM")


mat_maps = st.builds(
    lambda time, cab, Ts: {"time": time, **({"Ts": Ts} if Ts else {}),
                           "channels": {"T_cab": {"column": cab, "unit": "K"}}},
    st.sampled_from(["t", "sim.t", "sim.t", "sim", "x", "sim.sub.t"]),
    st.sampled_from(["Tcab", "sim.Tcab", "sim.Tcab", "sim", "x", "missing", "sim.sub"]),
    st.sampled_from([None, 5.0, 5.0, 1.0, 10.0]))


@st.composite
def mat_with_map(draw):
    return draw(mat_files()), draw(mat_maps)


# ----------------------------------------------------------------------- channel map
VALID_MAP = {"time": "t", "Ts": 5.0, "resample": "mean", "sep": ";", "encoding": "latin-1",
             "decimal": ",", "channels": {
                 "T_cab": {"column": "Tcab", "unit": "degC", "censored_above": 39.84},
                 "W_bl": "Wbl", "T_ain": {"expr": "min(T_cab, 30) - 2", "unit": "degC"},
                 "v_veh": {"constant": 0.0, "unit": "km/h"}}}


@st.composite
def mutated(draw, base: dict, keys: list[str], value: st.SearchStrategy):
    """``base`` (nested dict) with a few keys set to random values or removed."""
    d = json.loads(json.dumps(base))
    for _ in range(draw(st.integers(1, 3))):
        path = draw(st.sampled_from(keys)).split(".")
        target = d
        for p in path[:-1]:
            target = target.setdefault(p, {}) if isinstance(target, dict) else {}
        if not isinstance(target, dict):
            continue
        if draw(st.integers(0, 4)) == 0:
            target.pop(path[-1], None)
        else:
            target[path[-1]] = draw(value)
    return d


map_keys = ["time", "Ts", "resample", "channels", "channels.T_cab", "channels.T_cab.column",
            "channels.T_cab.unit", "channels.W_bl", "extra", "channels.a/b", "sep",
            "encoding", "decimal", "description", "time.unit", "channels.T_ain.expr",
            "channels.T_ain.unit", "channels.T_cab.censored_above", "channels.W_bl.constant",
            "channels.T_cab.note"]


@st.composite
def map_files(draw):
    kind = draw(st.sampled_from(["json", "toml", "toml", "damaged", "bytes"]))
    if kind == "bytes":
        return ".toml", draw(raw_bytes())
    if kind == "damaged":
        return ".toml", draw(damaged(toml_document(VALID_MAP)))
    if kind == "json":
        d = draw(st.one_of(mutated(VALID_MAP, map_keys, json_value), json_value))
        return ".json", _text_writer(json.dumps(d))
    d = draw(mutated(VALID_MAP, map_keys, toml_any))
    return ".toml", _text_writer(toml_document(d) if isinstance(d, dict) else "")


def _read_map(path: Path):
    from acid.data import ChannelMap

    return ChannelMap.from_file(path)


# ------------------------------------------------------------------------ parameters
def _paper_dict() -> dict:
    return {"name": "paper", "gamma": [0.2451, 0.0867, 1.2999, 1.0047, -0.5176, 0.4553,
                                       34.9579],
            "tau": [-0.1842, -1.3226, 154.4995], "beta": [24156.0, -1974.2, 49.318],
            "c_p": 1008.0, "eta_cop": 3.5, "Ts": 5.0, "units": "kelvin", "provenance": {}}


params_keys = ["name", "gamma", "tau", "beta", "c_p", "eta_cop", "Ts", "units", "provenance",
               "provenance.estimation_fraction", "extra"]
number_lists = st.lists(st.one_of(any_float, odd_float, st.integers(-10, 10), json_scalar),
                        max_size=9)


@st.composite
def params_files(draw):
    kind = draw(st.sampled_from(["mutated", "mutated", "mutated", "json", "damaged", "bytes"]))
    if kind == "bytes":
        return draw(raw_bytes())
    if kind == "damaged":
        return draw(damaged(json.dumps(_paper_dict())))
    if kind == "json":
        return _text_writer(json.dumps(draw(json_value)))
    d = draw(mutated(_paper_dict(), params_keys, st.one_of(json_value, number_lists, odd_float)))
    return _text_writer(json.dumps(d))


def _read_params(path: Path):
    from acid.models.params import load_params

    return load_params(path)


# ---------------------------------------------------------------------- plant config
def _plant_keys() -> list[str]:
    from acid.plant.config import PlantConfig

    return list(PlantConfig.field_names())


@st.composite
def plant_config_files(draw):
    from acid.plant.config import PlantConfig

    kind = draw(st.sampled_from(["flat", "sections", "sections", "damaged", "bytes"]))
    if kind == "bytes":
        return draw(raw_bytes())
    keys = _plant_keys() + ["warp", "ambient", "cabin"]
    value = st.one_of(toml_any, odd_float, st.sampled_from(
        ["R134a", "R1234yf", "water", "35 degC", "308.15 K", "95 degF", "5 W", "nan K", "K"]))
    if kind == "damaged":
        return draw(damaged('[ambient]\nT_amb = 30.0\n[initial]\nT_cab0 = "313.15 K"\n'
                            '[cabin]\nC_cab = 3877.0\n'))
    d: dict = {}
    for key in draw(st.lists(st.sampled_from(keys), max_size=6, unique=True)):
        v = draw(value)
        if kind == "sections" and key in PlantConfig.field_names():
            section = draw(st.one_of(
                st.just(PlantConfig.__dataclass_fields__[key].metadata["section"]),
                st.sampled_from(["ambient", "cabin", "solver", "nonsense"])))
            if not isinstance(d.get(section), dict):
                d[section] = {}
            d[section][key] = v
        else:
            d[key] = v
    return _text_writer(toml_document(d))


def _read_plant_config(path: Path):
    from acid.plant.config import PlantConfig

    return PlantConfig.from_toml(path)


# --------------------------------------------------- deep nesting (any TOML/JSON reader)
@st.composite
def deep_text(draw, toml: bool):
    """A document nested 20-5000 levels deep: arrays, inline tables or (TOML) dotted keys."""
    depth = draw(st.integers(20, 5000))
    kind = draw(st.sampled_from(["array", "table", "dotted"] if toml else ["array", "object"]))
    if kind == "dotted":
        return _text_writer("a" + ".a" * depth + " = 1\n")
    if toml:
        inner = "[" * depth + "]" * depth if kind == "array" else \
            "{ a = " * depth + "1" + " }" * depth
        return _text_writer(f"x = {inner}\n")
    inner = "[" * depth + "]" * depth if kind == "array" else '{"a": ' * depth + "1" + "}" * depth
    return _text_writer(f'{{"x": {inner}}}')


@st.composite
def documents(draw, base: Callable[[], dict], keys: list[str], value: st.SearchStrategy,
              toml: bool, edit: Callable | None = None):
    """A file of one kind of document: ``base()`` with keys mutated (``mutated``), or
    edited by ``edit(draw, base)`` (a strategy's own change), damaged text, deep nesting,
    or raw bytes."""
    kinds = ["mutated", "mutated", "damaged", "deep", "bytes"] + ["edit"] * 2 * bool(edit)
    kind = draw(st.sampled_from(kinds))
    if kind == "bytes":
        return draw(raw_bytes())
    if kind == "deep":
        return draw(deep_text(toml=toml))
    d = base()
    dump = toml_document if toml else (lambda x: json.dumps(x, allow_nan=True))
    if kind == "damaged":
        return draw(damaged(dump(d)))
    if kind == "edit":
        edit(draw, d)
        return _text_writer(dump(d))
    return _text_writer(dump(draw(mutated(d, keys, value))))


# ----------------------------------------------------------------------- sweep specs
VALID_SPEC = {"title": "fuzz", "baseline": "nmpc",
              "defaults": {"cycle": 15.0, "duration_s": 60.0, "warmup_s": 0.0,
                           "band_C": [22.0, 26.0], "plant": {"V_disp": 3.3e-5}},
              "grid": {"ambient_C": [25.0, 35.0]},
              "controllers": {"nmpc": {}, "icm": {"match": "nmpc"}},
              "identify": {"seed": 0}}
spec_keys = ["title", "baseline", "defaults", "defaults.cycle", "defaults.duration_s",
             "defaults.band_C", "defaults.plant", "defaults.plant.V_disp", "defaults.params",
             "defaults.plant.dt_int", "grid", "grid.ambient_C", "grid.plant", "controllers",
             "controllers.nmpc", "controllers.icm.match", "controllers.icm.type",
             "controllers.nmpc.N", "identify", "identify.seed", "scenarios", "extra"]


sweep_spec_files = documents(lambda: json.loads(json.dumps(VALID_SPEC)), spec_keys,
                             st.one_of(toml_any, odd_float), toml=True)


def _read_sweep_spec(path: Path):
    from acid.studies.sweep.spec import load_spec

    return load_spec(path)


# -------------------------------------------------------------------------- FMU maps
def _valid_fmu_map() -> dict:
    import tomllib

    from acid.plant.fmi.export import fmu_map_text, plant_interface

    return tomllib.loads(fmu_map_text(plant_interface(), "plant.fmu", 2))


def _fmu_map_keys() -> list[str]:
    base = _valid_fmu_map()
    return [k for k in base] + [f"{k}.{kk}" for k, v in base.items() if isinstance(v, dict)
                                for kk in list(v)[:3]] + ["extra", "outputs.T_cab.unit"]


fmu_map_files = st.deferred(lambda: documents(_valid_fmu_map, _fmu_map_keys(), toml_any,
                                              toml=True))


def _read_fmu_map(path: Path):
    from acid.plant.fmi.plant import FmuMap

    return FmuMap.from_file(path)


# -------------------------------------------------------------- summary.json (claims)
def _valid_summary() -> dict:
    from acid.claims import CLAIMS
    from acid.claims.core import Verdict

    items = [{"id": c.id, "verdict": "agrees", "rule_text": "within 5 %", "reason": "",
              "paper_text": "1.0", "acid_text": "1.1"} for c in CLAIMS]
    return {"command": "reproduce", "claims": {"items": items,
                                               "counts": {v.value: 0 for v in Verdict}}}


summary_keys = ["claims", "claims.items", "claims.counts", "claims.counts.agrees",
                "claims.counts.not measured", "command"]


def _edit_claim(draw, d: dict) -> None:
    """One claim's entries removed or replaced."""
    items = d["claims"]["items"]
    item = items[draw(st.integers(0, len(items) - 1))]
    for key in draw(st.lists(st.sampled_from([*item, "x"]), min_size=1, max_size=3)):
        if draw(st.booleans()):
            item.pop(key, None)
        else:
            item[key] = draw(st.one_of(json_value, st.sampled_from(
                ["agrees", "not comparable", "not measured", "mixed"])))


summary_files = documents(_valid_summary, summary_keys, json_value, toml=False,
                          edit=_edit_claim)


def _read_summary(path: Path):
    from acid.claims import headline_markdown, load_summary
    from acid_cli.claims import check_summary

    check_summary(path)
    return headline_markdown(load_summary(path))


# ------------------------------------------------------------- sweep scenario records
RECORD_KEY = "0123456789abcdef"


def _valid_record() -> dict:
    row = {"scenario_key": RECORD_KEY, "scenario": 0, "label": "15 m/s, 30 C",
           "cycle": "15 m/s", "ambient_C": 30.0, "controller": "nominal",
           "controller_type": "nominal", "baseline": "nominal", "status": "ok", "error": None,
           "energy_MJ": 1.5, "mean_T_cab_C": 25.0, "comfort_violation_Ks": 0.0,
           "max_T_cab_C": 26.0, "solve_ms_median": None, "plant": {}}
    return {"key": RECORD_KEY, "index": 0, "label": "x", "status": "ok", "error": None,
            "rows": [row], "tracebacks": {}, "elapsed_s": 1.0, "worker": None}


record_keys = ["key", "status", "rows", "index", "error"]


def _edit_row(draw, d: dict) -> None:
    """Entries of the record's row replaced."""
    row = d["rows"][0]
    for key in draw(st.lists(st.sampled_from(list(row)), min_size=1, max_size=3)):
        row[key] = draw(st.one_of(json_value, odd_float))


record_files = documents(_valid_record, record_keys, json_value, toml=False, edit=_edit_row)


def _read_record(path: Path):
    """A record written where ``acid sweep`` keeps it, read back as a resumed sweep does;
    a valid one goes into the table and the summary."""
    from acid.studies.sweep.results import ResultStore, controller_summary, results_table

    folder = path.parent / "sweep" / "scenarios"
    folder.mkdir(parents=True, exist_ok=True)
    path.replace(folder / f"{RECORD_KEY}.json")
    rec = ResultStore(folder.parent, ("nominal",)).load(RECORD_KEY)
    if rec is not None:
        controller_summary(results_table([rec]), "nominal")
    return rec


# ------------------------------------------------------------------ econ parameters
def _valid_econ() -> dict:
    from conftest import ECON_MAP, ECON_TRUTH

    from acid.models.econ_params import EconParams, PowerMap

    domain = {"Q_e": (-500.0, 6000.0), "T_evap": (270.0, 290.0), "v_veh": (0.0, 35.0),
              "T_amb": (290.0, 320.0)}
    return json.loads(json.dumps(EconParams(values=dict(ECON_TRUTH), C_ew=2000.0, power_map=(
        PowerMap(coef=ECON_MAP, domain=domain)), name="truth").to_json_dict()))


econ_keys = ["model", "name", "Ts", "parameters", "parameters.C_cab", "parameters.C_cab.value",
             "parameters.r_max.value", "C_ew", "C_ew.value", "beta", "power_map",
             "power_map.coef", "power_map.domain", "provenance", "extra"]


econ_files = documents(_valid_econ, econ_keys, st.one_of(json_value, odd_float, number_lists),
                       toml=False)


def _read_econ(path: Path):
    from acid.models.econ_params import load_any_params

    return load_any_params(path)


# ------------------------------------------------------------------------- readers
def _read_csv(path: Path, cmap: dict):
    from acid.data import ChannelMap, from_csv

    return from_csv(path, ChannelMap.from_dict(cmap))


def _read_mat(path: Path, cmap: dict):
    from acid.data import ChannelMap, from_mat

    return from_mat(path, ChannelMap.from_dict(cmap))


READERS: dict[str, Reader] = {
    "hdf5": Reader("hdf5", ".h5", st.one_of(hdf5_files(), raw_bytes(), raw_bytes(
        b"\x89HDF\r\n\x1a\n")), _read_hdf5),
    "csv": Reader("csv", ".csv", csv_with_map(), _read_csv),
    "mat": Reader("mat", ".mat", mat_with_map(), _read_mat),
    "channel_map": Reader("channel_map", "", map_files(), _read_map),
    "params_json": Reader("params_json", ".json", st.one_of(params_files(), deep_text(False)),
                          _read_params),
    "plant_config": Reader("plant_config", ".toml", st.one_of(plant_config_files(),
                                                              deep_text(True)),
                           _read_plant_config),
    "sweep_spec": Reader("sweep_spec", ".toml", sweep_spec_files, _read_sweep_spec),
    "fmu_map": Reader("fmu_map", ".toml", fmu_map_files, _read_fmu_map),
    "summary_json": Reader("summary_json", ".json", summary_files, _read_summary),
    "sweep_record": Reader("sweep_record", ".json", record_files, _read_record),
    "econ_params": Reader("econ_params", ".json", econ_files, _read_econ),
}


def read_example(reader: Reader, example, folder: Path):
    """Write one drawn example into ``folder`` and read it (warnings silenced); returns what
    the reader gave."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return _read_example(reader, example, folder)


def _read_example(reader: Reader, example, folder: Path):
    if reader.name in ("csv", "mat"):
        write, cmap = example
        path = folder / f"x{reader.suffix}"
        write(path)
        return reader.read(path, cmap)
    if reader.name == "channel_map":
        suffix, write = example
        path = folder / f"map{suffix}"
    else:
        write, path = example, folder / f"x{reader.suffix}"
    write(path)
    return reader.read(path)


# ----------------------------------------------------------------------- counting
def count_escapes(reader: Reader, examples: int) -> Counter:
    """Exceptions other than ``AcidError`` over ``examples`` random files (by type)."""
    from hypothesis import HealthCheck, Phase, given, settings

    from acid.errors import AcidError

    escapes: Counter = Counter()
    folder = Path(tempfile.mkdtemp(prefix=f"acid-fuzz-{reader.name}-"))

    @settings(max_examples=examples, database=None, deadline=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck))
    @given(reader.files)
    def run(example):
        try:
            read_example(reader, example, folder)
        except AcidError:
            pass
        except Exception as exc:  # noqa: BLE001 - what we count
            escapes[type(exc).__name__] += 1

    run()
    return escapes


if __name__ == "__main__":
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1500
    names = sys.argv[2:] or list(READERS)
    total = 0
    for name in names:
        esc = count_escapes(READERS[name], n)
        total += sum(esc.values())
        print(f"{name:13s} {n} examples, {sum(esc.values())} escapes "
              f"{dict(esc.most_common()) if esc else ''}", flush=True)
    print(f"total escapes: {total}")
