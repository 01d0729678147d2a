"""``acid heating-control``: the heating NMPC against the production controller and the best
tuned simple rule, at equal mean cabin temperature, in closed loop on the heating plant."""

from __future__ import annotations

from pathlib import Path

import typer

from acid import __version__
from acid_cli._common import (
    check_paths,
    handle_errors,
    print_table,
    require,
    require_range,
    say,
    timed_lines,
    write_summary,
)

CONTROLLERS = ("production", "rule", "rule_eq", "nmpc_held", "nmpc")


@handle_errors
def heating_control(
    cycle: str = typer.Option("all", "--cycle",
                              help="Drive cycle from datasets/drive_cycles, or 'all' (UDDS and "
                                   "HWFET)."),
    t_amb: list[float] = typer.Option([-10.0, 0.0, 7.0], "--t-amb",
                                      help="Ambient, degC (repeat for several)."),
    horizon: int = typer.Option(60, "--horizon", help="NMPC horizon, samples of 10 s."),
    warmup: float = typer.Option(1800.0, "--warmup",
                                 help="Common warm-up (production controller, cold soak), s."),
    tail: float = typer.Option(1200.0, "--tail",
                               help="Common continuation measuring the end-state cost, s."),
    pull_up: float = typer.Option(0.0, "--pull-up",
                                  help="Pull-up allowance from a cold soak (with --warmup 0), "
                                       "s: the rule's comfort test looks at the cabin after "
                                       "it."),
    out: Path = typer.Option(Path("reports/heating-control"), "--out",
                             help="Folder for the figure."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
) -> None:
    """Compare heating controllers at equal comfort on the heating plant: energy (heat pump,
    coolant heater, blower, front fan) with the end state charged back, the saving of the
    economic NMPC against the best tuned simple rule held to 2 K of fogging margin (rule) and
    against the best rule held to the margin the NMPC kept (rule_eq: equal constraints), the
    verdict over the cases from its 95 % interval, and the share owed to preview."""
    from acid.control.heating import HeatingControlConfig
    from acid.signals import available_drive_cycles
    from acid.studies.heating_control import CYCLES, heating_study

    cycles = CYCLES if cycle == "all" else (cycle,)
    for c in cycles:
        require(c in available_drive_cycles(), "--cycle",
                f"{c!r} is not a drive cycle (known: {', '.join(available_drive_cycles())})")
    for a in t_amb:
        require_range(a, "--t-amb", -20.0, 15.0, "degC")
    require_range(horizon, "--horizon", 2, 600, integer=True)
    require_range(warmup, "--warmup", 0.0, 86400.0, "s")     # at most a day of driving
    require_range(tail, "--tail", 0.0, 86400.0, "s")
    require_range(pull_up, "--pull-up", 0.0, 3600.0, "s")
    png = out / "heating_control.png"
    check_paths(outputs={"--json": json_path, "--out": png})
    from acid.outdir import claim

    with claim(out, "acid heating-control"):  # a folder it made goes again if left empty
        result = heating_study(cycles, tuple(t_amb),
                               HeatingControlConfig(N=horizon, pull_up_s=pull_up),
                               png_path=png, progress=timed_lines("heating-control"),
                               tail_s=tail, warmup_s=warmup)
    rows = []
    for case in result["cases"]:
        for name in CONTROLLERS:
            r = case["controllers"].get(name)
            if r is None:
                say(f"{case['cycle']} {case['T_amb_C']:+.0f} degC: no rule of the grid keeps "
                    "the NMPC's constraints")
                continue
            rows.append([case["cycle"], f"{case['T_amb_C']:+.0f}", name,
                         f"{r['energy_charged_kWh']:.3f}", f"{r['saving_vs_rule_pct']:+.1f}",
                         "n/a" if r["saving_vs_rule_eq_pct"] is None
                         else f"{r['saving_vs_rule_eq_pct']:+.1f}",
                         f"{r['mean_T_cab_C']:.2f}", f"{100 * r['mean_RH']:.0f}",
                         f"{r['min_fog_margin_K']:.2f}", str(r["fog_samples"]),
                         f"{r['E_hp_kWh']:.3f}", f"{r['E_heater_kWh']:.3f}",
                         f"{r['defrost_s']:.0f}"])
        say(f"{case['cycle']} {case['T_amb_C']:+.0f} degC: speed preview changed the NMPC's "
            f"saving by {case['preview_points']:+.1f} points")
    print_table("acid heating-control (end state charged back)",
                ["_cycle", "T_amb", "_controller", "kWh", "vs rule %", "vs rule_eq %", "T_cab",
                 "RH %",
                 "fog margin K", "fogged", "HP kWh", "heater kWh", "defrost s"], rows)
    from acid.studies.verdict import Verdict

    v = Verdict.from_dict(result["verdict_nmpc_vs_rule_eq"])
    say(f"NMPC against the rule at equal constraints, over the cases: {v.summary()}")
    result["acid_version"] = __version__
    write_summary(json_path, result)
    say(f"figure written to {png}")
