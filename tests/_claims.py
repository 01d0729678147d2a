"""Synthetic typed stage results for the claims tests (imported as ``from _claims import ...``).

Plausible numbers for every stage of ``acid reproduce`` (no simulation), so that verdicts,
``summary.json`` and the headline table can be checked in milliseconds.
"""

from __future__ import annotations

import dataclasses
import json
import math

from acid.claims.results import (
    CavComparisonSummary,
    CavStudyStage,
    ChannelErrors,
    ClosedLoopSummary,
    EconStage,
    EnergyController,
    EnergyCycle,
    Estimate,
    FitStage,
    MpcStage,
    StudyResults,
    SweepStage,
    TimingSummary,
    ValidationStage,
)
from acid.models.params import paper
from acid.paper import STUDIES, TABLE_I
from acid.pipeline import StageOutcome
from acid.studies.reproduce import ReproduceOptions, write_outputs


def sweep(duration_s=TABLE_I.duration_s, scale=1.01) -> SweepStage:
    E = tuple(scale * e for e in TABLE_I.energy_MJ)
    km = tuple(math.nan if v == 0 else e / (v * duration_s / 1000.0)
               for v, e in zip(TABLE_I.speeds_mps, E, strict=True))
    D = tuple(0.98 * e * (1 - 0.015 * v) for e, v in zip(E, TABLE_I.speeds_mps, strict=True))
    return SweepStage(speeds_mps=TABLE_I.speeds_mps, duration_s=duration_s, energy_MJ=E,
                      energy_MJ_per_km=km, ratio_last_first=E[-1] / E[0],
                      max_energy_step_MJ=max(b - a for a, b in zip(E, E[1:], strict=False)),
                      efficiency_gain_pct=100 * (E[0] / E[-1] - 1), vehicle="paper",
                      beside_vehicle="default", beside_energy_MJ=D,
                      beside_ratio_last_first=D[-1] / D[0])


def fit() -> FitStage:
    names = [f"gamma{i}" for i in range(1, 8)] + [f"tau{i}" for i in range(1, 4)] + \
        [f"beta{i}" for i in range(1, 4)]
    theta = paper().theta * 0.9
    return FitStage(method="oe", covariance="hac", gamma=tuple(theta[:7]),
                    tau=tuple(theta[7:10]), beta=tuple(theta[10:]),
                    parameters={n: Estimate(v, 0.01, v - 0.02, v + 0.02)
                                for n, v in zip(names, theta, strict=True)},
                    ls_gamma=tuple(theta[:7]), ls_tau=tuple(theta[7:10]),
                    fit_percent_one_step={"T_cab": 98.0}, fit_percent_simulation={"T_cab": 90.0})


def validation(p90=1.0) -> ValidationStage:
    ch = ChannelErrors(rmse=0.5, mean_abs=0.4, median_abs=0.3, p90_abs=p90, p95_abs=p90 + 0.1,
                       max_abs=2.5, fit_percent=60.0)
    return ValidationStage(starts=STUDIES.validation_starts, horizon=STUDIES.validation_horizon,
                           horizon_s=1500.0, channels={c: ch for c in ("T_cab", "T_evap",
                                                                       "T_ain")})


def mpc(saving=20.0, difference=0.008, avoidable=0.02) -> MpcStage:
    loop = ClosedLoopSummary(passed=True, criterion="", energy_MJ=0.1, max_violation_K=0.0,
                             ride_error_K=0.0)
    cav = CavComparisonSummary(window_s=STUDIES.cav_window_s, case1_energy_MJ=0.026,
                               case2_energy_MJ=0.034, energy_difference_MJ=difference,
                               saving_pct=saving, speed_blind_saving_pct=saving - 1.0,
                               saving_from_speed_pct=1.0, T_cab_end_difference_K=2.0)
    return MpcStage(passed=True, model=loop,
                    plant=dataclasses.replace(loop, max_violation_K=0.3,
                                              max_avoidable_violation_K=avoidable),
                    cav=loop, cav_paper=cav, cav_periodic=dataclasses.replace(cav, saving_pct=-0.3),
                    cycles=4, timing=TimingSummary(median_ms=1.0, p95_ms=1.5, max_ms=3.0,
                                                   steps=50, passed=True, criterion="",
                                                   mean_ms=1.2))


def cav() -> CavStudyStage:
    def ctl(saving, gap):
        return EnergyController(energy_MJ=0.5, tail_corrected_energy_MJ=0.5,
                                saving_raw_pct=saving, saving_tail_corrected_pct=saving,
                                saving_vs_best_pi_pct=saving - 7.0,
                                saving_vs_best_pi_pi_charge_pct=saving - 6.9, in_rh_band=1.0,
                                gap_to_best_plan_pct=gap, mean_T_cab_K=297.3, max_T_cab_K=297.4,
                                pmv_mean=0.1, rh_mean_pct=35.0, w_cab_mean_g_kg=6.5,
                                mean_T_evap_set_K=280.0, mean_W_bl_kg_s=0.07)

    cycle = EnergyCycle(target_mean_T_cab_K=297.3, preview_share_points=-1e-12,  # signed 0
                        band_vs_pinned_pct=0.9, replay_vs_model_pct=-1.6,
                        controllers={"A": ctl(0.0, 8.0), "B": ctl(1.2, 7.0),
                                     "D": ctl(5.6, 2.2), "E": ctl(5.6, 2.2),
                                     "P": ctl(4.0, 3.9), "F": ctl(7.0, 0.6),
                                     "plan": ctl(7.6, 0.0)},
                        best_plan_spread_pct=0.4, best_pi_coil_set_point_K=283.0)
    return CavStudyStage(cycles={"udds": cycle, "sc03": cycle})


def econ() -> EconStage:
    ch = ChannelErrors(rmse=0.5, mean_abs=0.4, median_abs=0.3, p90_abs=1.0, p95_abs=1.1,
                       max_abs=2.5, fit_percent=60.0)
    return EconStage(duration_s=21600.0, power_map_rms_pct=3.6, power_map_steady_rms_pct=2.9,
                     starts=60, horizon=300, econ={c: ch for c in ("T_cab", "T_evap", "T_ain")},
                     paper={c: ch for c in ("T_cab", "T_evap", "T_ain")},
                     extra_median_abs={"T_int": 0.5, "w_cab": 0.13})


def results(**over) -> StudyResults:
    stages = {"sweep": sweep(), "fit": fit(), "validate": validation(), "mpc": mpc(),
              "econ": econ(), "cav": cav()}
    stages.update(over)
    return StudyResults({k: v for k, v in stages.items() if v is not None})


def outcomes(tmp_path, res: StudyResults) -> dict[str, StageOutcome]:
    out = {}
    for name, r in res.by_stage.items():
        d = tmp_path / "stages" / name
        d.mkdir(parents=True)
        out[name] = StageOutcome(name, name, d, r.to_json_dict(), 0.1, False, "k")
    return out


def summary_of(tmp_path, res: StudyResults, opts: ReproduceOptions | None = None) -> dict:
    _, path, _ = write_outputs(tmp_path, outcomes(tmp_path, res), opts or ReproduceOptions(),
                               1.0)
    return json.loads(path.read_text())
