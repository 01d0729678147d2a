"""Typed results of the ``acid reproduce`` stages: what the report and the claims read.

Every stage of :mod:`acid.studies.reproduce` returns the JSON form of one of the dataclasses below
(``to_json_dict()``); the pipeline stores it in the stage's cache record and the report reads
it back with ``from_json_dict()``. The claims registry (:mod:`acid.claims`) names the field
of these classes where acid measures each of the paper's results, and checks those names
against the declared fields when it is built, so a renamed field fails at import, not as a
silent ``n/a`` in the report.

Units: temperatures in K (errors in K), energies in MJ, times in s, step times in ms.
Non-finite numbers are written as JSON ``null`` and read back as NaN.

Adding a stage result: subclass :class:`StageResult` as a frozen dataclass, decorate it with
``@stage_result("<stage name>")``, give it fields with type hints the codec understands
(float, int, str, bool, ``X | None``, ``tuple[X, ...]``, ``dict[str, X]``, nested dataclasses)
and return ``YourResult(...).to_json_dict()`` from the stage function.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, TypeVar, Union

from acid._io import json_safe
from acid.errors import DataError

T = TypeVar("T", bound="StageResult")

#: stage name -> result class (filled by ``@stage_result``)
STAGE_RESULTS: dict[str, type[StageResult]] = {}


# ---------------------------------------------------------------------------- codec
@functools.cache
def _hints(cls) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def field_type(cls, name: str):
    """The declared type of dataclass field ``name`` of ``cls`` (``KeyError`` if none)."""
    if not dataclasses.is_dataclass(cls):
        raise KeyError(name)
    names = {f.name for f in dataclasses.fields(cls)}
    if name not in names:
        raise KeyError(name)
    return _hints(cls)[name]


def _decode(tp, value, where: str):
    """``value`` (parsed JSON) as an instance of the type hint ``tp``."""
    origin = typing.get_origin(tp)
    if tp is Any:
        return value
    if origin in (Union, types.UnionType):
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        if len(inner) == 1:
            return _decode(inner[0], value, where)
        raise DataError(f"{where}: union types other than X | None are not supported")
    if tp is float:
        if value is None:
            return math.nan
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise DataError(f"{where}: expected a number, got {value!r}")
        return float(value)
    if tp in (int, str, bool):
        if not isinstance(value, tp) or (tp is int and isinstance(value, bool)):
            raise DataError(f"{where}: expected {tp.__name__}, got {value!r}")
        return value
    if origin is tuple:
        args = typing.get_args(tp)
        if not isinstance(value, (list, tuple)):
            raise DataError(f"{where}: expected a list, got {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_decode(args[0], v, f"{where}[{i}]") for i, v in enumerate(value))
        if len(args) != len(value):
            raise DataError(f"{where}: expected {len(args)} items, got {len(value)}")
        return tuple(_decode(a, v, f"{where}[{i}]")
                     for i, (a, v) in enumerate(zip(args, value, strict=True)))
    if origin is dict:
        _, vt = typing.get_args(tp)
        if not isinstance(value, Mapping):
            raise DataError(f"{where}: expected an object, got {value!r}")
        return {str(k): _decode(vt, v, f"{where}.{k}") for k, v in value.items()}
    if dataclasses.is_dataclass(tp):
        return _decode_dataclass(tp, value, where)
    if tp is dict:
        return dict(value)
    raise DataError(f"{where}: cannot decode type {tp!r}")


def _decode_dataclass(cls, value, where: str):
    if not isinstance(value, Mapping):
        raise DataError(f"{where}: expected an object for {cls.__name__}, got {value!r}")
    hints = _hints(cls)
    kwargs = {}
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        if f.name in value:
            kwargs[f.name] = _decode(hints[f.name], value[f.name], f"{where}.{f.name}")
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise DataError(f"{where}: missing key {f.name!r} of {cls.__name__}")
    return cls(**kwargs)


class JsonDataclass:
    """Mixin: ``to_json_dict()`` / ``from_json_dict()`` for a frozen dataclass."""

    def to_json_dict(self) -> dict:
        """Strict JSON (tuples as lists, non-finite numbers as ``null``)."""
        return json_safe(dataclasses.asdict(self))

    @classmethod
    def from_json_dict(cls: type[T], d: Mapping, source: str | None = None) -> T:
        """Read back what ``to_json_dict`` wrote (``DataError`` naming the key on mismatch)."""
        return _decode_dataclass(cls, d, source or cls.__name__)


class StageResult(JsonDataclass):
    """Base of the typed stage results (the name of its stage in ``STAGE``)."""

    STAGE: ClassVar[str] = ""


def stage_result(name: str):
    """Class decorator: register ``cls`` as the result type of stage ``name``."""
    def register(cls):
        cls.STAGE = name
        STAGE_RESULTS[name] = cls
        return cls
    return register


# ----------------------------------------------------------------- shared structures
@dataclass(frozen=True)
class Estimate(JsonDataclass):
    """A measured number with its uncertainty (when the method gives one).

    ``stderr`` is the standard error and ``ci95_low``/``ci95_high`` the 95 % interval, in
    the unit of ``value``; NaN when not available.
    """

    value: float
    stderr: float = math.nan
    ci95_low: float = math.nan
    ci95_high: float = math.nan

    @property
    def has_interval(self) -> bool:
        return math.isfinite(self.ci95_low) and math.isfinite(self.ci95_high)


# ----------------------------------------------------------------------- the stages
@stage_result("sweep")
@dataclass(frozen=True)
class SweepStage(StageResult):
    """Paper Table I / Fig. 3 on the high-fidelity plant (energies compressor + blower).

    The energies are of ``vehicle`` (the paper vehicle, ``acid.plant.vehicles``: the Table I
    calibration), the one the paper's Table I is judged on; ``beside_*`` are acid's default
    vehicle at the same speeds, shown beside it. ``max_energy_step_MJ`` is the largest change
    of energy from one speed to the next (negative when the energy falls with every speed
    step); ``efficiency_gain_pct`` is ``100 (E(first) / E(last) - 1)``, the paper's
    "efficiency increases by ..." reading.
    """

    speeds_mps: tuple[float, ...]
    duration_s: float
    energy_MJ: tuple[float, ...]
    energy_MJ_per_km: tuple[float, ...]
    ratio_last_first: float
    max_energy_step_MJ: float
    efficiency_gain_pct: float
    vehicle: str = ""
    beside_vehicle: str = ""
    beside_energy_MJ: tuple[float, ...] = ()
    beside_ratio_last_first: float = math.nan

    @classmethod
    def of(cls, result, vehicle: str = "", beside=None, beside_vehicle: str = ""
           ) -> SweepStage:
        """From an :class:`acid.plant.sweep.SweepResult` (``beside``: another vehicle's)."""
        E = [float(e) for e in result.energy_MJ]
        steps = [b - a for a, b in zip(E, E[1:], strict=False)]
        extra = {} if beside is None else {
            "beside_vehicle": beside_vehicle,
            "beside_energy_MJ": tuple(float(e) for e in beside.energy_MJ),
            "beside_ratio_last_first": float(beside.ratio_last_first)}
        return cls(speeds_mps=tuple(float(v) for v in result.speeds_mps),
                   duration_s=float(result.duration_s), energy_MJ=tuple(E),
                   energy_MJ_per_km=tuple(float(e) for e in result.energy_MJ_per_km),
                   ratio_last_first=float(result.ratio_last_first),
                   max_energy_step_MJ=max(steps) if steps else math.nan,
                   efficiency_gain_pct=100.0 * (E[0] / E[-1] - 1.0), vehicle=vehicle, **extra)


@stage_result("excite")
@dataclass(frozen=True)
class ExcitationStage(StageResult):
    """The excitation record of the high-fidelity plant (estimation + held-out parts)."""

    samples: int
    duration_s: float
    seed: int
    T_cab_range_degC: tuple[float, float]


@stage_result("fit")
@dataclass(frozen=True)
class FitStage(StageResult):
    """Identified eqs. 1-3 and 5 (kelvin convention), each parameter with its uncertainty.

    ``parameters`` maps gamma1..7, tau1..3, beta1..3 (and eta_cop when the data allow) to an
    :class:`Estimate`; ``ls_gamma``/``ls_tau`` are the least-squares start of output error.
    """

    method: str
    covariance: str
    gamma: tuple[float, ...]
    tau: tuple[float, ...]
    beta: tuple[float, ...]
    parameters: dict[str, Estimate]
    ls_gamma: tuple[float, ...]
    ls_tau: tuple[float, ...]
    fit_percent_one_step: dict[str, float]
    fit_percent_simulation: dict[str, float]
    warnings: tuple[str, ...] = ()

    @classmethod
    def of(cls, res, ls, params, eta_cop: tuple[float, float] = (math.nan, math.nan)
           ) -> FitStage:
        """From fits of the paper's declaration (``acid.ident.fit_model``): ``res`` the
        chosen method's, ``ls`` least squares; ``params`` the ``ModelParams`` written;
        ``eta_cop`` (value, stderr) read off P_comp with eq. 4."""
        est = {e.name: Estimate(value=e.value, stderr=e.stderr, ci95_low=e.ci95[0],
                                ci95_high=e.ci95[1])
               for e in res.estimates if e.experiment is None}
        eta, se = eta_cop
        if math.isfinite(eta):
            est["eta_cop"] = Estimate(value=eta, stderr=se, ci95_low=eta - 1.96 * se,
                                      ci95_high=eta + 1.96 * se)
        n_gamma, n_tau = len(params.gamma), len(params.tau)
        return cls(method=res.method, covariance=res.covariance_kind, gamma=params.gamma,
                   tau=params.tau, beta=params.beta, parameters=est,
                   ls_gamma=tuple(map(float, ls.values[:n_gamma])),
                   ls_tau=tuple(map(float, ls.values[n_gamma:n_gamma + n_tau])),
                   fit_percent_one_step=dict(res.one_step_fit),
                   fit_percent_simulation=dict(res.simulation_fit),
                   warnings=tuple(res.warnings))


@dataclass(frozen=True)
class ChannelErrors(JsonDataclass):
    """Open-loop prediction error of one channel over all starts and steps (K, fit %)."""

    rmse: float
    mean_abs: float
    median_abs: float
    p90_abs: float
    p95_abs: float
    max_abs: float
    fit_percent: float


@stage_result("validate")
@dataclass(frozen=True)
class ValidationStage(StageResult):
    """Multi-start open-loop validation (paper Figs. 5-6): ``starts`` x ``horizon`` steps."""

    starts: int
    horizon: int
    horizon_s: float
    channels: dict[str, ChannelErrors]
    #: ``DeclaredValidation.window_design`` in words, and its overlap of consecutive windows
    window_design: str = ""
    overlap_fraction: float = math.nan
    #: {"model" | yardstick: {channel: {horizon_s: {"rmse_K", "p90_K"}}}}
    by_horizon: dict[str, dict[str, dict[str, dict[str, float]]]] = field(
        default_factory=dict)
    #: {yardstick: its description (orders and the rule that chose them)}
    yardsticks: dict[str, str] = field(default_factory=dict)
    yardsticks_fitted_on: tuple[int, ...] = ()

    @classmethod
    def of(cls, res) -> ValidationStage:
        """From an :class:`acid.ident.validate.DeclaredValidation` (errors at prediction
        steps 1 .. horizon)."""
        from acid.ident.validate import window_design_text

        names = [f.name for f in dataclasses.fields(ChannelErrors)]
        ch = {c: ChannelErrors(**{n: float(res.metrics[c].get(n, math.nan)) for n in names})
              for c in res.channels}
        design = res.window_design
        return cls(starts=int(res.n_starts), horizon=int(res.horizon),
                   horizon_s=float(res.horizon_s[-1]), channels=ch,
                   window_design=window_design_text(design),
                   overlap_fraction=float(design["overlap_fraction"]),
                   by_horizon=res.by_horizon_table(),
                   yardsticks={k: y["description"] for k, y in res.yardsticks.items()},
                   yardsticks_fitted_on=tuple(res.settings.get("yardsticks_fitted_on")
                                              or ()))


@dataclass(frozen=True)
class ClosedLoopSummary(JsonDataclass):
    """One closed-loop scenario of ``acid mpc-check`` (violations after the first step, K).

    ``skipped`` holds the reason when the scenario did not run (numbers are then NaN).
    """

    passed: bool | None
    criterion: str
    energy_MJ: float = math.nan
    max_violation_K: float = math.nan
    max_T_cab_violation_K: float = math.nan
    first_step_violation_K: float = math.nan
    ride_error_K: float = math.nan
    max_avoidable_violation_K: float = math.nan
    fallbacks: int = 0
    skipped: str | None = None


@dataclass(frozen=True)
class CavComparisonSummary(JsonDataclass):
    """Case 1 (ICM bound) vs Case 2 (constant bound) over a window (energies in MJ).

    ``energy_difference_MJ`` is Case 2 minus Case 1 (positive: Case 1 uses less), and
    ``saving_pct`` the same relative to Case 2. The ``speed_blind_*`` numbers are the same
    comparison on the plant without speed effects; ``saving_from_speed_pct`` their difference.
    """

    window_s: tuple[float, float]
    case1_energy_MJ: float
    case2_energy_MJ: float
    energy_difference_MJ: float
    saving_pct: float
    speed_blind_saving_pct: float = math.nan
    saving_from_speed_pct: float = math.nan
    T_cab_end_difference_K: float = math.nan


@dataclass(frozen=True)
class TimingSummary(JsonDataclass):
    """Wall time of the whole ``make_step`` (ms) over the timed closed-loop steps."""

    median_ms: float
    p95_ms: float
    max_ms: float
    steps: int
    passed: bool
    criterion: str
    mean_ms: float = math.nan


@stage_result("mpc")
@dataclass(frozen=True)
class MpcStage(StageResult):
    """``acid mpc-check`` with the identified parameters (paper Figs. 7-10)."""

    passed: bool
    model: ClosedLoopSummary
    plant: ClosedLoopSummary
    cav: ClosedLoopSummary
    cav_paper: CavComparisonSummary | None
    cav_periodic: CavComparisonSummary | None
    cycles: int
    timing: TimingSummary

    @classmethod
    def of(cls, check) -> MpcStage:
        """From an :class:`acid.studies.mpc_check.scenarios.CheckResult`."""
        sc = {k: s.to_json_dict() for k, s in check.scenarios.items()}

        def loop(d: dict) -> ClosedLoopSummary:
            if d.get("skipped"):
                return ClosedLoopSummary(passed=None, criterion=d.get("criterion", ""),
                                         skipped=d["skipped"])
            ride = d.get("ride_error_K")
            return ClosedLoopSummary(
                passed=d.get("passed"), criterion=d.get("criterion", ""),
                energy_MJ=_f(d.get("energy_MJ")), max_violation_K=_f(d.get("max_violation_K")),
                max_T_cab_violation_K=_f(d.get("max_T_cab_violation_K")),
                first_step_violation_K=_f(d.get("first_step_violation_K")),
                ride_error_K=max(ride) if ride else math.nan,
                max_avoidable_violation_K=_f(d.get("max_avoidable_violation_K")),
                fallbacks=int(d.get("fallbacks", 0)))

        cav = sc.get("cav", {})
        paper = _comparison(cav) if not cav.get("skipped") and "case1_energy_MJ" in cav else None
        per = cav.get("periodic") if not cav.get("skipped") else None
        tm = check.timing
        return cls(passed=bool(check.passed), model=loop(sc["model"]), plant=loop(sc["plant"]),
                   cav=loop(cav), cav_paper=paper,
                   cav_periodic=_comparison(per) if per else None,
                   cycles=int(per.get("cycles", 0)) if per else 0,
                   timing=TimingSummary(median_ms=_f(tm.get("median")), p95_ms=_f(tm.get("p95")),
                                        max_ms=_f(tm.get("max")), mean_ms=_f(tm.get("mean")),
                                        steps=int(tm.get("n", 0)),
                                        passed=bool(tm.get("passed", False)),
                                        criterion=str(tm.get("criterion", ""))))


def _f(x) -> float:
    try:
        x = float(x)
    except (TypeError, ValueError):
        return math.nan
    return x


def _comparison(m: dict) -> CavComparisonSummary:
    """From the metrics of a CAV comparison (``run_cav_scenario``)."""
    e1, e2 = _f(m.get("case1_energy_MJ")), _f(m.get("case2_energy_MJ"))
    blind = m.get("speed_blind_plant") or {}
    end = m.get("T_cab_window_end_K") or {}
    return CavComparisonSummary(
        window_s=tuple(float(w) for w in m["window_s"]), case1_energy_MJ=e1,
        case2_energy_MJ=e2, energy_difference_MJ=e2 - e1, saving_pct=_f(m.get("saving_pct")),
        speed_blind_saving_pct=_f(blind.get("saving_pct")),
        saving_from_speed_pct=_f(m.get("saving_from_speed_pct")),
        T_cab_end_difference_K=_f(end.get("case1")) - _f(end.get("case2")) if end else math.nan)


@dataclass(frozen=True)
class EnergyController(JsonDataclass):
    """One controller on one drive cycle of ``acid cav-study`` (MJ, %, K, g/kg, kg/s).

    ``tail_corrected_energy_MJ`` is the energy with the end state charged back (a common
    continuation from the end and from the start); savings are against controller A and
    against the best fixed-coil PI F, the gap against the best known plan's replay (perfect
    information, not a bound), all on the tail-corrected energies;
    ``saving_vs_best_pi_pi_charge_pct`` the saving against F with the end states charged by
    F's PI loops instead of the paper NMPC (the charge's own uncertainty). ``in_rh_band`` is 1 when
    the mean cabin RH lies inside the study's band, 0 outside (not ranked), NaN unknown.
    """

    energy_MJ: float = math.nan
    tail_corrected_energy_MJ: float = math.nan
    saving_raw_pct: float = math.nan
    saving_tail_corrected_pct: float = math.nan
    saving_vs_best_pi_pct: float = math.nan
    saving_vs_best_pi_pi_charge_pct: float = math.nan
    gap_to_best_plan_pct: float = math.nan
    in_rh_band: float = math.nan
    mean_T_cab_K: float = math.nan
    max_T_cab_K: float = math.nan
    pmv_mean: float = math.nan
    ppd_mean_pct: float = math.nan
    rh_mean_pct: float = math.nan
    w_cab_mean_g_kg: float = math.nan
    mean_T_evap_set_K: float = math.nan
    mean_W_bl_kg_s: float = math.nan


@dataclass(frozen=True)
class EnergyCycle(JsonDataclass):
    """One cycle of ``acid cav-study``: the controllers (A, B, D, E, P, F, plan), the target
    mean cabin temperature (K), speed preview's share (E minus D, points), the best known
    plan's value of the comfort band over pinning T_cab (%), its replay's miss of the model
    energy (%), its spread over independent optima (%, its uncertainty) and F's coil
    set-point (K)."""

    target_mean_T_cab_K: float
    preview_share_points: float
    band_vs_pinned_pct: float
    replay_vs_model_pct: float
    controllers: dict[str, EnergyController]
    best_plan_spread_pct: float = math.nan
    best_pi_coil_set_point_K: float = math.nan


@stage_result("cav")
@dataclass(frozen=True)
class CavStudyStage(StageResult):
    """Beyond the paper, where the energy is: ``acid cav-study`` on drive cycles."""

    cycles: dict[str, EnergyCycle]

    @classmethod
    def of(cls, d: dict) -> CavStudyStage:
        """From ``acid.studies.cav_study.CavStudyResult.to_json_dict()``."""
        names = [f.name for f in dataclasses.fields(EnergyController)]
        cycles = {}
        for name, c in d["cycles"].items():
            ctl = c["controllers"]
            plan = ctl.get("plan", {})
            cycles[name] = EnergyCycle(
                target_mean_T_cab_K=_f(c.get("target_mean_T_cab_K")),
                preview_share_points=_f(c.get("preview_share_points")),
                band_vs_pinned_pct=_f(plan.get("band_vs_pinned_pct")),
                replay_vs_model_pct=_f(plan.get("replay_vs_model_pct")),
                controllers={k: EnergyController(**{n: _f(v.get(n)) for n in names})
                             for k, v in ctl.items()},
                best_plan_spread_pct=_f(c.get("best_plan_spread_pct")),
                best_pi_coil_set_point_K=_f(ctl.get("F", {}).get("coil_set_point_K")))
        return cls(cycles=cycles)


@dataclass(frozen=True)
class EngineVerdict(JsonDataclass):
    """One verdict of the comparison engine (``acid compare``): ``candidate`` against
    ``baseline`` over the held-out scenarios, saving in % of the baseline (positive: the
    candidate uses less), its 95 % paired-bootstrap and paired-t intervals, the word read
    from them, the comfort gaps (candidate minus baseline: K min per pass, K) and the
    single-pass charged figures under both charge conventions (figures, not verdicts)."""

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
    discomfort_gap_Kmin: float = math.nan
    T_cab_gap_K: float = math.nan
    single_own_pct: float = math.nan
    single_pi_pct: float = math.nan


def engine_key(candidate: str, baseline: str) -> str:
    """The key of a verdict in :attr:`EngineStage.savings`: "E_vs_F", and "E_matched_vs_F"
    for E at F's mean cabin temperature."""
    return candidate.replace(" at F's T_cab", "_matched") + "_vs_" + baseline


@dataclass(frozen=True)
class BestPlan(JsonDataclass):
    """The best known operation on one held-out scenario under periodic steady state
    (kJ per pass, K; ``plan["E_at_F_kJ"]``: E interpolated to F's mean cabin temperature
    there): the cyclic whole-cycle plan (least replayed energy over its
    formulations and starts, ``spread_pct`` between the formulations), beside F at its tuned
    coil and E on the same scenario; ``best`` names the least of the three at equal mean
    cabin temperature (a plan is matched to the engine's set-point, F holds it, E is
    interpolated to F's mean): the best known operation ("when another formulation finds a
    cheaper plan, that becomes the plan"); ``E_gap_pct`` how far E lies above it."""

    scenario: str
    plan_kJ: float
    formulation: str
    spread_pct: float
    formulations_kJ: dict[str, float]
    plan_mean_T_cab_K: float
    F_kJ: float
    F_mean_T_cab_K: float
    E_kJ: float = math.nan
    best: str = ""
    best_kJ: float = math.nan
    E_gap_pct: float = math.nan
    #: each operation's energy above the best known one, %
    gaps_pct: dict[str, float] = field(default_factory=dict)


def _best_plan(result, plan: Mapping) -> BestPlan:
    from acid.units import C2K

    name = plan["scenario"]
    runs = {r.family: r for r in result.held_out if r.scenario == name}
    F = runs.get("F")
    w = plan["winner"]
    E_kJ = _f(plan.get("E_at_F_kJ"))
    cands = {"plan": float(w["replay_energy_kJ"])}
    if F is not None:
        cands["F"] = F.energy_J / 1e3
    if math.isfinite(E_kJ):
        cands["E"] = E_kJ
    best = min(cands, key=cands.get)
    return BestPlan(
        scenario=name, plan_kJ=cands["plan"], formulation=f"{w['formulation']} ({w['start']})",
        spread_pct=_f(plan.get("spread_pct")),
        formulations_kJ={k: _f(c.get("replay_energy_kJ"))
                         for k, c in plan.get("by_formulation", {}).items()},
        plan_mean_T_cab_K=C2K(_f(w.get("replay_mean_T_cab_degC"))),
        F_kJ=cands.get("F", math.nan),
        F_mean_T_cab_K=F.mean_T_cab if F is not None else math.nan, E_kJ=E_kJ, best=best,
        best_kJ=cands[best], E_gap_pct=100.0 * (E_kJ - cands[best]) / cands[best],
        gaps_pct={k: 100.0 * (v - cands[best]) / cands[best] for k, v in cands.items()})


@stage_result("engine")
@dataclass(frozen=True)
class EngineStage(StageResult):
    """The comparison engine on acid's plant (``acid compare`` with the reproduction's econ
    model): knobs tuned on ``training``, verdicts over ``held_out``, periodic steady state.
    ``tuned`` knobs in SI (coil set-points K, E's comfort weight W/K^2 s);
    ``extrapolated``: per family, the held-out scenarios on which its econ model's plans
    left the model's identification data."""

    training: tuple[str, ...]
    held_out: tuple[str, ...]
    rule: str
    comfort_level_Kmin: float
    tuned: dict[str, float]
    econ_ref_offset_K: float
    verdicts: tuple[EngineVerdict, ...]
    extrapolated: dict[str, tuple[str, ...]] = field(default_factory=dict)
    periodic_passes_max: int = 0
    all_converged: bool = True
    #: held-out runs whose periodic steady state is a period-2 orbit (two alternating
    #: passes, their mean the figure); the rest repeat every pass
    period_two_runs: int = 0
    #: every verdict's saving (%) with its 95 % bootstrap interval, keyed
    #: :func:`engine_key` ("E_vs_F", "E_matched_vs_F", "F_vs_own", ...)
    savings: dict[str, Estimate] = field(default_factory=dict)
    #: the best known operation per energy-study cycle (its held-out scenario)
    best_plans: dict[str, BestPlan] = field(default_factory=dict)

    @classmethod
    def of(cls, result, plans: Mapping[str, Mapping] | None = None) -> EngineStage:
        """From ``acid.studies.compare.CompareResult`` and, per cycle, the periodic plan set
        (``acid.control.econ.periodic_plan.PeriodicPlanSet.to_dict()`` with its
        ``scenario``)."""
        names = [f.name for f in dataclasses.fields(EngineVerdict)]
        out: dict[str, list[str]] = {}
        for r in result.held_out:
            if r.extrapolated:
                out.setdefault(r.family, []).append(r.scenario)
        return cls(training=tuple(s.name for s in result.scenarios.training),
                   held_out=tuple(s.name for s in result.scenarios.held_out),
                   rule=result.scenarios.rule, comfort_level_Kmin=result.comfort_level_Kmin,
                   tuned={k: float(v) for k, v in result.tuned.items()},
                   econ_ref_offset_K=_f(result.settings.get("econ_ref_offset_K")),
                   verdicts=tuple(EngineVerdict(**{n: getattr(v, n) for n in names})
                                  for v in result.verdicts),
                   extrapolated={k: tuple(sorted(v)) for k, v in out.items()},
                   periodic_passes_max=max((r.passes for r in result.held_out), default=0),
                   all_converged=all(r.converged for r in result.held_out),
                   period_two_runs=sum(getattr(r, "period", 1) == 2 for r in result.held_out),
                   savings={engine_key(v.candidate, v.baseline): Estimate(
                       float(v.mean_pct), ci95_low=float(v.boot_lo),
                       ci95_high=float(v.boot_hi)) for v in result.verdicts},
                   best_plans={c: _best_plan(result, p) for c, p in (plans or {}).items()})

    def verdict(self, candidate: str, baseline: str) -> EngineVerdict | None:
        return next((v for v in self.verdicts if v.candidate == candidate
                     and v.baseline == baseline), None)


@stage_result("econ")
@dataclass(frozen=True)
class EconStage(StageResult):
    """Beyond the paper: the econ model identified from an ``acid excite --model econ`` record
    and validated beside the paper's model (both fitted on its first part, the same starts
    on the rest). ``power_map_*`` are RMS errors in % of the mean compressor power;
    ``extra_median_abs`` the econ model's median |error| of the channels the paper's model
    does not predict (K, g/kg, W, % of a window's energy)."""

    duration_s: float
    power_map_rms_pct: float
    power_map_steady_rms_pct: float
    starts: int
    horizon: int
    econ: dict[str, ChannelErrors]
    paper: dict[str, ChannelErrors]
    extra_median_abs: dict[str, float]

    @classmethod
    def of(cls, duration_s: float, power_map: dict, econ, paper) -> EconStage:
        """From the power map's quality and the two ``DeclaredValidation``s; the extra
        channels are the econ model's beyond the paper's (in the declaration's units) and
        its compressor energy per window (%)."""
        e, p = ValidationStage.of(econ), ValidationStage.of(paper)
        extra = {k: _f(econ.metrics[k].get("median_abs")) * (1e3 if u == "kg/kg" else 1.0)
                 for k, u in zip(econ.channels, econ.units, strict=True)
                 if k not in paper.channels}   # humidity in g/kg
        if "P_comp" in econ.energy:
            extra["compressor_energy"] = _f(econ.energy["P_comp"].get("median_abs"))
        return cls(duration_s=float(duration_s),
                   power_map_rms_pct=_f(power_map.get("rms_pct")),
                   power_map_steady_rms_pct=_f(power_map.get("steady_rms_pct")),
                   starts=e.starts, horizon=e.horizon, econ=e.channels, paper=p.channels,
                   extra_median_abs=extra)


@dataclass(frozen=True)
class PlantCredential(JsonDataclass):
    """One plant-check row: a plant quantity beside a published reference (not the paper's).

    ``value`` in ``unit`` (NaN when the check only computes, e.g. a figure); ``passed`` is
    the plant check's own verdict (None when it could not run, and for ``info`` rows: a
    design target shown without a verdict).
    """

    name: str
    group: str
    reference: str
    unit: str
    value: float = math.nan
    passed: bool | None = None
    note: str = ""
    info: bool = False


@stage_result("plant_check")
@dataclass(frozen=True)
class PlantCheckStage(StageResult):
    """``acid plant-check``: the high-fidelity plant's credentials."""

    passed: bool
    checks: tuple[PlantCredential, ...]
    cop_steady_30C_standstill: float = math.nan
    cop_gain_25_vs_0_equal_load_pct: float = math.nan
    search_note: str = ""

    @classmethod
    def of(cls, d: dict) -> PlantCheckStage:
        """From ``PlantCheckResult.to_json_dict()``."""
        rows = tuple(PlantCredential(
            name=str(c["name"]), group=str(c.get("group", "")),
            reference=str(c.get("reference", "")), unit=str(c.get("unit", "")),
            value=_f(c.get("value")), passed=c.get("passed"), note=str(c.get("note") or ""),
            info=bool(c.get("info", False)))
            for c in d["checks"])
        return cls(passed=bool(d["passed"]), checks=rows,
                   cop_steady_30C_standstill=_f(d.get("cop_steady_30C_standstill")),
                   cop_gain_25_vs_0_equal_load_pct=_f(d.get("cop_gain_25_vs_0_equal_load_pct")),
                   search_note=str(d.get("search_note") or ""))


@dataclass(frozen=True)
class YearShare(JsonDataclass):
    """One point of the whole-year sweep: the climate's energy over one pass of
    ``cycle`` from a soak at ``T_amb_C`` and the share of range it costs (0-1)."""

    T_amb_C: float
    cycle: str
    vehicle: str
    heating: str          # "heat pump", "heater only", or "-" (cooling)
    E_climate_kWh: float
    E_heater_kWh: float
    share: float
    T_cab_mean_C: float


@stage_result("heating")
@dataclass(frozen=True)
class HeatingStage(StageResult):
    """Winter: the heating plant's credentials that need no logs
    (``acid heating-check`` without ``--logs``) and the whole-year sweep at a few ambients
    (``acid year-sweep``). acid's own checks, not the paper's claims."""

    passed: bool
    checks: tuple[PlantCredential, ...]
    year: tuple[YearShare, ...] = ()
    switch_over_C: float = math.nan


# ------------------------------------------------------------------------- reading
@dataclass(frozen=True)
class StudyResults:
    """The typed results of the stages that ran, looked up by their class."""

    by_stage: dict[str, StageResult] = field(default_factory=dict)

    @classmethod
    def from_summaries(cls, summaries: Mapping[str, Mapping]) -> StudyResults:
        """From {stage name: summary dict} (stage cache records or ``summary.json``).

        Stages without a registered result class are left out (their summaries stay
        plain data for the report's stage table).
        """
        out = {}
        for name, d in summaries.items():
            kind = STAGE_RESULTS.get(name)
            if kind is not None:
                out[name] = kind.from_json_dict(d, source=f"stage {name!r} summary")
        return cls(out)

    def get(self, kind: type[T]) -> T | None:
        """The result of the stage whose class is ``kind`` (None if it did not run)."""
        r = self.by_stage.get(kind.STAGE)
        return r if isinstance(r, kind) else None


__all__ = ["STAGE_RESULTS", "CavComparisonSummary", "CavStudyStage", "ChannelErrors",
           "BestPlan", "EconStage", "EngineStage", "EngineVerdict", "EnergyController",
           "EnergyCycle", "HeatingStage", "YearShare", "engine_key",
           "ClosedLoopSummary", "Estimate", "ExcitationStage", "FitStage", "JsonDataclass",
           "MpcStage", "PlantCheckStage", "PlantCredential", "StageResult",
           "StudyResults", "SweepStage", "TimingSummary", "ValidationStage", "field_type",
           "stage_result"]
