"""Configuration of the high-fidelity plant: every parameter with its unit and its source.

``PlantConfig()`` is the frozen default calibration documented in ``/work/shared/PLANT.md``.
Parameters anchored in the paper (Wang et al., ACC 2018) say so in their ``source``; all
others are engineering assumptions for a compact electric vehicle, labelled as such, and were
chosen (once, then frozen) so that the nominal-controller speed sweep lands in the bands of the
paper's Table I (``acid.plant.sweep``).

Units are SI with **temperatures in kelvin** (the library's inside), also in TOML files::

    # my_plant.toml -- flat keys or grouped by section, units as in ``parameter_table()``
    refrigerant = "R1234yf"
    [ambient]
    T_amb = 308.15      # K (35 degC)
    RH_amb = 0.4

A temperature below 150 K is refused (it was almost certainly written in degC).
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from acid.claims import MODEL as _PAPER_MODEL
from acid.claims import TABLE_II as _TABLE_II
from acid.errors import ConfigError

REFRIGERANTS = ("R134a", "R1234yf")

SECTIONS = ("ambient", "cabin", "hvac", "evaporator", "condenser", "compressor", "controller",
            "initial", "solver")


def _p(default, unit: str, section: str, source: str):
    """A configuration field with its unit, section and source in the field metadata."""
    return field(default=default, metadata={"unit": unit, "section": section, "source": source})


_ASSUMED = "assumption"


@dataclass(frozen=True)
class PlantConfig:
    """All parameters of ``acid.plant.hifi.HifiPlant`` (SI units, temperatures in K).

    The unit, section and source of each field are in its dataclass metadata and in
    ``parameter_table()``. Build variants with ``replace(**changes)`` or ``from_toml(path)``;
    both validate (``ConfigError`` with a one-line message).
    """

    # ---------------------------------------------------------------- ambient / boundary
    T_amb: float = _p(303.15, "K", "ambient", "paper Table II (30 degC)")
    RH_amb: float = _p(0.5, "1", "ambient", "assumption: 50 % relative humidity (PLANT.md)")
    p_atm: float = _p(101325.0, "Pa", "ambient", "standard atmosphere")
    Q_solar_int: float = _p(350.0, "W", "ambient",
                            "assumption: solar gain absorbed by seats/dash through the glass")
    Q_solar_shell: float = _p(900.0, "W", "ambient",
                              "assumption: solar gain absorbed by roof, doors and glass "
                              "(~1.5 m^2 roof x 800 W/m^2 x 0.6 + sides); keeps T_shell above "
                              "T_amb under sun")
    Q_pass: float = _p(80.0, "W", "ambient", "assumption: sensible heat of one occupant")
    m_moist_pass: float = _p(1.4e-5, "kg/s", "ambient",
                             "assumption: moisture of one occupant (about 50 g/h)")

    # ---------------------------------------------------------------- cabin
    C_cab: float = _p(3877.0, "J/K", "cabin",
                      "paper gamma3: c_p Ts / gamma3 (about 3.3 m^3 of air)")
    hA_int: float = _p(190.0, "W/K", "cabin", "paper gamma1: gamma1 C_cab / Ts")
    hA_sh: float = _p(67.2, "W/K", "cabin", "paper gamma2: gamma2 C_cab / Ts")
    C_int: float = _p(65.0e3, "J/K", "cabin", "assumption: seats, dash, panels (PLANT.md 60-70)")
    C_sh: float = _p(65.0e3, "J/K", "cabin", "assumption: roof, doors, glass (PLANT.md 60-70)")
    hA_ext0: float = _p(60.0, "W/K", "cabin",
                        "assumption: shell-to-ambient conductance at standstill")
    hA_ext_v: float = _p(9.0, "W/K/(m/s)^0.8", "cabin",
                         "assumption: forced-convection increase, hA_ext = hA_ext0 + "
                         "hA_ext_v V^0.8 (flat-plate turbulent exponent)")

    # ---------------------------------------------------------------- HVAC air side
    c_p_air: float = _p(_TABLE_II.c_p, "J/(kg K)", "hvac", "paper Table II")
    h_fg: float = _p(2.45e6, "J/kg", "hvac", "latent heat of water near 20 degC")
    W_bl_min: float = _p(0.05, "kg/s", "hvac", "paper Table II")
    W_bl_max: float = _p(0.15, "kg/s", "hvac", "paper Table II")
    beta1: float = _p(_PAPER_MODEL.beta[0], "W s^2/kg^2", "hvac", "paper eq. 5")
    beta2: float = _p(_PAPER_MODEL.beta[1], "W s/kg", "hvac", "paper eq. 5")
    beta3: float = _p(_PAPER_MODEL.beta[2], "W", "hvac", "paper eq. 5")
    k_rec: float = _p(0.1, "1/K", "hvac",
                      "assumption: recirculation r = sat(k_rec (T_amb - T_cab), 0, r_max); the "
                      "paper only says proportional and saturated")
    r_max: float = _p(0.8, "1", "hvac", "assumption: fresh-air minimum of 20 %")

    # ---------------------------------------------------------------- evaporator
    C_ew: float = _p(2000.0, "J/K", "evaporator", "assumption: ~2 kg aluminium + refrigerant")
    UA_ea0: float = _p(280.0, "W/K", "evaporator",
                       "assumption: air-side conductance at W_ea0 (epsilon about 0.94)")
    W_ea0: float = _p(0.1, "kg/s", "evaporator", "reference flow of UA_ea0")
    n_ea: float = _p(0.6, "1", "evaporator", "air-side Nusselt exponent, UA ~ W^0.6 (PLANT.md)")
    UA_er: float = _p(900.0, "W/K", "evaporator",
                      "assumption: refrigerant-side (two-phase) conductance")

    # ---------------------------------------------------------------- condenser
    C_cw: float = _p(3000.0, "J/K", "condenser", "assumption: ~3 kg aluminium + refrigerant")
    UA_cr: float = _p(1300.0, "W/K", "condenser",
                      "calibrated to Table I: refrigerant-side conductance (mean over "
                      "desuperheating and two-phase)")
    m_ca_fan: float = _p(0.9, "kg/s", "condenser",
                         "assumption (brief): condenser air by the fan at standstill")
    k_ram: float = _p(0.028, "kg/s/(m/s)", "condenser",
                      "assumption: ram air per unit vehicle speed, linear fan + ram "
                      "superposition (0.9 -> 1.6 kg/s from 0 to 25 m/s)")
    UA_ca0: float = _p(720.0, "W/K", "condenser",
                       "calibrated to Table I: air-side conductance at m_ca_fan "
                       "(epsilon 0.55 at standstill, 0.45 at 25 m/s)")
    n_ca: float = _p(0.6, "1", "condenser", "air-side exponent, UA ~ m_ca^0.6 (PLANT.md)")
    P_fan: float = _p(150.0, "W", "condenser",
                      "assumption: condenser fan (reported, not counted, as in the paper)")

    # ---------------------------------------------------------------- compressor / cycle
    refrigerant: str = _p("R134a", "-", "compressor", "paper era default; R1234yf option")
    V_disp: float = _p(33.0e-6, "m^3", "compressor", "assumption: electric scroll (PLANT.md)")
    N_min: float = _p(800.0, "rpm", "compressor", "assumption: scroll minimum speed")
    N_max: float = _p(8000.0, "rpm", "compressor", "assumption: scroll maximum speed")
    tau_N: float = _p(2.0, "s", "compressor", "assumption: speed response of motor + inverter")
    superheat: float = _p(5.0, "K", "compressor", "fixed evaporator superheat (PLANT.md)")
    subcool: float = _p(5.0, "K", "compressor", "fixed condenser subcooling (PLANT.md)")
    eta_v0: float = _p(0.95, "1", "compressor",
                       "assumption: volumetric efficiency eta_v = eta_v0 - k_v (PR - 1)")
    k_v: float = _p(0.025, "1", "compressor", "assumption: re-expansion / leakage slope")
    eta_is_max: float = _p(0.68, "1", "compressor",
                           "assumption: isentropic efficiency "
                           "eta_is = eta_is_max - k_is (PR - PR_opt)^2")
    k_is: float = _p(0.008, "1", "compressor", "assumption: off-design curvature")
    PR_opt: float = _p(3.0, "1", "compressor", "assumption: built-in pressure ratio of the scroll")
    eta_motor: float = _p(0.88, "1", "compressor", "assumption: motor + inverter efficiency")

    # ---------------------------------------------------------------- nominal controller
    T_cab_set: float = _p(295.15, "K", "controller", "assumption (brief): 22 degC")
    T_ew_set: float = _p(276.15, "K", "controller",
                         "assumption: 3 degC, lower bound of paper Table II T_evap_set")
    Kp_comp: float = _p(200.0, "rpm/K", "controller", "assumption: tuned for a 20-60 s response")
    Ki_comp: float = _p(15.0, "rpm/(K s)", "controller", "assumption: tuned as Kp_comp")
    hyst_off: float = _p(2.0, "K", "controller", "paper/brief: A/C off below T_ew,set - 2 K")
    hyst_on: float = _p(1.0, "K", "controller", "paper/brief: A/C on above T_ew,set + 1 K")
    Kp_bl: float = _p(0.02, "kg/s/K", "controller", "assumption: blower PI gain")
    Ki_bl: float = _p(4.0e-4, "kg/s/(K s)", "controller", "assumption: blower PI integral gain")
    anti_windup: bool = _p(True, "-", "controller",
                           "conditional integration (False: integrators never stop, for tests)")

    # ---------------------------------------------------------------- initial hot soak
    T_cab0: float = _p(313.15, "K", "initial", "assumption: hot soak 40 degC (PLANT.md 38-42)")
    T_int0: float = _p(315.15, "K", "initial", "assumption: sun-heated seats and dash")
    T_shell0: float = _p(315.15, "K", "initial", "assumption: sun-heated roof and glass")
    T_ew0: float = _p(303.15, "K", "initial", "assumption: HVAC box at ambient after the soak")
    T_cw0: float = _p(303.15, "K", "initial", "assumption: front end at ambient")
    RH_cab0: float = _p(0.4, "1", "initial",
                        "assumption: cabin relative humidity at T_cab0 after the soak")

    # ---------------------------------------------------------------- solver
    Ts: float = _p(5.0, "s", "solver", "paper: sampling at 0.2 Hz")
    dt_int: float = _p(0.5, "s", "solver",
                       "internal step; quartering it changes 600 s energy < 0.5 % "
                       "(tests/test_plant_hifi.py)")

    # ---------------------------------------------------------------- construction
    def __post_init__(self):
        self._validate("PlantConfig")

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """Names of all parameters, in declaration order."""
        return tuple(f.name for f in dataclasses.fields(cls))

    def replace(self, **changes) -> PlantConfig:
        """A copy with some parameters changed (validated; unknown names refused)."""
        names = set(self.field_names())
        for key in changes:
            if key not in names:
                raise ConfigError(f"PlantConfig: unknown parameter {key!r}")
        return dataclasses.replace(self, **changes)

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
                flat[key] = float(v)
        try:
            return cls(**flat)
        except ConfigError as exc:
            raise ConfigError(str(exc).replace("PlantConfig:", f"{source}:", 1)) from None

    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> PlantConfig:
        """Read a TOML plant configuration (keys as in ``parameter_table()``, SI units, K)."""
        try:
            import tomllib
        except ModuleNotFoundError:  # Python < 3.11
            import tomli as tomllib
        path = Path(path)
        if not path.is_file():
            raise ConfigError(f"{path}: plant configuration not found")
        try:
            d = tomllib.loads(path.read_text())
        except Exception as exc:
            msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise ConfigError(f"{path}: not valid TOML ({msg})") from None
        return cls.from_dict(d, str(path))

    def to_dict(self) -> dict:
        """Flat, JSON-serialisable dict of all parameters (SI units, K)."""
        return {name: getattr(self, name) for name in self.field_names()}

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
            if f.metadata["unit"] == "K" and f.name not in ("superheat", "subcool",
                                                             "hyst_off", "hyst_on"):
                if not 150.0 < v < 450.0:
                    bad(f"{f.name} = {v} K is implausible (temperatures are in kelvin)")
        if self.refrigerant not in REFRIGERANTS:
            bad(f"refrigerant {self.refrigerant!r} not supported (choose "
                f"{' or '.join(REFRIGERANTS)})")
        positive = ("C_cab", "C_int", "C_sh", "C_ew", "C_cw", "hA_int", "hA_sh", "hA_ext0",
                    "c_p_air", "h_fg", "UA_ea0", "W_ea0", "UA_er", "UA_cr", "m_ca_fan",
                    "UA_ca0", "V_disp", "tau_N", "eta_v0", "eta_is_max", "eta_motor", "Ts",
                    "dt_int", "p_atm", "W_bl_min")
        for name in positive:
            if getattr(self, name) <= 0.0:
                bad(f"{name} must be positive, got {getattr(self, name)}")
        nonneg = ("Q_solar_int", "Q_solar_shell", "Q_pass", "m_moist_pass", "hA_ext_v",
                  "k_ram", "P_fan", "k_rec", "r_max", "superheat", "subcool", "k_v", "k_is",
                  "Kp_comp", "Ki_comp", "hyst_off", "hyst_on", "Kp_bl", "Ki_bl")
        for name in nonneg:
            if getattr(self, name) < 0.0:
                bad(f"{name} must not be negative, got {getattr(self, name)}")
        for lo, hi in (("W_bl_min", "W_bl_max"), ("N_min", "N_max")):
            if not getattr(self, lo) < getattr(self, hi):
                bad(f"bounds out of order: {lo} = {getattr(self, lo)} must be below "
                    f"{hi} = {getattr(self, hi)}")
        if self.N_min <= 0.0:
            bad(f"N_min must be positive, got {self.N_min}")
        for name in ("RH_amb", "RH_cab0", "r_max"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                bad(f"{name} must lie in [0, 1], got {getattr(self, name)}")
        for name in ("eta_v0", "eta_is_max", "eta_motor"):
            if getattr(self, name) > 1.0:
                bad(f"{name} must not exceed 1, got {getattr(self, name)}")
        ratio = self.Ts / self.dt_int
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            bad(f"dt_int = {self.dt_int} s must divide Ts = {self.Ts} s")
        if self.superheat < 0.5:
            bad(f"superheat = {self.superheat} K is too small for a vapour suction state "
                "(use at least 0.5 K)")
