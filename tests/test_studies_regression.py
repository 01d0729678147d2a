"""Closed loops against stored references (``tests/references/closed_loop.json``).

If a change to the plant, the model or the controller moves these numbers on purpose, run
``python -m acid.studies.mpc_check.regression --update`` and commit the new reference with the
change.
"""

from __future__ import annotations

import copy

import pytest

from acid.studies.mpc_check.regression import REFERENCE_FILE, compare, load, measure

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def stored() -> dict:
    return load(REFERENCE_FILE)


@pytest.fixture(scope="module")
def measured() -> dict:
    pytest.importorskip("acid.plant.hifi")
    return measure()


def test_closed_loops_match_the_stored_references(stored, measured):
    bad = [d.describe() for d in compare(stored, measured) if not d.ok]
    assert not bad, ("closed loops drifted from tests/references/closed_loop.json (if "
                     "intended: python -m acid.studies.mpc_check.regression --update):\n"
                     + "\n".join(bad))


def test_references_cover_every_scenario_with_a_2_percent_energy_tolerance(stored):
    assert {c.split(".")[0] for c in stored["cases"]} == {"model", "plant", "cav"}
    assert stored["tolerances"]["energy_MJ"]["rel"] <= 0.02
    for numbers in stored["cases"].values():
        assert {"energy_MJ", "max_violation_K", "first_W_bl_kg_s",
                "first_T_evap_set_K"} <= set(numbers)


@pytest.mark.parametrize(("factor", "fails"), [(1.03, True), (0.97, True), (1.01, False)])
def test_a_perturbed_energy_is_caught(stored, measured, factor, fails):
    perturbed = copy.deepcopy(measured)
    perturbed["plant.hot_start"]["energy_MJ"] *= factor
    bad = [d for d in compare(stored, perturbed) if not d.ok]
    assert [(d.case, d.quantity) for d in bad] == (
        [("plant.hot_start", "energy_MJ")] if fails else [])
    if fails:
        assert "tolerance 2 %" in bad[0].describe()


def test_a_missing_case_is_caught(stored, measured):
    fewer = {k: v for k, v in measured.items() if k != "cav.case2"}
    assert any(d.case == "cav.case2" and not d.ok for d in compare(stored, fewer))
