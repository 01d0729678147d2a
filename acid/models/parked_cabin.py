"""The parked car's cabin as the day planner predicts it: ``parked_cabin`` (two thermal nodes,
the pre-conditioning's electric power split between the charger and the battery).

Declared once; ``acid.studies.dayplan`` identifies its parameters on the plant's parked
records (soaks and pull-downs of the training days) and builds its optimal-control problem
from it with :class:`acid.control.ocp.OCP`. Kelvin, W, s::

    P_el = P_grid + P_bat                                   electric power (climate + 12 V)
    C_cab dT_cab/dt = UA_cm (T_m - T_cab) + UA_ca (T_amb - T_cab) + a_c G + sign eta P_el
    C_m   dT_m/dt   = UA_cm (T_cab - T_m) + UA_ma (T_amb - T_m)   + a_m G
    dE_bat/dt       = P_bat / 3.6e6                         battery energy drawn, kWh

``T_cab`` the cabin air (measured), ``T_m`` the interior and shell as one mass (latent),
``G`` the global horizontal irradiance (W/m^2), ``sign`` -1 when the pre-conditioning cools
(summer) and +1 when it heats (winter), ``eta`` the heat moved per electric watt at full
power (the air conditioner's or the heat pump's COP and the heater's efficiency lumped, the
12 V base load included). The output ``P_cap = P_cap0 + P_cap1 (T_cab - 295.15 K)`` is the most
power the climate system draws at full output (a hot cabin loads the compressor more, a
warm one the heater less), fitted on its own as a line through the pull-downs' first
minutes. Only the ratios to ``C_cab`` can be told from the cabin
temperature, so ``C_cab`` is fixed (a normalisation, not a claim about the car); the other
rows are identified. The defaults are starting values for the fit only.
"""

from __future__ import annotations

from acid.models import RK4, Constant, Model, Parameter, Signal, State

#: C_cab: fixed normalisation of the heat balance, J/K (the order of a small car's cabin
#: air and fast interior; only the ratios of the other rows to it are identified)
C_CAB = 1.5e5
#: the cabin temperature the full-power line is written about, K (22 degC)
T_REF = 295.15


def _ode(s):
    P_el = s.P_grid + s.P_bat
    return {
        "T_cab": (s.UA_cm * (s.T_m - s.T_cab) + s.UA_ca * (s.T_amb - s.T_cab) + s.a_c * s.G
                  + s.sign * s.eta * P_el) / s.C_cab,
        "T_m": (s.UA_cm * (s.T_cab - s.T_m) + s.UA_ma * (s.T_amb - s.T_m) + s.a_m * s.G)
        / s.C_m,
        "E_bat": s.P_bat / 3.6e6,
    }


def _output(s):
    return {"P_el": s.P_grid + s.P_bat,
            "P_cap": s.P_cap0 + s.P_cap1 * (s.T_cab - T_REF)}


def parked_cabin_model(season: str, values: dict[str, float] | None = None) -> Model:
    """The declaration for ``season`` ("summer": cooling, "winter": heating) at 60 s, with the
    parameter ``values`` given by name (default: the fit's starting values)."""
    sign = -1.0 if season == "summer" else 1.0
    v = {"C_m": 1.5e6, "UA_cm": 150.0, "UA_ca": 30.0, "UA_ma": 30.0, "a_c": 0.3, "a_m": 1.0,
         "eta": 1.5, "P_cap0": 2000.0, "P_cap1": 0.0, **(values or {})}
    return Model(
        f"parked_cabin_{season}",
        states=[State("T_cab", "K", description="cabin air"),
                State("T_m", "K", measured=False, initial=lambda s: s.T_cab,
                      description="interior and shell, one mass"),
                State("E_bat", "kWh", measured=False, initial=0.0,
                      description="battery energy drawn by the pre-conditioning")],
        inputs=[Signal("P_grid", "W", "pre-conditioning power through the charger (DC side)"),
                Signal("P_bat", "W", "pre-conditioning power from the battery")],
        disturbances=[Signal("T_amb", "K", "ambient air"),
                      Signal("G", "W/m^2", "global horizontal irradiance")],
        outputs=[Signal("P_el", "W", "pre-conditioning electric power"),
                 Signal("P_cap", "W", "the most power the climate system draws")],
        parameters=[
            Parameter("C_cab", "J/K", C_CAB, fixed=True, description="normalisation"),
            Parameter("C_m", "J/K", v["C_m"], 1e4, 1e8, description="interior and shell"),
            Parameter("UA_cm", "W/K", v["UA_cm"], 1.0, 5000.0,
                      description="cabin air to interior"),
            Parameter("UA_ca", "W/K", v["UA_ca"], 0.0, 2000.0,
                      description="cabin air to ambient (infiltration, glass)"),
            Parameter("UA_ma", "W/K", v["UA_ma"], 0.0, 2000.0,
                      description="interior and shell to ambient"),
            Parameter("a_c", "m^2", v["a_c"], 0.0, 10.0, description="sun into the air"),
            Parameter("a_m", "m^2", v["a_m"], 0.0, 20.0, description="sun into the mass"),
            Parameter("eta", "1", v["eta"], 0.05, 8.0,
                      description="heat moved per electric watt at full power"),
            Parameter("P_cap0", "W", v["P_cap0"], fixed=True,
                      description="full power with the cabin at 22 degC"),
            Parameter("P_cap1", "W/K", v["P_cap1"], fixed=True,
                      description="full power's change per K of cabin temperature")],
        constants=[Constant("sign", sign, "1", "-1 cooling, +1 heating")],
        Ts=60.0, ode=_ode, integrator=RK4(2), output=_output,
        description="the parked cabin of the day planner")


FREE = ("C_m", "UA_cm", "UA_ca", "UA_ma", "a_c", "a_m", "eta")

__all__ = ["C_CAB", "FREE", "T_REF", "parked_cabin_model"]
