"""Quasi-static vapour-compression cycle: one algebraic solve per internal step.

Refrigerant-side dynamics (about 1 s) are invisible at the paper's 5 s sampling, so the cycle
is solved algebraically for the saturation temperatures T_e (evaporator), T_c (condenser)
given the compressor speed N and the evaporator and condenser wall temperatures T_ew, T_cw
(the pattern of the Modelica Buildings / AixLib heat-pump models). Second generation:

    dT_s = dT_suc0 (m_r / m_r0)^2                   suction line: saturation-temperature drop
    T_s  = T_e - dT_s,  p_s = p_sat(T_s)            compressor suction (low-side service port)
    PR   = p_sat(T_c) / p_s                         compressor pressure ratio
    eta_v  = eta_v0 - k_v (PR - 1) - c_L / N        re-expansion + leakage through a fixed gap
    eta_is = eta_is_max - k_is (PR - PR_opt)^2 - c_is_lo / N - c_is_hi (N / N_max)^2
    m_r = eta_v rho_s V_disp N / 60                 rho_s at (p_s, T_e + SH)
    h2  = h1 + (h2s(T_s, T_c) - h1(T_s)) / eta_is   isentropic lift from the suction pressure
    W   = m_r (h2 - h1)                             shaft (fluid) power
    P_el = W + P_loss0 + P_loss_N N / N_max + P_loss_cu (W / P_rated)^2   inverter + motor
    F1  = UA_er (T_ew - T_e) - m_r (h1 - h3) = 0    UA_er = UA_er0 (m_r / m_r0)^n_r
    F2  = UA_cr (T_c - T_cw) - m_r (h2 - h3) = 0    UA_cr = UA_cr0 (m_r / m_r0)^n_r

(states: 1 evaporator outlet at (p_sat(T_e), T_e + SH), 2 discharge, 3 liquid line at
(p_sat(T_c), T_c - SC), 4 = 3 after the isenthalpic valve). The suction line is isenthalpic,
so Q_e = m_r (h1 - h3) and Q_c = Q_e + W exactly. The 2x2 system is solved by Newton's method
with a finite-difference Jacobian, warm-started from the previous solution (2-4 iterations),
the suction drop updated from the latest flow at every iteration. N = 0 means no flow.

``cycle()`` is the one public interface, so that a moving-boundary cycle can be swapped in and
compared in steady state; ``cycle_at()`` evaluates the cycle at given (T_e, T_c), for the
independent cross-check with CoolProp/TESPy. Sources of every parameter: ``PlantConfig``
field metadata and ``datasets/plant/SOURCES.md``.
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
_TOL_SUC = 1e-4  # K, change of the suction-line drop between iterations
_FD = 1e-3  # K, finite-difference step of the Jacobian


@dataclass(frozen=True)
class CycleResult:
    """One quasi-static cycle solution (SI units, temperatures in K).

    Attributes
    ----------
    T_e, T_c : evaporating and condensing saturation temperatures, K.
    m_r : refrigerant mass flow, kg/s.
    Q_e, Q_c : evaporator and condenser heat flows (refrigerant side), W.
    P_comp : compressor electrical power (inverter + motor losses included), W.
    W_comp : compressor shaft (fluid) power m_r (h2 - h1), W.
    COP : Q_e / P_comp (0 without flow).
    p_e, p_c : evaporating and condensing pressures, Pa.
    h1, h2, h3 : evaporator-outlet, discharge and liquid-line enthalpies, J/kg.
    eta_v, eta_is : volumetric and isentropic efficiencies at this speed and pressure ratio.
    iterations : Newton iterations used.
    T_s, p_s : compressor suction saturation temperature (K) and pressure (Pa), after the
        suction-line drop.
    eta_motor : W_comp / P_comp, inverter + motor efficiency at this load and speed.
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
    T_s: float = math.nan
    p_s: float = math.nan
    eta_motor: float = math.nan


