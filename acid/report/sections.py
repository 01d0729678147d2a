"""Report sections built from typed stage results: one builder per stage result class.

A stage whose results need more than claim rows (a study beyond the paper, a plant check)
registers a builder here; the report shows its section after the claims::

    @report_section(MyStage)
    def _my_section(r: MyStage) -> ReportSection:
        return ReportSection("My study", paragraphs=(...,), header=(...), rows=(...))
"""

from __future__ import annotations

import math

from acid.claims.results import (
    CavStudyStage,
    EconStage,
    EngineStage,
    PlantCheckStage,
    StudyResults,
    SweepStage,
    ValidationStage,
)
from acid.numbers import format_number
from acid.report.html import ReportSection
from acid.report.registry import SECTION_BUILDERS, report_section

#: the first words of a paragraph that draws a conclusion from a stage's numbers
CONCLUSION = "Conclusion (from the numbers):"


def sections_for(results: StudyResults, quick: bool = False) -> list[ReportSection]:
    """The sections of the stages that ran, in registration order.

    ``quick``: the results are of a ``--quick`` run. A section of a stage the quick run
    shortens (outside ``acid.claims.registry.QUICK_RUN_JUDGES``) then says so first, and
    draws no conclusion.
    """
    import dataclasses

    from acid.claims.registry import QUICK_RUN_JUDGES, QUICK_RUN_REASON

    out = []
    for kind, builder in SECTION_BUILDERS.items():
        r = results.get(kind)
        if r is None:
            continue
        sec = builder(r)
        if quick and kind not in QUICK_RUN_JUDGES:
            paras = tuple(p for p in sec.paragraphs if not p.startswith(CONCLUSION))
            sec = dataclasses.replace(sec, paragraphs=(
                f"Not judged (quick run): {QUICK_RUN_REASON}. The numbers below are those of "
                "the smaller study and support no conclusion.",) + paras)
        out.append(sec)
    return out


