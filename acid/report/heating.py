"""The report's heating section from ``acid.claims.results.HeatingStage``: the
heating plant's credentials that need no logs, each with the criterion ``acid heating-check``
states for it, and the whole year at a few ambients (information: no criterion, no verdict).
acid's own checks, not the paper's claims. No computation here."""

from __future__ import annotations

import math

from acid.claims.results import HeatingStage
from acid.numbers import format_number
from acid.report.html import ReportSection
from acid.report.registry import report_section

_WORD = {True: "pass", False: "FAIL", None: "n/a"}


def _value(v: float, unit: str) -> str:
    return "computed" if math.isnan(v) else f"{format_number(v, '.4g')} {unit}".strip()


@report_section(HeatingStage)
def heating_section(r: HeatingStage) -> ReportSection:
    """The credentials as rows with their criteria, then the year's shares as rows without a
    verdict."""
    rows = [(c.group, c.name, c.reference, _value(c.value, c.unit),
             "information" if c.info else _WORD[c.passed], c.note) for c in r.checks]
    n_pass = sum(c.passed is True for c in r.checks)
    n_fail = sum(c.passed is False for c in r.checks)
    for p in sorted(r.year, key=lambda p: (p.cycle, p.vehicle, p.T_amb_C, p.heating)):
        system = "A/C" if p.heating == "-" else p.heating
        rows.append(("year", f"{p.cycle.upper()}, {p.vehicle}, {format_number(p.T_amb_C, 'g')} "
                     f"degC, {system}: share of range the climate costs",
                     "none (acid's own figure; no criterion)",
                     f"{format_number(100.0 * p.share, '.1f')} %",
                     "information",
                     f"climate {format_number(p.E_climate_kWh, '.3f')} kWh (heater "
                     f"{format_number(p.E_heater_kWh, '.3f')}), mean cabin "
                     f"{format_number(p.T_cab_mean_C, '.1f')} degC"))
    return ReportSection(
        "Winter: heating plant and the whole year",
        paragraphs=(
            "acid's own checks, not the paper's claims. The heating plant (coolant heater, heat "
            "pump with frost and defrost, windscreen fogging, production controller) against "
            "published references, with the criteria acid heating-check states for each "
            f"(verdicts only there): {n_pass} pass, {n_fail} fail. The rows against the real "
            "BMW i3 winter logs need the logs (acid heating-check --logs) and are not run here.",
            "The whole year (acid year-sweep, one pass of the cycle from a soak at ambient; "
            f"heating plant below {format_number(r.switch_over_C, 'g')} degC with and without "
            "the heat pump, cooling plant above): the share of range the climate costs, "
            "climate / (traction + 12 V base + climate). Information, no verdict: acid states "
            "no criterion for it."),
        header=("group", "credential", "reference", "plant", "check", "note"),
        rows=tuple(rows))


__all__ = ["heating_section"]
