"""degC at every edge (issue 23): a quick tour (excite, fit, validate, mpc-check, speed-sweep,
plant-check on a plant file in degC, a one-scenario sweep) leaves no absolute temperature in
kelvin in what the user reads: printed text, JSON keys and values, CSV headers and cells,
figure axes.

A temperature *difference* (an error, a violation, a band) may be given in K: a kelvin and a
degC of difference are the same size. What this test refuses is an absolute temperature in
kelvin: a number from 150 to 450 labelled K, a key ``..._K`` holding one, a temperature-named
key holding one, an axis whose temperature values lie in that range.
"""

from __future__ import annotations

import csv
import json
import math
import re

import matplotlib
import pytest
from typer.testing import CliRunner

from acid_cli.main import app

matplotlib.use("Agg")
from matplotlib.figure import Figure  # noqa: E402

runner = CliRunner()

#: a number from 150 to 450 followed by the unit K: an absolute temperature in kelvin
KELVIN_TEXT = re.compile(r"(?<![\d.])(1[5-9]\d|[2-4]\d\d)(\.\d+)?\s*K\b(?!/)")
#: names that hold a temperature
TEMPERATURE_NAME = re.compile(r"(^|_)T_|_C$|_degC$|_K$|temperature|set_?point|bound")
KELVIN = (150.0, 450.0)

TINY_SWEEP = ('[defaults]\ncycle = 10.0\nduration_s = 60.0\nwarmup_s = 0.0\n'
              '[grid]\nambient_C = [30.0]\n[controllers.nominal]\n')


def _in_kelvin_range(v) -> bool:
    return (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            and KELVIN[0] <= v <= KELVIN[1])


def _json_offences(obj, path: str) -> list[str]:
    found = []
    if isinstance(obj, dict):
        for key, value in obj.items():
            here = f"{path}.{key}"
            if isinstance(key, str) and TEMPERATURE_NAME.search(key):
                values = value if isinstance(value, list) else [value]
                if any(_in_kelvin_range(v) for v in values):
                    found.append(f"{here} = {value!r}")
            found += _json_offences(value, here)
    elif isinstance(obj, list):
        for i, value in enumerate(obj):
            found += _json_offences(value, f"{path}[{i}]")
    elif isinstance(obj, str) and KELVIN_TEXT.search(obj):
        found.append(f"{path}: {obj!r}")
    return found


@pytest.fixture(scope="module")
def tour(tmp_path_factory):
    """Run the quick tour once; collect the text, the files and every saved figure's axes."""
    w = tmp_path_factory.mktemp("tour")
    axes = []
    original = Figure.savefig

    def recording_savefig(fig, *args, **kwargs):
        for ax in fig.axes:
            for label, limits, data in (
                    (ax.get_ylabel(), ax.get_ylim(), [ln.get_ydata() for ln in ax.lines]),
                    (ax.get_xlabel(), ax.get_xlim(), [ln.get_xdata() for ln in ax.lines])):
                axes.append((str(args[0]) if args else "", ax.get_title(), label, limits, data))
        return original(fig, *args, **kwargs)

    (w / "s.toml").write_text(TINY_SWEEP)
    (w / "plant.toml").write_text('[ambient]\nT_amb = 35.0\n[initial]\nT_cab0 = "318.15 K"\n')
    commands = [
        ["excite", "--out", f"{w}/d.h5", "--duration", "3000", "--plant-config",
         f"{w}/plant.toml", "--json", f"{w}/excite.json"],
        ["fit", f"{w}/d.h5", "--out", f"{w}/p.json", "--json", f"{w}/fit.json"],
        ["validate", f"{w}/d.h5", "--params", f"{w}/p.json", "--starts", "5", "--horizon", "60",
         "--no-yardsticks", "--out", f"{w}/val", "--json", f"{w}/validate.json"],
        ["mpc-check", "--skip-plant", "--t-amb", "35", "--out", f"{w}/mpc", "--json",
         f"{w}/mpc.json"],
        ["speed-sweep", "--duration", "30", "--t-amb", "35", "--out", f"{w}/sw", "--json",
         f"{w}/speed.json"],
        ["plant-check", "--plant-config", f"{w}/plant.toml", "--out", f"{w}/pc", "--json",
         f"{w}/pc.json"],
        ["sweep", f"{w}/s.toml", "--out", f"{w}/sweep", "--jobs", "1", "--json",
         f"{w}/sweep.json"],
    ]
    #: plant-check exits 1 when a check fails (a plant file's vehicle may fail Table I)
    allowed = {"plant-check": (0, 1)}
    text = {}
    mp = pytest.MonkeyPatch()
    mp.setattr(Figure, "savefig", recording_savefig)
    try:
        for cmd in commands:
            result = runner.invoke(app, cmd, terminal_width=200)
            assert result.exit_code in allowed.get(cmd[0], (0,)), (cmd, result.output)
            text[cmd[0]] = result.output
    finally:
        mp.undo()
    return w, text, axes


