"""``acid car fit|validate|control``: the car study on a folder of a car's logs.

``fit`` fits the A/C power rows of ``car_ac`` on estimation trips (the cabin rows from a
``car_cabin`` parameter file) and scores them on held-out trips; ``validate`` holds out each
trip in turn (leave-trips-out) beside an unconstrained regressor's bound; ``control`` runs
the car's economic NMPC on one trip's replay against the car's own set-point replayed.
"""

from __future__ import annotations

from pathlib import Path

import typer

from acid import __version__
from acid_cli._common import (
    check_paths,
    handle_errors,
    print_table,
    progress_bar,
    require,
    say,
    write_summary,
)

#: the import map used when --map is not given (the BMW i3 summer trips' channels)
DEFAULT_MAP = "example:bmw_i3_map.toml"
#: per season of ``acid car select``: the map, the fit method, the warm start, the warm-up (s)
SEASONS = {"summer": ("example:bmw_i3_map.toml", "pem", "ekf-trip", 300.0),
           "winter": ("example:bmw_i3_winter_map.toml", "oe", "fit", 0.0)}

LOGS = typer.Argument(..., metavar="LOGS", help="Folder of the car's trip logs (*.csv.gz or "
                      "*.csv, one trip per file), read through --map.")
MAP = typer.Option(None, "--map", "-m", help="Import map of the logs' channels (T_cab, T_evap, "
                   f"T_amb, v_veh, P_comp; default {DEFAULT_MAP}).")
JSON = typer.Option(None, "--json", help="Write a JSON summary here.")


def _folder(logs: Path) -> None:
    from acid.errors import DataError

    if not logs.exists():
        raise DataError(f"LOGS {logs}: folder not found")
    if not logs.is_dir():
        raise DataError(f"LOGS {logs}: not a folder of trip logs")


def _trips(logs: Path, map_path, names=None):
    from acid.data import ChannelMap
    from acid.examples import resolve
    from acid.studies.car.run import load_trips

    cmap = ChannelMap.from_file(map_path if map_path is not None else resolve(DEFAULT_MAP))
    return load_trips(logs, cmap, names)


def _names(spec: str | None) -> list[str]:
    return [s.strip() for s in spec.split(",") if s.strip()] if spec else []


def _read(params: Path | None):
    from acid.models.values import ParameterValues

    return None if params is None else ParameterValues.from_json(params).replace(
        source=str(params))


def _f(x, d=2) -> str:
    return "n/a" if x is None or x != x else f"{x:.{d}f}"


@handle_errors
def car_fit(
    logs: Path = LOGS,
    map_path: Path | None = MAP,
    params: Path | None = typer.Option(
        None, "--params", help="car_cabin parameter file (acid fit --model car_cabin --method "
        "pem) for the cabin rows; default: car_cabin's declared values."),
    held_out: str | None = typer.Option(
        None, "--held-out", help="Comma-separated trip names held out (default: every "
        "second trip, the 2nd, 4th...)."),
    out: Path = typer.Option(Path("car_ac.json"), "--out", help="car_ac parameter file to "
                             "write."),
    json_path: Path | None = JSON,
) -> None:
    """Fit car_ac's A/C power on estimation trips, score it on the held-out trips, write
    the car_ac parameter file (`acid validate --model car_ac --params` reads it)."""
    from acid.studies.car.run import cabin_values, fit_car

    _folder(logs)
    check_paths(inputs={"--map": map_path, "--params": params}, read_folders={"LOGS": logs},
                outputs={"--out": out, "--json": json_path})
    cab = cabin_values(_read(params))
    trips = _trips(logs, map_path)
    names = [t.experiment_names()[0] for t in trips]
    want = _names(held_out)
    missing = [n for n in want if n not in names]
    require(not missing, "--held-out", f"trip(s) {', '.join(missing)} not in {logs}")
    held = [names.index(n) for n in want] if want else list(range(1, len(trips), 2))
    with progress_bar("car fit", 1) as update:
        result = fit_car(trips, cab, held)
        update(1, 1, "power fitted")
    result.values.to_json(out)
    print_table("car_ac power rows", ["_row", "value"],
                [[k, f"{v:.4g}"] for k, v in result.fit.values.items()])
    rows = [[what, s.n, _f(s.r2), f"{s.rmse_W:.0f}", _f(s.energy_ratio)]
            for what, s in (("estimation trips", result.fit.estimation),
                            ("held-out trips", result.fit.held_out))]
    print_table(f"P_comp on {len(result.estimation)} estimation and {len(result.held_out)} "
                "held-out trips", ["_trips", "samples", "R^2 (5 s)", "RMSE W",
                                   "energy model/logged"], rows)
    say(f"car_ac parameters written to {out}")
    write_summary(json_path, {**result.summary(), "params": str(out),
                              "acid_version": __version__})


