"""The control-oriented heating model: ``heating_control``.

What the heating controller predicts with, declared once (the NMPC of
``acid.control.heating`` builds its optimal-control problem from it). Unlike ``heating``
(identified from what the logged car records), this model carries what a controller acts on:
the heat pump's heat, the coolant heater's power and the recirculation share, and the
windscreen's fogging margin. **Its values are derived from the heating plant's configuration**
(``acid.control.heating.heating_control_model(heating, config)``: ``HeatingConfig`` and the
winter ``PlantConfig``, every value cited there), not identified; the heat pump's COP law is the one
fitted here (``COP_*`` below) to 71 direct-mode runs of the heating plant
(``acid.control.heating.heat_pump_map``). The blower flow is held (``W_bl``), the
defrost-outlet share at its normal value ``f_def0``; frost and defrost are not modelled (the
plant does them; feedback absorbs them).

States (K; ``w_cab`` kg/kg)::

    T_mix = T_amb + recirc (T_cab - T_amb) + f_bl P_bl / (W c_p)      mixed air, blower heat
    T_a1  = T_mix + eps_ic (T_icw - T_mix)                             after the inner condenser
    Q_hc  = max(0, eps_hc W c_p (T_cool + eta P_heater / G_cool - T_a1))   heater core
    T_sup = T_a1 + Q_hc / (W c_p)                                      supply air
    C_cab dT_cab/dt   = hA_int (T_int - T_cab) + hA_sh (T_shell - T_cab) + W c_p (T_sup - T_cab)
                        + G_inf (T_amb - T_cab) + Q_pass
                        + hA_gi (T_glass - T_cab - f_def (T_sup - T_cab))
    C_int dT_int/dt   = hA_int (T_cab - T_int) + hA_is (T_is - T_int)
    C_is dT_is/dt     = hA_is (T_int - T_is)
    C_sh dT_shell/dt  = hA_ext(v) (1 - f_ws) (T_amb - T_shell) + hA_sh (T_cab - T_shell)
    C_ws dT_glass/dt  = hA_gi (T_cab + f_def (T_sup - T_cab) - T_glass)
                        + hA_ext(v) f_ws (T_amb - T_glass)
    C_icw dT_icw/dt   = Q_hp - eps_ic W c_p (T_icw - T_mix)            inner-condenser wall
    C_cool dT_cool/dt = eta P_heater - Q_hc - UA_cool (T_cool - T_amb)
    M_cab dw_cab/dt   = m_moist + (W (1 - recirc) + m_inf(v)) (w_amb(T_amb) - w_cab)

the heating plant's equations (``acid.plant.heating``); ``Q_hp`` is the heat the refrigerant
gives the inner condenser. Outputs: the heat pump's electric power ``P_hp = Q_hp / COP``,
``COP = COP_0 + COP_amb (T_amb - 273.15) - COP_lift (T_a1 - T_amb)`` (floored at 1), the
fogging margin ``fog_margin = T_glass - T_dew(w_cab)`` (Magnus, over water), ``T_sup`` and
``T_a1``. Kelvin, W, kg/s.
"""

from __future__ import annotations

from acid.models import RK4, Model, Parameter, Signal, State, exp, fmax, log

T0C = 273.15

#: The COP law fitted to the heating plant (``heat_pump_map``: 71 runs, -10 to 7 degC,
#: recirculation 0-0.8, 800-4500 rpm, inner-condenser air below 68 degC; power RMS 4.8 %,
#: worst 17 %).
COP_FIT = {"COP_0": 5.009, "COP_amb": 0.00548, "COP_lift": 0.04721}

#: The blower flow the heating controllers hold, kg/s (about the production controller's
#: while it holds: 0.058-0.069 kg/s at 7 to -10 degC).
W_BL_HOLD = 0.07


def _air(s):
    Wcp = s.W_bl * s.c_p
    P_bl = (s.beta1 * s.W_bl + s.beta2) * s.W_bl + s.beta3
    T_mix = s.T_amb + s.recirc * (s.T_cab - s.T_amb) + s.f_bl_heat * P_bl / Wcp
    T_a1 = T_mix + s.eps_ic * (s.T_icw - T_mix)
    Q_hc = fmax(0.0, s.eps_hc * Wcp * (s.T_cool + s.eta_heater * s.P_heater / s.G_cool - T_a1))
    return Wcp, T_a1, Q_hc, T_a1 + Q_hc / Wcp, T_mix


def _hA_ext(s):
    # forced convection hA_ext0 + hA_ext_v v^0.8 (PlantConfig.hA_ext), smoothed at standstill
    return s.hA_ext0 + s.hA_ext_v * exp(0.8 * log(s.v_veh + 0.05))


def _w_sat(s, T):
    p = 611.2 * exp(17.62 * (T - T0C) / (243.12 + T - T0C))
    return 0.621945 * p / (s.p_atm - p)