@report_section(EngineStage)
def _energy_answer(r: EngineStage) -> ReportSection:
    from acid.studies.verdict import MAX_DISCOMFORT_GAP_KMIN, MAX_WARMER_K, MIN_SCENARIOS

    def f(x, spec="+.2f") -> str:
        return format_number(x, spec)

    rows = tuple((v.candidate, v.baseline, str(len(v.scenarios)), f(v.mean_pct),
                  f"[{f(v.boot_lo)}, {f(v.boot_hi)}]", f"[{f(v.t_lo)}, {f(v.t_hi)}]",
                  f(v.discomfort_gap_Kmin), f(v.T_cab_gap_K), v.word,
                  f"{f(v.single_own_pct)} / {f(v.single_pi_pct)}") for v in r.verdicts)
    tuned = "; ".join(
        f"{k} {format_number(v - 273.15, '.2f')} °C" if k in ("F", "Fs", "P")
        else f"{k} weight {format_number(v, '.4g')} W/K² s" for k, v in r.tuned.items()
        if math.isfinite(v))
    answer = []
    for cand in ("E", "E at F's T_cab"):
        v = r.verdict(cand, "F")
        if v is not None:
            answer.append(f"{cand} against F: {v.word}, {f(v.mean_pct)} % "
                          f"[{f(v.boot_lo)}, {f(v.boot_hi)}] (95 % bootstrap over "
                          f"{len(v.scenarios)} held-out scenarios)")
    v = r.verdict("F", "own")
    if v is not None:
        answer.append(f"F against the plant's own loops at their configured coil: {v.word}, "
                      f"{f(v.mean_pct)} % [{f(v.boot_lo)}, {f(v.boot_hi)}]")
    extra = "; ".join(f"{k} on {len(n)} of {len(r.held_out)} ({', '.join(n)})"
                      for k, n in r.extrapolated.items())
    plans = []
    for b in r.best_plans.values():
        forms = ", ".join(f"{k} {format_number(v, '.1f')} kJ" for k, v in
                          b.formulations_kJ.items())
        plans.append(
            f"{b.scenario}: the plan {format_number(b.plan_kJ, '.1f')} kJ per pass ({forms}; "
            f"spread {format_number(b.spread_pct, '.2f')} %, mean T_cab "
            f"{format_number(b.plan_mean_T_cab_K - 273.15, '.2f')} °C), F "
            f"{format_number(b.F_kJ, '.1f')} kJ "
            f"({format_number(b.F_mean_T_cab_K - 273.15, '.2f')} °C)"
            + (f", E at F's T_cab {format_number(b.E_kJ, '.1f')} kJ"
               if math.isfinite(b.E_kJ) else "")
            + f": the best known operation is {'the plan' if b.best == 'plan' else b.best}"
            + "; the others above it by " + ", ".join(
                f"{'the plan' if k == 'plan' else k} {format_number(g, '+.2f')} %"
                for k, g in b.gaps_pct.items() if k != b.best))
    best = ((" The best known plan (perfect information; the cyclic whole-cycle optimum on "
             "the econ model, two formulations from several seeded starts, each replayed on "
             "the plant pass after pass at the engine's mean cabin temperature; when another "
             "operation uses less energy under the same accounting, it is the best known one): "
             + "; ".join(plans) + ".") if plans else "")
    return ReportSection(
        "The energy answer: verdicts on held-out scenarios",
        paragraphs=(
            "Every energy verdict of this report comes from the comparison engine (acid "
            "compare) with this run's econ model. Each controller family is swept over its "
            "knob on the training scenarios (" + ", ".join(r.training) + ") and tuned there "
            f"to the plant's own comfort level ({r.comfort_level_Kmin:.2f} K min per pass "
            f"outside the band); tuned: {tuned}; E's cabin reference moved by "
            f"{format_number(r.econ_ref_offset_K, '+.3f')} K so that its training mean "
            "matches F's. The verdicts are over the held-out scenarios ("
            + ", ".join(r.held_out) + f"), never tuned on. The split: {r.rule}.",
            "Each run repeats its cycle until the cabin, interior and shell temperatures at "
            "the end of a pass repeat (periodic steady state: no end state is charged, so "
            "no charge convention decides a sign; at most "
            f"{r.periodic_passes_max} passes{'' if r.all_converged else ', not all converged'}"
            "), or those of every second pass (a period-2 orbit: two passes alternate, "
            "their mean, the cycle average, is the figure; "
            f"{r.period_two_runs} held-out run{'' if r.period_two_runs == 1 else 's'}). "
            "Saving: % of the baseline's energy per pass (compressor and blower), "
            "positive when the candidate uses less. The word comes from both 95 % intervals "
            "(paired bootstrap and paired t over the held-out scenarios): saves, costs, or no "
            f"resolvable difference; fewer than {MIN_SCENARIOS} scenarios: not resolved; a "
            f"candidate more than {MAX_WARMER_K:g} K warmer on average or "
            f"{MAX_DISCOMFORT_GAP_KMIN:g} K min less comfortable: not at equal comfort. "
            "\"X at F's T_cab\": X run again 0.3 K cooler and interpolated to F's mean cabin "
            "temperature per scenario. The single-pass figures (first pass from the common "
            "start, its end state charged by the plant's own loops / by acid's PI) are "
            "figures beside the verdict, not verdicts.",
            "Families: F, fixed coil on the plant's own loops (knob: coil set-point); Fs, "
            "acid's sampled fixed-coil PI; P, production-style coil reset; own, the plant's "
            "own loops at their configured coil; E, economic NMPC with speed preview (knob: "
            "comfort weight)." + best,
            f"{CONCLUSION} " + "; ".join(answer) + "."
            + (f" E's plans left its econ model's identification data: {extra}." if extra
               else "")),
        header=("candidate", "baseline", "n", "saving (%)", "bootstrap 95 %", "paired t 95 %",
                "comfort gap (K min)", "mean T_cab gap (K)", "verdict",
                "single pass, own / PI charge (%)"),
        rows=rows, lead=True)