@handle_errors
def car_validate(
    logs: Path = LOGS,
    map_path: Path | None = MAP,
    params: Path | None = typer.Option(
        None, "--params", help="car_cabin or car_ac parameter file for the cabin rows "
        "(the power rows are refitted in each fold); default: declared values."),
    folds: int | None = typer.Option(None, "--folds", help="Folds of trips (default: one "
                                     "per trip, each trip held out alone)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the trip resampling (intervals)."),
    json_path: Path | None = JSON,
) -> None:
    """Leave-trips-out: car_ac's power rows refitted without each fold's trips and scored on
    them (R^2 per 5 s, energy model/logged, per trip and pooled with 90 % intervals), beside
    an unconstrained quadratic regressor on the same logged channels (the logs' bound)."""
    from acid.studies.car.power import leave_trips_out, regressor_bound
    from acid.studies.car.run import cabin_values

    _folder(logs)
    check_paths(inputs={"--map": map_path, "--params": params}, read_folders={"LOGS": logs},
                outputs={"--json": json_path})
    require(seed >= 0, "--seed", "must be >= 0")
    trips = _trips(logs, map_path)
    cab = cabin_values(_read(params))
    k = folds or len(trips)
    with progress_bar("car validate", k) as update:
        model = leave_trips_out(trips, cab, k, seed=seed, progress=update)
    bound = regressor_bound(trips, k, seed=seed)
    rows = [[a.trip, a.n, f"{a.mean_logged_W:.0f}", f"{a.mean_model_W:.0f}", _f(a.r2),
             _f(a.energy_ratio), _f(b.r2)] for a, b in zip(model.trips, bound.trips,
                                                           strict=True)]
    print_table(f"P_comp on held-out trips ({k} folds)",
                ["_trip", "samples", "logged W", "model W", "R^2 (5 s)", "energy ratio",
                 "bound R^2"], rows)
    print_table("pooled over the held-out trips (90 % intervals over trips resampled)",
                ["_predictor", "R^2 (5 s)", "energy model/logged", "RMSE W"],
                [[h.predictor, f"{h.r2:.2f} [{h.r2_ci[0]:.2f}, {h.r2_ci[1]:.2f}]",
                  f"{h.energy_ratio:.2f} [{h.energy_ratio_ci[0]:.2f}, "
                  f"{h.energy_ratio_ci[1]:.2f}]", f"{h.rmse_W:.0f}"] for h in (model, bound)])
    write_summary(json_path, {"model": model.summary(), "bound": bound.summary(),
                              "acid_version": __version__})


@handle_errors
def car_control(
    logs: Path = LOGS,
    trip: str = typer.Option(..., "--trip", help="The trip replayed (its file name without "
                             "suffixes, e.g. TripA12)."),
    map_path: Path | None = MAP,
    params: Path | None = typer.Option(
        None, "--params", help="car_ac parameter file (acid car fit); default: declared "
        "values."),
    horizon: int = typer.Option(120, "--horizon", help="NMPC horizon, samples (5 s each)."),
    json_path: Path | None = JSON,
) -> None:
    """The car's economic NMPC on one trip's replay (its ambient and speed), the identified
    car_ac model as the plant, beside the car's logged set-point replayed on it."""
    from acid.control.car_ac import CarACConfig
    from acid.models.values import ParameterValues
    from acid.studies.car.run import control_trip

    _folder(logs)
    check_paths(inputs={"--map": map_path, "--params": params}, read_folders={"LOGS": logs},
                outputs={"--json": json_path})
    require(horizon >= 2, "--horizon", "must be >= 2 samples")
    values = _read(params)
    if values is not None and values.declaration.name != "car_ac":
        from acid.errors import DataError
        raise DataError(f"--params {params}: a parameter file of model "
                        f"{values.declaration.name!r}; control needs one of 'car_ac' "
                        "(acid car fit writes it)")
    if values is None:
        from acid.models import load
        values = ParameterValues(model=load("car_ac"), source="declared values")
    (ds,) = _trips(logs, map_path, [trip])
    with progress_bar(f"car control {trip}", len(ds)) as update:
        s = control_trip(ds, values, CarACConfig(N=horizon), progress=update)
    rows = [[r["controller"], f"{r['energy_kJ']:.0f}", f"{r['mean_T_cab_C']:.2f}",
             f"{r['violation_Ks']:.0f}", r["fallbacks"]]
            for r in (s["nmpc"], s["logged_replayed"])]
    rows.append(["logged car (as driven)", f"{s['logged']['energy_kJ']:.0f}",
                 f"{s['logged']['mean_T_cab_C']:.2f}", "", ""])
    print_table(f"{trip}: {s['samples']} samples, band {s['band_C'][0]:.0f}-"
                f"{s['band_C'][1]:.0f} degC", ["_controller", "A/C energy kJ",
                                               "mean cabin degC", "outside band K s",
                                               "fallbacks"], rows)
    write_summary(json_path, {**s, "params": values.label, "acid_version": __version__})