def make_solver(config: PlantConfig) -> tuple[Callable, Callable]:
    """Build the fast scalar cycle functions for ``config`` (closures over plain floats).

    Returns
    -------
    solve(N, T_ew, T_cw, T_e0, T_c0)
        -> (T_e, T_c, m_r, Q_e, Q_c, P_el, W, p_s, p_c, iterations)
        Newton solve from the guess (T_e0, T_c0); N in rpm, temperatures in K, pressures Pa.
    state(T_e, T_c, N, dT_s) -> (m_r, p_e, p_c, h1, h2, h3, eta_v, eta_is, p_s)
        the cycle's state points at given saturation temperatures and suction drop.
    """
    tab = rf.table(config.refrigerant, config.superheat, config.subcool)
    P, R, H1, H3, H2S = tab.lists
    n1 = len(P)
    ne, nc = len(tab.Te2), len(tab.Tc2)
    inv1, inv2 = 1.0 / rf.DT1, 1.0 / rf.DT2
    T1_LO, TE_LO, TC_LO = rf.T1_LO, rf.TE_LO, rf.TC_LO
    i1max, iemax, icmax = n1 - 2, ne - 2, nc - 2
    SH = config.superheat
    Vd60 = config.V_disp / 60.0
    eta_v0, k_v, c_L = config.eta_v0, config.k_v, config.c_L
    eta_is_max, k_is, PR_opt = config.eta_is_max, config.k_is, config.PR_opt
    c_is_lo, c_is_hi, inv_Nmax = config.c_is_lo, config.c_is_hi, 1.0 / config.N_max
    UA_er0, UA_cr0, n_r = config.UA_er0, config.UA_cr0, config.n_r
    inv_m0, dT_suc0 = 1.0 / config.m_r0, config.dT_suc0
    L0, LN, Lcu, inv_Pr = config.P_loss0, config.P_loss_N, config.P_loss_cu, 1.0 / config.P_rated
    last_dTs = [0.0]  # warm start of the suction drop (the previous solution's)

    def state(Te, Tc, N, dTs):
        x = (Te - T1_LO) * inv1
        i = int(x)
        i = 0 if i < 0 else (i1max if i > i1max else i)
        f = x - i
        pe = P[i] + f * (P[i + 1] - P[i])
        h1 = H1[i] + f * (H1[i + 1] - H1[i])
        Ts = Te - dTs
        x = (Ts - T1_LO) * inv1
        i = int(x)
        i = 0 if i < 0 else (i1max if i > i1max else i)
        f = x - i
        ps = P[i] + f * (P[i + 1] - P[i])
        rho = (R[i] + f * (R[i + 1] - R[i])) * (Ts + SH) / (Te + SH)
        h1s = H1[i] + f * (H1[i + 1] - H1[i])
        x = (Tc - T1_LO) * inv1
        j = int(x)
        j = 0 if j < 0 else (i1max if j > i1max else j)
        f = x - j
        pc = P[j] + f * (P[j + 1] - P[j])
        h3 = H3[j] + f * (H3[j + 1] - H3[j])
        x = (Ts - TE_LO) * inv2
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
        PR = pc / ps
        if PR < 1.0:
            PR = 1.0
        ev = eta_v0 - k_v * (PR - 1.0) - c_L / N
        if ev < 0.05:
            ev = 0.05
        d = PR - PR_opt
        r = N * inv_Nmax
        ei = eta_is_max - k_is * d * d - c_is_lo / N - c_is_hi * r * r
        if ei < 0.2:
            ei = 0.2
        # isentropic lift from the suction state: tabulated at (p_s, T_s + SH), scaled to the
        # actual suction temperature T_e + SH (ideal-gas: isentropic work ~ inlet temperature)
        dh = (h2s - h1s) * (Te + SH) / (Ts + SH)
        if dh < 0.0:
            dh = 0.0
        m = ev * rho * Vd60 * N
        return m, pe, pc, h1, h1 + dh / ei, h3, ev, ei, ps

    def residual(Te, Tc, N, Tew, Tcw, dTs):
        m, _, _, h1, h2, h3, _, _, _ = state(Te, Tc, N, dTs)
        g = (m * inv_m0) ** n_r
        return UA_er0 * g * (Tew - Te) - m * (h1 - h3), UA_cr0 * g * (Tc - Tcw) - m * (h2 - h3)

    def solve(N, Tew, Tcw, Te, Tc):
        if N <= 0.0:
            return Tew, Tcw, 0.0, 0.0, 0.0, 0.0, 0.0, math.nan, math.nan, 0
        if Te > Tew:
            Te = Tew - 0.5
        if Tc < Tcw:
            Tc = Tcw + 0.5
        dTs = last_dTs[0]
        it = 0
        for it in range(1, _MAX_ITER + 1):  # noqa: B007  (iteration count is returned)
            F1, F2 = residual(Te, Tc, N, Tew, Tcw, dTs)
            a1, a2 = residual(Te + _FD, Tc, N, Tew, Tcw, dTs)
            b1, b2 = residual(Te, Tc + _FD, N, Tew, Tcw, dTs)
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
            q = state(Te, Tc, N, dTs)[0] * inv_m0
            d_new = dT_suc0 * q * q
            change = abs(d_new - dTs)
            dTs = d_new
            if big < _TOL and change < _TOL_SUC:
                break
        else:
            _warn_not_converged(N, Tew, Tcw)
        last_dTs[0] = dTs
        m, _, pc, h1, h2, h3, _, _, ps = state(Te, Tc, N, dTs)
        W = m * (h2 - h1)
        x = W * inv_Pr
        P_el = W + L0 + LN * N * inv_Nmax + Lcu * x * x
        return Te, Tc, m, m * (h1 - h3), m * (h2 - h3), P_el, W, ps, pc, it

    return solve, state


