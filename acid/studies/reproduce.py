"""``acid reproduce``: the paper end to end, from our own plant, model, fit and controller.

Stages (cached by their inputs, see :mod:`acid.pipeline`):

    sweep     Table I and Fig. 3: 600 s at 0..25 m/s with the nominal controller, on the
              paper vehicle (the Table I calibration) with acid's default vehicle beside it
    excite    random excitation of the high-fidelity plant (estimation + held-out parts)
    fit       eqs. 1-3 and 5 identified from the estimation part (output error, from LS)
    validate  60 open-loop predictions of 300 steps on the held-out part (Figs. 5-6)
    mpc       acid mpc-check with the identified parameters (Figs. 7-10, CAV saving)
    econ      beyond the paper: the econ model family identified from an `acid excite
              --model econ` record and validated beside the paper's model on the same data
    cav       beyond the paper, "where the energy is": acid cav-study on drive cycles
              (A paper NMPC, B ICM, D/E economic NMPC without/with preview, P/F PI baselines,
              the best known plan)
    plant_check  the high-fidelity plant's credentials against published references
    heating   winter: the heating plant's credentials that need no logs and the
              whole year at three ambients (acid's own checks, not the paper's)

``sweep`` and the chain excite -> fit -> (validate, mpc) are independent, so ``--jobs 2``
runs them side by side. Each stage returns its typed result (:mod:`acid.claims.results`) as
JSON and lists its figures in ``figures.json``; the report (``report.html`` +
``summary.json``) reads them back, and every verdict in it comes from the claims registry
(:mod:`acid.claims`): the paper's value, where acid measures it and the rule.
"""

from __future__ import annotations

import dataclasses
import json
import math
import platform
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING

from acid import __version__
from acid._io import write_json
from acid.claims import ClaimVerdict, evaluate, summary_claims
from acid.claims.options import ReproduceOptions, is_quick, run_mode
from acid.claims.registry import ENERGY_CYCLES
from acid.claims.results import (
    CavStudyStage,
    EconStage,
    ExcitationStage,
    FitStage,
    MpcStage,
    PlantCheckStage,
    StudyResults,
    SweepStage,
    ValidationStage,
)
from acid.pipeline import Stage, StageOutcome
from acid.plant.vehicles import DEFAULT_VEHICLE, PAPER_VEHICLE

if TYPE_CHECKING:
    from acid.report.html import ReportFigure


# matplotlib and the report load when a stage or the report needs them, not on import: `acid
# claims` reads the study's options (``run_mode``) from here
def save_report_figure(*args, **kwargs):
    """``acid.report.figures.save_report_figure`` (imported on first use)."""
    from acid.report.figures import save_report_figure as save

    return save(*args, **kwargs)


def write_figure_index(*args, **kwargs):
    """``acid.report.figures.write_figure_index`` (imported on first use)."""
    from acid.report.figures import write_figure_index as write

    return write(*args, **kwargs)


