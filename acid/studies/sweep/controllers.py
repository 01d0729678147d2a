"""Controllers a sweep can compare: a small registry, name -> constructor + dataclass config.

A controller is registered with

    register_controller(name, config_type, constructor, description)

``config_type`` is a frozen dataclass whose fields (with defaults) are what a sweep spec may
set in ``[controllers.<label>]`` (TOML types: str, int, float, bool, list of numbers; edge
units, degC in names ending ``_C``); its ``__post_init__`` may raise ``ConfigError``.
``constructor(config)`` returns an object with ``run(ctx: ScenarioContext) -> ControllerRun``
(:mod:`acid.studies.sweep.context`), called on the worker, once per scenario. The spec is checked
against the registry before anything runs, and the constructor travels to the worker by
reference (module + name), so it must be a module-level class or function.

Built-in
--------
``nmpc``     the paper's NMPC (eqs. 7-13) on a constant upper cabin bound (the set-point, or
             the band's upper edge); ``match = "<label>"`` tunes that constant bound until
             the mean cabin temperature equals another controller's (the fair comparison of
             ``acid cav-study``).
``icm``      the paper's NMPC following the Intelligent Constraint Management bound (paper
             Fig. 9) built from the previewed speed inside the comfort band.
``nominal``  the plant's own PI controllers (blower on the cabin set-point, compressor on
             the evaporator set-point): the conventional A/C.
``econ``     the economic NMPC on the identified power map (``acid cav-study``'s D and E;
             :mod:`acid.studies.sweep.econ`).
``plan``     the best known plan (perfect information) from the scenario's start, replayed
             on the plant; ``match`` is required (:mod:`acid.studies.sweep.econ`).
``pi``       the PI baselines of ``acid cav-study`` (:mod:`acid.control.pi_baselines`): the
             plant's blower PI with the coil set-point ``coil = "reset"`` (production-style
             reset, P), ``"fixed"`` (``T_evap_set_C``) or ``"search"`` (the fixed coil
             set-point of least energy with the mean cabin RH in the band, golden section
             over 3-``coil_max_C`` degC, 10 by default as the econ controller's, F);
             ``match`` tunes the cabin set-point to another controller's mean cabin
             temperature. The search ranks energies with the end state charged back by the
             scenario's continuation (``tail_s``; raw energies when it is 0), as
             ``acid cav-study``'s F does.

Further controllers register from their own module: add it to ``CONTROLLER_MODULES`` (in
acid) or name it in the spec's ``plugins = ["my_package.my_controller"]``.
"""

from __future__ import annotations

import dataclasses
import importlib
import types
import typing
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from acid.errors import ConfigError
from acid.studies.sweep.context import ControllerRun, ScenarioContext
from acid.units import C2K

#: acid modules that register controllers when imported (the built-ins are in this one)
CONTROLLER_MODULES: tuple[str, ...] = ("acid.studies.sweep.econ",)


@dataclass(frozen=True)
class ControllerType:
    """A registry entry: how to build a controller from its dataclass configuration."""

    name: str
    config_type: type
    constructor: Callable
    description: str = ""


_REGISTRY: dict[str, ControllerType] = {}
_loaded = [False]


def register_controller(name: str, config_type: type, constructor: Callable,
                        description: str = "") -> ControllerType:
    """Make a controller available to sweeps under ``name`` (see the module docstring)."""
    if not dataclasses.is_dataclass(config_type):
        raise TypeError(f"controller {name!r}: config_type must be a dataclass")
    entry = ControllerType(name, config_type, constructor, description)
    _REGISTRY[name] = entry
    return entry


def _load_modules(extra: tuple[str, ...] = ()) -> None:
    if not _loaded[0]:
        _loaded[0] = True
        for mod in CONTROLLER_MODULES:
            importlib.import_module(mod)
    for mod in extra:
        importlib.import_module(mod)


def controller_types(plugins: tuple[str, ...] = ()) -> dict[str, ControllerType]:
    """Every registered controller by name (importing ``plugins`` first)."""
    _load_modules(tuple(plugins))
    return dict(_REGISTRY)