@report_section(SweepStage)
def _table_i_vehicles(r: SweepStage) -> ReportSection:
    from acid.claims.registry import DEFAULT_VEHICLE_MECHANISM, TABLE_I_MECHANISM
    from acid.paper import TABLE_I

    full = abs(r.duration_s - TABLE_I.duration_s) < 1e-9
    other = r.beside_energy_MJ if len(r.beside_energy_MJ) == len(r.energy_MJ) else ()
    rows = []
    for i, (v, e) in enumerate(zip(r.speeds_mps, r.energy_MJ, strict=True)):
        paper = TABLE_I.energy_at(v) if full else None
        rows.append((format_number(v, "g"), format_number(e, ".3f"),
                     format_number(other[i], ".3f") if other else "n/a",
                     "n/a" if paper is None else format_number(paper, ".2f")))
    rows.append(("E(25)/E(0)", format_number(r.ratio_last_first, ".3f"),
                 format_number(r.beside_ratio_last_first, ".3f") if other else "n/a",
                 format_number(TABLE_I.energy_MJ[-1] / TABLE_I.energy_MJ[0], ".3f")
                 if full else "n/a"))
    vehicle = r.vehicle or "acid's"
    return ReportSection(
        "Table I: the paper vehicle and acid's default vehicle",
        paragraphs=(
            f"The paper's Table I is judged on the {vehicle} vehicle (the Table I calibration, "
            "--plant-config paper, example:table_i_20cc.toml); acid's "
            f"{r.beside_vehicle or 'default'} vehicle (the plant of every other stage) is "
            "shown beside it. Energy over "
            f"{format_number(r.duration_s, 'g')} s, compressor + blower, MJ"
            + ("" if full else f" (not the paper's {TABLE_I.duration_s:g} s: no paper values)")
            + ".",
            f"Why they differ: {TABLE_I_MECHANISM}; on the default vehicle "
            f"{DEFAULT_VEHICLE_MECHANISM}.",
            "The Table I calibration was found by about 1,000 random and local-search runs "
            "inside the cited parameter ranges; that search was not exhaustive."),
        header=("speed (m/s)", f"{vehicle} vehicle (MJ)",
                f"{r.beside_vehicle or 'default'} vehicle (MJ)", "paper Table I (MJ)"),
        rows=tuple(rows))


#: Prediction times (s) of the report's yardstick table.
YARDSTICK_TIMES = ("60", "300", "1500")


@report_section(ValidationStage)
def _validation_design(r: ValidationStage) -> ReportSection:
    if not r.window_design:  # a stage record from before the design was recorded
        return ReportSection("Validation design and yardsticks", paragraphs=(
            "The window design was not recorded with this stage (run it again).",))
    paragraphs = [
        f"Figs. 5-6, {r.window_design}. Overlapping windows are not "
        "independent trials: one event in the data enters the errors of every window that "
        "holds it (`acid validate --non-overlapping` spaces the starts by more than the "
        "horizon)."]
    rows: tuple = ()
    if r.yardsticks:
        lo, hi = (r.yardsticks_fitted_on + (0, 0))[:2]
        paragraphs.append(
            "Is the model better than black-box predictors fitted on the same data? On the "
            f"same windows: {'; '.join(r.yardsticks.values())}. ARX and subspace were fitted "
            f"on samples {lo}..{hi - 1}; they are yardsticks, never used for control.")
        times = [t for t in YARDSTICK_TIMES if t in r.by_horizon.get("model", {}).get(
            "T_cab", {})]

        def cell(d: dict) -> str:
            return f"{format_number(d['rmse_K'], '.2f')} / {format_number(d['p90_K'], '.2f')}"

        rows = tuple((c, name if name == "model" else f"{name} (yardstick)",
                      *(cell(by[c][t]) for t in times))
                     for c in r.channels for name, by in r.by_horizon.items() if c in by)
        header = ("channel", "predictor", *(f"{t} s: RMSE / p90 |e| (K)" for t in times))
        return ReportSection("Validation design and yardsticks", paragraphs=tuple(paragraphs),
                             header=header, rows=rows)
    return ReportSection("Validation design and yardsticks", paragraphs=tuple(paragraphs))


