"""``acid reproduce``'s heating stage: independent of the other stages and the same in both
sizes. Its typed result read back from JSON, the report's heating section and its figure are
checked on the quick run's heating stage (``test_studies_reproduce.py``): the stage is not
shortened there, so it need not run twice."""

from __future__ import annotations

from acid.studies.reproduce import HEATING_YEAR, ReproduceOptions, build_stages


def test_the_stage_depends_on_no_other_and_runs_in_both_sizes():
    for opts in (ReproduceOptions(), ReproduceOptions.quick()):
        st = {s.name: s for s in build_stages(opts)}
        assert st["heating"].depends == ()
        assert st["heating"].config == HEATING_YEAR
