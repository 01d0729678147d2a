"""A connected car's day (``acid day``): parked phases, plug, charger, price, battery and the
trips, on acid's plants, and what pre-conditioning on grid power before a known departure buys.

**The day.** From 04:00 (every node of the car at the ambient: the night's soak) to the end
of the evening trip: parked at home (plugged), the morning trip (UDDS then HWFET), parked at
work (plugged on some days), the evening trip (NYCC stop-and-go then UDDS). Ambient over the
day from a city's monthly climate normals and ASHRAE's daily-range profile, sun from the
Haurwitz clear-sky model times a cloud factor; a hot day (Phoenix, July) on the cooling plant
(``acid.plant.hifi``) and a cold day (Minneapolis, January) on the heating plant
(``acid.plant.heating``, heat pump and coolant heater). Values and sources:
``datasets/plant/day.toml`` and ``datasets/plant/SOURCES.md``. Days differ by their daily
maximum, clouds, departure times and the work plug, drawn from a seeded generator.

**The plant through the day.** Parked and switched off, the plant keeps running (speed 0,
sun and ambient of the hour, sun updated every 10 minutes, nobody on board): compressor,
heater and blower off, the HVAC box's leakage flow (``W_PARKED``, an assumption) and the
cabin's infiltration the only air exchange, at a 60 s step. Pre-conditioning (nobody on
board) and driving run the plant's own production controller (5 s step). Pre-conditioning
only while plugged: its climate power and the car's 12 V base load come from the grid
through the charger (``acid.plant.battery.Charger``); driving draws traction
(``acid.plant.road_load``), base load and climate from the battery
(``acid.plant.battery.Battery``).

**Controllers** (``NoPreconditioning``, ``Timer``, ``Planner``): none (the plant's own
controller from departure); a production-style timer (the production controller from a fixed
lead before the *forecast* departure, the lead tuned on training days: the cheapest lead whose
mean discomfort over the first 10 minutes of a drive from a plug is at most
``COMFORT_TARGET_KMIN``);
and a planner that, for each plugged departure, tries each start time on the plant itself
(same weather, the forecast departure) and takes the cheapest start that meets the same
comfort target on that day, valuing grid energy at the hour's price and battery energy at the
off-peak price of recharging it over the charger.

**Accounting** (``DayOutcome``): battery, grid and total energy, cost, range lost to the
climate, comfort at departure (time to comfort, K.min outside the band), the winter fog
margin. **The study** (``day_study``): the timer tuned on training days, the three judged on
held-out days with a departure forecast error of 0, 5 and 15 minutes, paired differences with
95 % intervals read by ``acid.studies.verdict`` (``day_verdict``). SI inside (K, J, s),
degC and kWh at the edges.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field

import numpy as np
import tomllib

from acid.errors import ConfigError
from acid.plant.battery import J_PER_KWH, Battery, Charger
from acid.studies.verdict import paired_verdict
from acid.units import C2K, K2C

SEASONS = ("summer", "winter")
CONTROLLERS = ("none", "timer", "planner", "plant-search")
#: the planners the study can judge
PLANNERS = ("planner", "plant-search")
#: the day starts at 04:00 with every node at the ambient (assumption: the night's soak)
DAY_START_S = 4 * 3600.0
#: parked step, s (off plant) and the production controllers' step (the plants' 5 s)
PARKED_TS = 60.0
#: leakage air through the switched-off HVAC box, kg/s (assumption: the plants' lowest
#: accepted blower flow; the cabin's own infiltration ``m_inf0`` comes on top)
W_PARKED = 0.005
#: comfort band edge: above 26 degC in summer (the pull-down yardstick of acid's pre-cooling
#: measurements), below 20 degC in winter (assumption: the lower edge of ISO 7730's winter
#: operative range for light activity)
BAND_C = {"summer": 26.0, "winter": 20.0}
#: the comfort window after departure, s, and the target of timer and planner: mean K.min
#: outside the band over it (assumption: a cabin "ready" at departure)
COMFORT_WINDOW_S = 600.0
COMFORT_TARGET_KMIN = 1.0
#: leads the timer is tuned over and the planner chooses from, minutes
LEADS_MIN = tuple(float(x) for x in range(0, 65, 5))
QUICK_LEADS_MIN = tuple(float(x) for x in range(0, 70, 10))
#: departure forecast errors of the study (standard deviation, minutes)
FORECAST_ERRORS_MIN = (0.0, 5.0, 15.0)
#: paired intervals: fewer held-out days than this are "not resolved"
MIN_DAYS_RESOLVED = 8
#: the trips: (mean departure hour, spread min, cycles)
TRIPS = ((7.5, 20.0, ("udds", "hwfet")), (17.5, 30.0, ("nycc", "udds")))
#: probability that the car is plugged at work (assumption)
P_WORK_PLUG = 0.5
#: state of charge at 04:00 (assumption: charged overnight to the usual 90 %)
SOC_START = 0.9


# ----------------------------------------------------------------------------- the inputs
@dataclass(frozen=True)
class Climate:
    """A city's day (``datasets/plant/day.toml``): normals, humidity, sun geometry."""

    season: str
    city: str
    latitude_deg: float
    day_of_year: int
    T_max_C: float
    T_min_C: float
    RH: float
    T_max_sd_K: float
    fraction: tuple[float, ...]

    def T_amb_K(self, t_s: float, dT_max: float = 0.0) -> float:
        """Ambient at clock time ``t_s`` (s after midnight), K: ASHRAE's hourly fractions of
        the daily range (hour h at h:00, linear between), the maximum shifted by
        ``dT_max``. Remembered (:func:`_ambient_K`): the runs of one day under different
        controllers step through the same clock times."""
        return _ambient_K(self, float(t_s), float(dT_max))

    def _T_amb_K(self, t_s: float, dT_max: float) -> float:
        h = (t_s / 3600.0) % 24.0
        f = np.interp(h, np.arange(1, 26), list(self.fraction) + [self.fraction[0]],
                      period=24.0)
        T_max = self.T_max_C + dT_max
        return C2K(T_max - float(f) * (T_max - self.T_min_C))

    def G_solar(self, t_s: float, clouds: float = 1.0) -> float:
        """Global horizontal irradiance, W/m^2: Haurwitz's clear-sky model,
        1098 cos z exp(-0.057 / cos z), at solar time ``t_s``, times ``clouds`` (0-1)."""
        decl = math.radians(23.45) * math.sin(2 * math.pi * (284 + self.day_of_year) / 365)
        lat = math.radians(self.latitude_deg)
        hour_angle = math.radians(15.0 * (t_s / 3600.0 - 12.0))
        cz = (math.sin(lat) * math.sin(decl)
              + math.cos(lat) * math.cos(decl) * math.cos(hour_angle))
        if cz <= 0.01:
            return 0.0
        return clouds * 1098.0 * cz * math.exp(-0.057 / cz)


