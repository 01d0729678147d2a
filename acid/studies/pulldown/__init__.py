"""Identification through pull-down, and the economic NMPC on a pull-down (``acid pulldown``).

The econ model identified on ``acid excite --model econ`` alone has never seen a hot cabin:
its data hold cooling loads and evaporator temperatures of a car already near comfort. This
study measures what identifying it through pull-downs changes (kelvin inside, degC at the
edges):

1. **Records** (:func:`records`): the old record (``acid excite --model econ``, the record
   the economic NMPC is identified on today) and a pull-down record (``--design pulldown``,
   the same preset, hot soaks in ``soak_bounds`` and cold soaks at the ambient); the *old*
   model is identified on the old record, the *new* one on both joined as separate
   experiments, with only the first ``new_skip_s`` (60 s) of each experiment left out of the
   fit instead of the econ fit's ``FIT_SKIP_S`` (600 s, which drops most of a pull-down:
   measured, the new model's data then end at 26.8 degC cabin and 4.7 kW, the pull-down's
   own range unseen). Each model carries its envelope (:mod:`acid.ident.envelope`).
2. **Validation** (:func:`validate_pair`): both models open loop on held-out pull-downs
   (another seed; hot and cold soaks), the project's validator with its yardsticks
   (persistence, ARX, subspace) fitted on each model's own record, the speed and ambient
   measured along the prediction; T_cab's 90th-percentile absolute error per prediction time.
3. **Closed loop** (:func:`closed_loop`): one UDDS from a 40 degC soak at 30 degC ambient.
   The fixed coil is the comparison engine's family F (the plant's own loops, one pass of
   :func:`acid.studies.compare.periodic_run` from the soak) over its coil set-points; the
   best fixed coil at E's comfort is :func:`acid.studies.compare.tune_knob` on that front
   (discomfort: K min outside 23-25 degC), run again. E is the engine's economic NMPC with
   speed preview (the same construction as the engine's E) on the old and the new model;
   its applied steps are checked against the model's envelope. Reported: energy, the
   saving against the best fixed coil, time to 25 degC, K min above the band, the
   envelope count with the worst excursion, and (:func:`at_equal_comfort`) E's energy
   interpolated along its swept weights to each fixed coil's discomfort.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from acid.units import C2K, K2C

#: the held-out pull-downs' seed offset from the identification seed (never reused)
HELD_OUT_SEED_OFFSET = 1000


@dataclass(frozen=True)
class PulldownSettings:
    """What the study runs (durations s, temperatures degC at this edge)."""

    seed: int = 0
    old_duration_s: float = 3 * 3600.0
    pulldown_duration_s: float = 3 * 3600.0
    held_out_duration_s: float = 2 * 3600.0
    soak_bounds_C: tuple[float, float] = (30.0, 55.0)
    cycle: str = "udds"
    T_amb_C: float = 30.0
    soak_C: float = 40.0
    comfort_weights: tuple[float, ...] = (30.0, 300.0)
    horizon_s: float = 60.0
    validation_horizon_s: float = 1500.0
    validation_starts: int = 24
    T_reach_C: float = 25.0
    new_skip_s: float = 60.0


@dataclass(frozen=True)
class Models:
    """The old and the new econ model and the records they were identified on."""

    old: object
    new: object
    old_record: object
    pulldown_record: object


def _identify(ds, skip_s: float | None = None):
    from acid.ident.econ import identify

    kw = {} if skip_s is None else {"skip_s": float(skip_s)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # carried by the fit report
        return identify(ds, **kw).params


def records(settings: PulldownSettings = PulldownSettings(), plant_factory=None):
    """(old record, pull-down record, held-out pull-downs), hifi plant, seeded."""
    from acid.excite import spec_for_model
    from acid.plant import make_plant

    make = plant_factory or (lambda: make_plant("hifi"))
    s = settings
    old = spec_for_model("econ", duration=s.old_duration_s, seed=s.seed)
    pd = spec_for_model("econ", design="pulldown", duration=s.pulldown_duration_s,
                        soak_bounds=s.soak_bounds_C, seed=s.seed + 1)
    held = pd.replace(duration=s.held_out_duration_s, cold_fraction=0.5,
                      seed=s.seed + HELD_OUT_SEED_OFFSET)
    from acid.excite import excite

    return excite(make(), old), excite(make(), pd), excite(make(), held)


def identify_pair(old_record, pulldown_record, new_skip_s: float = 60.0) -> Models:
    """The old model (old record, the econ fit as it is) and the new one (old record +
    pull-downs, ``new_skip_s`` left out at each experiment's start)."""
    from acid.data import Dataset

    both = Dataset.concatenate([old_record, pulldown_record])
    return Models(_identify(old_record), _identify(both, new_skip_s), old_record,
                  pulldown_record)


def validate_pair(models: Models, held_out, settings: PulldownSettings = PulldownSettings()
                  ) -> dict:
    """{"old"|"new": {"model": {t: p90_K}, "persistence"|"arx"|"subspace": {t: p90_K}},
    "envelope": {...}} : T_cab's p90 absolute error (K) per prediction time on the held-out
    pull-downs, each model beside yardsticks fitted on its own identification record."""
    from acid.data import Dataset
    from acid.ident.envelope import Envelope
    from acid.ident.validate import validate_model

    out = {}
    for key, params, est in (("old", models.old, [models.old_record]),
                             ("new", models.new, [models.old_record,
                                                  models.pulldown_record])):
        ds = Dataset.concatenate([*est, held_out])
        lo = len(ds) - len(held_out)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            v = validate_model("econ", ds, params, starts=settings.validation_starts,
                               horizon=int(round(settings.validation_horizon_s / ds.Ts)),
                               warmup=12 * ds.Ts, start_range=(lo, len(ds)), estimation=(0, lo),
                               yardsticks=True, to_end=True, hold=())
        row = {"model": {t: d["p90_K"] for t, d in v.by_time.get("T_cab", {}).items()}}
        for name, y in v.yardsticks.items():
            row[name] = {t: d["p90_K"] for t, d in y.get("by_time", {}).get("T_cab",
                                                                             {}).items()}
        env = Envelope.of(params)
        held = {"Q_e": None, "T_cab": C2K(held_out["T_cab"]), "W_bl": held_out["W_bl"],
                "T_amb": C2K(held_out["T_amb"]), "T_evap": C2K(held_out["T_evap"])}
        ex = env.check(**{k: v for k, v in held.items() if v is not None})
        row["held_out_outside"] = ex.to_dict()
        row["n_starts"] = v.n_starts
        out[key] = row
    return out


# ------------------------------------------------------------------------- closed loop
@dataclass(frozen=True)
class LoopResult:
    """One controller on the pull-down (J, K min, s, K)."""

    name: str
    energy_J: float
    discomfort_Kmin: float
    above_Kmin: float
    time_to_reach_s: float
    mean_T_cab: float
    knob: float = math.nan
    envelope: dict = field(default_factory=dict)
    envelope_line: str = ""


def scenario(settings: PulldownSettings = PulldownSettings()):
    """The engine's scenario: the cycle at the ambient from the soak."""
    from acid.studies.compare import Scenario

    return Scenario(settings.cycle, C2K(settings.T_amb_C), soak_K=C2K(settings.soak_C))


def _trace_stats(name, E, T, Ts, rs, T_reach, knob=math.nan, **kw) -> LoopResult:
    T = np.asarray(T)
    out = np.maximum(0.0, np.maximum(T - rs.T_high, rs.T_low - T))
    above = np.maximum(0.0, T - rs.T_high)
    hit = np.flatnonzero(T <= T_reach)
    t = float((hit[0] + 1) * Ts) if hit.size else math.inf
    return LoopResult(name, float(E), float(out.sum() * Ts / 60.0),
                      float(above.sum() * Ts / 60.0), t, float(np.mean(T)), float(knob), **kw)


def fixed_coil(knob: float, settings: PulldownSettings = PulldownSettings()) -> LoopResult:
    """The engine's F (plant's own loops, coil set-point ``knob`` K) on one pass from the
    soak: energy and discomfort from :func:`acid.studies.compare.periodic_run`; the cabin
    trace (time to 25 degC, K min above the band) from the same run replayed, checked to
    give the engine's energy."""
    from acid.plant.hifi import HifiPlant
    from acid.studies.compare import RunSettings, periodic_run

    sc, rs = scenario(settings), RunSettings(max_passes=1)
    run = periodic_run(sc, "F", knob, rs, start=sc.start())
    cfg = sc.plant_config()   # the engine's F: its coil, the reset limit widened to it
    plant = HifiPlant(cfg.replace(T_ew_set=float(knob),
                                  T_ew_set_max=max(cfg.T_ew_set_max, float(knob) + 0.5)),
                      mode="nominal")
    plant.reset(sc.start())
    drive, E, T = sc.drive(), 0.0, []
    for k in range(drive.n):
        row = plant.step(0.0, 0.0, float(drive.v[k]), T_amb=float(drive.T_amb[k]),
                         T_cab_set=rs.T_set)
        E += (float(row["P_comp"]) + float(row["P_bl"])) * drive.Ts
        T.append(float(plant.measure()["T_cab"]))
    if not math.isclose(E, run.first_pass_J, rel_tol=1e-9):
        raise RuntimeError(f"fixed coil {K2C(knob):g} degC: replay {E:.6g} J differs from "
                           f"the engine's {run.first_pass_J:.6g} J")
    res = _trace_stats(f"F {K2C(knob):.2f} degC", run.first_pass_J, T, drive.Ts, rs,
                       C2K(settings.T_reach_C), knob)
    return res


def econ_run(params, weight: float, settings: PulldownSettings = PulldownSettings(),
             label: str = "E") -> LoopResult:
    """The engine's E (economic NMPC with speed preview, comfort weight ``weight``) on one
    pass from the soak, its applied steps checked against the model's envelope."""
    from acid.control.econ.nmpc import EconNMPC, EconNMPCConfig
    from acid.errors import ExtrapolationWarning
    from acid.plant.hifi import HifiPlant
    from acid.studies.cav_study import EconPreview
    from acid.studies.compare import RunSettings

    sc, rs = scenario(settings), RunSettings(max_passes=1)
    drive, cfg = sc.drive(), sc.plant_config()
    n = int(round(settings.horizon_s / drive.Ts))
    mpc = EconNMPC(params, EconNMPCConfig(intervals=(drive.Ts,) * n, preview=True,
                                          T_cab_min=rs.T_low - 1.0, T_cab_max=rs.T_high + 1.0,
                                          comfort_weight=float(weight), compiled=False))
    ctrl = EconPreview(mpc, drive, rs.T_set)
    plant = HifiPlant(cfg, mode="direct")
    plant.reset(sc.start())
    ctrl.reset()
    E, T = 0.0, []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)   # counted below
        for k in range(drive.n):
            u = ctrl.make_step(plant.measure(), k)
            row = plant.step(float(u[0]), float(u[1]), float(drive.v[k]),
                             T_amb=float(drive.T_amb[k]))
            E += (float(row["P_comp"]) + float(row["P_bl"])) * drive.Ts
            T.append(float(plant.measure()["T_cab"]))
    ex = mpc.envelope_steps
    return _trace_stats(f"{label} w={weight:g}", E, T, drive.Ts, rs, C2K(settings.T_reach_C),
                        weight, envelope=ex.to_dict(), envelope_line=ex.summary(mpc.envelope))


