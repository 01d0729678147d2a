"""``acid speed-sweep``: the paper's speed-sensitivity study (Fig. 3, Table I) on the plant."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from acid import __version__
from acid._io import file_sha256, save_figure, write_json
from acid.errors import ConfigError
from acid.units import json_in_degC
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
from acid_cli._plant import (
    ambient_option,
    config_input,
    config_option,
    fmu_map_option,
    identity_line,
    plant_choice,
    plant_identity,
    plant_option,
    plant_overrides,
    refrigerant_option,
)

#: Longest simulated time per speed accepted, s (one day).
MAX_DURATION_S = 86400.0


def _fmt(v, digits: int = 3) -> str:
    return "NA" if v is None or not math.isfinite(v) else f"{v:.{digits}f}"


@handle_errors
def speed_sweep(
    config: Path | None = config_option(),
    t_amb: float | None = ambient_option("the configuration's, 30 degC as in Table I's "
                                         "test"),
    refrigerant: str | None = refrigerant_option(),
    duration: float = typer.Option(600.0, "--duration", help="Simulated time per speed, s."),
    out: Path = typer.Option(Path("reports/speed-sweep"), "--out",
                             help="Folder for the figure and the result JSON."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
    plant: str = plant_option("hifi", ("hifi",)),
    fmu_map: Path | None = fmu_map_option(),
) -> None:
    """Run the nominal controller at 0-25 m/s for --duration s and judge the paper's Table I.

    The high-fidelity plant runs the paper vehicle (--plant-config paper, the default: the
    Table I calibration) with acid's default vehicle beside it; another --plant-config runs
    that vehicle with the default beside it. Energy is compressor + blower (as in the
    paper), in MJ and MJ/km; verdicts by the claims registry's rules (600 s runs only).
    """
    from acid.claims import TABLE_I, judge_value
    from acid.plant.sweep import speed_sweep as run_sweep
    from acid.plant.vehicles import (
        DEFAULT_VEHICLE,
        PAPER_VEHICLE,
        is_vehicle,
        resolve_config,
        vehicle_config,
        vehicle_label,
    )
    from acid.report.plant import sweep_figure

    check_paths(inputs={"--plant-config": config_input(config), **plant_inputs(plant, fmu_map)},
                outputs={"--json": json_path},
                folders={"--out": (out, ("speed_sweep.png", "speed_sweep.json"))})
    require_range(duration, "--duration", 0.0, MAX_DURATION_S, "s", lo_open=True)
    choice = plant_choice(plant, fmu_map, allowed=("hifi",))
    if config is not None and choice.kind != "hifi":
        raise ConfigError("--plant-config applies to --plant hifi only (an FMU plant is "
                          "configured through --fmu-map)")
    changes = plant_overrides(t_amb, refrigerant)
    if changes and choice.kind != "hifi":
        raise ConfigError("--t-amb and --refrigerant apply to --plant hifi only (an FMU plant "
                          "is configured through --fmu-map)")
    factory = None
    if choice.kind == "fmu":
        choice.check(mode="nominal")
        factory = choice.factory(mode="nominal")
    spec = (config if config is not None else PAPER_VEHICLE) if factory is None else None
    cfg = vehicle_config(spec).replace(**changes)
    label = vehicle_label(spec) if factory is None else choice.spec
    # acid's default vehicle beside any other configuration of acid's plant
    beside = factory is None and resolve_config(spec) is not None
    speeds = TABLE_I.speeds_mps
    with progress_bar("speed sweep", total=len(speeds) * (2 if beside else 1)) as update:
        result = run_sweep(cfg, speeds=speeds, duration=duration, progress=update,
                           plant_factory=factory)
        other = (run_sweep(vehicle_config(None).replace(**changes), speeds=speeds,
                           duration=duration, progress=lambda i, n: update(len(speeds) + i, 2 * n))
                 if beside else None)

    full = abs(result.duration_s - TABLE_I.duration_s) < 1e-9
    paper_E = TABLE_I.energy_MJ
    paper_km = [math.nan if e is None else e for e in TABLE_I.energy_MJ_per_km]

    def verdict(claim_id: str, value: float) -> str:
        return judge_value(claim_id, value)[0].value if full else "n/a"

    rows = []
    for i, (v, e, ek, pe, pk) in enumerate(zip(result.speeds_mps, result.energy_MJ,
                                               result.energy_MJ_per_km, paper_E, paper_km,
                                               strict=True)):
        row = [f"{v:g}", _fmt(e), _fmt(pe, 2), verdict(f"table1.energy.{v:g}mps", e)]
        if other is not None:
            row.append(_fmt(other.energy_MJ[i]))
        rows.append(row + [_fmt(ek), _fmt(pk)])
    name = f"{label} vehicle" if is_vehicle(label) else label
    identity = plant_identity(cfg if factory is None else None, label)
    say(identity_line(identity))
    head = ["m/s", name, "Table I", "verdict"]
    if other is not None:
        head.append(f"{DEFAULT_VEHICLE} vehicle")
    print_table(f"A/C energy over {result.duration_s:g} s, MJ (compressor + blower); "
                f"MJ/km of the {name}", head + ["MJ/km", "Table I MJ/km"], rows)
    ratio = result.ratio_last_first
    say(f"E({speeds[-1]:g})/E({speeds[0]:g}) = {ratio:.3f} on the {name}"
        + (f" ({verdict('table1.ratio', ratio)})" if full else "")
        + (f", {other.ratio_last_first:.3f} on the {DEFAULT_VEHICLE} vehicle"
           if other is not None else "")
        + f"; Table I {paper_E[-1] / paper_E[0]:.3f}"
        + ("" if full else f"  [paper values are for {TABLE_I.duration_s:g} s: no verdicts]"))

    summary = result.to_json_dict()
    summary.update(acid_version=__version__, **choice.to_json_dict(), **identity,
                   config_path=None if config_input(spec) is None else str(config_input(spec)),
                   config_sha256=(file_sha256(config_input(spec))
                                  if config_input(spec) is not None else None))
    if full:
        summary["verdicts"] = {f"{v:g}": verdict(f"table1.energy.{v:g}mps", e)
                               for v, e in zip(result.speeds_mps, result.energy_MJ, strict=True)}
        summary["verdicts"]["ratio"] = verdict("table1.ratio", ratio)
    if other is not None:
        d = other.to_json_dict()
        summary["beside"] = {"vehicle": DEFAULT_VEHICLE,
                             **{k: d[k] for k in ("energy_MJ", "energy_MJ_per_km",
                                                  "energy_with_fan_MJ", "ratio_last_first",
                                                  "ratio_last_first_with_fan", "plant_config")}}
    figure_path = save_figure(sweep_figure(result, other, (name, f"{DEFAULT_VEHICLE} vehicle")),
                              out / "speed_sweep.png")
    summary["figure"] = str(figure_path)
    write_json(out / "speed_sweep.json", json_in_degC(summary))
    say(f"figure written to {figure_path}")
    write_summary(json_path, summary)