def _type_ok(value, hint) -> tuple[bool, object]:
    """(accepted, converted) for a TOML value against a dataclass field annotation."""
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        for h in typing.get_args(hint):
            if h is type(None):
                if value is None:
                    return True, None
                continue
            ok, v = _type_ok(value, h)
            if ok:
                return True, v
        return False, value
    if origin is tuple:
        args = typing.get_args(hint)
        if not isinstance(value, (list, tuple)):
            return False, value
        if len(args) == 2 and args[1] is Ellipsis:
            args = (args[0],) * len(value)
        if len(value) != len(args):
            return False, value
        out = []
        for v, h in zip(value, args, strict=True):
            ok, c = _type_ok(v, h)
            if not ok:
                return False, value
            out.append(c)
        return True, tuple(out)
    if hint is bool:
        return isinstance(value, bool), value
    if hint is int:
        return isinstance(value, int) and not isinstance(value, bool), value
    if hint is float:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        return ok and np.isfinite(value), float(value) if ok else value
    if hint is str:
        return isinstance(value, str), value
    return True, value


def build_config(kind: str, table: dict, where: str, plugins: tuple[str, ...] = ()):
    """The controller type ``kind`` and its configuration from a spec table, validated.

    Raises ``ConfigError`` naming ``where`` and the key for an unknown controller, unknown
    key, wrong type or a value the configuration refuses.
    """
    types_ = controller_types(plugins)
    if kind not in types_:
        raise ConfigError(f"{where}: unknown controller {kind!r} (known: "
                          f"{', '.join(sorted(types_))})")
    entry = types_[kind]
    hints = typing.get_type_hints(entry.config_type)
    names = [f.name for f in dataclasses.fields(entry.config_type) if f.init]
    kwargs = {}
    for key, value in table.items():
        if key not in names:
            raise ConfigError(f"{where}: unknown key {key!r} for controller {kind!r} (known: "
                              f"{', '.join(names) or 'none'})")
        ok, conv = _type_ok(value, hints.get(key, object))
        if not ok:
            raise ConfigError(f"{where}: {key} = {value!r} must be "
                              f"{_hint_name(hints.get(key))}")
        kwargs[key] = conv
    try:
        config = entry.config_type(**kwargs)
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}") from None
    return entry, config


def _hint_name(hint) -> str:
    names = {float: "a number", int: "an integer", str: "a string", bool: "true or false"}
    if hint in names:
        return names[hint]
    return str(hint).replace("typing.", "")


# ------------------------------------------------------------------------- built-ins
#: the paper NMPC's solvers (acid.control.nmpc.SOLVERS), the default first: warm-started SQP
#: (qrqp, generated C) with fatrop as its fallback
SOLVERS = ("sqp", "fatrop", "ipopt")
BOUNDS = ("setpoint", "band-high")


def _check_nmpc_options(horizon: int, solver: str) -> None:
    if not 2 <= int(horizon) <= 60:
        raise ConfigError(f"horizon = {horizon} must lie in 2..60 steps")
    if solver not in SOLVERS:
        raise ConfigError(f"solver = {solver!r} unknown (choose {', '.join(SOLVERS)})")


@dataclass(frozen=True)
class PaperNMPCConfig:
    """The paper's NMPC on a constant upper bound.

    Attributes
    ----------
    horizon : N, steps of Ts (Table II: 6).
    bound : ``"setpoint"`` (the scenario's cabin set-point) or ``"band-high"`` (the comfort
        band's upper edge).
    match : label of another controller of the spec; the constant bound is then tuned until
        this controller's mean cabin temperature equals that one's (``bound`` is the start).
    tol_K : tolerance of the match, K.
    max_iter : closed-loop runs the match may take.
    solver : ``"sqp"`` (default: warm-started SQP, fatrop when it fails), ``"fatrop"`` or
        ``"ipopt"``.
    """

    horizon: int = 6
    bound: str = "setpoint"
    match: str = ""
    tol_K: float = 0.02
    max_iter: int = 8
    solver: str = "sqp"

    def __post_init__(self):
        _check_nmpc_options(self.horizon, self.solver)
        if self.bound not in BOUNDS:
            raise ConfigError(f"bound = {self.bound!r} unknown (choose {', '.join(BOUNDS)})")
        if not (self.tol_K > 0 and 1 <= self.max_iter <= 30):
            raise ConfigError("match needs tol_K > 0 and max_iter in 1..30")


class PaperNMPC:
    """The paper's NMPC (:class:`acid.control.nmpc.NMPC`) with a constant bound, optionally
    tuned to another controller's mean cabin temperature."""

    def __init__(self, config: PaperNMPCConfig):
        self.config = config

    def run(self, ctx: ScenarioContext) -> ControllerRun:

        c = self.config
        mpc = ctx.nmpc(c.horizon, solver=c.solver)
        cond = ctx.conditions
        b0 = cond.T_set if c.bound == "setpoint" else cond.T_high
        if not c.match:
            return ctx.simulate(mpc, ctx.constant_bound(b0, mpc.N), "nmpc")
        from acid.studies.cav_study import tune_mean  # the secant tuning of acid cav-study

        target = ctx.completed[c.match].mean_T_cab

        def run_at(b: float):
            r = ctx.simulate(mpc, ctx.constant_bound(b, mpc.N), "nmpc")
            return r.mean_T_cab, r

        b, r, hist = tune_mean(run_at, target, cond.T_low - 2.0, cond.T_high, c.tol_K,
                               c.max_iter)
        return ControllerRun(r.run, r.end_state,
                             {"bound_K": b, "matched_to": c.match, "target_mean_K": target,
                              "tuning_runs": len(hist)})


