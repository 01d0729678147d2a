"""Road load and traction energy of an i3-class electric car over a drive cycle.

acid's plants model the climate system, not the car's motion; the whole-year study
(``acid.plant.year``) needs the traction energy of each drive cycle to say what share of the
range the climate costs. The road load is the textbook longitudinal balance at the wheels,

    F = f_rot m dv/dt + m g C_rr + 1/2 rho(T_amb) C_d A v^2        (level road, no wind),

and the battery supplies P_wheel / eta_drive while the car pulls, and takes back
f_regen eta_drive |P_wheel| while it brakes; the 12 V base load ``P_aux`` runs throughout.
The air density follows the ambient (rho = p / (R_air T)): aerodynamic drag is 18 % higher
at -10 degC than at 40 degC. Rolling resistance is held constant (cold tyres roll harder:
left out, so winter traction is, if anything, underestimated and the climate's share
overestimated).

``RoadLoad()`` is the BMW i3 (60 Ah, 2013-2016, the car of the winter and summer logs): every
field cites its source (keys of ``datasets/plant/SOURCES.md``) or says *assumption*. Its
check against the car's EPA label is ``epa_label_check``: the battery energy per km on UDDS
and HWFET at 25 degC (drive and base load) against the label's values unadjusted (/ 0.7)
and net of charging losses. SI units, temperatures in kelvin.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from acid.errors import ConfigError
from acid.plant.config import config_field as _p

#: standard gravity, m/s^2; specific gas constant of dry air, J/(kg K)
G_N, R_AIR = 9.80665, 287.05

#: the EPA label's city and highway values of the 2014 BMW i3 BEV, MPGe ([EPA-i3])
EPA_I3_MPGE = {"udds": 137.0, "hwfet": 111.0}
#: kWh per gallon of gasoline equivalent (EPA's MPGe), the label adjustment factor (the
#: label's = the dynamometer's x 0.7) and the charger's AC-to-battery efficiency band
#: (assumption: Level-2 on-board chargers 0.85-0.92; [FASTSim] takes 0.86 for its BEVs)
KWH_PER_GGE, EPA_ADJUSTMENT, CHARGER_EFFICIENCY = 33.705, 0.7, (0.85, 0.92)


@dataclass(frozen=True)
class RoadLoad:
    """Road load and drivetrain of an electric car (module docstring), SI units."""

    m: float = _p(1331.0, "kg", "road",
                  "[BMW-i3] 1195 kg kerb weight (DIN) + 136 kg, the EPA test's loaded "
                  "vehicle weight (kerb + 300 lb, [CFR86.129])")
    f_rot: float = _p(1.05, "1", "road",
                      "assumption: rotating inertia (wheels, motor, gear) as 5 % of the mass "
                      "(3-10 % for passenger cars)")
    C_d: float = _p(0.29, "1", "road", "[i3-Cd] drag coefficient of the BEV (REx 0.30)")
    A_f: float = _p(2.38, "m^2", "road",
                    "[BMW-i3] 1775 mm width x 1578 mm height x 0.85 (assumption: the frontal "
                    "area's share of the enclosing rectangle, 0.8-0.9 for passenger cars)")
    C_rr: float = _p(0.008, "1", "road",
                     "[EU-tyre-label] assumption inside the fuel-efficiency classes B-C of C1 "
                     "tyres (6.6-9.0 N/kN): the i3's 155/70 R19 low-rolling-resistance tyres")
    eta_drive: float = _p(0.85, "1", "road",
                          "assumption: battery-to-wheel efficiency over a cycle (inverter "
                          "0.95-0.97 x motor 0.90-0.95 x single-speed gear 0.97)")
    f_regen: float = _p(0.8, "1", "road",
                        "assumption: share of the braking power at the wheels that goes "
                        "through the motor (the rest: friction brakes, and no regeneration "
                        "below a few km/h)")
    P_aux: float = _p(250.0, "W", "road",
                      "[FASTSim] the 12 V base load of its BEVs (aux_kw 0.25: lights off, "
                      "controllers, pumps, infotainment); not climate, but drawn over the "
                      "whole cycle and in the EPA test")
    p_atm: float = _p(101325.0, "Pa", "road", "standard atmosphere")

    def __post_init__(self):
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0.0:
                raise ConfigError(f"RoadLoad: {f.name} must be a positive number, got {v!r}")
        for name in ("eta_drive", "f_regen"):
            if getattr(self, name) > 1.0:
                raise ConfigError(f"RoadLoad: {name} must lie in (0, 1], got "
                                  f"{getattr(self, name)}")
        if self.f_rot < 1.0:
            raise ConfigError(f"RoadLoad: f_rot must be at least 1, got {self.f_rot}")

    def air_density(self, T_amb: float) -> float:
        """Dry-air density at ``T_amb`` (K) and ``p_atm``, kg/m^3."""
        return self.p_atm / (R_AIR * T_amb)

    def traction(self, v: np.ndarray, dt: float, T_amb: float) -> Traction:
        """Traction energy of the speed trace ``v`` (m/s, each value held over ``dt`` s, as a
        drive-cycle file at 1 Hz) at ambient ``T_amb`` (K).

        The acceleration of interval k is (v[k+1] - v[k]) / dt at the interval's mean speed
        (the trace's last value starts no interval)."""
        v = np.asarray(v, dtype=float)
        if v.ndim != 1 or v.size < 2 or not np.all(np.isfinite(v)) or np.any(v < 0.0):
            raise ConfigError("traction: the speed trace must hold 2+ finite speeds >= 0 m/s")
        if not (math.isfinite(dt) and dt > 0.0):
            raise ConfigError(f"traction: the time step must be positive, got {dt}")
        a = np.diff(v) / dt
        vm = 0.5 * (v[1:] + v[:-1])
        rho = self.air_density(T_amb)
        F = (self.f_rot * self.m * a + self.m * G_N * self.C_rr * (vm > 0.0)
             + 0.5 * rho * self.C_d * self.A_f * vm * vm)
        P = F * vm  # W at the wheels
        drive = np.where(P > 0.0, P, 0.0)
        brake = np.where(P < 0.0, -P, 0.0)
        E_wheel = float(drive.sum() * dt)
        E_regen = float(brake.sum() * dt * self.f_regen * self.eta_drive)
        duration = float(vm.size * dt)
        return Traction(distance_m=float(vm.sum() * dt), duration_s=duration,
                        wheel_J=E_wheel, regen_J=E_regen,
                        battery_J=E_wheel / self.eta_drive - E_regen,
                        aux_J=self.P_aux * duration, rho_air=rho)

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Traction:
    """Traction energy of one drive cycle (``RoadLoad.traction``).

    distance_m, duration_s : the trace's distance and time.
    wheel_J : positive work at the wheels, J.
    regen_J : braking energy returned to the battery, J.
    battery_J : net battery energy of the drive, wheel_J / eta_drive - regen_J, J.
    aux_J : the 12 V base load over the cycle, P_aux duration_s, J.
    rho_air : air density used, kg/m^3.
    """

    distance_m: float
    duration_s: float
    wheel_J: float
    regen_J: float
    battery_J: float
    aux_J: float
    rho_air: float

    @property
    def Wh_per_km(self) -> float:
        """Battery energy of the drive and the base load per distance, Wh/km."""
        return ((self.battery_J + self.aux_J) / 3.6 / self.distance_m if self.distance_m > 0
                else math.nan)


def cycle_traction(road: RoadLoad, cycle: str, T_amb: float) -> Traction:
    """Traction energy of one pass of a shipped drive cycle (``acid.signals``) at ``T_amb``
    (K), from its 1 Hz file."""
    from acid.signals import drive_cycle

    v, spec = drive_cycle(cycle, Ts=1.0, repeat=False)
    return road.traction(np.append(v, 0.0), 1.0, T_amb)


@dataclass(frozen=True)
class LabelCheck:
    """The road load against the i3's EPA label on one cycle, battery Wh/km at 25 degC."""

    cycle: str
    model_Wh_per_km: float
    label_low_Wh_per_km: float
    label_high_Wh_per_km: float

    @property
    def passed(self) -> bool:
        return self.label_low_Wh_per_km <= self.model_Wh_per_km <= self.label_high_Wh_per_km


def epa_label_check(road: RoadLoad | None = None) -> list[LabelCheck]:
    """Battery energy per km of ``road`` (drive and base load) on UDDS and HWFET at 25 degC
    (the test cell's 20-30 degC) against the 2014 i3's EPA label: wall energy = 33.705 kWh /
    (MPGe / 0.7) per mile, times the charger's efficiency band (``CHARGER_EFFICIENCY``)."""
    road = road or RoadLoad()
    out = []
    for cycle, mpge in EPA_I3_MPGE.items():
        wall = KWH_PER_GGE * 1000.0 / (mpge / EPA_ADJUSTMENT) / 1.609344  # Wh/km from the wall
        t = cycle_traction(road, cycle, 298.15)
        out.append(LabelCheck(cycle, t.Wh_per_km, wall * CHARGER_EFFICIENCY[0],
                              wall * CHARGER_EFFICIENCY[1]))
    return out


__all__ = ["EPA_I3_MPGE", "LabelCheck", "RoadLoad", "Traction", "cycle_traction",
           "epa_label_check"]
