"""``acid cav-study``: where the A/C energy is, over drive cycles, at equal comfort.

Seven controllers on the high-fidelity plant from the same warmed-up state, at the same mean
cabin temperature, end states charged back by a common continuation: A (paper NMPC, constant
bound), B (paper NMPC, ICM bound), D and E (economic NMPC without and with speed preview), P
(production-style PI with a coil set-point reset), F (best fixed-coil PI) and the best known
plan (perfect information) replayed open loop, with its uncertainty.
"""

from __future__ import annotations

import math
from functools import partial
from pathlib import Path

import typer

from acid import __version__
from acid._io import file_sha256, save_figure
from acid.errors import ConfigError
from acid.models.params import load_params
from acid.units import C2K, K2C
from acid_cli._common import (
    check_paths,
    handle_errors,
    params_input,
    plant_inputs,
    print_table,
    progress_bar,
    require,
    require_range,
    say,
    warn,
    write_summary,
)
from acid_cli._plant import (
    config_input,
    fmu_map_option,
    identity_line,
    plant_choice,
    plant_identity,
    plant_option,
    plant_overrides,
    refrigerant_option,
)

#: Longest paper-NMPC horizon (steps) and warm-up / tail / identification record accepted.
MAX_HORIZON = 200
MAX_SECONDS = 7 * 86400.0


def _fmt(v, digits: int = 3) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.{digits}f}"


def _econ_intervals(horizon_s: float, Ts: float) -> tuple[float, ...]:
    n = int(round(horizon_s / Ts))
    if n < 2 or abs(n * Ts - horizon_s) > 1e-6:
        raise ConfigError(f"--econ-horizon must be a multiple of {Ts:g} s and at least "
                          f"{2 * Ts:g} s, got {horizon_s:g}")
    return (float(Ts),) * n


