"""``acid fit``: identify a declared model (the paper's eqs. 1-5 by default) from a dataset;
write its parameter file."""

from __future__ import annotations

from pathlib import Path

import typer

from acid.errors import ConfigError
from acid.ident.fit import COVARIANCES, DEFAULT_COVARIANCE, LOSSES, METHODS, OE_SOLVERS
from acid_cli._common import (
    check_paths,
    handle_errors,
    params_input,
    require,
    require_range,
)
from acid_cli._declared import PaperOptions, fit_declared, is_model_file, model_file_input

#: Largest output-error window and HAC lag accepted, samples.
MAX_WINDOW = 100_000
MAX_EVALS = 100_000

MODEL_FAMILIES = ("paper", "econ")


@handle_errors
def fit(
    data: Path = typer.Argument(..., help="Dataset (HDF5, from `acid excite` or `acid import`)."),
    out: Path = typer.Option(Path("params.json"), "--out", help="Parameter file to write."),
    method: str | None = typer.Option(
        None, "--method",
        help="'auto' (ls where every equation allows it, else oe), 'ls' equation-error "
             "least squares, 'cvx' least squares inside the declared bounds and affine "
             "constraints (CVXPY; the active ones are noted), 'oe' "
             "output error (multi-step simulation error, started from the ls estimate), 'pem' "
             "prediction error (an extended Kalman filter over each whole record)."),
    loss: str = typer.Option("squared", "--loss",
                             help="'squared' or 'huber' (robust to outliers)."),
    estimation_fraction: float = typer.Option(
        1.0, "--estimation-fraction",
        help="Fit on the first F of the record (e.g. 0.5); the rest is left for "
             "`acid validate`."),
    oe_window: int = typer.Option(300, "--oe-window",
                                  help="Samples per output-error simulation window."),
    max_evals: int = typer.Option(
        100, "--max-evals",
        help="A declared model's output-error or prediction-error fit: at most this many "
             "evaluations of the loss (prediction error: as many gradients, then up to a "
             "third as many Fisher-information matrices for Newton steps); the report says "
             "whether it converged first."),
    reference: str = typer.Option(
        "paper", "--reference",
        help="--model paper: the values shown beside ours, where output error starts and "
             "what parameters the data do not separate stay closest to: 'paper' or a "
             "params.json."),
    strict: bool = typer.Option(False, "--strict",
                                help="Refuse (instead of reporting the combination the data "
                                     "identify) when parameters are not separated."),
    no_blower: bool = typer.Option(False, "--no-blower",
                                   help="--model paper: hold beta at the reference values "
                                        "instead of fitting P_bl."),
    oe_solver: str = typer.Option(
        "dense", "--oe-solver",
        help="Output error's solver: 'dense' (least squares over the windows) or 'ms' (one "
             "sparse multiple-shooting problem solved by IPOPT, the same optimum; squared "
             "loss only)."),
    oe_measured_x0: bool = typer.Option(
        False, "--oe-measured-x0",
        help="Output error: start each window from the measured states instead of "
             "estimating them (latent states are estimated still)."),
    use_eta_cop: bool = typer.Option(
        False, "--use-eta-cop",
        help="Put the eta_cop estimated from P_comp (eq. 4) into params.json."),
    covariance: str = typer.Option(
        DEFAULT_COVARIANCE, "--covariance",
        help="Standard errors: 'white' (sigma^2 (X^T X)^-1, residuals assumed white) or 'hac' "
             "(Newey-West 1987 sandwich, honest when the residuals are autocorrelated, "
             "as on plant data)."),
    hac_bandwidth: str = typer.Option(
        "auto", "--hac-bandwidth",
        help="HAC Bartlett lag: 'auto' (Newey-West 1994), 'nw' (floor(4 (n/100)^(2/9))) "
             "or an integer >= 0."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
    model: str = typer.Option(
        "paper", "--model",
        help="Model family: 'paper' (eqs. 1-5, the default) or 'econ' (cabin, interior, "
             "shell, evaporator and humidity with an identified compressor power map; needs "
             "data from `acid excite --model econ`), or a model file FILE.py declaring "
             "`model = acid.models.Model(...)` (the README's section 'Your own model')."),
    fix: list[str] | None = typer.Option(
        None, "--fix", help="NAME=VALUE: hold a parameter of a declared model (a model "
                            "file, paper or econ) at VALUE (repeatable)."),
    prior: list[str] | None = typer.Option(
        None, "--prior", help="NAME=MEAN,SD: a Gaussian prior on a parameter of a declared "
                              "model, in its unit (repeatable; replaces a declared prior): "
                              "output error and prediction error then maximise the "
                              "posterior."),
    prior_weight: float = typer.Option(
        1.0, "--prior-weight", help="W >= 0: every prior's information (1/SD^2) times W "
                                    "(0: no priors, 1: as declared or given)."),
    free: list[str] | None = typer.Option(
        None, "--free", help="NAME: estimate a parameter the declared model (a model "
                             "file, paper or econ) declares fixed (repeatable)."),
    fit_starts: int = typer.Option(
        1, "--fit-starts", help="Output-error (or, with --method pem, prediction-error) "
                                "starts spread inside the declared bounds (a model file, or "
                                "paper/econ through their declarations); the distinct optima "
                                "are reported, failed starts with their reason."),
    seed: int = typer.Option(0, "--seed", help="Seed of the --fit-starts draws."),
    add_record: list[Path] | None = typer.Option(
        None, "--add-record", help="Another record fitted with DATA, as its own experiment "
                                   "(model file; repeatable)."),
) -> None:
    """Fit a declared model (the paper's eqs. 1-5 by default) and write its parameter file.

    Prints the parameter table (declared or reference values beside ours), how each
    equation was fitted (least squares where it is linear in its parameters) with its
    conditioning and one-step fit %, and the multi-step simulation fit %. For the paper's
    model the file is also a params.json the controllers read (kelvin convention).
    """
    from acid.models.loader import BUILT_IN

    declared = model != "econ"
    require(model in (*MODEL_FAMILIES, *BUILT_IN) or is_model_file(model), "--model",
            f"must be one of {', '.join(dict.fromkeys([*MODEL_FAMILIES, *BUILT_IN]))} or a "
            f"model file FILE.py, got {model!r}")
    # econ keeps its family's fitter unless an option only the declared fitter has is given
    require_range(seed, "--seed", 0, 2**32 - 1, integer=True)
    require_range(prior_weight, "--prior-weight", 0.0, 1e6)
    if model == "econ" and (fix or free or prior or fit_starts != 1 or prior_weight != 1.0):
        declared = True
    check_paths(inputs={"DATA": data, "--reference": params_input(reference),
                        "--model": model_file_input(model),
                        **{f"--add-record {i + 1}": p for i, p in enumerate(add_record or [])}},
                outputs={"--out": out, "--json": json_path})
    method = method or "auto"
    require_range(estimation_fraction, "--estimation-fraction", 0.0, 1.0, lo_open=True)
    require(loss in LOSSES, "--loss", f"must be one of {', '.join(LOSSES)}, got {loss!r}")
    require(oe_solver in OE_SOLVERS, "--oe-solver",
            f"must be one of {', '.join(OE_SOLVERS)}, got {oe_solver!r}")
    require(oe_solver == "dense" or loss == "squared", "--oe-solver",
            "'ms' minimises the squared loss only (--loss huber needs 'dense')")
    require_range(oe_window, "--oe-window", 5, MAX_WINDOW, "samples")
    require_range(max_evals, "--max-evals", 1, MAX_EVALS)
    bandwidth: str | int = hac_bandwidth
    if hac_bandwidth.strip().isdigit():
        bandwidth = int(hac_bandwidth)
        require_range(bandwidth, "--hac-bandwidth", 0, MAX_WINDOW, "samples")
    elif hac_bandwidth not in ("auto", "nw"):
        raise ConfigError(f"--hac-bandwidth must be 'auto', 'nw' or an integer >= 0, "
                          f"got {hac_bandwidth!r}")
    if covariance not in COVARIANCES:
        raise ConfigError(f"--covariance: unknown covariance {covariance!r} (choose from "
                          f"{', '.join(COVARIANCES)})")
    paper_only = [opt for opt, set_ in (("--use-eta-cop", use_eta_cop),
                                        ("--reference", reference != "paper"),
                                        ("--no-blower", no_blower)) if set_]
    if paper_only and model != "paper":
        raise ConfigError(f"{', '.join(paper_only)}: only for --model paper")
    if declared:
        require(method in METHODS, "--method",
                f"must be one of {', '.join(METHODS)}, got {method!r}")
        records = {"DATA": data, **{f"--add-record {i + 1}": p
                                    for i, p in enumerate(add_record or [])}}
        check_paths(inputs=records, records=list(records))   # each fitted as its own record
        return fit_declared(data, model, out, json_path, method=method, fix=fix, free=free,
                            prior=prior, prior_weight=prior_weight,
                            fit_starts=fit_starts, seed=seed, oe_window=oe_window,
                            covariance=covariance, bandwidth=bandwidth,
                            estimation_fraction=estimation_fraction,
                            more=list(add_record or []), loss=loss, strict=strict,
                            max_evals=max_evals,
                            oe_estimate_x0=not oe_measured_x0, oe_solver=oe_solver,
                            paper=PaperOptions(reference=reference, no_blower=no_blower,
                                               use_eta_cop=use_eta_cop)
                            if model == "paper" else None)
    given = [opt for opt, set_ in (("--method", method != "auto"), ("--loss", loss != "squared"),
                                   ("--strict", strict), ("--oe-measured-x0", oe_measured_x0),
                                   ("--oe-solver", oe_solver != "dense"),
                                   ("--add-record", add_record),
                                   ("--max-evals", max_evals != 100)) if set_]
    if given:
        raise ConfigError(f"{', '.join(given)}: not for --model econ (its family's fitter; "
                          "--fix, --free or --fit-starts fit it through its declaration)")
    from acid_cli._fit_econ import fit_econ

    return fit_econ(data, out, estimation_fraction, covariance, bandwidth, json_path)
