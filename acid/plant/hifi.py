"""The high-fidelity A/C + cabin plant: acid's open stand-in for NREL's CoolSim (PLANT.md).

Quasi-static refrigerant cycle (``acid.plant.cycle``) + dynamic thermal masses, integrated at
a fixed internal step ``dt_int`` (default 0.5 s) inside each 5 s sample:

* air mixing: r = sat(k_rec (T_amb - T_cab), 0, r_max), T_mix = r T_cab + (1 - r) T_amb, and
  likewise the humidity ratio w_mix;
* evaporator air side (epsilon-NTU against the wall, Lewis analogy for moisture):
  UA_ea = UA_ea0 (W/W_ea0)^n_ea, eps = 1 - exp(-UA_ea/(W c_p)),
  Q_sens = eps W c_p (T_mix - T_ew), T_ain = T_mix - eps (T_mix - T_ew); when
  w_mix > w_sat(T_ew): w_ain = w_mix - eps (w_mix - w_sat(T_ew)), Q_lat = W (w_mix - w_ain) h_fg;
* condenser air side: m_ca = m_ca_fan + k_ram V (linear fan + ram superposition),
  UA_ca = UA_ca0 (m_ca/m_ca_fan)^n_ca, Q_ca = eps_c m_ca c_p (T_cw - T_amb): **this is where
  vehicle speed enters** (and, weakly, through the shell's external convection);
* walls and cabin:
  C_ew dT_ew/dt = Q_sens + Q_lat - Q_e,     C_cw dT_cw/dt = Q_c - Q_ca,
  C_cab dT_cab/dt = hA_int (T_int - T_cab) + hA_sh (T_shell - T_cab) + W c_p (T_ain - T_cab)
                    + Q_pass,
  C_int dT_int/dt = Q_solar_int + hA_int (T_cab - T_int),
  C_sh dT_shell/dt = Q_solar_shell + hA_ext(V) (T_amb - T_shell) + hA_sh (T_cab - T_shell),
  M_cab dw_cab/dt = W (w_ain - w_cab) + m_moist_pass,   M_cab = C_cab / c_p;
* compressor speed: first-order lag tau_N behind the PI command (``acid.plant.controller``).

Integration: each node's own linear term is integrated exactly (exponential Euler; the cabin
air, whose time constant is about 10 s, and the two heat-exchanger walls), couplings and the
refrigerant heat flows are explicit; the slow interior and shell use forward Euler. Quartering
``dt_int`` changes the 600 s energy by < 0.5 % (PLANT.md behaviour 13, tested).

Measurements follow ``acid.plant.base``: states at t_k (before the step), inputs held,
outputs and powers as means over [t_k, t_k + Ts). Temperatures in K.
"""

from __future__ import annotations

import math

import numpy as np

from acid.errors import ConfigError
from acid.plant.base import Measurement, Plant
from acid.plant.config import PlantConfig
from acid.plant.controller import BlowerLoop, CompressorLoop
from acid.plant.cycle import make_solver

MODES = ("direct", "nominal")

#: Initial-condition keys accepted by ``HifiPlant.reset`` (K, except w_cab in kg/kg).
INITIAL_KEYS = ("T_cab", "T_int", "T_shell", "T_evap", "T_cw", "w_cab")

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


def condenser_air_conductance(config: PlantConfig, v_veh: float) -> float:
    """eps_c m_ca c_p of the condenser air side at vehicle speed ``v_veh`` (m/s), W/K.

    m_ca = m_ca_fan + k_ram v_veh (linear fan + ram superposition),
    UA_ca = UA_ca0 (m_ca / m_ca_fan)^n_ca, eps_c = 1 - exp(-UA_ca / (m_ca c_p)).
    """
    m_ca = config.m_ca_fan + config.k_ram * v_veh
    cp = config.c_p_air
    UA_ca = config.UA_ca0 * (m_ca / config.m_ca_fan) ** config.n_ca
    return m_ca * cp * (1.0 - math.exp(-UA_ca / (m_ca * cp)))


