"""Report sections built from typed stage results: one builder per stage result class.

A stage whose results need more than claim rows (a study beyond the paper, a plant check)
registers a builder here; the report shows its section after the claims::

    @report_section(MyStage)
    def _my_section(r: MyStage) -> ReportSection:
        return ReportSection("My study", paragraphs=(...,), header=(...), rows=(...))
"""

from __future__ import annotations

from collections.abc import Callable

from acid.report.html import ReportSection
from acid.report.numbers import format_number
from acid.stage_results import CavStudyStage, PlantCheckStage, StageResult, StudyResults

SECTION_BUILDERS: dict[type[StageResult], Callable[[StageResult], ReportSection]] = {}


def report_section(kind: type[StageResult]):
    """Decorator: register ``builder(result) -> ReportSection`` for results of ``kind``."""
    def register(builder):
        SECTION_BUILDERS[kind] = builder
        return builder
    return register


def sections_for(results: StudyResults) -> list[ReportSection]:
    """The sections of the stages that ran, in registration order."""
    out = []
    for kind, builder in SECTION_BUILDERS.items():
        r = results.get(kind)
        if r is not None:
            out.append(builder(r))
    return out


@report_section(CavStudyStage)
def _cav_study(r: CavStudyStage) -> ReportSection:
    def pct(x) -> str:
        return format_number(x, ".2f")

    labels = {"B": "ICM bound", "C": "speed-aware NMPC"}
    rows = tuple((f"{k}: {labels.get(k, k)}", pct(s.raw), pct(s.corrected),
                  pct(s.tail_corrected),
                  pct(r.saving_from_speed_pct[k].tail_corrected)
                  if k in r.saving_from_speed_pct else "n/a")
                 for k, s in r.savings_pct.items())
    return ReportSection(
        f"Beyond the paper: speed preview on {r.cycle.upper()}",
        paragraphs=(
            "Savings against a constant upper bound at equal mean cabin temperature, raw, "
            "with the end state's heat charged back (lumped capacities, and a measured "
            "continuation), and the part that disappears on a plant whose efficiency does "
            "not depend on speed.",
            f"eta_cop(v) identified from plant data: {format_number(r.eta_cop0, '.3f')} + "
            f"{format_number(r.eta_cop1_per_mps, '.4f')} v (v in m/s), "
            f"R^2 = {format_number(r.eta_cop_r2, '.2f')}."),
        header=("controller", "saving raw (%)", "C_eff-corrected (%)", "tail-corrected (%)",
                "owed to speed, tail-corrected (points)"),
        rows=rows)


@report_section(PlantCheckStage)
def _plant_check(r: PlantCheckStage) -> ReportSection:
    word = {True: "pass", False: "FAIL", None: "n/a"}
    rows = tuple((c.group, c.name, c.reference,
                  "computed" if c.value != c.value and c.passed is not None else
                  f"{format_number(c.value, '.4g')} {c.unit}".strip(),
                  word[c.passed], c.note) for c in r.checks)
    n_pass = sum(c.passed is True for c in r.checks)
    n_fail = sum(c.passed is False for c in r.checks)
    return ReportSection(
        "Plant credentials (acid plant-check)",
        paragraphs=(
            "The high-fidelity plant against published references other than the paper "
            f"(verdicts are acid plant-check's own criteria): {n_pass} pass, {n_fail} fail, "
            f"{len(r.checks) - n_pass - n_fail} not run.",),
        header=("group", "credential", "reference", "plant", "check", "note"),
        rows=rows)
