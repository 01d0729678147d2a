"""The nominal A/C controller of the high-fidelity plant (paper section II-A) and protections.

"Two PI control loops with anti-windup and A/C on-off logic": the compressor speed tracks an
evaporator-wall temperature set-point, the blower flow tracks the cabin-air set-point; the
recirculation rate depends proportionally on the cabin-ambient temperature difference and is
saturated. The controllers run at the plant's internal step (continuous-time emulation, like
CoolSim's 0.01 s Simulink loop).

Anti-windup is conditional integration: the integrator stops while the output is clamped and
the error would drive it further into saturation. With ``anti_windup=False`` the integrator
never stops (the output is still clamped): the classic wind-up, kept for tests.

A/C on/off logic (hysteresis): the compressor stops when T_ew < T_ew,set - hyst_off (default
2 K) and restarts when T_ew > T_ew,set + hyst_on (1 K), from its minimum speed.

In the plant's "direct" mode (excitation, MPC) only ``CompressorLoop`` runs, tracking the
commanded T_evap_set; the blower flow is an input. In "nominal" mode ``BlowerLoop`` sets W_bl
and the evaporator set-point is reset within paper Table II's 3-10 degC when the blower sits at
its minimum and the cabin is still below its set-point (no overcooling at low load); when
even the fully reset evaporator overcools the cabin by 0.5 K the A/C demand switches off (the
compressor stops, the blower ventilates) until the cabin is 0.5 K above its set-point.

Protections (both modes, in ``acid.plant.hifi``): the compressor speed is capped by a
head-pressure derate (linear from N_max at ``p_derate`` to N_min at ``p_cut``) and by frost
protection (``K_frost`` rpm per K of evaporating temperature below ``T_e_min``); above
``p_cut`` the compressor stops until the head pressure falls 0.6 MPa below it.
"""

from __future__ import annotations

from acid.plant.config import PlantConfig


def recirculation(T_cab: float, T_amb: float, k_rec: float, r_max: float) -> float:
    """Recirculated fraction r = sat(k_rec (T_amb - T_cab), 0, r_max) of the blower air.

    Rises as the cabin cools below ambient (re-cooling cabin air is cheaper than ambient air)
    and is zero while the cabin is hotter than ambient (flush the hot-soak air). The sign and
    gain are assumptions: the paper only says "proportional ... and saturated".
    """
    r = k_rec * (T_amb - T_cab)
    return 0.0 if r < 0.0 else (r_max if r > r_max else r)


class CompressorLoop:
    """Compressor speed PI on the evaporator wall temperature error, with on/off hysteresis.

    N_cmd = sat(Kp e + I, N_min, N_max) with e = T_ew - T_ew,set (K), N in rpm; 0 when off.
    """

    def __init__(self, config: PlantConfig):
        self.Kp, self.Ki = config.Kp_comp, config.Ki_comp
        self.N_min, self.N_max = config.N_min, config.N_max
        self.hyst_off, self.hyst_on = config.hyst_off, config.hyst_on
        self.anti_windup = bool(config.anti_windup)
        self.reset()

    def reset(self, on: bool = True) -> None:
        """Start with the A/C on and the integrator at the minimum speed."""
        self.on = bool(on)
        self.integ = self.N_min

    def update(self, T_ew: float, T_set: float, dt: float, enabled: bool = True,
               N_cap: float | None = None) -> float:
        """Advance by ``dt`` s and return the commanded speed, rpm.

        ``N_cap`` (rpm, between N_min and N_max) is the protections' speed limit (head-pressure
        derate, frost protection); the PI clamps and stops integrating against it.
        """
        N_hi = self.N_max if N_cap is None else N_cap
        if not enabled:
            self.on = False
            self.integ = self.N_min
            return 0.0
        e = T_ew - T_set
        if self.on:
            if e < -self.hyst_off:
                self.on = False
                self.integ = self.N_min
                return 0.0
        elif e > self.hyst_on:
            self.on = True
        else:
            return 0.0
        u = self.Kp * e + self.integ
        if not self.anti_windup or not ((u >= N_hi and e > 0.0)
                                        or (u <= self.N_min and e < 0.0)):
            self.integ += self.Ki * e * dt
        if self.anti_windup and self.integ > N_hi:
            self.integ = N_hi  # a falling cap pulls the integrator down with it
        return self.N_min if u < self.N_min else (N_hi if u > N_hi else u)


class BlowerLoop:
    """Blower flow PI on the cabin temperature error: W = sat(Kp e + I, W_min, W_max), kg/s.

    e = T_cab - T_cab,set (K): a warm cabin gets more air.
    """

    def __init__(self, config: PlantConfig):
        self.Kp, self.Ki = config.Kp_bl, config.Ki_bl
        self.W_min, self.W_max = config.W_bl_min, config.W_bl_max
        self.anti_windup = bool(config.anti_windup)
        self.reset()

    def reset(self) -> None:
        """Integrator at the minimum flow."""
        self.integ = self.W_min

    def update(self, T_cab: float, T_set: float, dt: float) -> float:
        """Advance by ``dt`` s and return the blower flow, kg/s."""
        e = T_cab - T_set
        u = self.Kp * e + self.integ
        if not self.anti_windup or not ((u >= self.W_max and e > 0.0)
                                        or (u <= self.W_min and e < 0.0)):
            self.integ += self.Ki * e * dt
        return self.W_min if u < self.W_min else (self.W_max if u > self.W_max else u)

