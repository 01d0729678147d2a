"""Cabin heating from what a car records: ``--model heating``.

The BMW i3 winter trips log the high-voltage coolant heater's electric power, the coolant at
the heater's inlet and outlet, the air at the outlets (supply air), the cabin air (one sensor), the
ambient and the speed; no blower flow, recirculation share, interior or shell temperature,
solar or occupant load. This declaration follows the heat from the heater to the ambient
through what is logged, with the interior and the shell latent:

* ``T_cool`` (measured): the coolant loop, seen at the heater's inlet; the heater raises it
  by ``eta_heater P_heater / G_cool`` on its way to the heater core (``G_cool`` = m c of the
  coolant flow), as in the heating plant.
* ``T_cab`` (measured): the cabin air, with the fast trims that follow it.
* ``T_int`` (latent): seats, dashboard, panels, lumped.
* ``T_shell`` (latent): roof, doors, pillars and glazing with their trim, lumped.

Heat flows (W)::

    T_hc    = T_cool + eta_heater P_heater / G_cool     coolant at the heater core
    G_hc    = G_lo + (G_hi - G_lo) sat((T_cool - T_c0) / dT_w)   the automatic blower
    Q_hc    = G_hc (T_hc - T_cab)                       heater core -> supply air -> cabin
    Q_vent  = G_vent (T_amb - T_cab)                    fresh-air share and infiltration
    Q_int   = UA_int (T_int - T_cab)                    interior surfaces -> cabin air
    Q_shell = UA_shell (T_shell - T_cab)                inner shell surface -> cabin air
    Q_out   = (UA_out + UA_out_v v) (T_amb - T_shell)   ambient -> shell (forced convection)
    Q_loss  = UA_cool (T_cool - T_amb)                  coolant loop -> under-hood air

    C_cool dT_cool/dt   = eta_heater P_heater - Q_hc - Q_loss
    C_cab dT_cab/dt     = Q_hc + Q_vent + Q_int + Q_shell + Q_occ
    C_int dT_int/dt     = -Q_int
    C_shell dT_shell/dt = Q_out - Q_shell

and the supply air at the outlets (logged), a measured state that follows the heater core's
air with the lag ``tau_sup`` of the ducts and the outlet sensors:
``tau_sup dT_ain/dt = T_cab + eps_sup (T_hc - T_cab) - T_ain``. ``G_hc`` is the heater core's
effectiveness times the blower's flow and c_p, ``eps_sup`` that effectiveness seen at the
outlets (with the duct losses). The blower is not logged; an automatic unit holds it low until
the coolant is warm (cold-air prevention, as the heating plant's production controller does:
``T_coldair``), so ``G_hc`` rises from ``G_lo`` to ``G_hi`` as the coolant goes from ``T_c0``
to ``T_c0 + dT_w``. (Held constant, the fit could not serve both the warm-up and the hold:
the coolant fitted at -2 %; a latent blower followed by a filter, or a blower following the
cabin error, predicted worse.) ``Q_occ`` (occupants and sun, not
logged) is a per-trip parameter; a trip the fit never saw gets the mean over the fitted trips.

Ranges: the cabin ones are ``car_cabin``'s (``acid/models/SOURCES.md``: Fayazbakhsh2013,
Marcos2014, TorregrosaJaime2015, Wang2018); the heating ones are those of the heating plant's
cited parameters (``datasets/plant/SOURCES.md``, ``acid.plant.heating_config``):

* ``G_cool``: 0.174 kg/s of 50 % glycol at 3.5 kJ/(kg K), 609 W/K, from the logs (heater
  power over its outlet-inlet rise, median over 20 trips [Steinstraeter2020]; the logged flow
  channel is unusable); fixed.
* ``C_cool``: about 2 l of 50 % glycol (3.5 kJ/(kg K) [ASHRAE-F]) with the heater and core
  metal; the logs' first minutes give 8.5-11 kJ/K [Steinstraeter2020]: range 3-40 kJ/K.
* ``G_lo``, ``G_hi``: effectiveness 0.4-0.9 [Steinstraeter2020, ChangWang1997] of 0.01-0.15
  kg/s of blower air (the lowest level to full) [Wang2018 Table II, Fayazbakhsh2013] at 1.008
  kJ/(kg K): 5-160 W/K.
* ``T_c0``, ``dT_w``: where the blower leaves its lowest level and how many K of coolant it
  takes to reach its highest: 0-60 degC and 2-40 K (the heating plant's production
  controller, an assumption there, uses 30 degC of the warmest source and 15 K).
* ``tau_sup``: the outlets' lag behind the heater core (ducts, outlet sensors): 5-300 s.
* ``eps_sup``: the effectiveness at the outlets, 0.2-1 (the logs bound it to 0.4-0.65 while
  holding [Steinstraeter2020]).
* ``G_vent``: 0-50 % fresh air of that flow plus infiltration of 0-6 air changes per hour
  [Ott2008, Knibbs2009]: 0-80 W/K.
* ``UA_cool``: insulated hoses, heater and pump to the under-hood air: 0-30 W/K (the plant's
  5 W/K is an assumption; the logs' return line loses about 0.25 K at 0.17 kg/s).
* ``eta_heater``: 0.98 (resistive/PTC element, electronics' losses), fixed: with ``C_cool``
  and the blower's ``G_lo``/``G_hi`` free it is not separable from them.
* ``UA_shell``: the winter shell with its trim (``R_trim``, ``A_glass``): 10-300 W/K.
* ``Q_occ``: 0-2 occupants (about 100 W each) and winter sun through ~2 m^2 of glazing:
  -300-1500 W [Fayazbakhsh2013, Marcos2014].
"""

