"""The comparison engine: verdicts on controller energy that survive resampling.

Protocol (kelvin inside, degC at the edges):

1. **Scenario sets.** A :class:`Scenario` is a drive cycle
   (``acid.studies.cav_study.make_scenario``, ``stopgo`` included), an ambient, solar
   irradiance, ambient RH, an initial soak, a seed and a vehicle (plant configuration).
   :func:`default_set` crosses cycles with ambients and splits them deterministically: for
   each cycle a coin of ``numpy.random.default_rng(seed)`` sends one ambient to the training
   set (knobs tuned there) and the other to the held-out set (judged there), so every cycle,
   stop-and-go included, is in both sets.
2. **Periodic steady state.** Each run repeats the scenario's cycle from its soak until the
   plant's cabin, interior (fast and slow) and shell temperatures at the end of a pass differ
   from the previous pass's by less than ``tol_K`` (default 0.01 K); the energy (compressor +
   blower) of the last pass is the figure, so no end state needs charging. Passes are reported.
   A controller with discrete decisions (E) can settle on a period-2 orbit instead: two
   passes alternate (end states a few hundredths of a kelvin apart) and consecutive passes
   never agree. The same rule applied to the two-pass map (pass k against pass k - 2, once
   the period-1 test has failed and the cabin temperature toggles) detects it; its figures
   (energy, discomfort, mean cabin temperature and humidity) are the mean over the orbit's
   two passes, the cycle average of a period-2 steady state. :attr:`PeriodicRun.period`
   says which was found (``RunSettings.max_period = 1``: the period-1 test alone).
3. **Families with one knob each.** ``F``: fixed coil, run by the plant's own loops (the
   plant's nominal mode: blower PI and compressor PI at the plant's internal step) with the
   coil set-point as knob; ``Fs``: acid's sampled fixed-coil PI of ``acid cav-study``
   (:class:`acid.control.pi_baselines.PlantPI`, blower PI at the 5 s sample), same knob; ``P``:
   production coil reset (:class:`acid.control.pi_baselines.CoilReset`), knob its warm coil
   ``T_warm``; ``own``: the plant's own loops at its configured coil (no knob); ``E``:
   economic NMPC with speed preview, knob its comfort weight. Every family is swept on the
   training set to a front (mean energy vs mean discomfort); the knob that meets the common
   comfort level at least energy (linear interpolation between swept knobs) is then judged.
4. **Verdicts.** Paired differences per held-out scenario (baseline minus candidate, percent
   of the baseline: positive = the candidate saves), a seeded paired bootstrap 95 % interval
   with the paired t interval beside it. Words from the interval: "saves" (above 0),
   "costs" (below 0), "no resolvable difference" (straddles 0); fewer than
   ``MIN_SCENARIOS`` held-out scenarios: "not resolved".
5. **Equal mean cabin temperature.** A family that holds its cabin a little warmer than F
   buys energy with comfort (0.02 K is about 0.1 %). So every family but F and ``own`` is also
   run on each held-out scenario with its target lowered by ``MATCH_SHIFT_K``, and its energy
   and discomfort are interpolated linearly in the mean cabin temperature to F's mean on that
   scenario (extrapolated at most ``MATCH_EXTRAPOLATE`` spans; beyond, the scenario counts
   as not matched). The verdicts "X at F's T_cab vs F" read off these matched pairs.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from acid.errors import ConfigError
from acid.studies.verdict import (  # noqa: F401 (the engine's rule, re-exported)
    MAX_DISCOMFORT_GAP_KMIN,
    MAX_WARMER_K,
    MIN_SCENARIOS,
    UNEQUAL,
    paired_verdict,
)
from acid.units import C2K

#: default cycles and ambients (degC) of the default scenario set
DEFAULT_CYCLES = ("udds", "sc03", "hwfet", "us06", "stopgo")
DEFAULT_AMBIENTS_C = (30.0, 38.0)
#: the temperatures whose repetition between passes defines the periodic steady state
PERIODIC_KEYS = ("T_cab", "T_int", "T_int_slow", "T_shell")
SAVES, NONE, COSTS, UNRESOLVED = ("saves", "no resolvable difference", "costs",
                                  "not resolved")
#: comfort gaps beyond which a saving is not read (candidate minus baseline, held-out mean):
#: discomfort, K min per pass, and mean cabin temperature, K (0.02 K is about 0.1 % energy)
#: the second held-out run's lowered target, K, and how far (in spans of the two runs' mean
#: cabin temperatures) the matched energy may be extrapolated (module docstring, 5.)
MATCH_SHIFT_K = 0.3
MATCH_EXTRAPOLATE = 1.0
#: the suffix of a family's name in a verdict judged at the baseline's mean cabin temperature,
#: and of its held-out runs at the lowered target
MATCHED = " at F's T_cab"
LOWERED = " lowered"


# ------------------------------------------------------------------------------ scenarios
@dataclass(frozen=True)
class Scenario:
    """One driving situation (degC and percent at the edges, stored in K and fractions).

    ``soak_K`` None: the plant's own initial state; otherwise cabin, interior and shell all
    start at this temperature. ``vehicle`` is a plant configuration path or vehicle name
    (None: the default plant), ``refrigerant`` replaces its refrigerant (None: its own).
    ``stopgo_s`` is the stop-and-go cycle's length.
    """

    cycle: str
    T_amb: float
    G_solar: float = 850.0
    RH_amb: float = 0.5
    soak_K: float | None = None
    seed: int = 0
    vehicle: str | None = None
    stopgo_s: float = 800.0
    refrigerant: str | None = None

    @property
    def name(self) -> str:
        return f"{self.cycle}@{self.T_amb - 273.15:g}C"

    def plant_config(self):
        from acid.plant import make_plant

        base = make_plant("hifi", config_path=self.vehicle).cfg
        extra = {} if self.refrigerant is None else {"refrigerant": self.refrigerant}
        return base.replace(T_amb=float(self.T_amb), G_solar=float(self.G_solar),
                            RH_amb=float(self.RH_amb), **extra)

    def drive(self):
        """The cycle as ``acid.studies.cav_study.Scenario`` (speed per 5 s sample)."""
        from acid.studies.cav_study import make_scenario

        return make_scenario(self.cycle, self.plant_config().Ts, float(self.T_amb),
                             self.stopgo_s)

    def start(self) -> dict | None:
        if self.soak_K is None:
            return None
        return {k: float(self.soak_K) for k in ("T_cab", "T_int", "T_int_slow", "T_shell",
                                                 "T_evap", "T_cw")}

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class ScenarioSet:
    """Training (tune knobs) and held-out (judge) scenarios, and the split's rule."""

    training: tuple[Scenario, ...]
    held_out: tuple[Scenario, ...]
    rule: str

    def to_dict(self) -> dict:
        return {"training": [s.to_dict() for s in self.training],
                "held_out": [s.to_dict() for s in self.held_out], "rule": self.rule}

    @classmethod
    def from_dict(cls, d: dict) -> ScenarioSet:
        return cls(tuple(Scenario(**s) for s in d["training"]),
                   tuple(Scenario(**s) for s in d["held_out"]), d["rule"])


