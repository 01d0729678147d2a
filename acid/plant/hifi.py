"""The high-fidelity A/C + cabin plant: acid's open stand-in for NREL's CoolSim.

Second generation. Quasi-static refrigerant cycle (``acid.plant.cycle``: compressor
map in speed and pressure ratio, inverter + motor losses, refrigerant-side UA ~ m_r^0.8,
suction-line drop) + dynamic thermal masses, integrated at a fixed internal step ``dt_int``
(default 0.5 s) inside each 5 s sample:

* air mixing: r = sat(k_rec (T_amb - T_cab), 0, r_max), T_mix = r T_cab + (1 - r) T_amb
  + f_bl_heat P_bl / (W c_p) (the blower's heat enters ahead of the evaporator); likewise
  the humidity ratio w_mix;
* evaporator air side (epsilon-NTU against the wall, Lewis analogy for moisture):
  UA_ea = UA_ea0 (W/W_ea0)^n_ea, eps = 1 - exp(-UA_ea/(W c_p)),
  Q_sens = eps W c_p (T_mix - T_ew); when w_mix > w_sat(T_ew):
  w_ain = w_mix - eps (w_mix - w_sat(T_ew)), Q_lat = W (w_mix - w_ain) h_fg;
* front end (``front_end``): condenser face air flow from the balance of fan curve, ram
  pressure and grille + core resistance, a PWM fan proportional to head pressure (floor at
  low speed, off at speed when the pressure allows), hot-air recirculation at idle,
  Q_ca = G_ca(v, fan) (T_cw - T_amb - dT_rec(v)): **this is where vehicle speed enters the
  cycle**;
* cabin: C_cab dT_cab/dt = hA_int (T_int - T_cab) + hA_sh (T_shell - T_cab)
  + W c_p (T_ain - T_cab) + m_inf(v) c_p (T_amb - T_cab) + Q_pass,
  C_int dT_int/dt = G A_glass tau + hA_int (T_cab - T_int) + hA_is (T_int_slow - T_int),
  C_int_slow dT_int_slow/dt = hA_is (T_int - T_int_slow),
  C_sh dT_shell/dt = G A_sun alpha + hA_ext(v) (T_amb - T_shell) + hA_sh (T_cab - T_shell)
  with hA_ext(v) from a turbulent flat plate, M_cab dw_cab/dt = W (w_ain - w_cab)
  + m_inf (w_amb - w_cab) + m_moist_pass, M_cab = C_cab / c_p;
* walls: C_ew dT_ew/dt = Q_sens + Q_lat - Q_e, C_cw dT_cw/dt = Q_c - Q_ca;
* controls (``acid.plant.controller``): compressor PI with on/off hysteresis, speed capped by
  the head-pressure derate and frost protection, cut-out above ``p_cut``; in nominal mode the
  blower PI, the evaporator set-point reset and the A/C demand; compressor speed lags its
  command with ``tau_N``.

Integration: each node's own linear term is integrated exactly (exponential Euler: cabin air,
both heat-exchanger walls, cabin water), couplings and the refrigerant heat flows are
explicit; interior and shell use forward Euler. ``HifiPlant.balance()`` integrates every
flow with the trapezoidal rule and compares it with the stored energy (``acid plant-check``,
check b); the 0.5 s step stays within 0.12 % of 0.01 s in 600 s energy (check c).

Measurements follow ``acid.plant.base``: states at t_k (before the step), inputs held,
outputs and powers as means over [t_k, t_k + Ts). Temperatures in K, pressures in Pa.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from acid.errors import ConfigError
from acid.plant.base import (
    Measurement,
    Plant,
    balance_table,
    checked_ambient,
    validated_initial,
)
from acid.plant.config import PlantConfig
from acid.plant.controller import BlowerLoop, CompressorLoop
from acid.plant.cycle import make_solver

MODES = ("direct", "nominal")

#: Every dynamic state: the keys of ``HifiPlant.measure()`` accepted by ``reset(initial=...)``
#: (temperatures K, w_cab kg/kg, N_comp_state (the lagged compressor speed, at t_k) and
#: comp_integrator rpm, blower_integrator kg/s,
#: T_evap_set_eff K (evaporator set-point after the low-load reset), ac_state, cut_out and
#: ac_demand 0/1; T_e_last, T_c_last K and p_dis_last Pa (0 = stood still): the last cycle
#: solution, which warm-starts the solver and drives the fan and protections).
INITIAL_KEYS = ("T_cab", "T_int", "T_shell", "T_evap", "T_cw", "w_cab", "T_int_slow",
                "N_comp_state", "comp_integrator", "blower_integrator", "T_evap_set_eff",
                "ac_state", "cut_out",
                "ac_demand", "T_e_last", "T_c_last", "p_dis_last")

#: The states of the plant's own loops (nominal mode: compressor and blower PI integrators,
#: the low-load reset's effective evaporator set-point, the A/C's on/off logic): the
#: controller's memory, not the car's. A start shared by controllers with other set-points
#: drops them (:func:`physical_state`), or the loops would run a pass at the set-point the
#: state was saved under.
LOOP_KEYS = ("comp_integrator", "blower_integrator", "T_evap_set_eff", "ac_state", "cut_out",
             "ac_demand")


def physical_state(state: dict[str, float]) -> dict[str, float]:
    """``state`` without :data:`LOOP_KEYS`: what a start shared by different controllers
    may carry (temperatures K, humidity kg/kg, compressor speed, the cycle's last solution)."""
    return {k: v for k, v in state.items() if k not in LOOP_KEYS}


#: Units (inside: K for temperatures) of the states ``acid.data.CHANNELS`` does not know.
STATE_UNITS = {"N_comp_state": "rpm", "comp_integrator": "rpm",
               "blower_integrator": "kg/s", "T_evap_set_eff": "K", "ac_state": "1",
               "cut_out": "1", "ac_demand": "1", "T_e_last": "K",
               "T_c_last": "K", "p_dis_last": "Pa"}

_STEP_KEYWORDS = ("T_cab_set", "compressor_enabled", "T_int", "T_shell", "T_amb")


def saturation_humidity_ratio(T: float, p_atm: float = 101325.0) -> float:
    """Humidity ratio of saturated moist air at T (K), kg water / kg dry air.

    Magnus formula over water (WMO 2008, Sonntag constants 17.62 / 243.12 degC; better than
    0.1 % from -45 to 60 degC): p_ws = 611.2 exp(17.62 t / (243.12 + t)) Pa, t in degC.
    """
    t = T - 273.15
    p_ws = 611.2 * math.exp(17.62 * t / (243.12 + t))
    return 0.621945 * p_ws / (p_atm - p_ws)


def humidity_ratio(T: float, RH: float, p_atm: float = 101325.0) -> float:
    """Humidity ratio at temperature T (K) and relative humidity RH (0-1), kg/kg."""
    t = T - 273.15
    p_w = RH * 611.2 * math.exp(17.62 * t / (243.12 + t))
    return 0.621945 * p_w / (p_atm - p_w)


#: Condenser air-side conductance with no forced flow (natural convection of a parked front
#: end), W/K: assumption, keeps the condenser wall coupled to ambient with the fan off.
G_CA_NATURAL = 20.0

#: Fan speed fractions are quantised to 1/FAN_LEVELS (PWM steps) so that the front end can be
#: tabulated per vehicle speed.
FAN_LEVELS = 20


@dataclass(frozen=True)
class FrontEnd:
    """Condenser air side at one vehicle speed, per fan speed level i (s = i / FAN_LEVELS).

    Attributes
    ----------
    s : (L+1,) fan speed fraction actually running (0 where the fan would add no air).
    Q : (L+1,) face air flow, m^3/s.      m_ca : (L+1,) air mass flow, kg/s.
    G_ca : (L+1,) eps_c m_ca c_p, W/K.     P_fan : (L+1,) fan electric power, W.
    T_in_rise : hot-air recirculation: condenser inlet air above ambient, K.
    s_floor : fan speed the controller keeps at this vehicle speed while the compressor runs.
    """

    s: tuple
    Q: tuple
    m_ca: tuple
    G_ca: tuple
    P_fan: tuple
    T_in_rise: float
    s_floor: float

    def level(self, p_c: float, config: PlantConfig) -> int:
        """Fan level for head pressure ``p_c`` (Pa): proportional between p_fan_low and
        p_fan_high, at least ``s_floor`` (a NaN pressure, compressor stopped, gives 0)."""
        if p_c != p_c:
            return 0
        x = (p_c - config.p_fan_low) / (config.p_fan_high - config.p_fan_low)
        if x < self.s_floor:
            x = self.s_floor
        return FAN_LEVELS if x >= 1.0 else int(x * FAN_LEVELS + 0.5)


def front_end(config: PlantConfig, v_veh: float, T_amb: float | None = None) -> FrontEnd:
    """Condenser face air flow from a pressure balance, per fan speed level (closed form).

    Fan (speed fraction s; fan laws dp ~ s^2, Q ~ s) and ram pressure act against the
    grille + core resistance K Q^2:

        dp_ram + dp0 s^2 (1 - (Q / (s Q_free))^2) = K_front Q^2
        => Q = sqrt((dp_ram + dp0 s^2) / (K_front + dp0 / Q_free^2)),
        dp_ram = 1/2 rho C_ram v^2.

    With the fan off the stopped fan is a resistance K_fan_off Q^2: Q = sqrt(dp_ram / (K_front
    + K_fan_off)); a speed level at which the fan would move less air than ram alone (or would
    be overdriven beyond its free delivery s Q_free) is left off by the fan control. The fan's
    electric power follows the fan laws, P = s^3 P_1, with P_1 = dp_fan(Q_1) Q_1 / eta_fan at
    full speed and standstill. Air side: UA_ca = UA_ca0 (m_ca / m_ca0)^n_ca, eps_c =
    1 - exp(-UA_ca / (m_ca c_p)). Hot-air recirculation raises the condenser inlet air by
    dT_recirc (1 - v / v_recirc) below v_recirc. Fan control (``FrontEnd.level``): a PWM fan
    proportional to head pressure between the switch points p_fan_low and p_fan_high, never
    below ``s_fan_low`` below ``v_fan_off`` while the compressor runs, off at speed when the
    pressure allows. ``config.front_end_speed = False`` evaluates everything at standstill
    (speed-blind counterfactual).
    """
    c = config
    v = float(v_veh) if c.front_end_speed else 0.0
    T_amb = c.T_amb if T_amb is None else float(T_amb)
    rho = c.p_atm / (287.05 * T_amb)
    cp = c.c_p_air
    dp_ram = 0.5 * rho * c.C_ram * v * v
    K_fan = c.dp_fan0 / c.Q_fan_free ** 2
    Q_off = math.sqrt(dp_ram / (c.K_front + c.K_fan_off))
    Q_full0 = math.sqrt(c.dp_fan0 / (c.K_front + K_fan))
    P_1 = c.dp_fan0 * (1.0 - (Q_full0 / c.Q_fan_free) ** 2) * Q_full0 / c.eta_fan
    S, Qs, ms, Gs, Ps = [], [], [], [], []
    for i in range(FAN_LEVELS + 1):
        s = i / FAN_LEVELS
        P = s ** 3 * P_1
        if s == 0.0:
            Q = Q_off
        else:
            Q = math.sqrt((dp_ram + c.dp_fan0 * s * s) / (c.K_front + K_fan))
            if Q <= Q_off or Q > s * c.Q_fan_free:
                Q, P, s = Q_off, 0.0, 0.0
        m = rho * Q
        if m > 0.0:
            UA = c.UA_ca0 * (m / c.m_ca0) ** c.n_ca
            G = m * cp * (1.0 - math.exp(-UA / (m * cp)))
        else:
            G = 0.0
        G = max(G, G_CA_NATURAL)
        S.append(s)
        Qs.append(Q)
        ms.append(m)
        Gs.append(G)
        Ps.append(P)
    rise = c.dT_recirc * max(0.0, 1.0 - v / c.v_recirc)
    floor = c.s_fan_low * max(0.0, 1.0 - v / c.v_fan_off)
    return FrontEnd(tuple(S), tuple(Qs), tuple(ms), tuple(Gs), tuple(Ps), rise, floor)


def condenser_air_conductance(config: PlantConfig, v_veh: float, s_fan: float | None = None
                              ) -> float:
    """eps_c m_ca c_p of the condenser air side at ``v_veh`` (m/s), W/K.

    ``s_fan`` is the fan speed fraction (0-1); by default the controller's floor at this speed,
    s_fan_low (1 - v / v_fan_off) (0 above v_fan_off).
    """
    fe = front_end(config, v_veh)
    s = fe.s_floor if s_fan is None else float(s_fan)
    return fe.G_ca[int(round(min(max(s, 0.0), 1.0) * FAN_LEVELS))]


def steady_cycle(N: float, T_evap_wall: float, v_veh: float = 0.0,
                 config: PlantConfig | None = None, T_amb: float | None = None,
                 fan: float | None = None):
    """Cycle at steady condenser wall: fixed N (rpm), T_ew (K), speed (m/s) and ambient (K).

    Solves ``cycle`` together with the condenser wall balance Q_c = G_ca (T_cw - T_ca,in),
    T_ca,in = T_amb + hot-air recirculation (fixed-point iteration on T_cw). The fan runs at
    speed fraction ``fan`` (0-1) or, by default, as the fan control sets it from the head
    pressure (``FrontEnd.level``). Returns ``(CycleResult, T_cw)``; the fan's power at a
    level is ``front_end(config, v_veh).P_fan[level]``.
    """
    from acid.plant.cycle import cycle

    config = config or PlantConfig()
    T_amb = config.T_amb if T_amb is None else float(T_amb)
    fe = front_end(config, v_veh, T_amb)
    T_in = T_amb + fe.T_in_rise
    T_cw, res = T_in + 5.0, None
    for _ in range(400):
        lev = fe.level(res.p_c if res is not None and N > 0 else math.nan, config)
        if res is None:
            lev = int(round(fe.s_floor * FAN_LEVELS))
        if fan is not None:
            lev = int(round(min(max(fan, 0.0), 1.0) * FAN_LEVELS))
        G_ca = fe.G_ca[lev]
        res = cycle(N, T_evap_wall, T_cw, config,
                    guess=None if res is None or N <= 0 else (res.T_e, res.T_c))
        T_new = T_in + res.Q_c / G_ca
        if abs(T_new - T_cw) < 1e-7:
            break
        T_cw = 0.5 * (T_cw + T_new)
    return res, T_cw


def _p_sat_function(config: PlantConfig):
    """p_sat(T) (Pa) of the configured refrigerant from the cycle's tables (linear)."""
    from acid.plant import refrigerant as rf

    P = rf.table(config.refrigerant, config.superheat, config.subcool).lists[0]
    lo, inv, imax = rf.T1_LO, 1.0 / rf.DT1, len(P) - 2

    def p_sat(T: float) -> float:
        x = (T - lo) * inv
        i = int(x)
        i = 0 if i < 0 else (imax if i > imax else i)
        return P[i] + (x - i) * (P[i + 1] - P[i])

    return p_sat


class HifiPlant(Plant):
    """High-fidelity A/C + cabin plant (quasi-static cycle, dynamic thermal masses).

    Parameters
    ----------
    config : plant configuration; ``PlantConfig()`` (the documented calibration) by default.
    mode : "direct": W_bl and T_evap_set are commanded, only the compressor PI runs inside
        (excitation, MPC); "nominal": the paper's nominal controller sets both (blower PI on
        the cabin set-point ``config.T_cab_set``, compressor PI on ``config.T_ew_set`` reset
        up to ``T_ew_set_max`` at low load) and the inputs given to ``step`` are ignored.
    meas_noise_std : std of white noise added to the recorded T_cab, T_evap, T_ain, K.
    rng : random generator for the noise (seed it for reproducible data).

    Notes
    -----
    Deterministic without noise. Blower flows outside [W_bl_min, W_bl_max] are clipped; the
    applied flow is recorded in ``W_bl``. ``balance()`` returns the energy and water balances
    accumulated since the last ``reset``.
    """

    name = "hifi"
    Ts = 5.0

    def __init__(self, config: PlantConfig | None = None, mode: str = "direct",
                 meas_noise_std: float = 0.0, rng: np.random.Generator | None = None):
        if mode not in MODES:
            raise ConfigError(f"plant mode {mode!r} unknown (choose 'direct' or 'nominal')")
        if meas_noise_std < 0:
            raise ConfigError(f"meas_noise_std must not be negative, got {meas_noise_std}")
        self.cfg = config if config is not None else PlantConfig()
        self.mode = mode
        self.Ts = float(self.cfg.Ts)
        self.meas_noise_std = float(meas_noise_std)
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self._solve, _ = make_solver(self.cfg)
        self._p_sat = _p_sat_function(self.cfg)
        self._comp = CompressorLoop(self.cfg)
        self._blower = BlowerLoop(self.cfg)
        self.n_sub = int(round(self.Ts / self.cfg.dt_int))
        self._fe_cache: dict = {}
        self._acw_cache: dict = {}
        self.reset()

    # ------------------------------------------------------------------ protocol
    def config(self) -> dict:
        d = self.cfg.to_dict()
        d.update(mode=self.mode, meas_noise_std_K=self.meas_noise_std)
        return d

    def units(self) -> dict[str, str]:
        """Units of the controller states ``acid.data.CHANNELS`` does not know (K inside)."""
        return dict(STATE_UNITS)

    def nominal(self) -> HifiPlant:
        """A fresh copy of this plant run by its own nominal controller (paper section II-A)."""
        return HifiPlant(self.cfg, mode="nominal", meas_noise_std=self.meas_noise_std,
                         rng=self.rng)

    def reset(self, initial: dict[str, float] | None = None) -> Measurement:
        """Reset to the hot soak of the configuration, overridden by ``initial``.

        Keys: ``INITIAL_KEYS`` (temperatures in K; w_cab kg/kg; N_comp_state rpm;
        comp_integrator rpm; blower_integrator kg/s; T_evap_set_eff K; ac_state, cut_out,
        ac_demand 0/1; the
        last cycle solution T_e_last, T_c_last K, p_dis_last Pa, 0 = stood still). Without
        ``w_cab`` the cabin starts with the ambient humidity ratio (a closed, soaked car holds
        outside air's moisture). Without controller states the compressor starts on from rest
        and both PI integrators sit at their minimum outputs.
        """
        c = self.cfg
        init = {"T_cab": c.T_cab0, "T_int": c.T_int0, "T_shell": c.T_shell0,
                "T_evap": c.T_ew0, "T_cw": c.T_cw0}
        init.update(validated_initial(initial, INITIAL_KEYS))
        self.T_amb = c.T_amb
        self.w_amb = humidity_ratio(c.T_amb, c.RH_amb, c.p_atm)
        self.T_cab, self.T_int, self.T_shell = init["T_cab"], init["T_int"], init["T_shell"]
        self.T_int_slow = init.get("T_int_slow", self.T_int)
        self.T_ew, self.T_cw = init["T_evap"], init["T_cw"]
        self.w_cab = init.get("w_cab", self.w_amb)
        self.N = init.get("N_comp_state", 0.0)
        self.T_e = init.get("T_e_last", self.T_ew - 5.0)
        self.T_c = init.get("T_c_last", self.T_cw + 5.0)
        self.p_c = init.get("p_dis_last", 0.0) or math.nan  # 0: the compressor stood still
        self.p_s = math.nan
        self._comp.reset(on=bool(init.get("ac_state", 1.0) >= 0.5))
        self._blower.reset()
        if "comp_integrator" in init:
            self._comp.integ = init["comp_integrator"]
        if "blower_integrator" in init:
            self._blower.integ = init["blower_integrator"]
        self.T_reset = init.get("T_evap_set_eff", c.T_ew_set) - c.T_ew_set
        self.cut_out = bool(init.get("cut_out", 0.0) >= 0.5)
        self.ac_demand = bool(init.get("ac_demand", 1.0) >= 0.5)
        self.t = 0.0
        self._bal = [0.0] * 12
        self._U0 = self._stored()
        return self.measure()

    def measure(self) -> Measurement:
        """Every dynamic state (K; w_cab kg/kg; controller states), keyed as ``INITIAL_KEYS``.

        ``reset(initial=plant.measure())`` restores the plant exactly (plus ``T_amb``, which
        is a boundary condition, not a state).
        """
        return {"T_cab": self.T_cab, "T_evap": self.T_ew, "T_int": self.T_int,
                "T_shell": self.T_shell, "T_amb": self.T_amb, "w_cab": self.w_cab,
                "T_cw": self.T_cw, "T_int_slow": self.T_int_slow, "N_comp_state": self.N,
                "comp_integrator": self._comp.integ, "blower_integrator": self._blower.integ,
                "T_evap_set_eff": self.cfg.T_ew_set + self.T_reset,
                "ac_state": 1.0 if self._comp.on else 0.0,
                "cut_out": 1.0 if self.cut_out else 0.0,
                "ac_demand": 1.0 if self.ac_demand else 0.0, "T_e_last": self.T_e,
                "T_c_last": self.T_c,
                "p_dis_last": self.p_c if self.p_c == self.p_c else 0.0}

    def _front_end(self, v: float) -> FrontEnd:
        key = (v, self.T_amb)
        fe = self._fe_cache.get(key)
        if fe is None:
            if len(self._fe_cache) > 256:
                self._fe_cache.clear()
                self._acw_cache.clear()
            fe = self._fe_cache[key] = front_end(self.cfg, v, self.T_amb)
        return fe

    def _a_cw(self, fe: FrontEnd) -> tuple:
        a = self._acw_cache.get(id(fe))
        if a is None or a[0] is not fe:
            a = (fe, tuple(math.exp(-G * self.cfg.dt_int / self.cfg.C_cw) for G in fe.G_ca))
            self._acw_cache[id(fe)] = a
        return a[1]

    def _stored(self) -> tuple[float, float, float, float]:
        """(U_ew, U_cw, U_cabin, M_water): stored energies (J, from 0 K) and water (kg)."""
        c = self.cfg
        return (c.C_ew * self.T_ew, c.C_cw * self.T_cw,
                c.C_cab * self.T_cab + c.C_int * self.T_int + c.C_int_slow * self.T_int_slow
                + c.C_sh * self.T_shell, c.C_cab / c.c_p_air * self.w_cab)

    def balance(self) -> dict:
        """Energy and water balances since ``reset``: stored change against integrated flows.

        Returns ``{name: {"stored", "inflow", "residual", "scale", "relative"}}`` for the
        refrigerant loop (Q_c = Q_e + W, quasi-static: stored 0), the evaporator and condenser
        walls, the cabin (air + both interior nodes + shell) in J, and the cabin water in kg.
        ``relative`` = |residual| / scale, scale = integral of the absolute flows. Flows are
        integrated with the trapezoidal rule over each internal step, so ``relative`` measures
        the integrator's splitting error.
        """
        U1 = self._stored()
        b = self._bal
        out = {"refrigerant": (0.0, b[0], b[1]), "evaporator_wall": (U1[0] - self._U0[0], b[2],
                                                                   b[3]),
               "condenser_wall": (U1[1] - self._U0[1], b[4], b[5]),
               "cabin": (U1[2] - self._U0[2], b[6], b[7]),
               "water": (U1[3] - self._U0[3], b[8], b[9])}
        return balance_table(out)

    def step(self, W_bl: float, T_evap_set: float, v_veh: float = 0.0, **kw) -> Measurement:
        """Advance one sample period Ts (see the module docstring for the model).

        Parameters
        ----------
        W_bl : blower flow, kg/s (direct mode; ignored in nominal mode).
        T_evap_set : evaporator wall set-point, K (direct mode; nominal uses
            ``config.T_ew_set`` plus its low-load reset).
        v_veh : vehicle speed, m/s, held over the step.
        T_cab_set : (keyword, nominal mode) cabin set-point, K; default ``config.T_cab_set``.
        compressor_enabled : (keyword) False forces the compressor off (open-loop shut-off).
        T_amb : (keyword) ambient temperature over this step, K (default: the configured
            ``T_amb``); the ambient humidity ratio follows it at the configured ``RH_amb``.
        T_int, T_shell : accepted and ignored (this plant computes its own).

        Returns
        -------
        Row k: every state at t_k (``measure()``: T_cab, T_evap, T_int, T_int_slow, T_shell,
        T_cw, K; w_cab, kg/kg; the controller states), T_amb, the applied inputs
        (W_bl mean, kg/s; T_evap_set, K; v_veh, m/s) and means over the step: T_ain, T_e,
        T_c (K); N_comp (rpm); P_comp (compressor electric power), P_bl (paper eq. 5), P_fan
        (condenser fan), W_comp (compressor shaft power), Q_evap, Q_cond, Q_lat (W);
        COP = Q_evap / P_comp (0 while the compressor stands still); p_suc (compressor
        suction = low-side service port) and p_dis (head) pressures (Pa; while the
        compressor stands still, the saturation pressures of the two walls); m_r, m_ca
        (refrigerant and condenser air flows, kg/s); fan_speed
        (condenser fan speed fraction); recirc (fraction); ac_on (fraction of the step the
        A/C logic was on).
        """
        for key in kw:
            if key not in _STEP_KEYWORDS:
                raise ConfigError(f"HifiPlant.step: unknown keyword {key!r}")
        c = self.cfg
        nominal = self.mode == "nominal"
        enabled = bool(kw.get("compressor_enabled", True))
        T_cab_set = float(kw.get("T_cab_set", c.T_cab_set))
        T_set_in = c.T_ew_set if nominal else float(T_evap_set)
        v = float(v_veh)
        if "T_amb" in kw:
            T_amb_k = checked_ambient(kw["T_amb"])
            if T_amb_k != self.T_amb:
                self.T_amb = T_amb_k
                self.w_amb = humidity_ratio(T_amb_k, c.RH_amb, c.p_atm)
        if not (math.isfinite(v) and v >= 0.0):
            raise ConfigError(f"vehicle speed must be a finite non-negative number, got {v_veh}")
        if not nominal:
            W_cmd = float(W_bl)
            if not math.isfinite(W_cmd) or not math.isfinite(T_set_in):
                raise ConfigError(f"non-finite input W_bl = {W_bl}, T_evap_set = {T_evap_set}")
            W_cmd = min(max(W_cmd, c.W_bl_min), c.W_bl_max)
        else:
            W_cmd = 0.0
        row = self.measure()

        # ---- constants over the step (plain floats for a lean substep loop)
        dt = c.dt_int
        n = self.n_sub
        cp = c.c_p_air
        T_amb, w_amb, p_atm = self.T_amb, self.w_amb, c.p_atm
        fe = self._front_end(v)
        G_st, P_st, m_st, s_st_tab = fe.G_ca, fe.P_fan, fe.m_ca, fe.s
        a_st = self._a_cw(fe)
        T_ca_in = T_amb + fe.T_in_rise
        v_cab = v if c.cabin_speed else 0.0
        lev_floor = int(round(fe.s_floor * FAN_LEVELS))
        fan_x = FAN_LEVELS / (c.p_fan_high - c.p_fan_low)
        hA_ext = c.hA_ext(v_cab)
        m_inf = c.m_inf0 + c.k_inf * v_cab
        Ginf = m_inf * cp
        hA_int, hA_sh, hA_is, C_cab = c.hA_int, c.hA_sh, c.hA_int_slow, c.C_cab
        M_cab = C_cab / cp
        k_int, k_is, k_sh = dt / c.C_int, dt / c.C_int_slow, dt / c.C_sh
        Q_si, Q_ss, Q_pass, m_moist = c.Q_solar_int, c.Q_solar_shell, c.Q_pass, c.m_moist_pass
        UA_ea0, W_ea0, n_ea, C_ew, h_fg = c.UA_ea0, c.W_ea0, c.n_ea, c.C_ew, c.h_fg
        b1, b2, b3, f_bh = c.beta1, c.beta2, c.beta3, c.f_bl_heat
        k_rec, r_max = c.k_rec, c.r_max
        W_min = c.W_bl_min
        a_N = math.exp(-dt / c.tau_N)
        N_min, N_max = c.N_min, c.N_max
        p_fl, p_der, p_cut = c.p_fan_low, c.p_derate, c.p_cut
        k_der = (N_max - N_min) / (p_cut - p_der)
        T_e_min, K_frost = c.T_e_min, c.K_frost
        reset_max = c.T_ew_set_max - c.T_ew_set
        k_reset = c.k_reset
        solve, p_sat = self._solve, self._p_sat
        comp, blower = self._comp, self._blower
        exp = math.exp

        T_cab, T_int, T_is, T_sh = self.T_cab, self.T_int, self.T_int_slow, self.T_shell
        T_ew, T_cw, w_cab, N = self.T_ew, self.T_cw, self.w_cab, self.N
        T_e, T_c, p_c, p_s = self.T_e, self.T_c, self.p_c, self.p_s
        T_reset, cut, demand = self.T_reset, self.cut_out, self.ac_demand
        W_prev, eps = -1.0, 0.0
        s_W = s_Pbl = s_Pc = s_Qe = s_Qc = s_Qlat = s_Tain = s_N = s_r = s_Te = s_Tc = 0.0
        s_on = s_Pf = s_W_sh = s_ps = s_pc = s_m = s_mca = s_st = s_Tset = 0.0
        bal = self._bal
        B0 = B1 = B2 = B3 = B4 = B5 = B6 = B7 = B8 = B9 = 0.0

        for _ in range(n):
            # ---- controllers (continuous-time emulation at the internal step)
            if nominal:
                W = blower.update(T_cab, T_cab_set, dt)
                e_cab = T_cab - T_cab_set
                if demand and (e_cab > 0.0 or W <= W_min):  # raise only at minimum blower
                    T_reset -= k_reset * e_cab * dt
                    T_reset = 0.0 if T_reset < 0.0 else (reset_max if T_reset > reset_max
                                                         else T_reset)
                # A/C demand: off when even the fully reset evaporator overcools the cabin
                if demand and T_reset >= reset_max and e_cab < -0.5:
                    demand = False
                elif not demand and e_cab > 0.5:
                    demand = True
                T_set = T_set_in + T_reset
            else:
                W = W_cmd
                T_set = T_set_in
            # protections on the last cycle state: head-pressure cut-out/derate, frost
            N_cap = N_max
            if p_c == p_c:  # not NaN: the compressor ran
                if p_c > p_cut:
                    cut = True
                elif cut and p_c < p_cut - 6.0e5:
                    cut = False
                if p_c > p_der:
                    N_cap -= k_der * (p_c - p_der)
                if T_e < T_e_min:
                    N_cap -= K_frost * (T_e_min - T_e)
                if N_cap < N_min:
                    N_cap = N_min
            N_cmd = comp.update(T_ew, T_set, dt, enabled and demand and not cut, N_cap)
            N = N_cmd + (N - N_cmd) * a_N
            if N < 1.0 and N_cmd == 0.0:
                N = 0.0
            if N > 0.0 and p_c == p_c:  # fan: proportional to head pressure, floor at low speed
                st = int((p_c - p_fl) * fan_x + 0.5)
                st = lev_floor if st < lev_floor else (FAN_LEVELS if st > FAN_LEVELS else st)
            else:
                st = lev_floor if N > 0.0 else 0
            G_ca = G_st[st]
            # ---- air mixing (controller.recirculation, inlined), blower heat
            r = k_rec * (T_amb - T_cab)
            r = 0.0 if r < 0.0 else (r_max if r > r_max else r)
            P_bl = (b1 * W + b2) * W + b3
            Wcp = W * cp
            T_mix = T_amb + r * (T_cab - T_amb) + f_bh * P_bl / Wcp
            w_mix = w_amb + r * (w_cab - w_amb)
            # ---- evaporator air side, epsilon-NTU
            if W != W_prev:
                eps = 1.0 - exp(-UA_ea0 * (W / W_ea0) ** n_ea / Wcp)
                W_prev = W
            G_a = eps * Wcp
            t_ew = T_ew - 273.15
            p_ws = 611.2 * exp(17.62 * t_ew / (243.12 + t_ew))
            w_sat = 0.621945 * p_ws / (p_atm - p_ws)
            if w_mix > w_sat:
                w_ain = w_mix - eps * (w_mix - w_sat)
                Q_lat = W * (w_mix - w_ain) * h_fg
            else:
                w_ain, Q_lat = w_mix, 0.0
            # ---- refrigerant cycle (quasi-static)
            if N > 0.0:
                T_e, T_c, m_r, Q_e, Q_c, P_c, W_sh, p_s, p_c, _it = solve(N, T_ew, T_cw, T_e,
                                                                            T_c)
                s_ps += p_s
                s_pc += p_c
            else:  # no flow: each side sits at the saturation pressure of its wall
                T_e, T_c, m_r, Q_e, Q_c, P_c, W_sh = T_ew, T_cw, 0.0, 0.0, 0.0, 0.0, 0.0
                p_c = p_s = math.nan
                s_ps += p_sat(T_ew)
                s_pc += p_sat(T_cw)
            # ---- thermal masses (exponential Euler on each node's own term)
            Tinf = T_mix + (Q_lat - Q_e) / G_a
            T_ew_n = Tinf + (T_ew - Tinf) * exp(-G_a * dt / C_ew)
            T_ain = T_mix - eps * (T_mix - 0.5 * (T_ew + T_ew_n))
            Tinf = T_ca_in + Q_c / G_ca
            T_cw_n = Tinf + (T_cw - Tinf) * a_st[st]
            G = hA_int + hA_sh + Wcp + Ginf
            Tinf = (hA_int * T_int + hA_sh * T_sh + Wcp * T_ain + Ginf * T_amb + Q_pass) / G
            T_cab_n = Tinf + (T_cab - Tinf) * exp(-G * dt / C_cab)
            T_int_n = T_int + k_int * (Q_si + hA_int * (T_cab - T_int) + hA_is * (T_is - T_int))
            T_is += k_is * hA_is * (T_int - T_is)
            T_sh_n = T_sh + k_sh * (Q_ss + hA_ext * (T_amb - T_sh) + hA_sh * (T_cab - T_sh))
            winf = (W * w_ain + m_inf * w_amb + m_moist) / (W + m_inf)
            w_cab_n = winf + (w_cab - winf) * exp(-(W + m_inf) * dt / M_cab)
            # ---- balances (trapezoidal flows over the internal step)
            Tc_m = 0.5 * (T_cab + T_cab_n)
            Q_sens = G_a * (T_mix - 0.5 * (T_ew + T_ew_n))
            Q_ca = G_ca * (0.5 * (T_cw + T_cw_n) - T_ca_in)
            Q_sup = Wcp * (T_ain - Tc_m)
            Q_out = Q_si + Q_ss + Q_pass + hA_ext * (T_amb - T_sh) + Q_sup + Ginf * (T_amb - Tc_m)
            B0 += Q_c - Q_e - W_sh
            B1 += Q_c + Q_e + W_sh
            B2 += Q_sens + Q_lat - Q_e
            B3 += abs(Q_sens) + Q_lat + Q_e
            B4 += Q_c - Q_ca
            B5 += Q_c + abs(Q_ca)
            B6 += Q_out
            B7 += abs(Q_si) + Q_ss + Q_pass + abs(hA_ext * (T_amb - T_sh)) + abs(Q_sup) + abs(
                Ginf * (T_amb - Tc_m))
            wc_m = 0.5 * (w_cab + w_cab_n)
            B8 += W * (w_ain - wc_m) + m_inf * (w_amb - wc_m) + m_moist
            B9 += abs(W * (w_ain - wc_m)) + abs(m_inf * (w_amb - wc_m)) + m_moist
            T_ew, T_cw, T_cab, T_int, T_sh = T_ew_n, T_cw_n, T_cab_n, T_int_n, T_sh_n
            w_cab = w_cab_n
            # ---- means over the sample
            s_W += W
            s_Pbl += P_bl
            s_Pc += P_c
            s_W_sh += W_sh
            s_Qe += Q_e
            s_Qc += Q_c
            s_Qlat += Q_lat
            s_Tain += T_ain
            s_N += N
            s_r += r
            s_Te += T_e
            s_Tc += T_c
            s_on += comp.on
            s_Pf += P_st[st]
            s_m += m_r
            s_mca += m_st[st]
            s_st += s_st_tab[st]
            s_Tset += T_set

        self.T_cab, self.T_int, self.T_int_slow, self.T_shell = T_cab, T_int, T_is, T_sh
        self.T_ew, self.T_cw, self.w_cab, self.N = T_ew, T_cw, w_cab, N
        self.T_e, self.T_c, self.p_c, self.p_s = T_e, T_c, p_c, p_s
        self.T_reset, self.cut_out, self.ac_demand = T_reset, cut, demand
        self.t += n * dt
        for i, x in enumerate((B0, B1, B2, B3, B4, B5, B6, B7, B8, B9)):
            bal[i] += x * dt

        inv = 1.0 / n
        P_comp = s_Pc * inv
        Q_evap = s_Qe * inv
        row.update(
            T_ain=s_Tain * inv, W_bl=s_W * inv, T_evap_set=s_Tset * inv, v_veh=v,
            N_comp=s_N * inv, P_comp=P_comp, P_bl=s_Pbl * inv, P_fan=s_Pf * inv,
            COP=Q_evap / P_comp if P_comp > 0.0 else 0.0, recirc=s_r * inv,
            Q_evap=Q_evap, Q_cond=s_Qc * inv, Q_lat=s_Qlat * inv, W_comp=s_W_sh * inv,
            T_e=s_Te * inv, T_c=s_Tc * inv, ac_on=s_on * inv,
            p_suc=s_ps * inv, p_dis=s_pc * inv,
            m_r=s_m * inv, m_ca=s_mca * inv, fan_speed=s_st * inv,
        )
        if self.meas_noise_std:
            e = self.rng.standard_normal(3) * self.meas_noise_std
            row["T_cab"] += e[0]
            row["T_evap"] += e[1]
            row["T_ain"] += e[2]
        return row
