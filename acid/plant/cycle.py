"""Quasi-static vapour-compression cycle: one algebraic solve per internal step (PLANT.md).

Refrigerant-side dynamics (about 1 s) are invisible at the paper's 5 s sampling, so the cycle
is solved algebraically for the saturation temperatures T_e, T_c given the compressor speed N
and the evaporator and condenser wall temperatures T_ew, T_cw (the pattern of the Modelica
Buildings / AixLib heat-pump models). With fixed superheat SH and subcooling SC:

    PR  = p_sat(T_c) / p_sat(T_e)                   pressure ratio
    m_r = eta_v(PR) rho1(T_e) V_disp N / 60          eta_v = eta_v0 - k_v (PR - 1)
    h2  = h1 + (h2s - h1) / eta_is(PR)               eta_is = eta_is_max - k_is (PR - PR_opt)^2
    F1  = UA_er (T_ew - T_e) - m_r (h1 - h3) = 0     evaporator: wall -> refrigerant
    F2  = UA_cr (T_c - T_cw) - m_r (h2 - h3) = 0     condenser: refrigerant -> wall
    Q_e = m_r (h1 - h3),  Q_c = m_r (h2 - h3),  P_comp = m_r (h2 - h1) / eta_motor

(states: 1 suction, 2 discharge, 3 liquid line, 4 = 3 after the isenthalpic valve). The 2x2
system is solved by Newton's method with a finite-difference Jacobian, warm-started from the
previous solution (2-3 iterations). N = 0 means no flow: T_e = T_ew, T_c = T_cw.

``cycle()`` is the one public interface, so that a moving-boundary cycle can be swapped in and
compared in steady state; ``cycle_at()`` evaluates the cycle at given (T_e, T_c), for the
independent cross-check with CoolProp/TESPy.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

from acid.errors import SolverWarning
from acid.plant import refrigerant as rf
from acid.plant.config import PlantConfig

_MAX_ITER = 40
_TOL = 1e-5  # K, Newton step on T_e and T_c
_FD = 1e-3  # K, finite-difference step of the Jacobian


@dataclass(frozen=True)
class CycleResult:
    """One quasi-static cycle solution (SI units, temperatures in K).

    Attributes
    ----------
    T_e, T_c : evaporating and condensing saturation temperatures, K.
    m_r : refrigerant mass flow, kg/s.
    Q_e, Q_c : evaporator and condenser heat flows (refrigerant side), W.
    P_comp : compressor electrical power, W.
    W_comp : compressor shaft (fluid) power m_r (h2 - h1), W.
    COP : Q_e / P_comp (0 without flow).
    p_e, p_c : evaporating and condensing pressures, Pa.
    h1, h2, h3 : suction, discharge and liquid-line enthalpies, J/kg.
    eta_v, eta_is : volumetric and isentropic efficiencies at this pressure ratio.
    iterations : Newton iterations used.
    """

    T_e: float
    T_c: float
    m_r: float
    Q_e: float
    Q_c: float
    P_comp: float
    W_comp: float
    COP: float
    p_e: float
    p_c: float
    h1: float
    h2: float
    h3: float
    eta_v: float
    eta_is: float
    iterations: int = 0


def make_solver(config: PlantConfig) -> tuple[Callable, Callable]:
    """Build the fast scalar cycle functions for ``config`` (closures over plain floats).

    Returns
    -------
    solve(N, T_ew, T_cw, T_e0, T_c0) -> (T_e, T_c, m_r, Q_e, Q_c, P_comp, iterations)
        Newton solve from the guess (T_e0, T_c0); N in rpm, temperatures in K.
    state(T_e, T_c, N) -> (m_r, p_e, p_c, h1, h2, h3, eta_v, eta_is)
        the cycle's state points at given saturation temperatures.
    """
    tab = rf.table(config.refrigerant, config.superheat, config.subcool)
    P, R, H1, H3, H2S = tab.lists
    n1 = len(P)
    ne, nc = len(tab.Te2), len(tab.Tc2)
    inv1, inv2 = 1.0 / rf.DT1, 1.0 / rf.DT2
    T1_LO, TE_LO, TC_LO = rf.T1_LO, rf.TE_LO, rf.TC_LO
    i1max, iemax, icmax = n1 - 2, ne - 2, nc - 2
    Vd60 = config.V_disp / 60.0
    eta_v0, k_v = config.eta_v0, config.k_v
    eta_is_max, k_is, PR_opt = config.eta_is_max, config.k_is, config.PR_opt
    UA_er, UA_cr = config.UA_er, config.UA_cr
    inv_motor = 1.0 / config.eta_motor

    def state(Te, Tc, N):
        x = (Te - T1_LO) * inv1
        i = int(x)
        i = 0 if i < 0 else (i1max if i > i1max else i)
        f = x - i
        pe = P[i] + f * (P[i + 1] - P[i])
        rho = R[i] + f * (R[i + 1] - R[i])
        h1 = H1[i] + f * (H1[i + 1] - H1[i])
        x = (Tc - T1_LO) * inv1
        j = int(x)
        j = 0 if j < 0 else (i1max if j > i1max else j)
        f = x - j
        pc = P[j] + f * (P[j + 1] - P[j])
        h3 = H3[j] + f * (H3[j + 1] - H3[j])
        x = (Te - TE_LO) * inv2
        i = int(x)
        i = 0 if i < 0 else (iemax if i > iemax else i)
        fe = x - i
        x = (Tc - TC_LO) * inv2
        j = int(x)
        j = 0 if j < 0 else (icmax if j > icmax else j)
        fc = x - j
        k = i * nc + j
        h2s = ((1.0 - fe) * (H2S[k] + fc * (H2S[k + 1] - H2S[k]))
               + fe * (H2S[k + nc] + fc * (H2S[k + nc + 1] - H2S[k + nc])))
        PR = pc / pe
        if PR < 1.0:
            PR = 1.0
        ev = eta_v0 - k_v * (PR - 1.0)
        if ev < 0.05:
            ev = 0.05
        d = PR - PR_opt
        ei = eta_is_max - k_is * d * d
        if ei < 0.3:
            ei = 0.3
        dh = h2s - h1
        if dh < 0.0:
            dh = 0.0
        m = ev * rho * Vd60 * N
        return m, pe, pc, h1, h1 + dh / ei, h3, ev, ei

    def residual(Te, Tc, N, Tew, Tcw):
        m, _, _, h1, h2, h3, _, _ = state(Te, Tc, N)
        return UA_er * (Tew - Te) - m * (h1 - h3), UA_cr * (Tc - Tcw) - m * (h2 - h3)

    def solve(N, Tew, Tcw, Te, Tc):
        if N <= 0.0:
            return Tew, Tcw, 0.0, 0.0, 0.0, 0.0, 0
        if Te > Tew:
            Te = Tew - 0.5
        if Tc < Tcw:
            Tc = Tcw + 0.5
        it = 0
        for it in range(1, _MAX_ITER + 1):  # noqa: B007  (iteration count is returned)
            F1, F2 = residual(Te, Tc, N, Tew, Tcw)
            a1, a2 = residual(Te + _FD, Tc, N, Tew, Tcw)
            b1, b2 = residual(Te, Tc + _FD, N, Tew, Tcw)
            J11, J21 = (a1 - F1) / _FD, (a2 - F2) / _FD
            J12, J22 = (b1 - F1) / _FD, (b2 - F2) / _FD
            det = J11 * J22 - J12 * J21
            if det == 0.0:
                break
            dTe = (J22 * F1 - J12 * F2) / det
            dTc = (J11 * F2 - J21 * F1) / det
            # damp large steps (cold starts) to keep inside the tables
            big = abs(dTe) if abs(dTe) > abs(dTc) else abs(dTc)
            if big > 8.0:
                dTe *= 8.0 / big
                dTc *= 8.0 / big
            Te -= dTe
            Tc -= dTc
            if Te > Tew:
                Te = Tew
            if Tc < Tcw:
                Tc = Tcw
            if big < _TOL:
                break
        else:
            _warn_not_converged(N, Tew, Tcw)
        m, _, _, h1, h2, h3, _, _ = state(Te, Tc, N)
        return Te, Tc, m, m * (h1 - h3), m * (h2 - h3), m * (h2 - h1) * inv_motor, it

    return solve, state


def _warn_not_converged(N, Tew, Tcw) -> None:
    import warnings

    warnings.warn(f"cycle Newton solve did not converge at N = {N:.0f} rpm, "
                  f"T_ew = {Tew:.2f} K, T_cw = {Tcw:.2f} K; using the last iterate",
                  SolverWarning, stacklevel=3)


@functools.lru_cache(maxsize=16)
def _solver(config: PlantConfig) -> tuple[Callable, Callable]:
    """``make_solver(config)``, cached per (hashable, frozen) configuration."""
    return make_solver(config)


def _result(config, Te, Tc, N, it) -> CycleResult:
    _, state = _solver(config)
    m, pe, pc, h1, h2, h3, ev, ei = state(Te, Tc, N)
    Q_e, Q_c, W = m * (h1 - h3), m * (h2 - h3), m * (h2 - h1)
    P = W / config.eta_motor
    cop = Q_e / P if P > 0.0 else 0.0
    return CycleResult(Te, Tc, m, Q_e, Q_c, P, W, cop, pe, pc, h1, h2, h3, ev, ei, it)


def cycle(N: float, T_evap_wall: float, T_cond_wall: float, config: PlantConfig | None = None,
          guess: tuple[float, float] | None = None) -> CycleResult:
    """Solve the quasi-static cycle for the saturation temperatures and flows.

    Parameters
    ----------
    N : compressor speed, rpm (0 = off, no flow).
    T_evap_wall : evaporator wall temperature T_ew, K.
    T_cond_wall : condenser wall temperature T_cw, K.
    config : plant configuration (refrigerant, compressor, UA values); default calibration.
    guess : (T_e, T_c) starting point in K (e.g. the previous solution); a cold start
        otherwise.

    Returns
    -------
    CycleResult with T_e <= T_ew and T_c >= T_cw.
    """
    config = config or PlantConfig()
    solve, _ = _solver(config)
    if guess is None:
        guess = (T_evap_wall - 5.0, T_cond_wall + 5.0)
    Te, Tc, _, _, _, _, it = solve(float(N), float(T_evap_wall), float(T_cond_wall),
                                   float(guess[0]), float(guess[1]))
    if N <= 0.0:
        return CycleResult(Te, Tc, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, math.nan, math.nan,
                           math.nan, math.nan, math.nan, math.nan, math.nan, 0)
    return _result(config, Te, Tc, float(N), it)


def cycle_at(T_e: float, T_c: float, config: PlantConfig | None = None,
             N: float | None = None) -> CycleResult:
    """The cycle at given saturation temperatures (no heat-exchanger balance).

    Used for the steady-state cross-check: COP depends only on (T_e, T_c), SH, SC, the
    efficiencies and the fluid, so it can be compared with an independent calculation.
    ``N`` (rpm, default ``config.N_max``) only scales the flows.
    """
    config = config or PlantConfig()
    return _result(config, float(T_e), float(T_c), float(config.N_max if N is None else N), 0)
