"""The heating plant: coolant heater, heat pump with frost and defrost, windscreen
fogging and a production heating controller, on the cooling plant's cabin.

Air path (blower flow W, recirculated fraction r):

* mixing as the cooling plant: T_mix = T_amb + r (T_cab - T_amb) + f_bl_heat P_bl / (W c_p),
  w_mix = w_amb + r (w_cab - w_amb); the A/C evaporator is idle (no latent load in winter);
* **inner condenser** (heat pump): epsilon-NTU against its wall, UA_ic = UA_ic0 (W/W_hc0)^n_hc,
  C_icw dT_icw/dt = Q_c - eps_ic W c_p (T_icw - T_mix), T_a1 = T_mix + eps_ic (T_icw - T_mix);
* **heater core** (coolant loop), downstream: the coolant capacity rate (m_cool c_cool about
  610 W/K) is 4-12 times the air's, so the core is taken at the heater outlet temperature
  T_hc = T_cool + eta P_h / (m_cool c_cool): Q_hc = eps_hc W c_p (T_hc - T_a1),
  T_sup = T_a1 + Q_hc / (W c_p) (the supply air into the cabin, reported as ``T_ain``);
* coolant: C_cool dT_cool/dt = eta_heater P_heater - Q_hc - UA_cool_loss (T_cool - T_amb).

Heat pump: the cooling plant's quasi-static cycle (``acid.plant.cycle.make_solver``) with the
front heat exchanger as evaporator (its wall T_ow against the ambient air through the front
end of ``acid.plant.hifi.front_end``) and the inner condenser as condenser:
C_ow dT_ow/dt = G_oa (T_amb - T_ow) + m_frost h_sg - Q_e. **Frost** grows while the coil is
below 0 degC and the ambient air is wetter than saturation over ice at the coil (Lewis
analogy: m_frost = G_oa / c_p (w_amb - w_sat,ice(T_ow))) and chokes the air side,
G_oa = G_oa0 (1 - a_frost M / M_frost_def). At M_frost_def the unit **defrosts** (hot gas,
P_defrost into the coil, no heat to the cabin) until the coil is ice-free and above
T_defrost_end. Below T_hp_min the heat pump is off.

Cabin: the cooling plant's cabin air, fast and slow interior, shell and water balance
(``PlantConfig``'s parameters, same equations as ``acid.plant.hifi``) with a **winter
envelope**: the air-to-shell conductance ``shell_conductance`` puts the trim and insulation
``R_trim`` behind the inner film of the opaque skin (the summer shell is the film alone), and
the windscreen is split off the shell as a **glass node**:
C_ws dT_gl/dt = h_ws_in A_ws (T_loc - T_gl) + hA_ext(v) A_ws/A_shell (T_amb - T_gl), where
the air at the glass T_loc = T_cab + f_def (T_sup - T_cab) carries the defrost-outlet share
f_def of the supply air. The glass fogs when T_gl is below the cabin dew point.

Production controller (``mode="nominal"``): supply-air target from a PI on the cabin error;
blower rising with the cabin error, held low until a heat source is warm (cold-air
prevention); heat pump (speed PI on the inner-condenser outlet air) first, the coolant heater
(PI on a coolant target = supply target + dT_approach) when the heat pump is unavailable
(cold, defrost, not fitted) or saturated; recirculation r_max unless the glass nears the dew
point, then fresh air and the defrost outlets (anti-fog override).

Integration as in ``acid.plant.hifi``: exponential Euler on the fast nodes (cabin air, both
heat-exchanger walls, cabin water), forward Euler on the others, internal step ``dt_int``.
``HeatingPlant.balance()`` closes the coolant loop, the air path and the cabin. Temperatures in
K, powers in W; rows follow ``acid.plant.base`` (states at t_k, means over the step).
"""

from __future__ import annotations

import math

from acid.errors import ConfigError
from acid.plant.base import (
    Measurement,
    Plant,
    balance_table,
    checked_ambient,
    validated_initial,
)
from acid.plant.config import PlantConfig
from acid.plant.cycle import make_solver
from acid.plant.heating_config import HeatingConfig, winter_plant_config
from acid.plant.hifi import FAN_LEVELS, front_end, humidity_ratio