@handle_errors
def cav_study(
    cycle: str = typer.Option("udds", "--cycle",
                              help="Drive cycle from datasets/drive_cycles, 'stopgo' (the "
                                   "paper's stop-and-go, repeated) or 'all'."),
    params: str = typer.Option("paper", "--params",
                               help="Paper-model params.json of A and B, or 'paper'."),
    econ_params: Path | None = typer.Option(
        None, "--econ-params",
        help="Econ-model params from `acid fit --model econ`; default: identified here from "
             "an `acid excite --model econ` record of the plant."),
    identify_duration: float = typer.Option(21600.0, "--identify-duration",
                                            help="Length of that record, s."),
    horizon: int = typer.Option(6, "--horizon", help="Paper NMPC horizon N (steps of 5 s)."),
    econ_horizon: float = typer.Option(120.0, "--econ-horizon",
                                       help="Economic NMPC horizon, s (5 s steps)."),
    econ_solver: str = typer.Option(
        "sqp", "--econ-solver",
        help="'sqp' (warm-started SQP, IPOPT when it fails), 'fatrop' or 'ipopt'."),
    econ_terminal: str = typer.Option(
        "steady", "--econ-terminal",
        help="Terminal cost of D and E: 'steady' (multipliers of the model's optimal steady "
             "state), 'heat' (heat content at the marginal compressor price) or 'none'."),
    offset_free: bool = typer.Option(
        False, "--offset-free/--no-offset-free",
        help="D and E estimate model disturbances with an offset-free Kalman filter."),
    compiled: bool = typer.Option(
        True, "--compiled/--no-compiled",
        help="Run the economic NMPC's solver as generated C (compiled once per horizon and "
             "cached per user; needs a C compiler, else CasADi is used)."),
    T_low: float = typer.Option(22.0, "--t-low", help="Comfort band lower edge, degC."),
    T_high: float = typer.Option(26.0, "--t-high", help="Comfort band upper edge, degC."),
    rh_max: float | None = typer.Option(None, "--rh-max",
                                        help="Upper bound on cabin relative humidity, % "
                                             "(economic NMPC and bound)."),
    t_amb: float | None = typer.Option(None, "--t-amb",
                                       help="Ambient temperature, degC (default: the "
                                            "plant's)."),
    warmup: float = typer.Option(7200.0, "--warmup", help="Warm-up before the cycle, s."),
    tail: float = typer.Option(2400.0, "--tail",
                               help="Common continuation measuring the end-state cost, s "
                                    "(0: raw energies only)."),
    plan: bool = typer.Option(True, "--plan/--no-plan",
                              help="Compute the best known plan (perfect information): its "
                                   "variants, replayed."),
    econ_modifier: bool = typer.Option(
        True, "--econ-modifier/--no-econ-modifier",
        help="Correct the econ model's coil economics for D and E from steady holds of the "
             "plant (modifier adaptation) before they run."),
    coil_max: float = typer.Option(10.0, "--coil-max",
                                   help="Warmest coil set-point of D, E, the plan and F's "
                                        "search, degC (paper Table II: 10)."),
    comfort_weight: float = typer.Option(
        30.0, "--comfort-weight",
        help="D's and E's comfort price, W per K^2 of distance from a reference cabin "
             "temperature and per second; the reference is tuned to the common mean, the "
             "band stays a soft bound. 0: tune the band's upper edge instead."),
    baselines: bool = typer.Option(True, "--baselines/--no-baselines",
                                   help="Run the PI baselines P (coil reset) and F (best "
                                        "fixed coil, searched)."),
    jobs: int = typer.Option(2, "--jobs", min=1, help="Cycles run in parallel (--cycle all)."),
    plant_config: Path | None = typer.Option(None, "--plant-config",
                                             help="TOML configuration of the plant."),
    refrigerant: str | None = refrigerant_option(),
    out: Path = typer.Option(Path("reports/cav-study"), "--out",
                             help="Folder for the figures."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
    figures: bool = typer.Option(True, "--figures/--no-figures", help="Write PNG figures."),
    allow_unstable: bool = typer.Option(
        False, "--allow-unstable",
        help="Use --params even if eqs. 1-3 are unstable or not in kelvin."),
    plant: str = plant_option("hifi", ("hifi",)),
    fmu_map: Path | None = fmu_map_option(),
) -> None:
    """Energy of A, B, D, E, P, F and the best known plan per cycle, at equal comfort.

    Equal comfort: equal mean cabin temperature, and cabin RH inside the band (a controller
    outside it is marked and not ranked). Reports energy (compressor + blower), the
    tail-corrected energy, savings against A and against the best fixed-coil PI F, each
    controller's gap to the best known plan with the plan's spread, mean/max T_cab, PMV, RH,
    and preview's share (E minus D); writes energy_CYCLE.png (energy_all.png for --cycle all)
    and cav_CYCLE.png (trajectories of A, E, F and the plan) to --out.
    """
    from acid.comfort import RH_BAND_SOURCE
    from acid.control.econ.nmpc import ECON_SOLVERS, TERMINALS, EconNMPCConfig
    from acid.models.econ_params import EconParams
    from acid.plant import make_plant
    from acid.plant.vehicles import vehicle_config, vehicle_label
    from acid.studies.cav_study import (
        CONTROLLERS,
        STOPGO,
        StudyConfig,
        available_cycles,
        estimated_steps,
        identify_econ,
        make_scenario,
    )
    from acid.studies.cav_study import cav_study as run_study

    names = available_cycles()
    if cycle != "all" and cycle not in names:
        raise ConfigError(f"--cycle: unknown cycle {cycle!r} (available: "
                          f"{', '.join(names)}, all)")
    stem = "all" if cycle == "all" else cycle
    figure_names = [f"energy_{stem}.png"] + [f"cav_{n}.png"
                                             for n in (names if cycle == "all" else [cycle])]
    plant_config_given = plant_config
    plant_config = config_input(plant_config)  # a named vehicle ('paper') -> its file
    check_paths(inputs={"--params": params_input(params), "--econ-params": econ_params,
                        "--plant-config": plant_config, **plant_inputs(plant, fmu_map)},
                outputs={"--json": json_path},
                folders={"--out": (out if figures else None, figure_names)})
    require_range(horizon, "--horizon", 2, MAX_HORIZON, "steps")
    require_range(T_low, "--t-low", 0.0, 50.0, "degC")
    require_range(T_high, "--t-high", 0.0, 50.0, "degC")
    if not T_low < T_high:
        raise ConfigError(f"--t-low {T_low:g} degC must be below --t-high {T_high:g} degC "
                          "(the comfort band is empty)")
    require_range(warmup, "--warmup", 0.0, MAX_SECONDS, "s")
    require_range(tail, "--tail", 0.0, MAX_SECONDS, "s")
    require_range(identify_duration, "--identify-duration", 3600.0, MAX_SECONDS, "s")
    require_range(econ_horizon, "--econ-horizon", 10.0, 3600.0, "s")
    require(econ_solver in ECON_SOLVERS, "--econ-solver",
            f"must be one of {', '.join(ECON_SOLVERS)}, got {econ_solver!r}")
    require(econ_terminal in TERMINALS, "--econ-terminal",
            f"must be one of {', '.join(TERMINALS)}, got {econ_terminal!r}")
    require_range(coil_max, "--coil-max", 4.0, 15.0, "degC")
    require_range(comfort_weight, "--comfort-weight", 0.0, 1e5, "W/K^2 per second")
    if rh_max is not None:
        require_range(rh_max, "--rh-max", 0.0, 100.0, "%", lo_open=True)
    if t_amb is not None:
        require_range(t_amb, "--t-amb", -40.0, 55.0, "degC")
    choice = plant_choice(plant, fmu_map, allowed=("hifi",))
    require(plant_config is None or choice.kind == "hifi", "--plant-config",
            "applies to --plant hifi only")
    require(refrigerant is None or choice.kind == "hifi", "--refrigerant",
            "applies to --plant hifi only")
    p = load_params(params, allow_unstable=allow_unstable)
    econ_cfg = EconNMPCConfig(intervals=_econ_intervals(econ_horizon, p.Ts),
                              solver=econ_solver, terminal=econ_terminal,
                              compiled="auto" if compiled else False,
                              offset_free=offset_free,
                              T_cab_min=C2K(T_low), T_cab_max=C2K(T_high),
                              RH_max=None if rh_max is None else rh_max / 100.0)
    config = StudyConfig(horizon=horizon, econ=econ_cfg, T_low=C2K(T_low), T_high=C2K(T_high),
                         T_amb=None if t_amb is None else C2K(t_amb), warmup_s=warmup,
                         tail_s=tail, plan=plan, baselines=baselines,
                         econ_modifier=econ_modifier, coil_max=C2K(coil_max),
                         comfort_weight=comfort_weight)
    for name in names if cycle == "all" else [cycle]:   # refuse before any long work
        sc = make_scenario(name, p.Ts, 303.15, config.stopgo_s)
        if sc.duration_s < econ_cfg.horizon_s:
            raise ConfigError(f"--cycle: cycle {name!r} lasts {sc.duration_s:g} s, shorter "
                              f"than the economic NMPC's horizon ({econ_cfg.horizon_s:g} s, "
                              "--econ-horizon)")
    if choice.kind == "fmu":
        choice.check()
        factory = choice.factory()
    else:
        factory = partial(make_plant, "hifi", config_path=plant_config,
                          **plant_overrides(refrigerant=refrigerant))
    identity = plant_identity(
        vehicle_config(plant_config).replace(**plant_overrides(t_amb, refrigerant))
        if choice.kind == "hifi" else None,
        vehicle_label(plant_config_given) if choice.kind == "hifi" else choice.spec)
    say(identity_line(identity))
    if econ_params is not None:
        econ = EconParams.from_json(econ_params)
        econ_summary = {"source": str(econ_params), "power_map": econ.power_map.quality}
    else:
        say("identifying the econ model (acid excite --model econ + acid fit --model econ)")
        econ, econ_summary = identify_econ(factory, duration_s=identify_duration)
    q = econ.power_map.quality
    say(f"econ model: {econ_summary['source']}; power map RMS error "
        f"{q.get('rms_pct', math.nan):.2f} % (near-steady "
        f"{q.get('steady_rms_pct', math.nan):.2f} %)")
    cycles = "all" if cycle == "all" else [cycle]
    if cycle == "all":
        total, label = len(names), f"cav-study: {len(names)} cycles, {jobs} processes"
    else:
        sc = make_scenario(cycle, p.Ts, 303.15, config.stopgo_s)
        total, label = estimated_steps(config, sc.n, p.Ts), f"cav-study {cycle}"
    with progress_bar(label, total=total) as up:
        result = run_study(p, cycles, config, econ=econ, econ_summary=econ_summary,
                           plant_factory=factory, jobs=jobs, progress=up)

    for name, st in result.cycles.items():
        sc = st.scenario
        rows = []
        for key in CONTROLLERS:
            if key not in st.results:
                continue
            d = st.controller_json(key)
            ms = d["step_ms"]
            rows.append([key, _fmt(d["energy_MJ"], 4), _fmt(d["tail_corrected_energy_MJ"], 4),
                         _fmt(d["saving_tail_corrected_pct"], 2),
                         _fmt(d["saving_vs_best_pi_pct"], 2),
                         _fmt(d["gap_to_best_plan_pct"], 2), f"{K2C(d['mean_T_cab_K']):.3f}",
                         f"{K2C(d['max_T_cab_K']):.2f}", _fmt(d["pmv_mean"], 2),
                         _fmt(d["ppd_mean_pct"], 1), _fmt(d["rh_mean_pct"], 0),
                         "-" if d["rank"] is None else str(d["rank"]),
                         "yes" if d["in_rh_band"] else "outside RH band",
                         "-" if ms is None else f"{ms['median']:.1f}"])
        title = ("the paper's stop-and-go, repeated" if name == STOPGO else name.upper())
        print_table(f"{title}: {sc.duration_s:g} s, mean {sc.v.mean():.1f} m/s, target mean "
                    f"T_cab {K2C(st.target_mean_K):.2f} °C",
                    ["_ctrl", "E MJ", "E corr MJ", "save vs A %", "save vs F %",
                     "gap plan %", "mean °C", "max °C", "PMV", "PPD %", "RH %", "rank",
                     "in band",
                     "ms"], rows)
        line = f"preview's share (E minus D): {_fmt(st.preview_share_points, 3)} points"
        if "F" in st.results:
            line += (f"; F: coil set-point "
                     f"{K2C(st.results['F'].extra['coil_set_point_K']):.2f} °C")
        say(line)
        if "F" in st.results:
            spread = {k: st.charge_back_spread_points(k) for k in ("D", "E")
                      if k in st.results}
            if any(v is not None for v in spread.values()):
                say("the same vs F with every end state charged by F's PI loops instead of the "
                    "paper NMPC: " + ", ".join(
                        f"{k} {_fmt(st.saving_pct(k, ref='F', pi_charge=True), 2)} %"
                        for k in spread) + "; charge-back uncertainty " + ", ".join(
                        f"{k} {_fmt(v, 2)} points" for k, v in spread.items()))
        if st.econ_modifier is not None:
            m = st.econ_modifier
            say("D, E: coil economics corrected from steady plant holds (modifier "
                "adaptation): the model's optimal coil set-point "
                + " -> ".join(f"{K2C(t):.2f}" for t in m["model_optimal_coil_K"]) + " °C")
        if "plan" in st.results:
            bx = st.controller_json("plan")
            say(f"best known plan (perfect information, not a bound): variant "
                f"{bx['best_variant']}, spread of {len(bx['variants'])} independent optima "
                f"{_fmt(st.plan_spread_pct, 2)} %; model {bx['model_energy_MJ']:.4f} MJ, "
                f"replay {_fmt(bx['replay_vs_model_pct'], 2)} % off it, band vs pinned "
                f"T_cab {_fmt(bx['band_vs_pinned_pct'], 3)} %")
        for w in st.warnings:
            warn(f"{name}: {w}")
    say("E: compressor + blower over the cycle; E corr: + tail(end) - tail(start); savings "
        "vs A and vs F and gaps to the plan on E corr; PMV: ISO 7730, 1.2 met, 0.5 clo, "
        "0.2 m/s, radiant = mean of interior and shell; RH band "
        f"{100 * config.rh_band[0]:g}-{100 * config.rh_band[1]:g} % ({RH_BAND_SOURCE}), "
        "rank among the controllers inside it; ms: median controller step")
    if baselines:
        say(f"P's rule: {config.coil_reset.describe()}")

    fig_paths = {}
    if figures:
        from acid.report.cav import energy_figure, trajectory_figure

        fig_paths["energy"] = str(save_figure(energy_figure(result),
                                              out / f"energy_{stem}.png"))
        for name, st in result.cycles.items():
            fig_paths[name] = str(save_figure(trajectory_figure(st), out / f"cav_{name}.png"))
        say(f"figures written to {out}")
    summary = {
        "command": "cav-study", "acid_version": __version__,
        "inputs": {"params": params,
                   "params_sha256": None if params == "paper" else file_sha256(params),
                   "econ_params": None if econ_params is None else str(econ_params),
                   **choice.to_json_dict()},
        **identity, "figures": fig_paths, **result.to_json_dict(),
    }
    write_summary(json_path, summary)