@report_section(EconStage)
def _econ_model(r: EconStage) -> ReportSection:
    def pair(c) -> str:
        return f"{format_number(c.median_abs, '.2f')} / {format_number(c.p90_abs, '.2f')}"

    rows = tuple((ch, pair(r.econ[ch]), pair(r.paper[ch]) if ch in r.paper else "n/a")
                 for ch in r.econ)
    extra = ", ".join(f"{k} {format_number(v, '.3g')}" for k, v in r.extra_median_abs.items())
    return ReportSection(
        "Beyond the paper: the econ model beside the paper's",
        paragraphs=(
            "Both models fitted on the first part of one `acid excite --model econ` record "
            f"({format_number(r.duration_s / 3600.0, '.1f')} h: random speed, ambient and "
            f"steady holds) and validated by the same study ({r.starts} starts x {r.horizon} "
            "steps) on the rest. The econ model predicts the interior and the shell (the "
            "paper's holds them) and its compressor power is an identified map, RMS error "
            f"{format_number(r.power_map_rms_pct, '.2f')} % of the mean power "
            f"({format_number(r.power_map_steady_rms_pct, '.2f')} % on near-steady samples).",
            f"Median |error| of what only the econ model predicts: {extra} (K, g/kg, W, % of "
            "a window's compressor energy)."),
        header=("channel", "econ: median / p90 |error| (K)", "paper: median / p90 (K)"),
        rows=rows)


_LABELS = {"A": "A: paper NMPC, constant bound", "B": "B: paper NMPC, ICM bound",
           "D": "D: economic NMPC, no preview", "E": "E: economic NMPC, speed preview",
           "P": "P: production-style PI, coil reset", "F": "F: best fixed-coil PI",
           "plan": "best known plan (perfect information), replayed"}


@report_section(CavStudyStage)
def _where_the_energy_is(r: CavStudyStage) -> ReportSection:
    def f(x, spec=".2f") -> str:
        return format_number(x, spec)

    rows = []
    for cyc, c in r.cycles.items():
        for key, x in c.controllers.items():
            band = ("n/a" if not math.isfinite(x.in_rh_band) else
                    "yes" if x.in_rh_band else "outside RH band (not ranked)")
            rows.append((cyc.upper(), _LABELS.get(key, key), f(x.energy_MJ, ".4f"),
                         f(x.tail_corrected_energy_MJ, ".4f"), f(x.saving_tail_corrected_pct),
                         f(x.saving_vs_best_pi_pct), f(x.gap_to_best_plan_pct),
                         f(x.mean_T_cab_K - 273.15), f(x.mean_T_evap_set_K - 273.15, ".1f"),
                         f(x.pmv_mean), f(x.ppd_mean_pct, ".1f"), f(x.rh_mean_pct, ".0f"),
                         band))
    return ReportSection(
        "Where the energy is",
        paragraphs=(
            "Figures, not verdicts (the verdicts are the comparison engine's, in \"The "
            "energy answer\" above): one run per cycle, each controller tuned on the cycle it "
            "runs. Seven controllers on the high-fidelity plant over drive cycles, from the same "
            "warmed-up state, at the same mean cabin temperature (B's), the end state charged "
            "back by a common continuation (acid cav-study): the paper's NMPC (A, B), the "
            "economic NMPC (D, E), two tuned PI baselines (P: production-style coil reset; F: "
            "the best fixed coil set-point, searched) and the best known plan (perfect "
            "information; a feasible plan replayed on the plant, not a bound: its spread over "
            "independent optima is its uncertainty). Savings are against A and against F, "
            "gaps against the best known plan, all on the charged-back energies. Comfort is "
            "the mean T_cab and the cabin RH band; a controller outside the band is not "
            "ranked. PMV: ISO 7730, 1.2 met, 0.5 clo, 0.2 m/s.",
            f"{CONCLUSION} " + energy_conclusion(r)),
        header=("cycle", "controller", "energy (MJ)", "charged back (MJ)", "saving vs A (%)",
                "saving vs F (%)", "gap to plan (%)", "mean T_cab (°C)",
                "mean T_evap_set (°C)", "PMV", "PPD (%)", "RH (%)", "RH in band"),
        rows=tuple(rows))


