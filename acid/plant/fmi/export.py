"""``acid export-fmu``: acid's high-fidelity plant as an FMI co-simulation FMU (pythonfmu).

The FMU wraps :class:`acid.plant.hifi.HifiPlant` generically: the variables it exposes are
those the plant reports (a probe run at export time lists the states of
``HifiPlant.measure`` and the per-step means of ``HifiPlant.step``), so the export follows the
plant when its states and channels change. The plant configuration is baked into the FMU
(``resources/acid_plant.json``); the slave code is :mod:`acid.plant.fmi._slave`. Beside the
FMU, the export writes the FMU map (TOML) that drives it from acid (``--fmu-map``).

FMI 2.0 through pythonfmu (the default) or FMI 3.0 through pythonfmu3. The FMU runs in the
Python process that loads it, which must have acid installed (pythonfmu FMUs embed no
interpreter of their own).
"""

from __future__ import annotations

import json
import shutil
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path

from acid import __version__
from acid._io import atomic_path, write_text
from acid.errors import ConfigError, OutputError
from acid.plant.config import PlantConfig

#: Model identifier (and slave class) per FMI version: distinct, so that FMUs of both
#: versions can be loaded into one Python process (pythonfmu imports the slave by name).
MODEL_IDENTIFIERS = {2: "AcidHifiPlant", 3: "AcidHifiPlant3"}
SPEC_FILE = "acid_plant.json"
#: Real inputs of the exported FMU: channel -> (unit, where its start value comes from)
INPUTS = ("W_bl", "T_evap_set", "v_veh", "T_amb", "T_cab_set")


@dataclass(frozen=True)
class ExportResult:
    """What ``export_fmu`` wrote.

    Attributes
    ----------
    fmu : the FMU file.
    fmu_map : the TOML map that drives it from acid (None when not written).
    fmi_version : 2 or 3.
    model_identifier : the FMU's model identifier.
    states, means : the channels exposed as ``state.<name>`` and ``mean.<name>``.
    """

    fmu: Path
    fmu_map: Path | None
    fmi_version: int
    model_identifier: str
    states: tuple[str, ...]
    means: tuple[str, ...]

    def to_json_dict(self) -> dict:
        return {"fmu": str(self.fmu), "fmu_map": None if self.fmu_map is None else
                str(self.fmu_map), "fmi_version": self.fmi_version,
                "model_identifier": self.model_identifier, "states": list(self.states),
                "means": list(self.means)}


def plant_interface(config: PlantConfig | None = None) -> dict:
    """Probe ``HifiPlant(config)``: what the FMU exposes, with units and start values.

    Returns the JSON spec baked into the FMU: ``config``, ``states`` (channel -> value at
    reset), ``means`` (per-step channels), ``initial`` (reset keys -> default values),
    ``inputs`` (channel -> start value) and ``units`` (channel -> inside unit, K for
    temperatures; the units a native dataset stores, before degC conversion).
    """
    from acid.plant import hifi
    from acid.plant.base import measurements_to_dataset

    config = config or PlantConfig()
    plant = hifi.HifiPlant(config)
    state = plant.reset()
    row = plant.step(0.1, config.T_ew_set, 0.0)
    states = {k: float(v) for k, v in state.items()}
    means = [k for k in row if k not in states]
    ds_units = measurements_to_dataset([row], config.Ts, {}, units=plant.units()).units
    units = {k: ("K" if u == "degC" else u) for k, u in ds_units.items()}
    initial = {k: states[k] for k in getattr(hifi, "INITIAL_KEYS", ()) if k in states}
    inputs = {"W_bl": 0.1, "T_evap_set": float(config.T_ew_set), "v_veh": 0.0,
              "T_amb": float(config.T_amb), "T_cab_set": float(config.T_cab_set)}
    units.update({"W_bl": "kg/s", "T_evap_set": "K", "v_veh": "m/s", "T_amb": "K",
                  "T_cab_set": "K"})
    return {"acid_version": __version__, "config": config.to_dict(), "state_values": states,
            "states": list(states), "means": means, "initial": initial, "inputs": inputs,
            "units": units}


