"""Scenario sweeps: many drive cycles, climates, cabins and controllers, on Dask.

``load_spec(path)`` reads and validates a TOML specification (:mod:`acid.studies.sweep.spec`);
``run_sweep(spec, out)`` runs it on a local Dask cluster (or an existing one, or in this
process) and writes one tidy table (Parquet + CSV), summary figures and ``summary.json``
(:mod:`acid.studies.sweep.runner`). Controllers come from a small registry
(:mod:`acid.studies.sweep.controllers`); the climate is mapped onto the plant in one function
(:func:`acid.studies.sweep.conditions.plant_config_for`).
"""

from acid.studies.sweep.conditions import Conditions, plant_config_for
from acid.studies.sweep.context import ControllerRun, ScenarioContext
from acid.studies.sweep.controllers import controller_types, register_controller
from acid.studies.sweep.runner import SweepResult, run_sweep
from acid.studies.sweep.spec import Scenario, SweepSpec, load_spec, spec_from_dict

__all__ = ["load_spec", "spec_from_dict", "run_sweep", "SweepSpec", "SweepResult", "Scenario",
           "Conditions", "plant_config_for", "register_controller", "controller_types",
           "ScenarioContext", "ControllerRun"]
