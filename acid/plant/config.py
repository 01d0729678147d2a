"""Configuration of the high-fidelity plant: every parameter with its unit and its source.

``PlantConfig()`` is the frozen default (second generation). Every field's
``source`` names a reference key of ``datasets/plant/SOURCES.md`` (full bibliographic detail
there), the paper ([Wang2018]), or says *assumption* with its reason; the few *calibrated*
ones (UA_ca0) stay inside a stated range. The calibration targets E(0) of the paper's Table I
and the idle service chart of ``acid plant-check``; with the cited physics Table I falls
further with speed than the paper's (SOURCES.md says by how much and why).

Units are SI with **temperatures in kelvin** inside (``PlantConfig``, ``from_dict``,
``to_dict``); a TOML file a user writes gives **temperatures in degC**, like every other file
and option of acid, or tagged with a unit of ``acid.units.UNIT_SCALES``; kelvin is accepted
only when tagged (``from_toml``, ``to_file_dict``)::

    # my_plant.toml -- flat keys or grouped by section, units as in ``parameter_table()``
    refrigerant = "R1234yf"
    [ambient]
    T_amb = 35.0            # degC (or "35 degC", or "308.15 K")
    RH_amb = 0.4
    [compressor]
    superheat = 5.0         # K: a temperature difference (or "5 K")

An untagged temperature outside -60..150 degC is refused with a hint (it was almost certainly
written in kelvin); inside, a temperature below 150 K is refused (written in degC).
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from acid.errors import ConfigError
from acid.paper import MODEL as _PAPER_MODEL
from acid.paper import TABLE_II as _TABLE_II
from acid.units import C2K, K2C, UNIT_SCALES

REFRIGERANTS = ("R134a", "R1234yf")

SECTIONS = ("ambient", "cabin", "hvac", "evaporator", "condenser", "compressor", "controller",
            "initial", "solver")

#: Air properties at 300 K for the shell's flat-plate convection, [Incropera] Table A.4:
#: conductivity W/(m K), kinematic viscosity m^2/s, Prandtl number.
K_AIR, NU_AIR, PR_AIR = 0.0263, 15.89e-6, 0.707

#: Generation-1 parameter names still accepted by ``replace`` with the value 0 only (callers
#: that build the speed-blind counterfactual): name -> (switch it turns off, meaning).
_LEGACY_ZERO = {"k_ram": ("front_end_speed", "no ram air"),
                "hA_ext_v": ("cabin_speed", "no speed-dependent shell convection")}


#: fields in K that are temperature *differences* (a number in a file is K, the same as a degC
#: difference); every other field in K is an absolute temperature, degC in a file
TEMPERATURE_DIFFERENCES = ("superheat", "subcool", "dT_suc0", "dT_recirc", "hyst_off",
                           "hyst_on")

#: an untagged temperature in a plant file, degC: outside this it was written in kelvin
FILE_DEGC_RANGE = (-60.0, 150.0)

_FRACTION = "a fraction"
_CAR_TO_BUS = "a city car to a bus"
#: physical range of every numeric parameter, (min, max, why): wide enough for any vehicle
#: from a city car to a bus and any climate acid's property tables cover, narrow enough to
#: refuse a typo of orders of magnitude (a 1 m^3 displacement, a MJ/K cabin air)
RANGES: dict[str, tuple[float, float, str]] = {
    # ambient
    "T_amb": (233.15, 330.15, "the refrigerant property tables, -40 to 57 degC"),
    "RH_amb": (0.0, 1.0, _FRACTION),
    "p_atm": (5.0e4, 1.1e5, "sea level to about 5500 m altitude"),
    "G_solar": (0.0, 1400.0, "the solar constant, 1361 W/m^2, bounds irradiance at ground"),
    "A_glass_sun": (0.0, 5.0, "projected glazing of " + _CAR_TO_BUS),
    "tau_glass": (0.0, 1.0, _FRACTION),
    "A_shell_sun": (0.0, 20.0, "projected roof and sides of " + _CAR_TO_BUS),
    "alpha_shell": (0.0, 1.0, _FRACTION),
    "Q_pass": (0.0, 6000.0, "sensible heat of up to about 60 occupants"),
    "m_moist_pass": (0.0, 1.0e-3, "moisture of up to about 60 occupants"),
    # cabin
    "C_cab": (500.0, 1.0e5, "air of 0.4-80 m^3 at 1.2 kJ/(m^3 K): " + _CAR_TO_BUS),
    "hA_int": (1.0, 2.0e4, "1-200 m^2 of interior at 1-100 W/(m^2 K)"),
    "hA_sh": (1.0, 2.0e4, "1-200 m^2 of inner shell at 1-100 W/(m^2 K)"),
    "C_int": (1.0e3, 5.0e6, "1 kg to 5 t of interior at about 1 kJ/(kg K)"),
    "C_int_slow": (1.0e3, 5.0e6, "as C_int"),
    "hA_int_slow": (0.1, 2.0e4, "as hA_int"),
    "C_sh": (1.0e3, 1.0e7, "shell steel and glass of " + _CAR_TO_BUS),
    "A_shell": (1.0, 300.0, "outer surface of " + _CAR_TO_BUS),
    "L_shell": (1.0, 25.0, "length of " + _CAR_TO_BUS),
    "h_ext_nat": (1.0, 50.0, "natural convection plus linearised radiation, 2-25 W/(m^2 K)"),
    "m_inf0": (0.0, 0.5, "below about 20 air changes per hour of a bus"),
    "k_inf": (0.0, 0.05, "as m_inf0 per m/s of vehicle speed"),
    # HVAC air side
    "c_p_air": (1000.0, 1050.0, "moist air, 1005-1030 J/(kg K)"),
    "h_fg": (2.2e6, 2.6e6, "latent heat of water between 0 and 100 degC"),
    "W_bl_min": (0.005, 1.0, "blower flows of " + _CAR_TO_BUS),
    "W_bl_max": (0.01, 3.0, "blower flows of " + _CAR_TO_BUS),
    "beta1": (-1.0e6, 1.0e6, "blower power map coefficient: within 10^4 W at 1 kg/s"),
    "beta2": (-1.0e5, 1.0e5, "blower power map coefficient: within 10^4 W at 1 kg/s"),
    "beta3": (-1.0e4, 1.0e4, "blower power offset within 10 kW"),
    "f_bl_heat": (0.0, 1.0, _FRACTION),
    "k_rec": (0.0, 10.0, "saturates within 0.1-100 K of ambient-cabin difference"),
    "r_max": (0.0, 1.0, _FRACTION),
    # evaporator
    "C_ew": (100.0, 1.0e6, "0.1 kg to a bus's 1 t of aluminium and refrigerant"),
    "UA_ea0": (10.0, 1.0e5, "evaporator air sides of " + _CAR_TO_BUS),
    "W_ea0": (0.01, 3.0, "a reference blower flow (W_bl range)"),
    "n_ea": (0.0, 1.5, "Reynolds exponents of heat-transfer correlations lie in 0.3-1"),
    "UA_er0": (100.0, 1.0e6, "refrigerant sides of " + _CAR_TO_BUS),
    "m_r0": (0.001, 2.0, "refrigerant flows of " + _CAR_TO_BUS),
    "n_r": (0.0, 1.5, "as n_ea"),
    "dT_suc0": (0.0, 10.0, "suction lines are sized for about 1 K, never 10 K"),
    # condenser / front end
    "C_cw": (100.0, 1.0e6, "as C_ew"),
    "UA_cr0": (50.0, 1.0e6, "refrigerant sides of " + _CAR_TO_BUS),
    "UA_ca0": (50.0, 2.0e5, "condenser air sides of " + _CAR_TO_BUS),
    "m_ca0": (0.05, 50.0, "front-end air flows of " + _CAR_TO_BUS),
    "n_ca": (0.0, 1.5, "as n_ea"),
    "A_cond": (0.02, 5.0, "condenser faces of " + _CAR_TO_BUS),
    "K_front": (1.0, 1.0e4, "front-end resistances of 5-5000 Pa at the design flow"),
    "C_ram": (0.0, 1.5, "ram pressure recovery, below about 1"),
    "dp_fan0": (10.0, 3000.0, "axial fan shut-off pressures"),
    "Q_fan_free": (0.01, 50.0, "fan free deliveries of " + _CAR_TO_BUS),
    "K_fan_off": (0.1, 1.0e4, "as K_front"),
    "s_fan_low": (0.0, 1.0, _FRACTION),
    "eta_fan": (0.01, 1.0, "an efficiency"),
    "v_fan_off": (0.0, 60.0, "vehicle speeds, m/s"),
    "p_fan_high": (2.0e5, 6.0e6, "head pressures of R134a/R1234yf, 2-60 bar"),
    "p_fan_low": (1.0e5, 6.0e6, "as p_fan_high"),
    "dT_recirc": (0.0, 20.0, "hot-air recirculation of a few K"),
    "v_recirc": (0.1, 60.0, "vehicle speeds, m/s"),
    # compressor / cycle
    "V_disp": (5.0e-6, 5.0e-4, "5-500 cm^3: car scrolls (20-35 cc) to bus compressors"),
    "N_min": (100.0, 5000.0, "compressor speeds, rpm"),
    "N_max": (500.0, 20000.0, "compressor speeds, rpm"),
    "tau_N": (0.05, 60.0, "motor and inverter speed responses"),
    "superheat": (0.5, 30.0, "a vapour suction state, a few K of superheat"),
    "subcool": (0.0, 30.0, "a few K of subcooling"),
    "eta_v0": (0.3, 1.0, "a volumetric efficiency"),
    "k_v": (0.0, 0.2, "efficiency loss per unit pressure ratio"),
    "c_L": (0.0, 3000.0, "leakage as an rpm equivalent, below N_min"),
    "eta_is_max": (0.2, 1.0, "an isentropic efficiency"),
    "k_is": (0.0, 0.5, "efficiency curvature in the pressure ratio"),
    "PR_opt": (1.2, 10.0, "pressure ratios of an A/C cycle"),
    "c_is_lo": (0.0, 5000.0, "as c_L"),
    "c_is_hi": (0.0, 0.5, "an efficiency loss"),
    "P_loss0": (0.0, 5000.0, "inverter and motor losses of " + _CAR_TO_BUS),
    "P_loss_N": (0.0, 1.0e4, "as P_loss0"),
    "P_loss_cu": (0.0, 1.0e4, "as P_loss0"),
    "P_rated": (200.0, 1.0e5, "shaft powers of " + _CAR_TO_BUS),
    # nominal controller
    "T_cab_set": (283.15, 308.15, "cabin set-points, 10-35 degC"),
    "T_ew_set": (268.15, 293.15, "evaporator set-points, -5 to 20 degC"),
    "T_ew_set_max": (268.15, 298.15, "evaporator set-points, -5 to 25 degC"),
    "k_reset": (0.0, 1.0, "reset rates of at most 1 K/s per K"),
    "Kp_comp": (0.0, 1.0e5, "compressor gains, rpm/K"),
    "Ki_comp": (0.0, 1.0e4, "compressor gains, rpm/(K s)"),
    "hyst_off": (0.0, 20.0, "a hysteresis of a few K"),
    "hyst_on": (0.0, 20.0, "a hysteresis of a few K"),
    "Kp_bl": (0.0, 10.0, "blower gains, kg/s/K"),
    "Ki_bl": (0.0, 1.0, "blower gains, kg/s/(K s)"),
    "p_derate": (5.0e5, 6.0e6, "as p_fan_high"),
    "p_cut": (5.0e5, 6.0e6, "as p_fan_high"),
    "T_e_min": (243.15, 283.15, "frost limits, -30 to 10 degC"),
    "K_frost": (0.0, 1.0e5, "speed-cap gains, rpm/K"),
    # initial hot soak
    "T_cab0": (233.15, 363.15, "a soaked cabin, -40 to 90 degC"),
    "T_int0": (233.15, 373.15, "sun-heated seats and dash, up to 100 degC"),
    "T_shell0": (233.15, 373.15, "as T_int0"),
    "T_ew0": (233.15, 363.15, "as T_cab0"),
    "T_cw0": (233.15, 363.15, "as T_cab0"),
    # solver
    "Ts": (0.1, 60.0, "sample periods of a climate controller"),
    "dt_int": (1.0e-3, 60.0, "internal steps; also Ts / dt_int <= MAX_SUBSTEPS"),
}
_UNITS: dict[str, str] = {}
#: most internal steps per sample (Ts / dt_int): plant-check's 0.01 s reference at the
#: longest Ts (60 s) is 6000; 1e-6 s would run for days
MAX_SUBSTEPS = 10_000


def config_field(default, unit: str, section: str, source: str):
    """A configuration field with its unit, section and source in the field metadata."""
    return field(default=default, metadata={"unit": unit, "section": section, "source": source})


_p = config_field


_ASSUMED = "assumption"


def _file_temperature(key: str, value, source: str):
    """A temperature field of a plant file in K: a plain number is degC (a difference: K), a
    string is ``"NUMBER UNIT"`` with a temperature unit of ``acid.units.UNIT_SCALES``. Anything
    else is returned as is (``from_dict`` names its type)."""
    difference = key in TEMPERATURE_DIFFERENCES
    if isinstance(value, str):
        number, _, unit = value.strip().partition(" ")
        unit = unit.strip()
        try:
            x = float(number)
        except ValueError:
            x = math.nan
        scale = UNIT_SCALES.get(unit)
        if not math.isfinite(x) or scale is None or scale[0] != "K":
            temperature_units = ", ".join(u for u, (b, _, _) in UNIT_SCALES.items() if b == "K")
            raise ConfigError(f"{source}: {key} = {value!r}: give a number or \"NUMBER UNIT\" "
                              f"with a temperature unit ({temperature_units})")
        if difference:
            return x * scale[1]          # a difference: the unit's size, no offset
        return x * scale[1] + scale[2]
    if difference or isinstance(value, bool) or not isinstance(value, (int, float)):
        return value
    x = _finite(key, value, source)
    lo, hi = FILE_DEGC_RANGE
    if not lo <= x <= hi:
        raise ConfigError(f"{source}: {key} = {x:g} is read in degC (plant files give "
                          f"temperatures in degC) and lies outside {lo:g}..{hi:g} degC; if "
                          f"kelvin is meant, write {key} = \"{x:g} K\"")
    return C2K(x)


def _finite(key: str, value, source: str) -> float:
    """``value`` as a finite float, else one line naming ``key`` (an integer too large for a
    float included)."""
    try:
        x = float(value)
    except OverflowError:
        x = math.inf
    if not math.isfinite(x):
        shown = "an integer too large" if isinstance(value, int) else repr(value)
        raise ConfigError(f"{source}: {key} must be a finite number, got {shown}")
    return x


@dataclass(frozen=True)
class PlantConfig:
    """All parameters of ``acid.plant.hifi.HifiPlant`` (SI units, temperatures in K).

    The unit, section and source of each field are in its dataclass metadata and in
    ``parameter_table()``. Build variants with ``replace(**changes)`` or ``from_toml(path)``;
    both validate (``ConfigError`` with a one-line message).
    """

    # ---------------------------------------------------------------- ambient / boundary
    T_amb: float = _p(303.15, "K", "ambient", "[Wang2018] Table II (30 degC)")
    RH_amb: float = _p(0.5, "1", "ambient", "assumption: 50 % relative humidity")
    p_atm: float = _p(101325.0, "Pa", "ambient", "standard atmosphere")
    G_solar: float = _p(850.0, "W/m^2", "ambient",
                        "[CFR86.161] SC03 solar load 850 W/m^2; sweep 0-1000 W/m^2 maps here")
    A_glass_sun: float = _p(0.9, "m^2", "ambient",
                            "assumption: sunlit glazing area projected normal to the sun "
                            "(windshield + share of side glass of a compact car)")
    tau_glass: float = _p(0.5, "1", "ambient",
                          "[CARB2009] total solar transmittance of a windshield, TST <= 50 %")
    A_shell_sun: float = _p(1.8, "m^2", "ambient",
                            "assumption: sunlit opaque area projected normal to the sun (roof "
                            "about 1.5 m^2 plus share of pillars and upper doors)")
    alpha_shell: float = _p(0.6, "1", "ambient",
                            "assumption: solar absorptance of a mid-colour paint (0.3 white to "
                            "0.95 black, [Levinson2011])")
    Q_pass: float = _p(80.0, "W", "ambient", "assumption: sensible heat of one occupant")
    m_moist_pass: float = _p(1.4e-5, "kg/s", "ambient",
                             "assumption: moisture of one occupant (about 50 g/h)")

    # ---------------------------------------------------------------- cabin
    C_cab: float = _p(3877.0, "J/K", "cabin",
                      "[Wang2018] gamma3: c_p Ts / gamma3 (about 3.3 m^3 of air)")
    hA_int: float = _p(190.0, "W/K", "cabin", "[Wang2018] gamma1: gamma1 C_cab / Ts")
    hA_sh: float = _p(67.2, "W/K", "cabin", "[Wang2018] gamma2: gamma2 C_cab / Ts")
    C_int: float = _p(35.0e3, "J/K", "cabin",
                      "assumption: fast interior node (seat covers, dash skin, trim surfaces) "
                      "that the cabin air sees; with C_int_slow 125 kJ/K in all, inside the "
                      "100-150 kJ/K of the design")
    C_int_slow: float = _p(90.0e3, "J/K", "cabin",
                           "assumption: slow interior node (seat foam cores, dash substrate, "
                           "floor); see C_int")
    hA_int_slow: float = _p(60.0, "W/K", "cabin",
                            "assumption: conduction fast -> slow interior node (time constant "
                            "C_int_slow / hA_int_slow = 25 min)")
    C_sh: float = _p(80.0e3, "J/K", "cabin",
                     "assumption from masses: ~100 kg steel x 460 + ~25 kg glass x 840 + "
                     "~15 kg trim x "
                      "1500 J/(kg K), about 80 kJ/K")
    A_shell: float = _p(9.0, "m^2", "cabin",
                        "assumption: outer cabin surface swept by the air stream (roof 1.6, sides "
                        "2 x 2.5, windshield 1.1, rear glass 0.8, pillars; design range about 10)")
    L_shell: float = _p(4.0, "m", "cabin", "assumption: flow length along the car (its length)")
    h_ext_nat: float = _p(9.0, "W/(m^2 K)", "cabin",
                          "assumption: parked outer coefficient, natural convection + "
                          "linearised radiation (design range 8-10)")
    m_inf0: float = _p(0.001, "kg/s", "cabin",
                       "[Knibbs2009], [Ott2008]: closed, parked cabins about 0-1.4 air changes "
                       "per hour; 1 ACH of 3.3 m^3")
    k_inf: float = _p(2.0e-4, "kg/s/(m/s)", "cabin",
                      "[Ott2008]: linear in speed, below 6.6 ACH at 32-116 km/h with windows "
                      "closed and fan off; 5.7 ACH at 25 m/s here")

    # ---------------------------------------------------------------- HVAC air side
    c_p_air: float = _p(_TABLE_II.c_p, "J/(kg K)", "hvac", "[Wang2018] Table II")
    h_fg: float = _p(2.45e6, "J/kg", "hvac", "latent heat of water near 20 degC")
    W_bl_min: float = _p(0.05, "kg/s", "hvac", "[Wang2018] Table II")
    W_bl_max: float = _p(0.15, "kg/s", "hvac", "[Wang2018] Table II")
    beta1: float = _p(_PAPER_MODEL.beta[0], "W s^2/kg^2", "hvac", "[Wang2018] eq. 5")
    beta2: float = _p(_PAPER_MODEL.beta[1], "W s/kg", "hvac", "[Wang2018] eq. 5")
    beta3: float = _p(_PAPER_MODEL.beta[2], "W", "hvac", "[Wang2018] eq. 5")
    f_bl_heat: float = _p(1.0, "1", "hvac",
                          "assumption: share of the blower's electric power that ends as heat in "
                          "the air ahead of the evaporator (motor in the air stream)")
    k_rec: float = _p(0.1, "1/K", "hvac",
                      "assumption: recirculation r = sat(k_rec (T_amb - T_cab), 0, r_max); the "
                      "paper only says proportional and saturated")
    r_max: float = _p(0.8, "1", "hvac", "assumption: fresh-air minimum of 20 %")

    # ---------------------------------------------------------------- evaporator
    C_ew: float = _p(2000.0, "J/K", "evaporator", "assumption: ~2 kg aluminium + refrigerant")
    UA_ea0: float = _p(280.0, "W/K", "evaporator",
                       "assumption: air-side conductance at W_ea0 (epsilon about 0.94)")
    W_ea0: float = _p(0.1, "kg/s", "evaporator", "reference flow of UA_ea0")
    n_ea: float = _p(0.51, "1", "evaporator",
                     "[ChangWang1997] louvred fins j ~ Re^-0.49, so UA ~ W^0.51")
    UA_er0: float = _p(5000.0, "W/K", "evaporator",
                       "calibrated (idle low side, plant-check d) at the top of the design's "
                       "3-5 kW/K (an assumption): two-phase refrigerant side at "
                       "m_r0 (flow boiling 2-5 kW/(m^2 K) on about 1-1.5 m^2)")
    m_r0: float = _p(0.05, "kg/s", "evaporator",
                     "reference refrigerant flow of UA_er0, UA_cr0, dT_suc0 (33 cc at 8000 rpm)")
    n_r: float = _p(0.8, "1", "evaporator",
                    "[Incropera] Dittus-Boelter exponent: UA_r = UA_r0 (m_r/m_r0)^0.8")
    dT_suc0: float = _p(1.0, "K", "evaporator",
                        "calibrated (idle low side) to [ASHRAE-R]'s design value: suction line "
                        "pressure drop as a saturation-temperature drop at m_r0, "
                        "scaling with m_r^2: [ASHRAE-R] sizes suction lines for about 1 K")

    # ---------------------------------------------------------------- condenser / front end
    C_cw: float = _p(3000.0, "J/K", "condenser", "assumption: ~3 kg aluminium + refrigerant")
    UA_cr0: float = _p(2500.0, "W/K", "condenser",
                       "assumption: refrigerant side at m_r0 (mean over desuperheating and "
                       "two-phase), scaling with (m_r/m_r0)^n_r")
    UA_ca0: float = _p(1200.0, "W/K", "condenser",
                       "calibrated (E(0) of Table I, idle head pressures) at the top of "
                       "700-1200 W/K, an assumption: a compact condenser rejecting ~10 kW at "
                       "~17 K inlet difference and 1 kg/s has eps ~0.6, NTU ~0.9, UA ~900 W/K")
    m_ca0: float = _p(1.0, "kg/s", "condenser", "reference air flow of UA_ca0")
    n_ca: float = _p(0.51, "1", "condenser",
                     "[ChangWang1997] louvred fins j ~ Re^-0.49, so UA ~ m^0.51")
    A_cond: float = _p(0.25, "m^2", "condenser",
                       "assumption: condenser face area of a compact car (about 0.62 x 0.40 m)")
    K_front: float = _p(100.0, "Pa s^2/m^6", "condenser",
                        "grille + condenser + radiator resistance dp = K Q^2: 56 Pa at 3 m/s "
                        "face velocity (design range 50-100 Pa: K 89-178, an assumption)")
    C_ram: float = _p(0.5, "1", "condenser",
                      "assumption: ram pressure recovery 1/2 rho C_ram v^2 (design range 0.4-0.6)")
    dp_fan0: float = _p(200.0, "Pa", "condenser",
                        "assumption: fan shut-off pressure at full speed (design range 150-250)")
    Q_fan_free: float = _p(0.69, "m^3/s", "condenser",
                           "calibrated (idle head pressure) inside the design's idle face velocity "
                           "1.5-2.5 m/s (an assumption): fan free delivery; gives 2.48 m/s face "
                           "velocity (design range 1.5-2.5) and about 100 W of fan power")
    K_fan_off: float = _p(20.0, "Pa s^2/m^6", "condenser",
                          "assumption: resistance of the stopped, windmilling fan and shroud")
    s_fan_low: float = _p(0.6, "1", "condenser", "assumption: low fan stage, speed fraction")
    eta_fan: float = _p(0.25, "1", "condenser",
                        "assumption: fan + motor efficiency of an automotive axial fan")
    v_fan_off: float = _p(15.0, "m/s", "condenser",
                          "assumption: the fan's floor speed s_fan_low fades linearly to 0 at "
                          "this vehicle speed; above it the fan runs only on head pressure")
    p_fan_high: float = _p(1.621e6, "Pa", "condenser",
                           "[HondaPS] fan to high above 1520 kPa gauge (1621 kPa absolute)")
    p_fan_low: float = _p(1.031e6, "Pa", "condenser",
                          "[HondaPS] fan back to low below 930 kPa gauge")
    dT_recirc: float = _p(4.0, "K", "condenser",
                          "calibrated (Table I shape, idle head pressure) inside the design's "
                          "3-8 K (an assumption): idle hot-air recirculation raises the condenser "
                          "inlet air, fading linearly to 0 at v_recirc")
    v_recirc: float = _p(5.0, "m/s", "condenser", "assumption: fading by about 5 m/s")

    # ---------------------------------------------------------------- compressor / cycle
    refrigerant: str = _p("R134a", "-", "compressor", "paper era default; R1234yf option")
    V_disp: float = _p(33.0e-6, "m^3", "compressor",
                       "assumption: electric scroll, inside the 20-35 cc of the design")
    N_min: float = _p(800.0, "rpm", "compressor", "assumption: scroll minimum speed")
    N_max: float = _p(8000.0, "rpm", "compressor", "assumption: scroll maximum speed")
    tau_N: float = _p(2.0, "s", "compressor", "assumption: speed response of motor + inverter")
    superheat: float = _p(5.0, "K", "compressor", "fixed evaporator superheat (design assumption)")
    subcool: float = _p(5.0, "K", "compressor", "fixed condenser subcooling (design assumption)")
    eta_v0: float = _p(1.0, "1", "compressor",
                       "[Cuevas2010] eta_v from about 1.0 at PR 1.3 falling linearly: "
                       "eta_v = eta_v0 - k_v (PR - 1) - c_L / N")
    k_v: float = _p(0.02, "1", "compressor",
                    "[Cuevas2010] (1.0 - 0.83) / (9.7 - 1.3) = 0.020 per unit pressure ratio")
    c_L: float = _p(100.0, "rpm", "compressor",
                    "assumption inside the design's 80-150 rpm: leakage through a fixed "
                    "equivalent nozzle [Winandy2002], a loss c_L / N of displacement flow")
    eta_is_max: float = _p(0.72, "1", "compressor",
                           "[Cuevas2010] maximal isentropic efficiency 72 % at PR 2.5-2.6: "
                           "eta_is = eta_is_max - k_is (PR - PR_opt)^2 - c_is_lo / N "
                           "- c_is_hi (N / N_max)^2")
    k_is: float = _p(0.008, "1", "compressor", "assumption: off-design curvature in PR")
    PR_opt: float = _p(2.55, "1", "compressor", "[Cuevas2010] peak at PR 2.5-2.6")
    c_is_lo: float = _p(150.0, "rpm", "compressor",
                        "assumption: low-speed loss (leakage re-compression, heat) c_is_lo / N: "
                        "10-20 points below 1500 rpm (design range, shape as [Li2013])")
    c_is_hi: float = _p(0.05, "1", "compressor",
                        "assumption: port/valve pressure loss at N_max, about 5 points")
    P_loss0: float = _p(60.0, "W", "compressor",
                        "assumption: inverter + motor no-load loss (switching, control)")
    P_loss_N: float = _p(120.0, "W", "compressor",
                         "assumption: speed-proportional loss at N_max (iron, friction)")
    P_loss_cu: float = _p(150.0, "W", "compressor",
                          "assumption: copper + conduction loss at P_rated, ~ (shaft power)^2; "
                          "with P_loss0 and P_loss_N gives 0.80-0.83 at light load and 0.93 at "
                          "rated (design assumption)")
    P_rated: float = _p(4500.0, "W", "compressor", "assumption: rated shaft power at N_max")

    # ---------------------------------------------------------------- nominal controller
    T_cab_set: float = _p(295.15, "K", "controller", "assumption (brief): 22 degC")
    T_ew_set: float = _p(276.15, "K", "controller",
                         "assumption: 3 degC, lower bound of [Wang2018] Table II T_evap_set")
    T_ew_set_max: float = _p(283.15, "K", "controller",
                             "[Wang2018] Table II: evaporator set-point reset up to 10 degC")
    k_reset: float = _p(0.01, "1/s", "controller",
                        "assumption: set-point reset rate, K/s per K of cabin undershoot while "
                        "the blower sits at its minimum")
    Kp_comp: float = _p(200.0, "rpm/K", "controller", "assumption: tuned for a 20-60 s response")
    Ki_comp: float = _p(15.0, "rpm/(K s)", "controller", "assumption: tuned as Kp_comp")
    hyst_off: float = _p(2.0, "K", "controller", "paper/brief: A/C off below T_ew,set - 2 K")
    hyst_on: float = _p(1.0, "K", "controller", "paper/brief: A/C on above T_ew,set + 1 K")
    Kp_bl: float = _p(0.02, "kg/s/K", "controller", "assumption: blower PI gain")
    Ki_bl: float = _p(4.0e-4, "kg/s/(K s)", "controller", "assumption: blower PI integral gain")
    anti_windup: bool = _p(True, "-", "controller",
                           "conditional integration (False: integrators never stop, for tests)")
    p_derate: float = _p(2.6e6, "Pa", "controller",
                         "assumption: inverter derates speed above 26 bar head pressure "
                         "(design range 26-28), linearly to N_min at p_cut")
    p_cut: float = _p(3.241e6, "Pa", "controller",
                      "[HondaPS] compressor off above 3140 kPa gauge (3241 kPa absolute)")
    T_e_min: float = _p(272.15, "K", "controller",
                        "assumption: frost protection keeps the evaporating temperature above "
                        "-1 degC (design assumption)")
    K_frost: float = _p(2000.0, "rpm/K", "controller",
                        "assumption: speed cap reduction per K below T_e_min")

    # ---------------------------------------------------------------- initial hot soak
    T_cab0: float = _p(313.15, "K", "initial", "assumption: hot soak 40 degC (design range 38-42)")
    T_int0: float = _p(315.15, "K", "initial", "assumption: sun-heated seats and dash")
    T_shell0: float = _p(313.15, "K", "initial",
                         "assumption: shell at its parked equilibrium with the 40 degC soak: "
                         "(Q_solar_shell + hA_ext0 T_amb + hA_sh T_cab0) / (hA_ext0 + hA_sh)")
    T_ew0: float = _p(303.15, "K", "initial", "assumption: HVAC box at ambient after the soak")
    T_cw0: float = _p(303.15, "K", "initial", "assumption: front end at ambient")

    front_end_speed: bool = _p(True, "-", "condenser",
                               "False: the front end sees standstill at every vehicle speed (no "
                               "ram air, idle recirculation and fan staging): the speed-blind "
                               "counterfactual")
    cabin_speed: bool = _p(True, "-", "cabin",
                           "False: shell convection and infiltration at their parked values at "
                           "every speed (speed-blind counterfactual)")

    # ---------------------------------------------------------------- solver
    Ts: float = _p(5.0, "s", "solver", "[Wang2018]: sampling at 0.2 Hz")
    dt_int: float = _p(0.5, "s", "solver",
                       "internal step; 600 s energy within 0.12 % of 0.01 s "
                       "(acid plant-check, check c)")

    # ---------------------------------------------------------------- construction
    def __post_init__(self):
        if not _UNITS:
            _UNITS.update({f.name: f.metadata["unit"] for f in dataclasses.fields(self)})
        self._validate("PlantConfig")

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """Names of all parameters, in declaration order."""
        return tuple(f.name for f in dataclasses.fields(cls))

    def replace(self, **changes) -> PlantConfig:
        """A copy with some parameters changed (validated; unknown names refused)."""
        names = set(self.field_names())
        changes = dict(changes)
        for key in list(changes):
            if key in _LEGACY_ZERO and key not in names:
                switch, meaning = _LEGACY_ZERO[key]
                if changes.pop(key) != 0.0:
                    raise ConfigError(f"PlantConfig: {key} is a generation-1 parameter; only "
                                      f"{key}=0 ({meaning}) is still accepted, as {switch}=False")
                changes[switch] = False
            elif key not in names:
                raise ConfigError(f"PlantConfig: unknown parameter {key!r}")
        return dataclasses.replace(self, **changes)

    # ---------------------------------------------------------------- derived quantities
    @property
    def Q_solar_int(self) -> float:
        """Solar heat absorbed by the interior through the glazing, G A_glass tau, W."""
        return self.G_solar * self.A_glass_sun * self.tau_glass

    @property
    def Q_solar_shell(self) -> float:
        """Solar heat absorbed by the shell, G A_shell_sun alpha_shell, W."""
        return self.G_solar * self.A_shell_sun * self.alpha_shell

    @property
    def hA_ext0(self) -> float:
        """Parked shell-to-ambient conductance A_shell h_ext_nat, W/K."""
        return self.A_shell * self.h_ext_nat

    @property
    def hA_ext_v(self) -> float:
        """Forced-convection coefficient: hA_ext(v) = hA_ext0 + hA_ext_v v^0.8, W/K/(m/s)^0.8.

        Fully turbulent flat plate, [Incropera] eq. 7.38 without the laminar correction:
        Nu_L = 0.037 Re_L^0.8 Pr^(1/3), so h = 0.037 (k/L) Pr^(1/3) (v L / nu)^0.8.
        Zero when ``cabin_speed`` is False.
        """
        if not self.cabin_speed:
            return 0.0
        return (self.A_shell * 0.037 * K_AIR / self.L_shell * PR_AIR ** (1.0 / 3.0)
                * (self.L_shell / NU_AIR) ** 0.8)

    def hA_ext(self, v_veh: float) -> float:
        """Shell-to-ambient conductance at vehicle speed ``v_veh`` (m/s), W/K."""
        return self.hA_ext0 + self.hA_ext_v * max(float(v_veh), 0.0) ** 0.8

    @classmethod
    def from_dict(cls, d: dict, source: str = "plant config") -> PlantConfig:
        """Build from a flat dict or one grouped by section (as in a TOML file)."""
        meta = {f.name: f.metadata["section"] for f in dataclasses.fields(cls)}
        flat: dict = {}
        for key, value in d.items():
            if isinstance(value, dict):
                if key not in SECTIONS:
                    raise ConfigError(f"{source}: unknown section [{key}] "
                                      f"(known: {', '.join(SECTIONS)})")
                for sub, v in value.items():
                    if sub not in meta:
                        raise ConfigError(f"{source}: unknown key {sub!r} in [{key}]")
                    if meta[sub] != key:
                        raise ConfigError(f"{source}: key {sub!r} belongs in [{meta[sub]}], "
                                          f"not [{key}]")
                    flat[sub] = v
            elif key not in meta:
                raise ConfigError(f"{source}: unknown key {key!r}")
            else:
                flat[key] = value
        for key, v in flat.items():
            default = getattr(cls, key)
            if isinstance(default, bool):
                if not isinstance(v, bool):
                    raise ConfigError(f"{source}: {key} must be true or false, got {v!r}")
            elif isinstance(default, str):
                if not isinstance(v, str):
                    raise ConfigError(f"{source}: {key} must be a string, got {v!r}")
            elif isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ConfigError(f"{source}: {key} must be a number, got {v!r}")
            else:
                flat[key] = float(v) if isinstance(v, float) else _finite(key, v, source)
        try:
            return cls(**flat)
        except ConfigError as exc:
            raise ConfigError(str(exc).replace("PlantConfig:", f"{source}:", 1)) from None

    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> PlantConfig:
        """Read a TOML plant configuration (keys as in ``parameter_table()``; temperatures in
        degC or unit-tagged, see ``from_file_dict``)."""
        from acid._readers import load_toml

        path = Path(path)
        d = load_toml(path, "plant configuration", ConfigError)
        if not d:   # an empty (or truncated to nothing) file is not a choice of the defaults
            raise ConfigError(f"{path}: the plant configuration is empty (no keys); for the "
                              "defaults name a vehicle ('default', 'paper') instead")
        return cls.from_file_dict(d, str(path))

    @classmethod
    def from_file_dict(cls, d: dict, source: str = "plant config") -> PlantConfig:
        """Build from a dict as a user's file gives it (flat or by section): absolute
        temperatures in degC as plain numbers, or tagged strings (``"35 degC"``,
        ``"308.15 K"``, any temperature unit of ``acid.units.UNIT_SCALES``); temperature
        differences (``TEMPERATURE_DIFFERENCES``) in K, plain or ``"5 K"``."""
        units = {f.name: f.metadata["unit"] for f in dataclasses.fields(cls)}

        def convert(key: str, value):
            if units.get(key) != "K":
                return value
            return _file_temperature(key, value, source)

        si = {key: ({sub: convert(sub, v) for sub, v in value.items()}
                    if isinstance(value, dict) else convert(key, value))
              for key, value in d.items()}
        return cls.from_dict(si, source)

    def to_dict(self) -> dict:
        """Flat, JSON-serialisable dict of all parameters (SI units, K)."""
        return {name: getattr(self, name) for name in self.field_names()}

    def to_file_dict(self) -> dict:
        """Flat dict of all parameters as a plant file gives them (what a user reads): absolute
        temperatures in degC, everything else as ``to_dict``; ``from_file_dict`` reads it back."""
        return self.in_file_units(self.to_dict())

    @classmethod
    def in_file_units(cls, d: dict) -> dict:
        """A copy of a flat dict keyed by parameter names (``to_dict``, a plant's
        ``config()``) with the absolute temperatures in degC; other keys as they are."""
        units = {f.name: f.metadata["unit"] for f in dataclasses.fields(cls)}
        return {name: (round(float(K2C(v)), 9) if units.get(name) == "K"
                       and name not in TEMPERATURE_DIFFERENCES
                       and isinstance(v, (int, float)) and not isinstance(v, bool) else v)
                for name, v in d.items()}

    @classmethod
    def parameter_table(cls) -> list[tuple[str, str, str, str]]:
        """(name, unit, section, source) of every parameter."""
        return [(f.name, f.metadata["unit"], f.metadata["section"], f.metadata["source"])
                for f in dataclasses.fields(cls)]

    # ---------------------------------------------------------------- validation
    def _validate(self, source: str) -> None:
        def bad(msg: str):
            raise ConfigError(f"{source}: {msg}")

        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if f.metadata["unit"] == "-":
                continue
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
                bad(f"{f.name} must be a finite number, got {v!r}")
            if f.metadata["unit"] == "K" and f.name not in TEMPERATURE_DIFFERENCES:
                if not 150.0 < v < 450.0:
                    bad(f"{f.name} = {v} K is implausible (temperatures are in kelvin)")
        if not 233.15 <= self.T_amb <= 330.15:
            bad(f"T_amb = {K2C(self.T_amb):.6g} degC is outside the refrigerant property "
                "tables (-40 to 57 degC)")
        if self.refrigerant not in REFRIGERANTS:
            bad(f"refrigerant {self.refrigerant!r} not supported (choose "
                f"{' or '.join(REFRIGERANTS)})")
        positive = ("C_cab", "C_int", "C_int_slow", "C_sh", "C_ew", "C_cw", "hA_int", "hA_sh",
                    "hA_int_slow", "A_shell", "L_shell", "h_ext_nat", "c_p_air", "h_fg",
                    "UA_ea0", "W_ea0", "UA_er0", "UA_cr0", "m_r0", "UA_ca0", "m_ca0", "A_cond",
                    "K_front", "dp_fan0", "Q_fan_free", "K_fan_off", "s_fan_low", "eta_fan",
                    "v_recirc", "V_disp", "tau_N", "eta_v0", "eta_is_max", "P_rated", "Ts",
                    "dt_int", "p_atm", "W_bl_min", "p_fan_high", "p_fan_low", "p_derate",
                    "p_cut")
        for name in positive:
            if getattr(self, name) <= 0.0:
                bad(f"{name} must be positive, got {getattr(self, name)}")
        nonneg = ("G_solar", "A_glass_sun", "tau_glass", "A_shell_sun", "alpha_shell",
                  "Q_pass", "m_moist_pass", "m_inf0", "k_inf", "f_bl_heat", "k_rec", "r_max",
                  "n_ea", "n_r", "n_ca", "dT_suc0", "C_ram", "v_fan_off", "dT_recirc",
                  "superheat", "subcool", "k_v", "c_L", "k_is", "c_is_lo", "c_is_hi",
                  "P_loss0", "P_loss_N", "P_loss_cu", "k_reset", "K_frost", "Kp_comp",
                  "Ki_comp", "hyst_off", "hyst_on", "Kp_bl", "Ki_bl")
        for name in nonneg:
            if getattr(self, name) < 0.0:
                bad(f"{name} must not be negative, got {getattr(self, name)}")
        for lo, hi in (("W_bl_min", "W_bl_max"), ("N_min", "N_max"), ("T_ew_set", "T_ew_set_max"),
                       ("p_fan_low", "p_fan_high"), ("p_derate", "p_cut")):
            if not getattr(self, lo) < getattr(self, hi):
                bad(f"bounds out of order: {lo} = {getattr(self, lo)} must be below "
                    f"{hi} = {getattr(self, hi)}")
        if self.N_min <= 0.0:
            bad(f"N_min must be positive, got {self.N_min}")
        for name in ("RH_amb", "r_max", "tau_glass", "alpha_shell", "f_bl_heat", "s_fan_low"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                bad(f"{name} must lie in [0, 1], got {getattr(self, name)}")
        for name in ("eta_v0", "eta_is_max", "eta_fan"):
            if getattr(self, name) > 1.0:
                bad(f"{name} must not exceed 1, got {getattr(self, name)}")
        for name, (lo, hi, why) in RANGES.items():
            v = getattr(self, name)
            if not lo <= v <= hi:
                unit = _UNITS.get(name, "")
                if unit == "K" and name not in TEMPERATURE_DIFFERENCES:  # degC, as in files
                    v, lo, hi, unit = K2C(v), K2C(lo), K2C(hi), "degC"
                unit = "" if unit in ("1", "") else " " + unit
                bad(f"{name} = {v:.6g}{unit} is outside its physical range "
                    f"{lo:.6g}..{hi:.6g}{unit} ({why})")
        ratio = self.Ts / self.dt_int
        if ratio > MAX_SUBSTEPS:
            bad(f"dt_int = {self.dt_int:g} s gives {ratio:.0f} internal steps per Ts = "
                f"{self.Ts:g} s (at most {MAX_SUBSTEPS})")
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            bad(f"dt_int = {self.dt_int} s must divide Ts = {self.Ts} s")
        if self.superheat < 0.5:
            bad(f"superheat = {self.superheat} K is too small for a vapour suction state "
                "(use at least 0.5 K)")
