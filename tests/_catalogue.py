"""A catalogue of bad inputs for every command, one row per case (used by
``tests/test_cli_catalogue.py``; run as a script to classify every case, also against an
older acid, for a before/after measurement).

Every case must end with exactly one ``error: ...`` line that names the culprit (the file,
channel, key or option: ``Case.names``), exit 2, no traceback, no output written and no file
of the workspace changed. ``classify`` sorts an outcome into ``clean``, ``traceback``,
``exit0`` (exit 0 on nonsense), ``dataloss`` (an existing file changed or vanished),
``internal`` (acid's one-line internal-error net caught a bug) or ``unclear`` (anything
else: several lines, another exit code, the culprit not named, a new file written).

Add a case: append a ``Case`` to ``CASES`` (arguments use ``{w}`` for the workspace folder;
``make`` builds extra files into it). New commands: add their bad inputs the same way.

    python tests/_catalogue.py                 # classify every case in-process
    python tests/_catalogue.py --subprocess    # one process per case (timeouts, memory cap)
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import shutil
import sys
import unittest
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

MODEL = ("T_cab", "T_evap", "T_ain", "W_bl", "T_evap_set", "T_int", "T_shell")
CSV_COLUMNS = {"T_cab": "Tcab", "T_evap": "Tevap", "T_ain": "Tain", "W_bl": "Wbl",
               "T_evap_set": "Tset", "T_int": "Tint", "T_shell": "Tshell"}


@dataclass(frozen=True)
class Case:
    """One bad input: ``args`` after ``acid`` (``{w}``: workspace), the ``names`` the error
    line must contain, the class of bad input, and an optional file builder."""

    id: str
    cls: str
    args: tuple[str, ...]
    names: tuple[str, ...]
    make: Callable[[Path], None] | None = field(default=None, compare=False)

    def argv(self, w: Path) -> list[str]:
        return [a.replace("{w}", str(w)) for a in self.args]

    def fragments(self, w: Path) -> list[str]:
        return [n.replace("{w}", str(w)) for n in self.names]


def _tampered_summary(w: Path, stages: dict | None) -> None:
    """A ``summary.json`` of acid reproduce whose stage values were edited (``acid claims``
    judges them again and must name the key)."""
    from acid.claims.core import Verdict

    d = {"claims": {"items": [], "counts": {v.value: 0 for v in Verdict}}, "options": {}}
    if stages is not None:
        d["stages"] = stages
    (w / "tampered.json").write_text(json.dumps(d))


# ------------------------------------------------------------------------- workspace
def build_workspace(w: Path) -> Path:
    """The files every case starts from (a copy per case): a 2 h model-plant dataset
    ``d.h5``, parameters ``p.json`` fitted on its first half, a CSV export with its map, a
    MAT file with its map, a file ``afile``, a folder ``adir`` and an earlier output."""
    import scipy.io

    from acid.excite import ExcitationSpec, excite
    from acid.models.params import paper
    from acid.plant import make_plant

    w.mkdir(parents=True, exist_ok=True)
    spec = ExcitationSpec(seed=0)
    ds = excite(make_plant("model", rng=spec.rng("noise")), spec)
    ds.to_hdf5(w / "d.h5", created="2026-01-01T00:00:00+00:00")
    sha = hashlib.sha256((w / "d.h5").read_bytes()).hexdigest()
    p = paper().replace(name="fitted", provenance={"estimation_fraction": 0.5,
                                                   "data_sha256": sha})
    p.to_json(w / "p.json")
    rows = 300
    cols = {"t": ds.time[:rows]}
    cols.update({CSV_COLUMNS[n]: ds[n][:rows] for n in MODEL})
    header = ",".join(cols)
    body = "\n".join(",".join(f"{cols[c][i]:.6g}" for c in cols) for i in range(rows))
    (w / "run.csv").write_text(header + "\n" + body + "\n")
    (w / "map.toml").write_text(_map_toml())
    t = np.arange(0.0, 600.0, 1.0)
    sim = {"time": t, "T_cabin_air": 303.15 - 0.01 * t, "m_dot_blower": 0.05 + 0 * t}
    scipy.io.savemat(w / "run.mat", {"sim": sim, "cellvar": np.array([[1.0], "x"],
                                                                     dtype=object)})
    (w / "mat_map.toml").write_text(
        'time = "sim.time"\nTs = 5.0\n[channels]\n'
        'T_cab = { column = "sim.T_cabin_air", unit = "K" }\n'
        'W_bl = { column = "sim.m_dot_blower", unit = "kg/s" }\n')
    (w / "afile").write_text("a plain file\n")
    (w / "adir").mkdir()
    (w / "prev.json").write_text('{"earlier": "output"}\n')
    return w


def _map_toml(extra: str = "", channels: dict | None = None) -> str:
    chans = channels if channels is not None else CSV_COLUMNS
    lines = ['time = "t"', extra, "[channels]"]
    lines += [f'{k} = {{ column = "{v}", unit = "{"kg/s" if k == "W_bl" else "degC"}" }}'
              for k, v in chans.items()]
    return "\n".join(lines) + "\n"


def _write(name: str, text: str) -> Callable[[Path], None]:
    def make(w: Path) -> None:
        (w / name).parent.mkdir(parents=True, exist_ok=True)
        (w / name).write_text(text)
    return make


def _write_bytes(name: str, data: bytes) -> Callable[[Path], None]:
    def make(w: Path) -> None:
        (w / name).write_bytes(data)
    return make


def _params(name: str, **changes) -> Callable[[Path], None]:
    """A params.json from the paper preset with some keys replaced (raw JSON values)."""
    def make(w: Path) -> None:
        from acid.models.params import paper

        p = paper()   # the layout users' older params.json files have: groups as lists
        d = {"gamma": list(p.gamma), "tau": list(p.tau), "beta": list(p.beta), "c_p": p.c_p,
             "eta_cop": p.eta_cop, "Ts": p.Ts}
        for k, v in changes.items():
            if k.startswith("gamma") and k[5:].isdigit():
                d["gamma"][int(k[5:]) - 1] = v
            else:
                d[k] = v
        (w / name).write_text(json.dumps(d))
    return make


def _h5(name: str, edit: Callable) -> Callable[[Path], None]:
    """A copy of d.h5 changed by ``edit(h5py.File)``."""
    def make(w: Path) -> None:
        import h5py

        shutil.copy(w / "d.h5", w / name)
        with h5py.File(w / name, "r+") as f:
            edit(f)
    return make


def _set_attr(path: str, key: str, value) -> Callable:
    def edit(f):
        f[path].attrs[key] = value
    return edit


def _replace(path: str, value) -> Callable:
    def edit(f):
        del f[path]
        f[path] = value
        if path.startswith("channels/"):
            f[path].attrs["unit"] = "degC"
    return edit


def _scale_channel(name: str, factor: float) -> Callable:
    def edit(f):
        f[f"channels/{name}"][...] = f[f"channels/{name}"][()] * factor
    return edit


def _add_channel(name: str, value: float, unit: str) -> Callable:
    def edit(f):
        if name in f["channels"]:
            del f["channels"][name]
        d = f.create_dataset(f"channels/{name}", data=np.full(f["time"].shape, value))
        d.attrs["unit"] = unit
    return edit


def _copy(src: str, dst: str) -> Callable[[Path], None]:
    def make(w: Path) -> None:
        (w / dst).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(w / src, w / dst)
    return make


def _symlink(target: str, link: str) -> Callable[[Path], None]:
    def make(w: Path) -> None:
        (w / link).symlink_to(w / target)
    return make


def _csv_with(column: str, values: str, name: str = "bad.csv") -> Callable[[Path], None]:
    """run.csv with one column's values replaced (``values``: a Python expression of x)."""
    def make(w: Path) -> None:
        lines = (w / "run.csv").read_text().splitlines()
        head = lines[0].split(",")
        j = head.index(column)
        out = [lines[0]]
        for ln in lines[1:]:
            cells = ln.split(",")
            cells[j] = str(eval(values, {}, {"x": float(cells[j])}))  # noqa: S307 - test data
            out.append(",".join(cells))
        (w / name).write_text("\n".join(out) + "\n")
    return make


def _zip(name: str, members: dict[str, bytes]) -> Callable[[Path], None]:
    """A zip archive (an FMU as far as its name goes) with these members."""
    def make(w: Path) -> None:
        import zipfile

        with zipfile.ZipFile(w / name, "w") as z:
            for member, data in members.items():
                z.writestr(member, data)
    return make


def _summary(name: str, edit: Callable[[dict], None]) -> Callable[[Path], None]:
    """A summary.json whose claims block is well formed but for ``edit``."""
    def make(w: Path) -> None:
        from acid.claims import CLAIMS
        from acid.claims.core import Verdict

        items = [{"id": c.id, "verdict": "agrees", "rule_text": "r", "reason": "",
                  "paper_text": "1", "acid_text": "1"} for c in CLAIMS]
        d = {"claims": {"items": items, "counts": {v.value: 0 for v in Verdict}}}
        edit(d)
        (w / name).write_text(json.dumps(d))
    return make


def _both(*makers) -> Callable[[Path], None]:
    def make(w: Path) -> None:
        for m in makers:
            m(w)
    return make


D, P = "{w}/d.h5", "{w}/p.json"
V = ("validate", D, "--out", "{w}/figs", "--starts", "5", "--horizon", "50")
IMP = ("import", "{w}/run.csv", "--map", "{w}/map.toml", "--out", "{w}/run.h5")
EXC = ("excite", "--plant", "model", "--duration", "600")

#: A user's model file (a cabin with a latent interior mass) for the --model FILE.py cases.
MODEL_FILE = """from acid.models import Model, Parameter, Signal, State

def ode(s):
    return {"T_cab": (s.a * (s.T_m - s.T_cab) + s.b * (s.T_shell - s.T_cab)) / 1e4,
            "T_m": s.a * (s.T_cab - s.T_m) / 1e5}

model = Model("mine", states=[State("T_cab", "K"),
                              State("T_m", "K", measured=False, initial=lambda m: m.T_cab)],
              disturbances=[Signal("T_shell", "K")],
              parameters=[Parameter("a", "W/K", 100.0, 0.0, 1e3),
                          Parameter("b", "W/K", 50.0, 0.0, 1e3)], Ts=5.0, ode=ode)
"""

#: A one-state model file with a step, for the equation and noise cases.
_ONE_STATE = ("from acid.models import Model, Parameter, Signal, State, log\n"
              "model = Model('m', states=[State('T_cab', 'K'{state})],\n"
              "    inputs=[Signal('W_bl', 'kg/s')],\n"
              "    parameters=[Parameter('a', '1/s', 0.1, 0.0, 1.0){extra}], Ts=5.0,\n"
              "    step=lambda s: {{'T_cab': {step}}})\n")