def energy_conclusion(r: CavStudyStage) -> str:
    """A conclusion drawn only from the measured numbers of the study."""
    cyc = {k: c for k, c in r.cycles.items() if {"A", "E"} <= set(c.controllers)}
    if not cyc:
        return "the economic controllers were not run."
    names = ", ".join(k.upper() for k in cyc)
    sav = [c.controllers["E"].saving_tail_corrected_pct for c in cyc.values()]
    lo, hi = min(sav), max(sav)
    span = f"{lo:.1f} %" if abs(hi - lo) < 0.05 else f"{lo:.1f}-{hi:.1f} %"
    parts = [f"at equal mean cabin temperature, end state charged back, the economic NMPC "
             f"used {span} {'less' if lo >= 0 else 'more (at worst)'} energy than the paper's "
             f"NMPC ({names})"]
    vs_pi = [c.controllers["E"].saving_vs_best_pi_pct for c in cyc.values()]
    pi_charge = [c.controllers["E"].saving_vs_best_pi_pi_charge_pct for c in cyc.values()]
    if all(math.isfinite(v) for v in vs_pi):
        both = [v for v in vs_pi + pi_charge if math.isfinite(v)]
        parts.append(f"against the best fixed-coil PI at equal comfort its point differences "
                     f"were {min(both):+.2f} to {max(both):+.2f} points over the two charges "
                     "of the end state: one run per cycle, tuned on the cycle it is judged on, "
                     "is no verdict (a saving needs its interval over held-out scenarios)")
    gaps = [c.controllers["E"].gap_to_best_plan_pct for c in cyc.values()]
    spread = [c.best_plan_spread_pct for c in cyc.values()]
    if all(math.isfinite(g) for g in gaps):
        unc = (f" (the plan's spread over independent optima: up to {max(spread):.1f} %)"
               if all(math.isfinite(x) for x in spread) else "")
        parts.append(f"it lies {max(gaps):.1f} % at most above the best known plan (perfect "
                     f"information, a feasible plan, not a bound){unc}")
    prev = max(abs(c.preview_share_points) for c in cyc.values())
    parts.append(f"speed preview changed the saving by at most {prev:.2f} points"
                 + (", negligible" if prev < 0.5 else ""))
    t_A = sum(c.controllers["A"].mean_T_evap_set_K for c in cyc.values()) / len(cyc) - 273.15
    t_E = sum(c.controllers["E"].mean_T_evap_set_K for c in cyc.values()) / len(cyc) - 273.15
    w_A = sum(c.controllers["A"].w_cab_mean_g_kg for c in cyc.values()) / len(cyc)
    w_E = sum(c.controllers["E"].w_cab_mean_g_kg for c in cyc.values()) / len(cyc)
    if t_E > t_A + 1.0 and prev < 0.5:
        parts.append(f"the saving comes from the operating point, the coil set-point at "
                     f"{t_E:.1f} degC instead of {t_A:.1f} degC (a cabin at {w_E:.1f} instead "
                     f"of {w_A:.1f} g/kg: less latent load at a better COP), not from timing "
                     "cooling to speed")
    return "; ".join(parts) + "."


@report_section(PlantCheckStage)
def _plant_check(r: PlantCheckStage) -> ReportSection:
    word = {True: "pass", False: "FAIL", None: "n/a"}
    rows = tuple((c.group, c.name, c.reference,
                  "computed" if c.value != c.value and c.passed is not None else
                  f"{format_number(c.value, '.4g')} {c.unit}".strip(),
                  "information" if c.info else word[c.passed], c.note) for c in r.checks)
    n_pass = sum(c.passed is True for c in r.checks)
    n_fail = sum(c.passed is False for c in r.checks)
    n_info = sum(c.info for c in r.checks)
    return ReportSection(
        "Plant credentials (acid plant-check)",
        paragraphs=(
            "The high-fidelity plant (acid's default vehicle, the plant of every stage but "
            "Table I's) against published references other than the paper "
            f"(verdicts are acid plant-check's own criteria): {n_pass} pass, {n_fail} fail, "
            f"{n_info} information without a verdict, "
            f"{len(r.checks) - n_pass - n_fail - n_info} not run.",)
        + ((r.search_note,) if r.search_note else ()),
        header=("group", "credential", "reference", "plant", "check", "note"),
        rows=rows)


# the heating section registers itself on import (acid/report/heating.py)
from acid.report import heating as _heating  # noqa: E402, F401