def fmu_map_text(spec: dict, fmu_name: str, fmi_version: int) -> str:
    """The TOML FMU map of an exported FMU (every channel it exposes, with units)."""
    u = spec["units"]
    Ts = float(spec["config"]["Ts"])

    def line(channel: str, name: str, sampling: str | None = None) -> str:
        extra = f', sampling = "{sampling}"' if sampling else ""
        return f'{channel} = {{ name = "{name}", unit = "{u[channel]}"{extra} }}'

    out = [f"# FMU map for {fmu_name}: acid's high-fidelity plant exported as an FMI "
           f"{fmi_version}.0 co-simulation FMU",
           f"# (acid {__version__}). Drive it with: --plant fmu:{fmu_name} --fmu-map <this file>",
           "# Format: datasets/FORMAT.md, section 'FMU maps'.", "",
           "[fmu]", 'label = "acid-hifi-fmu"',
           f"Ts = {Ts!r}        # acid's sample period, s",
           f"step = {Ts!r}      # FMU communication step, s (Ts or a divisor of it)", "",
           "[inputs]       # set at t_k, held over the sample"]
    out += [line(ch, f"input.{ch}") for ch in spec["inputs"]]
    out.append('compressor_enabled = { name = "input.compressor_enabled" }')
    out += ["", "[states]       # read at t_k, before the step"]
    out += [line(ch, f"state.{ch}") for ch in spec["states"]]
    out += ["", "[outputs]      # means over the sample (the FMU reports step means)"]
    out += [line(ch, f"mean.{ch}", "interval-mean") for ch in spec["means"]]
    out += ["", "[initial]      # reset(initial=...) sets these start values"]
    out += [line(ch, f"start.{ch}") for ch in spec["initial"]]
    out += ["", "[modes.direct] # acid commands W_bl and T_evap_set", "nominal = false", "",
            "[modes.nominal] # the plant's own nominal controller (speed-sweep)",
            "nominal = true", ""]
    return "\n".join(out)


def _unit_definitions(root: ET.Element, units_used: set[str]) -> None:
    """Insert ``<UnitDefinitions>`` (right after ``<CoSimulation>``, as the schemas order)."""
    from acid.plant.fmi.plant import fmi_unit_definition

    defs = ET.Element("UnitDefinitions")
    for name in sorted(units_used):
        exps, factor, offset = fmi_unit_definition(name)
        unit = ET.SubElement(defs, "Unit", {"name": name})
        attrib = {k: str(v) for k, v in exps.items()}
        if factor != 1.0:
            attrib["factor"] = repr(factor)
        if offset != 0.0:
            attrib["offset"] = repr(offset)
        ET.SubElement(unit, "BaseUnit", attrib)
    children = list(root)
    pos = next(i for i, c in enumerate(children) if c.tag == "CoSimulation") + 1
    root.insert(pos, defs)


def _annotate(xml: bytes, spec: dict, fmi_version: int) -> bytes:
    """Units on every Real variable, UnitDefinitions and the default experiment."""
    root = ET.fromstring(xml)
    units = spec["units"]
    used = set()

    def unit_of(name: str) -> str | None:
        prefix, _, channel = name.partition(".")
        if prefix in ("input", "state", "mean", "start") and channel in units:
            return units[channel]
        return None

    for var in root.iter("ScalarVariable" if fmi_version == 2 else "Float64"):
        unit = unit_of(var.get("name", ""))
        if unit is None:
            continue
        target = var.find("Real") if fmi_version == 2 else var
        if target is not None:
            target.set("unit", unit)
            used.add(unit)
    _unit_definitions(root, used)
    de = root.find("DefaultExperiment")
    if de is None:
        de = ET.Element("DefaultExperiment")
        children = list(root)
        pos = next(i for i, c in enumerate(children) if c.tag == "ModelVariables")
        root.insert(pos, de)
    de.set("startTime", "0.0")
    de.set("stepSize", repr(float(spec["config"]["Ts"])))
    ET.indent(root)
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8")


