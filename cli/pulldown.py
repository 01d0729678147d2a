"""``acid pulldown``: the econ model identified through pull-downs, validated on held-out
pull-downs, and the economic NMPC on a pull-down after a soak against the best fixed coil."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import typer

from acid import __version__
from acid_cli._common import (
    check_paths,
    handle_errors,
    print_table,
    require_range,
    say,
    write_summary,
)

#: ``--quick``: short records, one comfort weight, few validation windows (smoke runs)
QUICK = {"old_duration_s": 7200.0, "pulldown_duration_s": 3600.0,
         "held_out_duration_s": 3600.0, "validation_starts": 8}


def _min(s: float) -> str:
    return "never" if not math.isfinite(s) else f"{s / 60:.1f}"


@handle_errors
def pulldown(
    seed: int = typer.Option(0, "--seed", help="Seed of the records (held-out pull-downs: "
                                               "seed + 1000)."),
    t_amb: float = typer.Option(30.0, "--t-amb", help="Ambient of the closed loop, degC."),
    soak: float = typer.Option(40.0, "--soak", help="Soak of the closed loop, degC."),
    cycle: str = typer.Option("udds", "--cycle", help="Drive cycle of the closed loop."),
    quick: bool = typer.Option(False, "--quick", help="Short records (smoke runs)."),
    over_set: bool = typer.Option(
        False, "--set", help="Also judge E against the best fixed coil and the plant's own "
                             "loops over a set of pull-downs (soaks 35-45 degC): knobs tuned "
                             "on training pull-downs, paired intervals on held-out ones."),
    econ_model: str = typer.Option(
        "econ2", "--econ-model", help="E's model on the set: econ2 (a fast and a slow "
                                      "interior node, the slow one carried from the soak) or "
                                      "econ (one interior node)."),
    json_path: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
) -> None:
    """Identify the econ model on today's record and on it plus soak-and-pull-down segments,
    state each model's envelope, validate both on held-out hot- and cold-soak pull-downs
    beside persistence, ARX and subspace (T_cab p90 per prediction time), and run the economic
    NMPC on one cycle from a soak against the best fixed coil at its comfort."""
    from acid.ident.envelope import Envelope
    from acid.studies import pulldown as study

    require_range(seed, "--seed", 0, 2**62, integer=True)
    require_range(t_amb, "--t-amb", 20.0, 50.0, "degC")
    require_range(soak, "--soak", t_amb, 80.0, "degC")
    check_paths(outputs={"--json": json_path})
    from acid.errors import AcidError, ConfigError

    if econ_model not in ("econ", "econ2"):
        raise ConfigError(f"--econ-model must be econ or econ2, got {econ_model!r}")
    from acid.signals import drive_cycle

    try:   # an unknown cycle fails before minutes of excitation
        drive_cycle(cycle, n=1, Ts=5.0)
    except AcidError as exc:
        raise ConfigError(f"--cycle: {exc}") from None
    settings = study.PulldownSettings(seed=seed, T_amb_C=t_amb, soak_C=soak, cycle=cycle,
                                      **(QUICK if quick else {}))
    say("exciting the plant (old record, pull-downs, held-out pull-downs)")
    old, pd, held = study.records(settings)
    say("identifying the old and the new econ model")
    models = study.identify_pair(old, pd, settings.new_skip_s)
    envelopes = {k: Envelope.of(getattr(models, k)) for k in ("old", "new")}
    for k, env in envelopes.items():
        say(f"{k} model's envelope: {env.describe()}")
    say("identifying the two-node econ model (econ2) on the new model's record")
    from acid.studies.pulldown import slow as slow_study

    fit2 = slow_study.identify_new2(models, settings.new_skip_s)
    say(f"econ2 interior: C_int {fit2.params.C_int / 1e3:.1f} kJ/K, C_is {fit2.C_is / 1e3:.1f} "
        f"kJ/K, hA_is {fit2.hA_is:.1f} W/K (time constant {fit2.tau_is_s / 60:.1f} min), "
        f"simulated interior rms {fit2.interior['rms_T_int_K']:.3f} K")
    say("validating on the held-out pull-downs")
    val = study.validate_pair(models, held, settings)
    val2 = slow_study.validate_models(models, fit2, held, settings)
    times2 = list(val2["econ2"]["p90"])
    rows2 = [[name, *(f"{val2[name]['bias'][t]:+.2f} / {val2[name]['p90'][t]:.2f}"
                      for t in times2)] for name in ("econ", "econ2")]
    rows2 += [[name, *(f"{p.get(t, math.nan):.2f}" for t in times2)]
              for name, p in val2["yardsticks"].items()]
    print_table("T_cab on held-out pull-downs, both models identified through pull-downs: "
                "mean error / p90 |error|, K, per prediction time (s)",
                ["predictor", *times2], rows2)
    times = list(val["new"]["model"])
    rows = [[f"{k} model", name, *(f"{val[k][name].get(t, math.nan):.2f}" for t in times)]
            for k in ("old", "new") for name in val[k]
            if isinstance(val[k][name], dict) and name != "held_out_outside"]
    print_table("T_cab p90 |error|, K, on held-out pull-downs, per prediction time (s)",
                ["model", "predictor", *times], rows)
    say(f"closed loop: {cycle} at {t_amb:g} degC from a {soak:g} degC soak")
    loop = study.closed_loop(models, settings, progress=say)
    rows = []
    for r in loop["rows"]:
        for x in (r["E"], r["F"]):
            rows.append([x.name, f"{x.energy_J / 1e6:.3f}", f"{x.discomfort_Kmin:.1f}",
                         f"{x.above_Kmin:.1f}", _min(x.time_to_reach_s),
                         f"{x.mean_T_cab - 273.15:.2f}",
                         f"{r['saving_pct']:+.2f}" if x is r["E"] else ""])
    print_table("Pull-down: E against the best fixed coil at its comfort",
                ["controller", "energy MJ", "K min out", "K min above", "min to 25 degC",
                 "mean T_cab degC", "E below F %"], rows)
    for r in loop["rows"]:
        say(f"{r['E'].name}: {r['E'].envelope_line}")
    for key, pts in loop["equal_comfort"].items():
        for q in pts:
            say(f"E ({key} model) at {q['F']}'s comfort ({q['discomfort_Kmin']:.1f} K min): "
                f"{q['E_J'] / 1e6:.3f} MJ vs {q['F_J'] / 1e6:.3f} MJ ({q['saving_pct']:+.2f} %)")
    judged = None
    if over_set:
        judged = _judge_set(fit2.params, quick, seed, fit2) if econ_model == "econ2" \
            else _judge_set(models.new, quick, seed)
    write_summary(json_path, {
        "command": "pulldown", "acid_version": __version__,
        "settings": dataclasses.asdict(settings),
        "envelopes": {k: e.to_dict() for k, e in envelopes.items()},
        "validation_T_cab_p90_K": val,
        "econ2": {"values": dict(zip(_econ2_names(), fit2.values.tolist(), strict=True)),
                  "stderr": fit2.stderr, "interior": fit2.interior,
                  "validation_T_cab": val2},
        "econ_model": econ_model,
        "front": [dataclasses.asdict(x) for x in loop["front"]],
        "equal_comfort": loop["equal_comfort"],
        "closed_loop": [{"model": r["model"], "saving_pct": r["saving_pct"],
                         "E": dataclasses.asdict(r["E"]), "F": dataclasses.asdict(r["F"])}
                        for r in loop["rows"]],
        **({"set": judged} if judged is not None else {})})


def _econ2_names():
    from acid.models import econ2

    return econ2.model.parameter_names


def _judge_set(params, quick: bool, seed: int, slow=None) -> dict:
    """The set's tuning, held-out table and verdicts (printed), as JSON; ``slow``: E on the
    two-node model (``params`` its econ part)."""
    from acid.studies.pulldown import cases

    say("pull-down set: tuning on the training pull-downs, judging on the held-out ones")
    res = cases.run_set(params, *((cases.QUICK_TRAINING, cases.QUICK_HELD_OUT) if quick
                                  else (cases.TRAINING, cases.HELD_OUT)),
                        seed=seed, progress=say, slow=slow)
    t = res["tuning"]
    say(f"tuned on training: comfort level {t.level_Kmin:.2f} K min (the plant's own loops), "
        f"F coil {t.coil_K - 273.15:.2f} degC, E weight {t.weight:.1f}")
    rows = []
    for r in res["held_out"]:
        for fam in ("own", "F", "E"):
            x = r[fam]
            rows.append([r["case"] if fam == "own" else "", fam, f"{x.energy_J / 1e6:.3f}",
                         f"{x.charged_J / 1e6:.3f}", f"{x.discomfort_Kmin:.1f}",
                         _min(x.time_to_reach_s), f"{x.mean_T_cab - 273.15:.2f}",
                         x.envelope.get("line", "").split(";")[0] if fam == "E" else ""])
    print_table("Held-out pull-downs (charged: the pass + the common continuation)",
                ["case", "controller", "pass MJ", "charged MJ", "K min out",
                 "min to 25 degC", "mean T_cab degC", "envelope"], rows)
    for name, v in res["verdicts"].items():
        say(f"{name}: " + (v.summary() if v is not None else "no case matched"))
    solv = [r[k].solver for r in res["held_out"] for k in ("E", "E_lowered")]
    solv += [r.solver for r in res["training"] if r.family == "E"]
    if solv:
        say(f"E's solver over {len(solv)} runs, {sum(x['steps'] for x in solv)} steps: "
            f"{sum(x['fallback_solver'] for x in solv)} solved by the fallback solver after "
            f"SQP failed, {sum(x['rescues'] for x in solv)} by the convex-QP rescue, "
            f"{sum(x['failed'] for x in solv)} unsolved (last plan or safe input applied)")
    if res["unmatched"]:
        say("E not matched to F's mean cabin on: " + ", ".join(res["unmatched"]))
    return set_summary(res)


def set_summary(res: dict) -> dict:
    """The set's result (:func:`acid.studies.pulldown.cases.run_set`) as strict JSON
    values (NaN and infinity as null)."""
    from acid._io import json_safe

    return json_safe({
        "tuning": dataclasses.asdict(res["tuning"]),
        "held_out": [{k: (dataclasses.asdict(v) if dataclasses.is_dataclass(v) else v)
                      for k, v in r.items()} for r in res["held_out"]],
        "training": [dataclasses.asdict(r) for r in res["training"]],
        "verdicts": {k: (v.to_dict() if v is not None else None)
                     for k, v in res["verdicts"].items()},
        "unmatched": res["unmatched"]})