def default_set(cycles: Sequence[str] = DEFAULT_CYCLES,
                ambients_C: Sequence[float] = DEFAULT_AMBIENTS_C, seed: int = 0,
                stopgo_s: float = 800.0, vehicle: str | None = None,
                refrigerant: str | None = None) -> ScenarioSet:
    """Each cycle at each ambient; per cycle a seeded permutation of the ambients sends the
    first half to training and the rest to held-out (module docstring)."""
    if len(ambients_C) < 2:
        raise ConfigError("--t-amb: give at least two ambients (one trains, one judges)")
    rng = np.random.default_rng(seed)
    train, held = [], []
    for i, c in enumerate(cycles):
        order = rng.permutation(len(ambients_C))
        h = len(order) // 2
        for j, a in enumerate(order):
            s = Scenario(cycle=c, T_amb=C2K(float(ambients_C[a])), seed=seed * 1000 + i,
                         vehicle=vehicle, stopgo_s=stopgo_s, refrigerant=refrigerant)
            (train if j < h else held).append(s)
    return ScenarioSet(tuple(train), tuple(held),
                       f"per cycle, numpy default_rng({seed}).permutation of the ambients: "
                       "first half trains, the rest is held out")


# ------------------------------------------------------------------------------ controllers
@dataclass(frozen=True)
class Family:
    """A controller family with one knob; ``knobs`` are swept on training (SI units)."""

    key: str
    label: str
    knob: str
    knobs: tuple[float, ...]


def families(quick: bool = False, econ: bool = True) -> tuple[Family, ...]:
    coils = (C2K(6.0), C2K(8.0), C2K(10.0)) if quick else tuple(
        C2K(c) for c in (5.0, 7.0, 8.5, 10.0))
    out = [Family("F", "fixed coil, plant's own loops", "coil set-point, K", coils),
           Family("Fs", "fixed coil, acid's sampled PI (cav-study F)", "coil set-point, K",
                  coils),
           Family("P", "production coil reset", "warm coil T_warm, K",
                  (C2K(8.0), C2K(11.0)) if quick else (C2K(8.0), C2K(10.0), C2K(12.0))),
           Family("own", "plant's own loops, configured coil", "none", (math.nan,))]
    if econ:
        out.append(Family("E", "economic NMPC, speed preview", "comfort weight, W/K^2 s",
                          (3.0, 30.0) if quick else (30.0, 300.0, 3000.0)))
    return tuple(out)


@dataclass(frozen=True)
class RunSettings:
    """What every run shares: cabin set-point and comfort band (K); the periodic state's
    tolerances on the distance still to go (extrapolated from the last two passes): cabin,
    interior and shell temperatures ``tol_K`` (K), cabin humidity ``tol_w`` (kg/kg), the
    pass energy ``tol_E`` (relative)."""

    T_set: float = C2K(24.0)
    T_low: float = C2K(23.0)
    T_high: float = C2K(25.0)
    tol_K: float = 0.01
    tol_w: float = 1e-5
    tol_E: float = 5e-4
    max_passes: int = 400
    #: the longest orbit accepted as the periodic steady state, in passes (1 or 2)
    max_period: int = 2
    econ_horizon_s: float = 60.0
    tail_s: float = 2400.0
    econ_ref_offset_K: float = 0.0


#: ``--quick``: looser periodic tolerances (tests and smoke runs)
QUICK = RunSettings(tol_K=0.05, tol_w=1e-4, tol_E=2e-3, max_passes=30, tail_s=600.0)

#: the two charge conventions of a single pass: the continuation that prices a state
CHARGES = {"own": "the plant's own loops at its configured coil",
           "pi": "acid's sampled fixed-coil PI at the plant's configured coil"}


