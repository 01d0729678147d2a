"""Old import paths kept for one release (the layout of ``ARCHITECTURE.md`` moved them).

Each old module is a two-line file that calls :func:`alias`: it warns once
(:class:`acid.errors.MovedWarning`, a ``FutureWarning``: shown to users by default) and makes
the old name the new module itself, so ``from acid.mpc.nmpc import NMPC`` and
``acid.mpc.nmpc.NMPC`` keep working and patching either name patches the one module.
"""

from __future__ import annotations

import importlib
import sys
import warnings

#: old module -> its home now (the old paths are removed in the next release); the old
#: packages ``acid.mpc``, ``acid.sweep`` and ``acid.econ`` re-export their names with a warning
PACKAGES: dict[str, str] = {"acid.mpc": "acid.control, acid.studies",
                            "acid.sweep": "acid.studies.sweep",
                            "acid.econ": "acid.models.econ_params"}
#: old module -> its home now
MOVED: dict[str, str] = {
    "acid.mpc.nmpc": "acid.control.nmpc",
    "acid.mpc.econ_nmpc": "acid.control.econ.nmpc",
    "acid.mpc.econ_terminal": "acid.control.econ.terminal",
    "acid.mpc.econ_modifier": "acid.control.econ.modifier",
    "acid.mpc.best_plan": "acid.control.econ.best_plan",
    "acid.mpc.pi_baselines": "acid.control.pi_baselines",
    "acid.mpc.estimator": "acid.control.estimator",
    "acid.mpc.icm": "acid.control.icm",
    "acid.mpc.speed_model": "acid.control.speed_model",
    "acid.mpc.solver": "acid.control.codegen.solver",
    "acid.mpc.codegen": "acid.control.codegen.build",
    "acid.mpc.export": "acid.control.codegen.export_paper",
    "acid.control.export": "acid.control.codegen.export",
    "acid.mpc.cav_study": "acid.studies.cav_study",
    "acid.mpc.scenarios": "acid.studies.mpc_check.scenarios",
    "acid.mpc.regression": "acid.studies.mpc_check.regression",
    "acid.sweep.conditions": "acid.studies.sweep.conditions",
    "acid.sweep.context": "acid.studies.sweep.context",
    "acid.sweep.controllers": "acid.studies.sweep.controllers",
    "acid.sweep.econ": "acid.studies.sweep.econ",
    "acid.sweep.results": "acid.studies.sweep.results",
    "acid.sweep.runner": "acid.studies.sweep.runner",
    "acid.sweep.scenario": "acid.studies.sweep.scenario",
    "acid.sweep.spec": "acid.studies.sweep.spec",
    "acid.car_study": "acid.studies.car_study",
    "acid.reproduce": "acid.studies.reproduce",
    "acid.plant.check": "acid.studies.credentials.plant",
    "acid.plant.check_heating": "acid.studies.credentials.heating",
    "acid.params": "acid.models.params",
    "acid.econ.params": "acid.models.econ_params",
    "acid.hac": "acid.ident.hac",
    "acid.yardsticks": "acid.ident.yardsticks",
    "acid.analysis": "acid.ident.analysis",
    "acid.claims.paper": "acid.paper",
    "acid.report.numbers": "acid.numbers",
    "acid.models.plant": "acid.plant.declared",
    "acid.plant.fmu": "acid.plant.fmi.plant",
    "acid.plant.fmu_export": "acid.plant.fmi.export",
    "acid.stage_results": "acid.claims.results",
}


def alias(old: str) -> None:
    """Make the module ``old`` (being imported) an alias of ``MOVED[old]``, with a warning."""
    from acid.errors import MovedWarning

    new = MOVED[old]
    warnings.warn(f"{old} has moved to {new}; the old name will be removed in the next "
                  "release", MovedWarning, stacklevel=3)
    sys.modules[old] = importlib.import_module(new)
