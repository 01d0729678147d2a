"""Thin names over the econ declaration (:mod:`acid.models.econ`, where the equations are
written once) for code that still passes an :class:`acid.econ.params.EconParams` (the
economic NMPC, its terminal cost, the best known plan, the modifier). No equation here: each
function converts the parameters to the declaration's names and calls the declaration's.

Symbolic paths (``step``, ``derivatives``, ``heat_content``) take CasADi scalars; numeric
batches go through CasADi Functions (``casadi_step``, ``simulate``).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import casadi as ca
import numpy as np

from acid.models import econ
from acid.models.econ import MAP_NAMES, STATES, AirSide

NX, NU, ND = len(STATES), 2, 2
#: Scaling of the NLPs' variables on this model (economic NMPC, steady state, bound):
#: z = (x - X_OFFSET) / X_SCALE, w = (u - U_OFFSET) / U_SCALE (K, kg/kg, kg/s)
X_OFFSET = np.array([293.15, 293.15, 293.15, 278.15, 0.008])
X_SCALE = np.array([1.0, 1.0, 1.0, 1.0, 1e-3])
U_OFFSET = np.array([0.1, 278.15])
U_SCALE = np.array([0.01, 1.0])
#: Length of :func:`parameter_vector`: the declared parameter vector of ``econ.model``.
N_THETA = econ.model.np


def parameter_vector(p) -> np.ndarray:
    """All numbers of ``p`` (``EconParams``) as the declared parameter vector."""
    return np.asarray(p.theta_all if hasattr(p, "theta_all") else p, dtype=float)


def symbolic_parameters(theta):
    """The parameters by name from the declared vector ``theta`` (numbers or CasADi), with
    ``power_map.coef`` as the economic NMPC reads it."""
    s = econ.parameters(theta)
    s["power_map"] = SimpleNamespace(coef=[s[n] for n in MAP_NAMES])
    return s


def _names(p):
    """The parameters by name from ``EconParams`` or an object with some of its attributes
    (a map or C_ew it lacks reads as zero, any other parameter as NaN)."""
    if isinstance(p, dict):
        return p
    pm = getattr(p, "power_map", None)
    return econ._ByName(
        {n: getattr(p, n, np.nan) for n in econ.THERMAL_NAMES}, C_ew=getattr(p, "C_ew", 0.0),
        **dict(zip(MAP_NAMES, pm.coef if pm is not None else [0.0] * len(MAP_NAMES),
                   strict=True)),
        **dict(zip(("beta1", "beta2", "beta3"), p.beta, strict=True)),
        **{c.name: c.value for c in econ.model.constants})


def air_side(T_cab, T_evap, w_cab, W_bl, T_amb, p) -> AirSide:
    """:func:`acid.models.econ.air_side` with ``EconParams``."""
    return econ.air_side(_names(p), T_cab, T_evap, w_cab, W_bl, T_amb)


def step(x, u, d, p, dt: float = 5.0, dist=None, n_sub: int | None = None) -> econ.Interval:
    """:func:`acid.models.econ.interval` with ``EconParams``: CasADi scalars, or numbers
    and arrays (evaluated over the batch by its CasADi Function)."""
    s = _names(p)
    if any(isinstance(v, (ca.SX, ca.MX)) for v in (*x, *u, *d, *(dist or ()), *s.values())):
        return econ.interval(s, x, u, d, dt, n_sub, dist)
    args = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (*x, *u, *d)))
    shape = args[0].shape
    n = int(np.prod(shape)) if shape else 1
    theta = np.array([s[k] for k in econ.model.parameter_names])
    w = np.zeros((NX, n)) if dist is None else np.broadcast_to(
        np.asarray(dist, float).reshape(NX, -1), (NX, n))
    A = np.vstack([a.reshape(1, n) for a in args])
    out = econ.casadi_interval(dt, n_sub).map(n)(A[:NX], A[NX:NX + NU], A[NX + NU:],
                                                 np.tile(theta, (n, 1)).T, w)
    xn, T_ain, Q_e, P_c, P_bl, Q_coil, T_ev = (np.asarray(o).reshape(-1, n) for o in out)
    return econ.Interval(x=tuple(r.reshape(shape) for r in xn), T_ain=T_ain.reshape(shape),
                         Q_coil=Q_coil.reshape(shape), T_evap=T_ev.reshape(shape),
                         Q_e=Q_e.reshape(shape), P_comp=P_c.reshape(shape),
                         P_bl=P_bl.reshape(shape), dt=float(dt))


def refrigerant_heat(Q_coil, T_evap_start, T_evap_end, dt: float, p):
    """:func:`acid.models.econ.refrigerant_heat` with ``EconParams``, W."""
    return econ.refrigerant_heat(_names(p), Q_coil, T_evap_start, T_evap_end, dt)


def compressor_power(Q_e, T_evap, v_veh, T_amb, pm):
    """The power map (``pm.coef`` in ``MAP_TERMS`` order) at the given inputs, W."""
    return econ.compressor_power(econ._ByName(zip(MAP_NAMES, pm.coef, strict=True)), Q_e,
                                 T_evap, v_veh, T_amb)


def blower_power(W_bl, p):
    """Paper eq. 5 with ``EconParams``, W."""
    return econ.blower_power(_names(p), W_bl)


def heat_content(x, v_veh, p):
    """:func:`acid.models.econ.heat_content` with ``EconParams``, J (+ constant)."""
    return econ.heat_content(_names(p), x, v_veh)


def casadi_step(p, dt: float, n_sub: int | None = None) -> ca.Function:
    """``F(x[5], u[2], d[2], dist[5]) -> (x_next[5], T_ain, Q_e, P_comp, P_bl)``: the
    declaration's interval at the numbers of ``p`` (P_comp unclipped)."""
    F = econ.casadi_interval(dt, n_sub)
    x, u, d, w = (ca.SX.sym(n, k) for n, k in (("x", NX), ("u", NU), ("d", ND), ("dist", NX)))
    out = F(x, u, d, ca.DM(parameter_vector(p)), w)[:5]
    return ca.Function("econ_step", [x, u, d, w], list(out), ["x", "u", "d", "dist"],
                       ["x_next", "T_ain", "Q_e", "P_comp", "P_bl"])