def _controller(family: str, knob: float, settings: RunSettings, cfg, drive, econ):
    """(nominal, controller or None, plant config) for one family and knob."""
    from acid.control.pi_baselines import CoilReset, PlantPI
    from acid.psychro import P_ATM

    p_atm = float(getattr(cfg, "p_atm", P_ATM))
    if family in ("F", "own"):
        # the plant's low-load reset range widened only as far as the knob needs
        c = cfg if family == "own" else cfg.replace(
            T_ew_set=float(knob), T_ew_set_max=max(cfg.T_ew_set_max, float(knob) + 0.5))
        return True, None, c
    if family == "Fs":
        return False, PlantPI(cfg, drive.Ts, settings.T_set, float(knob), p_atm), cfg
    if family == "P":
        return False, PlantPI(cfg, drive.Ts, settings.T_set, CoilReset(T_warm=float(knob)),
                              p_atm), cfg
    if family == "E":
        from acid.control.econ.nmpc import EconNMPC, EconNMPCConfig
        from acid.studies.cav_study import EconPreview

        n = int(round(settings.econ_horizon_s / drive.Ts))
        mpc = EconNMPC(econ, EconNMPCConfig(intervals=(drive.Ts,) * n, preview=True,
                                            T_cab_min=settings.T_low - 1.0,
                                            T_cab_max=settings.T_high + 1.0,
                                            comfort_weight=float(knob)))
        # E's comfort price pulls toward T_set - offset: the offset (tuned on training, see
        # compare) moves E's mean cabin onto F's, so E is judged at equal mean comfort
        return False, EconPreview(mpc, drive, settings.T_set - settings.econ_ref_offset_K), cfg
    raise ConfigError(f"unknown controller family {family!r}")


@dataclass(frozen=True)
class PeriodicRun:
    """One family/knob on one scenario at periodic steady state (J, K min, fractions)."""

    scenario: str
    family: str
    knob: float
    energy_J: float
    discomfort_Kmin: float
    rh_mean: float
    mean_T_cab: float
    passes: int
    converged: bool
    residual_K: float
    first_pass_J: float
    end: dict = field(default_factory=dict)
    #: the econ model's inputs a controller's plans took outside the data its power map was
    #: identified on (E only: the model's envelope; empty when it stayed inside)
    extrapolated: tuple[str, ...] = ()
    single_own_J: float = math.nan
    single_pi_J: float = math.nan
    #: the period of the steady state found, in passes: 1 (the pass repeats) or 2 (two
    #: passes alternate; the figures are the two passes' mean, the cycle average)
    period: int = 1

    def single_charged_J(self, charge: str) -> float:
        """The first pass from the common start with its state change charged: ``E +
        tail(end) - tail(start)``, the tail under ``charge`` (:data:`CHARGES`), J."""
        return {"own": self.single_own_J, "pi": self.single_pi_J}[charge]


def _pass(plant, ctrl, drive, T_set: float):
    from acid.psychro import relative_humidity

    if ctrl is not None:
        ctrl.reset()
    E = 0.0
    T, rh = [], []
    for k in range(drive.n):
        meas = plant.measure()
        if ctrl is None:
            row = plant.step(0.0, 0.0, float(drive.v[k]), T_amb=float(drive.T_amb[k]),
                             T_cab_set=T_set)
        else:
            u = ctrl.make_step(meas, k)
            row = plant.step(float(u[0]), float(u[1]), float(drive.v[k]),
                             T_amb=float(drive.T_amb[k]))
        E += (float(row["P_comp"]) + float(row["P_bl"])) * drive.Ts
        m = plant.measure()
        T.append(float(m["T_cab"]))
        rh.append(float(relative_humidity(float(m["T_cab"]), float(m["w_cab"]))))
    return E, np.asarray(T), np.asarray(rh)


def periodic_run(sc: Scenario, family: str, knob: float, settings: RunSettings = RunSettings(),
                 econ=None, start: dict | None = None, charge: bool = False) -> PeriodicRun:
    """Repeat the scenario's cycle until the pass-end states repeat (module docstring).

    ``charge``: also the single pass beside it, the first pass from ``start`` with its state
    change charged under both conventions (:data:`CHARGES`, ``settings.tail_s`` long)."""
    import warnings

    from acid.errors import ExtrapolationWarning
    from acid.plant.hifi import HifiPlant, physical_state
    from acid.studies.cav_study import plant_state

    warnings.simplefilter("ignore", ExtrapolationWarning)  # E's econ model off its data

    drive = sc.drive()
    cfg = sc.plant_config()
    nominal, ctrl, pcfg = _controller(family, knob, settings, cfg, drive, econ)
    plant = HifiPlant(pcfg, mode="nominal" if nominal else "direct")
    # a shared start carries the car's states, never another controller's loop memory
    plant.reset(physical_state(start) if start is not None else sc.start())
    prev = plant_state(plant)
    start_state = dict(prev)
    first = math.nan
    first_end: dict = {}
    res, last = math.inf, {}
    period = 1
    # per pass: end state, energy and the pass's (discomfort K min, mean RH, mean T_cab)
    ends, Es, stats, steps2 = [prev], [math.nan], [None], [{}]
    outside: list[str] = []
    for p in range(1, settings.max_passes + 1):
        E, T, rh = _pass(plant, ctrl, drive, settings.T_set)
        outside += [n for n in getattr(getattr(ctrl, "mpc", None), "extrapolation", ())
                    if n not in outside]
        if p == 1:
            first, first_end = E, plant_state(plant)
        now = plant_state(plant)
        out = np.maximum(0.0, np.maximum(T - settings.T_high, settings.T_low - T))
        ends.append(now)
        Es.append(E)
        stats.append((float(np.sum(out) * drive.Ts / 60.0), float(np.mean(rh)),
                      float(np.mean(T))))
        steps = _steps(now, prev, E, Es[-2], settings)
        res = _residual(steps, last, settings)
        prev, last = now, steps
        if p >= 3 and res < settings.tol_K:
            break
        # a period-2 orbit (module docstring, 2.): the same rule on the two-pass map
        steps2.append(_steps(now, ends[-3], E, Es[-3], settings) if p >= 2 else {})
        if settings.max_period >= 2 and p >= 5:
            res2 = _residual(steps2[-1], steps2[-3], settings)
            dT = [ends[i]["T_cab"] - ends[i - 1]["T_cab"] for i in (-1, -2)]
            if res2 < settings.tol_K and dT[0] * dT[1] < 0.0:
                res, period = res2, 2
                break
    n = period  # the figures: the last pass (period 1) or the orbit's two passes' mean
    figures = [float(np.mean([s[j] for s in stats[-n:]])) for j in range(3)]
    E = Es[-1] if n == 1 else float(np.mean(Es[-n:]))
    charged = {c: first + tail_J(sc, first_end, c, settings)
               - tail_J(sc, start_state, c, settings) for c in CHARGES} if charge else {}
    return PeriodicRun(sc.name, family, float(knob), E, *figures, p,
                       bool(res < settings.tol_K), float(res), first, plant_state(plant),
                       tuple(outside), charged.get("own", math.nan),
                       charged.get("pi", math.nan), period)


