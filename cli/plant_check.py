"""``acid plant-check``: the plant's credentials, each beside a published reference."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from acid import __version__
from acid._io import file_sha256, save_figure
from acid.units import json_in_degC
from acid_cli._common import (
    check_paths,
    console,
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


def format_value(v) -> str:
    if v == math.inf:
        return "not reached"
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.4g}"


def verdict_text(row) -> str:
    if row.info:
        return "info"
    return "n/a" if row.passed is None else ("PASS" if row.passed else "FAIL")


@handle_errors
def plant_check(
    plant: str = plant_option(),
    fmu_map: Path | None = fmu_map_option(),
    config: Path | None = config_option(),
    ambient: float | None = ambient_option("the configuration's, 30 degC; checks (a)-(c)"),
    refrigerant: str | None = refrigerant_option(),
    out: Path = typer.Option(Path("reports/plant-check"), "--out",
                             help="Folder for the figures and the result JSON."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
) -> None:
    """Check the plant: (a) Table I, (b) balances and the cycle recomputed with CoolProp,
    (c) step size, (d) idle service chart, (e) pull-down (the 43 degC hot pull-down as
    information), (f) steady COP map, (g) COP gain at speed. Exits 1 on any FAIL.

    Sources of every reference: datasets/plant/SOURCES.md.
    """
    from acid.errors import ConfigError
    from acid.report.plant import plant_check_figures
    from acid.studies.credentials.plant import build_plant
    from acid.studies.credentials.plant import plant_check as run_check
    from acid.units import C2K

    check_paths(inputs={"--plant-config": config_input(config), **plant_inputs(plant, fmu_map)},
                outputs={"--json": json_path},
                folders={"--out": (out, ("plant_check_energy.png", "plant_check_service.png",
                                         "plant_check.json"))})
    if ambient is not None:
        require_range(ambient, "--t-amb", -60.0, 150.0, "degC")  # kelvin typed by mistake
    choice = plant_choice(plant, fmu_map)
    if config is not None and choice.kind != "hifi":
        raise ConfigError("--plant-config applies to --plant hifi only")
    T_amb = None if ambient is None else C2K(ambient)
    extra = {"fmu_map": choice.fmu_map} if choice.kind == "fmu" else {}
    if refrigerant is not None:
        extra["refrigerant"] = plant_overrides(refrigerant=refrigerant)["refrigerant"]
    the_plant = build_plant(choice.spec, config, T_amb, **extra)
    nominal = (choice.factory(mode="nominal", T_amb=T_amb) if choice.kind == "fmu" else None)
    with progress_bar("plant check", total=13) as update:
        result = run_check(the_plant, progress=update, nominal_factory=nominal)

    rows = [[r.group, r.name, format_value(r.value), r.unit, r.reference, verdict_text(r)]
            for r in result.rows]
    identity = plant_identity(getattr(the_plant, "cfg", None),
                              choice.spec if choice.kind != "hifi"
                              else "default" if config is None else str(config))
    say(identity_line(identity))
    print_table(f"acid plant-check: {result.plant}",
                ["_", "_check", "value", "_unit", "_reference", "_verdict"], rows)
    from acid.studies.credentials.plant import SEARCH_NOTE

    say(SEARCH_NOTE)
    console.print(f"cop_steady_30C_standstill = {format_value(result.cop_steady_30C_standstill)}, "
                  f"cop_gain_25_vs_0_equal_load_pct = "
                  f"{format_value(result.cop_gain_25_vs_0_equal_load_pct)} %")
    summary = result.to_json_dict()
    summary.update(acid_version=__version__, **choice.to_json_dict(), **identity,
                   config_path=None if config_input(config) is None else str(config_input(config)),
                   config_sha256=(file_sha256(config_input(config))
                                  if config_input(config) is not None else None))
    figures = {}
    for name, fig in plant_check_figures(result).items():
        figures[name] = str(save_figure(fig, out / f"{name}.png"))
    summary["figures"] = figures
    from acid._io import write_json

    write_json(out / "plant_check.json", json_in_degC(summary))
    say(f"figures written to {out}")
    write_summary(json_path, summary)
    console.print("[bold green]PASS[/]" if result.passed else "[bold red]FAIL[/]")
    if not result.passed:
        raise typer.Exit(code=1)
