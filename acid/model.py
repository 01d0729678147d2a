"""The paper's eqs. 1-5 as functions of ``ModelParams``, for the controllers that still take
them (``acid/mpc``): each evaluates the declaration (``acid.models.paper``), the one place
the equations are written, traced into CasADi once. Floats, numpy arrays (broadcasting over
any batch shape) and CasADi symbols alike; kelvin, kg/s, W.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from acid.models.paper import compressor_power as _compressor_power
from acid.models.paper import model as _DECL


@functools.cache
def _equations() -> ca.Function:
    """``(T_cab, T_evap, W_bl, T_evap_set, T_int, T_shell, T_ain_in, theta) -> (eq. 1 with
    T_ain_in, eq. 1 with eq. 3 substituted, eq. 2, eq. 3, eq. 5)`` from the declaration."""
    sym = [ca.SX.sym(n) for n in ("T_cab", "T_evap", "W_bl", "T_evap_set", "T_int",
                                   "T_shell", "T_ain_in")]
    th = ca.SX.sym("theta", _DECL.np)
    x, u, d = ca.vertcat(*sym[0:2]), ca.vertcat(*sym[2:4]), ca.vertcat(*sym[4:6])
    raw = _DECL.equations_raw
    subs = [_DECL._x, _DECL._u, _DECL._d, _DECL._p, _DECL._yr]
    yr = ca.vertcat(sym[6], ca.SX(0))       # the measured T_ain; P_bl is read by nothing
    args = [x, u, d, th, yr]

    def at(expr):
        return ca.substitute([expr], subs, args)[0]

    x_next, y = _DECL.F(x, u, d, th)
    names = _DECL.output_names
    return ca.Function("paper_eqs", [*sym, th],
                       [at(raw["T_cab"]), x_next[0], x_next[1], y[names.index("T_ain")],
                        y[names.index("P_bl")]])


def _theta(p):
    """The declaration's 13 values of ``p`` (gamma, tau, beta; a parameter set without
    gamma/tau, e.g. the econ model's, reads eq. 5 only)."""
    vals = (*getattr(p, "gamma", (0.0,) * 7), *getattr(p, "tau", (0.0,) * 3), *p.beta)
    if any(isinstance(v, (ca.SX, ca.MX)) for v in vals):
        return ca.vertcat(*vals)
    return np.asarray(vals, dtype=float)


def _eval(p, T_cab=0.0, T_evap=0.0, W_bl=0.0, T_evap_set=0.0, T_int=0.0, T_shell=0.0,
          T_ain_in=0.0):
    """The five equations at these arguments (``_equations`` order)."""
    args = (T_cab, T_evap, W_bl, T_evap_set, T_int, T_shell, T_ain_in)
    theta = _theta(p)
    if isinstance(theta, ca.MX) or any(isinstance(a, (ca.SX, ca.MX)) for a in args):
        return _equations()(*args, theta)
    arr = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in args))
    shape, n = arr[0].shape, arr[0].size
    if n == 0:
        return tuple(np.zeros(shape) for _ in range(5))
    out = _equations().map(n)(*(a.reshape(1, n) for a in arr), np.tile(theta[:, None], n))
    if not shape:
        return tuple(float(np.asarray(o).item()) for o in out)
    return tuple(np.asarray(o).reshape(shape) for o in out)


def inlet_air(T_evap, W_bl, p):
    """Eq. 3: cabin inlet air temperature T_ain (K) from the evaporator wall and blower flow."""
    return _eval(p, T_evap=T_evap, W_bl=W_bl)[3]


def cabin_step(T_cab, T_int, T_shell, T_ain, W_bl, p):
    """Eq. 1 with a given (e.g. measured) T_ain: cabin air one sample later (K)."""
    return _eval(p, T_cab=T_cab, T_int=T_int, T_shell=T_shell, T_ain_in=T_ain, W_bl=W_bl)[0]