def _steps(now: dict, before: dict, E: float, E_before: float, settings: RunSettings) -> dict:
    """The change of the pass-end state from ``before`` (each quantity scaled to the
    temperature tolerance; the energy's infinite without an earlier pass)."""
    return {"T": max(abs(now[k] - before[k]) for k in PERIODIC_KEYS if k in now),
            "w": abs(now["w_cab"] - before["w_cab"]) * settings.tol_K / settings.tol_w,
            "E": abs(E - E_before) / abs(E) * settings.tol_K / settings.tol_E
            if math.isfinite(E_before) and E else math.inf}


def _residual(steps: dict, last: dict, settings: RunSettings) -> float:
    """The distance still to go to the periodic state, from the last two steps of the map:
    a slow mode contracting by rho per step leaves step * rho / (1 - rho) to go (rho from
    the last two steps, the factor at most 20); a step no smaller than the last is the
    loops' cycling, not a slow mode (factor 1)."""
    res = 0.0
    for q, st in steps.items():
        rho = st / last[q] if last.get(q, 0) > 0 else 0.95
        res = max(res, st * (min(20.0, max(1.0, rho / (1.0 - rho))) if rho < 1 else 1.0))
    return res


def tail_J(sc: Scenario, state: dict, charge: str, settings: RunSettings) -> float:
    """Energy of the common continuation from ``state`` (J): ``settings.tail_s`` at the
    cycle's mean speed and ambient under ``charge`` (:data:`CHARGES`). The same state costs
    the same under one convention, so ``E + tail(end) - tail(start)`` charges a pass the
    state it leaves behind. (Deterministic: a repeated call, as every family's run from a
    scenario's common start makes, is answered from a small cache of this process.)"""
    if charge not in CHARGES:
        raise ConfigError(f"unknown charge convention {charge!r}")
    return _tail_J(sc, tuple(sorted(state.items())), charge, float(settings.T_set),
                   float(settings.tail_s))


@functools.lru_cache(maxsize=64)
def _tail_J(sc: Scenario, state: tuple, charge: str, T_set: float, tail_s: float) -> float:
    from acid.control.pi_baselines import PlantPI
    from acid.plant.hifi import HifiPlant, physical_state
    from acid.psychro import P_ATM

    cfg, drive = sc.plant_config(), sc.drive()
    v, T_amb = float(np.mean(drive.v)), float(np.mean(drive.T_amb))
    plant = HifiPlant(cfg, mode="nominal" if charge == "own" else "direct")
    plant.reset(physical_state(dict(state)))  # the tail's loops start from their own memory
    ctrl = None if charge == "own" else PlantPI(cfg, drive.Ts, T_set, float(cfg.T_ew_set),
                                                float(getattr(cfg, "p_atm", P_ATM)))
    E = 0.0
    for k in range(int(round(tail_s / drive.Ts))):
        if ctrl is None:
            row = plant.step(0.0, 0.0, v, T_amb=T_amb, T_cab_set=T_set)
        else:
            u = ctrl.make_step(plant.measure(), k)
            row = plant.step(float(u[0]), float(u[1]), v, T_amb=T_amb)
        E += (float(row["P_comp"]) + float(row["P_bl"])) * drive.Ts
    return E


# ------------------------------------------------------------------------------ statistics
@dataclass(frozen=True)
class Verdict:
    """Candidate vs baseline over paired held-out scenarios (saving in percent of the
    baseline; positive: the candidate uses less)."""

    candidate: str
    baseline: str
    scenarios: tuple[str, ...]
    savings_pct: tuple[float, ...]
    mean_pct: float
    boot_lo: float
    boot_hi: float
    t_lo: float
    t_hi: float
    word: str
    n_boot: int
    seed: int
    discomfort_gap_Kmin: float = 0.0
    T_cab_gap_K: float = 0.0
    single_own_pct: float = math.nan
    single_pi_pct: float = math.nan

    def summary(self) -> str:
        single = "" if math.isnan(self.single_own_pct) else (
            f" (single pass, charged: {self.single_own_pct:+.2f} % by the plant's loops, "
            f"{self.single_pi_pct:+.2f} % by acid's PI; figures, not verdicts)")
        return (f"{self.candidate} vs {self.baseline}: {self.mean_pct:+.2f} % "
                f"[{self.boot_lo:+.2f}, {self.boot_hi:+.2f}] bootstrap 95 %, "
                f"[{self.t_lo:+.2f}, {self.t_hi:+.2f}] paired t, n = {len(self.scenarios)}, "
                f"comfort gap {self.discomfort_gap_Kmin:+.2f} K min, mean T_cab "
                f"{self.T_cab_gap_K:+.2f} K: {self.word}{single}")

    def __repr__(self) -> str:
        return f"Verdict({self.summary()})"

    def to_dict(self) -> dict:
        """Its fields, and the field names every verdict of acid reports
        (:meth:`acid.studies.verdict.Verdict.to_dict`, as heating-control and sweep write
        them): n, mean, lo/hi (paired t), boot_lo/boot_hi, level, words, decided_by."""
        return _json_safe({**dataclasses.asdict(self), **{
            "n": len(self.scenarios), "mean": self.mean_pct, "lo": self.t_lo, "hi": self.t_hi,
            "level": 0.95, "words": self.word, "decided_by": "both"}})

    @classmethod
    def from_dict(cls, d: dict) -> Verdict:
        d = {k: v for k, v in d.items() if k not in _SHARED}
        d["scenarios"] = tuple(d["scenarios"])
        d["savings_pct"] = tuple(_num(x) for x in d["savings_pct"])
        for k in ("mean_pct", "boot_lo", "boot_hi", "t_lo", "t_hi", "discomfort_gap_Kmin",
                  "T_cab_gap_K", "single_own_pct", "single_pi_pct"):
            if k in d:
                d[k] = _num(d[k])
        return cls(**d)


