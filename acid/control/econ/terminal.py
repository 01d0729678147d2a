"""Economic terminal cost from the optimal steady state's multipliers (beyond the paper).

An economic NMPC's horizon (120 s) is short against the interior and the shell; what the
plan leaves in them at the horizon's end must be priced. The economic-MPC literature prices
it with the **multipliers of the optimal steady state** (the "rotated" stage cost of Diehl,
Amrit & Rawlings, IEEE TAC 56(3), 2011; Amrit, Rawlings & Angeli, Annual Reviews in Control
35(2), 2011): on the model's interval map ``x+ = F(x, u, d)`` solve::

    min_{x, u}  l(x, u) = Ts (P_comp + P_bl)
    s.t.        F(x, u, d) - x = 0                        (multiplier lam, J per unit state)
                T_cab_min <= T_cab <= T_cab_max,  Q_e >= 0,  u_min <= u <= u_max

at the exogenous values ``d = (v, T_amb)``. Stationarity in ``x`` reads
``lam = l_x + F_x^T lam (+ the bound's multiplier on T_cab)``: ``lam`` is the stationary
costate, the marginal energy (J) the optimal operation pays, from then on, for one unit
more of each state (K, kg/kg). The NMPC's terminal cost ``lam^T (x_N - x_0)`` therefore
charges the heat left in the slow states at what removing it will cost at the best operating
point, per state and at the speed and ambient given.

The problem is the economic NMPC's own (:func:`acid.control.econ.problem.ocp_spec` over the econ
declaration), taken to its steady state by the builder
(:meth:`acid.control.ocp.OCP.steady_state_nlp`): the same interval map, stage cost and
bounds. The steady states are solved with IPOPT (7 variables) on a grid of speeds over the power
map's speed data (about 2 m/s apart) and interpolated linearly in speed; one grid per
(ambient, band), computed when first asked and cached. Temperatures in K, energies in J.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import casadi as ca
import numpy as np

from acid.control.econ import problem
from acid.control.ocp import OCP
from acid.errors import SolverWarning
from acid.models.econ import model as econ_model
from acid.models.econ_params import EconParams

_NX, _NU = econ_model.nx, econ_model.nu
#: speed spacing of the grid, m/s
GRID_DV = 2.0


@dataclass(frozen=True)
class SteadyState:
    """The model's optimal steady state at one speed and ambient.

    Attributes
    ----------
    v_veh, T_amb : exogenous values, m/s and K.
    x : (5,) state (K, kg/kg); u : (2,) input [W_bl kg/s, T_evap_set K].
    power_W : P_comp + P_bl at the steady state, W.
    lam : (5,) multipliers of ``F(x, u, d) - x = 0``, J per unit state (K, kg/kg).
    success : IPOPT's verdict.
    """

    v_veh: float
    T_amb: float
    x: np.ndarray
    u: np.ndarray
    power_W: float
    lam: np.ndarray
    success: bool


class SteadyStatePrice:
    """Multipliers of the optimal steady state, interpolated in speed (module docstring).

    Parameters
    ----------
    params : identified econ model.
    u_min, u_max : (2,) input bounds [W_bl kg/s, T_evap_set K].
    comfort_weight : the NMPC's comfort price, W/K^2 per second (0: none); with it the steady
        state is the optimum of energy plus that price at a reference ``T_cab_ref``.
    """

    def __init__(self, params: EconParams, u_min, u_max, comfort_weight: float = 0.0):

        self.params = params
        self.u_min, self.u_max = np.asarray(u_min, float), np.asarray(u_max, float)
        # the economic NMPC's own problem: the steady state of its builder (the input
        # bounds, which may pin an input here, are applied per solve: u_min, u_max)
        cfg = problem.EconNMPCConfig(intervals=(params.Ts, params.Ts), terminal="none",
                                  stage_functions=False, compiled=False,
                                  comfort_weight=float(comfort_weight))
        self._comfort = cfg.comfort_weight > 0.0
        self._ocp = OCP(econ_model, problem.ocp_spec(cfg))
        # the NMPC's variable scaling (K, kg/kg, kg/s)
        self._x_off, self._x_scl = problem.X_OFFSET, problem.X_SCALE
        self._u_off, self._u_scl = problem.U_OFFSET, problem.U_SCALE
        self._theta = params.theta_all
        nlp = self._ocp.steady_state_nlp()
        self._solver = ca.nlpsol("acid_econ_steady", "ipopt", nlp, {
            "print_time": False, "ipopt": {"print_level": 0, "sb": "yes", "tol": 1e-10,
                                           "max_iter": 200}})
        self._sides = self._ocp.steady_state_sides
        self._cost_scale = cfg.cost_scale
        F = problem.at_parameters(problem.econ_interval(params.Ts), self._theta)
        xs, us = ca.SX.sym("x", _NX), ca.SX.sym("u", _NU)
        d = ca.SX.sym("d", econ_model.nd)
        out = dict(zip(F.name_out(), F(xs, us, d, ca.DM.zeros(_NX)), strict=True))
        self._power = ca.Function("power", [xs, us, d], [out["P_comp"] + out["P_bl"]])
        self._F = F
        lo, hi = params.power_map.domain.get("v_veh", (0.0, 36.0))
        n = max(2, int(np.ceil((hi - lo) / GRID_DV)) + 1)
        self.v_grid = np.linspace(lo, hi, n)
        self._grids: dict = {}
        self.failures = 0

    def steady_state(self, v_veh: float, T_amb: float, T_cab_min: float, T_cab_max: float,
                     guess: SteadyState | None = None, dist=None,
                     T_cab_ref: float | None = None) -> SteadyState:
        """Solve the steady-state NLP once (module docstring).

        ``dist`` : optional (5,) additive disturbances on the state derivatives (K/s,
        kg/kg/s), as in :func:`acid.models.econ.casadi_interval`; ``guess`` a nearby solution;
        ``T_cab_ref`` the comfort price's reference, K (with ``comfort_weight``; default the
        band's upper edge).
        """
        dist = np.zeros(_NX) if dist is None else np.asarray(dist, dtype=float)
        x_off, x_scl, u_off, u_scl = self._x_off, self._x_scl, self._u_off, self._u_scl
        if guess is not None:
            w0 = np.concatenate(((guess.x - x_off) / x_scl, (guess.u - u_off) / u_scl))
        else:
            x0 = np.array([T_cab_max, T_cab_max, 0.5 * (T_cab_max + T_amb), u_off[1], 0.008])
            w0 = np.concatenate(((x0 - x_off) / x_scl, np.zeros(_NU)))
        lbx = np.concatenate((np.full(_NX, -np.inf), (self.u_min - u_off) / u_scl))
        ubx = np.concatenate((np.full(_NX, np.inf), (self.u_max - u_off) / u_scl))
        # the band on T_cab and Q_e >= 0 (ocp_spec's soft bounds, hard here), limits 0
        limits = np.array([T_cab_max, T_cab_min, 0.0][:len(self._sides)])
        lbg = np.concatenate((np.zeros(_NX),
                              [-np.inf if s == "hi" else 0.0 for s in self._sides]))
        ubg = np.concatenate((np.zeros(_NX),
                              [0.0 if s == "hi" else np.inf for s in self._sides]))
        q = [T_cab_max if T_cab_ref is None else T_cab_ref] if self._comfort else []
        res = self._solver(x0=w0, p=np.concatenate(([v_veh, T_amb], self._theta, dist, q,
                                                    limits)),
                           lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
        ok = bool(self._solver.stats().get("success", False))
        wv = np.asarray(res["x"]).ravel()
        x = wv[:_NX] * x_scl + x_off
        u = wv[_NX:] * u_scl + u_off
        lam = np.asarray(res["lam_g"]).ravel()[:_NX] / x_scl / self._cost_scale
        return SteadyState(v_veh=float(v_veh), T_amb=float(T_amb), x=x, u=u,
                           power_W=float(self._power(x, u, [v_veh, T_amb])), lam=lam,
                           success=ok)

    def grid(self, T_amb: float, T_cab_min: float, T_cab_max: float,
             T_cab_ref: float | None = None) -> np.ndarray:
        """(len(v_grid), 5) multipliers over the speed grid (cached per ambient, band and
        comfort reference)."""
        ref = None if T_cab_ref is None or not self._comfort else round(float(T_cab_ref), 4)
        key = (round(float(T_amb), 2), round(float(T_cab_min), 3), round(float(T_cab_max), 3),
               ref)
        if key not in self._grids:
            lams, guess = [], None
            for v in self.v_grid:
                ss = self.steady_state(v, *key[:3], guess=guess, T_cab_ref=ref)
                if not ss.success:
                    ss = self.steady_state(v, *key[:3], T_cab_ref=ref)
                if ss.success:
                    guess = ss
                else:
                    self.failures += 1
                    warnings.warn(
                        f"econ terminal cost: no optimal steady state at {v:.1f} m/s, "
                        f"{key[0] - 273.15:.1f} degC ambient and band {key[1] - 273.15:.2f}-"
                        f"{key[2] - 273.15:.2f} degC; its neighbours' multipliers are used",
                        SolverWarning, stacklevel=3)
                lams.append(ss.lam if ss.success else np.full(_NX, np.nan))
            lam = np.array(lams)
            for j in range(_NX):  # a failed point takes its neighbours' value
                ok = np.isfinite(lam[:, j])
                lam[:, j] = (np.interp(self.v_grid, self.v_grid[ok], lam[ok, j])
                             if ok.any() else 0.0)
            self._grids[key] = lam
        return self._grids[key]

    def __call__(self, v_veh: float, T_amb: float, T_cab_min: float, T_cab_max: float,
                 T_cab_ref: float | None = None) -> np.ndarray:
        """(5,) multipliers at speed ``v_veh`` (linear in speed, held outside the grid)."""
        lam = self.grid(T_amb, T_cab_min, T_cab_max, T_cab_ref)
        return np.array([np.interp(v_veh, self.v_grid, lam[:, j]) for j in range(_NX)])
