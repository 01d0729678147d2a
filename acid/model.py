"""The control-oriented A/C model of the paper (eqs. 1-5), kelvin inside.

States x = [T_cab, T_evap] (K), inputs u = [W_bl (kg/s), T_evap_set (K)], measured
disturbances v = [T_int, T_shell] (K), output T_ain (K). The same functions serve the
regressors of the fit, the simulator and the NMPC: they only use ``+ - *`` so they accept
floats, numpy arrays (broadcasting over any batch shape) and CasADi symbols alike.
"""

from __future__ import annotations

import numpy as np

from acid.params import ModelParams


def inlet_air(T_evap, W_bl, p: ModelParams):
    """Eq. 3: cabin inlet air temperature T_ain (K) from the evaporator wall and blower flow."""
    g, t = p.gamma, p.tau
    return g[5] * T_evap + g[6] * W_bl + t[2]


def cabin_step(T_cab, T_int, T_shell, T_ain, W_bl, p: ModelParams):
    """Eq. 1: cabin air temperature one sample later (K)."""
    g, t = p.gamma, p.tau
    return (T_cab + g[0] * (T_int - T_cab) + g[1] * (T_shell - T_cab)
            + g[2] * (T_ain - T_cab) * W_bl + t[0])


def evap_step(T_evap, T_evap_set, p: ModelParams):
    """Eq. 2: evaporator wall temperature one sample later (K)."""
    g, t = p.gamma, p.tau
    return g[3] * T_evap + g[4] * (T_evap - T_evap_set) + t[1]


def step(T_cab, T_evap, W_bl, T_evap_set, T_int, T_shell, p: ModelParams):
    """Eqs. 1-3 together: (T_cab(k+1), T_evap(k+1), T_ain(k)), all K."""
    T_ain = inlet_air(T_evap, W_bl, p)
    return (cabin_step(T_cab, T_int, T_shell, T_ain, W_bl, p),
            evap_step(T_evap, T_evap_set, p), T_ain)


def air_heat_flow(W_bl, T_ain, T_amb, c_p):
    """Numerator of eq. 4: c_p * W_bl * (T_amb - T_ain), W (c_p in J/(kg K))."""
    return c_p * W_bl * (T_amb - T_ain)


def compressor_power(W_bl, T_ain, T_amb, p: ModelParams, eta_cop=None):
    """Eq. 4: P_c = c_p / eta_cop * W_bl * (T_amb - T_ain), W.

    ``eta_cop`` overrides ``p.eta_cop`` (a scalar, an array per stage broadcasting against
    ``W_bl``, or a CasADi symbol), e.g. a speed-dependent efficiency previewed per stage.
    """
    eta = p.eta_cop if eta_cop is None else eta_cop
    return air_heat_flow(W_bl, T_ain, T_amb, p.c_p) / eta


def blower_power(W_bl, p: ModelParams):
    """Eq. 5: P_bl = beta1 W_bl^2 + beta2 W_bl + beta3, W."""
    b = p.beta
    return b[0] * W_bl * W_bl + b[1] * W_bl + b[2]


def evap_steady_state(T_evap_set, p: ModelParams):
    """Fixed point of eq. 2 for a constant set-point (K); requires |gamma4 + gamma5| < 1."""
    g, t = p.gamma, p.tau
    return (t[1] - g[4] * T_evap_set) / (1.0 - g[3] - g[4])


def cabin_steady_state(T_ain, W_bl, T_int, T_shell, p: ModelParams):
    """Fixed point of eq. 1 for constant inputs (K)."""
    g, t = p.gamma, p.tau
    num = g[0] * T_int + g[1] * T_shell + g[2] * W_bl * T_ain + t[0]
    return num / (g[0] + g[1] + g[2] * W_bl)


def simulate(x0, W_bl, T_evap_set, T_int, T_shell, p: ModelParams):
    """Multi-step open-loop simulation of eqs. 1-3, vectorised over any batch of starts.

    Parameters
    ----------
    x0 : array (..., 2) of initial [T_cab, T_evap], K.
    W_bl, T_evap_set, T_int, T_shell : arrays (..., H) of inputs over the horizon (kg/s, K).
        Leading dimensions broadcast against ``x0[..., 0]``.

    Returns
    -------
    T_cab, T_evap : arrays (..., H + 1), K, starting with the initial state.
    T_ain : array (..., H), K, the output at steps 0 .. H-1.
    """
    x0 = np.asarray(x0, dtype=float)
    W_bl, T_evap_set, T_int, T_shell = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (W_bl, T_evap_set, T_int, T_shell)))
    H = W_bl.shape[-1]
    batch = np.broadcast_shapes(x0.shape[:-1], W_bl.shape[:-1])
    T_cab = np.empty(batch + (H + 1,))
    T_evap = np.empty(batch + (H + 1,))
    T_ain = np.empty(batch + (H,))
    T_cab[..., 0] = x0[..., 0]
    T_evap[..., 0] = x0[..., 1]
    for k in range(H):  # loop over time only; every start advances at once
        T_cab[..., k + 1], T_evap[..., k + 1], T_ain[..., k] = step(
            T_cab[..., k], T_evap[..., k], W_bl[..., k], T_evap_set[..., k],
            T_int[..., k], T_shell[..., k], p)
    return T_cab, T_evap, T_ain


def one_step(T_cab, T_evap, W_bl, T_evap_set, T_int, T_shell, p: ModelParams):
    """One-step-ahead predictions along measured data (arrays of equal length N).

    Returns (T_cab_next, T_evap_next, T_ain), each length N: the predictions of samples
    k+1 (states) and k (output) from the measurements at k.
    """
    return step(np.asarray(T_cab), np.asarray(T_evap), np.asarray(W_bl),
                np.asarray(T_evap_set), np.asarray(T_int), np.asarray(T_shell), p)
