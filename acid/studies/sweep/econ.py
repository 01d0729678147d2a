"""The economic NMPC as a sweep controller (``econ``): ``acid cav-study``'s D and E in a sweep.

``[controllers.<label>]`` with ``type = "econ"`` (or the label ``econ`` itself) runs
:class:`acid.control.econ.nmpc.EconNMPC` on the scenario's plant: the comfort band is the
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
``comfort_weight`` (W/K^2 per second, default 0) gives the NMPC ``acid cav-study``'s comfort
price instead: the band stays a soft bound and the price's reference is what ``match``
tunes (without ``match``: the scenario's set-point).
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from acid.errors import ConfigError
from acid.studies.sweep.context import ControllerRun, ScenarioContext
from acid.studies.sweep.controllers import register_controller
from acid.units import C2K

#: plant configuration fields that the econ identification does not depend on: the
#: excitation sets the ambient itself, and starts from a warmed-up state
_IDENTIFY_IGNORES = ("T_amb", "T_cab0", "T_int0", "T_shell0", "T_ew0", "T_cw0")


@dataclass(frozen=True)
class EconControllerConfig:
    """The economic NMPC of ``acid.control.econ.nmpc`` in a sweep.

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
        first (``acid cav-study``'s D and E; :mod:`acid.control.econ.modifier`).
    coil_max_C : warmest coil set-point, degC (``acid cav-study``'s 10 degC, Table II).
    comfort_weight : the comfort price, W/K^2 per second (0: tune the band's upper edge;
        ``acid cav-study`` runs 30).
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
    comfort_weight: float = 0.0

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
        if not 0.0 <= self.comfort_weight <= 1e5:
            raise ConfigError(f"comfort_weight = {self.comfort_weight:g} must lie in 0..1e5 "
                              "W/K^2 per second")


@functools.lru_cache(maxsize=8)
def _identified(config_json: str, hours: float, seed: int):
    """Econ parameters identified on the plant configuration ``config_json`` (cached per
    process)."""
    from acid.plant.config import PlantConfig
    from acid.plant.hifi import HifiPlant
    from acid.studies.cav_study import identify_econ

    config = PlantConfig(**json.loads(config_json))
    params, _ = identify_econ(functools.partial(HifiPlant, config), hours * 3600.0, seed)
    return params


def econ_params_for(ctx: ScenarioContext, config: EconControllerConfig):
    """The econ model of this scenario's plant (see the module docstring)."""
    from acid.models.econ_params import EconParams
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
        from acid.control.econ.nmpc import EconNMPC, EconNMPCConfig

        c, cond = self.config, ctx.conditions
        n_iv = int(round(c.horizon_s / ctx.Ts))
        econ = econ_params_for(ctx, c)
        target = ctx.completed[c.match].mean_T_cab if c.match else cond.T_set
        info = {}
        if c.modifier:
            from acid.control.econ.modifier import coil_modifier
            from acid.control.pi_baselines import COIL_RANGE

            # the same model, target and coil range on this scenario (D and E beside each
            # other, or with a comfort price): the same steady holds, run once
            key = ("coil_modifier", c.econ_params, float(c.identify_hours), int(c.seed),
                   float(target), float(c.coil_max_C))
            mod = ctx.shared.get(key)
            if mod is None:
                plant = ctx.make_plant()
                mod = ctx.shared[key] = coil_modifier(
                    econ, ctx.make_plant, plant.cfg, float(np.mean(ctx.v_step)), cond.T_amb,
                    target, start=ctx.start, coil_range=(COIL_RANGE[0], C2K(c.coil_max_C)))
            econ, info = mod.params, {"modifier_optimal_coil_K": [
                s["T_star_K"] for s in mod.steps]}
            ctx.shared["econ_model"] = econ
        mpc = EconNMPC(econ, EconNMPCConfig(intervals=(ctx.Ts,) * n_iv, T_cab_min=cond.T_low,
                                            T_cab_max=cond.T_high, preview=c.preview,
                                            T_evap_set_max=C2K(c.coil_max_C),
                                            compiled="auto" if c.compiled else False,
                                            comfort_weight=c.comfort_weight))
        comfort = c.comfort_weight > 0
        if not c.match:
            r = self._simulate(ctx, mpc, cond.T_set if comfort else cond.T_high)
            r.info.update(info)
            return r
        from acid.studies.cav_study import tune_mean

        def run_at(b: float):
            r = self._simulate(ctx, mpc, b)
            return r.mean_T_cab, r

        lo = cond.T_low - 2.0 if comfort else cond.T_low
        b, r, hist = tune_mean(run_at, target, lo, cond.T_high, c.tol_K, c.max_iter)
        return ControllerRun(r.run, r.end_state,
                             {**r.info, "bound_K": b, "matched_to": c.match,
                              "target_mean_K": target, "tuning_runs": len(hist), **info})

    @staticmethod
    def _simulate(ctx: ScenarioContext, mpc, setting: float) -> ControllerRun:
        """The closed loop ``u = mpc.make_step(x, previews); plant.step(u)`` from the
        scenario's start with the upper cabin bound, or with a comfort price its reference,
        at ``setting`` (K)."""
        from acid.control.econ.nmpc import stage_means
        from acid.models.econ import STATES
        from acid.studies.sweep.controllers import direct_loop, rh_into_info

        mpc.reset()
        iv = mpc.config.intervals
        T_amb_preview = np.full(ctx.n + ctx.v_preview.size, ctx.conditions.T_amb)

        key = "T_cab_ref" if mpc.config.comfort_weight > 0 else "T_cab_max"

        def make_step(meas, k):
            return mpc.make_step([meas[name] for name in STATES],
                                 stage_means(ctx.v_preview, k, iv, ctx.Ts),
                                 stage_means(T_amb_preview, k, iv, ctx.Ts), **{key: setting})

        plant = ctx.make_plant()
        upper = setting if key == "T_cab_max" else ctx.conditions.T_high   # the band's edge
        r = direct_loop(ctx, plant, make_step, "econ", upper,
                        step_ms=lambda n: np.asarray(mpc.log.step_time_s[-n:]) * 1e3,
                        fallback=lambda n: np.asarray(mpc.log.fallback[-n:], dtype=bool))
        rh_into_info(r, plant.cfg.p_atm)
        return r


@dataclass(frozen=True)
class PlanControllerConfig:
    """The best known plan (perfect information) of ``acid cav-study`` in a sweep.

    Attributes
    ----------
    match : label of the controller whose mean cabin temperature the plan must meet
        (required: a plan is only compared at equal comfort).
    econ_params, identify_hours, seed : the econ model, as the ``econ`` controller's.
    coil_max_C : warmest coil set-point, degC.
    tol_K : tolerance of the replay's mean cabin temperature, K.
    max_iter : plans solved per variant while the replay's mean is re-set to the target.
    """

    match: str = ""
    econ_params: str = "identify"
    identify_hours: float = 6.0
    seed: int = 0
    coil_max_C: float = 10.0
    tol_K: float = 0.02
    max_iter: int = 4

    def __post_init__(self):
        if not self.match:
            raise ConfigError('a plan needs match = "<label>" (equal comfort)')
        EconControllerConfig(econ_params=self.econ_params, identify_hours=self.identify_hours,
                             coil_max_C=self.coil_max_C, tol_K=self.tol_K,
                             max_iter=self.max_iter)


class PlanController:
    """The best known plan on a sweep's scenario: a whole-cycle optimum of the econ model
    from the scenario's start, its end state priced at the optimal steady state's
    multipliers, replayed open loop on the plant (:mod:`acid.control.econ.best_plan`).

    Two independent optima compete when the ``econ`` controller ran before it with its coil
    modifier: one on the identified model, one on the corrected model. Each is tail-corrected
    with the scenario's continuation; the least is the plan, ``plan_spread_pct`` (max - min
    over the variants that met the target mean) its uncertainty. Like every plan, a feasible
    operation, not a bound. For a pull-down from the soak the band's upper edge is raised to
    the start's cabin temperature (the mean is what is held equal).
    """

    def __init__(self, config: PlanControllerConfig):
        self.config = config

    def run(self, ctx: ScenarioContext) -> ControllerRun:
        import warnings

        from acid.errors import ExtrapolationWarning

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ExtrapolationWarning)  # the econ row counts them
            return self._run(ctx)

    def _run(self, ctx: ScenarioContext) -> ControllerRun:
        from acid.control.econ.terminal import SteadyStatePrice
        from acid.models.econ import STATES
        from acid.studies.sweep.context import tail_energy_J

        c, cond = self.config, ctx.conditions
        target = ctx.completed[c.match].mean_T_cab
        plant = ctx.make_plant()
        plant.reset(ctx.start)
        meas = plant.measure()
        x0 = np.array([float(meas[n]) for n in STATES])
        T_high = max(cond.T_high, float(x0[0]) + 0.5)
        models = {"identified_model": econ_params_for(ctx, EconControllerConfig(
            econ_params=c.econ_params, identify_hours=c.identify_hours, seed=c.seed))}
        if "econ_model" in ctx.shared:
            models["corrected_model"] = ctx.shared["econ_model"]
        v_mean = float(np.mean(ctx.v_step))
        found = {}
        for name, econ in models.items():
            price = SteadyStatePrice(econ, [0.05, C2K(3.0)], [0.15, C2K(c.coil_max_C)])(
                v_mean, cond.T_amb, cond.T_low, cond.T_high)
            r = self._matched(ctx, econ, x0, price, target, T_high)
            tail = tail_energy_J(ctx, r.end_state, ctx.tail_s)
            found[name] = (r, r.run.energy_J() + (tail if np.isfinite(tail) else 0.0))
        matched = [k for k, (r, _) in found.items() if abs(r.mean_T_cab - target) <= c.tol_K]
        pool = matched or [min(found, key=lambda k: abs(found[k][0].mean_T_cab - target))]
        best = min(pool, key=lambda k: found[k][1])
        e = [found[k][1] for k in matched]
        spread = 100.0 * (max(e) - min(e)) / min(e) if len(e) > 1 else float("nan")
        r = found[best][0]
        r.info.update(best_variant=best, plan_spread_pct=spread, matched_to=c.match,
                      target_mean_K=target, variants={
                          k: {"energy_plus_tail_MJ": v / 1e6, "mean_T_cab_K": q.mean_T_cab,
                              "matched": k in matched} for k, (q, v) in found.items()})
        return r

    def _matched(self, ctx: ScenarioContext, econ, x0, price, target: float,
                 T_high: float) -> ControllerRun:
        """The plan from ``x0`` whose replay meets the target mean (re-set mean)."""
        from acid.control.econ.best_plan import PlanConfig, best_known_plan
        from acid.studies.sweep.controllers import direct_loop, rh_into_info

        c, cond = self.config, ctx.conditions
        T_req, best, guess = target, None, None
        T_amb = np.full(ctx.n, cond.T_amb)
        for _ in range(c.max_iter):
            pc = PlanConfig(T_mean=float(np.clip(T_req, cond.T_low, T_high)),
                            T_low=cond.T_low, T_high=T_high, cyclic=False,
                            T_evap_set_max=C2K(c.coil_max_C))
            plan = best_known_plan(econ, ctx.v_step, T_amb, pc, guess=guess, x_start=x0,
                                   terminal_price=price)
            inputs = plan.inputs
            plant = ctx.make_plant()
            r = direct_loop(ctx, plant, lambda meas, k, u=inputs: u[k], "plan", T_high)
            rh_into_info(r, plant.cfg.p_atm)
            err = r.mean_T_cab - target
            r.info.update(model_energy_MJ=plan.energy_J / 1e6, solve_status=plan.status,
                          plan_mean_request_K=pc.T_mean)
            if best is None or abs(err) < abs(best[1]):
                best = (r, err)
            if abs(err) <= c.tol_K:
                break
            T_req, guess = pc.T_mean - err, (plan.x, plan.inputs)
        return best[0]


register_controller("econ", EconControllerConfig, EconController,
                    "the economic NMPC on the identified power map (acid cav-study's D/E)")
register_controller("plan", PlanControllerConfig, PlanController,
                    "the best known plan (perfect information), replayed (acid cav-study's "
                    "plan)")

__all__ = ["EconController", "EconControllerConfig", "PlanController",
           "PlanControllerConfig", "econ_params_for"]
