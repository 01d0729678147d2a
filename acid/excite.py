"""Random excitation of a plant into an identification dataset (paper section II-B-2).

``ExcitationSpec`` says what to do (signals, Table II bounds in degC, dwell times, duration,
seed, speed profile, T_int/T_shell variation for the model plant, random vehicle speed and
ambient temperature, steady-state holds); ``make_schedule`` turns it into an
``InputSchedule`` (kelvin inside), deterministically from the seed; ``excite`` runs a plant
through it and returns a ``Dataset`` whose metadata carries the spec, the seed, the plant and
its configuration.

What each model family needs (``MODEL_PRESETS``): the paper's model (eqs. 1-5) is identified
at one speed and ambient; the economic model (:mod:`acid.models.econ`) has vehicle speed and ambient
temperature in its compressor power map and its shell and humidity balances, so its data must
vary them (``speed_bounds``, ``T_amb_bounds``) and should contain near-steady operating points
(``steady_fraction``: some input steps held long enough for the interior to settle).

Randomness: one ``numpy.random.SeedSequence(seed)`` with a fixed child stream per signal
(``STREAMS``), so adding or changing one signal never changes the others.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from acid import signals
from acid.data import Dataset
from acid.errors import ConfigError
from acid.plant.base import InputSchedule, Plant
from acid.units import C2K, K2C, in_degC

SIGNAL_TYPES = ("aprbs", "prbs", "multisine")

#: Fixed child-stream index of every random source (never renumber; append new ones).
STREAMS = {"W_bl": 0, "T_evap_set": 1, "T_int": 2, "T_shell": 3, "noise": 4, "v_veh": 5,
           "T_amb": 6, "soak": 7, "segments": 8}

#: Record designs: ``random`` (one experiment from the plant's initial state) and
#: ``pulldown`` (soak-and-pull-down segments, :mod:`acid.excite_pulldown`).
DESIGNS = ("random", "pulldown")

#: Levels of a random speed signal (equally spaced, both bounds included: standstill is one).
SPEED_LEVELS = 7

#: Longest record ``excite`` makes (30 days: about 0.9 GB at Ts = 5 s on the hifi plant), s.
MAX_DURATION_S = 30 * 86400.0
#: Most samples a record may have (30 days at Ts = 5 s is 518400), checked before allocation.
MAX_SAMPLES = 1_000_000
#: Fastest vehicle speed accepted, m/s (360 km/h; Table I goes to 25 m/s).
MAX_SPEED = 100.0
#: Largest measurement noise standard deviation accepted, K.
MAX_NOISE_K = 10.0

#: Table II input bounds.
W_BL_BOUNDS = (0.05, 0.15)          # kg/s
T_EVAP_SET_BOUNDS_C = (3.0, 10.0)   # degC


@dataclass(frozen=True)
class ExcitationSpec:
    """How to excite a plant. Temperatures in degC (the edge); converted to K inside.

    Attributes
    ----------
    signal : generator for both inputs, one of ``SIGNAL_TYPES``; ``signal_T_evap_set``
        overrides it for the set-point when given.
    W_bl_bounds : (low, high) blower flow, kg/s (Table II: 0.05-0.15).
    T_evap_set_bounds : (low, high) evaporator set-point, degC (Table II: 3-10).
    min_dwell, max_dwell : APRBS dwell range, s. The defaults (20-300 s) mix steps shorter
        than the evaporator/cabin time constants (~10-30 s) with holds long enough to settle.
    levels : APRBS level count (``None``: continuous uniform levels).
    prbs_dwell : PRBS clock period, s.
    band : multisine band (f_lo, f_hi), Hz (Nyquist at Ts = 5 s is 0.1 Hz).
    n_sines : number of multisine components.
    duration : record length, s (rounded to whole samples).
    Ts : sample time, s (paper: 0.2 Hz).
    seed : seed of every random stream.
    speed : constant vehicle speed, m/s (ignored when ``cycle`` is given).
    cycle : drive-cycle name from ``datasets/drive_cycles`` (repeated to fill the record).
    vary_exogenous : vary T_int and T_shell (model plant only; the high-fidelity plant
        computes its own) so that gamma1 and gamma2 are identifiable.
    T_int_bounds, T_shell_bounds : their ranges, degC (the shell is hotter on average).
    exogenous_dwell : (min, max) dwell of their underlying steps, s.
    exogenous_time_constant : their first-order lag, s.
    noise : measurement noise standard deviation on recorded temperatures, K (applied by
        the plant; recorded here for provenance).
    speed_bounds : (low, high) m/s: the vehicle speed is a random step signal (APRBS on
        ``SPEED_LEVELS`` equally spaced levels, so standstill and the top speed both occur)
        with dwell ``speed_dwell`` (s); exclusive with ``cycle`` and ``speed``.
    T_amb_bounds : (low, high) degC: the ambient temperature wanders slowly in this range
        (long-dwell steps through a first-order lag: ``ambient_dwell`` s,
        ``ambient_time_constant`` s); the plant's configured ambient when None.
    steady_fraction : share of the W_bl and T_evap_set steps held for ``steady_dwell``
        (s) instead of the APRBS dwell: near-steady operating points (0: none).
    design : ``DESIGNS``: ``pulldown`` makes the record of separate experiments of
        ``segment_duration`` s each, every one starting from a soak (cabin, interior, shell,
        evaporator and condenser walls at one temperature: drawn in ``soak_bounds`` degC, or
        the segment's ambient for a share ``cold_fraction`` of them), then a full-power hold
        (highest blower, lowest coil set-point) of ``full_power_dwell`` s (at most half a
        segment), then the random inputs (:func:`excite_pulldown`).
    """

    signal: str = "aprbs"
    signal_T_evap_set: str | None = None
    W_bl_bounds: tuple[float, float] = W_BL_BOUNDS
    T_evap_set_bounds: tuple[float, float] = T_EVAP_SET_BOUNDS_C
    min_dwell: float = 20.0
    max_dwell: float = 300.0
    levels: int | None = None
    prbs_dwell: float = 30.0
    band: tuple[float, float] = (1 / 1800, 1 / 40)
    n_sines: int = 24
    duration: float = 7200.0
    Ts: float = 5.0
    seed: int = 0
    speed: float = 0.0
    cycle: str | None = None
    vary_exogenous: bool = True
    T_int_bounds: tuple[float, float] = (25.0, 45.0)
    T_shell_bounds: tuple[float, float] = (30.0, 50.0)
    exogenous_dwell: tuple[float, float] = (600.0, 1800.0)
    exogenous_time_constant: float = 600.0
    noise: float = 0.0
    speed_bounds: tuple[float, float] | None = None
    speed_dwell: tuple[float, float] = (60.0, 600.0)
    T_amb_bounds: tuple[float, float] | None = None
    ambient_dwell: tuple[float, float] = (900.0, 2700.0)
    ambient_time_constant: float = 600.0
    steady_fraction: float = 0.0
    steady_dwell: tuple[float, float] = (600.0, 1200.0)
    design: str = "random"
    segment_duration: float = 1800.0
    soak_bounds: tuple[float, float] = (30.0, 55.0)
    cold_fraction: float = 0.25
    full_power_dwell: tuple[float, float] = (300.0, 900.0)

    def __post_init__(self):
        for name in ("T_evap_set_bounds", "T_int_bounds", "T_shell_bounds", "soak_bounds"):
            # degC bounds; acid.degC(...) / acid.kelvin(...) values are converted, not guessed
            object.__setattr__(self, name, tuple(float(in_degC(t)) for t in getattr(self, name)))
        for name in ("signal", "signal_T_evap_set"):
            value = getattr(self, name)
            if value is not None and value not in SIGNAL_TYPES:
                raise ConfigError(f"--signal: unknown signal {value!r} "
                                  f"(choose {', '.join(SIGNAL_TYPES)})")
        if not (math.isfinite(self.duration) and 0 < self.duration <= MAX_DURATION_S):
            raise ConfigError(f"--duration must be a positive number of seconds up to "
                              f"{MAX_DURATION_S:g} (30 days), got {self.duration}")
        if not (math.isfinite(self.Ts) and self.Ts > 0):
            raise ConfigError(f"sample time must be positive, got {self.Ts}")
        if self.duration / self.Ts > MAX_SAMPLES:
            raise ConfigError(f"--duration {self.duration:g} s at Ts = {self.Ts:g} s gives "
                              f"{self.duration / self.Ts:.3g} samples (at most {MAX_SAMPLES})")
        if self.n_samples < 2:
            raise ConfigError(f"--duration {self.duration:g} s gives {self.n_samples} samples "
                              f"at Ts = {self.Ts:g} s; at least 2 are needed")
        for name in ("min_dwell", "max_dwell"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0 < value <= MAX_DURATION_S):
                raise ConfigError(f"--{name.replace('_', '-')} must be a positive number of "
                                  f"seconds up to {MAX_DURATION_S:g}, got {value}")
        if not 0 < self.min_dwell <= self.max_dwell:
            raise ConfigError(f"dwell times must satisfy 0 < --min-dwell <= --max-dwell, "
                              f"got {self.min_dwell:g} .. {self.max_dwell:g} s")
        if not (math.isfinite(self.noise) and 0 <= self.noise <= MAX_NOISE_K):
            raise ConfigError(f"--noise must be in [0, {MAX_NOISE_K:g}] K, got {self.noise}")
        if not (math.isfinite(self.speed) and 0 <= self.speed <= MAX_SPEED):
            raise ConfigError(f"--speed must be in [0, {MAX_SPEED:g}] m/s, got {self.speed}")
        if not 0 <= int(self.seed) < 2**63:
            raise ConfigError(f"--seed must be an integer >= 0, got {self.seed}")
        for name in ("W_bl_bounds", "T_evap_set_bounds", "T_int_bounds", "T_shell_bounds",
                     "speed_bounds", "T_amb_bounds", "speed_dwell", "ambient_dwell",
                     "steady_dwell"):
            value = getattr(self, name)
            if value is None:
                continue
            lo, hi = value
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise ConfigError(f"{name} must satisfy low < high, got ({lo}, {hi})")
        if self.speed_bounds is not None:
            if self.cycle is not None or self.speed != 0.0:
                raise ConfigError("random speed (--speed-range) excludes --speed and --cycle")
            if self.speed_bounds[0] < 0:
                raise ConfigError(f"--speed-range must be >= 0 m/s, got {self.speed_bounds}")
        if self.T_amb_bounds is not None and not (-40.0 < self.T_amb_bounds[0]
                                                  and self.T_amb_bounds[1] < 55.0):
            raise ConfigError(f"--t-amb-range must lie within -40..55 degC, got "
                              f"{self.T_amb_bounds}")
        if not 0.0 <= self.steady_fraction < 1.0:
            raise ConfigError(f"--steady-fraction must lie in [0, 1), got "
                              f"{self.steady_fraction}")
        if min(self.speed_dwell[0], self.ambient_dwell[0], self.steady_dwell[0]) <= 0 \
                or self.ambient_time_constant < 0:
            raise ConfigError("dwell times must be positive and time constants >= 0 s")
        self._check_design()

    def _check_design(self) -> None:
        if self.design not in DESIGNS:
            raise ConfigError(f"--design: unknown design {self.design!r} (choose "
                              f"{', '.join(DESIGNS)})")
        for name in ("soak_bounds", "full_power_dwell"):
            lo, hi = getattr(self, name)
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise ConfigError(f"{name} must satisfy low < high, got ({lo}, {hi})")
        if not (-40.0 <= self.soak_bounds[0] and self.soak_bounds[1] <= 80.0):
            raise ConfigError(f"--soak-range must lie within -40..80 degC, got "
                              f"{self.soak_bounds}")
        if not 0.0 <= self.cold_fraction <= 1.0:
            raise ConfigError(f"--cold-fraction must lie in [0, 1], got {self.cold_fraction}")
        if self.design != "pulldown":
            return
        seg = self.segment_duration
        if not (math.isfinite(seg) and 2 * self.Ts <= seg <= self.duration):
            raise ConfigError(f"--segment-duration must lie in [{2 * self.Ts:g}, --duration "
                              f"{self.duration:g}] s, got {seg}")
        if not 0 < self.full_power_dwell[0]:   # a draw is cut at half a segment
            raise ConfigError(f"full-power hold {self.full_power_dwell} s must be positive")

    @property
    def n_samples(self) -> int:
        """Number of samples of the record."""
        return int(round(self.duration / self.Ts))

    def replace(self, **changes) -> ExcitationSpec:
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        """JSON-serialisable fields (tuples become lists), with units in the key names' doc."""
        d = dataclasses.asdict(self)
        return {k: list(v) if isinstance(v, tuple) else v for k, v in d.items()}

    def rng(self, stream: str) -> np.random.Generator:
        """The independent random generator of one named stream (see ``STREAMS``)."""
        return np.random.default_rng(
            np.random.SeedSequence(int(self.seed), spawn_key=(STREAMS[stream],)))


def _samples(dwell_s: tuple[float, float], Ts: float) -> tuple[int, int]:
    """A (min, max) dwell in seconds as whole samples (at least one)."""
    lo = max(1, int(round(dwell_s[0] / Ts)))
    return lo, max(lo, int(round(dwell_s[1] / Ts)))


def _input_signal(kind: str, rng: np.random.Generator, spec: ExcitationSpec, low: float,
                  high: float) -> tuple[np.ndarray, dict]:
    n, Ts = spec.n_samples, spec.Ts
    if kind == "aprbs":
        lo_d, hi_d = _samples((spec.min_dwell, spec.max_dwell), Ts)
        hold = _samples(spec.steady_dwell, Ts) if spec.steady_fraction > 0 else None
        return signals.aprbs(rng, n, low, high, lo_d, hi_d, levels=spec.levels, hold=hold,
                             hold_fraction=spec.steady_fraction)
    if kind == "prbs":
        return signals.prbs(rng, n, low, high, max(1, int(round(spec.prbs_dwell / Ts))))
    return signals.multisine(rng, n, Ts, low, high, band=spec.band, n_sines=spec.n_sines,
                             phases="random")


def make_schedule(spec: ExcitationSpec) -> InputSchedule:
    """The input schedule of ``spec`` (W_bl in kg/s, temperatures in K), reproducible.

    ``schedule.spec`` records the excitation settings and each generator's own spec; it
    becomes the dataset's ``metadata["excitation"]``.
    """
    n, Ts = spec.n_samples, spec.Ts
    W_bl, W_spec = _input_signal(spec.signal, spec.rng("W_bl"), spec, *spec.W_bl_bounds)
    lo, hi = (C2K(t) for t in spec.T_evap_set_bounds)
    T_set, T_spec = _input_signal(spec.signal_T_evap_set or spec.signal,
                                  spec.rng("T_evap_set"), spec, lo, hi)
    if spec.cycle is not None:
        v, v_spec = signals.drive_cycle(spec.cycle, n=n, Ts=Ts, repeat=True)
    elif spec.speed_bounds is not None:
        v, v_spec = signals.aprbs(spec.rng("v_veh"), n, *spec.speed_bounds,
                                  *_samples(spec.speed_dwell, Ts), levels=SPEED_LEVELS)
        v_spec = {**v_spec, "unit": "m/s"}
    else:
        v, v_spec = signals.constant_speed(n, Ts, spec.speed)
    T_int = T_shell = None
    generators = {"W_bl": W_spec, "T_evap_set": {**T_spec, "unit": "K"}, "v_veh": v_spec}
    if spec.vary_exogenous:
        kw = {"dwell_s": spec.exogenous_dwell, "time_constant_s": spec.exogenous_time_constant}
        T_int, generators["T_int"] = signals.slow_exogenous(
            spec.rng("T_int"), n, Ts, *(C2K(t) for t in spec.T_int_bounds), **kw)
        T_shell, generators["T_shell"] = signals.slow_exogenous(
            spec.rng("T_shell"), n, Ts, *(C2K(t) for t in spec.T_shell_bounds), **kw)
    T_amb = None
    if spec.T_amb_bounds is not None:
        T_amb, amb_spec = signals.slow_exogenous(
            spec.rng("T_amb"), n, Ts, *(C2K(t) for t in spec.T_amb_bounds),
            dwell_s=spec.ambient_dwell, time_constant_s=spec.ambient_time_constant)
        generators["T_amb"] = {**amb_spec, "unit": "K"}
    record = {**spec.to_dict(), "n_samples": n, "units": _SPEC_UNITS,
              "generators": generators}
    return InputSchedule(W_bl=W_bl, T_evap_set=T_set, v_veh=v, Ts=Ts, T_int=T_int,
                         T_shell=T_shell, T_amb=T_amb, spec=record)


_SPEC_UNITS = {"W_bl_bounds": "kg/s", "T_evap_set_bounds": "degC", "min_dwell": "s",
               "max_dwell": "s", "prbs_dwell": "s", "band": "Hz", "duration": "s", "Ts": "s",
               "speed": "m/s", "T_int_bounds": "degC", "T_shell_bounds": "degC",
               "exogenous_dwell": "s", "exogenous_time_constant": "s", "noise": "K",
               "speed_bounds": "m/s", "speed_dwell": "s", "T_amb_bounds": "degC",
               "ambient_dwell": "s", "ambient_time_constant": "s", "steady_dwell": "s",
               "segment_duration": "s", "soak_bounds": "degC", "full_power_dwell": "s"}

#: What each model family needs from an excitation (``acid excite --model NAME``): the
#: paper's model is identified at one speed and ambient; the economic model
#: (:mod:`acid.models.econ`) needs vehicle speed and ambient variation and near-steady holds.
#: Ranges: speed 0-36 m/s covers every shipped drive cycle (WLTC class 3 peaks at 36.5 m/s,
#: within the power map's 2 % tolerance); ambient 25-40 degC is where cabin cooling is the load.
MODEL_PRESETS: dict[str, dict] = {
    "paper": {},
    "econ": {"speed_bounds": (0.0, 36.0), "T_amb_bounds": (25.0, 40.0),
             "steady_fraction": 0.2, "duration": 6 * 3600.0},
}


def spec_for_model(model: str, **options) -> ExcitationSpec:
    """The excitation a model family needs (``MODEL_PRESETS``), with ``options`` on top."""
    if model not in MODEL_PRESETS:
        raise ConfigError(f"--model: unknown model family {model!r} (choose "
                          f"{', '.join(MODEL_PRESETS)})")
    return ExcitationSpec(**{**MODEL_PRESETS[model], **options})


def uses_exogenous_schedule(plant: Plant) -> bool:
    """Whether the plant takes T_int / T_shell from the schedule: the model plant, and a
    declared model (``acid.plant.declared.DeclaredPlant``) with them among its disturbances."""
    return getattr(plant, "name", "") == "model" or bool(
        {"T_int", "T_shell"} & set(getattr(plant, "disturbance_names", ())))


def excite(plant: Plant, spec: ExcitationSpec,
           progress: Callable[[int, int], None] | None = None) -> Dataset:
    """Run ``plant`` through the schedule of ``spec`` and return the dataset (degC storage).

    On the model plant with ``spec.vary_exogenous`` the T_int/T_shell schedules drive it and
    its initial T_int/T_shell are their first values; other plants compute their own.
    ``progress(done, total)`` is called after every sample.
    """
    if abs(plant.Ts - spec.Ts) > 1e-9:
        raise ConfigError(f"excitation sample time {spec.Ts:g} s differs from the plant's "
                          f"{plant.Ts:g} s")
    if spec.design == "pulldown":
        return excite_pulldown(plant, spec, progress)
    schedule = make_schedule(spec)
    initial = None
    if uses_exogenous_schedule(plant):
        if schedule.T_int is not None and getattr(plant, "name", "") == "model":
            initial = {"T_int": float(schedule.T_int[0]), "T_shell": float(schedule.T_shell[0])}
    else:
        schedule.T_int = schedule.T_shell = None
        schedule.spec["exogenous"] = "computed by the plant"
    check = getattr(plant, "check_schedule", None)
    if check is not None:      # a declared model: every input it declares is driven
        check(schedule)
    return plant.simulate(schedule, initial=initial, progress=progress,
                          metadata={"seed": int(spec.seed)})


# --------------------------------------------------------------- soak and pull-down
# The soak-and-pull-down design (``acid excite --design pulldown``).
#
# A record of separate experiments (the project's multi-experiment dataset: the fitter treats
# each segment's first sample as its own initial state and no regressor crosses a segment
# boundary). Every segment
#
# 1. starts from a **soak**: the plant's cabin, interior (fast and slow), shell, evaporator
#    and condenser walls all at one temperature -- a **hot soak** drawn uniformly in
#    ``spec.soak_bounds`` (degC; never below the segment's ambient), or, for a share
#    ``spec.cold_fraction`` of the segments, a **cold soak** at the segment's ambient (a car
#    parked in the shade); the cabin air holds the ambient humidity ratio (the plant's own
#    default for a closed, soaked car);
# 2. is pulled down at **full power** first (highest blower ``W_bl_bounds[1]``, lowest coil
#    set-point ``T_evap_set_bounds[0]``) for a hold drawn in ``spec.full_power_dwell`` s (at
#    most half the segment): the
#    largest cooling loads and warmest evaporator the plant reaches;
# 3. continues with the usual random inputs of :func:`acid.excite.make_schedule` (APRBS on
#    W_bl and T_evap_set, the preset's speed and ambient), from its own seed.
#
# Randomness: the soak temperatures, hot/cold draws and hold lengths come from the ``soak``
# stream of ``spec.seed``; each segment's random inputs from a seed derived from the
# ``segments`` stream and the segment's index, so reruns are bit-identical and segment ``i``
# does not depend on how many segments follow it.
#

#: the plant states a soak sets (those the plant has; T_int/T_shell only where the plant
#: computes them itself)
SOAK_KEYS = ("T_cab", "T_int", "T_int_slow", "T_shell", "T_evap", "T_cw")


@dataclass(frozen=True)
class Segment:
    """One soak-and-pull-down experiment: ``soak_K`` (K; None for a cold soak: the
    segment's ambient), the full-power hold (samples) and the spec of its random inputs."""

    index: int
    cold: bool
    soak_K: float | None
    hold_samples: int
    spec: ExcitationSpec


def segments(spec: ExcitationSpec) -> list[Segment]:
    """The segments of ``spec`` (``design == "pulldown"``), deterministic in ``spec.seed``.

    The last segment takes what is left of ``spec.duration`` when it is at least two
    samples; otherwise the record is ``n * segment_duration`` long."""
    if spec.design != "pulldown":
        raise ConfigError(f"segments: design {spec.design!r} is not 'pulldown'")
    n_seg_samples = int(round(spec.segment_duration / spec.Ts))
    n_total = spec.n_samples
    lengths = [n_seg_samples] * (n_total // n_seg_samples)
    if n_total - sum(lengths) >= 2:
        lengths.append(n_total - sum(lengths))
    rng = spec.rng("soak")
    lo_h, hi_h = (max(1, int(round(t / spec.Ts))) for t in spec.full_power_dwell)
    out = []
    for i, n in enumerate(lengths):
        cold = bool(rng.random() < spec.cold_fraction)
        soak = float(rng.uniform(*spec.soak_bounds))   # drawn either way: streams stay aligned
        hold = min(int(rng.integers(lo_h, hi_h + 1)), n // 2)   # at most half a segment
        seed = int(np.random.SeedSequence(int(spec.seed), spawn_key=(STREAMS["segments"], i))
                   .generate_state(1, np.uint64)[0] >> np.uint64(1))
        sub = spec.replace(design="random", duration=n * spec.Ts, seed=seed)
        out.append(Segment(i, cold, None if cold else C2K(soak), hold, sub))
    return out


def excite_pulldown(plant: Plant, spec: ExcitationSpec,
                    progress: Callable[[int, int], None] | None = None) -> Dataset:
    """Run ``plant`` through every segment of ``spec`` from its soak; the segments joined
    as separate experiments (``Dataset.concatenate``). ``metadata["segments"]`` lists each
    segment's soak (degC), kind, full-power hold (s) and seed; ``metadata["excitation"]`` is
    the whole spec."""
    segs = segments(spec)
    total = spec.n_samples
    done = 0
    exogenous = uses_exogenous_schedule(plant)
    parts, info = [], []
    for seg in segs:
        schedule = make_schedule(seg.spec)
        h = seg.hold_samples
        schedule.W_bl[:h] = seg.spec.W_bl_bounds[1]
        schedule.T_evap_set[:h] = C2K(seg.spec.T_evap_set_bounds[0])
        if not exogenous:
            schedule.T_int = schedule.T_shell = None
            schedule.spec["exogenous"] = "computed by the plant"
        state = plant.reset()
        T_amb = float(schedule.T_amb[0]) if schedule.T_amb is not None else float(
            state.get("T_amb", getattr(plant, "T_amb", C2K(30.0))))
        soak = T_amb if seg.soak_K is None else max(seg.soak_K, T_amb)
        keys = [k for k in SOAK_KEYS if k in state
                and not (exogenous and schedule.T_int is not None and k in ("T_int",
                                                                            "T_shell"))]
        initial = {k: soak for k in keys}
        if exogenous and schedule.T_int is not None and getattr(plant, "name", "") == "model":
            initial.update(T_int=float(schedule.T_int[0]), T_shell=float(schedule.T_shell[0]))
        check = getattr(plant, "check_schedule", None)
        if check is not None:
            check(schedule)
        step = None if progress is None else (lambda k, n, d=done: progress(d + k, total))
        parts.append(plant.simulate(schedule, initial=initial, progress=step,
                                    metadata={"seed": int(seg.spec.seed)}))
        done += len(schedule)
        info.append({"index": seg.index, "kind": "cold" if seg.cold else "hot",
                     "soak_degC": float(K2C(soak)), "T_amb_degC": float(K2C(T_amb)),
                     "full_power_s": h * spec.Ts, "seed": int(seg.spec.seed),
                     "samples": len(schedule)})
    ds = Dataset.concatenate(parts)
    ds.metadata.update(excitation={**spec.to_dict(), "n_samples": total, "design": "pulldown"},
                       seed=int(spec.seed), segments=info,
                       experiments=[f"{s['kind']}-soak-{s['index']}" for s in info])
    return ds