def _warn_not_converged(N, Tew, Tcw) -> None:
    import warnings

    warnings.warn(f"cycle Newton solve did not converge at N = {N:.0f} rpm, "
                  f"T_ew = {Tew - 273.15:.2f} degC, T_cw = {Tcw - 273.15:.2f} degC; using the "
                  "last iterate",
                  SolverWarning, stacklevel=3)


@functools.lru_cache(maxsize=16)
def _solver(config: PlantConfig) -> tuple[Callable, Callable]:
    """``make_solver(config)``, cached per (hashable, frozen) configuration."""
    return make_solver(config)


def _result(config, Te, Tc, N, it, dTs=None) -> CycleResult:
    _, state = _solver(config)
    if dTs is None:  # consistent suction drop at this (T_e, T_c, N): fixed point on m_r
        dTs = 0.0
        for _ in range(50):
            m = state(Te, Tc, N, dTs)[0]
            new = config.dT_suc0 * (m / config.m_r0) ** 2
            if abs(new - dTs) < 1e-10:
                break
            dTs = new
    m, pe, pc, h1, h2, h3, ev, ei, ps = state(Te, Tc, N, dTs)
    Q_e, Q_c, W = m * (h1 - h3), m * (h2 - h3), m * (h2 - h1)
    P = motor_power(config, W, N)
    cop = Q_e / P if P > 0.0 else 0.0
    return CycleResult(Te, Tc, m, Q_e, Q_c, P, W, cop, pe, pc, h1, h2, h3, ev, ei, it,
                       Te - dTs, ps, W / P if P > 0.0 else math.nan)


def motor_power(config: PlantConfig, W: float, N: float) -> float:
    """Electric power of inverter + motor for shaft power ``W`` (W) at speed ``N`` (rpm), W.

    P_el = W + P_loss0 + P_loss_N N / N_max + P_loss_cu (W / P_rated)^2: a no-load loss
    (switching, control), a speed-proportional loss (iron, friction) and a copper loss growing
    with the square of the load; efficiency W / P_el rises from about 0.8 at light load to
    0.93 at rated (an assumption).
    """
    if N <= 0.0:
        return 0.0
    x = W / config.P_rated
    return W + config.P_loss0 + config.P_loss_N * N / config.N_max + config.P_loss_cu * x * x


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
    out = solve(float(N), float(T_evap_wall), float(T_cond_wall), float(guess[0]),
                float(guess[1]))
    Te, Tc, it = out[0], out[1], out[-1]
    if N <= 0.0:
        return CycleResult(Te, Tc, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, math.nan, math.nan,
                           math.nan, math.nan, math.nan, math.nan, math.nan, 0)
    return _result(config, Te, Tc, float(N), it)


def cycle_at(T_e: float, T_c: float, config: PlantConfig | None = None,
             N: float | None = None) -> CycleResult:
    """The cycle at given saturation temperatures (no heat-exchanger balance).

    Used for the steady-state cross-check: at given (T_e, T_c, N) the cycle's state points
    follow from SH, SC, the suction drop, the efficiencies and the fluid, so they can be
    compared with an independent calculation. ``N`` in rpm, default ``config.N_max``; the
    suction drop is the consistent one at this flow.
    """
    config = config or PlantConfig()
    return _result(config, float(T_e), float(T_c), float(config.N_max if N is None else N), 0)
