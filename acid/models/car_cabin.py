"""A cabin model for what a car records: ``--model car_cabin``.

A real car logs the cabin air temperature, the ambient, the speed, the A/C's electric power
and (on the BMW i3) the air temperature after the evaporator/heat exchanger; it logs no
blower flow, no supply air, no interior or shell temperature and no solar load. This
declaration reads the cabin air, the ambient, the speed and the evaporator air temperature
(the A/C's effect on the cabin arrives as that air; the A/C power is what a controller
spends to hold it, not a separate heat flow here):

* ``T_cab`` (measured): the cabin air, with the fast trims that follow it.
* ``T_int`` (latent): seats, dashboard, panels and the air they hold, lumped.
* ``T_shell`` (latent): roof, doors, pillars and glazing, lumped.

Heat flows (W), a three-resistance, three-capacitance network::

    Q_sup   = G_sup (T_evap + dT_sup - T_cab)          supply air (blower at a fixed level)
    Q_int   = UA_int (T_int - T_cab)                    interior surfaces -> cabin air
    Q_shell = UA_shell (T_shell - T_cab)                inner shell surface -> cabin air
    Q_out   = (UA_out + UA_out_v v) (T_amb - T_shell)   ambient -> shell (forced convection)

    C_cab dT_cab/dt     = Q_sup + Q_int + Q_shell
    C_int dT_int/dt     = Q_sol - Q_int
    C_shell dT_shell/dt = Q_out - Q_shell

``G_sup`` is the blower's mass flow times c_p: the log has no flow, so the model assumes the
blower level constant (the i3 trips ran in "Automatic, level 1") and identifies the product.
The supply air is the logged evaporator air temperature ``T_evap`` plus ``dT_sup`` (blower
heat and duct gains). ``Q_sol``, the solar and occupant load absorbed by the interior, is
not logged: it is a fourth, latent state that returns to its typical value ``Q_bar`` within
``tau_Q`` and is driven by noise ``sigma_Q``::

    dQ_sol/dt = (Q_bar - Q_sol) / tau_Q  (+ noise)

``acid fit --method pem`` (``acid.ident.pem``) follows it with an extended Kalman filter
along each whole trip and estimates the noises (``sigma_cab``, ``sigma_y``, ``sigma_Q``)
with the rest; output error estimates it at each window's start. ``acid validate
--warm-start ekf`` gives the filter's estimate at each start, then predicts open loop (the
load relaxing to ``Q_bar``).

What the data identify (13 BMW i3 trips, notes/i20-real-logs.md): ``T_cab`` alone sees the
network only through its response. ``C_cab`` and ``G_sup`` come out as one time constant
(both at a bound), the interior's and shell's capacities and conductances only in
combinations, and ``dT_sup`` is indistinguishable from the load (so it is fixed). A load
that returns to a typical value fits the trips better than a random walk (likelihood-ratio
test) and a blower flow rising with the A/C power does not (``G_P`` 2.5 +/- 3.3 W/K per kW).
The ranges are those of published cabin models and measurements
(``acid/models/SOURCES.md``):

* ``C_cab``: cabin air of a compact car (2.5-3 m^3, ~3 kg, ~3 kJ/K) plus the thin trims
  that follow it within a minute: 3-40 kJ/K [Marcos2014, TorregrosaJaime2015].
* ``C_int``: seats, dashboard and panels, 40-100 kg at 1-1.5 kJ/(kg K): 20-200 kJ/K
  [Fayazbakhsh2013, Marcos2014].
* ``C_shell``: steel/CFRP and glass body shell, 100-300 kg at 0.5-1 kJ/(kg K) (of which
  the part in thermal contact with the cabin): 20-300 kJ/K [TorregrosaJaime2015].
* ``G_sup``: 0.03-0.15 kg/s of supply air (low blower levels to full) times 1.008
  kJ/(kg K): 25-160 W/K [Fayazbakhsh2013, Wang2018 Table II].
* ``UA_int``: interior surfaces of 4-8 m^2 with 3-10 W/(m^2 K) film coefficients:
  10-300 W/K; ``UA_shell``: 8-12 m^2 of inner shell and glazing: 20-300 W/K
  [Fayazbakhsh2013, TorregrosaJaime2015].
* ``UA_out`` + ``UA_out_v v``: outer surface of ~10 m^2 with a still-air coefficient of
  5-15 W/(m^2 K) and a speed slope of 2-5 W/(m^2 K) per m/s (forced convection):
  20-300 W/K and 0-80 W/K per m/s [Fayazbakhsh2013].
* ``Q_bar`` (and the load ``Q_sol``): 0-1000 W/m^2 on ~2 m^2 of glazing, part transmitted
  and absorbed, plus occupants (~100 W each): -300-1500 W [Fayazbakhsh2013, Marcos2014].
* ``tau_Q``, ``sigma_cab``, ``sigma_y``, ``sigma_Q``: statistical, estimated by PEM; their
  bounds are explained in SOURCES.md ("Noises and the load's prior").
"""