#: the shared verdict field names :meth:`Verdict.to_dict` adds (read back from its own)
_SHARED = ("n", "mean", "lo", "hi", "level", "words", "decided_by")


def _num(x):
    return math.nan if x is None else float(x)


def _json_safe(d):
    if isinstance(d, dict):
        return {k: _json_safe(v) for k, v in d.items()}
    if isinstance(d, list | tuple):
        return [_json_safe(v) for v in d]
    if isinstance(d, float) and not math.isfinite(d):
        return None
    return d


def paired_bootstrap(diff: Sequence[float], seed: int, n_boot: int = 10000,
                     level: float = 0.95) -> tuple[float, float]:
    """Percentile interval of the mean of paired differences (seeded resampling)."""
    d = np.asarray(diff, dtype=float)
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, d.size, size=(n_boot, d.size))
    means = d[idx].mean(axis=1)
    a = (1.0 - level) / 2.0
    return float(np.quantile(means, a)), float(np.quantile(means, 1.0 - a))


def paired_t(diff: Sequence[float], level: float = 0.95) -> tuple[float, float]:
    from scipy import stats

    d = np.asarray(diff, dtype=float)
    if d.size < 2:
        return math.nan, math.nan
    s = float(np.std(d, ddof=1)) / math.sqrt(d.size)
    q = float(stats.t.ppf(0.5 + level / 2.0, d.size - 1))
    return float(d.mean() - q * s), float(d.mean() + q * s)


def verdict(candidate: str, baseline: str, names: Sequence[str], e_cand: Sequence[float],
            e_base: Sequence[float], seed: int = 0, n_boot: int = 10000,
            min_scenarios: int = MIN_SCENARIOS, discomfort_gap_Kmin: float = 0.0,
            T_cab_gap_K: float = 0.0) -> Verdict:
    """The verdict word from the bootstrap interval (and the t interval: both must agree
    for "saves" or "costs"); fewer than ``min_scenarios`` pairs: "not resolved"; a candidate
    less comfortable than the baseline (held-out discomfort more than
    ``MAX_DISCOMFORT_GAP_KMIN`` above, or a mean cabin more than ``MAX_WARMER_K`` warmer)
    that would "save" or show no difference: "not at equal comfort"."""
    eb, ec = np.asarray(e_base, float), np.asarray(e_cand, float)
    s = 100.0 * (eb - ec) / eb
    # the one reading of an interval (acid.studies.verdict): both intervals must exclude zero
    v = paired_verdict(s, min_count=1, n_boot=n_boot, seed=seed, decide="both")
    lo, hi = (v.boot_lo, v.boot_hi) if v.boot_lo is not None else paired_bootstrap(s, seed,
                                                                                   n_boot)
    tlo, thi = (v.lo, v.hi) if v.lo is not None else (math.nan, math.nan)
    word = UNRESOLVED if s.size < min_scenarios else {
        "saves": SAVES, "costs": COSTS}.get(v.words, NONE)
    if word in (SAVES, NONE) and (discomfort_gap_Kmin > MAX_DISCOMFORT_GAP_KMIN
                                  or T_cab_gap_K > MAX_WARMER_K):
        word = UNEQUAL
    return Verdict(candidate, baseline, tuple(names), tuple(float(x) for x in s),
                   float(s.mean()), lo, hi, tlo, thi, word, int(n_boot), int(seed),
                   float(discomfort_gap_Kmin), float(T_cab_gap_K))


# ------------------------------------------------------------------------------ the study
@dataclass(frozen=True)
class FrontPoint:
    family: str
    knob: float
    energy_J: float
    discomfort_Kmin: float
    rh_mean: float