def best_fixed_coil(front: list[LoopResult], level_Kmin: float,
                    settings: PulldownSettings = PulldownSettings()) -> LoopResult:
    """The engine's tuning rule on F's front: the coil meeting ``level_Kmin`` at least
    energy (:func:`acid.studies.compare.tune_knob`), run."""
    from acid.studies.compare import FrontPoint, tune_knob

    pts = [FrontPoint("F", r.knob, r.energy_J, r.discomfort_Kmin, math.nan) for r in front]
    return fixed_coil(tune_knob(pts, level_Kmin), settings)


def at_equal_comfort(front: list[LoopResult], runs: list[LoopResult]) -> list[dict]:
    """E's energy at each fixed coil's discomfort: E's swept weights (``runs``, one model)
    interpolated linearly in discomfort (K min outside the band), only inside their span;
    the saving against that coil, % (positive: E uses less)."""
    pts = sorted((r.discomfort_Kmin, r.energy_J) for r in runs)
    out = []
    for f in front:
        d = f.discomfort_Kmin
        if len(pts) < 2 or not pts[0][0] <= d <= pts[-1][0]:
            continue
        E = float(np.interp(d, [p[0] for p in pts], [p[1] for p in pts]))
        out.append({"F": f.name, "discomfort_Kmin": d, "F_J": f.energy_J, "E_J": E,
                    "saving_pct": 100.0 * (f.energy_J - E) / f.energy_J})
    return out


