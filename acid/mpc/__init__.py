"""Moved to :mod:`acid.control` (controllers) and :mod:`acid.studies` (studies): this alias
package warns, and goes in the next release. Its modules are aliases of the new ones."""

import warnings

from acid.control.codegen.solver import NLPSolver  # noqa: F401
from acid.control.estimator import (  # noqa: F401
    BackoffConfig,
    EstimatorConfig,
    OffsetFreeEstimator,
)
from acid.control.icm import ICMConfig, icm_upper_bound, speed_target  # noqa: F401
from acid.control.nmpc import NMPC, MPCSolution, NMPCConfig, StepLog  # noqa: F401
from acid.errors import MovedWarning
from acid.studies.mpc_check.scenarios import (  # noqa: F401
    CheckResult,
    ClosedLoopRun,
    ScenarioResult,
    closed_loop,
    mpc_check,
    run_cav_scenario,
    run_model_scenario,
    run_plant_scenario,
)

__all__ = ["BackoffConfig", "CheckResult", "ClosedLoopRun", "EstimatorConfig", "ICMConfig",
           "MPCSolution", "NLPSolver", "NMPC", "NMPCConfig", "OffsetFreeEstimator",
           "ScenarioResult", "StepLog", "closed_loop", "icm_upper_bound", "mpc_check",
           "run_cav_scenario", "run_model_scenario", "run_plant_scenario", "speed_target"]

warnings.warn("acid.mpc has moved to acid.control and acid.studies; the old name will be "
              "removed in the next release", MovedWarning, stacklevel=2)
