"""acid's economic model, declared once: cabin air, interior, shell, evaporator wall and cabin
humidity, with an identified compressor power map (beyond the paper; Wang et al.'s model is
``acid/models/paper.py``).

States ``(T_cab, T_int, T_shell, T_evap, w_cab)`` (K, kg/kg), inputs ``(W_bl, T_evap_set)``
(kg/s, K), disturbances ``(v_veh, T_amb)`` (m/s, K). Continuous time, integrated by the
declaration's ``RK4`` over each interval with inputs and disturbances held; the interval
means of T_ain, the coil load and T_evap are integrated as extra states of the same RK4
(Simpson-like accuracy). :func:`interval` serves any interval length (the non-uniform grids
of the economic NMPC); the declared step is one 5 s interval.

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
    P_comp = Q_e f(q, t, s, a)      f (inverse COP): full quadratic in normalised features
           q = Q_e / 1 kW, t = (mean T_evap - 5 degC) / 5 K, s = v / 10 m/s,
           a = (T_amb - 30 degC) / 5 K
    P_bl   = beta1 W_bl^2 + beta2 W_bl + beta3                                  paper eq. 5

``P_comp`` is the map unclipped (NLPs constrain ``Q_e >= 0``; a plant clips it at zero).
Every parameter is identified from data (``acid fit --model econ``, ``FIT_STAGES``); the
declared values are a start of the size identified on acid's high-fidelity plant; the bounds
are physical signs, wide otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from acid.errors import DataError
from acid.models.declaration import RK4, Constant, Group, Model, Parameter, Signal, State
from acid.models.paper import PARAMETER_TABLE as PAPER_TABLE
from acid.paper import MODEL as _PAPER_MODEL
from acid.psychro import H_FG, P_ATM, humidity_ratio

PAPER_BETA = _PAPER_MODEL.beta  # eq. 5's values: the econ model's start

TS = 5.0
STATES = ("T_cab", "T_int", "T_shell", "T_evap", "w_cab")
STATE_UNITS = ("K", "K", "K", "K", "kg/kg")
#: Reference blower flow of ntu_ref (a normalisation), kg/s.
W_REF = 0.1
#: Width of the smooth max of the condensation switch, kg/kg (0.05 g/kg: at most ~6 W of
#: spurious latent load at W_bl = 0.1 kg/s where the coil is exactly at its dew point).
W_SMOOTH = 5e-5
#: Width of the smooth clip of the recirculated share (in units of r / r_max).
R_SMOOTH = 0.02
#: RK4 sub-step used when an interval is split automatically, s.
MAX_SUBSTEP = 5.0
#: Normalisation of the power-map features (units only: the map is fitted to data).
Q_SCALE, T_REF, TA_REF, DT_SCALE, V_SCALE = 1000.0, 278.15, 303.15, 5.0, 10.0
#: Monomials of the inverse-COP map in (q, t, s, a): the full quadratic.
MAP_TERMS = ("1", "q", "t", "s", "a", "q^2", "q t", "q s", "q a", "t^2", "t s", "t a", "s^2",
             "s a", "a^2")
#: Parameter names of the map coefficients, ``MAP_TERMS`` order ("q t" -> "f_qt").
MAP_NAMES = tuple("f_" + t.replace("^2", "2").replace(" ", "") for t in MAP_TERMS)
#: The map's inputs and their units (the domain it was identified on).
MAP_INPUTS = (("Q_e", "W"), ("T_evap", "K"), ("v_veh", "m/s"), ("T_amb", "K"))

@dataclass(frozen=True)
class PowerMap:
    """Compressor electric power as a smooth map of the refrigerant-side cooling.

    ``P_comp = Q_e * f(q, t, s, a)`` (W), ``f`` (the inverse COP) a full quadratic in the
    normalised features (``MAP_TERMS``): ``q = Q_e / 1 kW``, ``t = (T_evap - 5 degC) / 5 K``,
    ``s = v / 10 m/s``, ``a = (T_amb - 30 degC) / 5 K``.

    Attributes
    ----------
    coef : (15,) coefficients of ``f`` in ``MAP_TERMS`` order (dimensionless, W/W).
    stderr : (15,) their standard errors.
    domain : {input: (low, high)} for ``MAP_INPUTS``: the range of the identification data;
        the map is not trusted outside it (:meth:`outside`).
    quality : fit statistics (``rms_W``, ``rms_pct`` of the mean power, ``max_pct``, ``n``,
        ``r2``; the ``steady_*`` numbers over near-steady samples only).
    envelope : {channel: (low, high)} the model's envelope: the ranges of its identification
        data in Q_e (W), T_evap, T_cab, T_amb (K) and W_bl (kg/s) (``acid.ident.envelope``);
        empty for files written before it was stored.
    """

    coef: tuple[float, ...]
    stderr: tuple[float, ...] = ()
    domain: dict = field(default_factory=dict)
    quality: dict = field(default_factory=dict, compare=False)
    envelope: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        coef = tuple(float(c) for c in self.coef)
        if len(coef) != len(MAP_TERMS) or not all(math.isfinite(c) for c in coef):
            raise DataError(f"power map needs {len(MAP_TERMS)} finite coefficients")
        object.__setattr__(self, "coef", coef)
        object.__setattr__(self, "stderr", tuple(float(c) for c in self.stderr))
        dom = {k: (float(v[0]), float(v[1])) for k, v in (self.domain or {}).items()}
        object.__setattr__(self, "domain", dom)
        object.__setattr__(self, "envelope", {k: (float(v[0]), float(v[1]))
                                              for k, v in (self.envelope or {}).items()})

    def outside(self, **values) -> list[str]:
        """Inputs (``Q_e``, ``T_evap``, ``v_veh``, ``T_amb`` arrays) outside the data's range.

        Returns one phrase per offending input, e.g. ``"v_veh up to 36.1 m/s (data 0-30)"``;
        a margin of 2 % of the range (at least 0.05 units) is tolerated.
        """
        out = []
        units = dict(MAP_INPUTS)
        for name, vals in values.items():
            if name not in self.domain or vals is None:
                continue
            lo, hi = self.domain[name]
            tol = max(0.02 * (hi - lo), 0.05)
            v = np.asarray(vals, dtype=float)
            if v.size == 0:
                continue
            # what the user reads is in degC (the map works in K)
            shift, unit = (273.15, "degC") if units[name] == "K" else (0.0, units[name])
            data = f"(data {lo - shift:.4g}-{hi - shift:.4g})"
            if v.max() > hi + tol:
                out.append(f"{name} up to {v.max() - shift:.4g} {unit} {data}")
            if v.min() < lo - tol:
                out.append(f"{name} down to {v.min() - shift:.4g} {unit} {data}")
        return out


_inf = math.inf
#: (name, unit, start, min, max, meaning) of the thermal and humidity parameters.
THERMAL = (
    ("r_max", "1", 0.8, 0.0, 0.99, "largest recirculated share of the blower air"),
    ("k_rec", "1/K", 0.1, 1e-3, 10.0, "recirculated share per kelvin of T_amb - T_cab"),
    ("ntu_ref", "1", 2.75, 1e-3, 50.0, "evaporator air-side NTU at W_bl = W_REF"),
    ("ntu_exp", "1", 0.4, -1.0, 2.0, "NTU ~ (W_bl / W_REF)^-ntu_exp (Nusselt exponent 1 - n)"),
    ("kappa_bl", "1", 0.1, 0.0, 1.0, "share of the blower power that heats the supply air"),
    ("C_cab", "J/K", 4500.0, 100.0, 1e6, "heat capacity of the cabin air node"),
    ("hA_int", "W/K", 190.0, 0.0, 1e4, "cabin air <-> interior conductance"),
    ("hA_sh", "W/K", 67.0, 0.0, 1e4, "cabin air <-> shell conductance"),
    ("Q_cab", "W", 80.0, -1e4, 1e4, "heat released into the cabin air (occupants)"),
    ("C_int", "J/K", 65000.0, 1e3, 1e8, "heat capacity of the interior (seats, dash)"),
    ("Q_int", "W", 350.0, -1e4, 1e4, "heat absorbed by the interior (solar through glass)"),
    ("C_sh", "J/K", 65000.0, 1e3, 1e8, "heat capacity of the shell (roof, doors, glass)"),
    ("hA_ext0", "W/K", 60.0, 0.0, 1e4, "shell <-> ambient conductance at standstill"),
    ("hA_ext_v", "W/K/(m/s)^0.8", 9.0, 0.0, 1e4, "its growth with speed, + hA_ext_v v^0.8"),
    ("Q_sh", "W", 900.0, -1e4, 1e4, "heat absorbed by the shell (solar)"),
    ("tau_ew", "s", 11.0, 0.5, 1e3, "time constant of the evaporator wall"),
    ("dT_ew", "K", 0.1, -10.0, 10.0, "steady offset of the evaporator wall from its set-point"),
    ("M_cab", "kg", 3.7, 0.1, 1e3, "air mass of the cabin humidity balance"),
    ("m_w", "kg/s", 1.4e-5, -1e-3, 1e-3, "moisture released into the cabin (occupants)"),
    ("RH_amb", "1", 0.5, 0.0, 1.0, "relative humidity of the ambient air"),
)
THERMAL_NAMES = tuple(row[0] for row in THERMAL)
_MAP_START = (0.155, 0.051, -0.029, -0.006, 0.05, -0.004, -0.01, -0.0015, 0.0027, 0.0022,
              0.0005, -0.005, 0.0014, -0.0015, -0.0052)
#: Eq. 5's coefficients (name, unit, meaning), started at the paper's values.
BETA = PAPER_TABLE[-3:]


def _is_sym(x) -> bool:
    return isinstance(x, (ca.SX, ca.MX))


def _math(fn: str):
    """``casadi.fn`` on CasADi symbols, ``numpy.fn`` on numbers."""
    return lambda x: getattr(ca if _is_sym(x) else np, fn)(x)


_exp, _sqrt = _math("exp"), _math("sqrt")


def speed_factor(v_veh):
    """``v^0.8`` (turbulent forced convection), m/s; shifted by 1e-6 m/s so that its
    derivative stays finite at standstill (CasADi differentiates through disturbances)."""
    return (v_veh + 1e-6) ** 0.8


def smooth_pos(x, width: float = W_SMOOTH):
    """A smooth max(x, 0): ``(x + sqrt(x^2 + width^2)) / 2`` (error at most ``width / 2``)."""
    return 0.5 * (x + _sqrt(x * x + width * width))


def blower_power(s, W_bl):
    """Paper eq. 5: P_bl = beta1 W_bl^2 + beta2 W_bl + beta3, W."""
    return s.beta1 * W_bl * W_bl + s.beta2 * W_bl + s.beta3


@dataclass(frozen=True)
class AirSide:
    """Air-side quantities at one instant (K, kg/kg, W; numbers or CasADi expressions)."""

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


def air_side(s, T_cab, T_evap, w_cab, W_bl, T_amb) -> AirSide:
    """Mixing, evaporator coil (epsilon-NTU, Lewis analogy) and supply air (module docstring);
    ``s`` gives the parameters and constants by name."""
    z = s.k_rec * (T_amb - T_cab) / s.r_max
    r = s.r_max * (smooth_pos(z, R_SMOOTH) - smooth_pos(z - 1.0, R_SMOOTH))
    T_mix = r * T_cab + (1.0 - r) * T_amb
    w_mix = r * w_cab + (1.0 - r) * humidity_ratio(T_amb, s.RH_amb, s.p_atm)
    eps = 1.0 - _exp(-s.ntu_ref * (W_bl / W_REF) ** -s.ntu_exp)
    Wcp = W_bl * s.c_p
    dw = eps * smooth_pos(w_mix - humidity_ratio(T_evap, 1.0, s.p_atm))
    heat = s.kappa_bl * blower_power(s, W_bl) / Wcp
    return AirSide(r=r, T_mix=T_mix, w_mix=w_mix, eps=eps,
                   T_ain=T_mix - eps * (T_mix - T_evap) + heat, w_ain=w_mix - dw,
                   Q_sens=eps * Wcp * (T_mix - T_evap), Q_lat=W_bl * s.h_fg * dw)


def derivatives(s, x, u, d, dist=None):
    """Time derivatives of the five states (K/s, kg/kg/s) and the :class:`AirSide` at ``x``
    with inputs ``u = (W_bl, T_evap_set)`` and disturbances ``d = (v_veh, T_amb)``; ``dist``
    optional additive terms on the derivatives (an offset-free estimator's hook)."""
    T_cab, T_int, T_sh, T_ev, w = x
    W_bl, T_set = u
    v, T_amb = d
    air = air_side(s, T_cab, T_ev, w, W_bl, T_amb)
    hA_ext = s.hA_ext0 + s.hA_ext_v * speed_factor(v)
    dx = [
        (s.hA_int * (T_int - T_cab) + s.hA_sh * (T_sh - T_cab)
         + W_bl * s.c_p * (air.T_ain - T_cab) + s.Q_cab) / s.C_cab,
        (s.hA_int * (T_cab - T_int) + s.Q_int) / s.C_int,
        (s.hA_sh * (T_cab - T_sh) + hA_ext * (T_amb - T_sh) + s.Q_sh) / s.C_sh,
        (T_set + s.dT_ew - T_ev) / s.tau_ew,
        (W_bl * (air.w_ain - w) + s.m_w) / s.M_cab,
    ]
    if dist is not None:
        dx = [a + b for a, b in zip(dx, dist, strict=True)]
    return dx, air


def map_features(Q_e, T_evap, v_veh, T_amb) -> list:
    """The 15 monomials of the power map (``MAP_TERMS`` order) at the given inputs."""
    q = Q_e / Q_SCALE
    t = (T_evap - T_REF) / DT_SCALE
    s = v_veh / V_SCALE
    a = (T_amb - TA_REF) / DT_SCALE
    one = 1.0 + 0.0 * q
    return [one, q, t, s, a, q * q, q * t, q * s, q * a, t * t, t * s, t * a, s * s, s * a,
            a * a]


def refrigerant_heat(s, Q_coil, T_evap_start, T_evap_end, dt: float):
    """Q_e = Q_coil - C_ew (T_evap(end) - T_evap(start)) / dt: heat the refrigerant takes
    over an interval of ``dt`` s, W."""
    return Q_coil - s.C_ew * (T_evap_end - T_evap_start) / float(dt)


def compressor_power(s, Q_e, T_evap, v_veh, T_amb):
    """P_comp = Q_e f(q, t, s, a): the identified compressor power map, W (unclipped)."""
    f = sum(s[n] * m for n, m in zip(MAP_NAMES, map_features(Q_e, T_evap, v_veh, T_amb),
                                      strict=True))
    return Q_e * f


@dataclass(frozen=True)
class Interval:
    """One interval of length ``dt`` (CasADi expressions): the states at its end, the means
    over it of the supply air (K), the coil load (W) and the wall temperature (K), the
    refrigerant heat ``Q_e`` and the powers (W)."""

    x: tuple
    T_ain: object
    Q_coil: object
    T_evap: object
    Q_e: object
    P_comp: object
    P_bl: object
    dt: float


def n_substeps(dt: float) -> int:
    """RK4 sub-steps for an interval of ``dt`` s (at most ``MAX_SUBSTEP`` s each)."""
    return max(1, int(np.ceil(float(dt) / MAX_SUBSTEP - 1e-9)))


def interval(s, x, u, d, dt: float = TS, n_sub: int | None = None, dist=None) -> Interval:
    """Integrate one interval with ``u`` and ``d`` held (the declaration's RK4; ``x``, ``u``,
    ``d``, ``dist`` sequences of CasADi scalars, ``s`` the parameters by name)."""
    def f(z):
        dx, air = derivatives(s, ca.vertsplit(z)[:len(STATES)], u, d, dist)
        return ca.vertcat(*dx, air.T_ain, air.Q_coil, z[3])

    z0 = ca.vertcat(*x, 0.0, 0.0, 0.0)
    z = ca.vertsplit(RK4(n_substeps(dt) if n_sub is None else int(n_sub)).integrate(
        f, z0, float(dt)))
    nx, inv = len(STATES), 1.0 / float(dt)
    T_ain, Q_coil, T_ev = z[nx] * inv, z[nx + 1] * inv, z[nx + 2] * inv
    Q_e = refrigerant_heat(s, Q_coil, x[3], z[3], dt)
    return Interval(x=tuple(z[:nx]), T_ain=T_ain, Q_coil=Q_coil, T_evap=T_ev, Q_e=Q_e,
                    P_comp=compressor_power(s, Q_e, T_ev, d[0], d[1]),
                    P_bl=blower_power(s, u[0]), dt=float(dt))


def heat_content(s, x, v_veh):
    """Heat stored in the states that future cooling must remove, J (+ constant):
    ``C_cab T_cab + C_int T_int + w_sh C_sh T_shell + C_ew T_evap + M_cab h_fg w_cab`` with
    ``w_sh = hA_sh / (hA_sh + hA_ext(v))`` the share of the shell's surplus that flows into
    the cabin rather than to ambient."""
    T_cab, T_int, T_sh, T_ev, w = x
    hA_ext = s.hA_ext0 + s.hA_ext_v * speed_factor(v_veh)
    w_sh = s.hA_sh / (s.hA_sh + hA_ext)
    return (s.C_cab * T_cab + s.C_int * T_int + w_sh * s.C_sh * T_sh + s.C_ew * T_ev
            + s.M_cab * s.h_fg * w)


def step(s):
    r = interval(s, [s[n] for n in STATES], (s.W_bl, s.T_evap_set), (s.v_veh, s.T_amb))
    # the wall's storage from its state at the interval's end (s.next): the measured one
    # when the map is fitted by equation error, the step's own when simulated
    Q_e = refrigerant_heat(s, r.Q_coil, s.T_evap, s.next.T_evap, TS)
    return {**dict(zip(STATES, r.x, strict=True)), "T_ain": r.T_ain,
            "P_comp": compressor_power(s, Q_e, r.T_evap, s.v_veh, s.T_amb), "P_bl": r.P_bl}


def plausibility(s) -> list[str]:
    """Values the equations cannot use: a capacity, time constant, air mass or NTU that is
    not positive, a recirculated share outside [0, 1) or an ambient humidity outside [0, 1]."""
    out = [f"{n} must be positive, got {getattr(s, n):g}"
           for n in ("C_cab", "C_int", "C_sh", "tau_ew", "M_cab", "ntu_ref") if getattr(s, n) <= 0]
    if not 0.0 <= s.r_max < 1.0 or not 0.0 <= s.RH_amb <= 1.0:
        out.append("r_max must lie in [0, 1) and RH_amb in [0, 1]")
    return out


model = Model(
    "econ",
    states=[State(n, u) for n, u in zip(STATES, STATE_UNITS, strict=True)],
    inputs=[Signal("W_bl", "kg/s"), Signal("T_evap_set", "K")],
    disturbances=[Signal("v_veh", "m/s"), Signal("T_amb", "K")],
    outputs=[Signal("T_ain", "K"), Signal("P_comp", "W"), Signal("P_bl", "W")],
    parameters=(
        [Parameter(n, u, v, lo, hi, description=m) for n, u, v, lo, hi, m in THERMAL]
        + [Parameter("C_ew", "J/K", 2000.0, 0.0, 5e4,
                     description="evaporator wall capacity in the refrigerant heat")]
        + [Parameter(n, "1", c, description=f"inverse-COP map term {t}")
           for n, c, t in zip(MAP_NAMES, _MAP_START, MAP_TERMS, strict=True)]
        + [Parameter(n, u, b, description=m)
           for (n, u, m), b in zip(BETA, PAPER_BETA, strict=True)]),
    constants=[Constant("c_p", 1008.0, "J/(kg K)", "specific heat of air (paper Table II)"),
               Constant("h_fg", H_FG, "J/kg", "latent heat of water near 20 degC"),
               Constant("p_atm", P_ATM, "Pa", "standard atmosphere")],
    groups={"power_map": Group(MAP_NAMES, view=PowerMap)}, checks=plausibility,
    Ts=TS, step=step,
    description="acid's economic model: cabin, interior, shell, evaporator wall, humidity",
)


#: How ``acid fit --model econ`` identifies it (``acid.ident.stages``): (parameters,
#: equations, method) in order. Eq. 5 by least squares on P_bl; the thermal part by one-step
#: prediction error of the states and the supply air; then C_ew and the power map on P_comp
#: with the model's coil load (the refrigerant side does not feed back into the air side).
FIT_STAGES = (
    (tuple(n for n, _, _ in BETA), ("P_bl",), "ls"),
    (THERMAL_NAMES, STATES + ("T_ain",), "ee"),
    (("C_ew",) + MAP_NAMES, ("P_comp",), "ee"),
)
#: Seconds left out at each experiment's start by the one-step stages: the hot-soak
#: pull-down, with the cabin warmer than ambient, is not what the recirculation describes.
FIT_SKIP_S = 600.0

#: A hot-soaked start (K, kg/kg): the default initial state of the model as a plant.
HOT_SOAK = {"T_cab": 313.15, "T_int": 315.15, "T_shell": 315.15, "T_evap": 303.15,
            "w_cab": 0.0085}


class _ByName(dict):
    __getattr__ = dict.__getitem__


def parameters(theta) -> _ByName:
    """The parameters (vector ``theta`` in the declared order: numbers or a CasADi vector)
    and the constants by name, as the functions above read them (``s.C_cab``, ``s["f_q"]``)."""
    t = ca.vertsplit(theta) if _is_sym(theta) else np.asarray(theta, dtype=float).tolist()
    return _ByName(zip(model.parameter_names, t, strict=True),
                   **{c.name: c.value for c in model.constants})


def casadi_interval(dt: float = TS, n_sub: int | None = None) -> ca.Function:
    """``F(x[5], u[2], d[2], p[np], dist[5]) -> (x_next, T_ain, Q_e, P_comp, P_bl, Q_coil,
    T_evap)``: one interval of ``dt`` s as a CasADi Function (SX inside) of the declared
    parameter vector, for NLPs whose grid is not the declared step (``dist``: additive
    derivative terms; ``Q_coil`` and ``T_evap`` interval means)."""
    x, u, d = ca.SX.sym("x", len(STATES)), ca.SX.sym("u", 2), ca.SX.sym("d", 2)
    p, w = ca.SX.sym("p", model.np), ca.SX.sym("dist", len(STATES))
    r = interval(parameters(p), ca.vertsplit(x), ca.vertsplit(u), ca.vertsplit(d), dt, n_sub,
                 ca.vertsplit(w))
    return ca.Function("econ_interval", [x, u, d, p, w],
                       [ca.vertcat(*r.x), r.T_ain, r.Q_e, r.P_comp, r.P_bl, r.Q_coil, r.T_evap],
                       ["x", "u", "d", "p", "dist"],
                       ["x_next", "T_ain", "Q_e", "P_comp", "P_bl", "Q_coil", "T_evap"])