CASES: list[Case] = [
    # ---------------------------------------------------- outputs colliding with inputs
    Case("fit-out-is-data", "collision", ("fit", D, "--out", D), ("--out", "d.h5", "DATA")),
    Case("validate-json-is-data", "collision", (*V, "--json", D), ("--json", "d.h5")),
    Case("import-out-is-src", "collision", (*IMP[:4], "--out", "{w}/run.csv"),
         ("--out", "run.csv", "SRC")),
    Case("import-out-is-map", "collision", (*IMP[:4], "--out", "{w}/map.toml"),
         ("--out", "map.toml", "--map")),
    Case("excite-out-is-json", "collision", (*EXC, "--out", "{w}/x.h5", "--json", "{w}/x.h5"),
         ("--json", "x.h5", "--out")),
    Case("fit-out-is-json", "collision", ("fit", D, "--out", "{w}/q.json", "--json",
                                          "{w}/q.json"), ("--json", "q.json", "--out")),
    Case("fit-out-is-reference", "collision", ("fit", D, "--out", P, "--reference", P),
         ("--out", "p.json", "--reference")),
    Case("validate-json-is-params", "collision", (*V, "--params", P, "--json", P),
         ("--json", "p.json", "--params")),
    Case("validate-out-folder-is-data", "collision", ("validate", D, "--out", D),
         ("--out", "d.h5")),
    Case("validate-json-is-a-figure", "collision",
         (*V, "--json", "{w}/figs/fig5_prediction.png"), ("--json", "fig5_prediction.png")),
    Case("excite-out-is-params", "collision", (*EXC, "--params", P, "--out", P),
         ("--out", "p.json", "--params")),
    Case("mpc-check-json-is-params", "collision", ("mpc-check", "--params", P, "--json", P),
         ("--json", "p.json")),
    Case("cav-study-json-is-params", "collision", ("cav-study", "--params", P, "--json", P),
         ("--json", "p.json")),
    Case("speed-sweep-json-is-config", "collision",
         ("speed-sweep", "--plant-config", "{w}/plant.toml", "--out", "{w}/sw", "--json",
          "{w}/plant.toml"), ("--json", "plant.toml"), _write("plant.toml", "")),
    Case("reproduce-json-is-report", "collision",
         ("reproduce", "--out", "{w}/r", "--json", "{w}/r/report.html"),
         ("--json", "report.html")),
    Case("fit-out-is-symlink-to-data", "collision", ("fit", D, "--out", "{w}/link.h5"),
         ("--out", "link.h5", "DATA"), _symlink("d.h5", "link.h5")),
    Case("fit-out-is-data-via-dotdot", "collision", ("fit", D, "--out", "{w}/adir/../d.h5"),
         ("--out", "d.h5")),
    Case("import-out-is-json", "collision", (*IMP[:4], "--out", "{w}/x.h5", "--json",
                                             "{w}/x.h5"), ("--json", "x.h5")),
    # ------------------------------------------------------------ unwritable outputs
    Case("fit-out-under-a-file", "output", ("fit", D, "--out", "{w}/afile/p.json"),
         ("--out", "afile", "not a folder")),
    Case("fit-out-is-a-folder", "output", ("fit", D, "--out", "{w}/adir"),
         ("--out", "adir", "folder")),
    Case("excite-out-under-dev-null", "output", (*EXC, "--out", "/dev/null/x.h5"),
         ("--out", "/dev/null")),
    Case("validate-out-is-a-file", "output", ("validate", D, "--out", "{w}/afile"),
         ("--out", "afile")),
    Case("mpc-check-out-under-a-file", "output", ("mpc-check", "--out", "{w}/afile/figs"),
         ("--out", "afile")),
    Case("reproduce-out-is-a-file", "output", ("reproduce", "--out", "{w}/afile"),
         ("--out", "afile")),
    Case("speed-sweep-out-is-a-file", "output", ("speed-sweep", "--out", "{w}/afile"),
         ("--out", "afile")),
    Case("fit-json-empty-path", "output", ("fit", D, "--out", "{w}/q.json", "--json", ""),
         ("--json",)),
    Case("excite-out-is-a-folder", "output", (*EXC, "--out", "{w}/adir"), ("--out", "adir")),
    Case("import-out-deep-under-a-file", "output", (*IMP[:4], "--out", "{w}/afile/a/b.h5"),
         ("--out", "afile")),
    # ------------------------------------------------------- markup in user-given text
    Case("markup-missing-data-path", "markup", ("fit", "{w}/[/x].h5", "--out", "{w}/q.json"),
         ("[/x].h5",)),
    Case("markup-missing-params", "markup", (*V, "--params", "{w}/[red]p.json"),
         ("[red]p.json",)),
    Case("markup-data-path-with-brackets", "markup",
         ("fit", "{w}/[bold]d.h5", "--out", "{w}/[bold]d.h5"), ("[bold]d.h5", "--out"),
         _copy("d.h5", "[bold]d.h5")),
    Case("markup-out-under-bracket-file", "markup", ("fit", D, "--out", "{w}/[/]/q.json"),
         ("[/]/q.json",), _write("[", "x")),
    Case("markup-missing-column", "markup", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("[red]Tcab",), _write("m.toml", _map_toml(channels={**CSV_COLUMNS,
                                                             "T_cab": "[red]Tcab"}))),
    # ---------------------------------------------------------------- parameter files
    Case("params-gamma4-unstable", "params", (*V, "--params", "{w}/b.json"),
         ("b.json", "gamma4"), _params("b.json", gamma4=3.0)),
    Case("params-gamma1-50", "params", (*V, "--params", "{w}/b.json"),
         ("b.json", "gamma1"), _params("b.json", gamma1=50.0)),
    Case("params-gamma1-1e308", "params", (*V, "--params", "{w}/b.json"),
         ("b.json", "gamma1"), _params("b.json", gamma1=1e308)),
    Case("params-gamma7-1e308", "params", (*V, "--params", "{w}/b.json"),
         ("b.json", "gamma7"), _params("b.json", gamma7=1e308)),
    Case("params-gamma-string", "params", (*V, "--params", "{w}/b.json"),
         ("b.json", "gamma"), _params("b.json", gamma="1111111")),
    Case("params-gamma-object", "params", (*V, "--params", "{w}/b.json"),
         ("b.json", "gamma"), _params("b.json", gamma={str(i): 0.1 for i in range(7)})),
    Case("params-gamma-six", "params", (*V, "--params", "{w}/b.json"),
         ("b.json", "gamma"), _params("b.json", gamma=[0.1] * 6)),
    Case("params-gamma-null", "params", (*V, "--params", "{w}/b.json"),
         ("b.json", "gamma"), _params("b.json", gamma1=None)),
    Case("params-gamma-bool", "params", (*V, "--params", "{w}/b.json"),
         ("b.json", "gamma"), _params("b.json", gamma1=True)),
    Case("params-tau-nan", "params", (*V, "--params", "{w}/b.json"), ("b.json", "tau"),
         _write("b.json", '{"gamma": [0.2451, 0.0867, 1.2999, 1.0047, -0.5176, 0.4553, '
                          '34.9579], "tau": [NaN, -1.3226, 154.4995]}')),
    Case("params-cp-string", "params", (*V, "--params", "{w}/b.json"), ("b.json", "c_p"),
         _params("b.json", c_p="1008")),
    Case("params-cp-kilojoule", "params", (*V, "--params", "{w}/b.json"), ("b.json", "c_p"),
         _params("b.json", c_p=1.008)),
    Case("params-eta-negative", "params", (*V, "--params", "{w}/b.json"),
         ("b.json", "eta_cop"), _params("b.json", eta_cop=-1)),
    Case("params-Ts-zero", "params", (*V, "--params", "{w}/b.json"), ("b.json", "Ts"),
         _params("b.json", Ts=0)),
    Case("params-list", "params", (*V, "--params", "{w}/b.json"), ("b.json", "object"),
         _write("b.json", "[1, 2, 3]")),
    Case("params-binary", "params", (*V, "--params", "{w}/b.json"), ("b.json", "JSON"),
         lambda w: (w / "b.json").write_bytes(b"\xff\xfe\x00garbage")),
    Case("params-provenance-list", "params", (*V, "--params", "{w}/b.json"),
         ("b.json", "provenance"), _params("b.json", provenance=[1, 2])),
    Case("params-celsius", "params", (*V, "--params", "{w}/b.json"), ("b.json", "Celsius"),
         _params("b.json", units="degC (Celsius)")),
    Case("mpc-check-unstable", "params", ("mpc-check", "--params", "{w}/b.json"),
         ("b.json", "gamma4"), _params("b.json", gamma4=3.0)),
    Case("excite-model-unstable", "params", (*EXC, "--params", "{w}/b.json", "--out",
                                             "{w}/x.h5"), ("b.json", "gamma1"),
         _params("b.json", gamma1=50.0)),
    Case("cav-study-unstable", "params", ("cav-study", "--params", "{w}/b.json"),
         ("b.json", "gamma4"), _params("b.json", gamma4=-3.0)),
    Case("fit-reference-malformed", "params", ("fit", D, "--out", "{w}/q.json", "--reference",
                                               "{w}/b.json"), ("b.json", "gamma"),
         _params("b.json", gamma="abc")),
    # -------------------------------------------------------------------- HDF5 files
    Case("h5-Ts-string", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"), ("b.h5", "Ts"),
         _h5("b.h5", _set_attr("/", "Ts", "5"))),
    Case("h5-Ts-zero", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"), ("b.h5", "Ts"),
         _h5("b.h5", _set_attr("/", "Ts", 0.0))),
    Case("h5-Ts-nan", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"), ("b.h5", "Ts"),
         _h5("b.h5", _set_attr("/", "Ts", float("nan")))),
    Case("h5-Ts-array", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"), ("b.h5", "Ts"),
         _h5("b.h5", _set_attr("/", "Ts", np.array([5.0, 5.0])))),
    Case("h5-unit-int-array", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"),
         ("b.h5", "T_cab", "unit"), _h5("b.h5", _set_attr("channels/T_cab", "unit",
                                                          np.array([1, 2])))),
    Case("h5-channel-2d", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"),
         ("b.h5", "T_cab"), _h5("b.h5", _replace("channels/T_cab", np.zeros((1440, 2))))),
    Case("h5-time-strings", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"),
         ("b.h5", "time"), _h5("b.h5", _replace("time", np.array([b"t"] * 1440)))),
    Case("h5-channel-is-group", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"),
         ("b.h5", "channels"), _h5("b.h5", lambda f: f.create_group("channels/sub"))),
    Case("h5-experiment-float", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"),
         ("b.h5", "experiment"), _h5("b.h5", _replace("experiment", np.full(1440, 0.5)))),
    Case("h5-metadata-list", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"),
         ("b.h5", "metadata"), _h5("b.h5", _set_attr("/", "metadata", "[1, 2]"))),
    Case("h5-format-array", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"),
         ("b.h5", "not an acid dataset"),
         _h5("b.h5", _set_attr("/", "format", np.array([1, 2])))),
    Case("h5-not-hdf5", "hdf5", ("fit", "{w}/afile", "--out", "{w}/q.json"),
         ("afile", "HDF5")),
    Case("h5-negative-W_bl", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"),
         ("b.h5", "W_bl"), _h5("b.h5", _scale_channel("W_bl", -1.0))),
    Case("h5-W_bl-in-wrong-unit", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"),
         ("b.h5", "W_bl", "kg/s"), _h5("b.h5", _set_attr("channels/W_bl", "unit", "degC"))),
    Case("h5-negative-speed", "hdf5", (*V[:1], "{w}/b.h5", *V[2:]), ("b.h5", "v_veh"),
         _h5("b.h5", _add_channel("v_veh", -1.0, "m/s"))),
    Case("h5-wrong-Ts", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"),
         ("b.h5", "Ts"), _h5("b.h5", _set_attr("/", "Ts", 2.0))),
    # ------------------------------------------------------------- channel maps, import
    Case("map-Ts-string", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "Ts"), _write("m.toml", _map_toml('Ts = "5"'))),
    Case("map-Ts-zero", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "Ts"), _write("m.toml", _map_toml("Ts = 0"))),
    Case("map-Ts-nan", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "Ts"), _write("m.toml", _map_toml("Ts = nan"))),
    Case("map-Ts-list", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "Ts"), _write("m.toml", _map_toml("Ts = [5.0]"))),
    Case("map-Ts-1e-9", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "Ts"), _write("m.toml", _map_toml("Ts = 1e-9"))),
    Case("map-Ts-bool", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "Ts"), _write("m.toml", _map_toml("Ts = true"))),
    Case("map-resample-unknown", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "resample"), _write("m.toml", _map_toml('Ts = 5.0\nresample = "cubic"'))),
    Case("map-mean-on-data-at-Ts", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "resample", "Ts = 5"),
         _write("m.toml", _map_toml('Ts = 5.0\nresample = "mean"'))),
    Case("map-resample-without-Ts", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "resample"), _write("m.toml", _map_toml('resample = "mean"'))),
    Case("map-unknown-key", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "Tss"), _write("m.toml", _map_toml("Tss = 5.0"))),
    Case("map-time-number", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "time"), _write("m.toml", _map_toml().replace('time = "t"', "time = 5"))),
    Case("map-column-list", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "T_cab"),
         _write("m.toml", _map_toml().replace('column = "Tcab"', 'column = ["Tcab"]'))),
    Case("map-channel-name-slash", "map", (*IMP[:2], "--map", "{w}/m.json", *IMP[4:]),
         ("m.json", "a/b"), _write("m.json", json.dumps({"time": "t", "channels": {
             "a/b": {"column": "Tcab", "unit": "degC"}}}))),
    Case("map-json-list", "map", (*IMP[:2], "--map", "{w}/m.json", *IMP[4:]),
         ("m.json",), _write("m.json", "[1, 2]")),
    Case("map-unknown-unit", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "T_cab", "furlong"),
         _write("m.toml", _map_toml().replace('"Tcab", unit = "degC"',
                                              '"Tcab", unit = "furlong"'))),
    Case("map-missing", "map", (*IMP[:2], "--map", "{w}/none.toml", *IMP[4:]),
         ("--map", "none.toml")),
    Case("mat-struct-variable", "mat", ("import", "{w}/run.mat", "--map", "{w}/m.toml",
                                        "--out", "{w}/run.h5"), ("run.mat", "sim"),
         _write("m.toml", 'time = "sim.time"\nTs = 5.0\n[channels]\n'
                          'T_cab = { column = "sim", unit = "K" }\n')),
    Case("mat-cell-variable", "mat", ("import", "{w}/run.mat", "--map", "{w}/m.toml",
                                      "--out", "{w}/run.h5"), ("run.mat", "cellvar"),
         _write("m.toml", 'time = "sim.time"\nTs = 5.0\n[channels]\n'
                          'T_cab = { column = "cellvar", unit = "K" }\n')),
    Case("mat-garbage", "mat", ("import", "{w}/g.mat", "--map", "{w}/mat_map.toml", "--out",
                                "{w}/run.h5"), ("g.mat", "MAT"),
         _write("g.mat", "MATLAB 5.0 MAT-file but not really\n")),
    Case("csv-text-column", "csv", ("import", "{w}/bad.csv", *IMP[2:]), ("bad.csv", "Tcab"),
         _csv_with("Tcab", "'warm'")),
    Case("csv-negative-W_bl", "csv", ("import", "{w}/bad.csv", *IMP[2:]),
         ("bad.csv", "W_bl"), _csv_with("Wbl", "-x")),
    Case("csv-empty", "csv", ("import", "{w}/bad.csv", *IMP[2:]), ("bad.csv",),
         _write("bad.csv", "")),
    Case("csv-kelvin-as-degC", "csv", ("import", "{w}/bad.csv", *IMP[2:]),
         ("bad.csv", "T_cab"), _csv_with("Tcab", "x + 273.15")),
    Case("import-unknown-suffix", "csv", ("import", "{w}/afile", *IMP[2:]), ("afile",)),
    Case("import-min-samples-zero", "options", (*IMP, "--min-samples", "0"),
         ("--min-samples",)),
    # ------------------------------------------ real logs (issue 20), examples (issue 23)
    Case("map-sep-two-chars", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "sep"), _write("m.toml", _map_toml('sep = ";;"'))),
    Case("map-decimal-semicolon", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "decimal"), _write("m.toml", _map_toml('decimal = ";"'))),
    Case("map-encoding-unknown", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "klingon-8"), _write("m.toml", _map_toml('encoding = "klingon-8"'))),
    Case("map-time-unit-not-time", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "time unit", "km/h"),
         _write("m.toml", _map_toml().replace('time = "t"',
                                              'time = { column = "t", unit = "km/h" }'))),
    Case("map-unit-other-quantity", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "W_bl", "kW"),
         _write("m.toml", _map_toml().replace('"Wbl", unit = "kg/s"', '"Wbl", unit = "kW"'))),
    Case("map-expr-python", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "T_ain", "__import__"),
         _write("m.toml", _map_toml().replace('T_ain = { column = "Tain", unit = "degC" }',
                                              "T_ain = { expr = \"__import__('os')\", "
                                              'unit = "degC" }'))),
    Case("map-expr-unknown-channel", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "T_ain", "T_nope"),
         _write("m.toml", _map_toml().replace('T_ain = { column = "Tain", unit = "degC" }',
                                              'T_ain = { expr = "T_nope + 1", unit = "degC" }'))),
    Case("map-expr-cycle", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "cycle"),
         _write("m.toml", _map_toml().replace(
             'T_ain = { column = "Tain", unit = "degC" }',
             'T_ain = { expr = "T_evap + 1", unit = "degC" }').replace(
             'T_evap = { column = "Tevap", unit = "degC" }',
             'T_evap = { expr = "T_ain - 1", unit = "degC" }'))),
    Case("map-constant-text", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "W_bl", "constant"),
         _write("m.toml", _map_toml().replace('W_bl = { column = "Wbl", unit = "kg/s" }',
                                              'W_bl = { constant = "0.1", unit = "kg/s" }'))),
    Case("map-censored-on-constant", "map", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("m.toml", "W_bl", "censored"),
         _write("m.toml", _map_toml().replace(
             'W_bl = { column = "Wbl", unit = "kg/s" }',
             'W_bl = { constant = 0.1, unit = "kg/s", censored_above = 0.2 }'))),
    Case("csv-latin1-read-as-utf8", "csv", ("import", "{w}/deg.csv", *IMP[2:]),
         ("deg.csv", "encoding"),
         _write_bytes("deg.csv", b"t,Tcab,Tevap,Tain,Wbl,Tset,Tint,Tshell,Note \xb0C\n"
                                 b"0,20,5,8,0.1,5,25,30,1\n5,20,5,8,0.1,5,25,30,2\n")),
    Case("csv-semicolons-read-with-commas", "csv", ("import", "{w}/semi.csv", *IMP[2:]),
         ("semi.csv", "sep = ';'"),
         _write("semi.csv", "t;Tcab;Tevap;Tain;Wbl;Tset;Tint;Tshell\n"
                            "0;20;5;8;0.1;5;25;30\n5;20;5;8;0.1;5;25;30\n")),
    Case("csv-missing-two-columns", "csv", (*IMP[:2], "--map", "{w}/m.toml", *IMP[4:]),
         ("run.csv", "'Tint2'", "'Tshell2'", "T_int", "T_shell"),
         _write("m.toml", _map_toml().replace('"Tint"', '"Tint2"').replace('"Tshell"',
                                                                           '"Tshell2"'))),
    Case("csv-gz-damaged", "csv", ("import", "{w}/bad.csv.gz", *IMP[2:]), ("bad.csv.gz",),
         _write("bad.csv.gz", "not gzip at all\n")),
    Case("import-same-file-twice", "csv", ("import", "{w}/run.csv", "{w}/run.csv", *IMP[2:]),
         ("run.csv", "twice")),
    Case("import-require-lacking-channels", "map", (*IMP, "--require", "econ"),
         ("map.toml", "'w_cab'", "'v_veh'", "'T_amb'", "'P_comp'")),
    Case("import-require-bad-name", "options", (*IMP, "--require", "T_cab,a/b"),
         ("--require", "a/b")),
    Case("import-unknown-example", "csv", ("import", "example:nope.csv.gz", *IMP[2:]),
         ("example:nope.csv.gz", "acid examples")),
    Case("import-out-is-bundled-example", "collision",
         (*IMP[:4], "--out", "example:sample_log_map.toml"), ("--out", "bundled")),
    Case("fit-missing-several-channels", "hdf5", ("fit", "{w}/b.h5", "--out", "{w}/q.json"),
         ("b.h5", "'T_int'", "'T_shell'"),
         _h5("b.h5", lambda f: (f["channels"].__delitem__("T_int"),
                                f["channels"].__delitem__("T_shell")))),
    Case("examples-unknown-action", "options", ("examples", "frob"), ("ACTION", "frob")),
    Case("examples-copy-without-name", "options", ("examples", "copy"), ("NAME",)),
    Case("examples-copy-unknown", "options", ("examples", "copy", "nope.toml", "{w}/n.toml"),
         ("nope.toml",)),
    Case("examples-copy-onto-existing", "output",
         ("examples", "copy", "sweep_econ.toml", "{w}/prev.json"), ("prev.json", "--force")),
    Case("examples-copy-under-a-file", "output",
         ("examples", "copy", "sweep_econ.toml", "{w}/afile/x.toml"), ("DEST", "afile")),
    # ------------------------------------------------------------------- options
    Case("validate-seed-negative", "options", (*V, "--seed", "-1"), ("--seed",)),
    Case("validate-starts-zero", "options", (*V[:4], "--starts", "0"), ("--starts",)),
    Case("validate-starts-1e9", "options", (*V[:4], "--starts", "1000000000"), ("--starts",)),
    Case("validate-horizon-zero", "options", (*V[:6], "--horizon", "0"), ("--horizon",)),
    Case("validate-horizon-too-long", "options", (*V[:6], "--horizon", "5000"),
         ("d.h5", "too short")),
    Case("validate-held-out-1.5", "options", (*V, "--held-out-fraction", "1.5"),
         ("--held-out-fraction",)),
    Case("validate-held-out-nan", "options", (*V, "--held-out-fraction", "nan"),
         ("--held-out-fraction",)),
    Case("validate-placement", "options", (*V, "--placement", "diagonal"), ("--placement",)),
    Case("validate-non-overlapping-random", "options",
         (*V, "--non-overlapping", "--placement", "random"), ("--non-overlapping",)),
    Case("validate-exogenous", "options", (*V, "--exogenous", "guess"), ("--exogenous",)),
    Case("validate-warmup-negative", "options", (*V, "--warmup", "-5"), ("--warmup", "] s")),
    Case("validate-warmup-nan", "options", (*V, "--warmup", "nan"), ("--warmup",)),
    Case("fit-estimation-fraction-zero", "options",
         ("fit", D, "--out", "{w}/q.json", "--estimation-fraction", "0"),
         ("--estimation-fraction",)),
    Case("fit-method", "options", ("fit", D, "--out", "{w}/q.json", "--method", "magic"),
         ("--method",)),
    Case("fit-loss", "options", ("fit", D, "--out", "{w}/q.json", "--loss", "cubic"),
         ("--loss",)),
    Case("fit-oe-window-zero", "options", ("fit", D, "--out", "{w}/q.json", "--oe-window", "0"),
         ("--oe-window",)),
    Case("fit-max-evals-zero", "options",
         ("fit", D, "--out", "{w}/q.json", "--model", "car_cabin", "--max-evals", "0"),
         ("--max-evals",)),
    Case("fit-max-evals-econ-family", "options",
         ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--max-evals", "50"),
         ("--max-evals", "--model econ")),
    Case("fit-hac-negative", "options",
         ("fit", D, "--out", "{w}/q.json", "--hac-bandwidth", "-3"), ("--hac-bandwidth",)),
    Case("excite-duration-1e12", "sizes", ("excite", "--out", "{w}/x.h5", "--duration",
                                           "1e12"), ("--duration",)),
    Case("excite-heating-plant-config", "options",
         ("excite", "--plant", "heating", "--plant-config", "paper", "--out", "{w}/x.h5"),
         ("--plant-config", "heating")),
    Case("excite-duration-nan", "options", ("excite", "--out", "{w}/x.h5", "--duration",
                                            "nan"), ("--duration",)),
    Case("excite-max-dwell-1e9", "sizes", ("excite", "--out", "{w}/x.h5", "--max-dwell",
                                           "1e9"), ("--max-dwell",)),
    Case("excite-min-dwell-inf", "options", ("excite", "--out", "{w}/x.h5", "--min-dwell",
                                             "inf", "--max-dwell", "inf"), ("--min-dwell",)),
    Case("excite-speed-1e6", "sizes", ("excite", "--out", "{w}/x.h5", "--speed", "1e6"),
         ("--speed",)),
    Case("excite-speed-negative", "options", ("excite", "--out", "{w}/x.h5", "--speed", "-1"),
         ("--speed",)),
    Case("excite-noise-huge", "options", (*EXC, "--out", "{w}/x.h5", "--noise", "1e300"),
         ("--noise",)),
    Case("excite-seed-negative", "options", (*EXC, "--out", "{w}/x.h5", "--seed", "-1"),
         ("--seed",)),
    Case("excite-seed-not-int", "options", (*EXC, "--out", "{w}/x.h5", "--seed", "1.5"),
         ("--seed",)),
    Case("excite-signal", "options", (*EXC, "--out", "{w}/x.h5", "--signal", "chirp"),
         ("--signal",)),
    Case("excite-plant", "options", ("excite", "--out", "{w}/x.h5", "--plant", "wind"),
         ("--plant",)),
    Case("excite-t-amb-kelvin", "options", (*EXC, "--out", "{w}/x.h5", "--t-amb", "303.15"),
         ("--t-amb",)),
    Case("excite-cycle-unknown", "options", (*EXC, "--out", "{w}/x.h5", "--cycle", "moon"),
         ("moon",)),
    Case("excite-speed-and-cycle", "options",
         (*EXC, "--out", "{w}/x.h5", "--cycle", "udds", "--speed", "5"), ("--speed",)),
    Case("excite-plant-config-missing", "options",
         ("excite", "--out", "{w}/x.h5", "--plant-config", "{w}/none.toml"),
         ("--plant-config", "none.toml")),
    Case("excite-plant-config-bad-key", "options",
         ("excite", "--out", "{w}/x.h5", "--plant-config", "{w}/c.toml"), ("c.toml", "warp"),
         _write("c.toml", "warp = 9\n")),
    Case("excite-missing-out", "options", ("excite", "--duration", "600"), ("--out",)),
    Case("excite-unknown-option", "options", (*EXC, "--out", "{w}/x.h5", "--turbo"),
         ("--turbo",)),
    Case("speed-sweep-duration-1e12", "sizes", ("speed-sweep", "--out", "{w}/sw",
                                                "--duration", "1e12"), ("--duration",)),
    Case("speed-sweep-duration-zero", "options", ("speed-sweep", "--out", "{w}/sw",
                                                  "--duration", "0"), ("--duration",)),
    Case("mpc-check-solver", "options", ("mpc-check", "--solver", "excel"), ("--solver",)),
    Case("mpc-check-first-move", "options", ("mpc-check", "--first-move", "late"),
         ("--first-move",)),
    Case("cav-study-horizon-zero", "options", ("cav-study", "--horizon", "0"), ("--horizon",)),
    Case("cav-study-horizon-1e5", "sizes", ("cav-study", "--horizon", "100000"),
         ("--horizon",)),
    Case("cav-study-band-inverted", "options", ("cav-study", "--t-low", "26", "--t-high",
                                                "22"), ("--t-low",)),
    Case("cav-study-warmup-negative", "options", ("cav-study", "--warmup", "-1"),
         ("--warmup",)),
    Case("cav-study-tail-1e12", "sizes", ("cav-study", "--tail", "1e12"), ("--tail",)),
    Case("cav-study-cycle", "options", ("cav-study", "--cycle", "moon"), ("--cycle",)),
    Case("compare-one-ambient", "options", ("compare", "--t-amb", "30", "--no-econ"),
         ("--t-amb",)),
    Case("compare-cycle", "options", ("compare", "--cycle", "moon", "--no-econ"), ("--cycle",)),
    Case("pulldown-soak-below-ambient", "options", ("pulldown", "--t-amb", "35", "--soak",
                                                    "30"), ("--soak",)),
    Case("pulldown-cycle", "options", ("pulldown", "--cycle", "moon"), ("--cycle",)),
    Case("cav-study-econ-terminal", "options", ("cav-study", "--econ-terminal", "zero"),
         ("--econ-terminal",)),
    Case("cav-study-coil-max-hot", "options", ("cav-study", "--coil-max", "40"),
         ("--coil-max",)),
    Case("cav-study-comfort-weight-negative", "options",
         ("cav-study", "--comfort-weight", "-1"), ("--comfort-weight",)),
    # ------------------------------------------------------------------------- claims
    Case("claims-summary-missing", "files", ("claims", "{w}/none.json"), ("SUMMARY",
                                                                          "none.json")),
    Case("claims-summary-is-params", "files", ("claims", "{w}/p.json"),
         ("p.json", "'claims' block")),
    Case("claims-summary-not-json", "files", ("claims", "{w}/afile"), ("afile", "JSON")),
    Case("claims-json-is-summary", "collision", ("claims", "{w}/p.json", "--json", "{w}/p.json"),
         ("--json", "p.json")),
    Case("claims-json-under-a-file", "output", ("claims", "--json", "{w}/afile/c.json"),
         ("--json", "afile")),
    Case("claims-summary-value-not-a-number", "files", ("claims", "{w}/tampered.json"),
         ("tampered.json", "speeds_mps[1]", "expected a number"),
         make=lambda w: _tampered_summary(w, {"sweep": {"summary": {"speeds_mps": [0, "x"]}}})),
    Case("claims-summary-value-nan", "files", ("claims", "{w}/tampered.json"),
         ("tampered.json", "stages.sweep.summary.duration_s", "finite"),
         make=lambda w: _tampered_summary(w, {"sweep": {"summary": {"duration_s": math.nan}}})),
    Case("claims-summary-without-stages", "files", ("claims", "{w}/tampered.json"),
         ("tampered.json", "'stages'"), make=lambda w: _tampered_summary(w, None)),
    Case("speed-sweep-config-unknown-vehicle", "files",
         ("speed-sweep", "--plant-config", "papr", "--out", "{w}/sw"), ("--plant-config", "papr")),
    # ------------------------------------- plant-check, export-fmu, --plant fmu:PATH
    Case("plant-check-json-is-config", "collision",
         ("plant-check", "--plant-config", "{w}/plant.toml", "--json", "{w}/plant.toml"),
         ("--json", "plant.toml"), _write("plant.toml", "")),
    Case("plant-check-out-is-a-file", "output", ("plant-check", "--out", "{w}/afile"),
         ("--out", "afile")),
    Case("plant-check-ambient-kelvin", "options", ("plant-check", "--t-amb", "303.15"),
         ("--t-amb",)),
    # ---------------------------------- --t-amb, --refrigerant on every plant command (issue 23)
    Case("speed-sweep-ambient-kelvin", "options",
         ("speed-sweep", "--t-amb", "303.15", "--out", "{w}/sw"), ("--t-amb 303.15", "degC")),
    Case("mpc-check-ambient-kelvin", "options",
         ("mpc-check", "--skip-plant", "--t-amb", "303.15", "--out", "{w}/m"),
         ("--t-amb 303.15", "degC")),
    Case("speed-sweep-refrigerant-unknown", "options",
         ("speed-sweep", "--refrigerant", "R22", "--out", "{w}/sw"),
         ("--refrigerant 'R22'", "R1234yf")),
    Case("excite-refrigerant-model-plant", "options", (*EXC, "--refrigerant", "R1234yf",
                                                       "--out", "{w}/x.h5"),
         ("--refrigerant", "--plant hifi only")),
    Case("plant-config-kelvin-untagged", "files",
         ("plant-check", "--plant-config", "{w}/k.toml", "--out", "{w}/pc"),
         ("k.toml", "T_amb = 308.15", '"308.15 K"'), _write("k.toml", "T_amb = 308.15\n")),
    Case("heating-check-logs-is-a-file", "options", ("heating-check", "--logs", "{w}/afile"),
         ("--logs", "afile")),
    Case("heating-check-logs-without-trips", "options", ("heating-check", "--logs", "{w}/adir"),
         ("--logs", "adir")),
    Case("heating-check-json-is-a-folder", "output", ("heating-check", "--json", "{w}/adir"),
         ("--json", "adir")),
    Case("heating-control-ambient-out-of-range", "options",
         ("heating-control", "--t-amb", "40", "--out", "{w}/hc"), ("--t-amb", "40")),
    Case("heating-control-negative-pull-up", "options",
         ("heating-control", "--pull-up", "-5", "--out", "{w}/hc"), ("--pull-up", "-5")),
    Case("heating-control-unknown-cycle", "options",
         ("heating-control", "--cycle", "nope", "--out", "{w}/hc"), ("--cycle", "nope")),
    Case("heating-control-warmup-unbounded", "options",
         ("heating-control", "--warmup", "1e9", "--out", "{w}/hc"), ("--warmup", "1000000000")),
    Case("heating-control-tail-unbounded", "options",
         ("heating-control", "--tail", "1e12", "--out", "{w}/hc"), ("--tail",)),
    Case("fit-negative-seed", "options",
         ("fit", D, "--model", "cabin3", "--fit-starts", "2", "--seed", "-1", "--out",
          "{w}/p.json"), ("--seed", "-1")),
    Case("export-c-input-twice", "options",
         ("export-c", "--model", "cabin3", "--input", "W_bl=0.05:0.15", "--input",
          "W_bl=0.06:0.2", "--input", "T_evap_set=3:10", "--out", "{w}/c"),
         ("--input", "twice")),
    Case("export-c-input-below-absolute-zero", "options",
         ("export-c", "--model", "cabin3", "--input", "W_bl=0.05:0.15", "--input",
          "T_evap_set=-300:10", "--out", "{w}/c"), ("--input", "absolute zero")),
    Case("excite-t-amb-range-reversed", "options",
         ("excite", "--t-amb-range", "40", "20", "--duration", "600", "--out", "{w}/r.h5"),
         ("--t-amb-range", "40 20")),
    Case("heating-control-json-is-a-folder", "output",
         ("heating-control", "--json", "{w}/adir", "--out", "{w}/hc"), ("--json", "adir")),
    Case("plant-check-fmu-missing", "options",
         ("plant-check", "--plant", "fmu:{w}/none.fmu", "--fmu-map", "{w}/mat_map.toml"),
         ("--plant", "none.fmu")),
    Case("export-fmu-out-is-config", "collision",
         ("export-fmu", "--out", "{w}/c.fmu", "--plant-config", "{w}/c.fmu"),
         ("--out", "c.fmu", "--plant-config"), _write("c.fmu", "")),
    Case("export-fmu-map-is-json", "collision",
         ("export-fmu", "--out", "{w}/p.fmu", "--fmu-map", "{w}/m.toml", "--json",
          "{w}/m.toml"),
         ("--json", "m.toml")),
    Case("export-fmu-out-under-a-file", "output", ("export-fmu", "--out", "{w}/afile/p.fmu"),
         ("--out", "afile")),
    Case("export-fmu-version", "options", ("export-fmu", "--out", "{w}/p.fmu",
                                           "--fmi-version", "4"), ("--fmi-version",)),
    # ------------------------------------------------------------------------- export-c
    Case("export-c-json-is-params", "collision", ("export-c", "--params", P, "--json", P),
         ("--json", "p.json")),
    Case("export-c-out-is-a-file", "output", ("export-c", "--out", "{w}/afile"),
         ("--out", "afile")),
    Case("export-c-horizon-1", "options", ("export-c", "--out", "{w}/c", "--horizon", "1"),
         ("--horizon",)),
    Case("export-c-check-states-0", "options", ("export-c", "--out", "{w}/c",
                                                "--check-states", "0"), ("--check-states",)),
    Case("export-c-unstable", "params", ("export-c", "--params", "{w}/b.json", "--out",
                                         "{w}/c"), ("b.json", "gamma4"),
         _params("b.json", gamma4=3.0)),
    Case("export-c-model-no-input-bounds", "options",
         ("export-c", "--model", "car_cabin", "--out", "{w}/c"), ("--input", "T_evap")),
    Case("export-c-model-unknown-track", "options",
         ("export-c", "--model", "car_cabin", "--input", "T_evap=3:40", "--track", "T_dash",
          "--out", "{w}/c"), ("--track", "T_dash")),
    Case("export-c-model-bad-input-range", "options",
         ("export-c", "--model", "car_cabin", "--input", "T_evap=40:3", "--out", "{w}/c"),
         ("--input", "T_evap=40:3")),
    Case("excite-out-is-fmu-map", "collision",
         ("excite", "--plant", "fmu:{w}/g.fmu", "--fmu-map", "{w}/mat_map.toml", "--out",
          "{w}/mat_map.toml"), ("--out", "mat_map.toml", "--fmu-map"),
         _write("g.fmu", "not a zip")),
    Case("excite-fmu-garbage", "options",
         ("excite", "--plant", "fmu:{w}/g.fmu", "--fmu-map", "{w}/f.toml", "--out", "{w}/y.h5"),
         ("g.fmu",), _both(_write("g.fmu", "not a zip"), _write(
             "f.toml", '[inputs]\nW_bl = { name = "a" }\nT_evap_set = { name = "b" }\n'
                       '[states]\nT_cab = { name = "c" }\nT_evap = { name = "d" }\n'
                       'T_int = { name = "e" }\nT_shell = { name = "f" }\n'
                       '[outputs]\nT_ain = { name = "g" }\n'))),
    Case("mpc-check-fmu-missing", "options",
         ("mpc-check", "--plant", "fmu:{w}/none.fmu", "--fmu-map", "{w}/mat_map.toml"),
         ("--plant", "none.fmu")),
    Case("speed-sweep-fmu-without-map", "options",
         ("speed-sweep", "--out", "{w}/sw", "--plant", "fmu:{w}/g.fmu"), ("--fmu-map",),
         _write("g.fmu", "not a zip")),
    Case("cav-study-fmu-map-missing", "options",
         ("cav-study", "--plant", "fmu:{w}/g.fmu", "--fmu-map", "{w}/none.toml"),
         ("--fmu-map", "none.toml"), _write("g.fmu", "not a zip")),
    Case("reproduce-jobs-zero", "options", ("reproduce", "--out", "{w}/r", "--jobs", "0"),
         ("--jobs",)),
    Case("reproduce-jobs-100", "options", ("reproduce", "--out", "{w}/r", "--jobs", "100"),
         ("--jobs",)),
    # ------------------------------------------------------------------ acid sweep
    Case("sweep-spec-missing", "options", ("sweep", "{w}/none.toml", "--out", "{w}/o"),
         ("SPEC.toml", "none.toml")),
    Case("sweep-spec-not-toml", "options", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "not valid TOML"), _write("s.toml", "[grid\n")),
    Case("sweep-unknown-controller", "options", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "controllers.turbo", "unknown controller"),
         _write("s.toml", "[grid]\nambient_C = [30.0]\n[controllers.turbo]\n")),
    Case("sweep-negative-humidity", "options", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "grid", "humidity_pct = -5"),
         _write("s.toml", "[grid]\nhumidity_pct = [50.0, -5.0]\n")),
    Case("sweep-empty-grid", "options", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "ambient_C is empty"), _write("s.toml", "[grid]\nambient_C = []\n")),
    Case("sweep-plant-override-unknown", "options",
         ("sweep", "{w}/s.toml", "--out", "{w}/o"), ("s.toml", "scenarios #1", "'warp'"),
         _write("s.toml", "[[scenarios]]\nplant = { warp = 9.0 }\n")),
    Case("sweep-params-missing", "params", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "params", "none.json"),
         _write("s.toml", "[defaults]\nparams = \"none.json\"\n[grid]\nambient_C = [30.0]\n")),
    Case("sweep-json-is-spec", "collision",
         ("sweep", "{w}/s.toml", "--out", "{w}/o", "--json", "{w}/s.toml"),
         ("--json", "s.toml"), _write("s.toml", "[grid]\nambient_C = [30.0]\n")),
    Case("sweep-json-is-results", "collision",
         ("sweep", "{w}/s.toml", "--out", "{w}/o", "--json", "{w}/o/results.csv"),
         ("--json", "results.csv"), _write("s.toml", "[grid]\nambient_C = [30.0]\n")),
    Case("sweep-out-is-a-file", "output", ("sweep", "{w}/s.toml", "--out", "{w}/afile"),
         ("--out", "afile"), _write("s.toml", "[grid]\nambient_C = [30.0]\n")),
    Case("sweep-workers-zero", "options",
         ("sweep", "{w}/s.toml", "--out", "{w}/o", "--jobs", "0"), ("--jobs",),
         _write("s.toml", "[grid]\nambient_C = [30.0]\n")),
    Case("sweep-workers-and-scheduler", "options",
         ("sweep", "{w}/s.toml", "--out", "{w}/o", "--jobs", "2", "--scheduler",
          "tcp://127.0.0.1:1"), ("--jobs", "--scheduler"),
         _write("s.toml", "[grid]\nambient_C = [30.0]\n")),
    Case("markup-sweep-spec-path", "markup", ("sweep", "{w}/[red]s.toml", "--out", "{w}/o"),
         ("[red]s.toml",)),
    # ------------------------------------------------ declared models (--model FILE.py)
    Case("fit-model-file-missing", "params", ("fit", D, "--out", "{w}/q.json", "--model",
                                              "{w}/nope.py"), ("--model", "nope.py")),
    Case("fit-model-file-unknown-name", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"), ("m.py:", "'T_ambient'"),
         _write("m.py", MODEL_FILE.replace("s.T_shell - s.T_cab", "s.T_ambient - s.T_cab"))),
    Case("fit-model-file-symbolic-if", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"), ("m.py:", "if_else"),
         _write("m.py", MODEL_FILE.replace("    return {", "    if s.T_cab > 300:\n"
                                           "        pass\n    return {"))),
    Case("fit-model-file-sys-exit", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"), ("m.py", "sys.exit(0)"),
         _write("m.py", "import sys\nsys.exit(0)\n")),
    Case("fit-model-file-model-raises", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"), ("m.py:", "RuntimeError"),
         _write("m.py", "def model():\n    raise RuntimeError('no')\n")),
    Case("fit-model-file-raises-keyboard-interrupt", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"),
         ("m.py", "KeyboardInterrupt"), _write("m.py", "raise KeyboardInterrupt\n")),
    Case("fit-model-file-equations-not-finite", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py", "--method", "oe"),
         ("'nanny'", "NaN or inf", "T_cab"),
         _write("m.py", "from acid.models import RK4, Model, Parameter, Signal, State, log\n"
                        "def ode(s):\n"
                        "    return {'T_cab': log(s.T_cab - 400.0)\n"
                        "            + s.a * (s.T_evap_set - s.T_cab)}\n"
                        "model = Model('nanny', states=[State('T_cab', 'K')],\n"
                        "              inputs=[Signal('T_evap_set', 'K')],\n"
                        "              parameters=[Parameter('a', '1/s', 0.001, 0.0, 1.0)],\n"
                        "              Ts=5.0, ode=ode, integrator=RK4(substeps=1))\n")),
    Case("fit-model-file-fix-malformed", "options",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py", "--fix", "a"),
         ("--fix", "'a'"), _write("m.py", MODEL_FILE)),
    Case("fit-model-file-fix-unknown", "options",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py", "--fix", "zz=1"),
         ("'zz'",), _write("m.py", MODEL_FILE)),
    Case("fit-fit-starts-with-ls", "options",
         ("fit", D, "--out", "{w}/q.json", "--fit-starts", "3", "--method", "ls"),
         ("--fit-starts 3", "--method oe")),
    Case("fit-add-record-for-econ", "options",
         ("fit", D, "--model", "econ", "--out", "{w}/q.json", "--add-record", D),
         ("--add-record", "--model econ")),
    Case("excite-declared-plant-unknown-signal", "params",
         ("excite", "--plant", "model:{w}/m.py", "--duration", "100", "--out", "{w}/x.h5"),
         ("m.py", "'Q_heater'"), _write("m.py", MODEL_FILE.replace("T_shell", "Q_heater"))),
    Case("excite-declared-plant-noise", "options",
         ("excite", "--plant", "model:cabin3", "--noise", "0.1", "--duration", "100",
          "--out", "{w}/x.h5"), ("--noise", "model:cabin3")),
    Case("excite-declared-plant-missing-file", "options",
         ("excite", "--plant", "model:{w}/nope.py", "--out", "{w}/x.h5"), ("--plant",
                                                                           "nope.py")),
    Case("validate-model-file-paper-params", "params",
         (*V[:2], "--model", "{w}/m.py", "--params", P),
         ("p.json", "parameters of model 'paper', not 'mine'"),
         _write("m.py", MODEL_FILE)),


    # ------------------------------------------- hostile inputs, round 3 (issue 24)
    Case("sweep-out-holds-another-spec", "dataloss", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("--out", "another specification"),
         _both(_write("s.toml", "[grid]\nambient_C = [30.0]\n"),
               _write("o/spec.toml", "[grid]\nambient_C = [45.0]\n"),
               _write("o/summary.json", '{"command": "sweep"}\n'),
               _write("o/results.csv", "scenario,controller\n0,nmpc\n"))),
    Case("sweep-out-holds-results-without-spec", "dataloss",
         ("sweep", "{w}/s.toml", "--out", "{w}/o"), ("--out", "unknown specification"),
         _both(_write("s.toml", "[grid]\nambient_C = [30.0]\n"),
               _write("o/results.csv", "scenario,controller\n0,nmpc\n"))),
    Case("sweep-unstable-params", "params", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "b.json", "unstable", "--allow-unstable"),
         _both(_params("b.json", gamma4=3.0),
               _write("s.toml", '[defaults]\nparams = "b.json"\n[grid]\nambient_C = [30.0]\n'))),
    Case("sweep-spec-named-dots", "paths", ("sweep", "{w}/..toml"),
         ("SPEC.toml", "..toml", "only of dots"), _write("..toml", "[grid]\nambient_C = [30.0]\n")),
    Case("sweep-nested-plant-override", "structure", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "defaults", "plant.V_disp must be a value"),
         _write("s.toml", "[defaults]\nplant = { V_disp = { a = 1.0 } }\n[grid]\n"
                          "ambient_C = [30.0]\n")),
    Case("sweep-spec-deep", "structure", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "nests 20000 levels"), _write("s.toml", "x = " + "[" * 20000 + "]" * 20000)),
    Case("sweep-spec-dotted-deep", "structure", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "nests deeper than 32"), _write("s.toml", "a" + ".a" * 40 + " = 1\n")),
    Case("sweep-scheduler-malformed", "options",
         ("sweep", "{w}/s.toml", "--out", "{w}/o", "--scheduler", "tcp://[::"),
         ("--scheduler", "not a scheduler address"),
         _write("s.toml", "[grid]\nambient_C = [30.0]\n")),
    Case("reproduce-scheduler-malformed", "options",
         ("reproduce", "--out", "{w}/r", "--scheduler", "tcp://host:notaport"),
         ("--scheduler", "not a scheduler address")),
    Case("sweep-scheduler-port", "options",
         ("sweep", "{w}/s.toml", "--out", "{w}/o", "--scheduler", "tcp://h:70000"),
         ("--scheduler", "port 70000"), _write("s.toml", "[grid]\nambient_C = [30.0]\n")),
    Case("sweep-displacement-1m3", "sizes", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "V_disp = 1 m^3", "physical range"),
         _write("s.toml", "[defaults]\nplant = { V_disp = 1.0 }\n[grid]\nambient_C = [30.0]\n")),
    Case("sweep-dt-1e-6", "sizes", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "dt_int"),
         _write("s.toml", "[defaults]\nplant = { dt_int = 1e-6 }\n[grid]\nambient_C = [30.0]\n")),
    Case("sweep-scenario-samples", "sizes", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "samples", "at most 100000"),
         _write("s.toml", "[defaults]\nduration_s = 86400.0\nwarmup_s = 86400.0\n"
                          "plant = { Ts = 0.5, dt_int = 0.5 }\n[grid]\nambient_C = [30.0]\n")),
    Case("excite-plant-config-absurd", "sizes",
         ("excite", "--out", "{w}/x.h5", "--plant-config", "{w}/c.toml"),
         ("c.toml", "C_cab = 5e+07 J/K", "physical range"),
         _write("c.toml", "[cabin]\nC_cab = 5.0e7\n")),
    Case("sweep-scenario-internal-steps", "sizes", ("sweep", "{w}/s.toml", "--out", "{w}/o"),
         ("s.toml", "internal steps", "at most 2000000"),
         _write("s.toml", "[defaults]\nduration_s = 86400.0\nwarmup_s = 86400.0\n"
                          "plant = { dt_int = 0.05 }\n[grid]\nambient_C = [30.0]\n")),
    Case("excite-plant-config-dt-1e-6", "sizes",
         ("excite", "--out", "{w}/x.h5", "--plant-config", "{w}/c.toml"),
         ("c.toml", "dt_int = 1e-06 s", "physical range"),
         _write("c.toml", "[solver]\ndt_int = 1e-6\n")),
    Case("speed-sweep-config-internal-steps", "sizes",
         ("speed-sweep", "--plant-config", "{w}/c.toml", "--out", "{w}/sw"),
         ("c.toml", "internal steps", "at most 10000"),
         _write("c.toml", "[solver]\nTs = 60.0\ndt_int = 0.001\n")),
    Case("excite-plant-config-deep", "structure",
         ("excite", "--out", "{w}/x.h5", "--plant-config", "{w}/c.toml"),
         ("c.toml", "nests"), _write("c.toml", "[cabin]\nC_cab = " + "[" * 5000 + "]" * 5000)),
    Case("excite-params-deep", "structure",
         ("excite", "--plant", "model", "--params", "{w}/d.json", "--out", "{w}/x.h5"),
         ("d.json", "nests 100001 levels"),
         _write("d.json", '{"gamma": ' + "[" * 100000 + "]" * 100000 + "}")),
    Case("excite-params-not-utf8", "structure",
         ("excite", "--plant", "model", "--params", "{w}/d.json", "--out", "{w}/x.h5"),
         ("d.json", "not UTF-8"), lambda w: (w / "d.json").write_bytes(b'{"name": "\xff"}')),
    Case("excite-fmu-escaping-member", "paths",
         ("excite", "--plant", "fmu:{w}/z.fmu", "--fmu-map", "{w}/f.toml", "--out", "{w}/y.h5"),
         ("z.fmu", "escapes its folder"),
         _both(_zip("z.fmu", {"modelDescription.xml": b"<x/>", "../../evil.sh": b"x"}),
               _write("f.toml", '[inputs]\nW_bl = { name = "a" }\nT_evap_set = { name = "b" }\n'
                                '[states]\nT_cab = { name = "c" }\nT_evap = { name = "d" }\n'
                                'T_int = { name = "e" }\nT_shell = { name = "f" }\n'
                                '[outputs]\nT_ain = { name = "g" }\n'))),
    Case("claims-summary-tampered-verdict", "structure", ("claims", "{w}/s.json"),
         ("s.json", "claims.items[0].verdict"),
         _summary("s.json", lambda d: d["claims"]["items"][0].update(verdict=["x"]))),
    Case("claims-summary-tampered-counts", "structure", ("claims", "{w}/s.json"),
         ("s.json", "claims.counts.'disagrees'"),
         _summary("s.json", lambda d: d["claims"]["counts"].update(disagrees=-1))),
    Case("claims-summary-deep", "structure", ("claims", "{w}/s.json"), ("s.json", "nests"),
         _write("s.json", '{"claims": ' + "[" * 50000 + "]" * 50000 + "}")),

    Case("validate-model-unknown-name", "options",
         (*V[:2], "--model", "car_cabn"), ("--model", "car_cabin", "'car_cabn'")),
    Case("validate-warm-start-unknown", "options",
         (*V, "--model", "car_cabin", "--warm-start", "kalman"), ("--warm-start", "ekf-trip")),
    # ------------------------------------------------------------------------- year-sweep
    Case("year-sweep-ambient-kelvin", "options",
         ("year-sweep", "--t-amb", "263.15", "--out", "{w}/y"), ("--t-amb 263.15", "degC")),
    Case("year-sweep-cycle-unknown", "options", ("year-sweep", "--cycle", "moon", "--out",
                                                 "{w}/y"), ("--cycle moon", "udds")),
    Case("year-sweep-jobs-zero", "options", ("year-sweep", "--jobs", "0", "--out", "{w}/y"),
         ("--jobs",)),
    Case("year-sweep-vehicle-unknown", "files",
         ("year-sweep", "--plant-config", "papr", "--out", "{w}/y"), ("--plant-config", "papr")),
    Case("year-sweep-vehicle-bad-file", "files",
         ("year-sweep", "--plant-config", "{w}/c.toml", "--out", "{w}/y"), ("c.toml", "warp"),
         _write("c.toml", "warp = 9\n")),
    Case("year-sweep-refrigerant-unknown", "options",
         ("year-sweep", "--refrigerant", "R22", "--out", "{w}/y"), ("--refrigerant 'R22'",)),
    Case("day-season-unknown", "options", ("day", "--season", "spring", "--out", "{w}/dd"),
         ("--season", "spring")),
    Case("day-jobs-zero", "options", ("day", "--jobs", "0", "--out", "{w}/dd"), ("--jobs",)),
    Case("day-out-is-a-file", "output", ("day", "--out", "{w}/afile"), ("--out", "afile")),
    Case("year-sweep-out-is-a-file", "output", ("year-sweep", "--out", "{w}/afile"),
         ("--out", "afile")),
    # a model file that ends the process or declares a model too big to trace (guarded load)
    Case("fit-model-file-os-exit", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"), ("m.py", "os._exit(0)"),
         _write("m.py", "import os\nos._exit(0)\n")),
    Case("fit-model-file-crash-signal", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"), ("m.py", "SIGABRT"),
         _write("m.py", "import os, signal\nos.kill(os.getpid(), signal.SIGABRT)\n")),
    Case("fit-model-file-3000-states", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"),
         ("m.py", "3000 states", "ACID_MODEL_MAX_STATES"),
         _write("m.py", "from acid.models import Model, Parameter, Signal, State\n"
                        "n = 3000\n"
                        "model = Model('big', states=[State(f'x{i}', 'K', measured=(i == 0))"
                        " for i in range(n)],\n"
                        "    parameters=[Parameter('a', '1/s', 0.1, 0.0, 1.0)], Ts=1.0,\n"
                        "    inputs=[Signal('u', 'K')],\n"
                        "    ode=lambda s: {f'x{i}': s.a * (s.u - getattr(s, f'x{i}'))"
                        " for i in range(n)})\n")),
    Case("compare-identify-duration-nan", "options",
         ("compare", "--identify-duration", "nan", "--json", "{w}/c.json"),
         ("--identify-duration", "nan")),
    Case("compare-seed-negative", "options",
         ("compare", "--seed", "-1", "--json", "{w}/c.json"), ("--seed", "-1")),
    Case("day-seed-negative", "options", ("day", "--seed", "-1", "--out", "{w}/dd"),
         ("--seed", "-1")),
    # equations NaN/inf at the declared point or on the data, declared noises, interrupts
    # raised by a model file, options given twice, a bound on a prior
    Case("fit-model-file-step-nan-everywhere", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"), ("m.py", "'T_cab'", "NaN"),
         _write("m.py", _ONE_STATE.format(step="s.T_cab * float('nan') + s.a * s.W_bl",
                                          state="", extra=""))),
    Case("export-c-model-step-nan", "params",
         ("export-c", "--model", "{w}/m.py", "--input", "W_bl=0:1", "--out", "{w}/ec"),
         ("m.py", "'T_cab'", "NaN"),
         _write("m.py", _ONE_STATE.format(step="s.T_cab * float('nan') + s.a * s.W_bl",
                                          state="", extra=""))),
    Case("export-c-model-step-log-zero", "params",
         ("export-c", "--model", "{w}/m.py", "--input", "W_bl=0:1", "--out", "{w}/ec"),
         ("m.py", "'T_cab'", "inf"),
         _write("m.py", _ONE_STATE.format(step="s.T_cab + log(s.a - 0.1) + s.W_bl",
                                          state="", extra=""))),
    Case("fit-pem-noise-parameter-1e300", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py", "--method", "pem"),
         ("m.py", "parameter 'q'", "max 1e+300"),
         _write("m.py", _ONE_STATE.format(step="s.T_cab + s.a * (s.W_bl - 0.1)",
                                          state=", noise='q'",
                                          extra=", Parameter('q', 'K', 0.5, 0.0, 1e300)"))),
    Case("fit-pem-sensor-parameter-zero", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py", "--method", "pem"),
         ("m.py", "parameter 'q'", "sensor", "value 0.0"),
         _write("m.py", _ONE_STATE.format(step="s.T_cab + s.a * (s.W_bl - 0.1)",
                                          state=", sensor='q'",
                                          extra=", Parameter('q', 'K', 0.0, 0.0, 1.0)"))),
    Case("fit-model-file-equation-nan-on-the-data", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"),
         ("m.py", "'T_cab'", "NaN or inf", "d.h5"),
         _write("m.py", _ONE_STATE.format(step="s.T_cab + s.a * log(s.W_bl - 0.5)",
                                          state="", extra=""))),
    Case("fit-pem-equation-nan-on-the-data", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py", "--method", "pem"),
         ("m.py", "'T_cab'", "NaN or inf", "d.h5"),
         _write("m.py", _ONE_STATE.format(step="s.T_cab + s.a * log(s.W_bl - 0.5)",
                                          state="", extra=""))),
    Case("fit-model-file-initial-raises-keyboard-interrupt", "params",
         ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"),
         ("m.py:3", "KeyboardInterrupt"),
         _write("m.py", "from acid.models import Model, Parameter, Signal, State\n"
                        "def start(m):\n"
                        "    raise KeyboardInterrupt\n"
                        "model = Model('ki', states=[State('T_cab', 'K'),\n"
                        "    State('T_m', 'K', measured=False, initial=start)],\n"
                        "    inputs=[Signal('T_evap_set', 'K')],\n"
                        "    parameters=[Parameter('a', '1/s', 0.1, 0.0, 1.0)], Ts=5.0,\n"
                        "    step=lambda s: {'T_cab': s.T_cab + s.a * (s.T_evap_set - s.T_cab)"
                        " + 0.01 * (s.T_m - s.T_cab), 'T_m': s.T_m})\n")),
    Case("mpc-check-backoff-prior-1e300", "options",
         ("mpc-check", "--backoff-prior", "1e300", "--out", "{w}/mc"), ("--backoff-prior",)),
    Case("export-c-horizon-given-twice", "options",
         ("export-c", "--horizon", "5", "--horizon", "7", "--out", "{w}/ec"),
         ("--horizon", "given twice", "'5'", "'7'")),
    Case("export-c-check-and-no-check", "options",
         ("export-c", "--check", "--no-check", "--out", "{w}/ec"), ("--check", "--no-check")),
    Case("excite-heating-plant-80-degC", "options",
         ("excite", "--plant", "heating", "--t-amb", "80", "--duration", "600", "--out",
          "{w}/x.h5"), ("--t-amb", "80")),
    Case("cav-study-jobs-unbounded", "sizes", ("cav-study", "--jobs", "100000", "--json",
                                                "{w}/c.json"), ("--jobs", "256")),
    Case("validate-cv-folds-negative", "options", (*V, "--cv-folds", "-1"), ("--cv-folds",)),
    Case("excite-plant-config-empty", "files",
         ("excite", "--out", "{w}/x.h5", "--plant-config", "{w}/c.toml"),
         ("c.toml", "empty"), _write("c.toml", "")),
    Case("excite-t-amb-range-given-twice", "options",
         (*EXC, "--t-amb-range", "20", "30", "--t-amb-range", "20", "35", "--out", "{w}/x.h5"),
         ("--t-amb-range", "given twice")),
]


