"""Where report sections register: one builder per stage result class
(:func:`report_section`), read in registration order by
:func:`acid.report.sections.sections_for`."""

from __future__ import annotations

from collections.abc import Callable

from acid.claims.results import StageResult
from acid.report.html import ReportSection

SECTION_BUILDERS: dict[type[StageResult], Callable[[StageResult], ReportSection]] = {}


def report_section(kind: type[StageResult]):
    """Decorator: register ``builder(result) -> ReportSection`` for results of ``kind``."""
    def register(builder):
        SECTION_BUILDERS[kind] = builder
        return builder
    return register