@dataclass(frozen=True)
class ICMControllerConfig:
    """The paper's NMPC following the ICM bound (:class:`acid.control.icm.ICMConfig`; the band
    is the scenario's comfort band).

    Attributes
    ----------
    horizon : N, steps of Ts.
    v_slow, v_fast : at or below ``v_slow`` the bound is the band's top, at or above
        ``v_fast`` its bottom, m/s.
    fall_rate, rise_rate : rate limits of the bound, K/s.
    solver : ``"sqp"`` (default: warm-started SQP, fatrop when it fails), ``"fatrop"`` or
        ``"ipopt"``.
    """

    horizon: int = 6
    v_slow: float = 2.0
    v_fast: float = 20.0
    fall_rate: float = 0.1
    rise_rate: float = 0.2
    solver: str = "sqp"

    def __post_init__(self):
        _check_nmpc_options(self.horizon, self.solver)
        if not 0.0 <= self.v_slow < self.v_fast:
            raise ConfigError(f"need 0 <= v_slow < v_fast, got {self.v_slow:g}, "
                              f"{self.v_fast:g} m/s")
        if not (self.fall_rate > 0 and self.rise_rate > 0):
            raise ConfigError("fall_rate and rise_rate must be positive (K/s)")


class ICMController:
    """The paper's CAV controller: NMPC + speed-coordinated bound (paper section IV-C)."""

    def __init__(self, config: ICMControllerConfig):
        self.config = config

    def run(self, ctx: ScenarioContext) -> ControllerRun:
        from acid.control.icm import ICMConfig, icm_upper_bound

        c, cond = self.config, ctx.conditions
        mpc = ctx.nmpc(c.horizon, solver=c.solver)
        icm = ICMConfig(T_low=cond.T_low, T_high=cond.T_high, v_slow=c.v_slow,
                        v_fast=c.v_fast, fall_rate=c.fall_rate, rise_rate=c.rise_rate)
        m = ctx.n + mpc.N + 1
        ub = icm_upper_bound(np.arange(m) * ctx.Ts, ctx.v_preview[:m], icm,
                             initial=ctx.start_T_cab)
        return ctx.simulate(mpc, ub, "icm")


@dataclass(frozen=True)
class NominalConfig:
    """The plant's nominal PI controllers (paper section II-A).

    Attributes
    ----------
    T_evap_set_C : evaporator wall set-point of the compressor loop, degC.
    """

    T_evap_set_C: float = 3.0

    def __post_init__(self):
        if not 0.0 <= self.T_evap_set_C <= 12.0:
            raise ConfigError(f"T_evap_set_C = {self.T_evap_set_C:g} must lie in 0..12 degC")


class NominalController:
    """Blower PI on the cabin set-point, compressor PI on the evaporator set-point: the
    conventional A/C, run inside the plant (``HifiPlant(mode="nominal")``)."""

    def __init__(self, config: NominalConfig):
        self.config = config

    def run(self, ctx: ScenarioContext) -> ControllerRun:
        from acid.studies.mpc_check.scenarios import ClosedLoopRun
        from acid.studies.sweep.context import plant_state

        T_ew_set = C2K(self.config.T_evap_set_C)
        plant = ctx.make_plant(mode="nominal", T_ew_set=T_ew_set)
        plant.reset(ctx.start)
        T_set = ctx.conditions.T_set
        rows = []
        for v in ctx.v_step:
            rows.append(plant.step(0.0, T_ew_set, float(v), T_cab_set=T_set))
            if ctx.tick is not None:
                ctx.tick()
        end = plant.measure()

        def col(name):
            return np.array([float(r.get(name, 0.0)) for r in rows])

        def states(name):
            return np.append(col(name), float(end[name]))

        n = len(rows)
        return ControllerRun(ClosedLoopRun(
            label="nominal", Ts=ctx.Ts, time=np.arange(n + 1) * ctx.Ts,
            T_cab=states("T_cab"), T_evap=states("T_evap"), T_int=states("T_int"),
            T_shell=states("T_shell"), T_cab_max=np.full(n + 1, T_set),
            T_cab_min=np.full(n + 1, ctx.conditions.T_low), T_evap_min=C2K(0.0),
            T_evap_max=C2K(12.0), W_bl=col("W_bl"), T_evap_set=col("T_evap_set"),
            v_veh=np.asarray(ctx.v_step, dtype=float), T_ain=col("T_ain"),
            P_comp=col("P_comp"), P_bl=col("P_bl"), P_fan=col("P_fan"),
            compressor_on=np.ones(n, dtype=bool), step_ms=np.full(n, np.nan),
            fallback=np.zeros(n, dtype=bool), iterations=np.full(n, -1),
            predicted_T_cab=np.full((n, 1), np.nan)), plant_state(plant))


