"""The heating plant stepped for B scenarios at once (numpy arrays of shape (B,)).

``BatchHeatingPlant`` runs the model of ``acid.plant.heating.HeatingPlant`` (same equations,
same operation order) for B members that may differ in their heating configuration (heat pump
fitted or not, heater, controller, frost and defrost parameters), their cabin and compressor
configuration (the shipped vehicles), their ambient, initial state, inputs and length. Every
branch of the single plant (controllers of ``mode="nominal"``, cold-air prevention, anti-fog,
heat pump or coolant heater, head-pressure derate and cut-out, frost growth, melting and the
defrost cycle) is taken per member with ``numpy.where``; the heat pump's cycle is solved by
``BatchCycle`` (the Newton iteration of ``acid.plant.cycle.make_solver`` on arrays, each
member with its own iterations and its own suction-drop warm start) on the members whose
compressor runs, and the front heat exchanger's air flow comes from the cooling batch's
vectorised front end.

Members must share the refrigerant tables and the time steps (``Ts``, ``dt_int``). The energy
balances (``HeatingPlant.balance``) are not accumulated. The trajectories equal the single
plant's to rounding (numpy's ``exp``, ``log`` and ``**`` may differ from ``math``'s by an
ulp); ``tests/test_plant_batch_heating.py`` checks 1e-9 K and a relative 1e-9 on the rest.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from acid.errors import ConfigError
from acid.plant.base import checked_ambient
from acid.plant.batch.plant import BatchCycle, BatchMembers, check_shared
from acid.plant.config import PlantConfig
from acid.plant.heating import MODES, T0C, HeatingPlant, shell_conductance
from acid.plant.heating_config import HeatingConfig, winter_plant_config
from acid.plant.hifi import FAN_LEVELS, humidity_ratio

#: the direct-mode inputs (``HeatingPlant.step``'s keywords) and their defaults
DIRECT_INPUTS = ("P_heater", "N_hp", "recirc", "f_def", "pump")

#: the mean channels of a row (``HeatingPlant.step``), in its order
_MEANS = ("T_ain", "T_hp_out", "T_sup_target", "T_dew", "fog_margin", "fog", "W_bl", "recirc",
          "f_def", "N_comp", "P_heater", "P_comp", "P_bl", "P_fan", "Q_heater", "Q_cool_loss",
          "Q_hc", "Q_cond", "Q_evap", "Q_sup", "m_frost", "defrosting")


def _sat(x, lo, hi):
    return np.where(x < lo, lo, np.where(x > hi, hi, x))


def _members(x, B: int, kind: str) -> list:
    if x is None or not isinstance(x, Sequence):
        return [x] * B
    x = list(x)
    if len(x) != B:
        raise ConfigError(f"{len(x)} {kind} for {B} batch members")
    return x


class BatchHeatingPlant(BatchMembers):
    """B heating plants stepped together; see the module docstring.

    Parameters
    ----------
    heatings : one ``HeatingConfig`` per member, or one for all (default ``HeatingConfig()``).
    configs : one ``PlantConfig`` per member, or one for all (default
        ``winter_plant_config()``).
    mode : "nominal" or "direct", for every member (as ``HeatingPlant``).
    size : number of members when neither ``heatings`` nor ``configs`` is a list.
    """

    name = "heating"

    def __init__(self, heatings: Sequence[HeatingConfig] | HeatingConfig | None = None,
                 configs: Sequence[PlantConfig] | PlantConfig | None = None,
                 mode: str = "nominal", size: int | None = None):
        if mode not in MODES:
            raise ConfigError(f"BatchHeatingPlant: mode must be one of {MODES}, got {mode!r}")
        B = next((len(x) for x in (heatings, configs) if isinstance(x, Sequence)),
                 int(size or 1))
        self.hcs = [h or HeatingConfig() for h in _members(heatings, B, "heating configs")]
        self.cfgs = [c or winter_plant_config() for c in _members(configs, B, "plant configs")]
        if B < 1:
            raise ConfigError("a batch plant needs at least one member")
        check_shared(self.cfgs)
        self.B, self.mode = B, mode
        c0 = self.cfgs[0]
        self.Ts = float(c0.Ts)
        self.n_sub = int(round(self.Ts / c0.dt_int))
        # each member's heat-pump cycle, as HeatingPlant builds it
        self._cyc = BatchCycle([c.replace(UA_er0=h.UA_or0, UA_cr0=h.UA_icr0, k_is=h.k_is_hp)
                                for c, h in zip(self.cfgs, self.hcs, strict=True)])
        self._arrays: dict = {}
        self._harrays: dict = {}
        self._ft = None
        self._hA_cache: dict = {}
        self._fe_speed = np.array([bool(c.front_end_speed) for c in self.cfgs], bool)
        self._cabin_speed = np.array([bool(c.cabin_speed) for c in self.cfgs], bool)
        self._hp = np.array([bool(h.heat_pump) for h in self.hcs], bool)
        self._anti_fog = np.array([bool(h.anti_fog) for h in self.hcs], bool)
        self._a_N = np.array([math.exp(-c.dt_int / c.tau_N) for c in self.cfgs])
        self._hA_sh_in = np.array([shell_conductance(c, h)
                                   for c, h in zip(self.cfgs, self.hcs, strict=True)])
        self._lev = np.array([int(round(h.s_fan_hp * FAN_LEVELS)) for h in self.hcs])
        self.reset()

    def _h(self, name: str) -> np.ndarray:
        """The members' values of heating-configuration field ``name`` (cached; read-only)."""
        a = self._harrays.get(name)
        if a is None:
            a = self._harrays[name] = np.array([float(getattr(h, name)) for h in self.hcs])
            a.setflags(write=False)
        return a

    def reset(self, initial: Sequence[dict[str, float] | None] | None = None) -> dict:
        """Reset every member (as a new ``HeatingPlant``'s ``reset``): ``initial``, one dict
        (or None: a cold soak at the member's ambient) each."""
        initial = list(initial) if initial is not None else [None] * self.B
        if len(initial) != self.B:
            raise ConfigError(f"{len(initial)} initial states for {self.B} batch members")
        starts = []
        for h, c, init in zip(self.hcs, self.cfgs, initial, strict=True):
            p = HeatingPlant(h, c, mode=self.mode)  # validation and the start, its own
            p.reset(init)
            starts.append(p)
        g = lambda name: np.array([float(getattr(p, name)) for p in starts])  # noqa: E731
        self.T_amb, self.w_amb = g("T_amb"), g("w_amb")
        self.T_cab, self.T_int, self.T_is = g("T_cab"), g("T_int"), g("T_is")
        self.T_sh, self.T_gl, self.T_cool = g("T_sh"), g("T_gl"), g("T_cool")
        self.T_icw, self.T_ow, self.w_cab = g("T_icw"), g("T_ow"), g("w_cab")
        self.M_fr, self.N, self.t_def = g("M_fr"), g("N"), g("t_def")
        self.I_sup, self.I_h, self.I_hp, self.T_a1 = g("I_sup"), g("I_h"), g("I_hp"), g("T_a1")
        self.T_e, self.T_c, self.p_c = g("T_e"), g("T_c"), g("p_c")
        self.defrost = np.array([p.defrost for p in starts], bool)
        self.cut = np.array([p.cut for p in starts], bool)
        self.dTs = np.zeros(self.B)  # a new plant's solver starts without suction drop
        self.t = 0.0
        return self.measure()

    def measure(self) -> dict[str, np.ndarray]:
        """Every member's states, keyed as ``HeatingPlant.measure`` (arrays of shape (B,))."""
        return {"T_cab": self.T_cab.copy(), "T_int": self.T_int.copy(),
                "T_int_slow": self.T_is.copy(), "T_shell": self.T_sh.copy(),
                "T_glass": self.T_gl.copy(), "T_amb": self.T_amb.copy(),
                "w_cab": self.w_cab.copy(), "T_cool": self.T_cool.copy(),
                "T_icw": self.T_icw.copy(), "T_ow": self.T_ow.copy(),
                "T_evap": self.T_ow.copy(), "M_frost": self.M_fr.copy(),
                "N_comp_state": self.N.copy(), "defrost": self.defrost.astype(float),
                "t_defrost": self.t_def.copy(), "sup_integrator": self.I_sup.copy(),
                "heater_integrator": self.I_h.copy(), "hp_integrator": self.I_hp.copy(),
                "T_a1_last": self.T_a1.copy()}

    def step(self, W_bl=0.0, T_evap_set=0.0, v_veh=0.0, T_amb=None, T_cab_set=None,
             P_heater=0.0, N_hp=0.0, recirc=0.0, f_def=None, pump=True
             ) -> dict[str, np.ndarray]:
        """Advance every member one sample period (``HeatingPlant.step``, element by element).

        Inputs are arrays of shape (B,) (scalars broadcast): ``W_bl`` and the direct-mode
        ``P_heater``, ``N_hp``, ``recirc``, ``f_def`` (None: each member's ``f_def0``) and
        ``pump``; ``v_veh``; ``T_amb`` and ``T_cab_set`` (K, None: the member's own).
        ``T_evap_set`` is ignored (the protocol's cooling input). Returns row k as
        ``HeatingPlant.step`` does, each channel an array of shape (B,).
        """
        B = self.B
        A, H = self._a, self._h
        shape = (B,)
        nominal = self.mode == "nominal"
        bc = lambda x: np.broadcast_to(np.asarray(x, float), shape).copy()  # noqa: E731
        v = bc(v_veh)
        if not np.all(np.isfinite(v) & (v >= 0.0)):
            raise ConfigError(f"vehicle speed must be a finite non-negative number, got {v}")
        if T_amb is not None:
            T_amb = np.broadcast_to(np.asarray(T_amb, float), shape)
            for b in range(B):
                T_k = checked_ambient(T_amb[b])
                if T_k != self.T_amb[b]:
                    c = self.cfgs[b]
                    self.T_amb[b] = T_k
                    self.w_amb[b] = humidity_ratio(T_k, c.RH_amb, c.p_atm)
        T_set = H("T_heat_set") if T_cab_set is None else bc(T_cab_set)
        W_min, W_max = A("W_bl_min"), A("W_bl_max")
        N_min, N_max = A("N_min"), A("N_max")
        if nominal:
            pump_on = np.ones(shape, bool)
        else:
            pump_on = np.broadcast_to(np.asarray(pump, bool), shape).copy()
            cmd = {"W": bc(W_bl), "P": bc(P_heater), "N": bc(N_hp), "r": bc(recirc),
                   "f": H("f_def0") if f_def is None else bc(f_def)}
            for k2, x in cmd.items():
                if not np.all(np.isfinite(x)):
                    raise ConfigError(f"BatchHeatingPlant.step: non-finite input {k2}")
            W_cmd = _sat(cmd["W"], W_min, W_max)
            P_cmd = np.where(pump_on, _sat(cmd["P"], 0.0, H("P_heater_max")), 0.0)
            N_in = cmd["N"]
            N_cmd_d = np.where(N_in <= 0.0, 0.0, _sat(N_in, N_min, N_max))
            r_cmd = _sat(cmd["r"], 0.0, 1.0)
            f_cmd = _sat(cmd["f"], 0.0, 1.0)
        row = self.measure()

        cyc, rows_idx = self._cyc, np.arange(B)
        dt, n = self.cfgs[0].dt_int, self.n_sub
        cp, p_atm = A("c_p_air"), A("p_atm")
        T_amb, w_amb = self.T_amb, self.w_amb
        G_st, P_st = self._front_tables(v)[:2]
        lev = self._lev
        G_oa_on, P_fan_on, G_oa_off = G_st[rows_idx, lev], P_st[rows_idx, lev], G_st[:, 0]
        v_cab = np.where(self._cabin_speed, v, 0.0)
        f_ws = H("A_ws") / A("A_shell")
        hA_ext = self._hA_ext(v_cab)
        hA_go, hA_ext_sh = hA_ext * f_ws, hA_ext * (1.0 - f_ws)
        hA_gi = H("h_ws_in") * H("A_ws")
        hA_sh = self._hA_sh_in
        C_sh = A("C_sh") * (1.0 - f_ws)
        m_inf = A("m_inf0") + A("k_inf") * v_cab
        Ginf = m_inf * cp
        C_cab = A("C_cab")
        M_cab = C_cab / cp
        Q_pass, m_moist = A("Q_pass") * H("n_pass"), A("m_moist_pass") * H("n_pass")
        Q_si, Q_ss = A("Q_solar_int"), A("Q_solar_shell")
        mcc = H("m_cool") * H("c_cool")
        a_N = self._a_N
        hp_avail = self._hp & (T_amb >= H("T_hp_min"))
        p_cut, p_der = A("p_cut"), A("p_derate")
        k_der = (N_max - N_min) / (p_cut - p_der)
        hA_int, hA_is, C_int, C_is = A("hA_int"), A("hA_int_slow"), A("C_int"), A("C_int_slow")
        b1, b2, b3, f_bh, r_max = A("beta1"), A("beta2"), A("beta3"), A("f_bl_heat"), A("r_max")
        (Kp_sup, Ki_sup, T_sup_max, e_blower, T_coldair, m_fog, dm_fog, f_def_max, f_def0,
         Kp_hp, Ki_hp, dT_hp_off, dT_assist, dT_approach, Kp_heater, Ki_heater,
         P_heater_max) = (H(k) for k in (
             "Kp_sup", "Ki_sup", "T_sup_max", "e_blower", "T_coldair", "m_fog", "dm_fog",
             "f_def_max", "f_def0", "Kp_hp", "Ki_hp", "dT_hp_off", "dT_assist", "dT_approach",
             "Kp_heater", "Ki_heater", "P_heater_max"))
        (W_hc0, UA_ic0, UA_hc0, n_hc, C_icw, eta_h, UA_cl, C_cool, a_frost, M_def, h_sg, h_sf,
         C_ow, P_defrost, C_ws, T_def_end, t_def_max) = (H(k) for k in (
             "W_hc0", "UA_ic0", "UA_hc0", "n_hc", "C_icw", "eta_heater", "UA_cool_loss",
             "C_cool", "a_frost", "M_frost_def", "h_sg", "h_sf", "C_ow", "P_defrost", "C_ws",
             "T_defrost_end", "t_defrost_max"))
        exp = np.exp
        anti_fog = self._anti_fog

        T_cab, T_int, T_is, T_sh, T_gl = self.T_cab, self.T_int, self.T_is, self.T_sh, self.T_gl
        T_cool, T_icw, T_ow, w_cab, M_fr, N = (self.T_cool, self.T_icw, self.T_ow, self.w_cab,
                                               self.M_fr, self.N)
        T_e, T_c, T_a1_last = self.T_e.copy(), self.T_c.copy(), self.T_a1
        I_sup, I_h, I_hp = self.I_sup, self.I_h, self.I_hp
        defrost, t_def = self.defrost, self.t_def
        p_c, cut, dTs = self.p_c, self.cut, self.dTs.copy()
        S = {k: np.zeros(shape) for k in _MEANS}

        for _ in range(n):
            # dew point (inverse Magnus, as heating.dew_point)
            p_w = w_cab * p_atm / (0.621945 + w_cab)
            xl = np.log(np.where(p_w > 1e-3, p_w, 1e-3) / 611.2)
            T_dp = T0C + 243.12 * xl / (17.62 - xl)
            margin = T_gl - T_dp
            hp_ok = hp_avail & ~defrost
            # ---------------------------------------------------------- controls
            if nominal:
                e = T_set - T_cab
                u = T_set + Kp_sup * e + I_sup
                T_tgt = _sat(u, T_set, T_sup_max)
                hold = ((u >= T_sup_max) & (e > 0.0)) | ((u <= T_set) & (e < 0.0))
                I_sup = np.where(hold, I_sup, I_sup + Ki_sup * e * dt)
                T_src = np.where(T_cool > T_icw, T_cool, T_icw)
                W_dem = W_min + (W_max - W_min) * _sat(e / e_blower, 0.0, 1.0)
                W_cap = W_min + (W_max - W_min) * _sat((T_src - T_coldair) / 15.0, 0.0, 1.0)
                W = np.where(W_dem < W_cap, W_dem, W_cap)
                x = np.where(anti_fog, _sat((margin - m_fog) / dm_fog, 0.0, 1.0), 1.0)
                r = r_max * x
                f_d = f_def_max - (f_def_max - f_def0) * x
                # heat pump first: speed PI on the inner-condenser outlet air
                e_hp = T_tgt - T_a1_last
                u_hp = N_min + Kp_hp * e_hp + I_hp
                stop = (u_hp < N_min) & (e_hp < -dT_hp_off)
                go = hp_ok & ~stop
                N_cmd = np.where(go, _sat(u_hp, N_min, N_max), 0.0)
                hold = ((u_hp >= N_max) & (e_hp > 0.0)) | ((u_hp <= N_min) & (e_hp < 0.0))
                I_hp = np.where(go, np.where(hold, I_hp, I_hp + Ki_hp * e_hp * dt), 0.0)
                # coolant heater: alone, or assisting a saturated heat pump
                need = ~hp_ok | ((N_cmd >= N_max) & (T_a1_last < T_tgt - dT_assist))
                heat = need & (e > -1.0)
                e_c = T_tgt + dT_approach - T_cool
                u_h = Kp_heater * e_c + I_h
                P_h = np.where(heat, _sat(u_h, 0.0, P_heater_max), 0.0)
                hold = ((u_h >= P_heater_max) & (e_c > 0.0)) | ((u_h <= 0.0) & (e_c < 0.0))
                I_h = np.where(heat, np.where(hold, I_h, I_h + Ki_heater * e_c * dt), 0.0)
            else:
                W, P_h, r, f_d, T_tgt = W_cmd, P_cmd, r_cmd, f_cmd, T_set
                N_cmd = np.where(hp_ok, N_cmd_d, 0.0)
            # head-pressure derate and cut-out (the cooling plant's limits)
            ran = p_c == p_c
            cut = np.where(ran & (p_c > p_cut), True,
                           np.where(ran & cut & (p_c < p_cut - 6.0e5), False, cut))
            cap = N_max - k_der * (p_c - p_der)
            der = ran & (p_c > p_der) & (N_cmd > cap)
            N_cmd = np.where(der, np.where(cap > N_min, cap, N_min), N_cmd)
            N_cmd = np.where(cut, 0.0, N_cmd)
            restart = N == 0.0
            N = N_cmd + (N - N_cmd) * a_N
            N = np.where((N < 1.0) & (N_cmd == 0.0), 0.0, N)
            # ---------------------------------------------------------- air path
            P_bl = (b1 * W + b2) * W + b3
            Wcp = W * cp
            Q_blh = f_bh * P_bl
            T_mix = T_amb + r * (T_cab - T_amb) + Q_blh / Wcp
            wr = W / W_hc0
            eps_ic = 1.0 - exp(-UA_ic0 * wr ** n_hc / Wcp)
            eps_hc = 1.0 - exp(-UA_hc0 * wr ** n_hc / Wcp)
            G_ic = eps_ic * Wcp
            # ---------------------------------------------------------- heat pump cycle
            runs = N > 0.0
            Q_e, Q_c, P_c = np.zeros(shape), np.zeros(shape), np.zeros(shape)
            p_c = np.full(shape, math.nan)
            k = np.nonzero(runs)[0]
            if k.size:
                T_ow_k, T_icw_k = T_ow[k], T_icw[k]
                T_cw = np.where(T_icw_k > T_ow_k + 1.0, T_icw_k, T_ow_k + 1.0)
                rs = restart[k]
                te0 = np.where(rs, T_ow_k - 3.0, T_e[k])
                tc0 = np.where(rs, T_cw + 3.0, T_c[k])
                out = cyc.solve(N[k], T_ow_k, T_cw, te0, tc0, dTs[k], k)
                T_e[k], T_c[k], Q_e[k], Q_c[k], P_c[k], p_c[k], dTs[k] = (
                    out[0], out[1], out[3], out[4], out[5], out[8], out[9])
            G_oa0 = np.where(runs, G_oa_on, G_oa_off)
            P_fan = np.where(runs, P_fan_on, 0.0)
            Q_def = np.where(~runs & defrost, P_defrost, 0.0)
            # inner condenser wall (exponential Euler)
            Tinf = T_mix + Q_c / G_ic
            T_icw_n = Tinf + (T_icw - Tinf) * exp(-G_ic * dt / C_icw)
            T_icw_m = 0.5 * (T_icw + T_icw_n)
            Q_ic = G_ic * (T_icw_m - T_mix)
            T_a1 = T_mix + Q_ic / Wcp
            # heater core at the heater outlet temperature; coolant node (forward Euler)
            Q_h = eta_h * P_h
            T_hc = T_cool + Q_h / mcc
            Q_hc = np.where(pump_on & ((Q_h > 0.0) | (T_hc > T_a1)),
                            eps_hc * Wcp * (T_hc - T_a1), 0.0)
            T_sup = T_a1 + Q_hc / Wcp
            Q_loss = UA_cl * (T_cool - T_amb)
            T_cool_n = T_cool + dt / C_cool * (Q_h - Q_hc - Q_loss)
            # ---------------------------------------------------------- outdoor coil + frost
            G_oa = G_oa0 * (1.0 - a_frost * np.where(M_fr < M_def, M_fr / M_def, 1.0))
            t = np.where(T_ow < T0C, T_ow, T0C) - T0C  # saturation over ice at the coil
            p_i = 611.2 * exp(22.46 * t / (272.62 + t))
            w_si = 0.621945 * p_i / (p_atm - p_i)
            m_fr = np.where((T_ow < T0C) & (w_amb > w_si), G_oa / cp * (w_amb - w_si), 0.0)
            Tinf = T_amb + (m_fr * h_sg - Q_e + Q_def) / G_oa
            T_ow_n = Tinf + (T_ow - Tinf) * exp(-G_oa * dt / C_ow)
            M_fr = M_fr + m_fr * dt
            # the coil above 0 degC melts its frost first
            E = C_ow * (T_ow_n - np.where(T_ow > T0C, T_ow, T0C))
            melts = (M_fr > 0.0) & (T_ow_n > T0C) & (E > 0.0)
            if melts.any():
                melt = np.where(E < M_fr * h_sf, E / h_sf, M_fr)
                M_fr = np.where(melts, M_fr - melt, M_fr)
                T_ow_n = np.where(melts, T_ow_n - melt * h_sf / C_ow, T_ow_n)
            # ---------------------------------------------------------- cabin
            Q_gl_sup = hA_gi * f_d
            G = hA_int + hA_sh + Wcp + Ginf + hA_gi * (1.0 - f_d)
            Tinf = (hA_int * T_int + hA_sh * T_sh + Wcp * T_sup + Ginf * T_amb + Q_pass
                    - Q_gl_sup * T_sup + hA_gi * T_gl) / G
            T_cab_n = Tinf + (T_cab - Tinf) * exp(-G * dt / C_cab)
            Tc_m = 0.5 * (T_cab + T_cab_n)
            Q_gl_in = hA_gi * (T_cab + f_d * (T_sup - T_cab) - T_gl)
            T_int_n = T_int + dt / C_int * (Q_si + hA_int * (T_cab - T_int)
                                            + hA_is * (T_is - T_int))
            T_is_n = T_is + dt / C_is * hA_is * (T_int - T_is)
            Q_sh_out = hA_ext_sh * (T_amb - T_sh)
            T_sh_n = T_sh + dt / C_sh * (Q_ss + Q_sh_out + hA_sh * (T_cab - T_sh))
            Q_gl_out = hA_go * (T_amb - T_gl)
            T_gl_n = T_gl + dt / C_ws * (Q_gl_in + Q_gl_out)
            F = W * (1.0 - r) + m_inf
            winf = w_amb + m_moist / F
            w_cab = winf + (w_cab - winf) * exp(-F * dt / M_cab)
            Q_sup = Wcp * (T_sup - Tc_m)
            # ---------------------------------------------------------- defrost logic
            t_d = np.where(defrost, t_def + dt, t_def)
            end = defrost & (((M_fr <= 0.0) & (T_ow_n >= T_def_end)) | (t_d >= t_def_max))
            start = ~defrost & runs & (M_fr >= M_def)
            t_def = np.where(end | start, 0.0, t_d)
            defrost = (defrost & ~end) | start
            N = np.where(start, 0.0, N)
            I_hp = np.where(start, 0.0, I_hp)
            T_cab, T_int, T_is, T_sh, T_gl = T_cab_n, T_int_n, T_is_n, T_sh_n, T_gl_n
            T_cool, T_icw, T_ow = T_cool_n, T_icw_n, T_ow_n
            T_a1_last = T_a1
            # ---------------------------------------------------------- means
            S["T_ain"] += T_sup
            S["T_hp_out"] += T_a1
            S["T_sup_target"] += T_tgt
            S["T_dew"] += T_dp
            S["fog_margin"] += margin
            S["fog"] += margin < 0.0
            S["W_bl"] += W
            S["recirc"] += r
            S["f_def"] += f_d
            S["N_comp"] += N
            S["P_heater"] += P_h
            S["P_comp"] += P_c + Q_def
            S["P_bl"] += P_bl
            S["P_fan"] += P_fan
            S["Q_heater"] += Q_h
            S["Q_hc"] += Q_hc
            S["Q_cool_loss"] += Q_loss
            S["Q_cond"] += Q_c
            S["Q_evap"] += Q_e
            S["Q_sup"] += Q_sup
            S["m_frost"] += m_fr
            S["defrosting"] += defrost

        self.T_cab, self.T_int, self.T_is, self.T_sh, self.T_gl = T_cab, T_int, T_is, T_sh, T_gl
        self.T_cool, self.T_icw, self.T_ow, self.w_cab = T_cool, T_icw, T_ow, w_cab
        self.M_fr, self.N, self.T_e, self.T_c, self.T_a1 = M_fr, N, T_e, T_c, T_a1_last
        self.I_sup, self.I_h, self.I_hp = I_sup, I_h, I_hp
        self.defrost, self.t_def = defrost, t_def
        self.p_c, self.cut, self.dTs = p_c, cut, dTs
        self.t += n * dt
        inv = 1.0 / n
        means = {k: s * inv for k, s in S.items()}
        P_comp = means["P_comp"]
        means["COP_hp"] = np.where(P_comp > 0.0,
                                   means["Q_cond"] / np.where(P_comp > 0.0, P_comp, 1.0), 0.0)
        means["P_total"] = P_comp + means["P_heater"] + means["P_bl"] + means["P_fan"]
        row.update(means)
        row["v_veh"] = v
        return row

    def run(self, v_veh: Sequence[np.ndarray], inputs: Sequence[dict] | None = None,
            initial: Sequence[dict[str, float] | None] | None = None
            ) -> list[dict[str, np.ndarray]]:
        """Reset and run each member over its speed profile ``v_veh[b]`` (m/s per sample);
        ``inputs[b]``: the member's other ``step`` inputs (``W_bl``, ``T_amb``,
        ``T_cab_set`` and the direct-mode keywords), each a scalar or one value per sample.
        Per member, its channels as (n_b,) arrays (kelvin inside). A member that has ended
        holds its last inputs while the others go on; its rows stop at its own length."""
        if len(v_veh) != self.B:
            raise ConfigError(f"{len(v_veh)} speed profiles for {self.B} batch members")
        lens = np.array([len(x) for x in v_veh])
        if lens.min() == 0:
            raise ConfigError("an empty speed profile in the batch")
        n = int(lens.max())
        inputs = list(inputs) if inputs is not None else [{}] * self.B
        if len(inputs) != self.B:
            raise ConfigError(f"{len(inputs)} input sets for {self.B} batch members")
        names = sorted({k for d in inputs for k in d})
        allowed = ("W_bl", "T_amb", "T_cab_set", *DIRECT_INPUTS)
        for k in names:
            if k not in allowed:
                raise ConfigError(f"BatchHeatingPlant.run: unknown input {k!r}")

        def padded(cols, default):
            out = np.empty((n, self.B))
            for b, x in enumerate(cols):
                x = np.asarray(default[b] if x is None else x, float)
                if x.ndim == 0:
                    x = np.full(lens[b], float(x))
                if len(x) != lens[b]:
                    raise ConfigError(f"member {b}: {len(x)} input samples for "
                                      f"{lens[b]} speed samples")
                out[:lens[b], b] = x
                out[lens[b]:, b] = x[-1]
            return out

        defaults = {"W_bl": [0.0] * self.B, "T_amb": list(self._a("T_amb")),
                    "T_cab_set": list(self._h("T_heat_set")), "P_heater": [0.0] * self.B,
                    "N_hp": [0.0] * self.B, "recirc": [0.0] * self.B,
                    "f_def": list(self._h("f_def0")), "pump": [1.0] * self.B}
        v = padded(list(v_veh), [0.0] * self.B)
        cols_in = {k: padded([d.get(k) for d in inputs], defaults[k]) for k in names}
        self.reset(initial)
        cols: dict[str, np.ndarray] = {}
        for i in range(n):
            kw = {k: x[i] for k, x in cols_in.items()}
            if "pump" in kw:
                kw["pump"] = kw["pump"] > 0.5
            row = self.step(v_veh=v[i], **kw)
            if not cols:
                cols = {name: np.empty((n, self.B)) for name in row}
            for name, x in row.items():
                cols[name][i] = x
        return [{name: x[:lens[b], b] for name, x in cols.items()} for b in range(self.B)]


__all__ = ["DIRECT_INPUTS", "BatchHeatingPlant"]