@dataclass(frozen=True)
class Trajectory:
    """A simulation over H intervals (numpy, batch dimensions first): ``x`` (..., H + 1, 5)
    states, ``T_ain``, ``Q_e``, ``P_comp`` (clipped at zero), ``P_bl`` (..., H) means."""

    x: np.ndarray
    T_ain: np.ndarray
    Q_e: np.ndarray
    P_comp: np.ndarray
    P_bl: np.ndarray


def simulate(x0, W_bl, T_evap_set, v_veh, T_amb, p, dt: float | None = None,
             dist=None) -> Trajectory:
    """Open loop over H intervals of ``dt`` (default ``p.Ts``), vectorised over a batch of
    starts: ``x0`` (..., 5), the signals (..., H); ``dist`` optional (5,) constant terms."""
    dt = float(p.Ts if dt is None else dt)
    x0 = np.asarray(x0, dtype=float)
    W, Ts_, v, Ta = np.broadcast_arrays(*(np.asarray(a, dtype=float)
                                          for a in (W_bl, T_evap_set, v_veh, T_amb)))
    H = W.shape[-1]
    batch = np.broadcast_shapes(x0.shape[:-1], W.shape[:-1])
    n = int(np.prod(batch)) if batch else 1
    F = casadi_step(p, dt).map(n)
    w = np.broadcast_to(np.zeros(NX) if dist is None else np.asarray(dist, float), (n, NX)).T
    sig = [np.broadcast_to(a, batch + (H,)).reshape(n, H) for a in (W, Ts_, v, Ta)]
    X = np.empty((n, H + 1, NX))
    X[:, 0] = np.broadcast_to(x0, batch + (NX,)).reshape(n, NX)
    out = np.empty((4, n, H))
    for k in range(H):
        r = F(X[:, k].T, np.vstack([sig[0][:, k], sig[1][:, k]]),
              np.vstack([sig[2][:, k], sig[3][:, k]]), w)
        X[:, k + 1] = np.asarray(r[0]).T
        out[:, :, k] = np.vstack([np.asarray(a).ravel() for a in r[1:]])
    sh = batch + (H,)
    return Trajectory(x=X.reshape(batch + (H + 1, NX)), T_ain=out[0].reshape(sh),
                      Q_e=out[1].reshape(sh), P_comp=np.maximum(out[2], 0.0).reshape(sh),
                      P_bl=out[3].reshape(sh))