def steady_cycle(N: float, T_evap_wall: float, v_veh: float = 0.0,
                 config: PlantConfig | None = None, T_amb: float | None = None):
    """Cycle at steady condenser wall: fixed N (rpm), T_ew (K), speed (m/s) and ambient (K).

    Solves ``cycle`` together with the condenser wall balance Q_c = G_ca (T_cw - T_amb)
    (fixed-point iteration on T_cw). Returns ``(CycleResult, T_cw)``.
    """
    from acid.plant.cycle import cycle

    config = config or PlantConfig()
    T_amb = config.T_amb if T_amb is None else float(T_amb)
    G_ca = condenser_air_conductance(config, v_veh)
    T_cw, res = T_amb + 5.0, None
    for _ in range(200):
        res = cycle(N, T_evap_wall, T_cw, config,
                    guess=None if res is None or N <= 0 else (res.T_e, res.T_c))
        T_new = T_amb + res.Q_c / G_ca
        if abs(T_new - T_cw) < 1e-7:
            break
        T_cw = 0.5 * (T_cw + T_new)
    return res, T_cw


class HifiPlant(Plant):
    """High-fidelity A/C + cabin plant (quasi-static cycle, dynamic thermal masses).

    Parameters
    ----------
    config : plant configuration; ``PlantConfig()`` (the documented calibration) by default.
    mode : "direct": W_bl and T_evap_set are commanded, only the compressor PI runs inside
        (excitation, MPC); "nominal": the paper's nominal controller sets both (blower PI on
        the cabin set-point ``config.T_cab_set``, compressor PI on ``config.T_ew_set``) and
        the inputs given to ``step`` are ignored.
    meas_noise_std : std of white noise added to the recorded T_cab, T_evap, T_ain, K.
    rng : random generator for the noise (seed it for reproducible data).

    Notes
    -----
    Deterministic without noise. Blower flows outside [W_bl_min, W_bl_max] are clipped; the
    applied flow is recorded in ``W_bl``.
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
        self._comp = CompressorLoop(self.cfg)
        self._blower = BlowerLoop(self.cfg)
        self.n_sub = int(round(self.Ts / self.cfg.dt_int))
        self.reset()

    # ------------------------------------------------------------------ protocol
    def config(self) -> dict:
        d = self.cfg.to_dict()
        d.update(mode=self.mode, meas_noise_std_K=self.meas_noise_std)
        return d

    def reset(self, initial: dict[str, float] | None = None) -> Measurement:
        """Reset to the hot soak of the configuration, overridden by ``initial`` (K).

        Keys: T_cab, T_int, T_shell, T_evap (evaporator wall), T_cw (condenser wall),
        w_cab (kg/kg). The compressor starts on (from rest), both PI integrators at their
        minimum outputs.
        """
        c = self.cfg
        init = {"T_cab": c.T_cab0, "T_int": c.T_int0, "T_shell": c.T_shell0,
                "T_evap": c.T_ew0, "T_cw": c.T_cw0}
        for key, value in (initial or {}).items():
            if key not in INITIAL_KEYS:
                raise ConfigError(f"initial condition {key!r} unknown "
                                  f"(known: {', '.join(INITIAL_KEYS)})")
            value = float(value)
            if key != "w_cab" and not 200.0 < value < 400.0:
                raise ConfigError(f"initial {key} = {value} K is implausible "
                                  "(temperatures are in kelvin)")
            init[key] = value
        self.T_cab, self.T_int, self.T_shell = init["T_cab"], init["T_int"], init["T_shell"]
        self.T_ew, self.T_cw = init["T_evap"], init["T_cw"]
        self.w_cab = init.get("w_cab", humidity_ratio(self.T_cab, c.RH_cab0, c.p_atm))
        self.T_amb = c.T_amb
        self.w_amb = humidity_ratio(c.T_amb, c.RH_amb, c.p_atm)
        self.N = 0.0
        self.T_e, self.T_c = self.T_ew - 5.0, self.T_cw + 5.0
        self._comp.reset()
        self._blower.reset()
        self.t = 0.0
        return self.measure()

    def measure(self) -> Measurement:
        """Current states (K; w_cab in kg/kg): cabin, evaporator and condenser walls, masses."""
        return {"T_cab": self.T_cab, "T_evap": self.T_ew, "T_int": self.T_int,
                "T_shell": self.T_shell, "T_amb": self.T_amb, "w_cab": self.w_cab,
                "T_cw": self.T_cw}

    def step(self, W_bl: float, T_evap_set: float, v_veh: float = 0.0, **kw) -> Measurement:
        """Advance one sample period Ts (see the module docstring for the model).

        Parameters
        ----------
        W_bl : blower flow, kg/s (direct mode; ignored in nominal mode).
        T_evap_set : evaporator wall set-point, K (direct mode; nominal uses
            ``config.T_ew_set``).
        v_veh : vehicle speed, m/s, held over the step.
        T_cab_set : (keyword, nominal mode) cabin set-point, K; default ``config.T_cab_set``.
        compressor_enabled : (keyword) False forces the compressor off (open-loop shut-off).
        T_amb : (keyword) ambient temperature over this step, K (default: the configured
            ``T_amb``); the ambient humidity ratio follows it at the configured ``RH_amb``.
        T_int, T_shell : accepted and ignored (this plant computes its own).

        Returns
        -------
        Row k: states at t_k (T_cab, T_evap = evaporator wall T_ew, T_int, T_shell, T_cw, K;
        w_cab, kg/kg), T_amb (K), the applied inputs (W_bl mean, kg/s; T_evap_set, K; v_veh,
        m/s) and means over the step: T_ain, T_e, T_c (K), N_comp (rpm), P_comp, P_bl
        (paper eq. 5), P_fan, Q_evap, Q_cond, Q_lat (W), COP = Q_evap / P_comp (0 while the
        compressor stands still), recirc (fraction), ac_on (fraction of the step the A/C
        logic was on).
        """
        for key in kw:
            if key not in _STEP_KEYWORDS:
                raise ConfigError(f"HifiPlant.step: unknown keyword {key!r}")
        c = self.cfg
        nominal = self.mode == "nominal"
        enabled = bool(kw.get("compressor_enabled", True))
        T_cab_set = float(kw.get("T_cab_set", c.T_cab_set))
        T_set = c.T_ew_set if nominal else float(T_evap_set)
        v = float(v_veh)
        if "T_amb" in kw:
            T_amb_k = float(kw["T_amb"])
            if not 230.0 < T_amb_k < 330.0:
                raise ConfigError(f"ambient temperature T_amb = {kw['T_amb']} K is implausible "
                                  "(kelvin, -43 to 57 degC)")
            if T_amb_k != self.T_amb:
                self.T_amb = T_amb_k
                self.w_amb = humidity_ratio(T_amb_k, c.RH_amb, c.p_atm)
        if not (math.isfinite(v) and v >= 0.0):
            raise ConfigError(f"vehicle speed must be a finite non-negative number, got {v_veh}")
        if not nominal:
            W_cmd = float(W_bl)
            if not math.isfinite(W_cmd) or not math.isfinite(T_set):
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
        G_ca = condenser_air_conductance(c, v)  # eps_c m_ca c_p, W/K
        a_cw = math.exp(-G_ca * dt / c.C_cw)
        hA_ext = c.hA_ext0 + c.hA_ext_v * v ** 0.8
        hA_int, hA_sh, C_cab = c.hA_int, c.hA_sh, c.C_cab
        M_cab = C_cab / cp
        k_int, k_sh = dt / c.C_int, dt / c.C_sh
        Q_si, Q_ss, Q_pass, m_moist = c.Q_solar_int, c.Q_solar_shell, c.Q_pass, c.m_moist_pass
        UA_ea0, W_ea0, n_ea, C_ew, h_fg = c.UA_ea0, c.W_ea0, c.n_ea, c.C_ew, c.h_fg
        b1, b2, b3 = c.beta1, c.beta2, c.beta3
        k_rec, r_max = c.k_rec, c.r_max
        a_N = math.exp(-dt / c.tau_N)
        solve = self._solve
        comp, blower = self._comp, self._blower
        exp = math.exp

        T_cab, T_int, T_sh = self.T_cab, self.T_int, self.T_shell
        T_ew, T_cw, w_cab, N = self.T_ew, self.T_cw, self.w_cab, self.N
        T_e, T_c = self.T_e, self.T_c
        W_prev, eps = -1.0, 0.0
        s_W = s_Pbl = s_Pc = s_Qe = s_Qc = s_Qlat = s_Tain = s_N = s_r = s_Te = s_Tc = 0.0
        s_on = 0.0

        for _ in range(n):
            # controllers (continuous-time emulation at the internal step)
            W = blower.update(T_cab, T_cab_set, dt) if nominal else W_cmd
            N_cmd = comp.update(T_ew, T_set, dt, enabled)
            N = N_cmd + (N - N_cmd) * a_N
            if N < 1.0 and N_cmd == 0.0:
                N = 0.0
            # air mixing: controller.recirculation, inlined for speed
            r = k_rec * (T_amb - T_cab)
            r = 0.0 if r < 0.0 else (r_max if r > r_max else r)
            T_mix = T_amb + r * (T_cab - T_amb)
            w_mix = w_amb + r * (w_cab - w_amb)
            # evaporator air side, epsilon-NTU
            Wcp = W * cp
            if W != W_prev:
                eps = 1.0 - exp(-UA_ea0 * (W / W_ea0) ** n_ea / Wcp)
                W_prev = W
            G_a = eps * Wcp
            T_ain = T_mix - eps * (T_mix - T_ew)
            t_ew = T_ew - 273.15
            p_ws = 611.2 * exp(17.62 * t_ew / (243.12 + t_ew))
            w_sat = 0.621945 * p_ws / (p_atm - p_ws)
            if w_mix > w_sat:
                w_ain = w_mix - eps * (w_mix - w_sat)
                Q_lat = W * (w_mix - w_ain) * h_fg
            else:
                w_ain, Q_lat = w_mix, 0.0
            # refrigerant cycle (quasi-static)
            if N > 0.0:
                T_e, T_c, _m, Q_e, Q_c, P_c, _it = solve(N, T_ew, T_cw, T_e, T_c)
            else:
                T_e, T_c, Q_e, Q_c, P_c = T_ew, T_cw, 0.0, 0.0, 0.0
            # accumulate means over the sample
            s_W += W
            s_Pbl += (b1 * W + b2) * W + b3
            s_Pc += P_c
            s_Qe += Q_e
            s_Qc += Q_c
            s_Qlat += Q_lat
            s_Tain += T_ain
            s_N += N
            s_r += r
            s_Te += T_e
            s_Tc += T_c
            s_on += comp.on
            # thermal masses (exponential Euler on each node's own term)
            Tinf = T_mix + (Q_lat - Q_e) / G_a
            T_ew_n = Tinf + (T_ew - Tinf) * exp(-G_a * dt / C_ew)
            Tinf = T_amb + Q_c / G_ca
            T_cw = Tinf + (T_cw - Tinf) * a_cw
            G = hA_int + hA_sh + Wcp
            Tinf = (hA_int * T_int + hA_sh * T_sh + Wcp * T_ain + Q_pass) / G
            T_cab_n = Tinf + (T_cab - Tinf) * exp(-G * dt / C_cab)
            T_int += k_int * (Q_si + hA_int * (T_cab - T_int))
            T_sh += k_sh * (Q_ss + hA_ext * (T_amb - T_sh) + hA_sh * (T_cab - T_sh))
            winf = w_ain + m_moist / W
            w_cab = winf + (w_cab - winf) * exp(-W * dt / M_cab)
            T_ew, T_cab = T_ew_n, T_cab_n

        self.T_cab, self.T_int, self.T_shell = T_cab, T_int, T_sh
        self.T_ew, self.T_cw, self.w_cab, self.N = T_ew, T_cw, w_cab, N
        self.T_e, self.T_c = T_e, T_c
        self.t += n * dt

        inv = 1.0 / n
        P_comp = s_Pc * inv
        Q_evap = s_Qe * inv
        row.update(
            T_ain=s_Tain * inv, W_bl=s_W * inv, T_evap_set=T_set, v_veh=v,
            N_comp=s_N * inv, P_comp=P_comp, P_bl=s_Pbl * inv, P_fan=c.P_fan,
            COP=Q_evap / P_comp if P_comp > 0.0 else 0.0, recirc=s_r * inv,
            Q_evap=Q_evap, Q_cond=s_Qc * inv, Q_lat=s_Qlat * inv,
            T_e=s_Te * inv, T_c=s_Tc * inv, ac_on=s_on * inv,
        )
        if self.meas_noise_std:
            e = self.rng.standard_normal(3) * self.meas_noise_std
            row["T_cab"] += e[0]
            row["T_evap"] += e[1]
            row["T_ain"] += e[2]
        return row