PI_COILS = ("reset", "fixed", "search")
#: a fixed coil whose run misses the target mean cabin temperature by more than this (K) is
#: not at equal comfort: the search ranks it behind every coil that meets it
MEAN_MISS_K = 0.05


@dataclass(frozen=True)
class PIControllerConfig:
    """The PI baselines (module docstring).

    Attributes
    ----------
    coil : ``"reset"`` (P), ``"fixed"`` or ``"search"`` (F).
    T_evap_set_C : the fixed coil set-point, degC (``coil = "fixed"``).
    coil_max_C : warmest coil set-point of the search, degC.
    coil_tol_K : search interval width at which the search stops, K.
    match : label of another controller whose mean cabin temperature is the target.
    tol_K, max_iter : tolerance and runs of the match.
    """

    coil: str = "search"
    T_evap_set_C: float = 9.5
    coil_max_C: float = 10.0
    coil_tol_K: float = 0.5
    match: str = ""
    tol_K: float = 0.02
    max_iter: int = 8

    def __post_init__(self):
        if self.coil not in PI_COILS:
            raise ConfigError(f"coil = {self.coil!r} unknown (choose {', '.join(PI_COILS)})")
        if not 3.0 <= self.T_evap_set_C <= 15.0 or not 4.0 <= self.coil_max_C <= 15.0:
            raise ConfigError("T_evap_set_C must lie in 3..15 degC and coil_max_C in 4..15 "
                              "degC")
        if not (0.01 <= self.coil_tol_K <= 3.0 and self.tol_K > 0
                and 1 <= self.max_iter <= 30):
            raise ConfigError("need coil_tol_K in 0.01..3 K, tol_K > 0, max_iter in 1..30")
        if self.coil == "search" and not self.match:
            raise ConfigError('coil = "search" needs match = "<label>" (equal comfort)')


class PIController:
    """The plant's PI loops with a coil set-point rule, on the sweep's plant."""

    def __init__(self, config: PIControllerConfig):
        self.config = config

    def run(self, ctx: ScenarioContext) -> ControllerRun:
        from acid.comfort import RH_BAND, rh_band_distance
        from acid.control.pi_baselines import COIL_RANGE, CoilReset, golden_min
        from acid.studies.sweep.context import tail_energy_J

        c = self.config
        if c.coil != "search":
            coil = CoilReset() if c.coil == "reset" else C2K(c.T_evap_set_C)
            return self._matched(ctx, coil)

        def f(T_coil):
            # a coil too warm to reach the target mean (a pull-down from the soak) ranks
            # behind every coil that does, nearest first: equal comfort comes before energy
            r = self._matched(ctx, T_coil)
            miss = abs(r.mean_T_cab - r.info["target_mean_K"])
            miss = miss if miss > MEAN_MISS_K else 0.0
            out = rh_band_distance(r.info["rh_mean"], RH_BAND)
            tail = tail_energy_J(ctx, r.end_state, ctx.tail_s) / 1e6 if ctx.tail_s > 0 else 0.0
            return (miss, out > 0.0, out, r.info["energy_MJ"] + tail), r

        x, r, hist = golden_min(f, COIL_RANGE[0], C2K(c.coil_max_C), tol=c.coil_tol_K)
        r.info.update(coil_set_point_K=float(x), coil_search=[
            [float(t), float(k[-1])] for t, k in hist])
        return r

    def _matched(self, ctx: ScenarioContext, coil) -> ControllerRun:
        """The run at the cabin set-point matching ``match`` (or the scenario's set-point)."""
        c = self.config
        if not c.match:
            return self._simulate(ctx, coil, ctx.conditions.T_set)
        from acid.studies.cav_study import tune_mean

        target = ctx.completed[c.match].mean_T_cab

        def run_at(b: float):
            r = self._simulate(ctx, coil, b)
            return r.mean_T_cab, r

        b, r, hist = tune_mean(run_at, target, ctx.conditions.T_low - 2.0,
                               ctx.conditions.T_high, c.tol_K, c.max_iter)
        r.info.update(T_cab_set_K=b, matched_to=c.match, target_mean_K=target,
                      tuning_runs=len(hist))
        return r

    @staticmethod
    def _simulate(ctx: ScenarioContext, coil, T_cab_set: float) -> ControllerRun:
        from acid.control.pi_baselines import PlantPI

        plant = ctx.make_plant()
        ctl = PlantPI(plant.cfg, ctx.Ts, T_cab_set, coil, plant.cfg.p_atm)
        r = direct_loop(ctx, plant, lambda meas, k: ctl.make_step(meas, k), "pi",
                        T_cab_set)
        rh_into_info(r, plant.cfg.p_atm)
        r.info.update(energy_MJ=float(np.sum(r.run.P_comp + r.run.P_bl) * ctx.Ts / 1e6))
        return r


