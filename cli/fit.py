"""``acid fit``: identify gamma, tau, beta (paper eqs. 1-5) from a dataset; write params.json."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import typer

from acid import __version__
from acid.data import MODEL_CHANNELS, Dataset
from acid.errors import ConfigError
from acid.fit import (
    COVARIANCES,
    DEFAULT_COVARIANCE,
    EQUATION_CHANNEL,
    LOSSES,
    METHODS,
    ModelFitter,
)
from acid.params import load_params
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
from acid_cli._declared import fit_declared, is_model_file, model_file_input

#: Largest output-error window and HAC lag accepted, samples.
MAX_WINDOW = 100_000
MAX_EVALS = 100_000

MODEL_FAMILIES = ("paper", "econ")


def _num(v: float, digits: int = 5) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.{digits}g}"


def _lags(bandwidths: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in bandwidths.items())


@handle_errors
def fit(
    data: Path = typer.Argument(..., help="Dataset (HDF5, from `acid excite` or `acid import`)."),
    out: Path = typer.Option(Path("params.json"), "--out", help="Parameter file to write."),
    method: str | None = typer.Option(
        None, "--method",
        help="'ls' equation-error least squares (the default for paper), 'cvx' constrained "
             "(CVXPY), 'oe' output error (multi-step simulation error, started from the ls "
             "estimate); for a model file also 'auto' (its default: ls where every "
             "equation allows it, else oe) and 'pem' (prediction error: an extended "
             "Kalman filter over each whole record)."),
    loss: str = typer.Option("squared", "--loss",
                             help="'squared' or 'huber' (robust to outliers; cvx or oe)."),
    estimation_fraction: float = typer.Option(
        1.0, "--estimation-fraction",
        help="Fit on the first F of the record (e.g. 0.5); the rest is left for "
             "`acid validate`."),
    oe_window: int = typer.Option(300, "--oe-window",
                                  help="Samples per output-error simulation window."),
    max_evals: int = typer.Option(
        100, "--max-evals",
        help="A declared model's output-error or prediction-error fit: at most this many "
             "evaluations of the loss (the report says whether it converged first)."),
    reference: str = typer.Option(
        "paper", "--reference",
        help="Parameters shown beside ours and used for parameters the data do not excite: "
             "'paper' or a params.json."),
    strict: bool = typer.Option(False, "--strict",
                                help="Refuse (instead of warn) when a parameter is not excited."),
    no_blower: bool = typer.Option(False, "--no-blower",
                                   help="Keep the reference beta instead of fitting P_bl."),
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
             "`model = acid.models.Model(...)` (ARCHITECTURE.md, 'How to add a model')."),
    fix: list[str] | None = typer.Option(
        None, "--fix", help="NAME=VALUE: hold a parameter of a declared model (a model "
                            "file, paper or econ) at VALUE (repeatable)."),
    free: list[str] | None = typer.Option(
        None, "--free", help="NAME: estimate a parameter the declared model (a model "
                             "file, paper or econ) declares fixed (repeatable)."),
    fit_starts: int = typer.Option(
        1, "--fit-starts", help="Output-error starts spread inside the declared bounds "
                                "(a model file, or paper/econ through their declarations); "
                                "the distinct optima are reported."),
    seed: int = typer.Option(0, "--seed", help="Seed of the --fit-starts draws."),
    add_record: list[Path] | None = typer.Option(
        None, "--add-record", help="Another record fitted with DATA, as its own experiment "
                                   "(model file; repeatable)."),
) -> None:
    """Fit the control-oriented model and write params.json (kelvin convention).

    Prints the parameter table with the reference (paper) values beside ours, the
    conditioning of each regression and the one-step and multi-step fit %.
    """
    # A built-in family takes the declared path (acid.models.load(name)) when an option only
    # the declared fitter has is given; without them it keeps its hand-written stack.
    from acid.models.loader import BUILT_IN

    # A built-in declaration without a hand-written stack (cabin3, ...) is always declared.
    declared = is_model_file(model) or (model in BUILT_IN and model not in MODEL_FAMILIES) or (
        model in MODEL_FAMILIES and bool(fix or free or fit_starts != 1))
    require(declared or model in MODEL_FAMILIES, "--model",
            f"must be one of {', '.join(dict.fromkeys([*MODEL_FAMILIES, *BUILT_IN]))} or a "
            f"model file FILE.py, got {model!r}")
    check_paths(inputs={"DATA": data, "--reference": params_input(reference),
                        "--model": model_file_input(model) if declared else None,
                        **{f"--add-record {i + 1}": p for i, p in enumerate(add_record or [])}},
                outputs={"--out": out, "--json": json_path})
    if not declared:
        given = [opt for opt, set_ in (("--fix", fix), ("--free", free),
                                       ("--fit-starts", fit_starts != 1),
                                       ("--add-record", add_record)) if set_]
        if given:
            raise ConfigError(f"{', '.join(given)}: only for --model FILE.py (or with "
                              "--fix, --free or --fit-starts, which fit paper and econ "
                              "through the declared path)")
    method = method or ("auto" if declared else "ls")
    require_range(estimation_fraction, "--estimation-fraction", 0.0, 1.0, lo_open=True)
    require(declared or method in METHODS, "--method",
            f"must be one of {', '.join(METHODS)}, got {method!r}")
    require(loss in LOSSES, "--loss", f"must be one of {', '.join(LOSSES)}, got {loss!r}")
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
    if declared:
        given = [opt for opt, set_ in (
            ("--loss", loss != "squared"), ("--use-eta-cop", use_eta_cop),
            ("--strict", strict), ("--reference", reference != "paper"),
            ("--no-blower", no_blower)) if set_]
        if given:
            raise ConfigError(f"{', '.join(given)}: only for --model paper without --fix, "
                              "--free or --fit-starts")
        return fit_declared(data, model, out, json_path, method=method, fix=fix, free=free,
                            fit_starts=fit_starts, seed=seed, oe_window=oe_window,
                            covariance=covariance, bandwidth=bandwidth,
                            estimation_fraction=estimation_fraction,
                            more=list(add_record or []), max_evals=max_evals)
    require(max_evals == 100, "--max-evals", "is for a declared model's output-error or "
            "prediction-error fit (--model FILE.py or a built-in declaration)")
    if model == "econ":
        paper_only = {"--method": method != "ls", "--loss": loss != "squared",
                      "--use-eta-cop": use_eta_cop, "--strict": strict,
                      "--reference": reference != "paper", "--no-blower": no_blower}
        given = [opt for opt, set_ in paper_only.items() if set_]
        if given:
            raise ConfigError(f"{', '.join(given)}: only for --model paper")
        from acid_cli._fit_econ import fit_econ

        return fit_econ(data, out, estimation_fraction, covariance, bandwidth, json_path)
    ref = load_params(reference)
    ds = Dataset.from_hdf5(data, require=MODEL_CHANNELS, min_samples=20)
    est = ds if estimation_fraction == 1.0 else ds.split(estimation_fraction)[0]
    fitter = ModelFitter(method=method, loss=loss, fit_blower=not no_blower,
                         oe_window=oe_window, use_eta_cop=use_eta_cop,
                         on_rank_deficiency="raise" if strict else "fix", reference=ref,
                         covariance=covariance, hac_bandwidth=bandwidth)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the result carries them; printed below, once
        result = fitter.fit(est)

    provenance = dict(result.params.provenance)
    provenance["estimation_fraction"] = estimation_fraction
    provenance["reference"] = reference
    params = result.params.replace(provenance=provenance)
    report = result.to_json_dict()
    params.to_json(out, extra={"fit": report})

    say(f"{data}: {len(est)} of {len(ds)} samples ({est.duration:g} s), method "
                  f"{method}, loss {loss}, covariance {covariance}"
                  + (f" (lags {_lags(result.hac_bandwidth)})" if result.hac_bandwidth else "")
                  + f" ({result.elapsed_s * 1e3:.0f} ms)")
    rows = []
    for (name, unit, ref_v, v, se, lo, hi), st in zip(result.table(),
                                                      result.param_status + ("eq. 4",),
                                                      strict=False):
        ci = "-" if not math.isfinite(lo) else f"[{_num(lo)}, {_num(hi)}]"
        rows.append([name, unit, _num(ref_v), _num(v), _num(se, 2), ci, st])
    print_table(f"Parameters (kelvin convention), {reference} beside ours",
                ["name", "unit", reference, "estimate", "stderr", "95 % interval", "status"],
                rows)
    eq_rows = []
    for eq, ch in EQUATION_CHANNEL.items():
        if eq not in result.rank:
            eq_rows.append([f"eq. {eq[2:]}", ch, "-", "-", "-", "-", "-", "kept"])
            continue
        eq_rows.append([f"eq. {eq[2:]}", ch, f"{result.rank[eq]}/{result.n_regressors[eq]}",
                        _num(result.condition_number[eq], 3),
                        _num(result.condition_number_raw[eq], 3),
                        _num(result.residual_std[eq], 3),
                        f"{result.fit_percent_one_step.get(ch, math.nan):.2f}",
                        result.solver_status[eq].split(" ")[0]])
    print_table("Regressions: rank, condition number (centred+scaled / raw kelvin), "
                "residual std (K; W for eq. 5), one-step fit (%)",
                ["eq.", "channel", "rank", "cond", "cond raw", "resid", "fit %", "solver"],
                eq_rows)
    sim = ", ".join(f"{c} {v:.2f} %" for c, v in result.fit_percent_simulation.items())
    say(f"{oe_window}-step simulation fit from measured states: {sim}")
    if "oe" in result.solver_status:
        say(f"output error: {result.solver_status['oe']}")
    if result.active_constraints:
        say("active constraints: " + "; ".join(result.active_constraints))
    for line in result.notes:
        note(line)
    for line in result.warnings:
        warn(line)
    for line in params.stability_problems():
        warn(f"{out}: the fitted {line}; acid validate and mpc-check refuse these parameters "
             "without --allow-unstable")
    say(f"parameters written to {out}")
    write_summary(json_path, {"command": "fit", "acid_version": __version__,
                              "inputs": {"data": str(data), "reference": reference},
                              "estimation_fraction": estimation_fraction, "out": str(out),
                              "params": params.to_json_dict(), **report})