# --------------------------------------------------------------------- stage bodies
# Each stage returns the JSON form of its typed result (``acid.claims.results``) and lists
# its figures, with captions and line-visibility audits, in ``figures.json``.
def stage_sweep(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """Table I / Fig. 3 on the paper vehicle, acid's default vehicle beside it."""
    from acid.plant.sweep import speed_sweep
    from acid.plant.vehicles import vehicle_config
    from acid.report.plant import sweep_figure

    vehicle, other = config["vehicle"], config["beside"]
    res = speed_sweep(vehicle_config(vehicle), duration=config["duration_s"],
                      progress=lambda i, n: progress(i, 2 * n))
    beside = speed_sweep(vehicle_config(other), duration=config["duration_s"],
                         progress=lambda i, n: progress(n + i, 2 * n))
    write_figure_index(workdir, [save_report_figure(
        sweep_figure(res, beside, (f"{vehicle} vehicle", f"{other} vehicle")), workdir,
        "fig3_speed_sweep", f"Fig. 3 and Table I: speed sensitivity with the nominal "
        f"controller on the {vehicle} vehicle (Table I calibration), energy of acid's "
        f"{other} vehicle beside it")])
    d = res.to_json_dict()
    b = beside.to_json_dict()
    d.update(vehicle=vehicle, beside={"vehicle": other, **{k: b[k] for k in (
        "energy_MJ", "energy_MJ_per_km", "energy_with_fan_MJ", "ratio_last_first",
        "ratio_last_first_with_fan", "plant_config")}})
    write_json(workdir / "sweep.json", d)
    return SweepStage.of(res, vehicle, beside, other).to_json_dict()


def stage_excite(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """APRBS excitation of the high-fidelity plant at 0.2 Hz (paper section II-B-2)."""
    from acid.excite import ExcitationSpec, excite
    from acid.plant import make_plant

    spec = ExcitationSpec(duration=config["duration_s"], seed=config["seed"])
    ds = excite(make_plant("hifi"), spec, progress=progress)
    ds.to_hdf5(workdir / "excitation.h5", created="reproducible")
    return ExcitationStage(samples=len(ds), duration_s=float(ds.duration), seed=config["seed"],
                           T_cab_range_degC=(float(ds["T_cab"].min()),
                                             float(ds["T_cab"].max()))).to_json_dict()


def stage_fit(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """Identify eqs. 1-3 and 5 (the paper's declaration) on the estimation part of the
    excitation record."""
    from acid.data import MODEL_CHANNELS, Dataset
    from acid.ident.fit import fit_model, provenance
    from acid.models import load
    from acid.models.params import eta_cop_of, fitted

    ds = Dataset.from_hdf5(inputs["excite"] / "excitation.h5", require=MODEL_CHANNELS)
    est, _ = ds.split(config["estimation_fraction"])
    model = load("paper")
    ls = fit_model(model, est, "ls")
    progress(1, 2)
    res = fit_model(model, est, config["method"])
    progress(2, 2)
    prov = dict(provenance(est, res.method), estimation_fraction=config["estimation_fraction"])
    params = fitted(res, name=f"acid-{config['method']}", provenance=prov)
    res.write(workdir / "params.json", model, prov,
              extra={**params.to_json_dict(), "fit_ls": ls.to_json_dict()})
    return FitStage.of(res, ls, params, eta_cop_of(est)).to_json_dict()


def stage_validate(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """60 starts x 300 steps on the held-out part (paper Figs. 5-6)."""
    from acid.data import MODEL_CHANNELS, Dataset
    from acid.ident.validate import validate
    from acid.models.params import ModelParams
    from acid.report.validation import error_figure, prediction_figure, yardstick_figure

    ds = Dataset.from_hdf5(inputs["excite"] / "excitation.h5", require=MODEL_CHANNELS)
    params = ModelParams.from_json(inputs["fit"] / "params.json")
    held_out = 1.0 - config["estimation_fraction"]
    res = validate(ds, params, starts=config["starts"], horizon=config["horizon"],
                   held_out_fraction=held_out, yardsticks=config.get("yardsticks", True))
    progress(1, 1)
    figs = [save_report_figure(prediction_figure(res), workdir, "fig5_prediction",
                               f"Fig. 5: a {res.horizon}-step prediction against the plant"),
            save_report_figure(error_figure(res), workdir, "fig6_errors",
                               "Fig. 6: prediction errors of all starts vs time")]
    if res.yardsticks:
        figs.append(save_report_figure(
            yardstick_figure(res), workdir, "fig6b_yardsticks",
            "Beyond the paper: the model's RMSE over the starts beside persistence, ARX and "
            "subspace yardsticks fitted on the estimation part, same windows"))
    write_figure_index(workdir, figs)
    write_json(workdir / "validation.json", res.to_json_dict())
    return ValidationStage.of(res).to_json_dict()


#: captions of the mpc-check figures, by file stem
MPC_CAPTIONS = {
    "fig7_model": "Fig. 7: NMPC in closed loop with the control-oriented model",
    "fig8_plant": "Fig. 8: NMPC in closed loop with the high-fidelity plant",
    "fig9_cav_bound": "Fig. 9: previewed stop-and-go speed and the ICM bound on T_cab",
    "fig10_cav_comparison": "Fig. 10: Case 1 (ICM) vs Case 2 (constant bound)",
}


def stage_mpc(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """acid mpc-check with the identified parameters (paper Figs. 7-10)."""
    from acid.models.params import ModelParams
    from acid.report.mpc import mpc_figures
    from acid.studies.mpc_check.scenarios import mpc_check

    params = ModelParams.from_json(inputs["fit"] / "params.json")
    res = mpc_check(params, timing_repeats=config["timing_repeats"], progress=progress)
    write_figure_index(workdir, [
        save_report_figure(fig, workdir, stem, MPC_CAPTIONS.get(stem, stem.replace("_", " ")))
        for stem, fig in mpc_figures(res.scenarios).items()])
    write_json(workdir / "check.json", res.to_json_dict())
    return MpcStage.of(res).to_json_dict()


def stage_econ(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """Beyond the paper: the econ model identified and validated beside the paper's model.

    Both models are fitted on the estimation part of one ``acid excite --model econ`` record
    (the paper's by output error) and validated by the same study on its held-out part.
    """
    import warnings

    from acid.excite import excite, spec_for_model
    from acid.ident.econ import identify
    from acid.ident.fit import fit_model
    from acid.ident.validate import validate
    from acid.models.params import fitted
    from acid.plant import make_plant
    from acid.report.validation import error_figure

    ds = excite(make_plant("hifi"), spec_for_model("econ", duration=config["duration_s"],
                                                   seed=config["seed"]))
    progress(1, 4)
    est, _ = ds.split(config["estimation_fraction"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        econ = identify(est)
        progress(2, 4)
        paper_fit = fitted(fit_model("paper", est, "oe"), provenance={"data_file": ds.source})
    econ.params.to_json(workdir / "econ_params.json", extra={"fit": econ.to_json_dict()})
    kw = {"starts": config["starts"], "horizon": config["horizon"], "yardsticks": False,
          "held_out_fraction": 1.0 - config["estimation_fraction"]}
    val_econ, val_paper = validate(ds, econ.params, **kw), validate(ds, paper_fit, **kw)
    progress(4, 4)
    write_figure_index(workdir, [save_report_figure(
        error_figure(val_econ), workdir, "fig_econ_errors",
        "Beyond the paper: prediction errors of the econ model (interior and shell "
        "predicted), the study of Fig. 6")])
    return EconStage.of(ds.duration, econ.power_map_quality, val_econ,
                        val_paper).to_json_dict()


def _cav_setup(inputs: dict, config: dict):
    """The cav study's parameters, econ model and options from the stages' files."""
    from acid.control.econ.nmpc import EconNMPCConfig
    from acid.models.econ_params import EconParams
    from acid.models.params import ModelParams
    from acid.studies.cav_study import StudyConfig

    params = ModelParams.from_json(inputs["fit"] / "params.json")
    econ = EconParams.from_json(inputs["econ"] / "econ_params.json")
    n = int(round(config["econ_horizon_s"] / params.Ts))
    variants = config.get("plan_variants")
    cfg = StudyConfig(warmup_s=config["warmup_s"], tail_s=config["tail_s"],
                      econ=EconNMPCConfig(intervals=(params.Ts,) * n,
                                          compiled="auto" if config["compiled"] else False),
                      tol_K=config.get("tol_K", StudyConfig.tol_K),
                      plan_variants=None if variants is None else tuple(variants))
    return params, econ, cfg


#: the file a cav-study cycle task leaves for the ``cav`` stage (the cycle's full result)
CAV_CYCLE_FILE = "cycle_study.pkl"


def cav_cycle_stage(cycle: str) -> str:
    """The stage name of one cycle of the cav study."""
    return f"cav_{cycle}"


def stage_cav_cycle(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """One drive cycle of the cav study (every controller on it): an independent task, so
    the cycles run side by side on the workers."""
    import pickle

    from acid.studies.cav_study import (
        default_plant_factory,
        estimated_steps,
        make_scenario,
        study_cycle,
    )

    params, econ, cfg = _cav_setup(inputs, config)
    name = config["cycle"]
    total = estimated_steps(cfg, make_scenario(name, params.Ts, 303.15, cfg.stopgo_s).n,
                            params.Ts)
    done = [0]

    def tick(steps):
        done[0] += steps
        progress(min(done[0], total), total)

    st = study_cycle(params, econ, name, cfg, default_plant_factory(), progress=tick)
    progress(total, total)
    (workdir / CAV_CYCLE_FILE).write_bytes(pickle.dumps(st, protocol=pickle.HIGHEST_PROTOCOL))
    return {"cycle": name}


def stage_cav(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """Beyond the paper, where the energy is: ``acid cav-study`` on drive cycles, from the
    cycles' tasks (``stage_cav_cycle``)."""
    import pickle

    from acid.report.cav import CONTROLLER_COLORS as CONTROLLER_COLORS  # the trajectories' colours
    from acid.report.cav import trajectory_figure
    from acid.report.energy_bars import cav_energy_bars, difference_figure
    from acid.studies.cav_study import CONTROLLERS, study_result

    params, econ, cfg = _cav_setup(inputs, config)
    cycles, seconds = {}, 0.0
    for name in config["cycles"]:
        folder = inputs[cav_cycle_stage(name)]
        cycles[name] = pickle.loads((folder / CAV_CYCLE_FILE).read_bytes())
        record = json.loads((folder / "stage.json").read_text())
        seconds += float(record.get("seconds", 0.0))
    res = study_result(params, econ, cycles, cfg,
                       {"source": "stage econ", "power_map": econ.power_map.quality},
                       seconds)
    progress(1, 2)
    figs = [save_report_figure(
        difference_figure(cav_energy_bars(res), CONTROLLERS, CONTROLLER_COLORS), workdir,
        "energy", "Where the energy is: each controller's energy against the best simple "
                  "controller of each cycle (the fixed-coil PI F, the reset PI P or the paper "
                  "NMPC A, named under the cycle), %, at equal mean cabin temperature, end "
                  "state charged back")]
    figs += [save_report_figure(trajectory_figure(st), workdir, f"cav_{name}",
                                f"Where the energy is, {name.upper()}: paper NMPC (A), "
                                "economic NMPC with preview (E), the best known plan replayed")
             for name, st in res.cycles.items()]
    write_figure_index(workdir, figs)
    d = res.to_json_dict()
    write_json(workdir / "cav_study.json", d)
    return CavStudyStage.of(d).to_json_dict()


#: captions of the plant-check figures, by file stem
PLANT_CHECK_CAPTIONS = {
    "plant_check_energy": "Plant credentials: (a) Table I with and without the condenser fan, "
                          "(f) steady COP map",
    "plant_check_service": "Plant credentials: (d) idle pressures in a service chart's bands, "
                           "(e) pull-down against the JAF test",
}


# ------------------------------------------------------------------ the comparison engine
#: the file an engine task leaves for the next (its periodic runs, pickled)
ENGINE_RUNS_FILE = "runs.pkl"
#: the file of a best-known-plan task (every formulation and start, replayed)
PLANS_FILE = "plans.json"


def _engine_setup(inputs: dict, config: dict):
    """(scenario set, families, run settings, econ model) of the engine's tasks: ``acid
    compare``'s defaults (``--quick``'s in a quick run) with the reproduction's econ model."""
    from acid.models.econ_params import EconParams
    from acid.studies import compare as cmp

    quick = bool(config["quick"])
    sset = cmp.default_set(config["cycles"], config["ambients_C"], seed=config["seed"],
                           stopgo_s=160.0 if quick else 800.0)
    econ = EconParams.from_json(inputs["econ"] / "econ_params.json")
    fams = cmp.families(quick=quick)
    if quick:   # a smoke run: E at one comfort weight (its front is a point)
        fams = tuple(dataclasses.replace(f, knobs=f.knobs[-1:]) if f.key == "E" else f
                     for f in fams)
    # a smoke run: --quick's tolerances, at most 12 passes (the short stop-and-go's slow
    # interior mode does not settle in them: such runs are reported as not converged)
    return sset, fams, dataclasses.replace(cmp.QUICK, max_passes=12) if quick \
        else cmp.RunSettings(), econ


def engine_scenarios(config: dict) -> tuple[list[str], list[str]]:
    """The training and held-out scenario names of the engine (no model needed)."""
    from acid.studies import compare as cmp

    sset = cmp.default_set(config["cycles"], config["ambients_C"], seed=config["seed"])
    return [s.name for s in sset.training], [s.name for s in sset.held_out]


def engine_stage(kind: str, scenario: str) -> str:
    """The stage name of one engine task: ``kind`` "train" or "held" on ``scenario``."""
    return f"engine_{kind}_" + scenario.replace("@", "_").replace(".", "p")


def _runs_on(tasks: list[tuple], progress) -> list:
    from acid.studies.compare import periodic_run

    out = []
    for i, t in enumerate(tasks):
        out.append(periodic_run(*t))
        progress(i + 1, len(tasks))
    return out


def _pickle(path: Path, obj) -> None:
    import pickle

    path.write_bytes(pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))


def _unpickle(path: Path):
    import pickle

    return pickle.loads(path.read_bytes())


def stage_engine_train(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """One training scenario of the engine: its common start, then every family at every
    knob at periodic steady state (``acid.studies.compare.training_tasks``)."""
    from acid.studies import compare as cmp

    sset, fams, settings, econ = _engine_setup(inputs, config)
    sc = next(s for s in sset.training if s.name == config["scenario"])
    warm = _runs_on(cmp.warm_tasks([sc], fams, settings), lambda i, n: None)[0]
    tasks = cmp.training_tasks([sc], fams, settings, econ, {sc.name: warm.end})
    runs = _runs_on(tasks, progress)
    _pickle(workdir / ENGINE_RUNS_FILE, [(t[1], t[2], r) for t, r in zip(tasks, runs,
                                                                         strict=True)])
    return {"scenario": sc.name, "runs": len(runs),
            "period_two": sum(r.period == 2 for r in runs)}


def _engine_tuning(inputs: dict, config: dict, sset, fams, settings):
    """The engine's :class:`~acid.studies.compare.Tuning` from the training tasks' runs."""
    from acid.studies import compare as cmp

    keys, runs = [], []
    for sc in sset.training:
        for family, knob, r in _unpickle(inputs[engine_stage("train", sc.name)]
                                         / ENGINE_RUNS_FILE):
            keys.append((sc, family, knob))
            runs.append(r)
    return cmp.tune(fams, keys, runs, settings)


def stage_engine_held(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """One held-out scenario of the engine: every family at its knob tuned on training
    (and at a lowered target, to match F's mean cabin temperature)."""
    from acid.studies import compare as cmp

    sset, fams, settings, econ = _engine_setup(inputs, config)
    tuning = _engine_tuning(inputs, config, sset, fams, settings)
    sc = next(s for s in sset.held_out if s.name == config["scenario"])
    warm = _runs_on(cmp.warm_tasks([sc], fams, settings), lambda i, n: None)[0]
    tasks = cmp.held_out_tasks([sc], fams, tuning, settings, econ, {sc.name: warm.end},
                               match_mean=config.get("match_mean", True))
    runs = _runs_on(tasks, progress)
    _pickle(workdir / ENGINE_RUNS_FILE, [(len(t) == 7, r) for t, r in zip(tasks, runs,
                                                                          strict=True)])
    return {"scenario": sc.name, "runs": len(runs),
            "period_two": sum(r.period == 2 for r in runs)}


def plan_stage(cycle: str) -> str:
    """The stage name of the best known plan on ``cycle``'s held-out scenario."""
    return f"plan_{cycle}"


def stage_plan(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """The best known plan on one held-out scenario of the engine: the cyclic whole-cycle
    optimum on the econ model in two formulations (direct, multiple shooting) from several
    seeded starts, each replayed on the plant at periodic steady state at the engine's mean
    cabin temperature (``acid.control.econ.periodic_plan``)."""
    from acid.control.econ.best_plan import PlanConfig
    from acid.control.econ.periodic_plan import periodic_plans
    from acid.plant.hifi import HifiPlant

    sset, _, settings, econ = _engine_setup(inputs, config)
    sc = next(s for s in sset.held_out if s.cycle == config["cycle"])
    drive, cfg = sc.drive(), sc.plant_config()
    plans = periodic_plans(econ, drive.v, drive.T_amb,
                           PlanConfig(T_mean=settings.T_set, T_low=settings.T_low,
                                      T_high=settings.T_high),
                           plant_factory=lambda: HifiPlant(cfg, mode="direct"),
                           n_random=1, seed=config["seed"])
    write_json(workdir / PLANS_FILE, {"scenario": sc.name, **plans.to_dict()})
    progress(1, 1)
    return {"scenario": sc.name, "plan_kJ": plans.winner.energy_J / 1e3,
            "spread_pct": plans.spread_pct}


def stage_engine(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """The engine's verdicts on the held-out scenarios (``acid compare``), from its tasks."""
    from acid.claims.results import EngineStage
    from acid.studies import compare as cmp

    sset, fams, settings, _ = _engine_setup(inputs, config)
    tuning = _engine_tuning(inputs, config, sset, fams, settings)
    tasks, runs = [], []
    for sc in sset.held_out:
        for charged, r in _unpickle(inputs[engine_stage("held", sc.name)] / ENGINE_RUNS_FILE):
            tasks.append((None,) * (7 if charged else 6))
            runs.append(r)
    res = cmp.assemble(sset, fams, settings, tuning, tasks, runs, seed=config["seed"],
                       match_mean=config.get("match_mean", True))
    write_json(workdir / "compare.json", res.to_dict())
    plans = {c: json.loads((inputs[plan_stage(c)] / PLANS_FILE).read_text())
             for c in config.get("plan_cycles", ())}
    for p in plans.values():   # E at F's mean cabin temperature on the plan's scenario
        by = {r.family: r for r in res.held_out if r.scenario == p["scenario"]}
        if {"E", "E" + cmp.LOWERED, "F"} <= set(by):
            m = cmp.match_to_mean(by["E"], by["E" + cmp.LOWERED], by["F"].mean_T_cab)
            p["E_at_F_kJ"] = (m or by["E"]).energy_J / 1e3
    write_figure_index(workdir, [save_report_figure(
        cmp.fronts_figure(res), workdir, "engine_fronts",
        "The comparison engine: energy per pass against discomfort on the training "
        "scenarios, one line per controller family swept over its knob (periodic steady "
        "state); the dashed line is the common comfort level")])
    progress(1, 1)
    return EngineStage.of(res, plans).to_json_dict()


def stage_plant_check(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """The plant's credentials, each beside a published reference (``acid plant-check``)."""
    from acid.report.plant import plant_check_figures
    from acid.studies.credentials.plant import build_plant, plant_check

    res = plant_check(build_plant("hifi"), progress=progress)
    write_figure_index(workdir, [
        save_report_figure(fig, workdir, stem, PLANT_CHECK_CAPTIONS.get(stem, stem))
        for stem, fig in plant_check_figures(res).items()])
    d = res.to_json_dict()
    write_json(workdir / "plant_check.json", d)
    return PlantCheckStage.of(d).to_json_dict()


#: the whole-year points the report's heating section shows: three ambients (heating with
#: and without the heat pump, and cooling), one cycle, acid's default vehicle
HEATING_YEAR = {"ambients_C": [-10.0, 5.0, 30.0], "cycles": ["udds"], "vehicles": ["default"]}


def stage_heating(workdir: Path, inputs: dict, config: dict, progress) -> dict:
    """Winter: the heating plant's credentials that need no logs (``acid
    heating-check``) and the whole year at three ambients (``acid year-sweep``), with its
    figure. acid's own checks; a few seconds of CPU."""
    from acid.claims.results import HeatingStage, PlantCredential, YearShare
    from acid.plant.year import year_sweep
    from acid.report.year import year_figure
    from acid.studies.credentials.heating import heating_check
    from acid.units import K2C

    check = heating_check(None, progress=lambda: progress(1, 3))
    year = year_sweep(config["ambients_C"], config["cycles"], config["vehicles"],
                      progress=lambda done, total, _label: progress(2, 3))
    write_figure_index(workdir, [save_report_figure(
        year_figure(year), workdir, "year_share",
        "Winter and summer: the share of range the climate costs against ambient (one pass "
        "of the cycle from a soak; heat pump and coolant heater alone below the "
        f"switch-over at {year.switch_C:g} degC, the A/C above)")])
    progress(3, 3)
    rows = tuple(PlantCredential(name=r.name, group=r.group, reference=r.reference,
                                 unit=r.unit, value=math.nan if r.value is None else r.value,
                                 passed=r.passed, note=r.note, info=r.info)
                 for r in check.rows if r.passed is not None or r.info)
    points = tuple(YearShare(T_amb_C=K2C(p.T_amb_K), cycle=p.cycle, vehicle=p.vehicle,
                             heating=p.heating, E_climate_kWh=p.E_climate_kWh,
                             E_heater_kWh=p.E_heater_kWh, share=p.share,
                             T_cab_mean_C=K2C(p.T_cab_mean_K)) for p in year.points)
    return HeatingStage(passed=all(r.passed is not False for r in rows), checks=rows,
                        year=points, switch_over_C=year.switch_C).to_json_dict()


def engine_stages(opts: ReproduceOptions) -> list[Stage]:
    """The comparison engine as tasks: one per training scenario, one per held-out scenario
    (after every training task: the knobs are tuned on all of them), then the verdicts."""
    from acid.studies.compare import DEFAULT_AMBIENTS_C, DEFAULT_CYCLES

    config = {"quick": opts.engine_quick, "cycles": list(opts.engine_cycles or DEFAULT_CYCLES),
              "ambients_C": list(DEFAULT_AMBIENTS_C), "seed": opts.excite_seed}
    if not opts.engine_match_mean:   # (the study's keep their cache keys)
        config["match_mean"] = False
    training, held = engine_scenarios(config)
    train = [Stage(engine_stage("train", n), f"comparison engine, training on {n}",
                   stage_engine_train, {**config, "scenario": n}, depends=("econ",))
             for n in training]
    judged = [Stage(engine_stage("held", n), f"comparison engine, held out {n}",
                    stage_engine_held, {**config, "scenario": n},
                    depends=("econ", *(s.name for s in train))) for n in held]
    # the best known plan on the held-out scenarios of the energy study's cycles
    plan_cycles = [c for c in ENERGY_CYCLES if c in config["cycles"]]
    plans = [Stage(plan_stage(c), f"best known plan (periodic), {c.upper()}", stage_plan,
                   {**config, "cycle": c}, depends=("econ",)) for c in plan_cycles]
    return [*train, *judged, *plans, Stage(
        "engine", "comparison engine: verdicts on held-out scenarios", stage_engine,
        {**config, "plan_cycles": plan_cycles},
        depends=("econ", *(s.name for s in train), *(s.name for s in judged),
                 *(s.name for s in plans)))]


#: CPU seconds of each stage in a cold full run (measured, 2 workers; only their ratios
#: matter: they order the work, the longest remaining chain first, see
#: ``acid.pipeline.chain_costs``)
STAGE_COST_S = {
    "sweep": 2.2, "excite": 1.6, "fit": 0.8, "validate": 4.3, "mpc": 5.1, "econ": 9.1,
    "cav_udds": 44.7, "cav_sc03": 27.9, "cav": 3.8, "plant_check": 6.4, "heating": 4.2,
    "engine_train_udds_30C": 21.3, "engine_train_sc03_30C": 16.1, "engine_train_hwfet_30C": 47.0,
    "engine_train_us06_38C": 18.0, "engine_train_stopgo_38C": 17.6, "engine_held_udds_38C": 11.4,
    "engine_held_sc03_38C": 10.6, "engine_held_hwfet_38C": 10.8, "engine_held_us06_30C": 39.1,
    "engine_held_stopgo_30C": 19.9, "plan_udds": 15.0, "plan_sc03": 9.4, "engine": 0.3,
}


def build_stages(opts: ReproduceOptions) -> list[Stage]:
    """The stage graph of the reproduction (the cav study's cycles are independent tasks),
    each stage with its measured cost (:data:`STAGE_COST_S`: the order of the work)."""
    return [dataclasses.replace(s, cost=STAGE_COST_S.get(s.name, 10.0))
            for s in _stages(opts)]


def _stages(opts: ReproduceOptions) -> list[Stage]:
    cav = {"warmup_s": opts.cav_warmup_s, "tail_s": opts.cav_tail_s,
           "econ_horizon_s": opts.econ_horizon_s, "compiled": opts.econ_compiled}
    if opts.cav_tol_K != ReproduceOptions.cav_tol_K or opts.cav_plan_variants is not None:
        # (a smoke run's sizes; the study's keep their cache keys)
        cav.update(tol_K=opts.cav_tol_K, plan_variants=opts.cav_plan_variants)
    return [
        Stage("sweep", "speed sweep (Table I on the paper vehicle, Fig. 3)", stage_sweep,
              {"duration_s": opts.sweep_duration_s, "vehicle": PAPER_VEHICLE,
               "beside": DEFAULT_VEHICLE}),
        Stage("excite", "excitation of the high-fidelity plant", stage_excite,
              {"duration_s": opts.excite_duration_s, "seed": opts.excite_seed}),
        Stage("fit", "identification (eqs. 1-3, 5)", stage_fit,
              {"method": opts.fit_method, "estimation_fraction": opts.estimation_fraction},
              depends=("excite",)),
        Stage("validate", "validation, 300-step predictions (Figs. 5-6)", stage_validate,
              {"starts": opts.starts, "horizon": opts.horizon,
               "estimation_fraction": opts.estimation_fraction, "yardsticks": True},
              depends=("excite", "fit")),
        Stage("mpc", "NMPC checks (Figs. 7-10)", stage_mpc,
              {"timing_repeats": opts.timing_repeats}, depends=("fit",)),
        Stage("econ", "beyond the paper: econ model, identified and validated", stage_econ,
              {"duration_s": opts.econ_duration_s, "seed": opts.excite_seed,
               "estimation_fraction": opts.estimation_fraction, "starts": opts.starts,
               "horizon": opts.horizon}),
        *[Stage(cav_cycle_stage(c), f"where the energy is, {c.upper()}", stage_cav_cycle,
                {**cav, "cycle": c}, depends=("fit", "econ")) for c in opts.cav_cycles],
        Stage("cav", "where the energy is: " + ", ".join(c.upper() for c in opts.cav_cycles),
              stage_cav, {**cav, "cycles": list(opts.cav_cycles)},
              depends=("fit", "econ", *(cav_cycle_stage(c) for c in opts.cav_cycles))),
        *engine_stages(opts),
        Stage("plant_check", "plant credentials (acid plant-check)", stage_plant_check, {}),
        Stage("heating", "winter: heating credentials and the year", stage_heating, HEATING_YEAR),
    ]


# --------------------------------------------------------------------------- report
def study_results(outcomes: dict[str, StageOutcome]) -> StudyResults:
    """The typed results of the stages (read back from their cached summaries)."""
    return StudyResults.from_summaries({k: o.summary for k, o in outcomes.items()})


def report_figures(outcomes: dict[str, StageOutcome],
                   order: list[str] | None = None) -> list[ReportFigure]:
    """Every figure the stages listed, in stage ``order`` (default: as given)."""
    from acid.report.figures import read_figure_index
    from acid.report.html import ReportFigure

    names = [n for n in (order or []) if n in outcomes]
    names += [n for n in outcomes if n not in names]
    return [ReportFigure(outcomes[n].workdir / r.file, r) for n in names
            for r in read_figure_index(outcomes[n].workdir)
            if (outcomes[n].workdir / r.file).is_file()]


def summary_dict(outcomes: dict[str, StageOutcome], verdicts: list[ClaimVerdict],
                 opts: ReproduceOptions, elapsed_s: float,
                 figures: list[ReportFigure] = ()) -> dict:
    """``summary.json``: every stage's typed summary, every claim's verdict, the settings."""
    return {
        "acid_version": __version__,
        "mode": run_mode(opts),
        "options": dataclasses.asdict(opts),
        "elapsed_s": elapsed_s,
        "stages": {k: {"title": o.title, "seconds": o.seconds,
                       "cpu_seconds": None if math.isnan(o.cpu_seconds) else o.cpu_seconds,
                       "cached": o.cached, "key": o.key, "summary": o.summary}
                   for k, o in outcomes.items()},
        "claims": summary_claims(verdicts),
        "figures": [{"stage": f.path.parent.name, **f.record.to_json_dict()} for f in figures],
    }


def write_outputs(out: Path, outcomes: dict[str, StageOutcome], opts: ReproduceOptions,
                  elapsed_s: float) -> tuple[Path, Path, list[ClaimVerdict]]:
    """Write ``report.html`` and ``summary.json`` into ``out``; the verdicts behind them."""
    from acid.report.html import Report, StageTime, write_report
    from acid.report.sections import sections_for

    results = study_results(outcomes)
    quick = is_quick(opts)
    verdicts = evaluate(results, quick=quick)
    figs = report_figures(outcomes, [s.name for s in build_stages(opts)])
    meta = {"acid": __version__, "python": platform.python_version(),
            "machine": f"{platform.machine()}, {_cpu_count()} cores",
            "generated": datetime.now(timezone.utc).replace(microsecond=0).isoformat(),
            "mode": run_mode(opts)}
    html = write_report(out / "report.html", Report(
        title="acid: Model Predictive Climate Control of CAVs, reproduced",
        verdicts=verdicts, figures=figs, sections=sections_for(results, quick=quick),
        stages=[StageTime(o.title, o.seconds, o.cached) for o in outcomes.values()],
        meta=meta))
    summary = write_json(out / "summary.json",
                         summary_dict(outcomes, verdicts, opts, elapsed_s, figs))
    return html, summary, verdicts


def _cpu_count() -> int:
    import os

    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


def load_summary(path: Path) -> dict:
    """Read a ``summary.json`` written by :func:`write_outputs`."""
    return json.loads(Path(path).read_text())


__all__ = ["ReproduceOptions", "build_stages", "is_quick", "run_mode", "study_results",
           "write_outputs"]
