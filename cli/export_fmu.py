"""``acid export-fmu``: acid's high-fidelity plant as an FMI co-simulation FMU (with its map)."""

from __future__ import annotations

import time
from pathlib import Path

import typer

from acid import __version__
from acid._io import file_sha256
from acid.errors import ConfigError
from acid_cli._common import check_paths, handle_errors, print_table, say, write_summary
from acid_cli._plant import (
    config_input,
    identity_line,
    plant_identity,
    plant_overrides,
    refrigerant_option,
)


@handle_errors
def export_fmu(
    out: Path = typer.Option(..., "--out", "-o", help="The FMU to write (atomically), *.fmu."),
    plant_config: Path | None = typer.Option(
        None, "--plant-config", help="TOML plant configuration baked into the FMU (default: "
                                     "the documented calibration)."),
    refrigerant: str | None = refrigerant_option(),
    fmi_version: int = typer.Option(2, "--fmi-version",
                                    help="FMI version: 2 (pythonfmu) or 3 (pythonfmu3)."),
    map_out: Path | None = typer.Option(
        None, "--fmu-map", help="Where to write the FMU map that drives it (default: the FMU's "
                            "name with .toml)."),
    json_out: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
) -> None:
    """Export the high-fidelity plant as a co-simulation FMU, and the map that drives it.

    The FMU exposes what the plant reports (states at each communication point, means over
    each step) in SI units with kelvin; it runs in the Python that loads it, which needs acid.
    Drive it with `--plant fmu:OUT.fmu --fmu-map OUT.toml`.
    """
    from acid.plant.config import PlantConfig
    from acid.plant.fmi.export import export_fmu as run_export
    from acid.plant.vehicles import vehicle_label

    if fmi_version not in (2, 3):
        raise ConfigError(f"--fmi-version must be 2 or 3, got {fmi_version}")
    label = vehicle_label(plant_config)
    plant_config = config_input(plant_config)  # a named vehicle ('paper') -> its file
    if plant_config is not None and not plant_config.is_file():
        raise ConfigError(f"--plant-config: file not found: {plant_config}")
    if out.suffix != ".fmu":
        raise ConfigError(f"--out: an FMU file name ends in .fmu, got {out}")
    map_out = map_out if map_out is not None else out.with_suffix(".toml")
    check_paths(inputs={"--plant-config": plant_config},
                outputs={"--out": out, "--fmu-map": map_out, "--json": json_out})
    if map_out.resolve() == out.resolve():
        raise ConfigError("--fmu-map must differ from --out")
    cfg = PlantConfig.from_toml(plant_config) if plant_config is not None else PlantConfig()
    cfg = cfg.replace(**plant_overrides(refrigerant=refrigerant))
    identity = plant_identity(cfg, label)
    say(identity_line(identity))
    t0 = time.perf_counter()
    result = run_export(out, cfg, fmi_version=fmi_version, map_out=map_out)
    elapsed = time.perf_counter() - t0
    print_table(f"{out}: FMI {fmi_version}.0 co-simulation FMU, model "
                f"{result.model_identifier} ({elapsed:.2f} s)",
                ["_variables", "count", "_names"],
                [["state.*", len(result.states), ", ".join(result.states)],
                 ["mean.*", len(result.means), ", ".join(result.means)]])
    say(f"FMU map written to {result.fmu_map}")
    say(f"drive it with: --plant fmu:{out} --fmu-map {result.fmu_map}")
    write_summary(json_out, {
        "command": "export-fmu", "acid_version": __version__, **identity,
        **result.to_json_dict(),
        "fmu_sha256": file_sha256(out), "elapsed_s": elapsed,
        "plant_config": None if plant_config is None else str(plant_config),
        "plant_config_sha256": None if plant_config is None else file_sha256(plant_config),
    })
