"""The paper's eqs. 1-5 transcribed from the paper (Wang et al., ACC 2018), independently of
acid's declaration ``acid/models/paper.py``: the oracle of ``tests/test_control_nmpc.py``
and the peer
model of ``benchmarks/bench_mpc.py``. Numbers, arrays, complex steps and CasADi symbols
alike; ``p`` a ``ModelParams`` (kelvin convention)."""

from __future__ import annotations


def inlet_air(T_evap, W_bl, p):
    """Eq. 3, K."""
    return p.gamma[5] * T_evap + p.gamma[6] * W_bl + p.tau[2]


def step(T_cab, T_evap, W_bl, T_set, T_int, T_shell, p):
    """(T_cab+, T_evap+, T_ain): eqs. 1-3, K."""
    g, t = p.gamma, p.tau
    T_ain = inlet_air(T_evap, W_bl, p)
    return (T_cab + g[0] * (T_int - T_cab) + g[1] * (T_shell - T_cab)              # eq. 1
            + g[2] * (T_ain - T_cab) * W_bl + t[0],
            g[3] * T_evap + g[4] * (T_evap - T_set) + t[1], T_ain)                  # eq. 2


def power(W_bl, T_ain, T_amb, p):
    """P_comp + P_bl, W: eqs. 4-5."""
    b = p.beta
    return p.c_p / p.eta_cop * W_bl * (T_amb - T_ain) + b[0] * W_bl * W_bl + b[1] * W_bl + b[2]
