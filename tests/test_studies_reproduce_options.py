"""The run's sizes: a quick run is read as quick, a full one as full, also from a summary
written before a size was added (a size it did not record was the study's)."""

from __future__ import annotations

import dataclasses

import pytest

from acid.claims.options import ReproduceOptions, run_mode
from acid.errors import ConfigError
from acid.studies.cav_study import StudyConfig


def test_an_older_full_summary_without_the_newer_sizes_is_still_full():
    full = dataclasses.asdict(ReproduceOptions())
    older = {k: v for k, v in full.items() if k not in ("cav_tol_K", "cav_plan_variants")}
    assert run_mode(older) == run_mode(full) == "full"
    assert run_mode(ReproduceOptions.quick()) == "quick"
    assert run_mode({**older, "cav_tol_K": 0.02}) == "quick"


def test_the_quick_plan_variants_are_known_and_unknown_ones_refused():
    StudyConfig(plan_variants=ReproduceOptions.quick().cav_plan_variants)
    with pytest.raises(ConfigError, match="unknown plan variants: nope"):
        StudyConfig(plan_variants=("nope",))
