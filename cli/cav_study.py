"""``acid cav-study``: speed preview on a real drive cycle, compared fairly (equal comfort,
same start, end-state corrected, with a speed-blind twin plant)."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from acid import __version__
from acid._io import file_sha256, save_figure
from acid.errors import ConfigError
from acid.params import load_params
from acid.units import C2K, K2C
from acid_cli._common import (
    check_paths,
    handle_errors,
    note,
    params_input,
    plant_inputs,
    print_table,
    progress_bar,
    require_range,
    say,
    write_summary,
)
from acid_cli._plant import fmu_map_option, plant_choice, plant_option

#: Longest NMPC horizon (steps) and warm-up / tail / identification record accepted.
MAX_HORIZON = 200
MAX_SECONDS = 7 * 86400.0


def _fmt(v, digits: int = 3) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.{digits}f}"


@handle_errors
def cav_study(
    cycle: str = typer.Option("udds", "--cycle",
                              help="Drive cycle from datasets/drive_cycles (udds, nycc, sc03...)."),
    params: str = typer.Option("paper", "--params",
                               help="params.json from `acid fit`, or 'paper' for the preset."),
    horizon: int = typer.Option(6, "--horizon", help="NMPC horizon N (steps of 5 s)."),
    T_low: float = typer.Option(22.0, "--t-low", help="Comfort band lower edge, degC."),
    T_high: float = typer.Option(26.0, "--t-high", help="Comfort band upper edge, degC."),
    warmup: float = typer.Option(1800.0, "--warmup", help="Warm-up before the cycle, s."),
    tail: float = typer.Option(1200.0, "--tail",
                               help="Common continuation measuring the end-state cost, s "
                                    "(0: C_eff correction only)."),
    speed_blind: bool = typer.Option(True, "--speed-blind/--no-speed-blind",
                                     help="Also run the study on the speed-blind twin plant."),
    identify_duration: float = typer.Option(
        7200.0, "--identify-duration",
        help="Length of the APRBS + UDDS record that identifies eta_cop(v), s."),
    out: Path = typer.Option(Path("reports/cav-study"), "--out",
                             help="Folder for the figure (cav_<cycle>.png)."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
    figures: bool = typer.Option(True, "--figures/--no-figures", help="Write the PNG figure."),
    allow_unstable: bool = typer.Option(
        False, "--allow-unstable",
        help="Use --params even if eqs. 1-3 are unstable or not in kelvin."),
    plant: str = plant_option("hifi", ("hifi",)),
    fmu_map: Path | None = fmu_map_option(),
) -> None:
    """Compare (A) constant bound, (B) ICM bound, (C) speed-aware NMPC on a drive cycle.

    All three run the NMPC on the high-fidelity plant from the same warmed-up state; (A) and
    (C) are tuned to (B)'s mean cabin temperature. Reports energy (MJ, compressor + blower),
    mean/max T_cab, comfort violation (K s outside the band), the end-state correction and
    the savings vs (A), on the plant and on its speed-blind twin.
    """
    from acid.mpc.cav_study import CASE_LABELS, CASES, StudyConfig, estimated_steps
    from acid.mpc.cav_study import cav_study as run_study
    from acid.mpc.speed_model import identify_from_plant
    from acid.signals import available_drive_cycles, drive_cycle

    check_paths(inputs={"--params": params_input(params), **plant_inputs(plant, fmu_map)},
                outputs={"--json": json_path},
                folders={"--out": (out if figures else None, (f"cav_{cycle}.png",))})
    require_range(horizon, "--horizon", 2, MAX_HORIZON, "steps")
    require_range(T_low, "--t-low", 0.0, 50.0, "degC")
    require_range(T_high, "--t-high", 0.0, 50.0, "degC")
    if not T_low < T_high:
        raise ConfigError(f"--t-low {T_low:g} degC must be below --t-high {T_high:g} degC")
    require_range(warmup, "--warmup", 0.0, MAX_SECONDS, "s")
    require_range(tail, "--tail", 0.0, MAX_SECONDS, "s")
    require_range(identify_duration, "--identify-duration", 600.0, MAX_SECONDS, "s",
                  lo_open=True)
    names = available_drive_cycles()
    if cycle not in names:
        raise ConfigError(f"--cycle: unknown drive cycle {cycle!r} (available: "
                          f"{', '.join(names)})")
    choice = plant_choice(plant, fmu_map, allowed=("hifi",))
    p = load_params(params, allow_unstable=allow_unstable)
    factory = None
    if choice.kind == "fmu":
        choice.check()
        factory = choice.factory()
        if speed_blind:
            note("an FMU plant has no speed-blind twin; running without it")
            speed_blind = False
    config = StudyConfig(cycle=cycle, horizon=horizon, T_low=C2K(T_low), T_high=C2K(T_high),
                         warmup_s=warmup, tail_s=tail, speed_blind=speed_blind)
    eff = identify_from_plant(plant=None if factory is None else factory(),
                              duration_s=identify_duration)
    v, _ = drive_cycle(cycle, Ts=p.Ts)
    with progress_bar(f"cav-study {cycle}", total=estimated_steps(config, v.size, p.Ts)) as up:
        result = run_study(p, config, efficiency=eff, plant_factory=factory, progress=up)

    q = eff.quality
    say(
        f"eta_cop(v) = {eff.eta0:.3f} (+/- {eff.stderr[0]:.3f}) + {eff.eta1:.4f} "
        f"(+/- {eff.stderr[1]:.4f}) v [v in m/s]; R^2 {q['r2']:.3f} (constant eta "
        f"{q['const_eta']:.3f}: R^2 {q['const_r2']:.3f}), RMSE {q['rmse_W']:.0f} W, "
        f"n = {q['n']}; eta(25)/eta(0) = {eff.ratio(25.0):.3f}")
    studies = [result.main] + ([result.blind] if result.blind is not None else [])
    rows, lines = [], []
    for st in studies:
        plant = "hifi" if st.plant == "hifi" else "blind"
        for key in CASES:
            c = st.cases[key]
            ms = c.to_json_dict()["solve_ms"]
            rows.append([plant, key, _fmt(c.energy_J / 1e6, 4),
                         f"{K2C(c.mean_T_cab):.2f}", f"{K2C(c.max_T_cab):.2f}",
                         _fmt(c.comfort_violation_Ks, 1), _fmt(c.correction_J / 1e6, 4),
                         _fmt((c.tail_energy_J - st.cases["A"].tail_energy_J) / 1e6, 4),
                         f"{ms['median']:.2f}"])
        for key in ("B", "C"):
            s = st.savings_pct(key)
            lines.append(f"{st.plant}: {CASE_LABELS[key]} saves vs A: raw {_fmt(s['raw'], 2)} %,"
                         f" C_eff-corrected {_fmt(s['corrected'], 2)} %, tail-corrected "
                         f"{_fmt(s.get('tail_corrected'), 2)} %")
    print_table(f"{cycle.upper()} ({v.size * p.Ts:g} s, mean {v.mean():.1f} m/s), N = {horizon}",
                ["_plant", "_case", "E MJ", "mean C", "max C", "viol Ks", "Ceff MJ", "tail MJ",
                 "ms"], rows)
    say("A: constant bound, B: ICM bound, C: speed-aware NMPC; "
        "E: compressor + blower over the cycle; viol: K s outside the band; Ceff, "
        "tail: end-state corrections vs A; ms: median whole NMPC step")
    for line in lines:
        say(line)
    d = result.to_json_dict()
    if "saving_from_speed_pct" in d:
        sp = d["saving_from_speed_pct"]
        say("part of the saving owed to speed (plant minus speed-blind twin, points): "
            + "; ".join(f"{k}: " + ", ".join(f"{m} {_fmt(v_, 2)}" for m, v_ in sp[k].items())
                        for k in ("B", "C")))

    fig_path = None
    if figures:
        from acid.report.cav import cav_study_figure

        fig_path = str(save_figure(cav_study_figure(result), out / f"cav_{cycle}.png"))
        say(f"figure written to {fig_path}")
    summary = {
        "command": "cav-study", "acid_version": __version__,
        "inputs": {"params": params,
                   "params_sha256": None if params == "paper" else file_sha256(params),
                   **choice.to_json_dict()},
        "figure": fig_path, **d,
    }
    write_summary(json_path, summary)