import casadi as ca
import numpy as np

from acid.models import RK4, Model, Parameter, Signal, State


def _heater_core(s):
    return s.T_cool + s.eta_heater * s.P_heater / s.G_cool


def _blower(s):
    x = ca.fmin(ca.fmax((s.T_cool - s.T_c0) / s.dT_w, 0.0), 1.0)
    return s.G_lo + (s.G_hi - s.G_lo) * x


def ode(s):
    t_hc = _heater_core(s)
    q_hc = _blower(s) * (t_hc - s.T_cab)
    q_vent = s.G_vent * (s.T_amb - s.T_cab)
    q_int = s.UA_int * (s.T_int - s.T_cab)
    q_shell = s.UA_shell * (s.T_shell - s.T_cab)
    q_out = (s.UA_out + s.UA_out_v * s.v_veh) * (s.T_amb - s.T_shell)
    q_loss = s.UA_cool * (s.T_cool - s.T_amb)
    return {
        "T_cool": (s.eta_heater * s.P_heater - q_hc - q_loss) / (1e3 * s.C_cool),
        "T_cab": (q_hc + q_vent + q_int + q_shell + s.Q_occ) / (1e3 * s.C_cab),
        "T_ain": (s.T_cab + s.eps_sup * (t_hc - s.T_cab) - s.T_ain) / s.tau_sup,
        "T_int": -q_int / (1e3 * s.C_int),
        "T_shell": (q_out - q_shell) / (1e3 * s.C_shell),
    }


def _interior_start(m):
    # After a cold soak the cabin sensor may sit at its lower clip (10 degC on the i3) while
    # the outlets still read the soak: the interior starts at the colder of the two.
    return np.minimum(m.T_cab, m.T_ain)


def _shell_start(m):
    return 0.5 * (_interior_start(m) + m.T_amb)


model = Model(
    "heating",
    states=[State("T_cool", "K", description="coolant at the heater inlet (logged)"),
            State("T_cab", "K", description="cabin air (logged)"),
            State("T_ain", "K", description="supply air: the outlets' mean (logged)"),
            State("T_int", "K", measured=False, initial=_interior_start,
                  description="interior (seats, dashboard, panels), lumped; not logged"),
            State("T_shell", "K", measured=False, initial=_shell_start,
                  description="body shell, glazing and trim, lumped; not logged")],
    inputs=[Signal("P_heater", "W", "coolant heater electric power (logged)")],
    disturbances=[Signal("T_amb", "K", "ambient air (logged)"),
                  Signal("v_veh", "m/s", "vehicle speed (logged)")],
    parameters=[
        Parameter("C_cool", "kJ/K", 10.0, 3.0, 40.0, description="coolant loop, heater, core"),
        Parameter("C_cab", "kJ/K", 10.0, 3.0, 40.0, description="cabin air and trims"),
        Parameter("C_int", "kJ/K", 60.0, 20.0, 200.0, description="interior, lumped"),
        Parameter("C_shell", "kJ/K", 80.0, 20.0, 300.0, description="shell and glazing"),
        Parameter("G_lo", "W/K", 20.0, 5.0, 160.0,
                  description="heater core -> cabin, blower at its lowest: effectiveness x "
                              "flow x c_p"),
        Parameter("G_hi", "W/K", 90.0, 10.0, 160.0,
                  description="heater core -> cabin, blower at its highest"),
        Parameter("T_c0", "K", 293.15, 273.15, 333.15,
                  description="coolant where the blower leaves its lowest level"),
        Parameter("dT_w", "K", 15.0, 2.0, 40.0,
                  description="coolant rise from the lowest to the highest blower level"),
        Parameter("eps_sup", "1", 0.5, 0.2, 1.0,
                  description="heater-core effectiveness seen at the outlets"),
        Parameter("tau_sup", "s", 30.0, 5.0, 300.0,
                  description="outlets' lag behind the heater core (ducts, sensors)"),
        Parameter("G_vent", "W/K", 15.0, 0.0, 80.0,
                  description="fresh-air share and infiltration x c_p"),
        Parameter("UA_int", "W/K", 80.0, 10.0, 300.0, description="interior <-> cabin air"),
        Parameter("UA_shell", "W/K", 40.0, 10.0, 300.0,
                  description="inner shell surface (with trim) <-> cabin air"),
        Parameter("UA_out", "W/K", 80.0, 20.0, 300.0, description="ambient <-> shell, still"),
        Parameter("UA_out_v", "W s/(K m)", 10.0, 0.0, 80.0,
                  description="ambient <-> shell, per m/s of speed"),
        Parameter("UA_cool", "W/K", 5.0, 0.0, 30.0,
                  description="coolant loop -> under-hood air"),
        Parameter("G_cool", "W/K", 609.0, 300.0, 1200.0, fixed=True,
                  description="coolant flow x c_p through the heater"),
        Parameter("eta_heater", "1", 0.98, 0.9, 1.0, fixed=True,
                  description="heater: electric power into the coolant"),
        Parameter("Q_occ", "W", 150.0, -300.0, 1500.0, per_experiment=True,
                  description="occupants and sun into the cabin, per trip"),
    ],
    Ts=5.0, ode=ode, integrator=RK4(substeps=2),
    description="cabin heating from logged channels: coolant, cabin air, supply air; latent "
                "interior and shell",
)
