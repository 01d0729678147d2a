"""The sizes of the ``acid reproduce`` study and its run mode.

The claims are judged only on a run of the study's full sizes; a run with other sizes (``--quick``)
is a quick run whose shortened stages are not judged. ``acid reproduce`` (:mod:`acid.studies.
reproduce`) runs with these options and hands its results to the claims; ``acid claims`` judges a
``summary.json`` again from the options stored in it.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass

from acid.claims.registry import ENERGY_CYCLES


@dataclass(frozen=True)
class ReproduceOptions:
    """Sizes of the study. ``quick()`` is a small version for tests and first looks."""

    sweep_duration_s: float = 600.0
    excite_duration_s: float = 4 * 3600.0
    estimation_fraction: float = 0.5
    excite_seed: int = 0
    fit_method: str = "oe"
    starts: int = 60
    horizon: int = 300
    timing_repeats: int = 5
    cav_cycles: tuple[str, ...] = ENERGY_CYCLES
    cav_warmup_s: float = 7200.0
    cav_tail_s: float = 2400.0
    econ_duration_s: float = 6 * 3600.0
    econ_horizon_s: float = 120.0
    econ_compiled: bool = True
    #: the cav study's mean-cabin match (K) and the best known plan's variants beside the
    #: cyclic plan (None: all of them)
    cav_tol_K: float = 0.005
    cav_plan_variants: tuple[str, ...] | None = None
    #: the comparison engine at ``acid compare --quick``'s sizes (fewer knobs, a shorter
    #: stop-and-go cycle, looser periodic tolerances)
    engine_quick: bool = False
    #: the engine's drive cycles (each at 30 and 38 degC, one trains, one is held out);
    #: empty: ``acid compare``'s default set
    engine_cycles: tuple[str, ...] = ()
    #: the engine's families again at F's mean cabin temperature on the held-out scenarios
    #: (the matched comparison, e.g. E at F's T_cab)
    engine_match_mean: bool = True

    @classmethod
    def quick(cls) -> ReproduceOptions:
        # the economic NMPC compiled as in the study (built once per user and cached; a cav
        # cycle then costs two thirds of its CPU inside CasADi), the cav study's controllers
        # matched to 0.05 K, the engine without its runs at F's mean cabin temperature (its
        # results are not judged)
        return cls(sweep_duration_s=300.0, excite_duration_s=2 * 3600.0, starts=12,
                   horizon=120, timing_repeats=1, cav_warmup_s=300.0,
                   cav_tail_s=120.0, econ_duration_s=3 * 3600.0, econ_horizon_s=30.0,
                   cav_tol_K=0.05,
                   cav_plan_variants=("cyclic_corrected_model",),
                   engine_quick=True, engine_match_mean=False,
                   engine_cycles=("hwfet", "stopgo"))


def run_mode(opts: ReproduceOptions | dict) -> str:
    """"full" for the study's sizes (``ReproduceOptions()``), else "quick": a run whose
    sizes differ from the study's (``--quick``) cannot judge the claims of the stages it
    shortens (``acid.claims.registry.QUICK_RUN_JUDGES``)."""
    d = opts if isinstance(opts, dict) else dataclasses.asdict(opts)
    full = json.loads(json.dumps(dataclasses.asdict(ReproduceOptions())))
    # a size an older run did not record was the study's (its default)
    return "full" if {**full, **json.loads(json.dumps(d))} == full else "quick"


def is_quick(opts: ReproduceOptions | dict) -> bool:
    """True unless ``opts`` are the full study's (see :func:`run_mode`)."""
    return run_mode(opts) != "full"
