"""``acid mpc-check``: the NMPC of paper section IV in closed loop (Figs. 7-10), with verdicts."""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import typer

from acid import __version__
from acid._io import file_sha256, save_figure
from acid.control.nmpc import SOLVERS, NMPCConfig
from acid.errors import ConfigError
from acid.models.params import load_params
from acid.paper import STUDIES
from acid.studies.mpc_check.scenarios import PLANT_BACKOFF
from acid.studies.mpc_check.scenarios import mpc_check as run_check
from acid.units import K2C
from acid_cli._common import (
    check_paths,
    console,
    handle_errors,
    params_input,
    plant_inputs,
    print_table,
    progress_bar,
    require_range,
    say,
    write_summary,
)
from acid_cli._plant import (
    ambient_option,
    fmu_map_option,
    identity_line,
    plant_choice,
    plant_identity,
    plant_option,
    plant_overrides,
)

#: Largest --backoff-prior, K: the one-step error of a cabin model sampled at 5 s is a
#: fraction of a kelvin; the margin it sets is capped at 1 K (``BackoffConfig.max_margin``).
MAX_BACKOFF_PRIOR_K = 10.0

FIGURES = ("fig7_model.png", "fig8_plant.png", "fig9_cav_bound.png",
           "fig10_cav_comparison.png")


def _fmt(v, digits: int = 3) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.{digits}f}"


def _verdict(passed) -> str:
    return "skipped" if passed is None else ("PASS" if passed else "FAIL")