@dataclass(frozen=True)
class CompareResult:
    """Fronts on training, tuned knobs, held-out runs and verdicts."""

    scenarios: ScenarioSet
    comfort_level_Kmin: float
    fronts: tuple[FrontPoint, ...]
    tuned: dict = field(default_factory=dict)
    held_out: tuple[PeriodicRun, ...] = ()
    verdicts: tuple[Verdict, ...] = ()
    settings: dict = field(default_factory=dict)

    def summary(self) -> str:
        lines = ["training: " + ", ".join(s.name for s in self.scenarios.training),
                 "held out: " + ", ".join(s.name for s in self.scenarios.held_out),
                 f"comfort level: {self.comfort_level_Kmin:.2f} K min per pass outside the "
                 "band (mean over training)"]
        for f, k in self.tuned.items():
            lines.append(f"  {f}: knob {k:.4g} tuned on training")
        lines += [v.summary() for v in self.verdicts]
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (f"CompareResult({len(self.scenarios.training)} training, "
                f"{len(self.scenarios.held_out)} held out, {len(self.verdicts)} verdicts)")

    def to_dict(self) -> dict:
        return _json_safe({
            "scenarios": self.scenarios.to_dict(), "comfort_level_Kmin": self.comfort_level_Kmin,
            "fronts": [dataclasses.asdict(p) for p in self.fronts], "tuned": dict(self.tuned),
            "held_out": [dataclasses.asdict(r) for r in self.held_out],
            "verdicts": [v.to_dict() for v in self.verdicts], "settings": dict(self.settings)})

    @classmethod
    def from_dict(cls, d: dict) -> CompareResult:
        def fix(x: dict, keys):
            return {k: (_num(v) if k in keys else v) for k, v in x.items()}

        return cls(ScenarioSet.from_dict(d["scenarios"]), _num(d["comfort_level_Kmin"]),
                   tuple(FrontPoint(**fix(p, ("knob", "energy_J", "discomfort_Kmin",
                                                "rh_mean"))) for p in d["fronts"]),
                   {k: _num(v) for k, v in d["tuned"].items()},
                   tuple(PeriodicRun(**{**fix(r, ("knob", "energy_J", "discomfort_Kmin",
                                                  "rh_mean", "mean_T_cab", "residual_K",
                                                  "first_pass_J", "single_own_J",
                                                  "single_pi_J")),
                                        "extrapolated": tuple(r.get("extrapolated", ()))})
                         for r in d["held_out"]),
                   tuple(Verdict.from_dict(v) for v in d["verdicts"]), dict(d["settings"]))

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=1)


def _task(sc: Scenario, family: str, knob: float, settings: RunSettings, econ,
          start: dict | None = None, charge: bool = False):
    return periodic_run(sc, family, knob, settings, econ, start, charge)


def _map(tasks, executor, progress):
    """Run ``tasks`` (argument tuples of :func:`_task`), through ``executor`` if given."""
    out = [None] * len(tasks)
    if executor is None:
        for i, t in enumerate(tasks):
            out[i] = _task(*t)
            if progress:
                progress(f"{i + 1}/{len(tasks)} {t[0].name} {t[1]} knob {t[2]:.4g}: "
                         f"{out[i].energy_J / 1e6:.3f} MJ, {out[i].passes} passes{_orbit(out[i])}")
        return out
    handles = {executor.submit(_task, *t): i for i, t in enumerate(tasks)}
    pending, done = set(handles), 0
    while pending:
        for h in executor.wait_any(pending):
            pending.discard(h)
            i = handles[h]
            out[i] = executor.result(h)
            done += 1
            if progress:
                progress(f"{done}/{len(tasks)} {tasks[i][0].name} {tasks[i][1]}: "
                         f"{out[i].energy_J / 1e6:.3f} MJ, {out[i].passes} passes{_orbit(out[i])}")
    return out


def _orbit(r: PeriodicRun) -> str:
    """How a run's periodic state is shown beside its passes."""
    return ("" if r.converged else ", not converged") + (", period 2" if r.period == 2 else "")


def tune_knob(points: Sequence[FrontPoint], level: float) -> float:
    """The knob meeting the comfort ``level`` at least energy: among the swept knobs
    whose discomfort is at most ``level`` the cheapest, moved toward its cheaper
    neighbour by linear interpolation in discomfort up to the level."""
    pts = sorted(points, key=lambda p: p.knob)
    ok = [p for p in pts if p.discomfort_Kmin <= level + 1e-9]
    if not ok:
        return min(pts, key=lambda p: p.discomfort_Kmin).knob
    best = min(ok, key=lambda p: p.energy_J)
    i = pts.index(best)
    for j in (i - 1, i + 1):
        if 0 <= j < len(pts) and pts[j].energy_J < best.energy_J \
                and pts[j].discomfort_Kmin > level:
            q = pts[j]
            f = (level - best.discomfort_Kmin) / (q.discomfort_Kmin - best.discomfort_Kmin)
            return float(best.knob + f * (q.knob - best.knob))
    return best.knob


@dataclass(frozen=True)
class Tuning:
    """What the training set decided: the fronts (mean over training per family and knob),
    the common comfort level (K min per pass), the tuned knob of each family, and the
    settings E is judged with (its cabin reference offset, K)."""

    fronts: tuple[FrontPoint, ...]
    level: float
    tuned: dict
    esettings: RunSettings


