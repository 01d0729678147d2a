"""The whole year: climate energy and the share of range it costs, from -10 to
40 degC, over drive cycles, for the shipped vehicles, with and without the heat pump.

Each point is one pass of a drive cycle (``acid.signals``, at the plant's 5 s sample) from a
soak at ambient (every node of the plant at the ambient, no frost), run by the production
controllers of acid's plants. **The rule that picks the plant:**

* ambient below ``switch_C`` (default 18 degC): the **heating plant**
  (``acid.plant.heating.HeatingPlant``, nominal mode: heat pump first, the coolant heater
  when the heat pump is below its lowest ambient (-20 degC), defrosting, or saturated;
  target ``HeatingConfig.T_heat_set``, 23 degC) at the winter boundary
  (``winter_plant_config``: 80 % RH, no sun), on the vehicle's compressor and cabin; and the
  same with the heat pump removed (``heat_pump=False``: the coolant heater alone, as in the
  logged i3);
* at or above it: the **cooling plant** (``acid.plant.hifi.HifiPlant``, nominal mode: the
  paper's two PI loops, target the vehicle's ``T_cab_set``, 22 degC) with the vehicle's own
  sun and humidity (``PlantConfig``: 850 W/m^2, the SC03 A/C test's, and 50 % RH). The heat
  pump plays no part there: both heating systems share the point.

The 18 degC switch-over is an assumption: below it a sunless cabin held at 22-23 degC needs
heat; with the A/C test's sun it needs cooling from about 15 degC up (the sun's 0.5-0.9 kW).

Per point: compressor energy (A/C when cooling, heat pump when heating, defrost included),
coolant-heater, blower and front-fan energy (climate = their sum), the traction and 12 V
base-load energy of the cycle (``acid.plant.road_load``, the i3's road load at the point's
air density, for both vehicles: they differ in their A/C calibration, not their body) and
the **share of range the climate costs**, climate / (traction + base + climate) (the range
with climate over the range without is one minus it). Cabin temperature at the end and
mean, for the comfort each point bought. Temperatures in K inside, degC at the edges.

A grid's runs of one plant (at least ``BATCH_MIN`` of them) are stepped together on a batched
plant (``acid.plant.batch``: ``BatchHeatingPlant``, ``BatchPlant``), whose points equal one
plant per run (``run_task``) to rounding; smaller groups run one plant per run.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass

import numpy as np

from acid.errors import ConfigError
from acid.units import C2K, K2C

#: the default grid: ambients (degC), cycles, vehicles
AMBIENTS_C = tuple(float(t) for t in range(-10, 45, 5))
CYCLES = ("udds", "hwfet")
VEHICLES = ("default", "paper")
#: the coarse grid of ``--quick``
QUICK_AMBIENTS_C = (-10.0, 5.0, 25.0, 35.0)
QUICK_CYCLES = ("udds",)
#: heating below, cooling at and above, degC (module docstring)
SWITCH_C = 18.0
#: accepted ambients, degC: the refrigerant tables and the heat pump's lowest ambient bound
#: them below; the cooling plant's property tables above
AMBIENT_RANGE_C = (-30.0, 50.0)
#: the two heating systems compared
HEAT_PUMP, HEATER_ONLY = "heat pump", "heater only"
#: the most tasks in one batched plant (a bigger group is split into chunks)
BATCH_SIZE = 256
#: the fewest tasks run in one batched plant: below it numpy's per-call cost makes the batch
#: slower than one plant per task (the heating batch breaks even at about 48 members, the
#: cooling batch above 20; ``benchmarks/bench_plant_batch*.py``)
BATCH_MIN = 64


@dataclass(frozen=True)
class YearTask:
    """One plant run: ambient (K), cycle, vehicle (name or plant TOML), heat pump fitted,
    mode ("heating" or "cooling"), refrigerant (None: the vehicle's)."""

    T_amb_K: float
    cycle: str
    vehicle: str
    heat_pump: bool
    mode: str
    refrigerant: str | None = None

    @property
    def label(self) -> str:
        system = ("" if self.mode == "cooling"
                  else f", {HEAT_PUMP if self.heat_pump else HEATER_ONLY}")
        return f"{K2C(self.T_amb_K):g} degC {self.cycle} {self.vehicle} {self.mode}{system}"


@dataclass(frozen=True)
class YearPoint:
    """The energy of one run (module docstring). Energies in kWh, temperatures in K.

    heating : ``HEAT_PUMP`` or ``HEATER_ONLY``; "-" for a cooling point (both systems').
    E_ac_kWh : compressor energy while cooling; E_hp_kWh : compressor energy while heating
        (defrost included); E_heater_kWh : coolant heater; E_blower_kWh; E_fan_kWh : front
        (condenser / outdoor-coil) fan; E_climate_kWh : their sum.
    E_traction_kWh : battery energy of the drive (net of regeneration); E_base_kWh : the 12 V
        base load; share : E_climate / (E_traction + E_base + E_climate).
    defrost_s : time spent defrosting; T_cab_end_K, T_cab_mean_K : the cabin at the end and
        over the cycle; T_set_K : the controller's target.
    """

    T_amb_K: float
    cycle: str
    vehicle: str
    mode: str
    heating: str
    distance_km: float
    duration_s: float
    E_ac_kWh: float
    E_hp_kWh: float
    E_heater_kWh: float
    E_blower_kWh: float
    E_fan_kWh: float
    E_climate_kWh: float
    E_traction_kWh: float
    E_base_kWh: float
    share: float
    defrost_s: float
    T_cab_end_K: float
    T_cab_mean_K: float
    T_set_K: float

    def to_row(self) -> dict:
        """A CSV row: temperatures in degC."""
        return {(k[:-2] + "_C" if k.endswith("_K") else k):
                (round(K2C(v), 6) if k.endswith("_K") else v) for k, v in asdict(self).items()}


def plan_tasks(ambients_C: Sequence[float], cycles: Sequence[str], vehicles: Sequence[str],
               switch_C: float, refrigerant: str | None = None) -> list[YearTask]:
    """The runs of a grid: two per heating point (heat pump, heater only), one per cooling
    point."""
    tasks = []
    for vehicle in vehicles:
        for cycle in cycles:
            for t in ambients_C:
                T = C2K(float(t))
                if t < switch_C:
                    tasks += [YearTask(T, cycle, vehicle, hp, "heating", refrigerant)
                              for hp in (True, False)]
                else:
                    tasks.append(YearTask(T, cycle, vehicle, False, "cooling", refrigerant))
    return tasks


def check_grid(ambients_C: Sequence[float], cycles: Sequence[str], vehicles: Sequence[str],
               switch_C: float, refrigerant: str | None = None) -> None:
    """Refuse (``ConfigError``, one line naming the option) an empty or out-of-range grid or
    a refrigerant acid has no tables for."""
    from acid.plant.config import REFRIGERANTS
    from acid.plant.vehicles import is_vehicle, resolve_config, vehicle_config
    from acid.signals import available_drive_cycles

    lo, hi = AMBIENT_RANGE_C
    if not ambients_C:
        raise ConfigError("--t-amb: give at least one ambient")
    for t in ambients_C:
        if not (math.isfinite(t) and lo <= t <= hi):
            raise ConfigError(f"--t-amb {t:g}: must lie in {lo:g}..{hi:g} degC")
    if not (math.isfinite(switch_C) and lo <= switch_C <= hi):
        raise ConfigError(f"--switch-over {switch_C:g}: must lie in {lo:g}..{hi:g} degC")
    names = available_drive_cycles()
    for c in cycles:
        if c not in names:
            raise ConfigError(f"--cycle {c}: unknown drive cycle (available: "
                              f"{', '.join(names)})")
    if not cycles:
        raise ConfigError("--cycle: give at least one drive cycle")
    if not vehicles:
        raise ConfigError("--plant-config: give at least one vehicle")
    for v in vehicles:
        if not is_vehicle(v) and not resolve_config(v).is_file():
            raise ConfigError(f"--plant-config {v}: neither a vehicle name nor a file")
        vehicle_config(v)  # a bad file is refused here, before any run
    if refrigerant is not None and refrigerant not in REFRIGERANTS:
        raise ConfigError(f"--refrigerant {refrigerant!r}: choose {' or '.join(REFRIGERANTS)}")


def _task_configs(task: YearTask):
    """The plant configurations of a task: (HeatingConfig or None, PlantConfig, T_set K)."""
    from acid.plant.heating_config import HeatingConfig, winter_plant_config
    from acid.plant.vehicles import vehicle_config

    T = task.T_amb_K
    base = vehicle_config(task.vehicle)
    if task.refrigerant is not None:
        base = base.replace(refrigerant=task.refrigerant)
    if task.mode == "heating":
        hc = HeatingConfig(heat_pump=task.heat_pump)
        return hc, winter_plant_config(T, base=base), hc.T_heat_set
    cfg = base.replace(T_amb=T, T_cab0=T, T_int0=T, T_shell0=T, T_ew0=T, T_cw0=T)
    return None, cfg, cfg.T_cab_set


def _point(task: YearTask, cols: dict[str, np.ndarray], T_cab: np.ndarray, Ts: float,
           T_set: float) -> YearPoint:
    """The point of one run from its channels (one value per sample) and its cabin states at
    the end of each sample (``T_cab``, K)."""
    from acid.plant.road_load import RoadLoad, cycle_traction

    n = len(T_cab)

    def kwh(channel: str) -> float:
        x = cols.get(channel)
        return 0.0 if x is None else float(sum(x.tolist()) * Ts / 3.6e6)

    comp = kwh("P_comp")
    parts = {"E_ac_kWh": comp if task.mode == "cooling" else 0.0,
             "E_hp_kWh": comp if task.mode == "heating" else 0.0,
             "E_heater_kWh": kwh("P_heater"), "E_blower_kWh": kwh("P_bl"),
             "E_fan_kWh": kwh("P_fan")}
    climate = sum(parts.values())
    T = task.T_amb_K
    trac = cycle_traction(RoadLoad(), task.cycle, T)
    E_t, E_b = trac.battery_J / 3.6e6, trac.aux_J / 3.6e6
    defrost = cols.get("defrosting")
    return YearPoint(
        T_amb_K=T, cycle=task.cycle, vehicle=task.vehicle, mode=task.mode,
        heating=(HEAT_PUMP if task.heat_pump else HEATER_ONLY) if task.mode == "heating"
        else "-",
        distance_km=trac.distance_m / 1000.0, duration_s=n * Ts, **parts,
        E_climate_kWh=climate, E_traction_kWh=E_t, E_base_kWh=E_b,
        share=climate / (E_t + E_b + climate),
        defrost_s=0.0 if defrost is None else float(sum(defrost.tolist()) * Ts),
        T_cab_end_K=float(T_cab[-1]), T_cab_mean_K=float(T_cab.mean()), T_set_K=float(T_set))


def run_task(task: YearTask) -> YearPoint:
    """Run one point (module docstring) on its own plant and return its energies: the
    single-plant reference of ``run_batch``."""
    from acid.plant.heating import HeatingPlant
    from acid.plant.hifi import HifiPlant
    from acid.signals import drive_cycle

    hc, cfg, T_set = _task_configs(task)
    plant = (HeatingPlant(hc, cfg, mode="nominal") if task.mode == "heating"
             else HifiPlant(cfg, mode="nominal"))
    Ts = plant.Ts
    v, _ = drive_cycle(task.cycle, Ts=Ts, repeat=False)
    plant.reset()
    rows = [plant.step(0.0, 0.0, float(x)) if task.mode == "heating"
            else plant.step(0.0, plant.cfg.T_ew_set, float(x)) for x in v]
    cols = {name: np.array([r[name] for r in rows]) for name in rows[0]}
    T_cab = np.array([r["T_cab"] for r in rows[1:]] + [plant.measure()["T_cab"]])
    return _point(task, cols, T_cab, Ts, T_set)


def batch_key(task: YearTask) -> tuple:
    """Tasks with the same key run in one batched plant: the plant (mode) and what its members
    must share (refrigerant tables, time steps)."""
    from acid.plant.batch import SHARED_FIELDS

    _, cfg, _ = _task_configs(task)
    return (task.mode, *(getattr(cfg, f) for f in SHARED_FIELDS))


def run_batch(tasks: Sequence[YearTask], batch_min: int | None = BATCH_MIN
              ) -> list[YearPoint]:
    """Run tasks of one ``batch_key`` together: one ``BatchHeatingPlant`` (heating) or
    ``BatchPlant`` (cooling) of every task, each over its own cycle (a member whose cycle has
    ended holds its last speed, its samples stop at its own length). The points equal
    ``run_task``'s to rounding (``tests/test_plant_year.py``). Fewer tasks than
    ``batch_min`` (None: any number) run one plant each (``run_task``)."""
    tasks = list(tasks)
    if batch_min is None or len(tasks) < batch_min:
        return [run_task(t) for t in tasks]
    from acid.plant.batch import BatchPlant
    from acid.plant.batch.heating import BatchHeatingPlant
    from acid.signals import drive_cycle

    modes = {t.mode for t in tasks}
    if len(modes) != 1:
        raise ConfigError(f"run_batch: tasks of one mode only, got {sorted(modes)}")
    heating = modes == {"heating"}
    confs = [_task_configs(t) for t in tasks]
    cfgs = [c for _, c, _ in confs]
    if heating:
        plant = BatchHeatingPlant([h for h, _, _ in confs], cfgs, mode="nominal")
    else:
        plant = BatchPlant(cfgs, mode="nominal")
    Ts, B = plant.Ts, len(tasks)
    profiles = {c: np.asarray(drive_cycle(c, Ts=Ts, repeat=False)[0], float)
                for c in {t.cycle for t in tasks}}
    lens = np.array([len(profiles[t.cycle]) for t in tasks])
    n = int(lens.max())
    V = np.empty((n, B))
    for b, t in enumerate(tasks):
        x = profiles[t.cycle]
        V[:len(x), b] = x
        V[len(x):, b] = x[-1]
    T_ew_set = np.array([c.T_ew_set for c in cfgs])
    plant.reset()
    cols: dict[str, np.ndarray] = {}
    T_cab = np.empty((n + 1, B))
    for k in range(n):
        row = (plant.step(v_veh=V[k]) if heating
               else plant.step(np.zeros(B), T_ew_set, V[k]))
        if not cols:
            cols = {name: np.empty((n, B)) for name in row}
        for name, x in row.items():
            cols[name][k] = x
        T_cab[k] = row["T_cab"]
    T_cab[n] = plant.measure()["T_cab"]
    return [_point(t, {name: x[:lens[b], b] for name, x in cols.items()},
                   T_cab[1:lens[b] + 1, b], Ts, confs[b][2])
            for b, t in enumerate(tasks)]


def plan_batches(tasks: Sequence[YearTask], jobs: int = 1, size: int = BATCH_SIZE,
                 batch_min: int | None = BATCH_MIN) -> list[tuple[YearTask, ...]]:
    """The tasks in batches: grouped by ``batch_key`` (cycles mixed: a member that ends
    early costs little next to the per-step cost of numpy), longest cycles first so a chunk
    holds cycles of like length, chunks of at most ``size``; a group is split further, up to
    ``jobs`` chunks, while its chunks keep ``batch_min`` tasks. A group smaller than
    ``batch_min`` (or every group, ``batch_min`` None) gives one chunk per task: one plant per
    run, as the executor spreads them."""
    from acid.signals import drive_cycle

    groups: dict[tuple, list[YearTask]] = {}
    for t in tasks:
        groups.setdefault(batch_key(t), []).append(t)
    length = {c: len(drive_cycle(c, repeat=False)[0]) for c in {t.cycle for t in tasks}}
    out = []
    for group in groups.values():
        group.sort(key=lambda t: -length[t.cycle])  # stable: the plan's order within a cycle
        n, jobs = len(group), max(1, int(jobs))
        if batch_min is None or n < batch_min:
            out += [(t,) for t in group]
            continue
        k = max(1, math.ceil(n / size), min(jobs, n // batch_min))
        step = math.ceil(n / k)
        out += [tuple(group[i:i + step]) for i in range(0, len(group), step)]
    return out


@dataclass(frozen=True)
class YearResult:
    """The sweep: ``points`` (one per run: a cooling point, ``heating`` "-", serves both
    heating systems), the grid and the switch-over (degC at the edges; the CLI writes
    ``to_json_dict`` through ``json_in_degC``)."""

    points: tuple[YearPoint, ...]
    ambients_C: tuple[float, ...]
    cycles: tuple[str, ...]
    vehicles: tuple[str, ...]
    switch_C: float
    refrigerant: str | None = None

    def rows(self) -> list[dict]:
        return [p.to_row() for p in self.points]

    def select(self, cycle: str, vehicle: str, heating: str) -> list[YearPoint]:
        """The points of one line (cooling points included), by rising ambient."""
        pts = [p for p in self.points if p.cycle == cycle and p.vehicle == vehicle
               and p.heating in (heating, "-")]
        return sorted(pts, key=lambda p: p.T_amb_K)

    def to_json_dict(self) -> dict:
        from acid.plant.heating_config import HeatingConfig
        from acid.plant.road_load import RoadLoad, epa_label_check

        T_heat = K2C(HeatingConfig().T_heat_set)
        return {"switch_over_C": self.switch_C, "ambients_C": list(self.ambients_C),
                "cycles": list(self.cycles), "vehicles": list(self.vehicles),
                "refrigerant": self.refrigerant or "the vehicle's",
                "rule": (f"heating plant (heat pump first, coolant heater; and heater only) "
                         f"below {self.switch_C:g} degC, target {T_heat:g} degC, no sun, 80 % "
                         f"RH; cooling plant at and above, target the vehicle's T_cab_set, "
                         f"sun and humidity; one pass of each cycle from a soak at ambient"),
                "share": "climate / (traction + 12 V base + climate)",
                "road_load": RoadLoad().to_dict(),
                "road_load_check": [{"cycle": c.cycle, "model_Wh_per_km": c.model_Wh_per_km,
                                     "label_Wh_per_km": [c.label_low_Wh_per_km,
                                                         c.label_high_Wh_per_km],
                                     "passed": c.passed} for c in epa_label_check()],
                "points": [asdict(p) for p in self.points]}


def year_sweep(ambients_C: Sequence[float] = AMBIENTS_C, cycles: Sequence[str] = CYCLES,
               vehicles: Sequence[str] = VEHICLES, switch_C: float = SWITCH_C,
               refrigerant: str | None = None, jobs: int | None = 1, scheduler: str | None = None,
               progress: Callable[[int, int, str], None] | None = None,
               batch_min: int | None = BATCH_MIN) -> YearResult:
    """Run the whole grid through ``acid.executor`` (``jobs`` 1: in this process; more: a
    Dask LocalCluster of that many workers) and return the points.

    The runs go in chunks (``plan_batches``, one executor task each) through ``run_batch``:
    a chunk of at least ``batch_min`` runs steps one batched plant, a smaller one one plant
    per run (``run_task``, the reference the batched points equal to rounding); ``batch_min``
    None: one plant per run everywhere.
    ``progress(done, total, label)`` is called as each run finishes."""
    from acid.executor import check_interrupt, open_executor

    ambients_C = tuple(float(t) for t in ambients_C)
    cycles, vehicles = tuple(cycles), tuple(str(v) for v in vehicles)
    check_grid(ambients_C, cycles, vehicles, switch_C, refrigerant)
    tasks = plan_tasks(ambients_C, cycles, vehicles, switch_C, refrigerant)
    done: dict[YearTask, YearPoint] = {}
    with open_executor(jobs, scheduler) as ex:
        handles = {ex.submit(run_batch, chunk, batch_min): chunk
                   for chunk in plan_batches(tasks, jobs or 1, batch_min=batch_min)}
        pending = list(handles)
        while pending:
            check_interrupt()
            ex.pump()
            for h in ex.wait_any(pending, timeout=0.2):
                pending.remove(h)
                chunk = handles[h]
                points = ex.result(h)
                for task, point in zip(chunk, points, strict=True):
                    done[task] = point
                    if progress is not None:
                        progress(len(done), len(tasks), task.label)
    return YearResult(tuple(done[t] for t in tasks), ambients_C, cycles, vehicles,
                      float(switch_C), refrigerant)


__all__ = ["AMBIENTS_C", "BATCH_MIN", "BATCH_SIZE", "CYCLES", "HEATER_ONLY", "HEAT_PUMP",
           "SWITCH_C", "VEHICLES", "YearPoint", "YearResult", "YearTask", "batch_key", "check_grid",
           "plan_batches", "plan_tasks", "run_batch", "run_task", "year_sweep"]
