"""E against the best fixed coil over a set of pull-downs, tuned on training pull-downs and
judged on held-out ones with the comparison engine's paired intervals (``acid pulldown
--set``).

One pull-down is one pass of a drive cycle from a hot soak (cabin, interior, shell and the
A/C's walls at the soak temperature), under sun, at an ambient: the engine's
:class:`acid.studies.compare.Scenario` with ``soak_K`` set. The set declares training and
held-out cases apart (soaks 35-45 degC, ambients 28-38 degC, sun 600-1000 W/m2, four cycles);
nothing of the held-out cases is used before judging.

Tuning, the engine's rule (:func:`acid.studies.compare.tune`): every family's knobs are run
on the training pull-downs; the comfort level is the plant's own loops' mean training
discomfort (K min outside 23-25 degC); the fixed coil's set-point (family F: the engine's coils
and the plant's configured 3 degC, which alone reaches the own loops' comfort on a pull-down)
and E's comfort weight are each :func:`acid.studies.compare.tune_knob` on their training
fronts at that level.

Judging: on each held-out pull-down the plant's own loops, F at its tuned coil and E at its
tuned weight, and E again with its cabin target ``MATCH_SHIFT_K`` lower; E at F's (and at the
own loops') mean cabin temperature is :func:`acid.studies.compare.match_to_mean` between the
two (the engine's equal-comfort rule; beyond its extrapolation limit the case is not
matched): on a pull-down E's discomfort saturates with its weight (full power either way), so
the mean cabin, not the weight, is what moves its comfort. The energy of a
pull-down is charged with the state it leaves: the pass's compressor and blower energy plus
the engine's common continuation from its end state (:func:`acid.studies.compare.tail_J`,
40 min at the cycle's mean speed under the plant's own loops; the same for every controller
from the same state), so a controller that leaves the cabin warmer pays for it.
Verdicts: :func:`acid.studies.compare.verdict` (paired bootstrap
and paired t, both must exclude zero; "not resolved" under the engine's count; "not at equal
comfort" when the candidate is less comfortable). E's applied steps are checked against the
model's envelope per case.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from acid.units import C2K, K2C

#: (cycle, ambient degC, soak degC, sun W/m2): training pull-downs (tune the knobs)
TRAINING = (("udds", 30.0, 40.0, 850.0), ("sc03", 35.0, 45.0, 1000.0),
            ("hwfet", 28.0, 35.0, 600.0), ("us06", 33.0, 42.0, 800.0))
#: held-out pull-downs (judge): other soaks, ambients and suns on the same cycles
HELD_OUT = (("udds", 32.0, 38.0, 700.0), ("udds", 36.0, 45.0, 950.0),
            ("sc03", 30.0, 36.0, 850.0), ("sc03", 38.0, 44.0, 1000.0),
            ("hwfet", 34.0, 40.0, 750.0), ("hwfet", 30.0, 45.0, 900.0),
            ("us06", 29.0, 37.0, 600.0), ("us06", 37.0, 43.0, 1000.0))
#: ``--quick``: two training and two held-out cases (too few to resolve: a smoke run)
QUICK_TRAINING = TRAINING[1:2] + TRAINING[3:4]
QUICK_HELD_OUT = HELD_OUT[3:4] + HELD_OUT[6:7]


def case(cycle: str, T_amb_C: float, soak_C: float, G_solar: float):
    """The engine's scenario of one pull-down (K inside)."""
    from acid.studies.compare import Scenario

    return Scenario(cycle, C2K(T_amb_C), G_solar=float(G_solar), soak_K=C2K(soak_C))


def case_name(sc) -> str:
    return (f"{sc.cycle}@{K2C(sc.T_amb):g}C soak {K2C(sc.soak_K):g}C "
            f"sun {sc.G_solar:g}")


@dataclass(frozen=True)
class CaseRun:
    """One controller on one pull-down (J, K min, s, K); ``envelope``: E's applied steps
    against its model's envelope (:meth:`acid.ident.envelope.Excursion.to_dict`)."""

    case: str
    family: str
    knob: float
    energy_J: float
    #: the pass plus the common continuation from its end state (J)
    charged_J: float
    discomfort_Kmin: float
    above_Kmin: float
    time_to_reach_s: float
    mean_T_cab: float
    envelope: dict = field(default_factory=dict)
    #: not measured here (the engine's matching interpolates it)
    rh_mean: float = math.nan
    #: E's solver: steps whose SQP failed and the fallback solver (IPOPT) solved
    #: (``fallback_solver``), convex-QP rescues (``rescues``), steps where no solver
    #: succeeded and the last plan or the safe input was applied (``failed``)
    solver: dict = field(default_factory=dict)