from acid.models import RK4, Model, Parameter, Signal, State


def ode(s):
    q_sup = s.G_sup * (s.T_evap + s.dT_sup - s.T_cab)
    q_int = s.UA_int * (s.T_int - s.T_cab)
    q_shell = s.UA_shell * (s.T_shell - s.T_cab)
    q_out = (s.UA_out + s.UA_out_v * s.v_veh) * (s.T_amb - s.T_shell)
    return {
        "T_cab": (q_sup + q_int + q_shell) / (1e3 * s.C_cab),
        "T_int": (s.Q_sol - q_int) / (1e3 * s.C_int),
        "T_shell": (q_out - q_shell) / (1e3 * s.C_shell),
        "Q_sol": (s.Q_bar - s.Q_sol) / s.tau_Q,     # returns to Q_bar; noise sigma_Q
    }


#: The load a filter or an output-error window starts from, and its spread (W): the middle
#: and the half-width of the per-trip loads fitted on the 13 estimation trips (91-1500 W).
Q_SOL_PRIOR, Q_SOL_SPREAD = 500.0, 400.0


def _between_cabin_and_ambient(m):
    return 0.5 * (m.T_cab + m.T_amb)


model = Model(
    "car_cabin",
    states=[State("T_cab", "K", description="cabin air (logged)", noise="sigma_cab",
                  sensor="sigma_y", spread=0.1),
            State("T_int", "K", measured=False, initial=lambda m: m.T_cab,
                  description="interior (seats, dashboard, panels), lumped; not logged"),
            State("T_shell", "K", measured=False, initial=_between_cabin_and_ambient,
                  description="body shell and glazing, lumped; not logged"),
            State("Q_sol", "W", measured=False, initial=Q_SOL_PRIOR, noise="sigma_Q",
                  spread=Q_SOL_SPREAD,
                  description="solar and occupant load into the interior (not logged): "
                  "it returns to Q_bar within tau_Q, driven by noise sigma_Q; per window for "
                  "output error, followed by the filter")],
    inputs=[Signal("T_evap", "K", "air after the evaporator / heat exchanger (logged)")],
    disturbances=[Signal("T_amb", "K", "ambient air (logged)"),
                  Signal("v_veh", "m/s", "vehicle speed (logged)")],
    parameters=[
        Parameter("C_cab", "kJ/K", 12.0, 3.0, 40.0, description="cabin air and trims"),
        Parameter("C_int", "kJ/K", 60.0, 20.0, 200.0, description="interior, lumped"),
        Parameter("C_shell", "kJ/K", 80.0, 20.0, 300.0, description="shell and glazing"),
        Parameter("G_sup", "W/K", 60.0, 25.0, 160.0,
                  description="supply air flow x c_p (blower level held)"),
        Parameter("dT_sup", "K", 1.0, 0.0, 3.0, fixed=True,
                  description="supply air above the evaporator air (blower heat, ducts)"),
        Parameter("UA_int", "W/K", 80.0, 10.0, 300.0, description="interior <-> cabin air"),
        Parameter("UA_shell", "W/K", 80.0, 20.0, 300.0,
                  description="inner shell surface <-> cabin air"),
        Parameter("UA_out", "W/K", 80.0, 20.0, 300.0, description="ambient <-> shell, still"),
        Parameter("UA_out_v", "W s/(K m)", 20.0, 0.0, 80.0,
                  description="ambient <-> shell, per m/s of speed"),
        Parameter("Q_bar", "W", 500.0, -300.0, 1500.0,
                  description="the load's typical value (solar and occupants)"),
        Parameter("tau_Q", "s", 900.0, 60.0, 20000.0,
                  description="how long a departure of the load from Q_bar lasts"),
        Parameter("sigma_cab", "K", 0.02, 1e-4, 0.5, fixed=True,
                  description="cabin air's random increment per sample (model error)"),
        Parameter("sigma_y", "K", 0.05, 0.005, 0.5, fixed=True,
                  description="cabin sensor noise (0.01 K resolution, 0.5 K steps of "
                  "ambient/evaporator inputs)"),
        Parameter("sigma_Q", "W", 10.0, 0.1, 200.0, fixed=True,
                  description="load's random-walk step per sample"),
    ],
    Ts=5.0, ode=ode, integrator=RK4(substeps=2),
    description="car cabin from logged channels: cabin air, latent interior and shell",
)
