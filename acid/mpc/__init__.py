"""Predictive climate control: the NMPC of paper eqs. 7-13, Intelligent Constraint
Management (ICM) and the closed-loop scenarios of paper section IV."""

from acid.mpc.estimator import BackoffConfig, EstimatorConfig, OffsetFreeEstimator
from acid.mpc.icm import ICMConfig, icm_upper_bound, speed_target
from acid.mpc.nmpc import NMPC, MPCSolution, NMPCConfig, StepLog
from acid.mpc.scenarios import (
    CheckResult,
    ClosedLoopRun,
    ScenarioResult,
    closed_loop,
    mpc_check,
    run_cav_scenario,
    run_model_scenario,
    run_plant_scenario,
)
from acid.mpc.solver import NLPSolver

__all__ = ["BackoffConfig", "CheckResult", "ClosedLoopRun", "EstimatorConfig", "ICMConfig",
           "MPCSolution", "NLPSolver", "NMPC", "NMPCConfig", "OffsetFreeEstimator",
           "ScenarioResult", "StepLog", "closed_loop", "icm_upper_bound", "mpc_check",
           "run_cav_scenario", "run_model_scenario", "run_plant_scenario", "speed_target"]
