"""``acid validate``: multi-start open-loop validation of the model (paper Figs. 5-6)."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from acid.ident.validate import EXOGENOUS_MODES, PLACEMENTS
from acid.models.econ_params import load_any_params
from acid_cli._common import (
    check_paths,
    handle_errors,
    note,
    params_input,
    require,
    require_range,
)

FIGURES = ("fig5_prediction.png", "fig6_errors.png", "fig6b_yardsticks.png")
#: Largest --starts and --horizon accepted.
MAX_STARTS, MAX_HORIZON = 100_000, 1_000_000
#: --warmup's largest value, s (its default: ``acid.ident.validate.default_warmup``).
MAX_WARMUP_S = 7 * 86400.0


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
        help="The model's disturbances over a prediction: 'hold' each at its start value "
             "(the paper's protocol for T_int/T_shell) or 'measured'."),
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
    figures: bool = typer.Option(True, "--figures/--no-figures",
                                 help="Write the PNG figures into --out."),
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
    warmup: float | None = typer.Option(
        None, "--warmup", show_default=False,
        help="A model with latent states: the stretch before each start from which they are "
             "estimated, s (whole samples of the data's Ts, rounded up; default 300 s = 60 "
             "samples of 5 s, or 60 samples where 300 s is not whole samples of the data's "
             "Ts or no record holds 300 s + --horizon)."),
    to_end: bool = typer.Option(
        False, "--to-end", help="Also start where fewer than --horizon samples "
                                "remain (short trips); those predictions stop at the "
                                "experiment's end."),
    warm_start: str = typer.Option(
        "fit", "--warm-start",
        help="A model with latent states: how they are estimated at each start: 'fit' "
             "(least squares over the --warmup stretch, parameters held), 'ekf' (the "
             "extended Kalman filter with the declared noises, as `acid fit --method pem` "
             "uses, over that stretch) or 'ekf-trip' (the filter from the start of the "
             "trip, as it would run in the car)."),
    cv: str | None = typer.Option(
        None, "--cv",
        help="'experiments': leave-experiments-out cross-validation: each experiment (trip) "
             "predicted by the model fitted without it (`acid fit` with --method and "
             "--max-evals), the yardsticks fitted on the same training experiments; "
             "per-experiment and pooled intervals and verdicts. Needs --model."),
    cv_folds: int | None = typer.Option(
        None, "--cv-folds",
        help="With --cv: group the experiments into N folds taken in turn (fewer fits; "
             "default one fold per experiment)."),
    starts_design: str | None = typer.Option(
        None, "--starts-design",
        help="Start design(s): even, random (seeded by --seed) or non-overlapping; several "
             "comma-separated (e.g. even,random,non-overlapping) to see whether the verdicts "
             "hold across them (with --cv or --intervals)."),
    intervals: bool = typer.Option(
        False, "--intervals",
        help="Also report 95 % bootstrap intervals (experiments, then starts) of RMSE and "
             "p90 at every prediction time, with their counts, and the verdicts against the "
             "yardsticks from a paired bootstrap (always on with --cv)."),
    resamples: int = typer.Option(1000, "--resamples",
                                  help="Bootstrap resamples of --intervals and --cv."),
    method: str = typer.Option("auto", "--method",
                               help="With --cv: the fit method of each fold (as `acid fit`)."),
    max_evals: int = typer.Option(100, "--max-evals",
                                  help="With --cv: the fit's evaluation budget (as `acid fit`)."),
    prior: list[str] | None = typer.Option(
        None, "--prior", help="With --cv: NAME=MEAN,SD, a Gaussian prior on a parameter in "
                              "each fold's fit (as `acid fit`; repeatable)."),
    error_model: str | None = typer.Option(
        None, "--error-model",
        help="'arx': add to --model's prediction an ARX model of its residual, fitted on "
             "the windows of --error-model-data (estimation trips); DATA is held out."),
    error_model_data: Path | None = typer.Option(
        None, "--error-model-data", help="With --error-model: the estimation dataset."),
) -> None:
    """Predict open loop from many start instants and report the errors vs horizon.

    Errors are k-step prediction errors, k = 1 .. --horizon (K for temperatures); figures
    like the paper's Fig. 5 (one prediction) and Fig. 6 (errors of all starts vs prediction
    time) go to --out. The model is read from the parameter file (the paper's or the econ
    model), or given by --model; every model goes through the same validator
    (``acid.ident.validate``).
    """
    from acid.ident.validate import WARM_STARTS
    from acid.models.loader import BUILT_IN
    from acid_cli._declared import is_model_file, model_file_input, validate_declared

    if model is not None:
        require(is_model_file(model) or model in BUILT_IN, "--model",
                f"must be a model file FILE.py or a built-in declaration "
                f"({', '.join(BUILT_IN)}), got {model!r}")
        require(beside is None and not allow_unstable, "--model",
                "--beside and --allow-unstable are for parameter files of the paper and "
                "econ models")
    check_paths(inputs={"DATA": data, "--model": model_file_input(model),
                        "--params": params_input(params), "--beside": params_input(beside)},
                outputs={"--json": json_path},
                folders={"--out": (out, FIGURES)} if figures else {})
    _check_windows(starts, horizon, seed, exogenous, placement, non_overlapping,
                   held_out_fraction)
    if warmup is not None:
        require_range(warmup, "--warmup", 0.0, MAX_WARMUP_S, "s")
    require(warm_start in WARM_STARTS, "--warm-start",
            f"must be one of {', '.join(WARM_STARTS)}, got {warm_start!r}")
    designs = _designs(starts_design, placement, non_overlapping)
    require_range(resamples, "--resamples", 10, 1_000_000)
    require(not prior or cv is not None, "--prior",
            "is for --cv (the folds' fits); give priors to `acid fit`")
    if error_model is not None:
        return _with_error_model(data, model, params, error_model, error_model_data,
                                 starts=starts, horizon=horizon, to_end=to_end,
                                 warm_start=warm_start, hold_all=exogenous == "hold",
                                 resamples=resamples, seed=seed)
    if cv is not None:
        require(cv == "experiments", "--cv", f"must be 'experiments', got {cv!r}")
        require(model is not None, "--cv", "needs --model (the declared model to fit)")
        from acid_cli._declared import cross_validate_declared

        return cross_validate_declared(
            data, model, json_path, starts=starts, horizon=horizon,
            warmup=warmup_seconds(warmup, data), seed=seed, designs=designs,
            folds=cv_folds, hold_all=exogenous == "hold", to_end=to_end,
            warm_start=warm_start, resamples=resamples, method=method, max_evals=max_evals,
            prior=prior)
    if starts_design is not None and len(designs) == 1:
        from acid.ident.crossval import design_options

        opts = design_options(designs[0])
        placement, non_overlapping = opts["placement"], opts["non_overlapping"]
    ps = other = None
    if model is None:   # a parameter file of the paper's or the econ model names its model
        ps = load_any_params(params, allow_unstable=allow_unstable)
        model = ps.model
        if beside is not None:
            other = load_any_params(beside, allow_unstable=allow_unstable)
    validate_declared(data, model, params, json_path, starts=starts, horizon=horizon,
                      warmup=warmup_seconds(warmup, data),
                      placement=placement, seed=seed,
                      held_out_fraction=held_out_fraction, hold_all=exogenous == "hold",
                      non_overlapping=non_overlapping, yardsticks=yardsticks,
                      to_end=to_end, warm_start=warm_start, values=ps, beside=other,
                      figures=out if figures else None,
                      intervals=(designs, resamples) if intervals else None)


def _with_error_model(data, model, params, kind, est, *, hold_all, **opts) -> None:
    """--error-model: grey box plus residual ARX (``acid.ident.errmodel``), printed."""
    from acid.data import Dataset
    from acid.ident.errmodel import summary, validate_with_error_model
    from acid.ident.validate import read_parameters
    from acid.models.loader import load

    require(kind == "arx", "--error-model", f"must be 'arx', got {kind!r}")
    require(model is not None, "--error-model", "needs --model (the declared model)")
    require(est is not None, "--error-model", "needs --error-model-data (estimation data)")
    check_paths(inputs={"DATA": data, "--error-model-data": est},
                records=["DATA", "--error-model-data"])   # DATA is held out: not the same file
    m = load(model)
    a, b = Dataset.from_hdf5(est), Dataset.from_hdf5(data)
    both = Dataset.concatenate([a, b])
    both.source = f"{est} + {data}"
    ps = None if params == "paper" else read_parameters(m, params)
    hold = tuple(d.name for d in m.disturbances) if hold_all else ()
    resamples, seed = opts.pop("resamples"), opts.pop("seed")
    v = validate_with_error_model(m, both, ps, n_estimation=len(a), hold=hold,
                                  fit_starts=opts["starts"], n_resamples=resamples,
                                  seed=seed, **opts)
    print(summary(v))


def _designs(spec: str | None, placement: str, non_overlapping: bool) -> tuple[str, ...]:
    """--starts-design as a tuple of designs (default: the one --placement and
    --non-overlapping give)."""
    from acid.ident.crossval import STARTS_DESIGNS

    if spec is None:
        return ("non-overlapping" if non_overlapping else placement,)
    out = tuple(dict.fromkeys(p.strip() for p in spec.split(",") if p.strip()))
    for d in out or ("",):
        require(d in STARTS_DESIGNS, "--starts-design",
                f"must be one or more of {', '.join(STARTS_DESIGNS)}, got {d!r}")
    return out


def warmup_samples(warmup_s: float, Ts: float) -> int:
    """``--warmup`` (s) as whole samples of ``Ts`` (s): rounded up, said in one note when it
    is not a multiple of ``Ts``."""
    n = math.ceil(warmup_s / Ts - 1e-9)
    if not math.isclose(n * Ts, warmup_s, rel_tol=1e-9, abs_tol=1e-9):
        note(f"--warmup {warmup_s:g} s is not a whole number of samples of {Ts:g} s: "
             f"{n} samples ({n * Ts:g} s) are used")
    return n


def warmup_seconds(warmup_s: float | None, data: Path) -> float | None:
    """``--warmup`` (s) rounded up to whole samples of ``data``'s Ts, in seconds (what the
    API's ``warmup`` takes); None (not given): the API's default."""
    if warmup_s is None:
        return None
    Ts = _sample_time(data)
    return warmup_samples(warmup_s, Ts) * Ts


def _sample_time(data: Path) -> float:
    """The sample time of the dataset ``data``, s (``DataError`` naming the file)."""
    from acid.data import Dataset

    return Dataset.from_hdf5(data, min_samples=2).Ts


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