def rh_into_info(r: ControllerRun, p_atm: float) -> None:
    """Replace the cabin humidity ratio that :func:`direct_loop` leaves in ``r.info`` by the
    run's mean cabin relative humidity over samples 1..n (``rh_mean``, fraction)."""
    from acid.psychro import relative_humidity

    w = r.info.pop("w_cab")
    r.info["rh_mean"] = float(np.mean(relative_humidity(r.run.T_cab[1:], w[1:], p_atm)))


def direct_loop(ctx: ScenarioContext, plant, make_step, label: str, T_cab_max: float,
                step_ms=None, fallback=None) -> ControllerRun:
    """``u = make_step(measure(), k); plant.step(u)`` from the scenario's start over its
    speed, recorded as a :class:`ControllerRun` (``info["w_cab"]``: the cabin humidity
    ratio at the sample instants, kg/kg)."""
    from acid.studies.mpc_check.scenarios import ClosedLoopRun
    from acid.studies.sweep.context import plant_state

    plant.reset(ctx.start)
    T_amb = ctx.conditions.T_amb
    n = ctx.n
    states, rows = [plant.measure()], []
    for k in range(n):
        u = make_step(states[-1], k)
        rows.append(plant.step(float(u[0]), float(u[1]), float(ctx.v_step[k]), T_amb=T_amb))
        states.append(plant.measure())
        if ctx.tick is not None:
            ctx.tick()

    def col(name):
        return np.array([float(r.get(name, 0.0)) for r in rows])

    def st(name):
        return np.array([float(s[name]) for s in states])

    return ControllerRun(ClosedLoopRun(
        label=label, Ts=ctx.Ts, time=np.arange(n + 1) * ctx.Ts, T_cab=st("T_cab"),
        T_evap=st("T_evap"), T_int=st("T_int"), T_shell=st("T_shell"),
        T_cab_max=np.full(n + 1, float(T_cab_max)),
        T_cab_min=np.full(n + 1, ctx.conditions.T_low), T_evap_min=C2K(0.0),
        T_evap_max=C2K(12.0), W_bl=col("W_bl"), T_evap_set=col("T_evap_set"),
        v_veh=np.asarray(ctx.v_step, dtype=float), T_ain=col("T_ain"),
        P_comp=col("P_comp"), P_bl=col("P_bl"), P_fan=col("P_fan"),
        compressor_on=np.ones(n, dtype=bool),
        step_ms=np.full(n, np.nan) if step_ms is None else step_ms(n),
        fallback=np.zeros(n, dtype=bool) if fallback is None else fallback(n),
        iterations=np.full(n, -1), predicted_T_cab=np.full((n, 1), np.nan)),
        plant_state(plant), {"w_cab": st("w_cab")})


register_controller("nmpc", PaperNMPCConfig, PaperNMPC,
                    "the paper's NMPC on a constant cabin bound (set-point or band top)")
register_controller("icm", ICMControllerConfig, ICMController,
                    "the paper's NMPC on the speed-coordinated ICM bound (paper Fig. 9)")
register_controller("nominal", NominalConfig, NominalController,
                    "the plant's PI controllers (conventional A/C)")
register_controller("pi", PIControllerConfig, PIController,
                    "the PI baselines of acid cav-study: coil reset (P), fixed, or the best "
                    "fixed coil at equal comfort (F)")

__all__ = ["register_controller", "controller_types", "build_config", "ControllerType",
           "PaperNMPC", "PaperNMPCConfig", "ICMController", "ICMControllerConfig",
           "NominalController", "NominalConfig", "PIController", "PIControllerConfig",
           "direct_loop", "rh_into_info"]
