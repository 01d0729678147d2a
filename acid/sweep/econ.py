"""The economic NMPC as a sweep controller (``econ``): ``acid cav-study``'s D and E in a sweep.

``[controllers.<label>]`` with ``type = "econ"`` (or the label ``econ`` itself) runs
:class:`acid.mpc.econ_nmpc.EconNMPC` on the scenario's plant: the comfort band is the
scenario's, the horizon ``horizon_s`` in intervals of the sample time, the speed previewed
(``preview = true``, controller E of ``acid cav-study``) or held at its current value
(``preview = false``, controller D), the ambient held at the scenario's.

The econ model comes from ``econ_params``: ``"identify"`` (default) identifies it from the
scenario's plant configuration as ``acid cav-study`` does (``acid excite --model econ`` for
``identify_hours`` + ``acid fit --model econ``; once per worker process and plant
configuration, the climate fields and initial state aside since the excitation sweeps the
ambient itself), or a parameter file written by ``acid fit --model econ``.

``match = "<label>"`` tunes the upper cabin bound the NMPC is given until its mean cabin
temperature equals that controller's (the fair comparison of ``acid cav-study``).
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from acid.errors import ConfigError
from acid.sweep.context import ControllerRun, ScenarioContext
from acid.sweep.controllers import register_controller
from acid.units import C2K

#: plant configuration fields that the econ identification does not depend on: the
#: excitation sets the ambient itself, and starts from a warmed-up state
_IDENTIFY_IGNORES = ("T_amb", "T_cab0", "T_int0", "T_shell0", "T_ew0", "T_cw0")


@dataclass(frozen=True)
class EconControllerConfig:
    """The economic NMPC of ``acid.mpc.econ_nmpc`` in a sweep.

    Attributes
    ----------
    preview : use the previewed vehicle speed (``acid cav-study``'s E); False holds the
        current speed over the horizon (D).
    horizon_s : horizon, s (a whole number of sample times, 30-600 s).
    econ_params : ``"identify"`` or a parameter file of ``acid fit --model econ``.
    identify_hours : length of the identification record, h.
    seed : seed of the identification record.
    match : label of another controller; the cabin bound is tuned until this controller's
        mean cabin temperature equals that one's (default: the band's upper edge).
    tol_K : tolerance of the match, K.
    max_iter : closed-loop runs the match may take.
    compiled : solve as generated C when a compiler works (the first build of a horizon
        compiles for a minute or two, then is cached per user); False: inside CasADi.
    modifier : correct the model's coil economics from steady holds of the scenario's plant
        first (``acid cav-study``'s D and E; :mod:`acid.mpc.econ_modifier`).
    coil_max_C : warmest coil set-point, degC (``acid cav-study``'s 10 degC, Table II).
    """

    preview: bool = True
    horizon_s: float = 120.0
    econ_params: str = "identify"
    identify_hours: float = 6.0
    seed: int = 0
    match: str = ""
    tol_K: float = 0.02
    max_iter: int = 8
    compiled: bool = True
    modifier: bool = True
    coil_max_C: float = 10.0

    def __post_init__(self):
        if not 30.0 <= self.horizon_s <= 600.0:
            raise ConfigError(f"horizon_s = {self.horizon_s:g} must lie in 30..600 s")
        if not 1.0 <= self.identify_hours <= 24.0:
            raise ConfigError(f"identify_hours = {self.identify_hours:g} must lie in 1..24 h")
        if self.econ_params != "identify" and not Path(self.econ_params).is_file():
            raise ConfigError(f"econ_params = {self.econ_params!r}: no such file (or "
                              "'identify')")
        if not (self.tol_K > 0 and 1 <= self.max_iter <= 30):
            raise ConfigError("match needs tol_K > 0 and max_iter in 1..30")
        if not 4.0 <= self.coil_max_C <= 15.0:
            raise ConfigError(f"coil_max_C = {self.coil_max_C:g} must lie in 4..15 degC")


@functools.lru_cache(maxsize=8)
def _identified(config_json: str, hours: float, seed: int):
    """Econ parameters identified on the plant configuration ``config_json`` (cached per
    process)."""
    from acid.mpc.cav_study import identify_econ
    from acid.plant.config import PlantConfig
    from acid.plant.hifi import HifiPlant

    config = PlantConfig(**json.loads(config_json))
    params, _ = identify_econ(functools.partial(HifiPlant, config), hours * 3600.0, seed)
    return params


def econ_params_for(ctx: ScenarioContext, config: EconControllerConfig):
    """The econ model of this scenario's plant (see the module docstring)."""
    from acid.econ.params import EconParams
    from acid.plant.config import PlantConfig

    if config.econ_params != "identify":
        return EconParams.from_json(config.econ_params)
    ref = PlantConfig()
    neutral = ctx.plant_config.replace(**{k: getattr(ref, k) for k in _IDENTIFY_IGNORES})
    fields = {k: getattr(neutral, k) for k in PlantConfig.field_names()}
    return _identified(json.dumps(fields, sort_keys=True, default=str),
                       float(config.identify_hours), int(config.seed))


class EconController:
    """Controllers D and E of ``acid cav-study`` on a sweep's scenario."""

    def __init__(self, config: EconControllerConfig):
        self.config = config

    def run(self, ctx: ScenarioContext) -> ControllerRun:
        """The closed loop (tuned to ``match`` if set). Power-map extrapolation warnings are
        counted in the row's ``info`` (``extrapolation``: how many, and the first), not
        printed from the workers."""
        import warnings

        from acid.errors import ExtrapolationWarning

        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always", ExtrapolationWarning)
            r = self._run(ctx)
        extra = [str(w.message) for w in seen if issubclass(w.category, ExtrapolationWarning)]
        for w in seen:
            if not issubclass(w.category, ExtrapolationWarning):
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        if extra:
            r.info["extrapolation"] = {"count": len(extra), "first": extra[0]}
        return r

    def _run(self, ctx: ScenarioContext) -> ControllerRun:
        from acid.mpc.econ_nmpc import EconNMPC, EconNMPCConfig

        c, cond = self.config, ctx.conditions
        n_iv = int(round(c.horizon_s / ctx.Ts))
        econ = econ_params_for(ctx, c)
        target = ctx.completed[c.match].mean_T_cab if c.match else cond.T_set
        info = {}
        if c.modifier:
            from acid.mpc.econ_modifier import coil_modifier
            from acid.mpc.pi_baselines import COIL_RANGE

            plant = ctx.make_plant()
            mod = coil_modifier(econ, ctx.make_plant, plant.cfg, float(np.mean(ctx.v_step)),
                                cond.T_amb, target, start=ctx.start,
                                coil_range=(COIL_RANGE[0], C2K(c.coil_max_C)))
            econ, info = mod.params, {"modifier_optimal_coil_K": [
                s["T_star_K"] for s in mod.steps]}
        mpc = EconNMPC(econ, EconNMPCConfig(intervals=(ctx.Ts,) * n_iv, T_cab_min=cond.T_low,
                                            T_cab_max=cond.T_high, preview=c.preview,
                                            T_evap_set_max=C2K(c.coil_max_C),
                                            compiled="auto" if c.compiled else False))
        if not c.match:
            r = self._simulate(ctx, mpc, cond.T_high)
            r.info.update(info)
            return r
        from acid.mpc.cav_study import tune_mean

        def run_at(b: float):
            r = self._simulate(ctx, mpc, b)
            return r.mean_T_cab, r

        b, r, hist = tune_mean(run_at, target, cond.T_low, cond.T_high, c.tol_K, c.max_iter)
        return ControllerRun(r.run, r.end_state,
                             {"bound_K": b, "matched_to": c.match, "target_mean_K": target,
                              "tuning_runs": len(hist), **info})

    @staticmethod
    def _simulate(ctx: ScenarioContext, mpc, T_cab_max: float) -> ControllerRun:
        """The closed loop ``u = mpc.make_step(x, previews); plant.step(u)`` from the
        scenario's start with the upper cabin bound ``T_cab_max`` (K)."""
        from acid.econ.model import STATES
        from acid.mpc.econ_nmpc import stage_means
        from acid.sweep.controllers import direct_loop

        mpc.reset()
        iv = mpc.config.intervals
        T_amb_preview = np.full(ctx.n + ctx.v_preview.size, ctx.conditions.T_amb)

        def make_step(meas, k):
            return mpc.make_step([meas[name] for name in STATES],
                                 stage_means(ctx.v_preview, k, iv, ctx.Ts),
                                 stage_means(T_amb_preview, k, iv, ctx.Ts),
                                 T_cab_max=T_cab_max)

        r = direct_loop(ctx, ctx.make_plant(), make_step, "econ", T_cab_max,
                        step_ms=lambda n: np.asarray(mpc.log.step_time_s[-n:]) * 1e3,
                        fallback=lambda n: np.asarray(mpc.log.fallback[-n:], dtype=bool))
        r.info.pop("w_cab")
        return r


register_controller("econ", EconControllerConfig, EconController,
                    "the economic NMPC on the identified power map (acid cav-study's D/E)")

__all__ = ["EconController", "EconControllerConfig", "econ_params_for"]