MODES = ("direct", "nominal")

T0C = 273.15

#: Dynamic states: keys of ``HeatingPlant.measure()`` accepted by ``reset(initial=...)``.
INITIAL_KEYS = ("T_cab", "T_int", "T_int_slow", "T_shell", "T_glass", "w_cab", "T_cool",
                "T_icw", "T_ow", "M_frost", "N_comp_state", "defrost", "t_defrost",
                "sup_integrator", "heater_integrator", "hp_integrator", "T_a1_last")

UNITS = {"T_glass": "K", "T_cool": "K", "T_icw": "K", "T_ow": "K", "M_frost": "kg",
         "N_comp_state": "rpm", "defrost": "1", "t_defrost": "s", "sup_integrator": "K",
         "heater_integrator": "W", "hp_integrator": "rpm", "T_a1_last": "K",
         "T_sup_target": "K", "T_hp_out": "K", "T_dew": "K", "fog_margin": "K", "fog": "1",
         "defrosting": "1", "P_heater": "W", "Q_heater": "W", "Q_cool_loss": "W", "Q_hc": "W",
         "Q_cond": "W", "Q_evap": "W", "Q_sup": "W", "COP_hp": "1", "f_def": "1", "m_frost": "kg/s",
         "P_total": "W", "recirc": "1"}

_STEP_KEYWORDS = ("T_cab_set", "P_heater", "N_hp", "recirc", "f_def", "pump", "T_amb",
                  "T_int", "T_shell")


def dew_point(w: float, p_atm: float = 101325.0) -> float:
    """Dew point (K) of moist air with humidity ratio ``w`` (kg/kg): the inverse of the Magnus
    formula of ``acid.plant.hifi.humidity_ratio`` (over water)."""
    p_w = w * p_atm / (0.621945 + w)
    x = math.log(max(p_w, 1e-3) / 611.2)
    return T0C + 243.12 * x / (17.62 - x)


def saturation_humidity_ratio_ice(T: float, p_atm: float = 101325.0) -> float:
    """Humidity ratio of air saturated over ice at T (K): Magnus over ice (WMO 2008, Sonntag
    constants 22.46 / 272.62 degC)."""
    t = T - T0C
    p = 611.2 * math.exp(22.46 * t / (272.62 + t))
    return 0.621945 * p / (p_atm - p)


def shell_conductance(cfg: PlantConfig, hc: HeatingConfig) -> float:
    """Winter conductance from the cabin air to the shell node (W/K), windshield excluded.

    The inner film coefficient is the cooling plant's, h_in = hA_sh / A_shell (the paper's
    gamma2 over the shell area); the glazing besides the windshield (A_glass - A_ws) has the
    film alone, the opaque skin (A_shell - A_glass) the film in series with its trim and
    insulation R_trim: hA = h_in (A_glass - A_ws) + 1 / (1 / (h_in A_op) + R_trim / A_op).
    """
    A_op = cfg.A_shell - hc.A_glass
    if A_op <= 0.0:
        raise ConfigError(f"HeatingConfig: A_glass = {hc.A_glass} m^2 must be smaller than "
                          f"PlantConfig.A_shell = {cfg.A_shell} m^2")
    h_in = cfg.hA_sh / cfg.A_shell
    return h_in * (hc.A_glass - hc.A_ws) + 1.0 / (1.0 / (h_in * A_op) + hc.R_trim / A_op)


def _sat(x: float, lo: float, hi: float) -> float:
    return lo if x < lo else (hi if x > hi else x)


