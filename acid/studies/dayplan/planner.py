"""Identify the parked cabin on the plant's records and plan the pre-conditioning power over
the parked window as one optimal-control problem on the declared model.

**Identification** (:func:`identify`): the parked phases of the training days (switched-off
soaks and the production controller's pull-downs, one sample a minute: the cabin air at each
minute's start, the mean electric power, ambient and sun) fitted by simulation error over
each phase (output error; the latent mass starts at the cabin's temperature, as the planner
starts it), the free rows of ``acid.models.parked_cabin`` on a log scale, scipy's
trust-region least squares. The full-power line ``P_cap`` (the most the plan may ask for, by cabin
temperature): least squares through the pull-downs' first ``CAP_MINUTES`` minutes.

**The plan** (:func:`plan_power`): from the car's cabin when it parks, the model run with the
pre-conditioning off up to ``WINDOW_MIN`` minutes before the forecast departure (starting
earlier never pays: the cabin's time constant is well under that), then over the window at
one-minute stages::

    min  sum_i dt (price_i P_grid,i / eta_charger + v_bat P_bat,i) / 3.6e6      (USD)
    s.t. the model; 0 <= P_grid <= the charger's DC output; P_grid + P_bat <= P_cap(T_cab);
         E_bat <= the battery's usable energy left (soft, 1e4 USD per kWh and stage);
         T_cab within the band by ``MARGIN_K`` over the last ``margin_min`` minutes
         before the forecast departure (soft, 10 USD per K and stage)

``v_bat`` (USD per kWh taken from the battery while parked) is a stated value: the dearest
grid hour over the charger, so the plan never prefers the battery to the plug (a kWh from
the battery is range the trip then lacks, and is bought back later). Solved by IPOPT (an
LP in effect: the declaration is linear), one NLP per horizon length built once and reused
(the parameters, the preview and the limits are NLP parameters).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from acid.control.ocp import OCP, OCPSpec, SoftBound
from acid.errors import ConfigError
from acid.models.parked_cabin import FREE, T_REF, parked_cabin_model

#: the planning window before the forecast departure, min (assumption: pre-conditioning
#: that starts earlier only loses its effect to the ambient)
WINDOW_MIN = 120
#: comfort margin of the plan inside the band at departure, K (assumption: the model's
#: error on a pull-down; the study reports the comfort reached)
MARGIN_K = 1.0
#: the timer lead whose training-day runs give the pull-down records, min
FIT_LEAD_MIN = 30.0
#: penalty of the soft bounds, USD per unit and stage (comfort per K, power per kW,
#: battery per kWh): far above any price, so the bounds hold when they can
PENALTY = 10.0
#: the battery's usable energy as good as hard: USD per kWh beyond it and stage
PENALTY_BATTERY = 1e4
#: minutes at the start of each pull-down that give the full-power line
CAP_MINUTES = 3


@dataclass(frozen=True)
class ParkedRecord:
    """One parked phase at one sample a minute: ``T_cab`` (H + 1,) K at the minutes' starts
    (and the last one's end), ``P`` (H,) mean electric power W (0 while switched off),
    ``T_amb`` (H,) K and ``G`` (H,) W/m^2 at each minute's start."""

    T_cab: np.ndarray
    P: np.ndarray
    T_amb: np.ndarray
    G: np.ndarray

    @property
    def H(self) -> int:
        return int(self.P.size)


@dataclass(frozen=True)
class ParkedFit:
    """The identified parked cabin: ``values`` (parameter, value) pairs, the simulation
    error's RMS (K) over ``n_samples`` minutes of ``n_records`` phases, and the mean power
    ``P_full_W`` of the pull-downs' first minutes (the full-power line is in ``values``)."""

    season: str
    values: tuple[tuple[str, float], ...]
    rms_K: float
    n_samples: int
    n_records: int
    P_full_W: float

    def model(self):
        return parked_cabin_model(self.season, dict(self.values))

    def to_dict(self) -> dict:
        return {"season": self.season, "values": dict(self.values), "rms_K": self.rms_K,
                "n_samples": self.n_samples, "n_records": self.n_records,
                "P_full_W": self.P_full_W}


@lru_cache(maxsize=32)
def _accumulated(season: str, H: int) -> ca.Function:
    return parked_cabin_model(season).F.mapaccum("acc", H)


def simulate(season: str, theta: np.ndarray, rec: ParkedRecord) -> np.ndarray:
    """The model's cabin over a record (H,) K, from the record's first cabin temperature
    (the mass at the same temperature), the power, ambient and sun as recorded."""
    F = _accumulated(season, rec.H)
    x0 = np.array([rec.T_cab[0], rec.T_cab[0], 0.0])
    U = np.vstack([rec.P, np.zeros(rec.H)])
    D = np.vstack([rec.T_amb, rec.G])
    X, _ = F(x0, U, D, np.tile(theta[:, None], (1, rec.H)))
    return np.asarray(X)[0]


def identify(season: str, records: Sequence[ParkedRecord]) -> ParkedFit:
    """Fit the free rows of the parked cabin to ``records`` by simulation error (module
    docstring). Raises ConfigError without a pull-down among the records."""
    from scipy.optimize import least_squares

    recs = [r for r in records if r.H >= 2]
    starts = [(r, int(np.flatnonzero(r.P > 0)[0])) for r in recs if np.any(r.P > 0)]
    if not starts:
        raise ConfigError("parked cabin: no pull-down among the records")
    # the full-power line: power against the cabin at the minute's start, over the first
    # CAP_MINUTES of each pull-down (the production controller at full output)
    Tc = np.concatenate([r.T_cab[j:j + CAP_MINUTES] for r, j in starts])
    Pc = np.concatenate([r.P[j:j + CAP_MINUTES] for r, j in starts])
    A = np.vstack([np.ones_like(Tc), Tc - T_REF]).T
    cap = np.linalg.lstsq(A, Pc, rcond=None)[0] if np.ptp(Tc) > 1.0 else \
        np.array([float(np.mean(Pc)), 0.0])
    P_full = float(np.mean(Pc))
    base = parked_cabin_model(season, {"P_cap0": float(cap[0]), "P_cap1": float(cap[1])})
    names = base.parameter_names
    free = [names.index(n) for n in FREE]
    theta0 = base.values.copy()
    lo = np.log([base.parameter(n).min if base.parameter(n).min > 0 else 1e-3 for n in FREE])
    hi = np.log([base.parameter(n).max for n in FREE])

    def theta_of(z):
        th = theta0.copy()
        th[free] = np.exp(z)
        return th

    def residuals(z):
        th = theta_of(z)
        return np.concatenate([simulate(season, th, r) - r.T_cab[1:] for r in recs])

    z0 = np.clip(np.log(np.maximum(theta0[free], 1e-3)), lo + 1e-6, hi - 1e-6)
    sol = least_squares(residuals, z0, bounds=(lo, hi), x_scale=1.0, diff_step=1e-4,
                        max_nfev=200)
    th = theta_of(sol.x)
    res = residuals(sol.x)
    return ParkedFit(season, tuple((n, float(v)) for n, v in zip(names, th, strict=True)),
                     float(np.sqrt(np.mean(res ** 2))), int(res.size), len(recs), P_full)


# ----------------------------------------------------------------------------- the plan
@dataclass(frozen=True)
class PowerPlan:
    """A plan over the window: stage start times ``t_s`` (N,) s, electric power ``P_W``
    (N,) (grid + battery), its grid part, the predicted cabin ``T_cab_K`` (N + 1,), the
    full power ``P_cap_W`` (N,) at the predicted cabin, the objective (USD, penalties
    included) and the solver's status."""

    t_s: np.ndarray
    P_W: np.ndarray
    P_grid_W: np.ndarray
    T_cab_K: np.ndarray
    P_cap_W: np.ndarray
    cost_USD: float
    status: str

    def on_blocks(self) -> list[tuple[float, float]]:
        """The minutes whose planned power is at least half the full power predicted for
        them, merged into (start, end) blocks, s: where the production controller runs."""
        blocks: list[list[float]] = []
        for t, p, cap in zip(self.t_s, self.P_W, self.P_cap_W, strict=True):
            if p > 1.0 and p >= 0.5 * cap:
                if blocks and abs(blocks[-1][1] - t) < 1e-6:
                    blocks[-1][1] = t + 60.0
                else:
                    blocks.append([t, t + 60.0])
        return [(a, b) for a, b in blocks]


def _cost(s):
    return {"grid": s.dt * s.P_grid * s.price / s.eta_charger / 3.6e6,
            "battery": s.dt * s.P_bat * s.v_bat / 3.6e6}


@lru_cache(maxsize=8)
def _problem(season: str, N: int, cap_W: float, eta_charger: float, v_bat: float):
    from acid.control.codegen.solver import NLPSolver

    model = parked_cabin_model(season)
    side = {"upper": 400.0} if season == "summer" else {"lower": 200.0}
    spec = OCPSpec(
        N=N, stage_cost=_cost, stage_parameters=("price",),
        input_bounds={"P_grid": (0.0, cap_W), "P_bat": (0.0, 2.0e4)},
        soft_bounds=(SoftBound("T_cab", penalty=PENALTY, **side),
                     SoftBound("P_over", upper=0.0, penalty=PENALTY, scale=1e-3,
                               expr=lambda s: s.P_el - s.P_cap),
                     SoftBound("E_bat", upper=1e3, penalty=PENALTY_BATTERY)),
        u_offset={"P_grid": 0.0, "P_bat": 0.0}, u_scale={"P_grid": 1e-3, "P_bat": 1e-3},
        x_offset={"T_cab": 290.0, "T_m": 290.0}, x_scale={"T_cab": 10.0, "T_m": 10.0},
        constants={"eta_charger": eta_charger, "v_bat": v_bat}, cost_scale=10.0)
    ocp = OCP(model, spec)
    solver = NLPSolver(f"acid_dayplan_{season}_{N}", ocp.nlp, "ipopt",
                       {"print_time": False, "calc_lam_p": False,
                        "ipopt": {"print_level": 0, "sb": "yes", "tol": 1e-8,
                                  "max_iter": 300}}, compiled=False)
    return ocp, solver


def plan_power(fit: ParkedFit, T_cab0: float, t0: float, forecast_s: float,
               weather: Callable[[float], tuple[float, float]],
               price: Callable[[float], float], band_K: float, *, cap_W: float,
               eta_charger: float, v_bat: float, E_avail_kWh: float, margin_min: float = 0.0,
               margin_K: float = MARGIN_K, window_min: int = WINDOW_MIN,
               T_cab_now: tuple[float, float] | None = None) -> PowerPlan | None:
    """The pre-conditioning plan for a car parked at ``t0`` (s after midnight) with its cabin
    at ``T_cab0`` K and leaving at ``forecast_s``: module docstring. ``weather(t) -> (T_amb K,
    G W/m^2)``, ``price(t)`` USD/kWh at the plug, ``band_K`` the comfort band's edge.
    ``T_cab_now``: (time s, cabin K) measured at the window's start (the car woken to plan):
    the cabin state takes it, the mass keeps the model's soak estimate. None when the car
    leaves within a minute."""
    n_total = int(math.floor((forecast_s - t0) / 60.0 + 1e-9))
    N = min(int(window_min), n_total)
    if T_cab_now is not None:
        N = min(N, int(math.floor((forecast_s - T_cab_now[0]) / 60.0 + 1e-9)))
    if N < 1:
        return None
    season = fit.season
    model = fit.model()
    theta = model.values
    x = np.array([T_cab0, T_cab0, 0.0])
    t = t0
    for _ in range(n_total - N):  # the soak, switched off, up to the window
        x = model.step(x, [0.0, 0.0], list(weather(t)), theta)[0]
        t += 60.0
    if T_cab_now is not None:
        x[0] = T_cab_now[1]
    ts = forecast_s - 60.0 * np.arange(N, 0, -1)
    d = np.array([weather(float(ti)) for ti in ts])
    q = np.array([[price(float(ti))] for ti in ts])
    ocp, solver = _problem(season, N, float(cap_W), float(eta_charger), float(v_bat))
    summer = season == "summer"
    ready = ts + 60.0 >= forecast_s - 60.0 * margin_min - 1e-6  # x(i+1) inside the margin
    lim_T = np.where(ready, band_K - margin_K if summer else band_K + margin_K,
                     400.0 if summer else 200.0)
    par = ocp.parameters(
        np.zeros(ocp.par.size), x0=x, theta=theta, d=d, q=q,
        bounds={("T_cab", "hi" if summer else "lo"): lim_T,
                ("P_over", "hi"): np.zeros(N),
                ("E_bat", "hi"): np.full(N, max(E_avail_kWh, 0.0))})
    guess = ocp.guess(x, d, theta, np.array([0.0, 0.0]))
    res = solver.solve(guess, par, ocp.lbx, ocp.ubx, ocp.lbg, ocp.ubg)
    if not res.success:
        return PowerPlan(ts, np.zeros(N), np.zeros(N), ocp.states(guess)[:, 0],
                         np.zeros(N), math.nan, str(res.status))
    U, X = ocp.plan(res.x), ocp.states(res.x)
    p = dict(fit.values)
    return PowerPlan(ts, U[:, 0] + U[:, 1], U[:, 0], X[:, 0],
                     p["P_cap0"] + p["P_cap1"] * (X[:-1, 0] - T_REF),
                     float(res.f) / 10.0, str(res.status))


__all__ = ["FIT_LEAD_MIN", "MARGIN_K", "PENALTY", "WINDOW_MIN", "ParkedFit", "ParkedRecord",
           "PowerPlan", "identify", "plan_power", "simulate"]
