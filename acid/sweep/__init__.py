"""Moved to :mod:`acid.studies.sweep`: this alias package warns, and goes in the next release.
Its modules are aliases of the new ones."""

import warnings

from acid.errors import MovedWarning
from acid.studies.sweep import (  # noqa: F401
    Conditions,
    ControllerRun,
    Scenario,
    ScenarioContext,
    SweepResult,
    SweepSpec,
    controller_types,
    load_spec,
    plant_config_for,
    register_controller,
    run_sweep,
    spec_from_dict,
)

__all__ = ["load_spec", "spec_from_dict", "run_sweep", "SweepSpec", "SweepResult", "Scenario",
           "Conditions", "plant_config_for", "register_controller", "controller_types",
           "ScenarioContext", "ControllerRun"]

warnings.warn("acid.sweep has moved to acid.studies.sweep; the old name will be removed in the "
              "next release", MovedWarning, stacklevel=2)