def closed_loop(models: Models, settings: PulldownSettings = PulldownSettings(),
                progress=None) -> dict:
    """F's front, E on the old and the new model, each E against F at its comfort."""
    from acid.studies.compare import families

    say = progress or (lambda _msg: None)
    coils = next(f for f in families() if f.key == "F").knobs
    front = []
    for c in coils:
        front.append(fixed_coil(c, settings))
        say(f"{front[-1].name}: {front[-1].energy_J / 1e6:.3f} MJ")
    rows = []
    for key, params in (("old", models.old), ("new", models.new)):
        for w in settings.comfort_weights:
            e = econ_run(params, w, settings, label=f"E ({key} model)")
            f = best_fixed_coil(front, e.discomfort_Kmin, settings)
            saving = 100.0 * (f.energy_J - e.energy_J) / f.energy_J
            rows.append({"model": key, "E": e, "F": f, "saving_pct": saving})
            say(f"{e.name}: {e.energy_J / 1e6:.3f} MJ vs {f.name} {f.energy_J / 1e6:.3f} MJ "
                f"({saving:+.2f} %); {e.envelope_line}")
    equal = {key: at_equal_comfort(front, [r["E"] for r in rows if r["model"] == key])
             for key in ("old", "new")}
    return {"front": front, "rows": rows, "equal_comfort": equal}
