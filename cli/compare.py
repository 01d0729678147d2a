"""``acid compare``: controller families judged on held-out scenarios with intervals.

Each family is swept over its one knob on the training scenarios (periodic steady state: the
cycle repeated until the plant's states and pass energy repeat), tuned to the common comfort
level, run on the held-out scenarios and judged by paired differences with a seeded bootstrap
95 % interval and the paired t interval beside it.
"""

from __future__ import annotations

from pathlib import Path

import typer

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
from acid_cli._plant import plant_overrides, refrigerant_option


@handle_errors
def compare(
    cycle: str = typer.Option("udds,sc03,hwfet,us06,stopgo", "--cycle",
                              help="Comma-separated drive cycles ('stopgo': the stop-and-go "
                                   "cycle); each runs at every --t-amb."),
    t_amb: str = typer.Option("30,38", "--t-amb",
                              help="Comma-separated ambients, degC; per cycle a seeded draw "
                                   "sends half to training and half to the held-out set."),
    econ_params: Path | None = typer.Option(
        None, "--econ-params",
        help="Econ-model params from `acid fit --model econ` for the economic NMPC (E); "
             "default: identified here from an `acid excite --model econ` record."),
    identify_duration: float = typer.Option(10800.0, "--identify-duration",
                                            help="Length of that record, s."),
    identify_records: str | None = typer.Option(
        None, "--identify-records",
        help="Comma-separated seeds of the econ model's identification records (default: "
             "--seed). With several, every family is judged once per record and E's verdict "
             "holds only where every record gives the same word."),
    econ: bool = typer.Option(True, "--econ/--no-econ",
                              help="Include the economic NMPC family E."),
    seed: int = typer.Option(0, "--seed", help="Seed of the split and of the bootstrap."),
    quick: bool = typer.Option(False, "--quick",
                               help="Fewer knob values, a 160 s stop-and-go, looser periodic "
                                    "tolerances (0.05 K, 0.2 % of the pass energy)."),
    jobs: int = typer.Option(1, "--jobs", min=1, max=256,
                             help="Worker processes (Dask; 1: in this process)."),
    refrigerant: str | None = refrigerant_option(),
    plant_config: Path | None = typer.Option(None, "--plant-config",
                                             help="TOML configuration of the plant."),
    out: Path | None = typer.Option(None, "--out", help="Folder for fronts.png."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
) -> None:
    """Energy verdicts of E (economic NMPC), P (coil reset), Fs (acid's sampled fixed-coil PI)
    against F (fixed coil on the plant's own loops), and F against the plant's own loops,
    with 95 % intervals over held-out scenarios; knobs tuned on training only."""
    from acid.executor import open_executor
    from acid.studies import compare as cmp

    cycles = [c.strip() for c in cycle.split(",") if c.strip()]
    try:
        ambients = [float(a) for a in t_amb.split(",") if a.strip()]
    except ValueError:
        ambients = []
    require(bool(cycles), "--cycle", "give at least one cycle")
    require(len(ambients) >= 2, "--t-amb", "give at least two ambients, degC, comma-separated")
    require(all(-30.0 <= a <= 55.0 for a in ambients), "--t-amb", "ambients lie in -30..55 degC")
    require_range(seed, "--seed", 0, 2**63 - 1, integer=True)
    # the econ model's identification record: a day or a week of simulation is the bound
    require_range(identify_duration, "--identify-duration", 3600.0, 7 * 86400.0, "s")
    try:
        seeds = ([int(x) for x in identify_records.split(",") if x.strip()]
                 if identify_records is not None else [seed])
    except ValueError:
        seeds = []
    require(bool(seeds) and len(set(seeds)) == len(seeds), "--identify-records",
            "give distinct integer seeds, comma-separated")
    for s in seeds:
        require_range(s, "--identify-records", 0, 2**63 - 1, integer=True)
    require(econ_params is None or identify_records is None, "--identify-records",
            "the econ model comes from --econ-params; give one or the other")
    require(econ or identify_records is None, "--identify-records",
            "without E (--no-econ) no econ model is identified")
    check_paths(inputs={"--econ-params": econ_params, "--plant-config": plant_config},
                outputs={"--json": json_path}, folders={"--out": (out, ("fronts.png",))})
    from acid.studies.cav_study import available_cycles

    for c in cycles:
        require(c in available_cycles(), "--cycle",
                f"unknown cycle {c!r} (available: {', '.join(available_cycles())})")
    line = timed_lines("compare")
    plant_overrides(refrigerant=refrigerant)   # an unknown refrigerant: one line naming it
    sset = cmp.default_set(cycles, ambients, seed=seed, stopgo_s=160.0 if quick else 800.0,
                           vehicle=None if plant_config is None else str(plant_config),
                           refrigerant=refrigerant)
    say(f"training: {', '.join(s.name for s in sset.training)}")
    say(f"held out: {', '.join(s.name for s in sset.held_out)} ({sset.rule})")
    fams = cmp.families(quick=quick, econ=econ)
    results = []
    with open_executor(jobs, notice=line) as ex:
        for s in seeds if econ and econ_params is None else [seed]:
            params = None
            if econ and econ_params is not None:
                from acid.models.econ_params import EconParams

                params = EconParams.from_json(econ_params)
            elif econ:
                from acid.studies.cav_study import default_plant_factory, identify_econ

                line(f"identifying the econ model ({identify_duration:g} s record, seed {s})")
                params, _ = identify_econ(default_plant_factory(), identify_duration, seed=s)
            results.append(cmp.compare(sset, fams, cmp.QUICK if quick else cmp.RunSettings(),
                                       econ=params, seed=seed,
                                       executor=None if jobs == 1 else ex, progress=line))
            _print_result(results[-1], fams, sset, seed,
                          f"econ model of record seed {s}: " if len(seeds) > 1 else "")
    if len(results) > 1:
        rows = []
        for cand in ("E", "E" + cmp.MATCHED):
            word, vs = cmp.across_records(results, cand, "F")
            rows.append([f"{cand} vs F", *(f"{v.mean_pct:+.2f} [{v.boot_lo:+.2f}, "
                                           f"{v.boot_hi:+.2f}] {v.word}" for v in vs), word])
        print_table(f"E judged with econ models of {len(seeds)} identification records",
                    ["_candidate vs baseline", *(f"_record seed {s}" for s in seeds),
                     "_across records"], rows)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        cmp.plot_fronts(results[0], out / "fronts.png")
        say(f"fronts written to {out / 'fronts.png'}")
    write_summary(json_path, results[0].to_dict() if len(results) == 1 else {
        "records": {str(s): r.to_dict() for s, r in zip(seeds, results, strict=True)},
        "across_records": {cand: cmp.across_records(results, cand, "F")[0]
                           for cand in ("E", "E" + cmp.MATCHED)}})


def _print_result(result, fams, sset, seed: int, prefix: str) -> None:
    """The families' tuned knobs and the verdicts of one comparison."""
    say(f"{prefix}comfort level: {result.comfort_level_Kmin:.2f} K min per pass outside "
        f"{result.settings['T_low'] - 273.15:g}-{result.settings['T_high'] - 273.15:g} degC "
        "(the plant's own loops on training)")
    rows = []
    for f in fams:
        k = result.tuned[f.key]
        pt = min((p for p in result.fronts if p.family == f.key),
                 key=lambda p: abs(p.knob - k) if k == k else 0.0)
        knob = "-" if k != k else (f"{k - 273.15:.2f} degC" if f.knob.endswith(", K")
                                   else f"{k:.3g} {f.knob.rsplit(', ', 1)[-1]}")
        rows.append([f.key, f.label, knob, f"{pt.energy_J / 1e6:.3f}",
                     f"{pt.discomfort_Kmin:.2f}", f"{100 * pt.rh_mean:.1f}"])
    print_table(f"{prefix}families on training (tuned knob, nearest swept point)",
                ["_family", "_what", "knob", "MJ/pass", "K min", "RH %"], rows)
    print_table(f"{prefix}verdicts on held out ({len(sset.held_out)} scenarios, seed {seed})",
                ["_candidate vs baseline", "saving %", "bootstrap 95 %", "paired t 95 %",
                 "dK min", "dT_cab K", "_verdict", "1 pass own %", "1 pass PI %"],
                [[f"{v.candidate} vs {v.baseline}", f"{v.mean_pct:+.2f}",
                  f"[{v.boot_lo:+.2f}, {v.boot_hi:+.2f}]", f"[{v.t_lo:+.2f}, {v.t_hi:+.2f}]",
                  f"{v.discomfort_gap_Kmin:+.2f}", f"{v.T_cab_gap_K:+.2f}", v.word,
                  f"{v.single_own_pct:+.2f}", f"{v.single_pi_pct:+.2f}"]
                 if v.scenarios else [f"{v.candidate} vs {v.baseline}", *"-----", v.word, "-",
                                      "-"]
                 for v in result.verdicts])
    say("saving % and its intervals: periodic steady state; 1 pass: the first pass from the "
        "common start, its end state charged by a common continuation (the plant's own "
        "loops, or acid's PI), mean over the held-out set: figures beside the verdict, not "
        "verdicts")
    off = sorted({(r.family, r.scenario, n) for r in result.held_out for n in r.extrapolated})
    for fam in sorted({f for f, _, _ in off}):
        runs = sorted({sc for f, sc, _ in off if f == fam})
        names = sorted({n for f, _, n in off if f == fam})
        say(f"{fam} planned outside its econ model's identification data ({', '.join(names)}) "
            f"on {len(runs)} held-out run(s): {', '.join(runs)}")
