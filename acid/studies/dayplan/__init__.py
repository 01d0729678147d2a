"""The day planner built from a declared model (``acid.models.parked_cabin``): identified on
the plant's parked records, an optimal-control problem over the parked window
(:class:`acid.control.ocp.OCP`), its plan replayed on the plant by ``acid.studies.day``."""

from acid.studies.dayplan.planner import (
    FIT_LEAD_MIN,
    MARGIN_K,
    WINDOW_MIN,
    ParkedFit,
    ParkedRecord,
    PowerPlan,
    identify,
    plan_power,
)

__all__ = ["FIT_LEAD_MIN", "MARGIN_K", "WINDOW_MIN", "ParkedFit", "ParkedRecord", "PowerPlan",
           "identify", "plan_power"]