def run_case(sc, family: str, knob: float = math.nan, params=None, horizon_s: float = 60.0,
             T_reach_C: float = 25.0, settings=None, slow=None) -> CaseRun:
    """One pass of ``sc``'s cycle from its soak: ``family`` "own" (the plant's own loops at
    its configured coil), "F" (the same loops at coil ``knob`` K, the engine's F) or "E" (the
    engine's economic NMPC with speed preview on ``params``, comfort weight ``knob``; with
    ``slow``, an :class:`acid.ident.econ.Econ2Fit`, on its econ part with the slow interior
    carried from the soak, :class:`acid.studies.pulldown.slow.SlowInterior`)."""
    from acid.errors import ConfigError, ExtrapolationWarning
    from acid.plant.hifi import HifiPlant, physical_state
    from acid.studies.cav_study import plant_state
    from acid.studies.compare import RunSettings, tail_J

    rs = settings or RunSettings(max_passes=1)
    drive, cfg = sc.drive(), sc.plant_config()
    ctrl, mpc = None, None
    if family == "F":
        cfg = cfg.replace(T_ew_set=float(knob),
                          T_ew_set_max=max(cfg.T_ew_set_max, float(knob) + 0.5))
    elif family == "E":
        from acid.control.econ.nmpc import EconNMPC, EconNMPCConfig
        from acid.studies.cav_study import EconPreview

        n = int(round(horizon_s / drive.Ts))
        mpc = EconNMPC(params, EconNMPCConfig(
            intervals=(drive.Ts,) * n, preview=True, T_cab_min=rs.T_low - 1.0,
            T_cab_max=rs.T_high + 1.0, comfort_weight=float(knob), compiled=False))
        ctrl = EconPreview(mpc, drive, rs.T_set)
        if slow is not None:
            from acid.studies.pulldown.slow import SlowInterior

            ctrl = SlowInterior(ctrl, slow, drive.Ts)
    elif family != "own":
        raise ConfigError(f"unknown pull-down family {family!r} (own, F, E)")
    plant = HifiPlant(cfg, mode="direct" if ctrl is not None else "nominal")
    plant.reset(sc.start())
    if ctrl is not None:
        ctrl.reset()
    E, T = 0.0, []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)   # counted below
        for k in range(drive.n):
            v, T_amb = float(drive.v[k]), float(drive.T_amb[k])
            if ctrl is None:
                row = plant.step(0.0, 0.0, v, T_amb=T_amb, T_cab_set=rs.T_set)
            else:
                u = ctrl.make_step(plant.measure(), k)
                row = plant.step(float(u[0]), float(u[1]), v, T_amb=T_amb)
            E += (float(row["P_comp"]) + float(row["P_bl"])) * drive.Ts
            T.append(float(plant.measure()["T_cab"]))
    end = plant_state(plant)
    # the common continuation: the plant's own loops at the default set-point whatever this
    # run's target (a run with a lowered target must not be charged 40 min of a colder cabin
    # that its pass's mean cabin does not show)
    charged = E + tail_J(sc, physical_state(end), "own", RunSettings(max_passes=1))
    T = np.asarray(T)
    out = np.maximum(0.0, np.maximum(T - rs.T_high, rs.T_low - T))
    hit = np.flatnonzero(T <= C2K(T_reach_C))
    env = mpc.envelope_steps.to_dict() if mpc is not None else {}
    solver = {}
    if mpc is not None:
        env["line"] = mpc.envelope_steps.summary(mpc.envelope)
        solver = {"fallback_solver": int(mpc.solver_fallbacks),
                  "rescues": int(mpc.solver_rescues),
                  "failed": int(np.sum(np.asarray(mpc.log.fallback, dtype=bool))),
                  "steps": int(drive.n)}
    return CaseRun(case_name(sc), family, float(knob), float(E), float(charged),
                   float(out.sum() * drive.Ts / 60.0),
                   float(np.maximum(0.0, T - rs.T_high).sum() * drive.Ts / 60.0),
                   float((hit[0] + 1) * drive.Ts) if hit.size else math.inf,
                   float(T.mean()), env, solver=solver)


@dataclass(frozen=True)
class SetTuning:
    """What the training pull-downs decided: the comfort level (K min, the own loops' mean),
    the fronts ``{family: [(knob, mean charged J, mean K min)]}``, F's coil (K) and E's
    weight."""

    level_Kmin: float
    fronts: dict
    coil_K: float
    weight: float


def tune_on(runs: Sequence[CaseRun]) -> SetTuning:
    """The engine's tuning rule on training runs (:func:`acid.studies.compare.tune_knob`,
    level = the plant's own loops' mean discomfort)."""
    from acid.studies.compare import FrontPoint, tune_knob

    fronts: dict = {}
    for fam in ("own", "F", "E"):
        knobs = sorted({r.knob for r in runs if r.family == fam and not math.isnan(r.knob)})
        if fam == "own":
            knobs = [math.nan]
        pts = []
        for k in knobs:
            rs = [r for r in runs if r.family == fam
                  and (r.knob == k or (math.isnan(k) and math.isnan(r.knob)))]
            pts.append((float(k), float(np.mean([r.charged_J for r in rs])),
                        float(np.mean([r.discomfort_Kmin for r in rs]))))
        fronts[fam] = pts
    level = fronts["own"][0][2]

    def tuned(fam):
        return tune_knob([FrontPoint(fam, k, e, d, math.nan) for k, e, d in fronts[fam]], level)

    return SetTuning(float(level), fronts, float(tuned("F")), float(tuned("E")))


