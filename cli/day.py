"""``acid day``: a connected car's day, parked pre-conditioning on grid power before a known
departure, against no pre-conditioning and a production-style timer."""

from __future__ import annotations

from pathlib import Path

import typer

from acid import __version__
from acid._io import save_figure, write_json
from acid.units import json_in_degC
from acid_cli._common import (
    check_paths,
    handle_errors,
    print_table,
    progress_bar,
    require,
    require_range,
    say,
    write_summary,
)

OUTPUTS = ("day.json", "day.png")


@handle_errors
def day(
    season: list[str] | None = typer.Option(
        None, "--season", help="summer (Phoenix, July, cooling plant) or winter (Minneapolis, "
                               "January, heating plant); repeat for both (default both)."),
    days: int = typer.Option(10, "--days", help="Held-out days per season (the timer is "
                                                "tuned on half as many other days)."),
    planner: str = typer.Option(
        "both", "--planner",
        help="Which planner to judge besides the timer: 'model' (the power plan on the "
             "declared parked cabin identified on the training days), 'plant-search' (the "
             "start searched on the plant itself, the slow one) or 'both'."),
    no_planner: bool = typer.Option(False, "--no-planner",
                                    help="Judge the timer only (the planners are the slow "
                                         "part)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the days (weather, departures, plug, "
                                               "forecast errors)."),
    jobs: int = typer.Option(1, "--jobs", help="Worker processes (1: run in this process; "
                                              "more: a Dask LocalCluster)."),
    quick: bool = typer.Option(False, "--quick",
                               help="3 training and 4 held-out days, timer leads every 10 min."),
    out: Path = typer.Option(Path("reports/day"), "--out",
                             help="Folder for the JSON and the figure of a day."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
    soc_start: float = typer.Option(
        90.0, "--soc-start", help="Battery state of charge when each day starts, percent of "
                                  "the usable energy (no charging between the trips: a low "
                                  "start makes a range-limited day, the energy lacked shown)."),
) -> None:
    """Run a car's day (04:00 to the evening trip: parked and plugged at home, a morning trip,
    parked at work, an evening trip) on acid's plants, with the sun and ambient of the hour
    while parked. Compares no pre-conditioning, a timer (start a tuned lead before the
    forecast departure, on grid power) and two planners: a power plan over the parked window
    on a declared cabin model identified on the training days (an optimal-control problem:
    price, charger limit, battery energy, comfort at departure) and the cheapest start
    searched on the plant itself; on held-out days with departure forecast errors of 0, 5
    and 15 minutes: battery energy, cost, comfort and total grid energy as paired differences
    with 95 % intervals.
    """
    from acid.outdir import claim
    from acid.report.day import day_figure
    from acid.studies import day as study

    seasons = tuple(season) if season else study.SEASONS
    for s in seasons:
        require(s in study.SEASONS, "--season", f"{s!r}: choose summer or winter")
    require(planner in ("model", "plant-search", "both"), "--planner",
            f"{planner!r}: choose model, plant-search or both")
    require_range(days, "--days", 1, 1000, integer=True)
    require_range(jobs, "--jobs", 1, 256, integer=True)
    require_range(seed, "--seed", 0, 2**63 - 1, integer=True)
    require_range(soc_start, "--soc-start", 1.0, 100.0, "%")
    check_paths(outputs={"--json": json_path}, folders={"--out": (out, OUTPUTS)})
    n_test = 4 if quick else days
    n_train = 3 if quick else max(2, days // 2)
    leads = study.QUICK_LEADS_MIN if quick else study.LEADS_MIN
    planners = () if no_planner else {"model": ("planner",), "plant-search": (
        "plant-search",), "both": study.PLANNERS}[planner]
    n_ctrl = 1 + len(study.FORECAST_ERRORS_MIN) * (1 + len(planners))
    total = len(seasons) * (n_train * len(leads) + n_test * n_ctrl)
    with claim(out, "acid day"), progress_bar("day study", total=total) as update:
        result = study.day_study(seasons, n_train=n_train, n_test=n_test, seed=seed,
                                 leads_min=leads, planners=planners, jobs=jobs,
                                 progress=update, soc_start=soc_start / 100.0)
        traces, labels = {}, {}
        for s in seasons:
            # the figure's day: the first held-out day plugged before both trips
            pool = study.make_days(s, 20, seed, 0.0, first_index=1000,
                                   soc_start=soc_start / 100.0)
            d = next((x for x in pool if all(t.plugged for t in x.trips)), pool[0])
            ctrls = [study.NoPreconditioning(), study.Timer(result.tuned_lead_min[s])]
            if "planner" in planners:
                ctrls.append(study.ModelPlanner(result.fits[s],
                                                margin_K=result.margin_K[s]))
            if "plant-search" in planners:
                ctrls.append(study.Planner())
            traces[s] = {c.name: study.day_trace(d, c) for c in ctrls}
            labels[s] = f"{study.load_climate(s).city}: held-out {d.label}"
        tariff = study.load_tariff()
        fig_path = save_figure(day_figure(traces, study.BAND_C, tariff.hourly, labels),
                               out / "day.png")
        summary = result.to_dict()
        summary.update(acid_version=__version__, jobs=jobs, quick=quick,
                       tariff={"name": tariff.name, "hourly_USD_per_kWh": list(tariff.hourly)},
                       files={"figure": str(fig_path)})
        write_json(out / "day.json", json_in_degC(summary))

    for s in seasons:
        say(f"{s}: timer lead tuned on {n_train} training days: "
            f"{result.tuned_lead_min[s]:g} min")
        if s in result.fits:
            f = result.fits[s]
            say(f"{s}: parked cabin identified on {f.n_records} parked phases of the training "
                f"days ({f.n_samples} min): simulation error RMS {f.rms_K:.2f} K; planner's "
                f"comfort margin tuned: {result.margin_K[s]:g} K")
        rows = []
        for name in study.CONTROLLERS:
            for e in (result.forecast_errors_min if name != "none" else (0.0,)):
                if name in study.PLANNERS and name not in planners:
                    continue
                m = lambda k, n=name, e=e, s=s: result.mean_of(s, n, e, k)  # noqa: E731
                rows.append([name, f"{e:g}" if name != "none" else "-",
                             f"{m('E_battery_kWh'):.2f}", f"{m('E_climate_battery_kWh'):.2f}",
                             f"{m('E_pre_grid_kWh'):.2f}", f"{m('E_grid_kWh'):.2f}",
                             f"{m('cost_USD'):.2f}", f"{m('range_lost_km'):.1f}",
                             f"{m('Kmin_window'):.2f}", f"{m('Kmin_plugged'):.2f}",
                             f"{m('time_to_comfort_s') / 60:.1f}",
                             f"{m('fog_margin_min_K'):.1f}" if s == "winter" else "-",
                             f"{m('charger_limited_kWh'):.2f}", f"{m('short_kWh'):.2f}"])
        print_table(f"{s}: means over {n_test} held-out days (two trips a day)",
                    ["_controller", "forecast error, min", "battery kWh", "climate kWh",
                     "pre-cond. grid kWh", "total grid kWh", "cost USD", "range lost km",
                     "K.min first 10 min", "of it from a plug", "time to comfort min",
                     "lowest fog margin K", "above the charger kWh",
                     "short of range kWh"], rows)
        comp = []
        for c in result.comparisons:
            if c["season"] != s:
                continue
            comp.append([f"{c['controller']} - {c['baseline']}", f"{c['forecast_sd_min']:g}",
                         c["quantity"], f"{c['mean']:+.3f}",
                         f"[{c['low']:+.3f}, {c['high']:+.3f}]", c["verdict"]])
        print_table(f"{s}: paired differences per held-out day, 95 % t interval "
                    f"(\"not resolved\" below {study.MIN_DAYS_RESOLVED} days)",
                    ["_pair", "forecast error, min", "_quantity", "mean", "interval",
                     "_verdict"], comp)
    say(f"figure written to {fig_path}; JSON to {out / 'day.json'}")
    write_summary(json_path, summary)