class HeatingPlant(Plant):
    """Cabin heating with a coolant heater and a heat pump (module docstring).

    Parameters
    ----------
    heating : ``HeatingConfig`` (default: the logged i3's heater, a heat pump fitted).
    config : the cooling plant's ``PlantConfig`` for cabin, compressor and refrigerant;
        default ``winter_plant_config()`` (5 degC, 80 % RH, no sun).
    mode : "nominal" (the production controller) or "direct" (inputs commanded: ``W_bl`` and
        the keywords ``P_heater`` W, ``N_hp`` rpm, ``recirc`` and ``f_def`` fractions).
    """

    name = "heating"

    def __init__(self, heating: HeatingConfig | None = None, config: PlantConfig | None = None,
                 mode: str = "nominal"):
        if mode not in MODES:
            raise ConfigError(f"HeatingPlant: mode must be one of {MODES}, got {mode!r}")
        self.hc = heating or HeatingConfig()
        self.cfg = config or winter_plant_config()
        self.mode = mode
        self.Ts = self.cfg.Ts
        self.n_sub = int(round(self.cfg.Ts / self.cfg.dt_int))
        # the heat pump's cycle: front heat exchanger as evaporator, inner condenser as condenser
        self.cycle_cfg = self.cfg.replace(UA_er0=self.hc.UA_or0, UA_cr0=self.hc.UA_icr0,
                                          k_is=self.hc.k_is_hp)
        self._solve, _ = make_solver(self.cycle_cfg)
        self._fe_cache: dict = {}
        self.hA_sh_in = shell_conductance(self.cfg, self.hc)
        self.reset()

    # ------------------------------------------------------------------ protocol
    def config(self) -> dict:
        return {"plant_config": self.cfg.to_dict(), "heating_config": self.hc.to_dict(),
                "mode": self.mode}

    def units(self) -> dict[str, str]:
        return dict(UNITS)

    def reset(self, initial: dict[str, float] | None = None) -> Measurement:
        """Reset; by default a cold soak (every node at the configured ambient, no frost)."""
        c = self.cfg
        T = c.T_amb
        init = {"T_cab": T, "T_int": T, "T_int_slow": T, "T_shell": T, "T_glass": T,
                "T_cool": T, "T_icw": T, "T_ow": T}
        init.update(validated_initial(initial, INITIAL_KEYS))
        self.T_amb = T
        self.w_amb = humidity_ratio(T, c.RH_amb, c.p_atm)
        self.T_cab, self.T_int, self.T_is = init["T_cab"], init["T_int"], init["T_int_slow"]
        self.T_sh, self.T_gl = init["T_shell"], init["T_glass"]
        self.T_cool, self.T_icw, self.T_ow = init["T_cool"], init["T_icw"], init["T_ow"]
        self.w_cab = init.get("w_cab", self.w_amb)
        self.M_fr = init.get("M_frost", 0.0)
        self.N = init.get("N_comp_state", 0.0)
        self.defrost = init.get("defrost", 0.0) >= 0.5
        self.t_def = init.get("t_defrost", 0.0)
        self.I_sup = init.get("sup_integrator", 0.0)
        self.I_h = init.get("heater_integrator", 0.0)
        self.I_hp = init.get("hp_integrator", 0.0)
        self.T_a1 = init.get("T_a1_last", self.T_cab)
        self.T_e, self.T_c = self.T_ow - 5.0, self.T_icw + 5.0
        self.p_c, self.cut = math.nan, False  # last head pressure (NaN: stood still)
        self.t = 0.0
        self._bal = [0.0] * 10
        self._U0 = self._stored()
        return self.measure()

    def measure(self) -> Measurement:
        """Every dynamic state (K; w_cab kg/kg; M_frost kg; controller states). ``T_evap`` is
        the heat pump's evaporator, the front heat exchanger's wall."""
        return {"T_cab": self.T_cab, "T_int": self.T_int, "T_int_slow": self.T_is,
                "T_shell": self.T_sh, "T_glass": self.T_gl, "T_amb": self.T_amb,
                "w_cab": self.w_cab, "T_cool": self.T_cool, "T_icw": self.T_icw,
                "T_ow": self.T_ow, "T_evap": self.T_ow, "M_frost": self.M_fr,
                "N_comp_state": self.N, "defrost": 1.0 if self.defrost else 0.0,
                "t_defrost": self.t_def, "sup_integrator": self.I_sup,
                "heater_integrator": self.I_h, "hp_integrator": self.I_hp,
                "T_a1_last": self.T_a1}

    # ------------------------------------------------------------------ balances
    def _stored(self) -> tuple[float, float, float, float]:
        """(U_coolant, U_inner_condenser_wall, U_cabin, U_outdoor_coil) in J from 0 K; the
        coil's ice counts -h_sf per kg (liquid water at 0 degC is the reference)."""
        c, h = self.cfg, self.hc
        f_ws = h.A_ws / c.A_shell
        return (h.C_cool * self.T_cool, h.C_icw * self.T_icw,
                c.C_cab * self.T_cab + c.C_int * self.T_int + c.C_int_slow * self.T_is
                + (c.C_sh * (1.0 - f_ws)) * self.T_sh + h.C_ws * self.T_gl,
                h.C_ow * self.T_ow - h.h_sf * self.M_fr)

    def balance(self) -> dict:
        """Energy balances since ``reset``: stored change against the integrated flows.

        ``coolant``: eta P_heater - Q_hc - loss; ``inner_condenser``: Q_c - Q to the air;
        ``air_path``: heat picked up by the supply air (blower, inner condenser, heater core)
        against W c_p (T_sup - T_mix) (stored 0, quasi-static); ``cabin``: air + interior +
        shell + glass against the supply air, infiltration, envelope, passengers and sun;
        ``outdoor_coil``: wall + frost against the ambient air, the vapour frozen on it
        (h_sg - h_sf per kg), the refrigerant's uptake and the defrost heat.
        Returns ``{name: {stored, inflow, residual, scale, relative}}`` (J).
        """
        U1 = self._stored()
        b = self._bal
        out = {"coolant": (U1[0] - self._U0[0], b[0], b[1]),
               "inner_condenser": (U1[1] - self._U0[1], b[2], b[3]),
               "air_path": (0.0, b[4], b[5]),
               "cabin": (U1[2] - self._U0[2], b[6], b[7]),
               "outdoor_coil": (U1[3] - self._U0[3], b[8], b[9])}
        return balance_table(out)

    def _front(self, v: float):
        key = (v, self.T_amb)
        fe = self._fe_cache.get(key)
        if fe is None:
            if len(self._fe_cache) > 256:
                self._fe_cache.clear()
            fe = self._fe_cache[key] = front_end(self.cfg, v, self.T_amb)
        return fe

    # ------------------------------------------------------------------ step
    def step(self, W_bl: float = 0.0, T_evap_set: float = 0.0, v_veh: float = 0.0,
             **kw) -> Measurement:
        """Advance one sample period (module docstring).

        Parameters
        ----------
        W_bl : blower flow, kg/s (direct mode; nominal mode sets its own).
        T_evap_set : ignored (the protocol's cooling input).
        v_veh : vehicle speed, m/s.
        T_cab_set : (keyword, nominal) cabin set-point, K; default ``HeatingConfig.T_heat_set``.
        P_heater, N_hp, recirc, f_def : (keywords, direct) heater electric power W, compressor
            speed rpm (0 = heat pump off), recirculated fraction, defrost-outlet share.
        pump : (keyword, direct) False stops the coolant pump (the car switched off): no heat
            from the heater core to the air, and the heater off with it; default True.
        T_amb : (keyword) ambient over this step, K.

        Returns
        -------
        Row k: the states at t_k (``measure()``) and means over the step: T_ain (supply
        air into the cabin), T_hp_out (after the inner condenser), T_sup_target, T_dew,
        fog_margin (glass minus dew point, K), fog (fraction of the step fogged), W_bl,
        recirc, f_def, N_comp, P_heater, P_comp, P_bl, P_fan, P_total (W), Q_heater (to the
        coolant), Q_cool_loss (coolant to the under-hood air), Q_hc (coolant to air), Q_cond,
        Q_evap (heat pump), Q_sup (supply air to the cabin, W c_p (T_sup - T_cab)), COP_hp
        (Q_cond / P_comp, 0 when off), m_frost (kg/s), defrosting (fraction).
        """
        for key in kw:
            if key not in _STEP_KEYWORDS:
                raise ConfigError(f"HeatingPlant.step: unknown keyword {key!r}")
        c, h = self.cfg, self.hc
        nominal = self.mode == "nominal"
        v = float(v_veh)
        if not (math.isfinite(v) and v >= 0.0):
            raise ConfigError(f"vehicle speed must be a finite non-negative number, got {v_veh}")
        if "T_amb" in kw:
            T_amb_k = checked_ambient(kw["T_amb"])
            if T_amb_k != self.T_amb:
                self.T_amb = T_amb_k
                self.w_amb = humidity_ratio(T_amb_k, c.RH_amb, c.p_atm)
        T_set = float(kw.get("T_cab_set", h.T_heat_set))
        pump = nominal or bool(kw.get("pump", True))
        if not nominal:
            cmd = {"W": float(W_bl), "P": float(kw.get("P_heater", 0.0)),
                   "N": float(kw.get("N_hp", 0.0)), "r": float(kw.get("recirc", 0.0)),
                   "f": float(kw.get("f_def", h.f_def0))}
            for k2, x in cmd.items():
                if not math.isfinite(x):
                    raise ConfigError(f"HeatingPlant.step: non-finite input {k2} = {x}")
            W_cmd = _sat(cmd["W"], c.W_bl_min, c.W_bl_max)
            P_cmd = _sat(cmd["P"], 0.0, h.P_heater_max) if pump else 0.0
            N_in = cmd["N"]
            N_cmd_d = 0.0 if N_in <= 0.0 else _sat(N_in, c.N_min, c.N_max)
            r_cmd = _sat(cmd["r"], 0.0, 1.0)
            f_cmd = _sat(cmd["f"], 0.0, 1.0)
        row = self.measure()

        dt, n, cp = c.dt_int, self.n_sub, c.c_p_air
        T_amb, w_amb, p_atm = self.T_amb, self.w_amb, c.p_atm
        fe = self._front(v)
        lev = int(round(h.s_fan_hp * FAN_LEVELS))
        G_oa_on, P_fan_on, G_oa_off = fe.G_ca[lev], fe.P_fan[lev], fe.G_ca[0]
        v_cab = v if c.cabin_speed else 0.0
        f_ws = h.A_ws / c.A_shell
        hA_ext = c.hA_ext(v_cab)
        hA_go, hA_ext_sh = hA_ext * f_ws, hA_ext * (1.0 - f_ws)
        hA_gi = h.h_ws_in * h.A_ws
        hA_sh = self.hA_sh_in
        C_sh = c.C_sh * (1.0 - f_ws)
        m_inf = c.m_inf0 + c.k_inf * v_cab
        Ginf = m_inf * cp
        M_cab = c.C_cab / cp
        Q_pass, m_moist = c.Q_pass * h.n_pass, c.m_moist_pass * h.n_pass
        Q_si, Q_ss = c.Q_solar_int, c.Q_solar_shell
        mcc = h.m_cool * h.c_cool
        W_min, W_max = c.W_bl_min, c.W_bl_max
        a_N = math.exp(-dt / c.tau_N)
        hp_avail = h.heat_pump and T_amb >= h.T_hp_min
        exp = math.exp

        T_cab, T_int, T_is, T_sh, T_gl = self.T_cab, self.T_int, self.T_is, self.T_sh, self.T_gl
        T_cool, T_icw, T_ow, w_cab, M_fr, N = (self.T_cool, self.T_icw, self.T_ow, self.w_cab,
                                               self.M_fr, self.N)
        T_e, T_c, T_a1_last = self.T_e, self.T_c, self.T_a1
        I_sup, I_h, I_hp = self.I_sup, self.I_h, self.I_hp
        defrost, t_def = self.defrost, self.t_def
        p_c, cut = self.p_c, self.cut
        k_der = (c.N_max - c.N_min) / (c.p_cut - c.p_derate)
        S = dict.fromkeys(("T_ain", "T_hp_out", "T_sup_target", "T_dew", "fog_margin", "fog",
                           "W_bl", "recirc", "f_def", "N_comp", "P_heater", "P_comp", "P_bl",
                           "P_fan", "Q_heater", "Q_cool_loss", "Q_hc", "Q_cond", "Q_evap",
                           "Q_sup", "m_frost",
                           "defrosting"), 0.0)
        B = [0.0] * 10

        for _ in range(n):
            T_dp = dew_point(w_cab, p_atm)
            margin = T_gl - T_dp
            hp_ok = hp_avail and not defrost
            # ---------------------------------------------------------- controls
            if nominal:
                e = T_set - T_cab
                u = T_set + h.Kp_sup * e + I_sup
                T_tgt = _sat(u, T_set, h.T_sup_max)
                if not ((u >= h.T_sup_max and e > 0.0) or (u <= T_set and e < 0.0)):
                    I_sup += h.Ki_sup * e * dt
                T_src = T_cool if T_cool > T_icw else T_icw
                W_dem = W_min + (W_max - W_min) * _sat(e / h.e_blower, 0.0, 1.0)
                W_cap = W_min + (W_max - W_min) * _sat((T_src - h.T_coldair) / 15.0, 0.0, 1.0)
                W = W_dem if W_dem < W_cap else W_cap
                x = _sat((margin - h.m_fog) / h.dm_fog, 0.0, 1.0) if h.anti_fog else 1.0
                r = c.r_max * x
                f_def = h.f_def_max - (h.f_def_max - h.f_def0) * x
                # heat pump first: speed PI on the inner-condenser outlet air
                if hp_ok:
                    e_hp = T_tgt - T_a1_last
                    u_hp = c.N_min + h.Kp_hp * e_hp + I_hp
                    if u_hp < c.N_min and e_hp < -h.dT_hp_off:
                        N_cmd, I_hp = 0.0, 0.0
                    else:
                        N_cmd = _sat(u_hp, c.N_min, c.N_max)
                        if not ((u_hp >= c.N_max and e_hp > 0.0)
                                or (u_hp <= c.N_min and e_hp < 0.0)):
                            I_hp += h.Ki_hp * e_hp * dt
                else:
                    N_cmd, I_hp = 0.0, 0.0
                # coolant heater: alone, or assisting a saturated heat pump
                need = (not hp_ok) or (N_cmd >= c.N_max and T_a1_last < T_tgt - h.dT_assist)
                if need and e > -1.0:
                    e_c = T_tgt + h.dT_approach - T_cool
                    u_h = h.Kp_heater * e_c + I_h
                    P_h = _sat(u_h, 0.0, h.P_heater_max)
                    if not ((u_h >= h.P_heater_max and e_c > 0.0) or (u_h <= 0.0 and e_c < 0.0)):
                        I_h += h.Ki_heater * e_c * dt
                else:
                    P_h, I_h = 0.0, 0.0
            else:
                W, P_h, r, f_def, T_tgt = W_cmd, P_cmd, r_cmd, f_cmd, T_set
                N_cmd = N_cmd_d if hp_ok else 0.0
            if p_c == p_c:  # head-pressure derate and cut-out (the cooling plant's limits)
                if p_c > c.p_cut:
                    cut = True
                elif cut and p_c < c.p_cut - 6.0e5:
                    cut = False
                if p_c > c.p_derate:
                    cap = c.N_max - k_der * (p_c - c.p_derate)
                    if N_cmd > cap:
                        N_cmd = cap if cap > c.N_min else c.N_min
            if cut:
                N_cmd = 0.0
            restart = N == 0.0
            N = N_cmd + (N - N_cmd) * a_N
            if N < 1.0 and N_cmd == 0.0:
                N = 0.0
            # ---------------------------------------------------------- air path
            P_bl = (c.beta1 * W + c.beta2) * W + c.beta3
            Wcp = W * cp
            Q_blh = c.f_bl_heat * P_bl
            T_mix = T_amb + r * (T_cab - T_amb) + Q_blh / Wcp
            wr = W / h.W_hc0
            eps_ic = 1.0 - exp(-h.UA_ic0 * wr ** h.n_hc / Wcp)
            eps_hc = 1.0 - exp(-h.UA_hc0 * wr ** h.n_hc / Wcp)
            G_ic = eps_ic * Wcp
            # ---------------------------------------------------------- heat pump cycle
            Q_def = P_def = 0.0
            if N > 0.0:
                # a restart after a defrost finds the outdoor coil (warmed by the defrost)
                # warmer than the inner condenser (cooled by the fresh air meanwhile): the
                # cycle's solver needs a lift, so the condenser side is taken at least 1 K
                # above the coil for the seconds until the wall warms past it; a restart
                # solves from the walls, not from the saturation temperatures of the last run
                T_cw = T_icw if T_icw > T_ow + 1.0 else T_ow + 1.0
                if restart:
                    T_e, T_c = T_ow - 3.0, T_cw + 3.0
                T_e, T_c, _m, Q_e, Q_c, P_c, _w, _ps, p_c, _it = self._solve(N, T_ow, T_cw,
                                                                             T_e, T_c)
                G_oa0, P_fan = G_oa_on, P_fan_on
            else:
                Q_e = Q_c = P_c = 0.0
                p_c = math.nan
                G_oa0, P_fan = G_oa_off, 0.0
                if defrost:
                    Q_def = P_def = h.P_defrost
            # inner condenser wall (exponential Euler)
            Tinf = T_mix + Q_c / G_ic
            T_icw_n = Tinf + (T_icw - Tinf) * exp(-G_ic * dt / h.C_icw)
            T_icw_m = 0.5 * (T_icw + T_icw_n)
            Q_ic = G_ic * (T_icw_m - T_mix)
            T_a1 = T_mix + Q_ic / Wcp
            # heater core at the heater outlet temperature; coolant node (forward Euler)
            Q_h = h.eta_heater * P_h
            T_hc = T_cool + Q_h / mcc
            # the pump runs while the heater heats or the coolant is warmer than the air
            Q_hc = (eps_hc * Wcp * (T_hc - T_a1) if pump and (Q_h > 0.0 or T_hc > T_a1)
                    else 0.0)
            T_sup = T_a1 + Q_hc / Wcp
            Q_loss = h.UA_cool_loss * (T_cool - T_amb)
            T_cool_n = T_cool + dt / h.C_cool * (Q_h - Q_hc - Q_loss)
            # ---------------------------------------------------------- outdoor coil + frost
            G_oa = G_oa0 * (1.0 - h.a_frost * (M_fr / h.M_frost_def if M_fr < h.M_frost_def
                                               else 1.0))
            m_fr = 0.0
            if T_ow < T0C:
                w_si = saturation_humidity_ratio_ice(T_ow, p_atm)
                if w_amb > w_si:
                    m_fr = G_oa / cp * (w_amb - w_si)
            Tinf = T_amb + (m_fr * h.h_sg - Q_e + Q_def) / G_oa
            T_ow_n = Tinf + (T_ow - Tinf) * exp(-G_oa * dt / h.C_ow)
            Q_oa = G_oa * (T_amb - 0.5 * (T_ow + T_ow_n))
            M_fr += m_fr * dt
            if M_fr > 0.0 and T_ow_n > T0C:  # the coil above 0 degC melts its frost first
                E = h.C_ow * (T_ow_n - (T_ow if T_ow > T0C else T0C))
                if E > 0.0:
                    melt = E / h.h_sf if E < M_fr * h.h_sf else M_fr
                    M_fr -= melt
                    T_ow_n -= melt * h.h_sf / h.C_ow
            # ---------------------------------------------------------- cabin
            Q_gl_sup = hA_gi * f_def  # glass sees T_loc = T_cab + f_def (T_sup - T_cab)
            G = c.hA_int + hA_sh + Wcp + Ginf + hA_gi * (1.0 - f_def)
            Tinf = (c.hA_int * T_int + hA_sh * T_sh + Wcp * T_sup + Ginf * T_amb + Q_pass
                    - Q_gl_sup * T_sup + hA_gi * T_gl) / G
            T_cab_n = Tinf + (T_cab - Tinf) * exp(-G * dt / c.C_cab)
            Tc_m = 0.5 * (T_cab + T_cab_n)
            Q_gl_in = hA_gi * (T_cab + f_def * (T_sup - T_cab) - T_gl)
            T_int_n = T_int + dt / c.C_int * (Q_si + c.hA_int * (T_cab - T_int)
                                              + c.hA_int_slow * (T_is - T_int))
            T_is_n = T_is + dt / c.C_int_slow * c.hA_int_slow * (T_int - T_is)
            Q_sh_out = hA_ext_sh * (T_amb - T_sh)
            T_sh_n = T_sh + dt / C_sh * (Q_ss + Q_sh_out + hA_sh * (T_cab - T_sh))
            Q_gl_out = hA_go * (T_amb - T_gl)
            T_gl_n = T_gl + dt / h.C_ws * (Q_gl_in + Q_gl_out)
            F = W * (1.0 - r) + m_inf
            winf = w_amb + m_moist / F
            w_cab = winf + (w_cab - winf) * exp(-F * dt / M_cab)
            # ---------------------------------------------------------- balances
            Q_sup = Wcp * (T_sup - Tc_m)
            B[0] += Q_h - Q_hc - Q_loss
            B[1] += Q_h + abs(Q_hc) + abs(Q_loss)
            B[2] += Q_c - Q_ic
            B[3] += Q_c + abs(Q_ic)
            B[4] += Q_blh + Q_ic + Q_hc - Wcp * (T_sup - T_amb - r * (T_cab - T_amb))
            B[5] += Q_blh + abs(Q_ic) + abs(Q_hc)
            ext = Q_sup + Ginf * (T_amb - Tc_m) + Q_pass + Q_si + Q_ss + Q_sh_out + Q_gl_out
            B[6] += ext
            B[7] += (abs(Q_sup) + abs(Ginf * (T_amb - Tc_m)) + Q_pass + Q_si + Q_ss
                     + abs(Q_sh_out) + abs(Q_gl_out))
            B[8] += Q_oa + m_fr * (h.h_sg - h.h_sf) - Q_e + Q_def
            B[9] += abs(Q_oa) + m_fr * h.h_sg + Q_e + Q_def
            # ---------------------------------------------------------- defrost logic
            if defrost:
                t_def += dt
                if (M_fr <= 0.0 and T_ow_n >= h.T_defrost_end) or t_def >= h.t_defrost_max:
                    defrost, t_def = False, 0.0
            elif N > 0.0 and M_fr >= h.M_frost_def:
                defrost, t_def, N, I_hp = True, 0.0, 0.0, 0.0
            T_cab, T_int, T_is, T_sh, T_gl = T_cab_n, T_int_n, T_is_n, T_sh_n, T_gl_n
            T_cool, T_icw, T_ow = T_cool_n, T_icw_n, T_ow_n
            T_a1_last = T_a1
            # ---------------------------------------------------------- means
            S["T_ain"] += T_sup
            S["T_hp_out"] += T_a1
            S["T_sup_target"] += T_tgt
            S["T_dew"] += T_dp
            S["fog_margin"] += margin
            S["fog"] += 1.0 if margin < 0.0 else 0.0
            S["W_bl"] += W
            S["recirc"] += r
            S["f_def"] += f_def
            S["N_comp"] += N
            S["P_heater"] += P_h
            S["P_comp"] += P_c + P_def
            S["P_bl"] += P_bl
            S["P_fan"] += P_fan
            S["Q_heater"] += Q_h
            S["Q_hc"] += Q_hc
            S["Q_cool_loss"] += Q_loss
            S["Q_cond"] += Q_c
            S["Q_evap"] += Q_e
            S["Q_sup"] += Q_sup
            S["m_frost"] += m_fr
            S["defrosting"] += 1.0 if defrost else 0.0

        self.T_cab, self.T_int, self.T_is, self.T_sh, self.T_gl = T_cab, T_int, T_is, T_sh, T_gl
        self.T_cool, self.T_icw, self.T_ow, self.w_cab = T_cool, T_icw, T_ow, w_cab
        self.M_fr, self.N, self.T_e, self.T_c, self.T_a1 = M_fr, N, T_e, T_c, T_a1_last
        self.I_sup, self.I_h, self.I_hp = I_sup, I_h, I_hp
        self.defrost, self.t_def = defrost, t_def
        self.p_c, self.cut = p_c, cut
        self.t += n * dt
        for i in range(10):
            self._bal[i] += B[i] * dt

        inv = 1.0 / n
        means = {k: s * inv for k, s in S.items()}
        P_comp = means["P_comp"]
        means["COP_hp"] = means["Q_cond"] / P_comp if P_comp > 0.0 else 0.0
        means["P_total"] = P_comp + means["P_heater"] + means["P_bl"] + means["P_fan"]
        row.update(means)
        row["v_veh"] = v
        return row