# ------------------------------------------------------------------------- round 4
# the newest commands and options (the car study on the real i3 logs, compare, pulldown,
# excite --design pulldown, day, validate --error-model, fit --prior/--fit-starts/--add-record,
# reproduce --scheduler) and model files that print, start processes or fork
REAL_I3 = Path(os.environ.get("ACID_REAL_DATA", "/work/shared/real-data")) / "bmw-i3"


def _logs(w: Path) -> None:
    """``{w}/logs``: a copy of the real i3 summer logs (the case is skipped without them).
    A copy, never a link: a case that writes into the logs must not reach the originals."""
    if not REAL_I3.is_dir():
        raise unittest.SkipTest(f"{REAL_I3} absent")
    (w / "logs").mkdir()
    for f in REAL_I3.glob("*.csv*"):
        shutil.copyfile(f, w / "logs" / f.name)


CAR = "{w}/logs"
_OK_MODEL = _ONE_STATE.format(step="s.T_cab + s.a * (s.W_bl - 0.1)", state="", extra="")
R4 = [
    # the car study's options on the real logs
    Case(
        "car-select-folds-nan",
        "options",
        ("car", "select", CAR, "--folds", "nan"),
        ("--folds",),
        _logs,
    ),
    Case(
        "car-select-folds-zero",
        "options",
        ("car", "select", CAR, "--folds", "0"),
        ("--folds",),
        _logs,
    ),
    Case(
        "car-select-folds-1e9",
        "sizes",
        ("car", "select", CAR, "--folds", "1000000000"),
        ("--folds",),
        _logs,
    ),
    Case(
        "car-select-rule-time-nan",
        "options",
        ("car", "select", CAR, "--rule-time", "nan"),
        ("--rule-time",),
        _logs,
    ),
    Case(
        "car-select-rule-time-negative",
        "options",
        ("car", "select", CAR, "--rule-time", "-5"),
        ("--rule-time",),
        _logs,
    ),
    Case(
        "car-select-rule-time-inf",
        "options",
        ("car", "select", CAR, "--rule-time", "inf"),
        ("--rule-time",),
        _logs,
    ),
    Case(
        "car-select-warmup-nan",
        "options",
        ("car", "select", CAR, "--warmup", "nan"),
        ("--warmup",),
        _logs,
    ),
    Case(
        "car-select-warmup-1e12",
        "sizes",
        ("car", "select", CAR, "--warmup", "1e12"),
        ("--warmup",),
        _logs,
    ),
    Case(
        "car-select-starts-negative",
        "options",
        ("car", "select", CAR, "--starts", "-1"),
        ("--starts",),
        _logs,
    ),
    Case(
        "car-select-horizon-1e9",
        "sizes",
        ("car", "select", CAR, "--horizon", "1000000000"),
        ("--horizon",),
        _logs,
    ),
    Case(
        "car-select-resamples-negative",
        "options",
        ("car", "select", CAR, "--resamples", "-1"),
        ("--resamples",),
        _logs,
    ),
    Case(
        "car-select-seed-negative",
        "options",
        ("car", "select", CAR, "--seed", "-1"),
        ("--seed",),
        _logs,
    ),
    Case(
        "car-select-max-evals-zero",
        "options",
        ("car", "select", CAR, "--max-evals", "0"),
        ("--max-evals",),
        _logs,
    ),
    Case(
        "car-select-oe-window-zero",
        "options",
        ("car", "select", CAR, "--oe-window", "0"),
        ("--oe-window",),
        _logs,
    ),
    Case(
        "car-select-season-unknown",
        "options",
        ("car", "select", CAR, "--season", "spring"),
        ("--season", "spring"),
        _logs,
    ),
    Case(
        "car-select-method-unknown",
        "options",
        ("car", "select", CAR, "--method", "magic"),
        ("--method", "magic"),
        _logs,
    ),
    Case(
        "car-select-warm-start-unknown",
        "options",
        ("car", "select", CAR, "--warm-start", "psychic"),
        ("--warm-start", "psychic"),
        _logs,
    ),
    Case(
        "car-select-candidate-unknown",
        "options",
        ("car", "select", CAR, "--candidates", "car_cabin,nope"),
        ("--candidates", "nope"),
        _logs,
    ),
    Case(
        "car-select-candidate-file-raises",
        "params",
        ("car", "select", CAR, "--candidates", "car_cabin,{w}/m.py"),
        ("m.py", "ZeroDivisionError"),
        _both(_logs, _write("m.py", "1/0\n")),
    ),
    Case(
        "car-select-trips-unknown",
        "options",
        ("car", "select", CAR, "--trips", "TripZ99"),
        ("TripZ99",),
        _logs,
    ),
    Case(
        "car-select-folds-twice",
        "options",
        ("car", "select", CAR, "--folds", "2", "--folds", "3"),
        ("--folds", "given twice"),
        _logs,
    ),
    Case(
        "car-select-json-is-a-folder",
        "output",
        ("car", "select", CAR, "--json", "{w}/adir"),
        ("--json", "adir"),
        _logs,
    ),
    Case(
        "car-select-out-under-a-file",
        "output",
        ("car", "select", CAR, "--out", "{w}/afile/p.json"),
        ("--out", "afile"),
        _logs,
    ),
    Case(
        "car-validate-folds-negative",
        "options",
        ("car", "validate", CAR, "--folds", "-1"),
        ("--folds",),
        _logs,
    ),
    Case(
        "car-validate-folds-1e9",
        "sizes",
        ("car", "validate", CAR, "--folds", "1000000000"),
        ("--folds",),
        _logs,
    ),
    Case(
        "car-validate-seed-negative",
        "options",
        ("car", "validate", CAR, "--seed", "-1"),
        ("--seed",),
        _logs,
    ),
    Case(
        "car-validate-params-missing",
        "files",
        ("car", "validate", CAR, "--params", "{w}/none.json"),
        ("none.json",),
        _logs,
    ),
    Case(
        "car-validate-params-not-json",
        "files",
        ("car", "validate", CAR, "--params", "{w}/afile"),
        ("afile",),
        _logs,
    ),
    Case(
        "car-control-horizon-zero",
        "options",
        ("car", "control", CAR, "--trip", "TripA01", "--horizon", "0"),
        ("--horizon",),
        _logs,
    ),
    Case(
        "car-control-horizon-1e9",
        "sizes",
        ("car", "control", CAR, "--trip", "TripA01", "--horizon", "1000000000"),
        ("--horizon",),
        _logs,
    ),
    Case(
        "car-control-horizon-negative",
        "options",
        ("car", "control", CAR, "--trip", "TripA01", "--horizon", "-3"),
        ("--horizon",),
        _logs,
    ),
    Case(
        "car-control-params-is-data",
        "files",
        ("car", "control", CAR, "--trip", "TripA01", "--params", D),
        ("d.h5",),
        _logs,
    ),
    Case(
        "car-fit-held-out-unknown",
        "options",
        ("car", "fit", CAR, "--held-out", "TripZ99", "--out", "{w}/ca.json"),
        ("TripZ99",),
        _logs,
    ),
    Case(
        "car-fit-logs-is-a-file",
        "files",
        ("car", "fit", "{w}/afile", "--out", "{w}/ca.json"),
        ("afile",),
    ),
    Case(
        "car-fit-logs-empty-folder",
        "files",
        ("car", "fit", "{w}/adir", "--out", "{w}/ca.json"),
        ("adir",),
    ),
    Case(
        "car-fit-logs-missing",
        "files",
        ("car", "fit", "{w}/nope", "--out", "{w}/ca.json"),
        ("nope",),
    ),
    Case(
        "car-fit-map-missing",
        "files",
        ("car", "fit", CAR, "--map", "{w}/none.toml", "--out", "{w}/ca.json"),
        ("none.toml",),
        _logs,
    ),
    Case(
        "car-fit-map-garbage",
        "files",
        ("car", "fit", CAR, "--map", "{w}/afile", "--out", "{w}/ca.json"),
        ("afile",),
        _logs,
    ),
    Case(
        "car-fit-out-inside-logs",
        "collision",
        ("car", "fit", CAR, "--out", CAR + "/TripA01.csv.gz"),
        ("--out", "TripA01.csv.gz"),
        _logs,
    ),
    Case(
        "car-fit-out-is-params",
        "collision",
        ("car", "fit", CAR, "--params", P, "--out", P),
        ("--out", "p.json"),
        _logs,
    ),
    Case(
        "heating-check-json-inside-logs",
        "collision",
        ("heating-check", "--logs", CAR, "--json", CAR + "/TripA01.csv.gz"),
        ("--json", "--logs"),
        _logs,
    ),
    # compare --identify-records
    Case(
        "compare-identify-records-nan",
        "options",
        ("compare", "--identify-records", "nan", "--json", "{w}/c.json"),
        ("--identify-records",),
    ),
    Case(
        "compare-identify-records-negative",
        "options",
        ("compare", "--identify-records", "-1", "--json", "{w}/c.json"),
        ("--identify-records", "-1"),
    ),
    Case(
        "compare-identify-records-empty",
        "options",
        ("compare", "--identify-records", "", "--json", "{w}/c.json"),
        ("--identify-records",),
    ),
    Case(
        "compare-identify-records-repeated",
        "options",
        ("compare", "--identify-records", "1,1", "--json", "{w}/c.json"),
        ("--identify-records",),
    ),
    Case(
        "compare-identify-records-huge-list",
        "sizes",
        (
            "compare",
            "--identify-records",
            ",".join(str(i) for i in range(5000)),
            "--json",
            "{w}/c.json",
        ),
        ("--identify-records",),
    ),
    Case(
        "compare-identify-records-1e30",
        "options",
        (
            "compare",
            "--identify-records",
            "1000000000000000000000000000000",
            "--json",
            "{w}/c.json",
        ),
        ("--identify-records",),
    ),
    # pulldown and excite --design pulldown
    Case("pulldown-t-amb-nan", "options", ("pulldown", "--t-amb", "nan"), ("--t-amb",)),
    Case("pulldown-t-amb-below-zero-K", "options", ("pulldown", "--t-amb", "-300"), ("--t-amb",)),
    Case("pulldown-soak-inf", "options", ("pulldown", "--soak", "inf"), ("--soak",)),
    Case("pulldown-soak-1e300", "options", ("pulldown", "--soak", "1e300"), ("--soak",)),
    Case("pulldown-seed-negative", "options", ("pulldown", "--seed", "-1"), ("--seed",)),
    Case(
        "pulldown-json-is-a-folder",
        "output",
        ("pulldown", "--quick", "--json", "{w}/adir"),
        ("--json", "adir"),
    ),
    Case(
        "pulldown-json-under-a-file",
        "output",
        ("pulldown", "--quick", "--json", "{w}/afile/x.json"),
        ("--json", "afile"),
    ),
    Case(
        "excite-pulldown-soak-range-reversed",
        "options",
        ("excite", "--design", "pulldown", "--soak-range", "55", "30", "--out", "{w}/x.h5"),
        ("--soak-range",),
    ),
    Case(
        "excite-pulldown-soak-range-nan",
        "options",
        ("excite", "--design", "pulldown", "--soak-range", "nan", "55", "--out", "{w}/x.h5"),
        ("--soak-range",),
    ),
    Case(
        "excite-pulldown-soak-range-below-zero-K",
        "options",
        ("excite", "--design", "pulldown", "--soak-range", "-300", "55", "--out", "{w}/x.h5"),
        ("--soak-range",),
    ),
    Case(
        "excite-pulldown-segment-zero",
        "options",
        ("excite", "--design", "pulldown", "--segment-duration", "0", "--out", "{w}/x.h5"),
        ("--segment-duration",),
    ),
    Case(
        "excite-pulldown-segment-nan",
        "options",
        ("excite", "--design", "pulldown", "--segment-duration", "nan", "--out", "{w}/x.h5"),
        ("--segment-duration",),
    ),
    Case(
        "excite-pulldown-segment-1e12",
        "sizes",
        ("excite", "--design", "pulldown", "--segment-duration", "1e12", "--out", "{w}/x.h5"),
        ("--segment-duration",),
    ),
    Case(
        "excite-design-unknown",
        "options",
        ("excite", "--design", "zigzag", "--out", "{w}/x.h5"),
        ("--design", "zigzag"),
    ),
    Case(
        "excite-soak-range-without-pulldown",
        "options",
        ("excite", "--soak-range", "30", "55", "--out", "{w}/x.h5"),
        ("--soak-range",),
    ),
    # day
    Case("day-days-zero", "options", ("day", "--days", "0", "--out", "{w}/dd"), ("--days",)),
    Case("day-days-nan", "options", ("day", "--days", "nan", "--out", "{w}/dd"), ("--days",)),
    Case(
        "day-planner-unknown",
        "options",
        ("day", "--planner", "oracle", "--out", "{w}/dd"),
        ("--planner", "oracle"),
    ),
    Case(
        "day-planner-and-no-planner",
        "options",
        ("day", "--planner", "model", "--no-planner", "--out", "{w}/dd"),
        ("--planner", "--no-planner"),
    ),
    Case("day-jobs-1e9", "sizes", ("day", "--jobs", "1000000000", "--out", "{w}/dd"), ("--jobs",)),
    # validate --error-model
    Case(
        "validate-error-model-unknown",
        "options",
        (*V, "--model", "paper", "--error-model", "magic"),
        ("--error-model", "magic"),
    ),
    Case(
        "validate-error-model-without-data",
        "options",
        (*V, "--model", "paper", "--error-model", "arx"),
        ("--error-model-data",),
    ),
    Case(
        "validate-error-model-data-missing",
        "files",
        (*V, "--model", "paper", "--error-model", "arx", "--error-model-data", "{w}/none.h5"),
        ("none.h5",),
    ),
    Case(
        "validate-error-model-data-not-hdf5",
        "files",
        (*V, "--model", "paper", "--error-model", "arx", "--error-model-data", "{w}/afile"),
        ("afile",),
    ),
    Case(
        "validate-error-model-data-is-data",
        "options",
        (*V, "--model", "paper", "--error-model", "arx", "--error-model-data", D),
        ("--error-model-data", "d.h5"),
    ),
    Case(
        "validate-error-model-data-without-model",
        "options",
        (*V, "--error-model-data", D),
        ("--error-model-data", "--error-model"),
    ),
    # fit --prior / --fit-starts
    Case(
        "fit-prior-sd-negative",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--prior", "C_cab=100,-1"),
        ("--prior", "C_cab"),
    ),
    Case(
        "fit-prior-sd-zero",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--prior", "C_cab=100,0"),
        ("--prior", "C_cab"),
    ),
    Case(
        "fit-prior-mean-nan",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--prior", "C_cab=nan,1"),
        ("--prior", "C_cab"),
    ),
    Case(
        "fit-prior-mean-inf",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--prior", "C_cab=inf,1"),
        ("--prior", "C_cab"),
    ),
    Case(
        "fit-prior-sd-1e300",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--prior", "C_cab=100,1e300"),
        ("--prior", "C_cab"),
    ),
    Case(
        "fit-prior-mean-outside-bounds",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--prior", "C_cab=1e9,10"),
        ("--prior", "C_cab", "bounds"),
    ),
    Case(
        "fit-prior-unknown-parameter",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--prior", "warp=1,1"),
        ("--prior", "warp"),
    ),
    Case(
        "fit-prior-no-sd",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--prior", "C_cab=100"),
        ("--prior",),
    ),
    Case(
        "fit-prior-garbage",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--prior", "=,"),
        ("--prior",),
    ),
    Case(
        "fit-prior-twice-same-name",
        "options",
        (
            "fit",
            D,
            "--out",
            "{w}/q.json",
            "--model",
            "econ",
            "--prior",
            "C_cab=100,1",
            "--prior",
            "C_cab=50,1",
        ),
        ("--prior", "C_cab"),
    ),
    Case(
        "fit-prior-on-paper-model",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--prior", "gamma1=nan,1"),
        ("--prior", "gamma1"),
    ),
    Case(
        "fit-fit-starts-negative",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--fit-starts", "-1"),
        ("--fit-starts",),
    ),
    Case(
        "fit-fit-starts-1e9",
        "sizes",
        ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--fit-starts", "1000000000"),
        ("--fit-starts",),
    ),
    Case(
        "fit-fit-starts-nan",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--model", "econ", "--fit-starts", "nan"),
        ("--fit-starts",),
    ),
    Case(
        "fit-add-record-missing",
        "files",
        ("fit", D, "--out", "{w}/q.json", "--add-record", "{w}/none.h5"),
        ("none.h5",),
    ),
    Case(
        "fit-add-record-is-data",
        "options",
        ("fit", D, "--out", "{w}/q.json", "--add-record", D),
        ("--add-record", "d.h5"),
    ),
    Case(
        "fit-add-record-is-out",
        "collision",
        ("fit", D, "--out", "{w}/q.h5", "--add-record", "{w}/q.h5"),
        ("--add-record", "q.h5"),
    ),
    # reproduce --scheduler
    Case(
        "reproduce-scheduler-garbage",
        "options",
        ("reproduce", "--quick", "--out", "{w}/r", "--scheduler", "not a url"),
        ("--scheduler",),
    ),
    Case(
        "reproduce-scheduler-refused",
        "options",
        ("reproduce", "--quick", "--out", "{w}/r", "--scheduler", "tcp://127.0.0.1:9"),
        ("--scheduler",),
    ),
    Case(
        "reproduce-scheduler-empty",
        "options",
        ("reproduce", "--quick", "--out", "{w}/r", "--scheduler", ""),
        ("--scheduler",),
    ),
    Case(
        "reproduce-scheduler-unroutable",
        "options",
        ("reproduce", "--quick", "--out", "{w}/r", "--scheduler", "tcp://10.255.255.1:8786"),
        ("--scheduler",),
    ),
    # model files: prints megabytes, starts a process, loops
    Case(
        "fit-model-file-prints-megabytes",
        "params",
        ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"),
        ("m.py", "prints"),
        _write("m.py", "print('x' * 5_000_000)\n" + _OK_MODEL),
    ),
    Case(
        "fit-model-file-starts-a-process",
        "params",
        ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"),
        ("m.py", "process"),
        _write("m.py", "import subprocess\nsubprocess.Popen(['sleep', '300'])\n" + _OK_MODEL),
    ),
    Case(
        "fit-model-file-forks",
        "params",
        ("fit", D, "--out", "{w}/q.json", "--model", "{w}/m.py"),
        ("m.py", "process"),
        _write(
            "m.py",
            "import os, time\nif os.fork() == 0:\n    time.sleep(300)\n    os._exit(0)\n"
            + _OK_MODEL,
        ),
    ),
]
CASES += R4

