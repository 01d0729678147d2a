"""The economic model family: cabin, interior, shell, evaporator wall and cabin humidity,
with an identified compressor power map. Pure functions for numpy arrays and CasADi symbols.

States ``x = (T_cab, T_int, T_shell, T_evap, w_cab)`` (K, kg/kg), inputs
``u = (W_bl, T_evap_set)`` (kg/s, K), exogenous ``d = (v_veh, T_amb)`` (m/s, K), optional
additive disturbances ``dist`` on the five state derivatives (K/s, kg/kg/s; zero by default:
the hook for an offset-free estimator). Continuous time, integrated with classical RK4
(``n_sub`` sub-steps per interval), so the same functions serve a 5 s sample and the longer
intervals of a non-uniform NMPC grid. Parameters ``p``: any object with the attributes of
:class:`acid.econ.params.EconParams` (numbers, or CasADi symbols when fitting).

Air side (recirculation proportional to T_amb - T_cab and saturated, as the paper describes
CoolSim's; epsilon-NTU against the evaporator wall with NTU = ntu_ref (W_bl / W_REF)^-ntu_exp,
the same effectiveness for heat and moisture by the Lewis analogy)::

    r     = r_max sat(k_rec (T_amb - T_cab) / r_max)    (sat: smooth clip to [0, 1])
    T_mix = r T_cab + (1 - r) T_amb,          w_mix = r w_cab + (1 - r) w_amb(T_amb, RH_amb)
    eps   = 1 - exp(-NTU)
    Q_sens = eps W_bl c_p (T_mix - T_evap)                            coil sensible load, W
    dw    = eps smax(w_mix - w_sat(T_evap))                           condensed, kg/kg
    Q_lat = W_bl h_fg dw                                              coil latent load, W
    T_ain = T_mix - eps (T_mix - T_evap) + kappa_bl P_bl(W_bl) / (W_bl c_p)
    w_ain = w_mix - dw

(``smax`` a smooth max(., 0) of width ``W_SMOOTH``, so that the NLPs stay differentiable.)
Thermal masses::

    C_cab dT_cab/dt = hA_int (T_int - T_cab) + hA_sh (T_shell - T_cab)
                      + W_bl c_p (T_ain - T_cab) + Q_cab
    C_int dT_int/dt = hA_int (T_cab - T_int) + Q_int
    C_sh dT_shell/dt = hA_sh (T_cab - T_shell) + (hA_ext0 + hA_ext_v v^0.8)(T_amb - T_shell) + Q_sh
    dT_evap/dt = (T_evap_set + dT_ew - T_evap) / tau_ew     (compressor loop, first order)
    M_cab dw_cab/dt = W_bl (w_ain - w_cab) + m_w

Powers (means over an interval of length ``dt``)::

    Q_e    = mean(Q_sens + Q_lat) - C_ew (T_evap(t + dt) - T_evap(t)) / dt      refrigerant heat
    P_comp = Q_e f(Q_e, mean T_evap, v, T_amb)                                  identified map
    P_bl   = beta1 W_bl^2 + beta2 W_bl + beta3                                  paper eq. 5
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import casadi as ca
import numpy as np

from acid import model as paper_model
from acid.econ.params import DT_SCALE, MAP_TERMS, Q_SCALE, T_REF, TA_REF, V_SCALE, W_REF, PowerMap
from acid.econ.params import NAMES as PARAMETER_NAMES
from acid.psychro import H_FG, P_ATM, humidity_ratio

STATES = ("T_cab", "T_int", "T_shell", "T_evap", "w_cab")
STATE_UNITS = ("K", "K", "K", "K", "kg/kg")
INPUTS = ("W_bl", "T_evap_set")
EXOGENOUS = ("v_veh", "T_amb")
NX, NU, ND = len(STATES), len(INPUTS), len(EXOGENOUS)
#: Scaling of the NLPs' variables on this model (economic NMPC, steady state, bound):
#: z = (x - X_OFFSET) / X_SCALE, w = (u - U_OFFSET) / U_SCALE (K, kg/kg, kg/s)
X_OFFSET = np.array([293.15, 293.15, 293.15, 278.15, 0.008])
X_SCALE = np.array([1.0, 1.0, 1.0, 1.0, 1e-3])
U_OFFSET = np.array([0.1, 278.15])
U_SCALE = np.array([0.01, 1.0])

#: Width of the smooth max of the condensation switch, kg/kg (0.05 g/kg: at most ~6 W of
#: spurious latent load at W_bl = 0.1 kg/s where the coil is exactly at its dew point).
W_SMOOTH = 5e-5
#: Width of the smooth clip of the recirculated share (in units of r / r_max).
R_SMOOTH = 0.02
#: RK4 sub-step used when an interval is split automatically, s.
MAX_SUBSTEP = 5.0


def _is_sym(x) -> bool:
    return isinstance(x, (ca.SX, ca.MX))


def _exp(x):
    return ca.exp(x) if _is_sym(x) else np.exp(x)


def _sqrt(x):
    return ca.sqrt(x) if _is_sym(x) else np.sqrt(x)


def _pow(x, a):
    return x ** a if _is_sym(x) else np.power(x, a)


def speed_factor(v_veh):
    """``v^0.8`` (turbulent forced convection), m/s; shifted by 1e-6 m/s so that its
    derivative stays finite at standstill (CasADi differentiates through exogenous inputs)."""
    return _pow(v_veh + 1e-6, 0.8)


def smooth_pos(x, width: float = W_SMOOTH):
    """A smooth max(x, 0): ``(x + sqrt(x^2 + width^2)) / 2`` (error at most ``width / 2``)."""
    return 0.5 * (x + _sqrt(x * x + width * width))


def recirculation(T_cab, T_amb, p):
    """Recirculated share r of the blower air: ``r_max`` times a smooth clip to [0, 1] of
    ``k_rec (T_amb - T_cab) / r_max`` (more fresh air when the cabin is not cooler than
    outside)."""
    z = p.k_rec * (T_amb - T_cab) / p.r_max
    return p.r_max * (smooth_pos(z, R_SMOOTH) - smooth_pos(z - 1.0, R_SMOOTH))


@dataclass(frozen=True)
class AirSide:
    """Air-side quantities at one instant (K, kg/kg, W; arrays or CasADi expressions)."""

    r: object
    T_mix: object
    w_mix: object
    eps: object
    T_ain: object
    w_ain: object
    Q_sens: object
    Q_lat: object

    @property
    def Q_coil(self):
        """Coil load (sensible + latent), W."""
        return self.Q_sens + self.Q_lat


def air_side(T_cab, T_evap, w_cab, W_bl, T_amb, p) -> AirSide:
    """Mixing, evaporator coil (epsilon-NTU, Lewis analogy) and supply air (module docstring)."""
    r = recirculation(T_cab, T_amb, p)
    T_mix = r * T_cab + (1.0 - r) * T_amb
    w_amb = humidity_ratio(T_amb, p.RH_amb, p.p_atm)
    w_mix = r * w_cab + (1.0 - r) * w_amb
    ntu = p.ntu_ref * _pow(W_bl / W_REF, -p.ntu_exp)
    eps = 1.0 - _exp(-ntu)
    Wcp = W_bl * p.c_p
    dw = eps * smooth_pos(w_mix - humidity_ratio(T_evap, 1.0, p.p_atm))
    heat = p.kappa_bl * paper_model.blower_power(W_bl, p) / Wcp
    return AirSide(r=r, T_mix=T_mix, w_mix=w_mix, eps=eps,
                   T_ain=T_mix - eps * (T_mix - T_evap) + heat, w_ain=w_mix - dw,
                   Q_sens=eps * Wcp * (T_mix - T_evap), Q_lat=W_bl * p.h_fg * dw)


def derivatives(x, u, d, p, dist=None):
    """Time derivatives of the five states and the air side at ``x`` (module docstring).

    Parameters
    ----------
    x : (T_cab, T_int, T_shell, T_evap, w_cab), K and kg/kg.
    u : (W_bl, T_evap_set), kg/s and K.
    d : (v_veh, T_amb), m/s and K.
    p : parameters (attributes of ``EconParams``).
    dist : optional additive terms on the five derivatives (K/s, kg/kg/s).

    Returns
    -------
    (dx, air) : a tuple of five derivatives and the :class:`AirSide`.
    """
    T_cab, T_int, T_sh, T_ev, w = x
    W_bl, T_set = u
    v, T_amb = d
    air = air_side(T_cab, T_ev, w, W_bl, T_amb, p)
    hA_ext = p.hA_ext0 + p.hA_ext_v * speed_factor(v)
    dx = [
        (p.hA_int * (T_int - T_cab) + p.hA_sh * (T_sh - T_cab)
         + W_bl * p.c_p * (air.T_ain - T_cab) + p.Q_cab) / p.C_cab,
        (p.hA_int * (T_cab - T_int) + p.Q_int) / p.C_int,
        (p.hA_sh * (T_cab - T_sh) + hA_ext * (T_amb - T_sh) + p.Q_sh) / p.C_sh,
        (T_set + p.dT_ew - T_ev) / p.tau_ew,
        (W_bl * (air.w_ain - w) + p.m_w) / p.M_cab,
    ]
    if dist is not None:
        dx = [a + b for a, b in zip(dx, dist, strict=True)]
    return tuple(dx), air


@dataclass(frozen=True)
class StepResult:
    """One interval of length ``dt`` (arrays or CasADi expressions).

    Attributes
    ----------
    x : the five states at the end of the interval.
    T_ain, Q_coil, T_evap : means over the interval of the supply air (K), the coil load (W)
        and the evaporator wall temperature (K) (RK4 quadrature of their integrals).
    dt : interval length, s.
    """

    x: tuple
    T_ain: object
    Q_coil: object
    T_evap: object
    dt: float


def n_substeps(dt: float) -> int:
    """RK4 sub-steps for an interval of ``dt`` s (at most ``MAX_SUBSTEP`` s each)."""
    return max(1, int(np.ceil(float(dt) / MAX_SUBSTEP - 1e-9)))


def step(x, u, d, p, dt: float = 5.0, dist=None, n_sub: int | None = None) -> StepResult:
    """Integrate one interval with inputs and exogenous values held (classical RK4).

    The interval means of T_ain, the coil load and T_evap come from integrating them as
    extra states in the same RK4 scheme (Simpson-like accuracy).
    """
    n = n_substeps(dt) if n_sub is None else int(n_sub)
    h = float(dt) / n

    def f(z):
        dx, air = derivatives(z[:NX], u, d, p, dist)
        return list(dx) + [air.T_ain, air.Q_coil, z[3]]

    z = list(x) + [0.0, 0.0, 0.0]
    for _ in range(n):
        k1 = f(z)
        k2 = f([a + 0.5 * h * b for a, b in zip(z, k1, strict=True)])
        k3 = f([a + 0.5 * h * b for a, b in zip(z, k2, strict=True)])
        k4 = f([a + h * b for a, b in zip(z, k3, strict=True)])
        z = [a + h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
             for a, b1, b2, b3, b4 in zip(z, k1, k2, k3, k4, strict=True)]
    inv = 1.0 / float(dt)
    return StepResult(x=tuple(z[:NX]), T_ain=z[NX] * inv, Q_coil=z[NX + 1] * inv,
                      T_evap=z[NX + 2] * inv, dt=float(dt))


def refrigerant_heat(Q_coil, T_evap_start, T_evap_end, dt: float, p):
    """Q_e = Q_coil - C_ew (T_evap(end) - T_evap(start)) / dt: heat the refrigerant takes, W."""
    return Q_coil - p.C_ew * (T_evap_end - T_evap_start) / dt


def map_features(Q_e, T_evap, v_veh, T_amb) -> list:
    """The 15 monomials of the power map (``MAP_TERMS`` order) at the given inputs."""
    q = Q_e / Q_SCALE
    t = (T_evap - T_REF) / DT_SCALE
    s = v_veh / V_SCALE
    a = (T_amb - TA_REF) / DT_SCALE
    one = 1.0 + 0.0 * q
    return [one, q, t, s, a, q * q, q * t, q * s, q * a, t * t, t * s, t * a, s * s, s * a,
            a * a]


def inverse_cop(Q_e, T_evap, v_veh, T_amb, pm: PowerMap):
    """f = P_comp / Q_e of the power map (W/W)."""
    return sum(c * m for c, m in zip(pm.coef, map_features(Q_e, T_evap, v_veh, T_amb),
                                     strict=True))


def compressor_power(Q_e, T_evap, v_veh, T_amb, pm: PowerMap):
    """P_comp = Q_e f(Q_e, T_evap, v, T_amb): the identified compressor power map, W."""
    return Q_e * inverse_cop(Q_e, T_evap, v_veh, T_amb, pm)


def blower_power(W_bl, p):
    """Paper eq. 5 (the same function as the paper's model), W."""
    return paper_model.blower_power(W_bl, p)


@dataclass(frozen=True)
class Trajectory:
    """A simulation over H intervals (numpy, batch dimensions first).

    Attributes
    ----------
    x : (..., H + 1, 5) states at the interval boundaries.
    T_ain, Q_coil, Q_e, P_comp, P_bl : (..., H) interval means (K, W).
    """

    x: np.ndarray
    T_ain: np.ndarray
    Q_coil: np.ndarray
    Q_e: np.ndarray
    P_comp: np.ndarray
    P_bl: np.ndarray

    def state(self, name: str) -> np.ndarray:
        """(..., H + 1) of one state by name."""
        return self.x[..., STATES.index(name)]

    @property
    def power(self) -> np.ndarray:
        """P_comp + P_bl, W (negative refrigerant heat counts as zero compressor power)."""
        return self.P_comp + self.P_bl


def simulate(x0, W_bl, T_evap_set, v_veh, T_amb, p, dt: float | None = None,
             dist=None) -> Trajectory:
    """Open-loop simulation, vectorised over any batch of starts (numpy).

    Parameters
    ----------
    x0 : (..., 5) initial states.
    W_bl, T_evap_set, v_veh, T_amb : (..., H) inputs and exogenous values per interval.
    p : ``EconParams``.
    dt : interval length, s (default ``p.Ts``).
    dist : optional (5,) constant additive disturbances on the derivatives.
    """
    dt = float(p.Ts if dt is None else dt)
    x0 = np.asarray(x0, dtype=float)
    W, Ts_, v, Ta = np.broadcast_arrays(*(np.asarray(a, dtype=float)
                                          for a in (W_bl, T_evap_set, v_veh, T_amb)))
    H = W.shape[-1]
    batch = np.broadcast_shapes(x0.shape[:-1], W.shape[:-1])
    X = np.empty(batch + (H + 1, NX))
    X[..., 0, :] = x0
    out = {k: np.empty(batch + (H,)) for k in ("T_ain", "Q_coil", "T_evap")}
    for k in range(H):
        xk = tuple(X[..., k, i] for i in range(NX))
        r = step(xk, (W[..., k], Ts_[..., k]), (v[..., k], Ta[..., k]), p, dt, dist)
        X[..., k + 1, :] = np.stack(np.broadcast_arrays(*r.x), axis=-1)
        out["T_ain"][..., k], out["Q_coil"][..., k], out["T_evap"][..., k] = (
            r.T_ain, r.Q_coil, r.T_evap)
    Q_e = refrigerant_heat(out["Q_coil"], X[..., :-1, 3], X[..., 1:, 3], dt, p)
    P_comp = np.maximum(compressor_power(Q_e, out["T_evap"], v, Ta, p.power_map), 0.0)
    return Trajectory(x=X, T_ain=out["T_ain"], Q_coil=out["Q_coil"], Q_e=Q_e, P_comp=P_comp,
                      P_bl=blower_power(W, p) + 0.0 * P_comp)


def casadi_step(p, dt: float, n_sub: int | None = None) -> ca.Function:
    """The interval map as a CasADi Function (SX inside), for NLPs and batch evaluation.

    ``F(x[5], u[2], d[2], dist[5]) -> (x_next[5], T_ain, Q_e, P_comp, P_bl)``: means over the
    interval, ``P_comp`` the power map at the mean T_evap (not clipped: NLPs constrain
    ``Q_e >= 0`` instead).
    """
    x = ca.SX.sym("x", NX)
    u = ca.SX.sym("u", NU)
    d = ca.SX.sym("d", ND)
    w = ca.SX.sym("dist", NX)
    r = step(ca.vertsplit(x), ca.vertsplit(u), ca.vertsplit(d), p, dt,
             dist=ca.vertsplit(w), n_sub=n_sub)
    Q_e = refrigerant_heat(r.Q_coil, x[3], r.x[3], dt, p)
    P_c = compressor_power(Q_e, r.T_evap, d[0], d[1], p.power_map)
    return ca.Function("econ_step", [x, u, d, w],
                       [ca.vertcat(*r.x), r.T_ain, Q_e, P_c, blower_power(u[0], p)],
                       ["x", "u", "d", "dist"], ["x_next", "T_ain", "Q_e", "P_comp", "P_bl"])


def heat_content(x, v_veh, p):
    """Heat stored in the model's states that future cooling must remove, J (+ constant).

    ``H = C_cab T_cab + C_int T_int + w_sh C_sh T_shell + C_ew T_evap + M_cab h_fg w_cab``
    with ``w_sh = hA_sh / (hA_sh + hA_ext(v))`` the share of the shell's surplus that flows
    into the cabin rather than to ambient. All capacities are the model's identified ones.
    """
    T_cab, T_int, T_sh, T_ev, w = x
    hA_ext = p.hA_ext0 + p.hA_ext_v * speed_factor(v_veh)
    w_sh = p.hA_sh / (p.hA_sh + hA_ext)
    return (p.C_cab * T_cab + p.C_int * T_int + w_sh * p.C_sh * T_sh + p.C_ew * T_ev
            + p.M_cab * p.h_fg * w)



#: Layout of :func:`parameter_vector`: the dynamic parameters, C_ew, the 15 power-map
#: coefficients and eq. 5's beta (an NLP takes them as parameters, so that one built, and
#: compiled, solver serves every identified parameter set of the same structure).
N_THETA = len(PARAMETER_NAMES) + 1 + len(MAP_TERMS) + 3


def parameter_vector(p) -> np.ndarray:
    """All numbers of ``p`` (``EconParams``) as one vector (layout ``N_THETA``)."""
    return np.concatenate([[p.values[n] for n in PARAMETER_NAMES], [p.C_ew],
                           p.power_map.coef, p.beta]).astype(float)


def symbolic_parameters(theta) -> SimpleNamespace:
    """An object with ``EconParams``' attributes read from the vector ``theta`` (numbers or
    CasADi symbols; inverse of :func:`parameter_vector`), for the model functions."""
    t = ca.vertsplit(theta) if _is_sym(theta) else list(np.asarray(theta, dtype=float))
    n = len(PARAMETER_NAMES)
    return SimpleNamespace(**dict(zip(PARAMETER_NAMES, t[:n], strict=True)), C_ew=t[n],
                           power_map=SimpleNamespace(coef=t[n + 1: n + 1 + len(MAP_TERMS)]),
                           beta=tuple(t[n + 1 + len(MAP_TERMS):]), c_p=1008.0, h_fg=H_FG,
                           p_atm=P_ATM)