def ode(s):
    Wcp, _T_a1, Q_hc, T_sup, T_mix = _air(s)
    hA = _hA_ext(s)
    loc = s.T_cab + s.f_def * (T_sup - s.T_cab)
    F = s.W_bl * (1.0 - s.recirc) + s.m_inf0 + s.k_inf * s.v_veh
    w_amb = s.RH_amb * _w_sat(s, s.T_amb)
    return {
        "T_cab": (s.hA_int * (s.T_int - s.T_cab) + s.hA_sh * (s.T_shell - s.T_cab)
                  + Wcp * (T_sup - s.T_cab) + s.m_inf0 * s.c_p * (s.T_amb - s.T_cab)
                  + s.k_inf * s.v_veh * s.c_p * (s.T_amb - s.T_cab) + s.Q_pass
                  + s.hA_gi * (s.T_glass - loc)) / s.C_cab,
        "T_int": (s.hA_int * (s.T_cab - s.T_int) + s.hA_is * (s.T_is - s.T_int)) / s.C_int,
        "T_is": s.hA_is * (s.T_int - s.T_is) / s.C_is,
        "T_shell": (hA * (1.0 - s.f_ws) * (s.T_amb - s.T_shell)
                    + s.hA_sh * (s.T_cab - s.T_shell)) / s.C_sh,
        "T_glass": (s.hA_gi * (loc - s.T_glass) + hA * s.f_ws * (s.T_amb - s.T_glass)) / s.C_ws,
        "T_cool": (s.eta_heater * s.P_heater - Q_hc
                   - s.UA_cool * (s.T_cool - s.T_amb)) / s.C_cool,
        "T_icw": (s.Q_hp - s.eps_ic * Wcp * (s.T_icw - T_mix)) / s.C_icw,
        "w_cab": (s.m_moist + F * (w_amb - s.w_cab)) / (s.C_cab / s.c_p),
    }


def output(s):
    _Wcp, T_a1, _Q_hc, T_sup, _T_mix = _air(s)
    cop = fmax(1.0, s.COP_0 + s.COP_amb * (s.T_amb - T0C) - s.COP_lift * (T_a1 - s.T_amb))
    p_w = s.w_cab * s.p_atm / (0.621945 + s.w_cab)
    x = log(fmax(p_w, 1.0) / 611.2)   # floored: an iterate may pass through w_cab <= 0
    T_dew = T0C + 243.12 * x / (17.62 - x)
    return {"P_hp": s.Q_hp / cop, "fog_margin": s.T_glass - T_dew, "T_sup": T_sup,
            "T_a1": T_a1}


def declare(values: dict[str, tuple[float, str, str]], Ts: float = 10.0) -> Model:
    """The declaration with the fixed values ``values`` (name: (value, unit, description), every
    name of the module docstring's equations but the COP law's), ``Ts`` the sample (s).
    :func:`acid.control.heating.heating_control_model` derives them from the heating plant's
    configuration."""
    k = values
    params = [Parameter(n, u, float(v), fixed=True, description=d) for n, (v, u, d) in k.items()]
    params += [Parameter("COP_0", "1", COP_FIT["COP_0"], 1.0, 8.0,
                         description="COP at 0 degC ambient and zero lift (heat_pump_map)"),
               Parameter("COP_amb", "1/K", COP_FIT["COP_amb"], -0.2, 0.2,
                         description="COP per K of ambient"),
               Parameter("COP_lift", "1/K", COP_FIT["COP_lift"], 0.0, 0.2,
                         description="COP lost per K of inner-condenser air above ambient")]
    return Model(
        "heating_control",
        states=[State("T_cab", "K", description="cabin air"),
                State("T_int", "K", description="fast interior"),
                State("T_is", "K", description="slow interior"),
                State("T_shell", "K", description="shell without the windscreen"),
                State("T_glass", "K", description="windscreen glass"),
                State("T_cool", "K", description="coolant loop"),
                State("T_icw", "K", description="inner-condenser wall"),
                State("w_cab", "kg/kg", description="cabin humidity ratio")],
        inputs=[Signal("Q_hp", "W", "heat pump's heat into the inner condenser"),
                Signal("P_heater", "W", "coolant heater electric power"),
                Signal("recirc", "1", "recirculated share of the blower flow")],
        disturbances=[Signal("T_amb", "K", "ambient air"),
                      Signal("v_veh", "m/s", "vehicle speed")],
        outputs=[Signal("P_hp", "W", "heat pump's electric power"),
                 Signal("fog_margin", "K", "windscreen inner surface minus cabin dew point"),
                 Signal("T_sup", "K", "supply air"),
                 Signal("T_a1", "K", "air after the inner condenser")],
        parameters=params,
        Ts=Ts, ode=ode, integrator=RK4(substeps=2), output=output,
        description="heating for control: heat pump, coolant heater, recirculation, fogging; "
                    "values from the heating plant's configuration",
    )