def evap_step(T_evap, T_evap_set, p):
    """Eq. 2: evaporator wall temperature one sample later (K)."""
    return _eval(p, T_evap=T_evap, T_evap_set=T_evap_set)[2]


def step(T_cab, T_evap, W_bl, T_evap_set, T_int, T_shell, p):
    """Eqs. 1-3 together: (T_cab(k+1), T_evap(k+1), T_ain(k)), all K."""
    out = _eval(p, T_cab, T_evap, W_bl, T_evap_set, T_int, T_shell)
    return out[1], out[2], out[3]


def air_heat_flow(W_bl, T_ain, T_amb, c_p):
    """Numerator of eq. 4: c_p * W_bl * (T_amb - T_ain), W (c_p in J/(kg K))."""
    return _compressor_power(W_bl, T_ain, T_amb, c_p, 1.0)


def compressor_power(W_bl, T_ain, T_amb, p, eta_cop=None):
    """Eq. 4 (``acid.models.paper.compressor_power``) with ``p.c_p`` and ``p.eta_cop``;
    ``eta_cop`` overrides the latter (a scalar, an array per stage, a CasADi symbol)."""
    return _compressor_power(W_bl, T_ain, T_amb, p.c_p, p.eta_cop if eta_cop is None
                             else eta_cop)


def blower_power(W_bl, p):
    """Eq. 5: P_bl = beta1 W_bl^2 + beta2 W_bl + beta3, W."""
    return _eval(p, W_bl=W_bl)[4]


def evap_steady_state(T_evap_set, p):
    """Fixed point of eq. 2 for a constant set-point (K); requires |gamma4 + gamma5| < 1.
    Eq. 2 is affine in T_evap: T* = b / (1 - a), a and b read off the equation."""
    b = evap_step(0.0 * T_evap_set, T_evap_set, p)
    a = evap_step(1.0 + 0.0 * T_evap_set, T_evap_set, p) - b
    return b / (1.0 - a)


def cabin_steady_state(T_ain, W_bl, T_int, T_shell, p):
    """Fixed point of eq. 1 for constant inputs (K), read off the affine eq. 1 as above."""
    b = cabin_step(0.0 * T_ain, T_int, T_shell, T_ain, W_bl, p)
    a = cabin_step(1.0 + 0.0 * T_ain, T_int, T_shell, T_ain, W_bl, p) - b
    return b / (1.0 - a)


def simulate(x0, W_bl, T_evap_set, T_int, T_shell, p):
    """Multi-step open-loop simulation of eqs. 1-3, vectorised over any batch of starts.

    ``x0`` (..., 2) initial [T_cab, T_evap] (K); ``W_bl, T_evap_set, T_int, T_shell``
    (..., H) over the horizon (kg/s, K), leading dimensions broadcasting against
    ``x0[..., 0]``. Returns ``T_cab, T_evap`` (..., H + 1), K, from the initial state, and
    ``T_ain`` (..., H), K, at steps 0 .. H-1.
    """
    x0 = np.asarray(x0, dtype=float)
    W_bl, T_evap_set, T_int, T_shell = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (W_bl, T_evap_set, T_int, T_shell)))
    H = W_bl.shape[-1]
    batch = np.broadcast_shapes(x0.shape[:-1], W_bl.shape[:-1])
    T_cab, T_evap = np.empty(batch + (H + 1,)), np.empty(batch + (H + 1,))
    T_ain = np.empty(batch + (H,))
    T_cab[..., 0], T_evap[..., 0] = x0[..., 0], x0[..., 1]
    for k in range(H):  # loop over time only; every start advances at once
        T_cab[..., k + 1], T_evap[..., k + 1], T_ain[..., k] = step(
            T_cab[..., k], T_evap[..., k], W_bl[..., k], T_evap_set[..., k],
            T_int[..., k], T_shell[..., k], p)
    return T_cab, T_evap, T_ain