# ------------------------------------------------------------------------- running
def snapshot(w: Path) -> dict[str, str]:
    """{relative path: sha256 or '<dir>'} of everything in the workspace."""
    out = {}
    for p in sorted(w.rglob("*")):
        rel = str(p.relative_to(w))
        if p.is_symlink():
            out[rel] = "<link>" + os.readlink(p)
        elif p.is_dir():
            out[rel] = "<dir>"
        else:
            out[rel] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


@dataclass
class Outcome:
    case: Case
    exit_code: int | None
    output: str
    traceback: bool
    changed: list[str]
    created: list[str]
    result: object = None  # the CliRunner result

    @property
    def lines(self) -> list[str]:
        return [ln for ln in self.output.splitlines() if ln.strip()]


def classify(o: Outcome, w: Path) -> str:
    """clean / traceback / exit0 / dataloss / internal / unclear (see the module docstring)."""
    if o.changed:
        return "dataloss"
    if o.traceback:
        return "traceback"
    if o.exit_code == 0:
        return "exit0"
    flat = " ".join(o.output.split())
    if "internal error" in flat:
        return "internal"
    if (o.exit_code == 2 and len(o.lines) == 1 and o.lines[0].startswith("error:")
            and all(f in flat for f in o.case.fragments(w)) and not o.created):
        return "clean"
    return "unclear"