@handle_errors
def mpc_check(
    params: str = typer.Option("paper", "--params",
                               help="params.json from `acid fit`, or 'paper' for the preset."),
    out: Path = typer.Option(Path("reports/mpc-check"), "--out",
                             help="Folder for the figures (fig7-fig10 PNG)."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
    first_move: str = typer.Option(
        "free", "--first-move",
        help="Reading of eq. 13 u(0|k) = u(k): 'free' (u(0|k) is decided and applied now, "
             "default) or 'pinned' (u(0|k) is the input already applied; one-period delay)."),
    solver: str = typer.Option(
        "sqp", "--solver",
        help="NLP solver: 'sqp' (SQP with the active-set QP solver qrqp, warm-started, the "
             "algorithm of acid export-c; fatrop when it fails; default), 'fatrop' "
             "(structure-exploiting interior point) or 'ipopt'."),
    compiled: bool = typer.Option(
        True, "--compiled/--no-compiled",
        help="Run fatrop/SQP as generated C compiled at first use (cached per user); "
             "--no-compiled solves inside CasADi (same answers, slower)."),
    offset_free: bool = typer.Option(
        False, "--offset-free/--no-offset-free",
        help="Estimate disturbances on eqs. 1-2 with a Kalman filter and predict with them."),
    backoff: bool = typer.Option(
        True, "--backoff/--no-backoff",
        help="On the high-fidelity plant (scenario b), tighten the cabin bounds by 3 standard "
             "deviations of the NMPC's recent one-step T_cab prediction errors; "
             "--no-backoff: the paper's NMPC."),
    backoff_prior: float = typer.Option(
        PLANT_BACKOFF.sigma0, "--backoff-prior",
        help="Prior standard deviation of that one-step error before any is measured, K "
             "(0: learn from the errors only; at most 10 K: the margin it sets is capped "
             "at 1 K)."),
    skip_plant: bool = typer.Option(False, "--skip-plant",
                                    help="Only scenario (a), on the control-oriented model."),
    figures: bool = typer.Option(True, "--figures/--no-figures", help="Write the PNG figures."),
    allow_unstable: bool = typer.Option(
        False, "--allow-unstable",
        help="Use --params even if eqs. 1-3 are unstable or not in kelvin."),
    plant: str = plant_option("hifi", ("hifi",)),
    fmu_map: Path | None = fmu_map_option(),
    t_amb: float | None = ambient_option("the paper's, 30 degC (Table II); the NMPC's eq. 4 "
                                         "and the plant"),
) -> None:
    """Run the NMPC scenarios: (a) on the model, (b) on the plant, (c) CAV case.

    Reports A/C energy (MJ), constraint violations (K), whole-step solve time (ms) and
    fallbacks per scenario, with PASS/FAIL against the stated criteria; exits 1 on any FAIL.
    """
    check_paths(inputs={"--params": params_input(params), **plant_inputs(plant, fmu_map)},
                outputs={"--json": json_path},
                folders={"--out": (out if figures else None, FIGURES)})
    if first_move not in ("free", "pinned"):
        raise ConfigError(f"--first-move must be 'free' or 'pinned', got {first_move!r}")
    if solver not in SOLVERS:
        raise ConfigError(f"--solver must be one of {', '.join(SOLVERS)}, got {solver!r}")
    require_range(backoff_prior, "--backoff-prior", 0.0, MAX_BACKOFF_PRIOR_K, "K")
    choice = plant_choice(plant, fmu_map, allowed=("hifi",))
    p = load_params(params, allow_unstable=allow_unstable)
    ambient = plant_overrides(t_amb).get("T_amb")
    config = NMPCConfig(first_move=first_move, solver=solver, compiled="auto" if compiled
                        else False, offset_free=offset_free,
                        **({} if ambient is None else {"T_amb": ambient}))
    plant_backoff = dataclasses.replace(PLANT_BACKOFF, sigma0=backoff_prior) if backoff else None
    factory = None
    if choice.kind == "fmu" and not skip_plant:
        choice.check()
        factory = choice.factory(**({} if ambient is None else {"T_amb": ambient}))

    t0 = time.perf_counter()
    with progress_bar("mpc-check", total=1) as update:
        result = run_check(p, config, plant=not skip_plant, progress=update,
                           plant_factory=factory, plant_backoff=plant_backoff)
    elapsed = time.perf_counter() - t0

    tm = result.timing
    from acid.plant.config import PlantConfig

    identity = plant_identity(PlantConfig().replace(T_amb=config.T_amb)
                              if choice.kind == "hifi" else None,
                              "default" if choice.kind == "hifi" else choice.spec)
    identity["T_amb_C"] = round(float(K2C(config.T_amb)), 6)
    say(identity_line(identity))
    onoff = {True: "on", False: "off"}
    say(f"NMPC: N = {config.N}, solver {solver} ({tm.get('backend')}), first move "
        f"{first_move}, offset-free {onoff[offset_free]}, back-off on the plant "
        f"{onoff[backoff]}, parameters {p.name!r} ({elapsed:.1f} s)")
    rows, notes = [], []
    for key, s in result.scenarios.items():
        if s.skipped is not None:
            rows.append([key, "skipped", "", "", "", "", "", "", ""])
            notes.append(f"{key}: {s.skipped}")
            continue
        d = s.to_json_dict()
        ms = d["solve_ms"]
        rows.append([key, _verdict(s.passed), _fmt(d["energy_MJ"], 4),
                     _fmt(d["max_violation_K"]), _fmt(d.get("max_avoidable_violation_K")),
                     _fmt(d["max_T_cab_violation_K"]), _fmt(d["first_step_violation_K"]),
                     f"{ms['median']:.2f}/{ms['p95']:.2f}/{ms['max']:.2f}", str(d["fallbacks"])])
        notes.append(f"{key}: {_verdict(s.passed)} (criterion: {s.criterion})")
    rows.append(["timing", _verdict(tm["passed"]), "", "", "", "", "",
                 f"{tm['median']:.2f}/{tm['p95']:.2f}/{tm['max']:.2f}", ""])
    notes.append(f"timing: {_verdict(tm['passed'])} (criterion: {tm['criterion']}; mean "
                 f"{tm['mean']:.2f} ms; speed is measured by benchmarks/bench_mpc.py)")
    print_table("NMPC closed-loop checks (violations after the first step, K)",
                ["scenario", "verdict", "energy MJ", "max viol", "avoidable", "T_cab viol",
                 "1st step", "step ms med/p95/max", "fallbacks"], rows)
    for line in notes:
        say(f"  {line}")
    cav = result.scenarios.get("cav")
    if cav is not None and cav.skipped is None:
        m = cav.metrics
        line = (f"CAV over {m['window_s'][0]:g}-{m['window_s'][1]:g} s: Case 1 "
                f"{m['case1_energy_MJ']:.4f} MJ, Case 2 {m['case2_energy_MJ']:.4f} MJ, saving "
                f"{_fmt(m['saving_pct'], 1)} % (paper: {STUDIES.cav_case1_MJ} vs "
                f"{STUDIES.cav_case2_MJ} MJ, {STUDIES.cav_saving_pct:g} %)")
        if "saving_from_speed_pct" in m:
            line += (f"; speed-blind plant: {_fmt(m['speed_blind_plant']['saving_pct'], 1)} %, "
                     f"so {_fmt(m['saving_from_speed_pct'], 1)} points come from "
                     "speed-dependent efficiency")
        say(line)
        per = m.get("periodic")
        if per:
            line = (f"CAV periodic ({per['cycles']} cycles of {per['period_s']:g} s, energy over "
                    f"{per['window_s'][0]:g}-{per['window_s'][1]:g} s, stored heat cancels): "
                    f"Case 1 {per['case1_energy_MJ']:.4f} MJ, Case 2 "
                    f"{per['case2_energy_MJ']:.4f} MJ, saving {_fmt(per['saving_pct'], 1)} %")
            if "saving_from_speed_pct" in per:
                line += (f"; speed-blind plant {_fmt(per['speed_blind_plant']['saving_pct'], 1)}"
                         f" %, from speed {_fmt(per['saving_from_speed_pct'], 1)} points")
            say(line)
        say("  (cav max viol is T_evap above 12 degC while the compressor is shut off "
            "open loop, by design)")

    fig_paths = {}
    if figures:
        from acid.report.mpc import mpc_figures

        for stem, fig in mpc_figures(result.scenarios).items():
            fig_paths[stem] = str(save_figure(fig, out / f"{stem}.png"))
        if fig_paths:
            say(f"figures written to {out}/")

    summary = {
        "command": "mpc-check",
        "acid_version": __version__,
        "inputs": {"params": params,
                   "params_sha256": None if params == "paper" else file_sha256(params),
                   **choice.to_json_dict()},
        **identity,
        "elapsed_s": elapsed,
        "figures": fig_paths,
        **result.to_json_dict(),
    }
    write_summary(json_path, summary)
    console.print("[bold green]PASS[/]" if result.passed else "[bold red]FAIL[/]")
    if not result.passed:
        raise typer.Exit(code=1)
