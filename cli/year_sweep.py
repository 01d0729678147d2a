"""``acid year-sweep``: the whole year: A/C, heat-pump and heater energy and the
share of range they cost, from -10 to 40 degC, over drive cycles, for the shipped vehicles."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import typer

from acid import __version__
from acid._io import save_figure, write_json, write_text
from acid.units import json_in_degC
from acid_cli._common import (
    check_paths,
    handle_errors,
    print_table,
    progress_bar,
    require_range,
    say,
    write_summary,
)
from acid_cli._plant import config_input, refrigerant_option

OUTPUTS = ("year.csv", "year.json", "year_share.png")


@handle_errors
def year_sweep(
    t_amb: list[float] | None = typer.Option(
        None, "--t-amb", help="Ambient, degC; repeat for a list (default -10, -5, ..., 40)."),
    cycle: list[str] | None = typer.Option(
        None, "--cycle", help="Drive cycle; repeat for a list (default udds and hwfet)."),
    config: list[str] | None = typer.Option(
        None, "--plant-config",
        help="Vehicle name or plant TOML; repeat for a list (default: default and paper)."),
    refrigerant: str | None = refrigerant_option(),
    switch_over: float = typer.Option(
        18.0, "--switch-over",
        help="Heating plant below this ambient, cooling plant at and above it, degC."),
    jobs: int = typer.Option(1, "--jobs", help="Worker processes (1: run in this process; "
                                              "more: a Dask LocalCluster)."),
    quick: bool = typer.Option(False, "--quick",
                               help="A coarse grid: -10, 5, 25 and 35 degC on the UDDS."),
    out: Path = typer.Option(Path("reports/year"), "--out",
                             help="Folder for the CSV, the JSON and the figure."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
) -> None:
    """Run each vehicle over each drive cycle from a soak at each ambient with its production
    controllers: the heating plant (heat pump first, coolant heater; and the heater alone)
    below --switch-over, the cooling plant at and above. Reports compressor, heater, blower
    and fan energy, the cycle's traction energy (the i3's road load) and the share of range
    the climate costs, climate / (traction + 12 V base + climate); a CSV (degC), a JSON and
    a figure in --out.
    """
    from acid.outdir import claim
    from acid.plant import year
    from acid.report.year import year_figure

    check_paths(inputs={f"--plant-config {v}": config_input(v) for v in config or ()},
                outputs={"--json": json_path}, folders={"--out": (out, OUTPUTS)})
    require_range(jobs, "--jobs", 1, 256, integer=True)
    ambients = tuple(t_amb) if t_amb else (year.QUICK_AMBIENTS_C if quick else year.AMBIENTS_C)
    cycles = tuple(cycle) if cycle else (year.QUICK_CYCLES if quick else year.CYCLES)
    vehicles = tuple(config) if config else year.VEHICLES
    year.check_grid(ambients, cycles, vehicles, switch_over, refrigerant)
    n = len(year.plan_tasks(ambients, cycles, vehicles, switch_over, refrigerant))
    with claim(out, "acid year-sweep"), progress_bar("year sweep", total=n) as update:
        result = year.year_sweep(ambients, cycles, vehicles, switch_over, refrigerant, jobs=jobs,
                                 progress=update)
        rows = result.rows()
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
        files = {"csv": write_text(out / "year.csv", buf.getvalue()),
                 "figure": save_figure(year_figure(result), out / "year_share.png")}
        summary = result.to_json_dict()
        summary.update(acid_version=__version__, jobs=jobs,
                       files={k: str(v) for k, v in files.items()})
        write_json(out / "year.json", json_in_degC(summary))

    table = []
    for p in result.points:
        table.append([f"{p.T_amb_K - 273.15:g}", p.cycle, p.vehicle, p.heating,
                      f"{p.E_ac_kWh + p.E_hp_kWh:.3f}", f"{p.E_heater_kWh:.3f}",
                      f"{p.E_blower_kWh + p.E_fan_kWh:.3f}", f"{p.E_traction_kWh:.3f}",
                      f"{100 * p.share:.1f}", f"{p.T_cab_mean_K - 273.15:.1f}"])
    print_table("climate energy over one pass of each cycle, kWh; share of range, %",
                ["degC", "_cycle", "_vehicle", "_heating", "compressor", "heater",
                 "blower+fan", "traction", "share %", "mean T_cab"], table)
    say(f"table written to {files['csv']}; figure written to {files['figure']}")
    write_summary(json_path, summary)
