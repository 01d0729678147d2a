"""The paper's eqs. 1-5 as functions of ``ModelParams``, for the controllers that still take
them (``acid/mpc``): each calls the declaration's own equation functions
(``acid.models.paper.step`` and ``output``), the one place the equations are written, with
the values of ``ModelParams``. Floats, numpy arrays (broadcasting over any batch shape),
complex numbers and CasADi symbols alike (the equations use ``+ - *`` only); kelvin, kg/s, W.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from acid.models.paper import PARAMETER_TABLE
from acid.models.paper import compressor_power as _compressor_power
from acid.models.paper import output as _output
from acid.models.paper import step as _step

_NAMES = tuple(row[0] for row in PARAMETER_TABLE)


def _signals(p, **signals) -> SimpleNamespace:
    """The names the declaration's equations read: parameters from ``p`` (a parameter set
    without gamma/tau, e.g. the econ model's, serves eq. 5 alone), signals as given."""
    values = (*getattr(p, "gamma", (0.0,) * 7), *getattr(p, "tau", (0.0,) * 3), *p.beta)
    return SimpleNamespace(**dict(zip(_NAMES, values, strict=True)), **signals)


def inlet_air(T_evap, W_bl, p):
    """Eq. 3: cabin inlet air temperature T_ain (K) from the evaporator wall and blower flow."""
    return _output(_signals(p, T_evap=T_evap, W_bl=W_bl))["T_ain"]


def cabin_step(T_cab, T_int, T_shell, T_ain, W_bl, p):
    """Eq. 1 with a given (e.g. measured) T_ain: cabin air one sample later (K)."""
    return _step(_signals(p, T_cab=T_cab, T_int=T_int, T_shell=T_shell, T_ain=T_ain,
                          W_bl=W_bl, T_evap=0.0, T_evap_set=0.0))["T_cab"]


def evap_step(T_evap, T_evap_set, p):
    """Eq. 2: evaporator wall temperature one sample later (K)."""
    return _step(_signals(p, T_evap=T_evap, T_evap_set=T_evap_set, T_cab=0.0, T_int=0.0,
                          T_shell=0.0, T_ain=0.0, W_bl=0.0))["T_evap"]


def step(T_cab, T_evap, W_bl, T_evap_set, T_int, T_shell, p):
    """Eqs. 1-3 together (eq. 3 substituted into eq. 1): (T_cab(k+1), T_evap(k+1),
    T_ain(k)), all K."""
    T_ain = inlet_air(T_evap, W_bl, p)
    nxt = _step(_signals(p, T_cab=T_cab, T_evap=T_evap, W_bl=W_bl, T_evap_set=T_evap_set,
                         T_int=T_int, T_shell=T_shell, T_ain=T_ain))
    return nxt["T_cab"], nxt["T_evap"], T_ain


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
    return _output(_signals(p, W_bl=W_bl, T_evap=0.0))["P_bl"]


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
