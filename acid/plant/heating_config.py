"""Configuration of the heating plant: every parameter with its unit and its source.

``HeatingConfig()`` holds what winter adds to the cooling plant's ``PlantConfig``: the
high-voltage coolant heater with its coolant loop and heater core (as in the logged BMW i3),
the heat-pump mode of the vapour-compression loop (inner condenser, front heat exchanger as
evaporator, frosting and defrost), the windscreen glass node and the production heating
controller. The cabin, interior, shell, humidity, compressor and refrigerant parameters stay
``PlantConfig``'s (``winter_plant_config`` gives the winter boundary). Every field's ``source``
names a key of ``datasets/plant/SOURCES.md``, or says *assumption* / *from the logs* with its
reason. Units SI, temperatures in kelvin.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from acid.errors import ConfigError
from acid.plant.config import PlantConfig
from acid.plant.config import config_field as _p

#: Temperature-like fields that are differences (K), not absolute temperatures.
_DIFFERENCES = ("dT_approach", "dT_assist", "m_fog", "dm_fog", "dT_hp_off", "e_blower")


@dataclass(frozen=True)
class HeatingConfig:
    """All heating parameters of ``acid.plant.heating.HeatingPlant`` (SI units, K).

    Build variants with ``replace(**changes)`` (validated; ``ConfigError`` with one line).
    """

    # ---------------------------------------------------------------- coolant heater + loop
    P_heater_max: float = _p(5700.0, "W", "heater",
                             "[Steinstraeter2020] from the logs: the 90th percentile of the "
                             "heater's electric power in the first 5 min of cold-soak trips is "
                             "5.66-5.78 kW (brief peaks to 7 kW)")
    eta_heater: float = _p(0.98, "1", "heater",
                           "assumption: resistive/PTC element in the coolant; the 2 % are the "
                           "high-voltage electronics' losses, lost to the under-hood air")
    m_cool: float = _p(0.174, "kg/s", "heater",
                       "[Steinstraeter2020] from the logs: heater power / (c_cool x (outlet - "
                       "inlet)), median over 20 trips 0.174 kg/s (the logged flow channel reads "
                       "about -0.2, unusable)")
    c_cool: float = _p(3500.0, "J/(kg K)", "heater",
                       "[ASHRAE-F] 50 % ethylene glycol-water, about 3.3-3.6 kJ/(kg K) at "
                       "20-60 degC")
    C_cool: float = _p(10.0e3, "J/K", "heater",
                       "from the logs [Steinstraeter2020]: the heater-core coolant rises about "
                       "51 K in 2 min at 5.6 kW (trip B27) while the air takes 1-2 kW, so "
                       "8.5-11 kJ/K (about 2 l of coolant plus heater and core metal)")
    UA_hc0: float = _p(80.0, "W/K", "heater",
                       "[Steinstraeter2020] from the logs: heater-core air-side conductance at "
                       "W_hc0; holding, coolant about 50 degC and the 14 outlets' mean 31-37 "
                       "degC give an effectiveness of 0.4 (full recirculation) to 0.65 (fresh "
                       "air); 80 W/K gives 0.61 at 0.07 kg/s, inside that bound (the summer "
                       "cabin needed 120 W/K, effectiveness 0.76, beyond it)")
    W_hc0: float = _p(0.1, "kg/s", "heater", "reference air flow of UA_hc0")
    n_hc: float = _p(0.51, "1", "heater",
                     "[ChangWang1997] louvred fins j ~ Re^-0.49, so UA ~ W^0.51")
    UA_cool_loss: float = _p(5.0, "W/K", "heater",
                             "assumption: insulated hoses and heater to the under-hood air")

    # ---------------------------------------------------------------- heat pump
    heat_pump: bool = _p(True, "-", "heatpump",
                         "True: the vapour-compression loop can run as a heat pump (the logged "
                         "i3 ran its coolant heater only: AirCon Power about 0 in every trip)")
    UA_ic0: float = _p(250.0, "W/K", "heatpump",
                       "assumption: inner-condenser air-side conductance at W_hc0 (a compact "
                       "core like the evaporator's, effectiveness about 0.9)")
    UA_icr0: float = _p(1500.0, "W/K", "heatpump",
                        "assumption: inner-condenser refrigerant side at PlantConfig.m_r0 "
                        "(smaller than the front condenser's 2500 W/K)")
    C_icw: float = _p(1500.0, "J/K", "heatpump", "assumption: ~1.5 kg aluminium + refrigerant")
    UA_or0: float = _p(3000.0, "W/K", "heatpump",
                       "assumption: front heat exchanger as a two-phase evaporator at m_r0 "
                       "(the design's 3-5 kW/K for evaporators, bottom)")
    k_is_hp: float = _p(0.003, "1", "heatpump",
                        "assumption: off-design curvature of the compressor's isentropic "
                        "efficiency in pressure ratio for heat-pump duty (PR 5-10); "
                        "PlantConfig.k_is = 0.008 (an assumption for PR 2-5) would give "
                        "eta_is 0.28 at PR 10, below the 118-test scroll map of [Cuevas2010] "
                        "(tests to PR 9.7); 0.003 gives 0.55 there")
    C_ow: float = _p(3000.0, "J/K", "heatpump",
                     "assumption: the front heat exchanger (as PlantConfig.C_cw)")
    s_fan_hp: float = _p(1.0, "1", "heatpump",
                         "assumption: the front fan at full speed while the heat pump runs")
    T_hp_min: float = _p(253.15, "K", "heatpump",
                         "[Qin2014]: an EV heat pump tested down to -20 degC (COP above 1.7 "
                         "there); below it the coolant heater alone heats")
    dT_hp_off: float = _p(3.0, "K", "heatpump",
                          "assumption: compressor off when the inner-condenser air exceeds its "
                          "target by this at minimum speed")

    # ---------------------------------------------------------------- frost and defrost
    h_sg: float = _p(2.834e6, "J/kg", "frost", "[ASHRAE-F] latent heat of sublimation at 0 degC")
    h_sf: float = _p(3.34e5, "J/kg", "frost", "[ASHRAE-F] latent heat of fusion of ice")
    M_frost_def: float = _p(0.6, "kg", "frost",
                            "assumption: frost mass that starts a defrost (about 0.4 mm of "
                            "150 kg/m^3 frost on the ~10 m^2 fin surface of a compact coil)")
    a_frost: float = _p(0.8, "1", "frost",
                        "calibrated to [Zhang2025]'s ~30 % heating-capacity loss at defrost "
                        "initiation: air-side conductance G = G0 (1 - a_frost M / M_frost_def)")
    P_defrost: float = _p(2000.0, "W", "frost",
                          "assumption: compressor power in hot-gas defrost, all of it to the "
                          "coil; no heat to the cabin meanwhile")
    T_defrost_end: float = _p(278.15, "K", "frost",
                              "assumption: defrost ends with the coil ice-free at +5 degC")
    t_defrost_max: float = _p(600.0, "s", "frost", "assumption: defrost time-out")

    # ---------------------------------------------------------------- windscreen
    A_ws: float = _p(1.1, "m^2", "glass",
                     "PlantConfig.A_shell's windshield share (1.1 of 9 m^2): split off the "
                     "shell as its own node")
    C_ws: float = _p(11.0e3, "J/K", "glass",
                     "assumption from mass: 1.1 m^2 x 4.8 mm laminated glass x 2500 kg/m^3 x "
                     "840 J/(kg K)")
    h_ws_in: float = _p(8.0, "W/(m^2 K)", "glass",
                        "[Incropera] inner surface: free convection 2-25 W/(m^2 K) plus "
                        "radiation; assumption 8")
    f_def0: float = _p(0.2, "1", "glass",
                       "assumption: share of the supply air sent to the defrost outlets in "
                       "normal heating (the air near the glass mixes it with the cabin air)")
    f_def_max: float = _p(0.7, "1", "glass",
                          "assumption: share in anti-fog (defrost) mode")
    n_pass: float = _p(1.0, "1", "glass",
                       "occupants: PlantConfig.Q_pass and m_moist_pass are per occupant")

    # ---------------------------------------------------------------- winter cabin envelope
    A_glass: float = _p(3.0, "m^2", "envelope",
                        "assumption from the i3's body (4.0 x 1.78 x 1.58 m, [BMW-i3]): "
                        "windshield 1.1 (A_ws), four side windows about 1.4, tailgate glass "
                        "about 0.5; glazing carries no trim")
    R_trim: float = _p(0.25, "m^2 K/W", "envelope",
                       "[ASHRAE-F] fibrous and foam insulation 0.035-0.045 W/(m K): about 10 mm "
                       "of headliner, door-trim felt and carpet underlay (thickness an "
                       "assumption) between the cabin air's inner film and the opaque skin; the "
                       "i3's CFRP passenger cell [BMW-i3] adds 0.002-0.008 m^2 K/W (3 mm at "
                       "0.4-1.3 W/(m K) through the thickness [CFRP-k]). The summer shell "
                       "(PlantConfig.hA_sh, the paper's gamma2) is one film with no layer: "
                       "in winter the whole cabin-outside difference lies across it")

    # ---------------------------------------------------------------- production controller
    T_heat_set: float = _p(296.15, "K", "controller",
                           "[Steinstraeter2020] from the logs: warm cabins hold 23-24 degC")
    Kp_sup: float = _p(3.0, "1", "controller",
                       "assumption: supply-air target = set + Kp_sup (set - cabin) + integral")
    Ki_sup: float = _p(0.005, "1/s", "controller", "assumption: integral of the cabin error")
    T_sup_max: float = _p(331.15, "K", "controller",
                          "assumption: 58 degC supply-air target maximum (the logs' foot vents "
                          "reach 55-58 degC in warm-up)")
    dT_approach: float = _p(10.0, "K", "controller",
                            "[Steinstraeter2020] from the logs: coolant 65-68 degC while the "
                            "foot vents run 55-58 degC in warm-up; coolant target = supply-air "
                            "target + 10 K")
    Kp_heater: float = _p(600.0, "W/K", "controller",
                          "assumption: heater power on the coolant-temperature error")
    Ki_heater: float = _p(10.0, "W/(K s)", "controller", "assumption: its integral gain")
    Kp_hp: float = _p(300.0, "rpm/K", "controller",
                      "assumption: compressor speed on the inner-condenser outlet air error")
    Ki_hp: float = _p(10.0, "rpm/(K s)", "controller", "assumption: its integral gain")
    dT_assist: float = _p(2.0, "K", "controller",
                          "assumption: the coolant heater assists when the heat pump at full "
                          "speed leaves the supply air this far below target")
    T_coldair: float = _p(303.15, "K", "controller",
                          "assumption: cold-air prevention: the blower stays at its minimum "
                          "until the warmest heat source reaches 30 degC, full at +15 K")
    e_blower: float = _p(6.0, "K", "controller",
                         "assumption: blower rises from minimum to maximum over this cabin "
                         "error below set")
    anti_fog: bool = _p(True, "-", "controller",
                        "False: the recirculation rule without its anti-fog override (the "
                        "counterfactual of the fogging credential)")
    m_fog: float = _p(3.0, "K", "controller",
                      "assumption: anti-fog: fresh air and defrost outlets while the glass is "
                      "within m_fog of the cabin dew point")
    dm_fog: float = _p(3.0, "K", "controller",
                       "assumption: recirculation returns linearly over this further margin")

    def __post_init__(self):
        self._validate()

    # the cooling configuration's accessors, shared (they read only the dataclass fields)
    field_names = classmethod(PlantConfig.field_names.__func__)
    to_dict = PlantConfig.to_dict
    parameter_table = classmethod(PlantConfig.parameter_table.__func__)

    def replace(self, **changes) -> HeatingConfig:
        """A copy with some parameters changed (validated; unknown names refused)."""
        names = set(self.field_names())
        for key in changes:
            if key not in names:
                raise ConfigError(f"HeatingConfig: unknown parameter {key!r}")
        return dataclasses.replace(self, **changes)

    def _validate(self) -> None:
        def bad(msg: str):
            raise ConfigError(f"HeatingConfig: {msg}")

        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if f.metadata["unit"] == "-":
                if not isinstance(v, bool):
                    bad(f"{f.name} must be true or false, got {v!r}")
                continue
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
                bad(f"{f.name} must be a finite number, got {v!r}")
            if f.metadata["unit"] == "K" and f.name not in _DIFFERENCES:
                if not 150.0 < v < 450.0:
                    bad(f"{f.name} = {v} K is implausible (temperatures are in kelvin)")
            elif v < 0.0:
                bad(f"{f.name} must not be negative, got {v}")
        for name in ("m_cool", "c_cool", "C_cool", "UA_hc0", "W_hc0", "UA_ic0", "UA_icr0",
                     "C_icw", "UA_or0", "C_ow", "h_sg", "h_sf", "M_frost_def", "A_ws", "C_ws",
                     "h_ws_in", "t_defrost_max", "e_blower", "dm_fog", "A_glass"):
            if getattr(self, name) <= 0.0:
                bad(f"{name} must be positive, got {getattr(self, name)}")
        for name in ("eta_heater", "s_fan_hp", "a_frost", "f_def0", "f_def_max"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                bad(f"{name} must lie in [0, 1], got {getattr(self, name)}")
        if self.f_def0 > self.f_def_max:
            bad(f"bounds out of order: f_def0 = {self.f_def0} must not exceed "
                f"f_def_max = {self.f_def_max}")
        if self.A_glass < self.A_ws:
            bad(f"bounds out of order: A_glass = {self.A_glass} m^2 must include the "
                f"windshield A_ws = {self.A_ws} m^2")
        if self.a_frost >= 1.0:
            bad(f"a_frost = {self.a_frost} must stay below 1 (the coil would close)")


#: The winter boundary of the cabin (``PlantConfig`` fields): the logs' median ambient.
WINTER_BOUNDARY = {
    "T_amb": 278.15,  # [Steinstraeter2020] winter trips 1-9 degC, median about 5 degC
    "RH_amb": 0.8,  # assumption: humid winter air (frost needs it)
    "G_solar": 0.0,  # the logs do not measure sun: none (overcast); a lower bound on load
    "T_cab_set": 296.15,
}


def winter_plant_config(T_amb: float | None = None, base: PlantConfig | None = None,
                        **changes) -> PlantConfig:
    """The cooling plant's configuration at the winter boundary (``WINTER_BOUNDARY``), with
    ``T_amb`` (K) and further ``PlantConfig`` changes."""
    d = dict(WINTER_BOUNDARY)
    if T_amb is not None:
        d["T_amb"] = float(T_amb)
    d.update(changes)
    return (base or PlantConfig()).replace(**d)