@handle_errors
def car_select(
    logs: Path = LOGS,
    season: str = typer.Option("summer", "--season", help="'summer' (cabin under A/C: the "
                               "car_cabin candidates) or 'winter' (heater: the heating "
                               "candidates); sets the default map, method and warm start."),
    map_path: Path | None = typer.Option(
        None, "--map", "-m", help="Import map of the logs' channels (default: the i3 map of "
        "the season)."),
    candidates: str | None = typer.Option(
        None, "--candidates", help="Comma-separated candidate structures (built-in names or "
        ".py declarations; default: summer car_cabin,car_cabin2,car_cabin1, winter "
        "heating,car_heat3n,car_heat3,car_heat2; a structure declaring its noises, "
        "car_heat3n, is fitted by PEM and warm-started by ekf-trip)."),
    trips: str | None = typer.Option(None, "--trips", help="Comma-separated trip names "
                                     "used (default: every trip in LOGS)."),
    folds: int = typer.Option(2, "--folds", help="Folds of trips (the trips taken in turn); "
                              "the same folds for every candidate and yardstick."),
    method: str | None = typer.Option(None, "--method", help="Fit method of each fold "
                                      "(default: summer pem, winter oe)."),
    max_evals: int = typer.Option(100, "--max-evals", help="Cap on each fold's fit "
                                  "(optimiser evaluations)."),
    oe_window: int = typer.Option(240, "--oe-window", help="Output error: samples per "
                                  "window (as acid fit)."),
    prior_weight: float = typer.Option(
        1.0, "--prior-weight", help="W >= 0: every declared prior's information (1/SD^2) "
        "times W in each fit (0: no priors, 1: as declared; as acid fit)."),
    rule_time: float = typer.Option(600.0, "--rule-time", help="Prediction time of the "
                                    "rule, s: the fewest free parameters whose pooled RMSE "
                                    "there lies inside the best candidate's 95 % interval."),
    starts: int = typer.Option(60, "--starts", help="Prediction starts per fold."),
    horizon: int = typer.Option(300, "--horizon", help="Prediction horizon, samples."),
    warm_start: str | None = typer.Option(None, "--warm-start", help="How latent states are "
                                          "estimated at each start (as acid validate; "
                                          "default: summer ekf-trip, winter fit)."),
    warmup: float | None = typer.Option(None, "--warmup", help="Stretch before each start "
                                        "for the warm start, s (default: summer 300, "
                                        "winter 0)."),
    resamples: int = typer.Option(1000, "--resamples", help="Bootstrap resamples of the "
                                  "intervals."),
    seed: int = typer.Option(0, "--seed", help="Seed of the resampling."),
    error_model: str | None = typer.Option(
        None, "--error-model", help="'arx': also score the chosen structure plus an ARX "
        "model of its residual (fitted on each fold's training trips) on the same folds, "
        "against the structure alone and the yardsticks."),
    out: Path | None = typer.Option(None, "--out", help="Refit the chosen structure on every "
                                    "trip and write its parameter file here."),
    json_path: Path | None = JSON,
) -> None:
    """Candidate structures fitted by leave-trips-out cross-validation on the same folds,
    scored against persistence, ARX and subspace fitted on the same training trips; the
    structure chosen by a stated rule (and, with --out, refitted on every trip)."""
    import math

    from acid.data import Dataset
    from acid.ident.fit import METHODS, fit_model
    from acid.ident.validate import REPORT_TIMES_S, WARM_STARTS
    from acid.studies.car.select import CANDIDATES, select_structure
    from acid_cli._common import require_range

    require(season in SEASONS, "--season", f"must be one of {', '.join(SEASONS)}, got "
            f"{season!r}")
    dmap, dmethod, dwarm, dwarmup = SEASONS[season]
    method = method or dmethod
    warm_start = warm_start or dwarm
    warmup = dwarmup if warmup is None else warmup
    require(method in METHODS, "--method", f"must be one of {', '.join(METHODS)}, got "
            f"{method!r}")
    require(warm_start in WARM_STARTS, "--warm-start",
            f"must be one of {', '.join(WARM_STARTS)}, got {warm_start!r}")
    require_range(folds, "--folds", 2, 10_000)
    require_range(max_evals, "--max-evals", 1, 100_000)
    require_range(oe_window, "--oe-window", 5, 100_000, "samples")
    require_range(prior_weight, "--prior-weight", 0.0, 1e6)
    require_range(starts, "--starts", 1, 100_000)
    require_range(horizon, "--horizon", 1, 1_000_000, "samples")
    require_range(resamples, "--resamples", 10, 1_000_000)
    require_range(warmup, "--warmup", 0.0, 7 * 86400.0, "s")
    require(rule_time > 0 and math.isfinite(rule_time), "--rule-time", "must be > 0 s")
    require(seed >= 0, "--seed", "must be >= 0")
    require(error_model in (None, "arx"), "--error-model", f"must be 'arx', got "
            f"{error_model!r}")
    names = _names(candidates) or list(CANDIDATES[season])
    require(len(names) >= 2, "--candidates", "needs at least 2 structures")
    from acid.models.loader import BUILT_IN

    for name in names:   # a built-in name or a .py file (whose own errors name the file)
        require(name in BUILT_IN or name.endswith(".py"), "--candidates",
                f"{name!r} is neither a built-in structure ({', '.join(BUILT_IN)}) nor a "
                ".py file declaring one")
    _folder(logs)
    check_paths(inputs={"--map": map_path}, outputs={"--out": out, "--json": json_path},
                read_folders={"LOGS": logs})
    from acid.data import ChannelMap
    from acid.examples import resolve
    from acid.studies.car.run import load_trips

    cmap = ChannelMap.from_file(map_path if map_path is not None else resolve(dmap))
    parts = load_trips(logs, cmap, _names(trips) or None)
    require(len(parts) > folds, "--folds", f"must be below the number of trips "
            f"({len(parts)})")
    ds = Dataset.concatenate(parts)
    ds.source = str(logs)
    ds.metadata["experiments"] = [{"name": t.experiment_names()[0]} for t in parts]
    opts = {"method": method, "max_nfev": max_evals,
            **({"prior_weight": prior_weight} if prior_weight != 1.0 else {}),
            **({"oe_window": oe_window} if method in ("oe", "auto") else {})}
    Ts = ds.Ts
    with progress_bar(f"car select ({season})", 2 * folds * len(names)) as update:
        sel = select_structure(ds, names, fit_options=opts, folds=folds,
                               rule_time_s=rule_time, starts=starts, horizon=horizon,
                               warmup=math.ceil(warmup / Ts - 1e-9) * Ts, exogenous="measured",
                               to_end=True, warm_start=warm_start, n_resamples=resamples,
                               seed=seed, progress=update)
    times = tuple(t for t in sel.times_s() if t in REPORT_TIMES_S)
    print_table(f"T_cab held out ({len(sel.folds)} folds over {len(parts)} trips): pooled "
                "RMSE [95 %] / p90, K (* not resolved)",
                ["_structure", "free", *(f"{t:g} s" for t in times)], sel.rows(times))
    say(sel.summary().split("\n", 2 + len(sel.candidates) + len(sel.yardsticks))[-1])
    doc = {"command": "car select", "season": season, "acid_version": __version__,
           "selection": sel.to_dict()}
    from acid.models import load as load_model
    from acid.studies.car.select import candidate_options

    ref = next(n for n in names if load_model(n).name == sel.chosen)
    copts, cwarm = candidate_options(load_model(ref), opts, warm_start)   # PEM if noises
    if error_model is not None:
        from acid.studies.car.errcv import error_model_cv

        chosen = next(c for c in sel.candidates if c.name == sel.chosen)
        with progress_bar(f"car select: {sel.chosen} + residual ARX", folds) as update:
            emcv = error_model_cv(ref, ds, [f["values"] for f in chosen.cv.folds],
                                  folds=folds, starts=starts, horizon=horizon,
                                  warmup=math.ceil(warmup / Ts - 1e-9) * Ts, warm_start=cwarm,
                                  channel="T_cab", n_resamples=resamples, seed=seed,
                                  progress=update)
        say(emcv.summary())
        doc["error_model"] = emcv.to_dict()
    if out is not None:
        from acid.models import load

        write_summary(json_path, doc)      # the selection, before the (long) refit

        with progress_bar(f"car select: {sel.chosen} on every trip", None) as update:
            res = fit_model(ref, ds, **copts, progress=update)
        res.write(out, load(ref),
                  {"command": "acid car select", "season": season, "trips": len(parts),
                   "data_source": str(logs), "method": copts["method"],
                   "max_evals": max_evals, "prior_weight": prior_weight,
                   "rule": sel.rule, "chosen": sel.chosen})
        say(f"{sel.chosen} fitted on {len(parts)} trips written to {out}; on a bound: "
            f"{', '.join(res.on_bounds) or 'none'}")
        doc["params"] = str(out)
        doc["fit_on_every_trip"] = {"on_bounds": list(res.on_bounds),
                                    "values": dict(zip(load(ref).parameter_names,
                                                       map(float, res.values), strict=True))}
    write_summary(json_path, doc)