def export_fmu(out: str | Path, config: PlantConfig | None = None, fmi_version: int = 2,
               map_out: str | Path | None = None) -> ExportResult:
    """Export the high-fidelity plant (configuration ``config``) as a co-simulation FMU.

    Parameters
    ----------
    out : the ``.fmu`` file to write (atomically).
    config : plant configuration baked into the FMU (default ``PlantConfig()``).
    fmi_version : 2 (pythonfmu) or 3 (pythonfmu3).
    map_out : where to write the FMU map (TOML); None for none.
    """
    out = Path(out)
    if out.suffix != ".fmu":
        raise ConfigError(f"--out: an FMU file name ends in .fmu, got {out}")
    if fmi_version not in MODEL_IDENTIFIERS:
        raise ConfigError(f"--fmi-version must be 2 or 3, got {fmi_version}")
    try:
        if fmi_version == 3:
            from pythonfmu3.builder import FmuBuilder
        else:
            from pythonfmu.builder import FmuBuilder
    except ImportError:
        pkg = "pythonfmu3" if fmi_version == 3 else "pythonfmu"
        raise ConfigError(f"export-fmu needs {pkg} (pip install 'acid[fmi]')") from None
    config = config or PlantConfig()
    spec = plant_interface(config)
    ident = MODEL_IDENTIFIERS[fmi_version]
    template = (Path(__file__).parent / "_slave.py").read_text()
    source = (template.replace("FMI_VERSION = 2  # replaced at export",
                               f"FMI_VERSION = {fmi_version}")
              .replace("class AcidHifiPlant(Slave):",
                       f"class {ident}(Fmi{fmi_version}Slave):"))
    saved_path, saved_modules = list(sys.path), set(sys.modules)
    try:
        tmp_dir = tempfile.TemporaryDirectory(prefix="acid-export-")
    except OSError as exc:
        raise OutputError(f"{out}: cannot create a temporary folder to build the FMU "
                          f"({exc.strerror or type(exc).__name__})") from None
    with tmp_dir as tmp:
        tmp = Path(tmp)
        src = tmp / "src"
        try:  # a full disk or a file-size limit while building: one line naming --out
            src.mkdir()
            script = src / f"{ident}.py"
            script.write_text(source)
            spec_file = src / SPEC_FILE
            spec_file.write_text(json.dumps(spec, indent=1))
            built = Path(FmuBuilder.build_FMU(script, dest=tmp / f"{ident}.fmu",
                                              project_files=[spec_file]))
        except OSError as exc:
            raise OutputError(f"{out}: cannot build the FMU in a temporary folder "
                              f"({exc.strerror or type(exc).__name__})") from None
        finally:
            sys.path[:] = saved_path
            for name in set(sys.modules) - saved_modules:
                if name == ident or name.startswith(ident + "."):
                    del sys.modules[name]
        with atomic_path(out) as part, zipfile.ZipFile(built) as zin, \
                zipfile.ZipFile(part, "w", zipfile.ZIP_DEFLATED) as zout:
            for item in zin.infolist():
                data = zin.read(item.filename)
                if item.filename == "modelDescription.xml":
                    data = _annotate(data, spec, fmi_version)
                zout.writestr(item, data)
        shutil.rmtree(src, ignore_errors=True)
    map_path = None
    if map_out is not None:
        map_path = write_text(map_out, fmu_map_text(spec, out.name, fmi_version))
    return ExportResult(fmu=out, fmu_map=map_path, fmi_version=fmi_version,
                        model_identifier=ident, states=tuple(spec["states"]),
                        means=tuple(spec["means"]))