def _mid_knob(fams: Sequence[Family]) -> float:
    mid = [f for f in fams if f.key == "F"]
    return mid[0].knobs[len(mid[0].knobs) // 2] if mid else C2K(8.0)


def warm_tasks(scenarios: Sequence[Scenario], fams: Sequence[Family],
               settings: RunSettings) -> list[tuple]:
    """The common start of every run on a scenario: the periodic state of F's middle knob
    (a warm start: the periodic state does not depend on the start, it only saves passes;
    only the car's states are shared, see :func:`acid.plant.hifi.physical_state`)."""
    return [(sc, "F", _mid_knob(fams), settings, None) for sc in scenarios]


def training_tasks(scenarios: Sequence[Scenario], fams: Sequence[Family],
                   settings: RunSettings, econ, starts: dict) -> list[tuple]:
    """Every family at every knob on each training scenario (arguments of one run)."""
    return [(sc, f.key, k, settings, econ, starts[sc.name]) for f in fams for k in f.knobs
            for sc in scenarios]


def tune(fams: Sequence[Family], tasks: Sequence[tuple], runs: Sequence[PeriodicRun],
         settings: RunSettings) -> Tuning:
    """Fronts, comfort level and tuned knobs from the training runs (``tasks`` as made by
    :func:`training_tasks`, in any order; ``runs`` their results).

    The comfort level is the plant's own loops' mean training discomfort (``own``), or the
    least family mean when ``own`` is absent. E's second knob, its cabin reference: on
    training at the swept weight nearest the tuned one, E's mean cabin minus F's at its
    tuned coil (nearest swept) is taken off E's reference."""
    fronts = []
    for f in fams:
        for k in f.knobs:
            rs = [r for r, t in zip(runs, tasks, strict=True) if t[1] == f.key
                  and (t[2] == k or (math.isnan(k) and math.isnan(t[2])))]
            fronts.append(FrontPoint(f.key, float(k), float(np.mean([r.energy_J for r in rs])),
                                     float(np.mean([r.discomfort_Kmin for r in rs])),
                                     float(np.mean([r.rh_mean for r in rs]))))
    own = [p for p in fronts if p.family == "own"]
    level = own[0].discomfort_Kmin if own else min(
        max(p.discomfort_Kmin for p in fronts if p.family == f.key) for f in fams)
    tuned = {f.key: tune_knob([p for p in fronts if p.family == f.key], level) for f in fams}
    esettings = settings
    if "E" in tuned and "F" in tuned:
        def train_mean(fam):
            ks = sorted({t[2] for t in tasks if t[1] == fam}, key=lambda k: abs(k - tuned[fam]))
            return float(np.mean([r.mean_T_cab for r, t in zip(runs, tasks, strict=True)
                                  if t[1] == fam and t[2] == ks[0]]))
        esettings = dataclasses.replace(settings, econ_ref_offset_K=float(
            np.clip(train_mean("E") - train_mean("F"), -1.0, 1.0)))
    return Tuning(tuple(fronts), float(level), tuned, esettings)


def held_out_tasks(scenarios: Sequence[Scenario], fams: Sequence[Family], tuning: Tuning,
                   settings: RunSettings, econ, starts: dict,
                   match_mean: bool = True) -> list[tuple]:
    """Each family at its tuned knob on each held-out scenario (single pass charged beside),
    and, with ``match_mean``, every family but F and ``own`` again at a target
    ``MATCH_SHIFT_K`` lower (module docstring, 5.)."""
    keys = [f.key for f in fams]
    out = [(sc, f.key, tuning.tuned[f.key], tuning.esettings if f.key == "E" else settings,
            econ, starts[sc.name], True) for f in fams for sc in scenarios]
    if match_mean and "F" in keys:
        lowered = dataclasses.replace(settings, T_set=settings.T_set - MATCH_SHIFT_K)
        out += [(sc, k, tuning.tuned[k], lowered, econ, starts[sc.name]) for k in keys
                if k not in ("F", "own") for sc in scenarios]
    return out


def assemble(scenarios: ScenarioSet, fams: Sequence[Family], settings: RunSettings,
             tuning: Tuning, tasks: Sequence[tuple], runs: Sequence[PeriodicRun],
             seed: int = 0, n_boot: int = 10000, candidate: str = "E",
             min_scenarios: int = MIN_SCENARIOS, match_mean: bool = True) -> CompareResult:
    """The verdicts from the held-out runs (``tasks`` from :func:`held_out_tasks`, in any
    order, and their ``runs``): ``candidate`` (if run) and every family against ``F``,
    ``F`` against ``own``; with ``match_mean`` every family but ``F`` and ``own`` again at
    F's mean cabin temperature."""
    lowered = [r for r, t in zip(runs, tasks, strict=True) if len(t) < 7]
    hruns = [r for r, t in zip(runs, tasks, strict=True) if len(t) == 7]
    by = {(r.family, r.scenario): r for r in hruns}
    names = [s.name for s in scenarios.held_out]
    keys = [f.key for f in fams]
    pairs = [(candidate, "F")] if candidate in keys and "F" in keys else []
    pairs += [(k, "F") for k in keys if k not in ("F", candidate)]
    if "own" in keys and "F" in keys:
        pairs.append(("F", "own"))
    verdicts = [judge(by, names, c, b, seed, n_boot, min_scenarios) for c, b in pairs]
    if match_mean and "F" in keys:
        lower = {(r.family, r.scenario): r for r in lowered}
        for k in sorted((k for k in keys if k not in ("F", "own")), key=lambda k: k != candidate):
            matched = {n: match_to_mean(by[k, n], lower[k, n], by["F", n].mean_T_cab)
                       for n in names}
            ok = [n for n in names if matched[n] is not None]
            mby = {("F", n): by["F", n] for n in ok}
            mby.update({(k + MATCHED, n): matched[n] for n in ok})
            verdicts.append(judge(mby, ok, k + MATCHED, "F", seed, n_boot, min_scenarios)
                            if ok else Verdict(k + MATCHED, "F", (), (), *(math.nan,) * 5,
                                               UNRESOLVED, int(n_boot), int(seed)))
        hruns += [dataclasses.replace(r, family=r.family + LOWERED) for r in lowered]
    return CompareResult(scenarios, tuning.level, tuning.fronts, tuning.tuned, tuple(hruns),
                         tuple(verdicts), _json_safe(dataclasses.asdict(tuning.esettings)))


def compare(scenarios: ScenarioSet, fams: Sequence[Family], settings: RunSettings = RunSettings(),
            econ=None, seed: int = 0, n_boot: int = 10000, candidate: str = "E",
            executor=None, progress: Callable[[str], None] | None = None,
            min_scenarios: int = MIN_SCENARIOS, match_mean: bool = True) -> CompareResult:
    """Sweep every family on training, tune at the common comfort level, judge on held-out
    (:func:`warm_tasks`, :func:`training_tasks`, :func:`tune`, :func:`held_out_tasks`,
    :func:`assemble`; ``acid reproduce`` runs the same pieces as tasks of its graph)."""
    if progress:
        progress(f"training: {len(scenarios.training)} scenarios x "
                 f"{sum(len(f.knobs) for f in fams)} family settings")
    allsc = scenarios.training + scenarios.held_out
    warm = _map(warm_tasks(allsc, fams, settings), executor, progress)
    starts = {sc.name: r.end for sc, r in zip(allsc, warm, strict=True)}
    tasks = training_tasks(scenarios.training, fams, settings, econ, starts)
    tuning = tune(fams, tasks, _map(tasks, executor, progress), settings)
    if progress and tuning.esettings is not settings:
        progress(f"E's cabin reference {tuning.esettings.econ_ref_offset_K:+.3f} K off the "
                 "set-point (its training mean matched to F's)")
    if progress:
        progress("held out: " + ", ".join(s.name for s in scenarios.held_out)
                 + (f" (and at a target {MATCH_SHIFT_K:g} K lower: mean cabin matched to F)"
                    if match_mean else ""))
    htasks = held_out_tasks(scenarios.held_out, fams, tuning, settings, econ, starts,
                            match_mean)
    return assemble(scenarios, fams, settings, tuning, htasks,
                    _map(htasks, executor, progress), seed, n_boot, candidate,
                    min_scenarios, match_mean)


#: the word when the econ model's identification records disagree on a verdict
RECORD_DEPENDENT = "depends on the identification record"


def across_records(results: Sequence[CompareResult], candidate: str, baseline: str
                   ) -> tuple[str, tuple[Verdict, ...]]:
    """One verdict judged again with econ models identified on different excitation records
    (one :class:`CompareResult` per record, same scenarios): its word where every record
    gives the same word, else :data:`RECORD_DEPENDENT`; and the verdict of each record."""
    vs = tuple(v for r in results for v in r.verdicts
               if v.candidate == candidate and v.baseline == baseline)
    if len(vs) != len(results):
        raise ConfigError(f"no verdict {candidate} vs {baseline} in every record")
    words = {v.word for v in vs}
    return (vs[0].word if len(words) == 1 else RECORD_DEPENDENT), vs


def match_to_mean(at: PeriodicRun, lowered: PeriodicRun, T_target: float
                  ) -> PeriodicRun | None:
    """``at`` (the tuned run) with energy and discomfort interpolated linearly in the mean
    cabin temperature between it and ``lowered`` (the same family at a lower target) to
    ``T_target`` (K); None when the two means are too close to define the slope (under
    0.01 K apart) or the target lies more than ``MATCH_EXTRAPOLATE`` spans outside them."""
    span = lowered.mean_T_cab - at.mean_T_cab
    if abs(span) < 0.01:
        return None
    f = (T_target - at.mean_T_cab) / span
    if not -MATCH_EXTRAPOLATE <= f <= 1.0 + MATCH_EXTRAPOLATE:
        return None

    def lerp(a: float, b: float) -> float:
        return float(a + f * (b - a))

    return dataclasses.replace(
        at, energy_J=lerp(at.energy_J, lowered.energy_J),
        discomfort_Kmin=max(0.0, lerp(at.discomfort_Kmin, lowered.discomfort_Kmin)),
        rh_mean=lerp(at.rh_mean, lowered.rh_mean), mean_T_cab=float(T_target))


def judge(by: dict, names: Sequence[str], c: str, b: str, seed: int = 0, n_boot: int = 10000,
          min_scenarios: int = MIN_SCENARIOS) -> Verdict:
    """:func:`verdict` of family ``c`` against ``b`` from held-out runs keyed
    ``(family, scenario)``, with their comfort gaps."""
    def gap(attr):
        return float(np.mean([getattr(by[c, n], attr) - getattr(by[b, n], attr)
                              for n in names]))

    def single(charge):
        return float(np.mean([100.0 * (by[b, n].single_charged_J(charge)
                                       - by[c, n].single_charged_J(charge))
                              / by[b, n].single_charged_J(charge) for n in names]))

    v = verdict(c, b, names, [by[c, n].energy_J for n in names],
                [by[b, n].energy_J for n in names], seed, n_boot, min_scenarios,
                gap("discomfort_Kmin"), gap("mean_T_cab"))
    return dataclasses.replace(v, single_own_pct=single("own"), single_pi_pct=single("pi"))


def fronts_figure(result: CompareResult):
    """Energy vs discomfort per family on training (a matplotlib figure)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for fam in dict.fromkeys(p.family for p in result.fronts):
        pts = sorted((p for p in result.fronts if p.family == fam), key=lambda p: p.knob)
        ax.plot([p.discomfort_Kmin for p in pts], [p.energy_J / 1e6 for p in pts], "o-",
                label=fam)
    ax.axvline(result.comfort_level_Kmin, color="k", lw=0.8, ls="--", label="comfort level")
    ax.set_xlabel("discomfort, K min per pass outside the band (training mean)")
    ax.set_ylabel("energy per pass, MJ (periodic steady state)")
    ax.legend(loc="center left", bbox_to_anchor=(1.02, 0.5))
    fig.tight_layout()
    return fig


def plot_fronts(result: CompareResult, path) -> None:
    """:func:`fronts_figure` as one PNG."""
    import matplotlib.pyplot as plt

    from acid._io import save_figure

    fig = fronts_figure(result)
    save_figure(fig, path)
    plt.close(fig)
