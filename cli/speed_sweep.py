"""``acid speed-sweep``: the paper's speed-sensitivity study (Fig. 3, Table I) on the plant."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from acid import __version__
from acid._io import file_sha256, save_figure, write_json
from acid.errors import ConfigError
from acid_cli._common import (
    check_paths,
    handle_errors,
    plant_inputs,
    print_table,
    progress_bar,
    require_range,
    say,
    write_summary,
)
from acid_cli._plant import fmu_map_option, plant_choice, plant_option

#: Longest simulated time per speed accepted, s (one day).
MAX_DURATION_S = 86400.0


def _fmt(v, digits: int = 3) -> str:
    return "NA" if v is None or not math.isfinite(v) else f"{v:.{digits}f}"


@handle_errors
def speed_sweep(
    config: Path | None = typer.Option(None, "--config",
                                       help="Plant configuration (TOML, SI units, K)."),
    duration: float = typer.Option(600.0, "--duration", help="Simulated time per speed, s."),
    out: Path = typer.Option(Path("reports/speed-sweep"), "--out",
                             help="Folder for the figure and the result JSON."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
    plant: str = plant_option("hifi", ("hifi",)),
    fmu_map: Path | None = fmu_map_option(),
) -> None:
    """Run the nominal controller at 0-25 m/s for --duration s and compare with Table I.

    Energy is compressor + blower (as in the paper), in MJ and MJ/km.
    """
    from acid.claims import TABLE_I
    from acid.plant.config import PlantConfig
    from acid.plant.sweep import speed_sweep as run_sweep
    from acid.report.plant import sweep_figure

    check_paths(inputs={"--config": config, **plant_inputs(plant, fmu_map)},
                outputs={"--json": json_path},
                folders={"--out": (out, ("speed_sweep.png", "speed_sweep.json"))})
    require_range(duration, "--duration", 0.0, MAX_DURATION_S, "s", lo_open=True)
    choice = plant_choice(plant, fmu_map, allowed=("hifi",))
    if config is not None and choice.kind != "hifi":
        raise ConfigError("--config applies to --plant hifi only (an FMU plant is configured "
                          "through --fmu-map)")
    factory = None
    if choice.kind == "fmu":
        choice.check(mode="nominal")
        factory = choice.factory(mode="nominal")
    cfg = PlantConfig.from_toml(config) if config is not None else PlantConfig()
    speeds = TABLE_I.speeds_mps
    with progress_bar("speed sweep", total=len(speeds)) as update:
        result = run_sweep(cfg, speeds=speeds, duration=duration, progress=update,
                           plant_factory=factory)

    paper_E = TABLE_I.energy_MJ
    paper_km = [math.nan if e is None else e for e in TABLE_I.energy_MJ_per_km]
    rows = [[f"{v:g}", _fmt(e), _fmt(pe, 2), _fmt(ek), _fmt(pk)]
            for v, e, ek, pe, pk in zip(result.speeds_mps, result.energy_MJ,
                                        result.energy_MJ_per_km, paper_E, paper_km,
                                        strict=True)]
    print_table(f"A/C energy over {result.duration_s:g} s (compressor + blower)",
                ["speed (m/s)", "energy (MJ)", "paper (MJ)", "MJ/km", "paper MJ/km"], rows)
    say(f"E({speeds[-1]:g})/E({speeds[0]:g}) = {result.ratio_last_first:.3f} "
                  f"(paper {paper_E[-1] / paper_E[0]:.3f})"
                  + ("" if duration == TABLE_I.duration_s
                     else f"  [paper values are for {TABLE_I.duration_s:g} s]"))

    summary = result.to_json_dict()
    summary.update(acid_version=__version__, **choice.to_json_dict(),
                   config_path=str(config) if config is not None else None,
                   config_sha256=file_sha256(config) if config is not None else None)
    figure_path = save_figure(sweep_figure(result), out / "speed_sweep.png")
    summary["figure"] = str(figure_path)
    write_json(out / "speed_sweep.json", summary)
    say(f"figure written to {figure_path}")
    write_summary(json_path, summary)
