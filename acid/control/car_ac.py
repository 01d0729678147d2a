"""Economic NMPC of the real car's A/C on the identified model ``car_ac``.

The car's control input is the air temperature after the evaporator ``T_evap`` (the i3's
A/C controller holds it; the logs show it between 5 degC, its floor while the compressor
runs, and the cabin's temperature when it does not). Over ``N`` samples of 5 s, from the
filter's estimate of the state, the NMPC solves (:class:`acid.control.ocp.OCP` over
:mod:`acid.models.car_ac`; nothing written twice)::

    min  sum_i Ts P_comp(x_i, T_evap_i, d_i)  +  a_sl sum_i Ts (s_hi,i + s_lo,i)
    s.t. x_{i+1} = F(x_i, T_evap_i, d_i)                      (car_cabin, RK4)
         T_cab_min - s_lo <= T_cab(i+1) <= T_cab_max + s_hi    (soft comfort band)
         T_evap_min <= T_evap_i <= T_evap_max

``P_comp`` is the declaration's identified power output, ``d_i = (T_amb, v_veh)`` previewed
per sample (the trip as logged: perfect preview, the study's stated assumption). The cabin
model's latent states (interior, shell, the solar/occupant load) come from the extended
Kalman filter the prediction-error fit uses (:class:`CabinFilter`, one sample of
``acid.ident.pem``'s filter per update), which sees only the logged cabin air temperature.

:class:`CabinPI` is the baseline: a PI loop on ``T_cab`` acting on the same set-point
(anti-windup by clamping), the structure of a production automatic climate control.
Temperatures in K, powers in W.
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass

import numpy as np

from acid.control.codegen.solver import NLPSolver
from acid.control.ocp import OCP, OCPSpec, SoftBound
from acid.errors import ConfigError, SolverWarning
from acid.executor import check_interrupt
from acid.models.declaration import Model
from acid.units import C2K


@dataclass(frozen=True)
class CarACConfig:
    """Options of the car's economic NMPC (temperatures in K).

    Attributes
    ----------
    N : horizon, samples of the model's Ts (default 120 x 5 s = 10 min: with 3 min the NMPC
        spent 3-23 % more than with 10 min on two held-out trips, the cabin's time constant
        being about 30 min; no terminal price).
    T_cab_min, T_cab_max : comfort band on the cabin air (default 21-25 degC).
    T_evap_min, T_evap_max : set-point bounds; 5 degC is the logs' floor (1st percentile
        of both trip halves while the compressor runs), 25 degC about the cabin air, above
        which the evaporator cools nothing (warmer air needs the heater, not priced here).
    slack_penalty : W per K of band violation (per second of it).
    tol, max_iter : IPOPT's tolerance and iteration limit.
    """

    N: int = 120
    T_cab_min: float = C2K(21.0)
    T_cab_max: float = C2K(25.0)
    T_evap_min: float = C2K(5.0)
    T_evap_max: float = C2K(25.0)
    slack_penalty: float = 2e4
    tol: float = 1e-7
    max_iter: int = 300

    def __post_init__(self):
        if self.N < 2:
            raise ConfigError(f"car A/C NMPC: horizon N must be at least 2, got {self.N}")
        if not self.T_cab_min < self.T_cab_max:
            raise ConfigError("car A/C NMPC: comfort band is empty (T_cab_min >= T_cab_max)")
        if not self.T_evap_min < self.T_evap_max:
            raise ConfigError("car A/C NMPC: T_evap_min must be below T_evap_max")

    def replace(self, **changes) -> CarACConfig:
        return dataclasses.replace(self, **changes)


def energy_cost(s) -> dict:
    """Electric energy of one sample, J: ``dt P_comp`` (the declaration's output)."""
    return {"E": s.dt * s.P_comp}


def ocp_spec(config: CarACConfig) -> OCPSpec:
    """The car's economic NMPC as a configuration of :class:`acid.control.ocp.OCP` over
    ``acid.models.car_ac.model``: energy cost, soft comfort band, ``T_evap`` bounds,
    scaled states (K about 300, the load in hundreds of W)."""
    c = config
    return OCPSpec(
        N=c.N, stage_cost=energy_cost,
        input_bounds={"T_evap": (c.T_evap_min, c.T_evap_max)},
        soft_bounds=(SoftBound("T_cab", c.T_cab_min, c.T_cab_max, c.slack_penalty,
                               per_second=True),),
        u_offset={"T_evap": 288.15}, u_scale={"T_evap": 0.1},
        x_offset={"T_cab": 300.0, "T_int": 300.0, "T_shell": 300.0},
        x_scale={"T_cab": 10.0, "T_int": 10.0, "T_shell": 10.0, "Q_sol": 300.0},
        cost_scale=1e-3)


class CarEconNMPC:
    """Economic NMPC on ``car_ac`` (module docstring).

    Parameters
    ----------
    model : the declaration (``acid.models.car_ac.model``).
    values : (np,) parameter values in its table order (the identified ones).
    config : options.
    """

    def __init__(self, model: Model, values, config: CarACConfig | None = None):
        self.model, self.config = model, config or CarACConfig()
        if "P_comp" not in model.output_names or [i.name for i in model.inputs] != ["T_evap"]:
            raise ConfigError(f"car A/C NMPC: model {model.name!r} needs the input T_evap and "
                              "the output P_comp (acid.models.car_ac)")
        self.ocp = OCP(model, ocp_spec(self.config))
        self.theta = np.asarray(values, dtype=float)
        self._solver = NLPSolver(
            "acid_car_ac_nmpc", self.ocp.nlp, "ipopt",
            {"print_time": False, "calc_lam_p": False,
             "ipopt": {"print_level": 0, "sb": "yes", "tol": self.config.tol,
                       "max_iter": self.config.max_iter, "bound_relax_factor": 0.0}},
            compiled=False)
        N, c = self.ocp.N, self.config
        self._par = self.ocp.parameters(np.zeros(self.ocp.par.size), theta=self.theta, bounds={
            ("T_cab", "hi"): np.full(N, c.T_cab_max), ("T_cab", "lo"): np.full(N, c.T_cab_min)})
        self.reset()

    def reset(self) -> None:
        self._w = None
        self.fallbacks = 0
        self.plans: list[np.ndarray] = []

    def _guess(self, x0, d) -> np.ndarray:
        """The previous solution shifted by one sample, else the model run at the band's
        middle set-point."""
        u = np.array([0.5 * (self.config.T_evap_min + self.config.T_evap_max)])
        return self.ocp.guess(x0, d, self.theta, u, self._w)

    def make_step(self, x, d_preview) -> float:
        """The set-point ``T_evap`` (K) for the next sample from the state ``x`` (nx,) and the
        previewed disturbances ``d_preview`` (N, nd) in the declaration's order (past the
        trip's end the caller repeats its last row). A failed solve applies the last plan's
        next move (counted in ``fallbacks``, one :class:`SolverWarning`)."""
        check_interrupt()  # a Ctrl-C its last solve swallowed stops here
        ocp = self.ocp
        d = np.asarray(d_preview, dtype=float).reshape(ocp.N, self.model.nd)
        par = ocp.parameters(self._par.copy(), x0=x, d=d)
        res = self._solver.solve(self._guess(x, d), par, ocp.lbx, ocp.ubx, ocp.lbg, ocp.ubg)
        if res.success:
            self._w = res.x
            plan = ocp.plan(res.x)[:, 0]
            self.plans.append(plan)
            return float(np.clip(plan[0], self.config.T_evap_min, self.config.T_evap_max))
        self.fallbacks += 1
        check_interrupt()  # the failure was the interrupt: say only that
        warnings.warn(f"car A/C NMPC solve failed ({res.status}); the last plan continues",
                      SolverWarning, stacklevel=2)
        self._w = None
        last = self.plans[-1][min(1, len(self.plans[-1]) - 1)] if self.plans else \
            self.config.T_evap_min
        return float(last)


@dataclass(frozen=True)
class CabinPI:
    """A PI loop on the cabin air acting on the evaporator air set-point (the baseline).

    ``T_evap = clip(T_evap_ff - Kp e - Ki sum(e) Ts)``, ``e = T_cab - T_set``; the integral
    stops where the set-point is clamped (anti-windup). ``Kp`` K/K, ``Ki`` K/(K s).
    """

    T_set: float
    Kp: float = 3.0
    Ki: float = 0.01
    T_evap_ff: float = C2K(12.0)
    T_evap_min: float = C2K(5.0)
    T_evap_max: float = C2K(25.0)

    def run(self):
        """A stateful controller: ``u = ctrl(T_cab, Ts)`` each sample."""
        integral = 0.0

        def step(T_cab: float, Ts: float) -> float:
            nonlocal integral
            e = T_cab - self.T_set
            raw = self.T_evap_ff - self.Kp * e - self.Ki * (integral + e * Ts)
            u = float(np.clip(raw, self.T_evap_min, self.T_evap_max))
            if u == raw or (raw < self.T_evap_min) != (e > 0):
                integral += e * Ts
            return u

        return step


class CabinFilter:
    """The extended Kalman filter of the prediction-error fit (``acid.ident.pem``), one
    sample per call, over the measured cabin air only: the state estimate the NMPC starts
    from (interior, shell and load are latent)."""

    def __init__(self, model: Model, values, x0):
        from acid.ident.pem import ekf_step, initial_spread

        self.model, self.theta = model, np.asarray(values, dtype=float)
        self.ekf_step = ekf_step(model, (model.state_names.index("T_cab"),))
        self.x = np.asarray(x0, dtype=float)
        self.P = np.diag(initial_spread(model) ** 2).ravel(order="F")

    def update(self, T_cab: float) -> np.ndarray:
        """The filtered state (nx,) after the cabin air ``T_cab`` (K) measured now."""
        self._m = [float(T_cab)]
        u0, d0 = np.zeros(self.model.nu), np.zeros(self.model.nd)   # xf reads neither
        return np.asarray(self.ekf_step(self.x, self.P, u0, d0, self.theta, self._m,
                                     [1.0])[5]).ravel()

    def predict(self, u, d) -> None:
        """One sample ahead under the input ``u`` and disturbances ``d`` held over it."""
        out = self.ekf_step(self.x, self.P, u, d, self.theta, self._m, [1.0])
        self.x, self.P = np.asarray(out[0]).ravel(), np.asarray(out[1]).ravel()
