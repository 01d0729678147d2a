"""What a controller of a sweep is given (:class:`ScenarioContext`) and what it returns
(:class:`ControllerRun`).

Every controller of a scenario runs on its own fresh copy of the high-fidelity plant, from the
same start (the warmed-up plant state, or the configuration's hot soak), over the same speed
profile. Temperatures are kelvin inside; speeds m/s; times s.
"""

from __future__ import annotations

import json
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from acid.control.nmpc import NMPC, NMPCConfig
from acid.models.params import ModelParams, as_params
from acid.plant.config import PlantConfig
from acid.studies.mpc_check.scenarios import ClosedLoopRun, closed_loop
from acid.studies.sweep.conditions import Conditions

#: horizon of the NMPC that runs the common warm-up and the tails (paper Table II)
COMMON_HORIZON = 6

#: plant state carried from the warm-up into each run and from a run into its tail
#: (the reset keys of the high-fidelity plant)
STATE_KEYS = ("T_cab", "T_evap", "T_int", "T_shell", "T_cw", "w_cab")

#: samples of speed preview kept beyond the end of the run (horizons up to this long)
PREVIEW_SAMPLES = 64


#: paper NMPCs built in this thread, by (parameters, options), the most recent last; at most
#: BUILT_KEEP (each holds a compiled solver's memory slot)
_BUILT = threading.local()
BUILT_KEEP = 4


def built_nmpc(params, config: NMPCConfig) -> NMPC:
    """The paper NMPC of ``params`` and ``config``, built once per thread and handed out
    again for the same values (a build generates and hashes its C: about 40 ms of CPU, 15 % of
    a short scenario). A scenario's warm-up, controllers and tails share one build, so do a
    worker's scenarios of one climate. Every closed loop resets the controller it is given
    (:func:`closed_loop`), so a reused one starts as a new one: the same moves."""
    cache = getattr(_BUILT, "nmpc", None)
    if cache is None:
        cache = _BUILT.nmpc = OrderedDict()
    key = (json.dumps(as_params(params).to_json_dict(), sort_keys=True, default=repr),
           json.dumps(config.to_json_dict(), sort_keys=True, default=repr))
    mpc = cache.pop(key, None)
    if mpc is None:
        mpc = NMPC(params, config)
    cache[key] = mpc
    while len(cache) > BUILT_KEEP:
        cache.popitem(last=False)
    return mpc


def plant_state(plant) -> dict:
    """The plant's full state (``STATE_KEYS``; K, w_cab kg/kg), to restart a copy from it."""
    m = plant.measure()
    return {k: float(m[k]) for k in STATE_KEYS if k in m}


@dataclass(frozen=True)
class ControllerRun:
    """One controller's closed loop in a scenario.

    Attributes
    ----------
    run : the closed-loop record (states, inputs, powers, solve times).
    end_state : plant state at the end (``STATE_KEYS``), K.
    info : extra numbers the controller reports (e.g. a tuned bound, K).
    """

    run: ClosedLoopRun
    end_state: dict
    info: dict = field(default_factory=dict)

    @property
    def mean_T_cab(self) -> float:
        """Mean cabin temperature over samples 1 .. n, K."""
        return float(np.mean(self.run.T_cab[1:]))


@dataclass
class ScenarioContext:
    """Everything a controller needs to run one scenario.

    Attributes
    ----------
    conditions : climate and comfort (edge units; ``T_amb``, ``T_set``, ``T_low``,
        ``T_high`` in K as properties).
    plant_config : the high-fidelity plant's configuration for these conditions.
    params : control-oriented model parameters (eqs. 1-5) for model-based controllers.
    v_step : (n,) mean vehicle speed over each step, m/s.
    v_preview : (n + PREVIEW_SAMPLES,) the same followed by what the vehicle does next
        (the cycle's next pass, or the constant speed), for controllers that preview it.
    start : common initial plant state (K), None for the configuration's hot soak.
    completed : runs of the controllers that already ran in this scenario, by label.
    tick : called once per closed-loop step (interrupt checks, progress).
    tail_s : the scenario's common continuation that charges back an end state, s (0: none).
    shared : objects a controller leaves for the later ones of the same scenario, by name
        (``"econ_model"``: the econ model with the coil modifier that ``econ`` ran on; the
        coil modifier itself, by its inputs, so two econ controllers run its holds once).
    """

    conditions: Conditions
    plant_config: PlantConfig
    params: ModelParams
    v_step: np.ndarray
    v_preview: np.ndarray
    start: dict | None = None
    completed: dict = field(default_factory=dict)
    tick: Callable[[], None] | None = None
    tail_s: float = 0.0
    shared: dict = field(default_factory=dict)

    @property
    def Ts(self) -> float:
        """Sample time, s."""
        return float(self.params.Ts)

    @property
    def n(self) -> int:
        """Steps of the run."""
        return int(self.v_step.size)

    @property
    def start_T_cab(self) -> float:
        """Cabin temperature at t = 0, K."""
        return float(self.start["T_cab"] if self.start else self.plant_config.T_cab0)

    def make_plant(self, mode: str = "direct", **overrides):
        """A fresh high-fidelity plant for these conditions (``overrides``: config fields)."""
        from acid.plant.hifi import HifiPlant

        cfg = self.plant_config.replace(**overrides) if overrides else self.plant_config
        return HifiPlant(cfg, mode=mode)

    def nmpc_config(self, horizon: int = 6, **options) -> NMPCConfig:
        """Paper NMPC options for these conditions: eq. 4's ``T_amb`` is the scenario's
        ambient, the lower cabin bound the comfort band's lower edge (Table II otherwise)."""
        return NMPCConfig(N=int(horizon), T_amb=self.conditions.T_amb,
                          T_cab_min=self.conditions.T_low, **options)

    def nmpc(self, horizon: int = 6, **options) -> NMPC:
        """The paper NMPC of :meth:`nmpc_config` (built once per thread: :func:`built_nmpc`)."""
        return built_nmpc(self.params, self.nmpc_config(horizon, **options))

    def constant_bound(self, value_K: float, horizon: int) -> np.ndarray:
        """A constant upper bound over the run and one horizon beyond it, K."""
        return np.full(self.n + int(horizon) + 1, float(value_K))

    def simulate(self, mpc, T_cab_max: np.ndarray, label: str,
                 start: dict | None = None, v_step: np.ndarray | None = None) -> ControllerRun:
        """``closed_loop`` of ``mpc`` on a fresh plant from ``start`` (default: the
        scenario's start) over ``v_step`` (default: the scenario's speed)."""
        plant = self.make_plant()
        run = closed_loop(plant, mpc, self.start if start is None else start, T_cab_max,
                          self.v_step if v_step is None else v_step, label,
                          progress=self.tick)
        return ControllerRun(run, plant_state(plant))


__all__ = ["ScenarioContext", "ControllerRun", "STATE_KEYS", "plant_state", "built_nmpc"]


def tail_energy_J(ctx: ScenarioContext, end_state: dict, seconds: float) -> float:
    """Energy of the common continuation from ``end_state`` (paper NMPC, constant bound at
    the set-point, cycle mean speed), J; NaN when ``seconds`` is 0."""
    n_t = int(round(seconds / ctx.Ts))
    if n_t <= 0:
        return float("nan")
    mpc = ctx.nmpc(COMMON_HORIZON)
    r = ctx.simulate(mpc, np.full(n_t + mpc.N + 1, ctx.conditions.T_set), "tail",
                     start=end_state, v_step=np.full(n_t, float(np.mean(ctx.v_step))))
    return r.run.energy_J()