def run_case(case: Case, template: Path, w: Path) -> Outcome:
    """Copy the workspace, build the case's files, run it in-process (CliRunner)."""
    from typer.testing import CliRunner

    from acid_cli.main import app

    if w.exists():
        shutil.rmtree(w)
    shutil.copytree(template, w, symlinks=True)
    if case.make is not None:
        case.make(w)
    before = snapshot(w)
    res = CliRunner().invoke(app, case.argv(w))
    after = snapshot(w)
    tb = ("Traceback" in res.output
          or (res.exception is not None and not isinstance(res.exception, SystemExit)))
    changed = [k for k, v in before.items() if after.get(k) != v]
    created = [k for k in after if k not in before]
    return Outcome(case, res.exit_code, res.output, tb, changed, created, res)


def _run_one_in_subprocess(case: Case, template: Path, w: Path, timeout: float) -> str:
    import subprocess

    cmd = [sys.executable, __file__, "--one", case.id, str(template), str(w)]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                           preexec_fn=_limit_memory)
    except subprocess.TimeoutExpired:
        return "timeout"
    last = r.stdout.strip().splitlines()[-1:] or [""]
    return last[0] if last[0] in ("clean", "traceback", "exit0", "dataloss", "internal",
                                  "unclear") else ("crash" if r.returncode else "unclear")


