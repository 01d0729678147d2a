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

The steady states are solved with IPOPT (7 variables) on a grid of speeds over the power
map's speed data (about 2 m/s apart) and interpolated linearly in speed; one grid per
(ambient, band), computed when first asked and cached. Temperatures in K, energies in J.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import casadi as ca
import numpy as np

from acid.econ import model
from acid.econ.params import EconParams
from acid.errors import SolverWarning

_X_OFF, _X_SCL = model.X_OFFSET, model.X_SCALE
_U_OFF, _U_SCL = model.U_OFFSET, model.U_SCALE
#: objective scale inside the NLP (kJ instead of J)
_COST_SCALE = 1e-3
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
    """

    def __init__(self, params: EconParams, u_min, u_max):
        self.params = params
        self.u_min, self.u_max = np.asarray(u_min, float), np.asarray(u_max, float)
        from acid.mpc.econ_nmpc import _at_parameters, econ_interval  # (it imports this)

        # the declaration's interval map, as the NMPC predicts with it
        F = _at_parameters(econ_interval(params.Ts), model.parameter_vector(params))
        z = ca.SX.sym("z", model.NX)
        w = ca.SX.sym("w", model.NU)
        d = ca.SX.sym("d", model.ND)
        dist = ca.SX.sym("dist", model.NX)
        x = ca.DM(_X_OFF) + ca.DM(_X_SCL) * z
        u = ca.DM(_U_OFF) + ca.DM(_U_SCL) * w
        xn, _T_ain, Q_e, P_c, P_b = F(x, u, d, dist)
        g = ca.vertcat((xn - x) / ca.DM(_X_SCL), x[0], Q_e / 1e3)
        nlp = {"x": ca.vertcat(z, w), "p": ca.vertcat(d, dist), "g": g,
               "f": _COST_SCALE * params.Ts * (P_c + P_b)}
        self._solver = ca.nlpsol("acid_econ_steady", "ipopt", nlp, {
            "print_time": False, "ipopt": {"print_level": 0, "sb": "yes", "tol": 1e-10,
                                           "max_iter": 200}})
        xs, us = ca.SX.sym("x", model.NX), ca.SX.sym("u", model.NU)
        out = F(xs, us, d, ca.DM.zeros(model.NX))
        self._power = ca.Function("power", [xs, us, d], [out[3] + out[4]])
        self._F = F
        lo, hi = params.power_map.domain.get("v_veh", (0.0, 36.0))
        n = max(2, int(np.ceil((hi - lo) / GRID_DV)) + 1)
        self.v_grid = np.linspace(lo, hi, n)
        self._grids: dict = {}
        self.failures = 0

    def steady_state(self, v_veh: float, T_amb: float, T_cab_min: float, T_cab_max: float,
                     guess: SteadyState | None = None, dist=None) -> SteadyState:
        """Solve the steady-state NLP once (module docstring).

        ``dist`` : optional (5,) additive disturbances on the state derivatives (K/s,
        kg/kg/s), as in :func:`acid.econ.model.step`; ``guess`` a nearby solution.
        """
        dist = np.zeros(model.NX) if dist is None else np.asarray(dist, dtype=float)
        if guess is not None:
            w0 = np.concatenate(((guess.x - _X_OFF) / _X_SCL, (guess.u - _U_OFF) / _U_SCL))
        else:
            x0 = np.array([T_cab_max, T_cab_max, 0.5 * (T_cab_max + T_amb), _U_OFF[1], 0.008])
            w0 = np.concatenate(((x0 - _X_OFF) / _X_SCL, np.zeros(model.NU)))
        lbx = np.concatenate((np.full(model.NX, -np.inf), (self.u_min - _U_OFF) / _U_SCL))
        ubx = np.concatenate((np.full(model.NX, np.inf), (self.u_max - _U_OFF) / _U_SCL))
        lbg = np.concatenate((np.zeros(model.NX), [T_cab_min, 0.0]))
        ubg = np.concatenate((np.zeros(model.NX), [T_cab_max, np.inf]))
        res = self._solver(x0=w0, p=np.concatenate(([v_veh, T_amb], dist)), lbx=lbx,
                           ubx=ubx, lbg=lbg, ubg=ubg)
        ok = bool(self._solver.stats().get("success", False))
        wv = np.asarray(res["x"]).ravel()
        x = wv[:model.NX] * _X_SCL + _X_OFF
        u = wv[model.NX:] * _U_SCL + _U_OFF
        lam = np.asarray(res["lam_g"]).ravel()[:model.NX] / _X_SCL / _COST_SCALE
        return SteadyState(v_veh=float(v_veh), T_amb=float(T_amb), x=x, u=u,
                           power_W=float(self._power(x, u, [v_veh, T_amb])), lam=lam,
                           success=ok)

    def grid(self, T_amb: float, T_cab_min: float, T_cab_max: float) -> np.ndarray:
        """(len(v_grid), 5) multipliers over the speed grid (cached per ambient and band)."""
        key = (round(float(T_amb), 2), round(float(T_cab_min), 3), round(float(T_cab_max), 3))
        if key not in self._grids:
            lams, guess = [], None
            for v in self.v_grid:
                ss = self.steady_state(v, *key, guess=guess)
                if not ss.success:
                    ss = self.steady_state(v, *key)
                if ss.success:
                    guess = ss
                else:
                    self.failures += 1
                    warnings.warn(
                        f"econ terminal cost: no optimal steady state at {v:.1f} m/s, "
                        f"{key[0] - 273.15:.1f} degC ambient and band {key[1] - 273.15:.2f}-"
                        f"{key[2] - 273.15:.2f} degC; its neighbours' multipliers are used",
                        SolverWarning, stacklevel=3)
                lams.append(ss.lam if ss.success else np.full(model.NX, np.nan))
            lam = np.array(lams)
            for j in range(model.NX):  # a failed point takes its neighbours' value
                ok = np.isfinite(lam[:, j])
                lam[:, j] = (np.interp(self.v_grid, self.v_grid[ok], lam[ok, j])
                             if ok.any() else 0.0)
            self._grids[key] = lam
        return self._grids[key]

    def __call__(self, v_veh: float, T_amb: float, T_cab_min: float, T_cab_max: float
                 ) -> np.ndarray:
        """(5,) multipliers at speed ``v_veh`` (linear in speed, held outside the grid)."""
        lam = self.grid(T_amb, T_cab_min, T_cab_max)
        return np.array([np.interp(v_veh, self.v_grid, lam[:, j]) for j in range(model.NX)])