def matched(e_at: CaseRun, e_lowered: CaseRun, to: CaseRun) -> CaseRun | None:
    """E at ``to``'s mean cabin temperature: the engine's
    :func:`acid.studies.compare.match_to_mean` between E at its target and at the lowered
    one, on the charged energy; None when not matched."""
    import dataclasses

    from acid.studies.compare import match_to_mean

    def charged(r):
        return dataclasses.replace(r, energy_J=r.charged_J)

    m = match_to_mean(charged(e_at), charged(e_lowered), to.mean_T_cab)
    return None if m is None else dataclasses.replace(m, charged_J=m.energy_J,
                                                      energy_J=math.nan)


def run_set(params, training=TRAINING, held_out=HELD_OUT, coils: Sequence[float] | None = None,
            weights: Sequence[float] | None = None, horizon_s: float = 60.0, seed: int = 0,
            progress: Callable[[str], None] | None = None, slow=None) -> dict:
    """Tune on ``training``, judge on ``held_out`` (tuples as :data:`TRAINING`): the
    training runs, the tuning, the held-out runs per case and the verdicts E vs F, E at F's
    comfort vs F, E vs own and F vs own."""
    import dataclasses

    from acid.studies.compare import MATCH_SHIFT_K, RunSettings, families, verdict

    say = progress or (lambda _m: None)
    fams = {f.key: f for f in families()}
    own_coil = float(case(*training[0]).plant_config().T_ew_set)
    coils = tuple(coils or sorted({own_coil, *fams["F"].knobs}))
    weights = tuple(weights or fams["E"].knobs)
    train = []
    for spec in training:
        sc = case(*spec)
        jobs = [("own", math.nan)] + [("F", c) for c in coils] + [("E", w) for w in weights]
        for fam, k in jobs:
            train.append(run_case(sc, fam, k, params, horizon_s, slow=slow))
            r = train[-1]
            say(f"training {r.case}: {fam} {'' if math.isnan(k) else f'{k:g}'} "
                f"{r.charged_J / 1e6:.3f} MJ, {r.discomfort_Kmin:.1f} K min")
    tuning = tune_on(train)
    say(f"tuned on {len(training)} pull-downs: level {tuning.level_Kmin:.2f} K min, F coil "
        f"{K2C(tuning.coil_K):.2f} degC, E weight {tuning.weight:.1f}")
    base = RunSettings(max_passes=1)
    lowered = dataclasses.replace(base, T_set=base.T_set - MATCH_SHIFT_K)
    held = []
    for spec in held_out:
        sc = case(*spec)
        row = {"case": case_name(sc), "own": run_case(sc, "own", math.nan, params, horizon_s),
               "F": run_case(sc, "F", tuning.coil_K, params, horizon_s),
               "E": run_case(sc, "E", tuning.weight, params, horizon_s, slow=slow),
               "E_lowered": run_case(sc, "E", tuning.weight, params, horizon_s,
                                     settings=lowered, slow=slow)}
        row["E at F's T_cab"] = matched(row["E"], row["E_lowered"], row["F"])
        row["E at own's T_cab"] = matched(row["E"], row["E_lowered"], row["own"])
        held.append(row)
        say(f"held-out {row['case']}: E {row['E'].charged_J / 1e6:.3f} MJ "
            f"({row['E'].discomfort_Kmin:.1f} K min), F {row['F'].charged_J / 1e6:.3f} MJ "
            f"({row['F'].discomfort_Kmin:.1f}), own {row['own'].charged_J / 1e6:.3f} MJ "
            f"({row['own'].discomfort_Kmin:.1f}); {row['E'].envelope.get('line', '')}")

    def judge(c, b, rows, energy="charged_J"):
        rows = [r for r in rows if r.get(c) is not None]
        if not rows:
            return None
        return verdict(c, b, [r["case"] for r in rows],
                       [getattr(r[c], energy) for r in rows],
                       [getattr(r[b], energy) for r in rows], seed=seed,
                       discomfort_gap_Kmin=float(np.mean([r[c].discomfort_Kmin
                                                          - r[b].discomfort_Kmin
                                                          for r in rows])),
                       T_cab_gap_K=float(np.mean([r[c].mean_T_cab - r[b].mean_T_cab
                                                  for r in rows])))

    verdicts = {"E vs F": judge("E", "F", held),
                "E at F's T_cab vs F": judge("E at F's T_cab", "F", held),
                "E vs F, pass only": judge("E", "F", held, "energy_J"),
                "E vs own": judge("E", "own", held),
                "E at own's T_cab vs own": judge("E at own's T_cab", "own", held),
                "F vs own": judge("F", "own", held)}
    return {"training": train, "tuning": tuning, "held_out": held, "verdicts": verdicts,
            "unmatched": [r["case"] for r in held if r["E at F's T_cab"] is None]}