def _limit_memory() -> None:
    import resource

    cap = 4 * 1024 ** 3  # 4 GiB: sizes that used to exhaust memory fail here instead
    resource.setrlimit(resource.RLIMIT_AS, (cap, cap))


def main(argv: list[str]) -> int:
    import tempfile

    if argv[:1] == ["--one"]:
        case = next(c for c in CASES if c.id == argv[1])
        o = run_case(case, Path(argv[2]), Path(argv[3]))
        print(o.output)
        print(classify(o, Path(argv[3])))
        return 0
    sub = "--subprocess" in argv
    root = Path(tempfile.mkdtemp(prefix="acid-catalogue-"))
    template = build_workspace(root / "template")
    counts: Counter = Counter()
    by_class: dict[str, Counter] = {}
    for case in CASES:
        w = root / "case"
        if sub:
            verdict = _run_one_in_subprocess(case, template, w, timeout=120)
        else:
            o = run_case(case, template, w)
            verdict = classify(o, w)
        counts[verdict] += 1
        by_class.setdefault(case.cls, Counter())[verdict] += 1
        if verdict != "clean":
            print(f"{verdict:9s} {case.id}", flush=True)
    print(f"{len(CASES)} cases: " + ", ".join(f"{k} {v}" for k, v in counts.most_common()))
    for cls, c in by_class.items():
        print(f"  {cls:10s} " + ", ".join(f"{k} {v}" for k, v in c.most_common()))
    shutil.rmtree(root, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    raise SystemExit(main(sys.argv[1:]))