@pytest.mark.slow
def test_printed_text_has_no_kelvin(tour):
    _, text, _ = tour
    found = [f"acid {cmd}: {line.strip()}" for cmd, out in text.items()
             for line in out.splitlines() if KELVIN_TEXT.search(line)]
    assert not found, "\n".join(found)


@pytest.mark.slow
def test_json_files_have_no_kelvin(tour):
    w, _, _ = tour
    found = []
    files = sorted(w.rglob("*.json"))
    assert len(files) >= 10, files
    for f in files:
        if f.name == "p.json":   # the model's parameter file: the model's own units (eqs. 1-5)
            continue
        found += _json_offences(json.loads(f.read_text()), f.name)
    assert not found, "\n".join(found)


@pytest.mark.slow
def test_csv_headers_and_cells_have_no_kelvin(tour):
    w, _, _ = tour
    files = sorted(w.rglob("*.csv"))
    assert files
    found = []
    for f in files:
        with f.open() as fh:
            rows = list(csv.DictReader(fh))
        for row in rows:
            for column, cell in row.items():
                if column.endswith("_K") or TEMPERATURE_NAME.search(column):
                    try:
                        value = float(cell)
                    except (TypeError, ValueError):
                        continue
                    if _in_kelvin_range(value) and "_Ks" not in column:
                        found.append(f"{f.name}: {column} = {cell}")
                if cell.startswith("{"):
                    found += _json_offences(json.loads(cell), f"{f.name}:{column}")
    assert not found, "\n".join(found)


@pytest.mark.slow
def test_figure_axes_have_no_kelvin(tour):
    _, _, axes = tour
    assert axes
    found = []
    for figure, title, label, limits, data in axes:
        if re.search(r"\bK\b|kelvin", label) and all(_in_kelvin_range(v) for v in limits):
            found.append(f"{figure}: {title!r}: axis {label!r} spans {limits}")
        if re.search(r"°C|degC", label):
            values = [float(v) for d in data for v in d
                      if isinstance(v, (int, float)) and math.isfinite(v)]
            if values and min(values) > KELVIN[0]:
                found.append(f"{figure}: {title!r}: axis {label!r} plots kelvin values")
    assert not found, "\n".join(found)


@pytest.mark.slow
def test_every_plant_run_says_its_vehicle_refrigerant_and_ambient(tour):
    w, text, _ = tour
    excite = json.loads((w / "excite.json").read_text())
    assert excite["vehicle"].endswith("plant.toml") and excite["refrigerant"] == "R134a"
    assert excite["T_amb_C"] == pytest.approx(35.0)
    for name in ("mpc.json", "speed.json", "pc.json"):
        d = json.loads((w / name).read_text())
        assert d["refrigerant"] == "R134a" and d["T_amb_C"] == pytest.approx(35.0), name
    plant_file = json.loads((w / "pc.json").read_text())
    assert plant_file["plant_config"]["T_cab0"] == pytest.approx(45.0)   # "318.15 K" given
    assert "refrigerant R134a, ambient 35 degC" in text["speed-sweep"]
    assert "refrigerant R134a, ambient 35 degC" in text["mpc-check"]