@functools.lru_cache(maxsize=1 << 16)
def _ambient_K(climate: Climate, t_s: float, dT_max: float) -> float:
    return climate._T_amb_K(t_s, dT_max)


@functools.lru_cache(maxsize=1024)
def _with_sun(config, G_solar: float):
    """``config`` with the irradiance ``G_solar`` (a frozen plant configuration: the same
    object for the same pair; building and validating one costs more than a plant step)."""
    return config.replace(G_solar=G_solar)


@dataclass(frozen=True)
class Tariff:
    """A time-of-use price, USD/kWh by hour of the day."""

    name: str
    hourly: tuple[float, ...]

    def price(self, t_s: float) -> float:
        return self.hourly[int(t_s // 3600.0) % 24]

    @property
    def off_peak(self) -> float:
        return min(self.hourly)


def _day_toml() -> dict:
    from acid.signals import datasets_dir

    with open(datasets_dir() / "plant" / "day.toml", "rb") as fh:
        return tomllib.load(fh)


def load_climate(season: str) -> Climate:
    """The hot (``summer``) or cold (``winter``) day of ``datasets/plant/day.toml``."""
    if season not in SEASONS:
        raise ConfigError(f"--season {season!r}: choose {' or '.join(SEASONS)}")
    d = _day_toml()
    s = d[season]
    return Climate(season, s["city"], float(s["latitude_deg"]), int(s["day_of_year"]),
                   float(s["T_max_C"]), float(s["T_min_C"]), float(s["RH"]),
                   float(s["T_max_sd_K"]), tuple(float(x) for x in d["daily_range"]["fraction"]))


def load_tariff() -> Tariff:
    """The time-of-use tariff of ``datasets/plant/day.toml``."""
    t = _day_toml()["tariff"]
    hourly = [float(t["off_peak_USD_per_kWh"])] * 24
    for a, b in t["partial_peak_hours"]:
        for h in range(a, b):
            hourly[h] = float(t["partial_peak_USD_per_kWh"])
    a, b = t["peak_hours"]
    for h in range(a, b):
        hourly[h] = float(t["peak_USD_per_kWh"])
    return Tariff(t["name"], tuple(hourly))


@dataclass(frozen=True)
class Trip:
    """One drive: the true departure (s after midnight, whole minutes), the forecast the
    controllers plan with, the cycles driven back to back, and whether the car stood plugged
    before it."""

    depart_s: float
    forecast_s: float
    cycles: tuple[str, ...]
    plugged: bool


@dataclass(frozen=True)
class DaySpec:
    """One day: season, the shift of the daily maximum (K), clouds (0-1), the trips, the
    battery's state of charge when the day starts (0-1 of the usable energy; no charging
    between the trips, so a low start makes a range-limited day)."""

    season: str
    index: int
    dT_max: float
    clouds: float
    trips: tuple[Trip, ...]
    soc_start: float = SOC_START

    @property
    def label(self) -> str:
        return f"{self.season} day {self.index}"


def make_days(season: str, n: int, seed: int, forecast_sd_min: float = 0.0,
              first_index: int = 0, soc_start: float = SOC_START) -> list[DaySpec]:
    """``n`` days of a season from ``numpy.random.default_rng([seed, index])``: the daily
    maximum shifted by N(0, T_max_sd), clouds U(0.7, 1) in summer and U(0.3, 1) in winter
    (assumptions), departures at the trips' mean hour + N(0, spread) in whole minutes, the
    work plug with probability ``P_WORK_PLUG``, and a forecast of each departure off by
    N(0, ``forecast_sd_min``) minutes, rounded to whole minutes (drawn from a stream of its
    own so the days are the same for every forecast error); the battery at ``soc_start``."""
    if not 0.0 < soc_start <= 1.0:
        raise ConfigError(f"--soc-start: a state of charge in (0, 1], got {soc_start:g}")
    clim = load_climate(season)
    days = []
    for i in range(first_index, first_index + n):
        rng = np.random.default_rng([seed, i])
        frng = np.random.default_rng([seed, i, 1])
        dT = float(rng.normal(0.0, clim.T_max_sd_K))
        clouds = float(rng.uniform(0.7, 1.0) if season == "summer" else rng.uniform(0.3, 1.0))
        work_plug = bool(rng.random() < P_WORK_PLUG)
        trips = []
        for k, (hour, spread, cycles) in enumerate(TRIPS):
            dep = 60.0 * round(hour * 60.0 + rng.normal(0.0, spread))
            err = 60.0 * round(float(frng.normal(0.0, 1.0)) * forecast_sd_min)
            trips.append(Trip(dep, dep + err, cycles, True if k == 0 else work_plug))
        days.append(DaySpec(season, i, dT, clouds, tuple(trips), float(soc_start)))
    return days


# ----------------------------------------------------------------------------- the plant
class _Car:
    """The day's plant: a production-controlled plant (5 s) and a switched-off one (60 s)
    sharing one state (``measure``/``reset``), the sun of the hour set on both."""

    def __init__(self, climate: Climate, day: DaySpec, t0: float):
        from acid.plant.config import PlantConfig

        self.clim, self.day = climate, day
        T0 = climate.T_amb_K(t0, day.dT_max)
        self.season = climate.season
        if self.season == "summer":
            from acid.plant.hifi import INITIAL_KEYS, HifiPlant

            cfg = PlantConfig().replace(T_amb=T0, T_cab0=T0, T_int0=T0, T_shell0=T0,
                                        T_ew0=T0, T_cw0=T0, RH_amb=climate.RH, G_solar=0.0)
            self.on = HifiPlant(cfg, mode="nominal")
            self.off = HifiPlant(cfg.replace(W_bl_min=W_PARKED, Ts=PARKED_TS, dt_int=5.0),
                                 mode="direct")
        else:
            from acid.plant.heating import INITIAL_KEYS, HeatingPlant
            from acid.plant.heating_config import HeatingConfig, winter_plant_config

            cfg = winter_plant_config(T0, RH_amb=climate.RH, G_solar=0.0)
            hc = HeatingConfig()
            self.on = HeatingPlant(hc, cfg, mode="nominal")
            self.off = HeatingPlant(hc, cfg.replace(W_bl_min=W_PARKED, Ts=PARKED_TS,
                                                    dt_int=5.0), mode="direct")
        self.keys = INITIAL_KEYS
        # nobody in the parked car: no occupant heat or moisture off the road
        empty = {"Q_pass": 0.0, "m_moist_pass": 0.0}
        self.cfg = {"off": self.off.cfg.replace(**empty), "on": self.on.cfg.replace(**empty),
                    "drive": self.on.cfg}
        self.on.reset()
        self.state = {k: v for k, v in self.on.measure().items() if k in self.keys}
        self.t = t0
        self._sun = -1.0
        #: (clock time s, cabin K) when the car last parked
        self.parked_at = (t0, float(self.state["T_cab"]))

    def _set_sun(self, plant, mode: str, t: float) -> None:
        G = round(self.clim.G_solar(t, self.day.clouds), 1)
        if plant.cfg.G_solar != G or plant.cfg.Q_pass != self.cfg[mode].Q_pass:
            plant.cfg = _with_sun(self.cfg[mode], G)

    def run(self, until: float, mode: str, v: np.ndarray | None = None) -> list[dict]:
        """Advance to ``until`` (s): ``mode`` "off" (parked, switched off), "on" (parked,
        production controller) or "drive" (production controller over speeds ``v``, one a
        5 s step). Returns the rows, each with its clock time ``t``."""
        plant = self.off if mode == "off" else self.on
        plant.reset(initial=self.state)
        rows = []
        if mode == "drive":
            n = len(v)
        elif mode == "off":  # whole parked steps, never past ``until``
            n = int(math.floor((until - self.t) / plant.Ts + 1e-9))
        else:
            n = int(round((until - self.t) / plant.Ts))
        for k in range(n):
            if k % max(1, int(600 / plant.Ts)) == 0:
                self._set_sun(plant, mode, self.t)
            T_amb = self.clim.T_amb_K(self.t, self.day.dT_max)
            speed = float(v[k]) if mode == "drive" else 0.0
            if mode == "off":
                if self.season == "summer":
                    r = plant.step(W_PARKED, plant.cfg.T_ew_set, 0.0, compressor_enabled=False,
                                   T_amb=T_amb)
                else:
                    r = plant.step(W_PARKED, 0.0, 0.0, P_heater=0.0, N_hp=0.0, recirc=1.0,
                                   pump=False, T_amb=T_amb)
            elif self.season == "summer":
                r = plant.step(0.0, plant.cfg.T_ew_set, speed, T_amb=T_amb)
            else:
                r = plant.step(0.0, 0.0, speed, T_amb=T_amb)
            r["t"] = self.t
            r["Ts"] = plant.Ts
            rows.append(r)
            self.t += plant.Ts
        self.state = {k: v for k, v in plant.measure().items() if k in self.keys}
        return rows

    def copy_state(self) -> tuple[dict, float]:
        return dict(self.state), self.t

    def restore(self, saved: tuple[dict, float]) -> None:
        self.state, self.t = dict(saved[0]), saved[1]


def _climate_W(r: dict) -> float:
    """Climate electric power of a row (compressor, heater, blower, front fan), W."""
    return (r.get("P_comp", 0.0) + r.get("P_heater", 0.0) + r.get("P_bl", 0.0)
            + r.get("P_fan", 0.0))


def _speeds(cycles: Sequence[str]) -> np.ndarray:
    from acid.signals import drive_cycle

    return np.concatenate([drive_cycle(c, Ts=5.0, repeat=False)[0] for c in cycles])


def _outside_Kmin(rows: Sequence[dict], season: str, window_s: float | None = None) -> float:
    """K.min outside the comfort band over the rows (the first ``window_s`` of them)."""
    band = C2K(BAND_C[season])
    total = 0.0
    for r in rows:
        if window_s is not None and r["t"] - rows[0]["t"] >= window_s:
            break
        excess = r["T_cab"] - band if season == "summer" else band - r["T_cab"]
        total += max(0.0, excess) * r["Ts"] / 60.0
    return total


# ----------------------------------------------------------------------------- controllers
def _lead_blocks(trip: Trip, lead_s: float) -> list[tuple[float, float]]:
    """A lead as on-blocks: the production controller from ``lead_s`` before the forecast
    departure until the car leaves."""
    return [(trip.forecast_s - lead_s, math.inf)] if lead_s > 0 else []


@dataclass(frozen=True)
class NoPreconditioning:
    """The plant's own controller from departure; switched off while parked."""

    name: str = "none"

    def lead_s(self, car: _Car, trip: Trip, tariff: Tariff) -> float:
        return 0.0

    def blocks(self, car: _Car, trip: Trip, tariff: Tariff) -> list[tuple[float, float]]:
        return []


@dataclass(frozen=True)
class Timer:
    """Start the production controller ``lead_min`` minutes before the forecast departure
    (plugged phases only)."""

    lead_min: float
    name: str = "timer"

    def lead_s(self, car: _Car, trip: Trip, tariff: Tariff) -> float:
        return 60.0 * self.lead_min if trip.plugged else 0.0

    def blocks(self, car: _Car, trip: Trip, tariff: Tariff) -> list[tuple[float, float]]:
        return _lead_blocks(trip, self.lead_s(car, trip, tariff))


@dataclass(frozen=True)
class Planner:
    """``plant-search``: for each plugged departure, choose the start on the plant itself
    (same weather, the forecast departure, the first ``COMFORT_WINDOW_S`` of the drive): the
    shortest lead, to the minute, whose discomfort is at most ``target_Kmin`` (bisection: a
    longer lead never leaves a warmer (colder) cabin), then the cheapest of it and the leads 5
    and 10 minutes longer that also meet the target (a cheaper hour can pay for a longer
    lead); none meeting it within ``max_lead_min``: the longest. Cost: grid energy at the
    hour's price, the drive's battery energy in the window at the off-peak price over the
    charger. The lead found is lengthened by ``margin_min`` (the study: the departure
    forecast's stated standard deviation), so that an early departure still finds the cabin
    nearly ready."""

    max_lead_min: float = 60.0
    target_Kmin: float = COMFORT_TARGET_KMIN
    margin_min: float = 0.0
    name: str = "plant-search"

    def blocks(self, car: _Car, trip: Trip, tariff: Tariff) -> list[tuple[float, float]]:
        return _lead_blocks(trip, self.lead_s(car, trip, tariff))

    def lead_s(self, car: _Car, trip: Trip, tariff: Tariff) -> float:
        if not trip.plugged:
            return 0.0
        saved = car.copy_state()
        v = _speeds(trip.cycles)[:int(COMFORT_WINDOW_S / 5.0)]
        charger = Charger()
        top = int(round(self.max_lead_min))
        first = trip.forecast_s - 60.0 * top
        if first > car.t:  # the soak up to the earliest start, shared by every lead
            car.run(first, "off")
        soaked = car.copy_state()
        seen: dict[int, tuple[float, float]] = {}

        def evaluate(lead: int) -> tuple[float, float]:
            if lead not in seen:
                car.restore(soaked)
                if trip.forecast_s - 60.0 * lead > car.t:
                    car.run(trip.forecast_s - 60.0 * lead, "off")
                pre = car.run(trip.forecast_s, "on") if car.t < trip.forecast_s else []
                drive = car.run(0.0, "drive", v)
                _, grid_cost, pre_batt = _plugged_split(pre, charger, tariff, _base_W())
                batt = pre_batt + sum(_climate_W(r) * r["Ts"] for r in drive) / J_PER_KWH
                seen[lead] = (grid_cost + batt * tariff.off_peak / charger.efficiency,
                              _outside_Kmin(drive, car.season))
            return seen[lead]

        ok = lambda lead: evaluate(lead)[1] <= self.target_Kmin  # noqa: E731
        if not ok(top):
            car.restore(saved)
            return 60.0 * top
        lo, hi = -1, top  # lo infeasible (or none), hi feasible
        if ok(0):
            hi = 0
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if mid <= 0:
                break
            if ok(mid):
                hi = mid
            else:
                lo = mid
        best = min((L for L in (hi, hi + 5, hi + 10) if L <= top and ok(L)),
                   key=lambda L: (evaluate(L)[0], L))
        car.restore(saved)
        return 60.0 * min(best + self.margin_min, top)


@dataclass(frozen=True)
class ModelPlanner:
    """``planner``: for each plugged departure, the pre-conditioning power over the parked
    window planned on the declared parked cabin (``acid.models.parked_cabin``, identified on
    the plant's parked records of the training days: ``fit``) by the optimal-control problem
    of :func:`acid.studies.dayplan.plan_power` (grid energy at the hour's price, battery
    energy at the dearest hour's price, the charger's DC output, the battery's energy left,
    the cabin ``margin_K`` inside the band over the last ``margin_min`` minutes before the
    forecast departure; ``margin_K`` tuned on the training days like the timer's lead),
    from the cabin measured when the car wakes to plan and the day's weather (known).
    Replayed on the plant: the production controller on over the minutes the plan gives at
    least half the full power; a plan that runs up to the forecast departure holds the
    cabin until the car leaves."""

    fit: object
    margin_min: float = 0.0
    margin_K: float = 1.0
    name: str = "planner"

    def wake_s(self, trip: Trip) -> float | None:
        """When the car wakes to plan (s): the window's start before the forecast departure;
        the planner reads the cabin then and runs the model from its own soak estimate
        (the mass) and the measured cabin."""
        from acid.studies.dayplan import WINDOW_MIN

        return trip.forecast_s - 60.0 * WINDOW_MIN if trip.plugged else None

    def plan(self, car: _Car, trip: Trip, tariff: Tariff):
        from acid.studies.dayplan import plan_power

        charger = Charger()
        clim, day = car.clim, car.day
        return plan_power(
            self.fit, car.parked_at[1], car.parked_at[0], trip.forecast_s,
            lambda t: (clim.T_amb_K(t, day.dT_max), clim.G_solar(t, day.clouds)),
            tariff.price, C2K(BAND_C[car.season]), cap_W=charger.P_ac_W * charger.efficiency,
            eta_charger=charger.efficiency, v_bat=max(tariff.hourly) / charger.efficiency,
            E_avail_kWh=E_RESERVE_FREE * Battery(soc=SOC_START).usable_kWh * SOC_START,
            margin_min=self.margin_min, margin_K=self.margin_K,
            T_cab_now=(car.t, float(car.state["T_cab"])))

    def blocks(self, car: _Car, trip: Trip, tariff: Tariff) -> list[tuple[float, float]]:
        if not trip.plugged:
            return []
        plan = self.plan(car, trip, tariff)
        if plan is None:
            return []
        out = plan.on_blocks()
        if out and out[-1][1] >= trip.forecast_s - 1e-6:
            out[-1] = (out[-1][0], math.inf)
        return out


#: share of the battery's energy at the day's start the parked plan may use (assumption: the
#: rest is the trips' and a reserve)
E_RESERVE_FREE = 0.2
#: the timer lead of the training runs that give the planner's parked records, min
FIT_LEAD_MIN = 30.0


def parked_records(day: DaySpec, lead_min: float = FIT_LEAD_MIN) -> list:
    """The parked phases of ``day`` under the timer at ``lead_min`` (switched-off soak, then
    the production controller's pull-down on a plug) as one-minute records
    (:class:`acid.studies.dayplan.ParkedRecord`): the cabin air at each minute's start, the
    mean electric power drawn (climate + 12 V base) while on, ambient and sun."""
    from acid.studies.dayplan import ParkedRecord

    clim, tariff = load_climate(day.season), load_tariff()
    car = _Car(clim, day, DAY_START_S)
    timer, P_base = Timer(lead_min), _base_W()
    out = []
    for trip in day.trips:
        t0, T0 = car.t, float(car.state["T_cab"])
        rows = _park(car, trip, timer, tariff, keep_off=True)
        H = int(math.floor((trip.depart_s - t0) / 60.0 + 1e-9))
        T, P = [T0], np.zeros(H)
        buckets: list[list[dict]] = [[] for _ in range(H)]
        for r in rows:
            k = int(math.floor((r["t"] - t0) / 60.0 + 1e-9))
            if k < H:
                buckets[k].append(r)
        H = next((k for k, b in enumerate(buckets) if not b or
                  abs(sum(r["Ts"] for r in b) - 60.0) > 1e-6), H)
        for k in range(H):
            b = buckets[k]
            T.append(float(b[-1]["T_cab"]))
            if b[0]["Ts"] < PARKED_TS:
                P[k] = float(np.mean([_climate_W(r) + P_base for r in b]))
        ts = t0 + 60.0 * np.arange(H)
        out.append(ParkedRecord(np.array(T), P[:H],
                                np.array([clim.T_amb_K(t, day.dT_max) for t in ts]),
                                np.array([clim.G_solar(t, day.clouds) for t in ts])))
        car.run(0.0, "drive", _speeds(trip.cycles))
    return out


def _plugged_split(pre: Sequence[dict], charger: Charger, tariff: Tariff, P_base: float
                   ) -> tuple[float, float, float]:
    """Pre-conditioning rows split between the charger and the battery: the DC load
    (climate + 12 V base) up to the charger's DC output comes from the grid, the rest from
    the battery. Returns (grid kWh, its cost USD at the hour's price, battery kWh)."""
    cap = charger.P_ac_W * charger.efficiency
    grid = cost = batt = 0.0
    for r in pre:
        P = _climate_W(r) + P_base
        g = min(P, cap)
        e = charger.grid_J(g * r["Ts"]) / J_PER_KWH
        grid += e
        cost += e * tariff.price(r["t"])
        batt += (P - g) * r["Ts"] / J_PER_KWH
    return grid, cost, batt


def _base_W() -> float:
    from acid.plant.road_load import RoadLoad

    return RoadLoad().P_aux


def controller_of(name: str, lead_min: float = 0.0,
                  leads_min: Sequence[float] = LEADS_MIN, margin_min: float = 0.0,
                  fit=None):
    """A controller by name (``CONTROLLERS``): the timer with ``lead_min``, the plant-search
    planner up to the longest of ``leads_min`` with ``margin_min``, the declared-model
    planner on the identified ``fit`` with ``margin_min`` and a comfort margin of
    ``lead_min`` K."""
    if name == "none":
        return NoPreconditioning()
    if name == "timer":
        return Timer(float(lead_min))
    if name == "plant-search":
        return Planner(float(max(leads_min)), margin_min=float(margin_min))
    if name == "planner":
        if fit is None:
            raise ConfigError("the planner needs an identified parked cabin (fit)")
        return ModelPlanner(fit, margin_min=float(margin_min), margin_K=float(lead_min))
    raise ConfigError(f"unknown controller {name!r} (choose {', '.join(CONTROLLERS)})")


# ----------------------------------------------------------------------------- one day
@dataclass(frozen=True)
class TripOutcome:
    """One trip: the lead used (s), the pre-conditioning's grid energy (kWh, climate and 12 V
    base load over the charger, up to its DC output) and cost, its battery energy (the load
    above the charger's output: the heater and heat pump together draw more than 6.4 kW),
    the drive's battery energy (kWh: climate, traction, base),
    distance (km), comfort (K.min outside the band over the first 10 min and the whole drive,
    time to comfort s: 0 when ready at departure), the cabin at departure (K), the lowest fog
    margin of the drive (K, winter; NaN in summer)."""

    depart_s: float
    lead_s: float
    plugged: bool
    E_pre_grid_kWh: float
    cost_pre_USD: float
    E_pre_battery_kWh: float
    E_climate_kWh: float
    E_traction_kWh: float
    E_base_kWh: float
    distance_km: float
    Kmin_window: float
    Kmin_drive: float
    time_to_comfort_s: float
    T_cab_depart_K: float
    fog_margin_min_K: float


@dataclass(frozen=True)
class DayOutcome:
    """What a fleet operator reads of one day under one controller (energies kWh, cost USD).

    E_battery_kWh : battery energy of the day (the trips' traction, base and climate, and
    pre-conditioning above the charger's output); E_climate_battery_kWh : the climate's part;
    E_pre_grid_kWh : grid energy of the pre-conditioning; E_recharge_grid_kWh : grid energy
    to put the battery energy back (over the charger); E_grid_kWh : their sum, all energy the
    day took from the grid; cost_USD : pre-conditioning at the hour's price + recharging at the
    off-peak price; range_lost_km : the climate's battery energy in km of the day's trips
    (traction + base per km); soc_end : state of charge after the trips; Kmin_window :
    K.min outside the band over the first 10 minutes of the trips, summed; Kmin_plugged :
    the same over the trips that left a plug (where pre-conditioning can act); Kmin_drive : over
    the whole drives; time_to_comfort_s : summed over the trips; fog_margin_min_K : lowest
    over the drives (winter); short_kWh : the battery energy the trips needed beyond what
    the battery held (0: the day was driven; above: range-limited, the car would not have
    arrived; the battery is not charged between trips); charger_limited_kWh : the
    pre-conditioning's energy above the charger's DC output, from the battery (the charger's
    power bound)."""

    label: str
    season: str
    controller: str
    forecast_sd_min: float
    trips: tuple[TripOutcome, ...]
    E_battery_kWh: float
    E_climate_battery_kWh: float
    E_pre_grid_kWh: float
    E_recharge_grid_kWh: float
    E_grid_kWh: float
    cost_USD: float
    range_lost_km: float
    soc_end: float
    Kmin_window: float
    Kmin_plugged: float
    Kmin_drive: float
    time_to_comfort_s: float
    fog_margin_min_K: float
    short_kWh: float = 0.0
    charger_limited_kWh: float = 0.0

    def summary(self) -> str:
        short = f", {self.short_kWh:.2f} kWh short of range" if self.short_kWh > 0 else ""
        return (f"{self.label} {self.controller}{short}: battery {self.E_battery_kWh:.2f} kWh "
                f"(climate {self.E_climate_battery_kWh:.2f}), grid {self.E_grid_kWh:.2f} kWh "
                f"(pre-conditioning {self.E_pre_grid_kWh:.2f}), {self.cost_USD:.2f} USD, "
                f"range lost {self.range_lost_km:.1f} km, {self.Kmin_window:.1f} K.min in "
                f"the first 10 min")

    def to_dict(self) -> dict:
        """The fields as JSON values (NaN, e.g. the summer fog margin, as None)."""
        return _json_safe(asdict(self))


def _json_safe(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_safe(v) for v in x]
    return x


def _park(car: _Car, trip: Trip, controller, tariff: Tariff,
          keep_off: bool = False) -> list[dict]:
    """The parked phase before ``trip``: switched off, and the production controller over
    each on-block (start, end) s, cut at the true departure (none when the car leaves
    first; an end of ``inf``: until the car leaves). Returns the pre-conditioning rows (and
    the switched-off ones, in time order, with ``keep_off``). The off phases run whole 60 s
    steps: without pre-conditioning the drive starts up to 59 s before the departure. A
    controller with a ``wake_s`` is asked for its blocks at that time (the car switched off
    until then), the others when the car parks."""
    rows = []
    car.parked_at = (car.t, float(car.state["T_cab"]))
    wake = getattr(controller, "wake_s", lambda trip: None)(trip)
    if wake is not None and wake > car.t:
        off = car.run(min(wake, trip.depart_s), "off")
        if keep_off:
            rows += off
    for a, b in controller.blocks(car, trip, tariff):
        a, b = max(a, car.t), min(b, trip.depart_s)
        if a >= b:
            continue
        off = car.run(a, "off")
        if keep_off:
            rows += off
        if car.t < b:
            rows += car.run(b, "on")
    if car.t < trip.depart_s:
        off = car.run(trip.depart_s, "off")
        if keep_off:
            rows += off
    return rows


def run_day(day: DaySpec, controller, tariff: Tariff | None = None,
            battery: Battery | None = None, charger: Charger | None = None,
            forecast_sd_min: float = 0.0) -> DayOutcome:
    """Run one day (module docstring) under ``controller`` and account for it."""
    from acid.plant.road_load import RoadLoad, cycle_traction

    tariff = tariff or load_tariff()
    charger = charger or Charger()
    battery = battery or Battery(soc=day.soc_start)
    clim = load_climate(day.season)
    road = RoadLoad()
    car = _Car(clim, day, DAY_START_S)
    outs = []
    for trip in day.trips:
        pre = _park(car, trip, controller, tariff)
        v = _speeds(trip.cycles)
        drive = car.run(0.0, "drive", v)
        grid_pre, cost_pre, batt_pre = _plugged_split(pre, charger, tariff, road.P_aux)
        E_cl = sum(_climate_W(r) * r["Ts"] for r in drive) / J_PER_KWH
        T_mean = float(np.mean([r["T_amb"] for r in drive]))
        parts = [cycle_traction(road, c, T_mean) for c in trip.cycles]
        band = C2K(BAND_C[day.season])
        ok = [r["T_cab"] <= band if day.season == "summer" else r["T_cab"] >= band
              for r in drive]
        ttc = (next((i for i, x in enumerate(ok) if x), len(ok))) * 5.0
        fog = (float(min(r["fog_margin"] for r in drive)) if day.season == "winter"
               else math.nan)
        outs.append(TripOutcome(
            depart_s=trip.depart_s, lead_s=float(trip.depart_s - pre[0]["t"]) if pre else 0.0,
            plugged=trip.plugged, E_pre_grid_kWh=grid_pre, cost_pre_USD=cost_pre,
            E_pre_battery_kWh=batt_pre,
            E_climate_kWh=E_cl, E_traction_kWh=sum(p.battery_J for p in parts) / J_PER_KWH,
            E_base_kWh=sum(p.aux_J for p in parts) / J_PER_KWH,
            distance_km=sum(p.distance_m for p in parts) / 1000.0,
            Kmin_window=_outside_Kmin(drive, day.season, COMFORT_WINDOW_S),
            Kmin_drive=_outside_Kmin(drive, day.season), time_to_comfort_s=ttc,
            T_cab_depart_K=float(drive[0]["T_cab"]), fog_margin_min_K=fog))
    E_batt = sum(o.E_pre_battery_kWh + o.E_climate_kWh + o.E_traction_kWh + o.E_base_kWh
                 for o in outs)
    # the battery through the trips (no charging between them): what it lacked
    short = max(0.0, E_batt - battery.energy_kWh)
    E_cl = sum(o.E_pre_battery_kWh + o.E_climate_kWh for o in outs)
    E_pre = sum(o.E_pre_grid_kWh for o in outs)
    E_rech = charger.grid_J(E_batt * J_PER_KWH) / J_PER_KWH
    per_km = (sum(o.E_traction_kWh + o.E_base_kWh for o in outs)
              / sum(o.distance_km for o in outs))
    return DayOutcome(
        label=day.label, season=day.season, controller=controller.name,
        forecast_sd_min=float(forecast_sd_min), trips=tuple(outs), E_battery_kWh=E_batt,
        E_climate_battery_kWh=E_cl, E_pre_grid_kWh=E_pre, E_recharge_grid_kWh=E_rech,
        E_grid_kWh=E_pre + E_rech,
        cost_USD=sum(o.cost_pre_USD for o in outs) + E_rech * tariff.off_peak,
        range_lost_km=E_cl / per_km,
        soc_end=battery.drawn(E_batt * J_PER_KWH).soc,
        Kmin_window=sum(o.Kmin_window for o in outs),
        Kmin_plugged=sum(o.Kmin_window for o in outs if o.plugged),
        Kmin_drive=sum(o.Kmin_drive for o in outs),
        time_to_comfort_s=sum(o.time_to_comfort_s for o in outs),
        fog_margin_min_K=(min(o.fog_margin_min_K for o in outs) if day.season == "winter"
                          else math.nan),
        short_kWh=float(short),
        charger_limited_kWh=float(sum(o.E_pre_battery_kWh for o in outs)))


# ----------------------------------------------------------------------------- tuning, intervals
def tune_timer(outcomes: dict[float, Sequence[DayOutcome]],
               target_Kmin: float = COMFORT_TARGET_KMIN) -> float:
    """The lead (min) of the cheapest mean cost over the training days among the leads whose
    mean discomfort per plugged departure (``Kmin_plugged`` over the day's plugged trips) is
    at most ``target_Kmin``; none: the least discomfort."""
    feasible = {L: float(np.mean([o.cost_USD for o in outs])) for L, outs in outcomes.items()
                if plugged_Kmin(outs) <= target_Kmin}
    if feasible:
        return min(feasible, key=lambda L: (feasible[L], L))
    return min(outcomes, key=lambda L: plugged_Kmin(outcomes[L]))


def fine_leads(outcomes: dict[float, Sequence[DayOutcome]], leads: Sequence[float],
               target_Kmin: float = COMFORT_TARGET_KMIN) -> tuple[float, ...]:
    """The whole minutes strictly between the coarse scan's tuned lead and the scanned lead
    below it (none when the tuned lead is the shortest or no lead meets the target)."""
    best = tune_timer(outcomes, target_Kmin)
    if plugged_Kmin(outcomes[best]) > target_Kmin:
        return ()
    below = [L for L in leads if L < best]
    if not below:
        return ()
    return tuple(float(m) for m in range(int(math.floor(max(below))) + 1,
                                         int(math.ceil(best))) if m not in outcomes)


def plugged_Kmin(outs: Sequence[DayOutcome]) -> float:
    """Mean K.min outside the band over the first 10 minutes per plugged departure."""
    n = sum(sum(t.plugged for t in o.trips) for o in outs)
    return sum(o.Kmin_plugged for o in outs) / n if n else 0.0


def day_verdict(diff: Sequence[float], seed: int = 0,
                min_days: int = MIN_DAYS_RESOLVED) -> dict:
    """The paired differences ``diff`` (controller minus baseline, one per held-out day;
    lower is better for every quantity here) read by the project's one reading of an
    interval, :func:`acid.studies.verdict.paired_verdict`, on the saving (minus the
    difference): Student's t interval deciding, the paired bootstrap beside it; "not
    resolved" below ``min_days`` days. Returns ``{n, mean, low, high, boot_low, boot_high,
    verdict}`` in the difference's sign (``low``/``high``: the t interval)."""
    d = np.asarray(diff, dtype=float)
    v = paired_verdict(-d, min_count=min_days, seed=seed)
    if v.lo is None:
        mean = float(d.mean()) if d.size else math.nan
        return {"n": v.n, "mean": mean, "low": math.nan, "high": math.nan,
                "boot_low": math.nan, "boot_high": math.nan, "verdict": v.words}
    return {"n": v.n, "mean": -v.mean, "low": -v.hi, "high": -v.lo, "boot_low": -v.boot_hi,
            "boot_high": -v.boot_lo, "verdict": v.words}


# ----------------------------------------------------------------------------- the study
@dataclass(frozen=True)
class DayStudy:
    """The study: per season the tuned lead, the training scan (lead -> mean cost and
    K.min per plugged departure), the held-out outcomes and the paired intervals
    (controller vs baseline, per forecast error and quantity)."""

    seasons: tuple[str, ...]
    n_train: int
    n_test: int
    seed: int
    forecast_errors_min: tuple[float, ...]
    leads_min: tuple[float, ...]
    tuned_lead_min: dict[str, float]
    scan: dict[str, dict[str, tuple[float, float]]]
    outcomes: tuple[DayOutcome, ...]
    comparisons: tuple[dict, ...] = field(default=())
    #: per season, the identified parked cabin (:class:`acid.studies.dayplan.ParkedFit`)
    fits: dict = field(default_factory=dict)
    planners: tuple[str, ...] = ()
    #: per season, the declared-model planner's comfort margin tuned on the training days, K
    margin_K: dict = field(default_factory=dict)
    #: the battery's state of charge at each day's start
    soc_start: float = SOC_START

    def summary(self) -> str:
        lines = []
        for s in self.seasons:
            lines.append(f"{s}: timer lead tuned on {self.n_train} training days: "
                         f"{self.tuned_lead_min[s]:g} min")
            if s in self.fits:
                f = self.fits[s]
                lines.append(f"{s}: parked cabin identified on {f.n_records} parked phases "
                             f"({f.n_samples} min): simulation error RMS {f.rms_K:.2f} K, "
                             f"full power {f.P_full_W / 1000:.2f} kW; comfort margin "
                             f"tuned: {self.margin_K.get(s, math.nan):g} K")
        for c in self.comparisons:
            lines.append(f"{c['season']} {c['controller']} vs {c['baseline']}, forecast "
                         f"error {c['forecast_sd_min']:g} min, {c['quantity']}: "
                         f"{c['mean']:+.3f} [{c['low']:+.3f}, {c['high']:+.3f}] "
                         f"({c['n']} days) {c['verdict']}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"seasons": list(self.seasons), "n_train": self.n_train, "n_test": self.n_test,
                "seed": self.seed, "forecast_errors_min": list(self.forecast_errors_min),
                "leads_min": list(self.leads_min), "tuned_lead_min": self.tuned_lead_min,
                "scan": self.scan, "comfort_target_Kmin": COMFORT_TARGET_KMIN,
                "band_C": BAND_C, "min_days_resolved": MIN_DAYS_RESOLVED,
                "comparisons": _json_safe(list(self.comparisons)),
                "planners": list(self.planners), "planner_margin_K": self.margin_K,
                "parked_cabin_fit": {k: v.to_dict() for k, v in self.fits.items()},
                "soc_start": self.soc_start,
                "outcomes": [o.to_dict() for o in self.outcomes]}

    def mean_of(self, season: str, controller: str, sd: float, key: str) -> float:
        vals = [getattr(o, key) for o in self.outcomes if o.season == season
                and o.controller == controller and o.forecast_sd_min == sd]
        return float(np.mean(vals)) if vals else math.nan


def _run_task(day: DaySpec, name: str, lead: float, leads: tuple[float, ...],
              sd: float, fit=None) -> DayOutcome:
    """One day-run; for the planner ``lead`` carries its comfort margin, K."""
    return run_day(day, controller_of(name, lead, leads, margin_min=sd, fit=fit),
                   forecast_sd_min=sd)


def _planner_task(d: DaySpec, p: str, leads, e: float, fit, margin_K):
    return (d, p, margin_K, leads, e, fit) if p == "planner" else (d, p, 0.0, leads, e, None)


#: the comfort margins (K inside the band at the forecast departure) the declared-model
#: planner is tuned over on the training days (negative: the band's edge may be passed by
#: that much, the drive's first minutes still meeting the target)
PLAN_MARGINS_K = tuple(float(m) for m in range(-4, 7))


QUANTITIES = (("E_battery_kWh", "battery energy, kWh"), ("cost_USD", "cost, USD"),
              ("Kmin_window", "K.min outside the band, first 10 min"),
              ("Kmin_plugged", "K.min, first 10 min, trips from a plug"),
              ("E_grid_kWh", "total grid energy, kWh"))


def day_study(seasons: Sequence[str] = SEASONS, n_train: int = 6, n_test: int = 10,
              seed: int = 0, forecast_errors_min: Sequence[float] = FORECAST_ERRORS_MIN,
              leads_min: Sequence[float] = LEADS_MIN, planners: Sequence[str] = PLANNERS,
              jobs: int | None = 1,
              progress: Callable[[int, int, str], None] | None = None,
              soc_start: float = SOC_START) -> DayStudy:
    """Tune the timer over ``leads_min`` on ``n_train`` days per season (departures known),
    then to the minute below the coarse optimum (:func:`fine_leads`, bisected for the
    shortest lead meeting the comfort target); identify the parked cabin on the same days'
    parked records under the timer at ``FIT_LEAD_MIN`` (:func:`parked_records`,
    :func:`acid.studies.dayplan.identify`); judge none, the timer
    and the ``planners`` (``planner``: the declared-model plan; ``plant-search``: the start
    searched on the plant, leads up to the longest of ``leads_min``; both with a margin of
    the forecast's standard deviation) on ``n_test`` other days for each forecast error;
    paired intervals of each against none and of each planner against the timer.
    Training days are indices 0.., held-out days 1000..: no day is both. Every day starts
    with the battery at ``soc_start`` (a low one: range-limited days, ``short_kWh``)."""
    from acid.executor import check_interrupt, open_executor
    from acid.studies.dayplan import identify

    seasons, leads = tuple(seasons), tuple(float(x) for x in leads_min)
    errs = tuple(float(x) for x in forecast_errors_min)
    planners = tuple(planners)
    for s in seasons:
        load_climate(s)
    for p in planners:
        if p not in PLANNERS:
            raise ConfigError(f"--planner {p!r}: choose {' or '.join(PLANNERS)}")
    if n_train < 1 or n_test < 1:
        raise ConfigError("--days: need at least one training and one held-out day")
    total = [0]
    done = [0]

    def run_all(ex, tasks, fn=_run_task):
        handles = {ex.submit(fn, *t): t for t in tasks}
        out, pending = {}, list(handles)
        while pending:
            check_interrupt()
            ex.pump()
            for h in ex.wait_any(pending, timeout=0.2):
                pending.remove(h)
                out[handles[h]] = ex.result(h)
                done[0] += 1
                if progress is not None:
                    t = handles[h]
                    progress(done[0], total[0],
                             f"{t[0].label} {t[1]} {t[2]:g} min, error {t[4]:g} min"
                             if fn is _run_task else f"{t[0].label} parked records")
        return out

    n_ctrl = 1 + (1 + len(planners)) * len(errs)
    total[0] = len(seasons) * (n_train * (len(leads) + ("planner" in planners))
                               + n_test * n_ctrl)
    tuned, scan, outcomes, comps, fits, margin = {}, {}, [], [], {}, {}
    with open_executor(jobs) as ex:
        for s in seasons:
            train = make_days(s, n_train, seed, 0.0, first_index=0, soc_start=soc_start)
            res = run_all(ex, [(d, "timer", L, leads, 0.0) for d in train for L in leads])
            by_lead = {L: [res[(d, "timer", L, leads, 0.0)] for d in train] for L in leads}
            # to the minute: the whole minutes between the coarse optimum and the coarse
            # lead below it (comfort is monotone in the lead, and so is the energy: a
            # cheaper feasible lead can only be shorter), bisected for the shortest one
            # that meets the comfort target (log2 of the minutes' runs instead of all)
            fine = list(fine_leads(by_lead, leads))
            while fine:
                L = fine[len(fine) // 2]
                total[0] += n_train
                res = run_all(ex, [(d, "timer", L, leads, 0.0) for d in train])
                by_lead[L] = [res[(d, "timer", L, leads, 0.0)] for d in train]
                ok = plugged_Kmin(by_lead[L]) <= COMFORT_TARGET_KMIN
                fine = fine[:len(fine) // 2] if ok else fine[len(fine) // 2 + 1:]
            by_lead = dict(sorted(by_lead.items()))
            tuned[s] = tune_timer(by_lead)
            scan[s] = {f"{L:g}": (float(np.mean([o.cost_USD for o in v])), plugged_Kmin(v))
                       for L, v in by_lead.items()}
            fit = None
            if "planner" in planners:
                recs = run_all(ex, [(d, FIT_LEAD_MIN) for d in train], fn=parked_records)
                fit = fits[s] = identify(s, [r for v in recs.values() for r in v])
                # the plan's comfort margin tuned like the timer's lead: the cheapest whose
                # mean discomfort from a plug over the training days meets the target
                total[0] += len(PLAN_MARGINS_K) * n_train
                res = run_all(ex, [(d, "planner", m, leads, 0.0, fit) for d in train
                                   for m in PLAN_MARGINS_K])
                by_m = {m: [res[(d, "planner", m, leads, 0.0, fit)] for d in train]
                        for m in PLAN_MARGINS_K}
                margin[s] = tune_timer(by_m)
                scan[f"{s} planner margin K"] = {
                    f"{m:g}": (float(np.mean([o.cost_USD for o in v])), plugged_Kmin(v))
                    for m, v in by_m.items()}
            tasks = []
            base_days = make_days(s, n_test, seed, 0.0, first_index=1000,
                                  soc_start=soc_start)
            tasks += [(d, "none", 0.0, leads, 0.0) for d in base_days]
            test = {}
            for e in errs:
                test[e] = make_days(s, n_test, seed, e, first_index=1000,
                                    soc_start=soc_start)
                tasks += [(d, "timer", tuned[s], leads, e) for d in test[e]]
                tasks += [_planner_task(d, p, leads, e, fit, margin.get(s))
                          for p in planners for d in test[e]]
            res = run_all(ex, tasks)
            none = [res[(d, "none", 0.0, leads, 0.0)] for d in base_days]
            outcomes += none
            for e in errs:
                timer = [res[(d, "timer", tuned[s], leads, e)] for d in test[e]]
                outcomes += timer
                pairs = [("timer", timer, "none", none)]
                for p in planners:
                    plan = [res[_planner_task(d, p, leads, e, fit, margin.get(s))]
                            for d in test[e]]
                    outcomes += plan
                    pairs += [(p, plan, "none", none), (p, plan, "timer", timer)]
                for name, a, bname, b in pairs:
                    for key, words in QUANTITIES:
                        v = day_verdict([getattr(x, key) - getattr(y, key)
                                         for x, y in zip(a, b, strict=True)], seed)
                        comps.append({"season": s, "controller": name, "baseline": bname,
                                      "forecast_sd_min": e, "quantity": words, **v})
    return DayStudy(seasons, n_train, n_test, seed, errs, leads, tuned, scan,
                    tuple(outcomes), tuple(comps), fits, planners, margin, float(soc_start))


def day_trace(day: DaySpec, controller) -> dict[str, np.ndarray]:
    """The day's trace for the figure: clock time (h), ambient and cabin (degC), climate
    power (kW) and the phase (0 off, 1 pre-conditioning, 2 driving)."""
    clim = load_climate(day.season)
    car = _Car(clim, day, DAY_START_S)
    tariff = load_tariff()
    rows, phase = [], []
    for trip in day.trips:
        new = _park(car, trip, controller, tariff, keep_off=True)
        rows += new
        phase += [0 if r["Ts"] == PARKED_TS else 1 for r in new]
        new = car.run(0.0, "drive", _speeds(trip.cycles))
        rows += new
        phase += [2] * len(new)
    return {"t_h": np.array([r["t"] for r in rows]) / 3600.0,
            "T_amb_C": np.array([K2C(r["T_amb"]) for r in rows]),
            "T_cab_C": np.array([K2C(r["T_cab"]) for r in rows]),
            "P_climate_kW": np.array([_climate_W(r) for r in rows]) / 1000.0,
            "phase": np.array(phase)}


__all__ = ["BAND_C", "CONTROLLERS", "COMFORT_TARGET_KMIN", "Climate", "DayOutcome", "DaySpec",
           "DayStudy", "FORECAST_ERRORS_MIN", "LEADS_MIN", "ModelPlanner", "NoPreconditioning",
           "PLANNERS", "parked_records",
           "Planner", "QUICK_LEADS_MIN", "SEASONS", "Tariff", "Timer",
           "Trip", "TripOutcome", "controller_of", "day_study", "day_trace", "load_climate",
           "load_tariff", "make_days", "day_verdict", "fine_leads", "plugged_Kmin", "run_day",
           "tune_timer"]
