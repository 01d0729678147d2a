"""``acid validate``: multi-start open-loop validation of the model (paper Figs. 5-6)."""

from __future__ import annotations

import math
import time
import warnings
from pathlib import Path

import numpy as np
import typer

from acid import __version__
from acid._io import file_sha256, save_figure
from acid.data import MODEL_CHANNELS, Dataset
from acid.econ.params import load_any_params, model_family
from acid.validate import EXOGENOUS_MODES, PLACEMENTS, held_out_part, window_design_text
from acid.validate import validate as run_validation
from acid_cli._common import (
    check_paths,
    handle_errors,
    note,
    params_input,
    print_table,
    require,
    require_range,
    say,
    warn,
    write_summary,
)

FIGURES = ("fig5_prediction.png", "fig6_errors.png", "fig6b_yardsticks.png")
#: Largest --starts and --horizon accepted.
MAX_STARTS, MAX_HORIZON = 100_000, 1_000_000


def _fmt(v: float, digits: int = 3) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.{digits}f}"


@handle_errors
def validate(
    data: Path = typer.Argument(..., help="Dataset (HDF5, from `acid excite` or `acid import`)."),
    params: str = typer.Option("paper", "--params",
                               help="params.json from `acid fit`, or 'paper' for the preset."),
    starts: int = typer.Option(60, "--starts", help="Number of prediction start instants."),
    horizon: int = typer.Option(300, "--horizon",
                                help="Prediction steps per start (300 x 5 s = 1500 s)."),
    exogenous: str = typer.Option(
        "hold", "--exogenous",
        help="T_int/T_shell over a prediction: 'hold' at the start value (paper) or "
             "'measured' (a model file: all its disturbances)."),
    held_out_fraction: float | None = typer.Option(
        None, "--held-out-fraction",
        help="Validate on the last F of the record only. Default: the part after "
             "provenance.estimation_fraction of params.json when it was fitted on this "
             "file, else the whole record."),
    placement: str = typer.Option("even", "--placement",
                                  help="Start instants 'even'ly spread or 'random'."),
    non_overlapping: bool = typer.Option(
        False, "--non-overlapping",
        help="Space the starts by more than the horizon, so no sample lies in two windows "
             "(fewer starts when the record is short)."),
    yardsticks: bool = typer.Option(
        True, "--yardsticks/--no-yardsticks",
        help="Also predict the same windows with persistence, ARX and a subspace model "
             "fitted on the estimation part (yardsticks, never used for control)."),
    seed: int = typer.Option(0, "--seed", help="Seed of --placement random."),
    out: Path = typer.Option(
        Path("reports/validate"), "--out",
        help="Folder for the figures (fig5/fig6 PNG, fig6b with the yardsticks)."),
    allow_unstable: bool = typer.Option(
        False, "--allow-unstable",
        help="Validate parameters even if eqs. 1-3 are unstable or not in kelvin."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
    beside: str | None = typer.Option(
        None, "--beside",
        help="Another params.json (or 'paper') validated on the same data and starts, shown "
             "beside (e.g. the paper's model beside the econ model)."),
    model: str | None = typer.Option(
        None, "--model",
        help="A model file FILE.py or a built-in declaration (paper, econ, cabin3; "
             "acid.models): validate that declared model, with --params from `acid fit "
             "--model ...` (default: its declared values)."),
    warmup: int = typer.Option(
        60, "--warmup", help="Model file with latent states: samples before each start from "
                             "which they are estimated."),
    to_end: bool = typer.Option(
        False, "--to-end", help="Model file: also start where fewer than --horizon samples "
                                "remain (short trips); those predictions stop at the "
                                "experiment's end."),
    warm_start: str = typer.Option(
        "fit", "--warm-start",
        help="Model file with latent states: how they are estimated at each start: 'fit' "
             "(least squares over the --warmup stretch, parameters held), 'ekf' (the "
             "extended Kalman filter with the declared noises, as `acid fit --method pem` "
             "uses, over that stretch) or 'ekf-trip' (the filter from the start of the "
             "trip, as it would run in the car)."),
) -> None:
    """Predict open loop from many start instants and report the errors vs horizon.

    Errors are in K; figures like the paper's Fig. 5 (one prediction) and Fig. 6 (errors of
    all starts vs prediction time) go to --out. The model family (the paper's or econ) is
    read from the parameter file.
    """
    from acid.report.validation import error_figure, prediction_figure, yardstick_figure

    if model is not None:
        return _validate_model_file(data, model, params, json_path, starts, horizon, warmup,
                                    placement, seed, held_out_fraction, exogenous,
                                    beside is not None or allow_unstable, non_overlapping,
                                    yardsticks, to_end, warm_start)

    require(not to_end, "--to-end", "is for a declared model (--model)")
    require(warm_start == "fit", "--warm-start", "is for a declared model (--model)")
    check_paths(inputs={"DATA": data, "--params": params_input(params),
                        "--beside": params_input(beside)},
                outputs={"--json": json_path}, folders={"--out": (out, FIGURES)})
    _check_windows(starts, horizon, seed, exogenous, placement, non_overlapping,
                   held_out_fraction)
    p = load_any_params(params, allow_unstable=allow_unstable)
    families = {model_family(params)} | ({model_family(beside)} if beside else set())
    channels = MODEL_CHANNELS
    if "econ" in families:
        from acid.econ.params import REQUIRED

        channels = tuple(dict.fromkeys(MODEL_CHANNELS + REQUIRED))
    ds = Dataset.from_hdf5(data, require=channels)
    data_sha256 = file_sha256(data)
    part = held_out_part(p.provenance, str(data), data_sha256, held_out_fraction)
    if part.warning:
        warn(part.warning)

    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = run_validation(ds, p, starts=starts, horizon=horizon, exogenous=exogenous,
                                held_out_fraction=part.fraction, placement=placement,
                                seed=seed, non_overlapping=non_overlapping,
                                yardsticks=yardsticks)
    elapsed = time.perf_counter() - t0
    for w in caught:
        warn(w.message)
    fraction_source = part.source

    lo, hi = result.settings["sample_range"]
    say(f"{data}: {result.n_starts} starts x {result.horizon} steps "
                  f"({result.horizon_s[-1]:g} s), samples {lo}..{hi - 1} ({fraction_source}), "
                  f"T_int/T_shell {exogenous}, parameters {p.name!r} ({elapsed * 1e3:.0f} ms)")
    say(window_design_text(result.window_design))
    rows = []
    for name, m in result.metrics.items():
        rows.append([name, _fmt(m["rmse"]), _fmt(m["mean_abs"]), _fmt(m["median_abs"]),
                     _fmt(m["p90_abs"]), _fmt(m["p95_abs"]), _fmt(m["max_abs"]),
                     _fmt(m["fit_percent"], 1), _fmt(m["fit_percent_pooled"], 1)])
    print_table("Open-loop prediction error, all starts and steps: RMSE and |e| (K), fit (%)",
                ["channel", "RMSE", "mean", "median", "p90", "p95", "max", "fit",
                 "fit pooled"], rows)
    hrows = [[f"{r['time_s']:g}"] + [f"{_fmt(r[c]['mean_abs'], 2)} / {_fmt(r[c]['p95_abs'], 2)}"
                                     for c in result.channels]
             for r in result.at_horizon()]
    if hrows:
        print_table("Error vs prediction time: mean / p95 of |e| over starts (K)",
                    ["time (s)", *result.channels], hrows)
    if result.extra_metrics:
        print_table("Predicted beyond the paper's channels: |e| over all starts and steps",
                    ["channel", "unit", "median", "p90", "max"],
                    [[name, m["unit"], _fmt(m["median_abs"]), _fmt(m["p90_abs"]),
                      _fmt(m["max_abs"])]
                     for name, m in result.extra_metrics.items()])
    if result.yardsticks:
        yardstick_table(result)
    residuals = None
    if model_family(params) == "paper":
        residuals = residual_section(ds, p, lo, hi)
    else:
        note("residual tests (acid.analysis.resid) exist for the paper's model only")
    other = None
    if beside:
        q = load_any_params(beside, allow_unstable=allow_unstable)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the same windows: warned about above
            other = run_validation(ds, q, starts=starts, horizon=horizon, exogenous=exogenous,
                                   held_out_fraction=part.fraction, placement=placement,
                                   seed=seed, non_overlapping=non_overlapping)
        print_table(f"Beside: |e| median / p90 (K), {p.name!r} vs {q.name!r}, same starts",
                    ["channel", p.name, q.name],
                    [[c, f"{_fmt(result.metrics[c]['median_abs'])} / "
                         f"{_fmt(result.metrics[c]['p90_abs'])}",
                      f"{_fmt(other.metrics[c]['median_abs'])} / "
                      f"{_fmt(other.metrics[c]['p90_abs'])}"] for c in result.channels])

    fig5 = save_figure(prediction_figure(result), out / "fig5_prediction.png")
    fig6 = save_figure(error_figure(result), out / "fig6_errors.png")
    figures = {"fig5_prediction": str(fig5), "fig6_errors": str(fig6)}
    if result.yardsticks:
        fig6b = save_figure(yardstick_figure(result), out / "fig6b_yardsticks.png")
        figures["fig6b_yardsticks"] = str(fig6b)
    say(f"figures written to {', '.join(figures.values())}")

    summary = {
        "command": "validate",
        "acid_version": __version__,
        "inputs": {"data": str(data), "data_sha256": data_sha256,
                   "params": params,
                   "params_sha256": None if params == "paper" else file_sha256(params)},
        "held_out_fraction_source": fraction_source,
        "in_sample_warning": part.warning,
        "elapsed_s": elapsed,
        "figures": figures,
        **result.to_json_dict(),
    }
    if residuals is not None:
        summary["residuals"] = residuals
    if other is not None:
        summary["beside"] = {"params": beside, "channels": other.to_json_dict()["channels"]}
    write_summary(json_path, summary)


def _check_windows(starts, horizon, seed, exogenous, placement, non_overlapping,
                   held_out_fraction) -> None:
    """The window options both branches share (one line naming the option)."""
    require_range(starts, "--starts", 1, MAX_STARTS)
    require_range(horizon, "--horizon", 1, MAX_HORIZON, "steps")
    require_range(seed, "--seed", 0, 2**63 - 1)
    require(exogenous in EXOGENOUS_MODES, "--exogenous",
            f"must be one of {', '.join(EXOGENOUS_MODES)}, got {exogenous!r}")
    require(placement in PLACEMENTS, "--placement",
            f"must be one of {', '.join(PLACEMENTS)}, got {placement!r}")
    require(not (non_overlapping and placement != "even"), "--non-overlapping",
            f"places the starts evenly: it cannot be combined with --placement {placement}")
    if held_out_fraction is not None:
        require_range(held_out_fraction, "--held-out-fraction", 0.0, 1.0, lo_open=True)


def _validate_model_file(data, model, params, json_path, starts, horizon, warmup, placement,
                         seed, held_out_fraction, exogenous, paper_options,
                         non_overlapping=False, yardsticks=True, to_end=False,
                         warm_start="fit") -> None:
    """The declared-model branch (``--model FILE.py``, ``acid_cli._declared``)."""
    from acid.models.loader import BUILT_IN
    from acid_cli._declared import is_model_file, model_file_input, validate_declared

    require(is_model_file(model) or model in BUILT_IN, "--model",
            f"must be a model file FILE.py or a built-in declaration ({', '.join(BUILT_IN)}), "
            f"got {model!r}")
    require(not paper_options, "--model",
            "--beside and --allow-unstable are for the paper/econ families")
    check_paths(inputs={"DATA": data, "--model": model_file_input(model),
                        "--params": params_input(params)},
                outputs={"--json": json_path})
    _check_windows(starts, horizon, seed, exogenous, placement, non_overlapping,
                   held_out_fraction)
    require_range(warmup, "--warmup", 0, MAX_HORIZON, "samples")
    from acid.ident.validate import WARM_STARTS

    require(warm_start in WARM_STARTS, "--warm-start",
            f"must be one of {', '.join(WARM_STARTS)}, got {warm_start!r}")
    validate_declared(data, model, params, json_path, starts=starts, horizon=horizon,
                      warmup=warmup, placement=placement, seed=seed,
                      held_out_fraction=held_out_fraction, hold_all=exogenous == "hold",
                      non_overlapping=non_overlapping, yardsticks=yardsticks,
                      to_end=to_end, warm_start=warm_start)


#: Prediction times (s) of the yardstick table, when inside the horizon.
YARDSTICK_TIMES_S = (60.0, 300.0, 1500.0)


def yardstick_table(result) -> None:
    """The model beside persistence, ARX and subspace: RMSE / p90 |e| (K) per channel and
    prediction time, and how each yardstick was fitted."""
    horizon = float(result.horizon_s[-1])
    times = [t for t in YARDSTICK_TIMES_S if t <= horizon]
    if horizon not in times:
        times.append(horizon)
    table = result.by_horizon(times)
    keys = [f"{result.horizon_s[int(round(t / result.settings['Ts_s']))]:g}" for t in times]
    rows = []
    for c in result.channels:
        for name, by in table.items():
            label = "model" if name == "model" else f"{name} (yardstick)"
            rows.append([c, label] + [f"{_fmt(by[c][k]['rmse_K'], 2)} / "
                                      f"{_fmt(by[c][k]['p90_K'], 2)}" for k in keys])
    print_table("Model and yardsticks on the same windows: RMSE / p90 of |e| over the starts "
                "(K)", ["_channel", "_predictor", *[f"{k} s" for k in keys]], rows)
    lo, hi = result.settings["yardsticks_fitted_on"]
    for y in result.yardsticks.values():
        say(f"  {y.description}")
    fitted = f"ARX and subspace fitted on samples {lo}..{hi - 1}"
    if result.settings.get("yardsticks_in_sample"):
        note(f"{fitted}, the validated samples themselves (no held-out part): in-sample, "
             "they are favoured; yardsticks are never used for control")
    else:
        say(f"  {fitted} (the estimation part); yardsticks are never used for control")


def residual_section(ds, params, lo: int, hi: int) -> dict | None:
    """One-step residual tests (``acid.analysis.resid``) on the validated samples, with what
    they mean; returns their JSON summary (None when the part is too short)."""
    from acid.analysis import resid
    from acid.errors import DataError

    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            r = resid(ds.window(lo, hi), params)
    except DataError as exc:
        note(f"residual tests skipped: {exc}")
        return None
    rows = []
    for i, c in enumerate(r.channels):
        a = np.abs(r.autocorrelation[1:, i])
        rows.append([c, "yes" if r.white[c] else "no",
                     _fmt(float(a.max()) if np.all(np.isfinite(a)) else math.nan, 2),
                     _fmt(r.ljung_box[c]["p_value"], 3),
                     ", ".join(u for u in r.inputs if not r.independent[u][c]) or "none"])
    print_table(f"One-step residuals on the validated samples (N = {r.n}, 99 % band "
                f"+-{r.band99:.3f})", ["_channel", "white", "max |acf|", "Ljung-Box p",
                                       "_correlated with"], rows)
    for c, text in r.interpretation.items():
        say(f"  {c}: {text}")
    d = r.to_json_dict()
    return {k: d[k] for k in ("n", "band99", "white", "independent", "ljung_box",
                              "interpretation")}
