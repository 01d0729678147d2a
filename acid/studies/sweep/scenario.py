"""One scenario of a sweep, as a worker runs it: warm-up, every controller, the table rows.

:func:`run_scenario` is the task a sweep sends to a Dask worker (or runs in this process). It
never raises for a failure of the scenario (a controller that raises, a plant that refuses a
state): the failure is recorded with its one-line error in the returned record, so one bad
scenario does not stop the sweep. Only ``KeyboardInterrupt`` goes through.

Fair comparison
---------------
Every controller of a scenario runs on a fresh high-fidelity plant from the same start
(after a common warm-up with the paper's NMPC on a constant bound at the set-point and the
cycle's mean speed; or from the configuration's hot soak when ``warmup_s = 0``), over the same
speed profile, with the same comfort band. Energy is compressor + blower (the NMPC's
objective, paper eq. 7); the constant condenser fan is reported separately. Raw savings mix
comfort and stored heat: match the mean cabin temperature (``match`` of the ``nmpc``
controller) and charge back the end state (``tail_s``: every run continues for ``tail_s``
under the same paper NMPC; the difference of the tail energies to the baseline's is added to
the run's energy) for savings that compare like with like (see ``acid cav-study``).
"""

from __future__ import annotations

import json
import os
import socket
import time
import traceback
from dataclasses import dataclass

import numpy as np

from acid import __version__
from acid.models.params import ModelParams
from acid.plant.config import PlantConfig
from acid.studies.sweep.context import (
    COMMON_HORIZON,
    PREVIEW_SAMPLES,
    ControllerRun,
    ScenarioContext,
    plant_state,
    tail_energy_J,
)
from acid.studies.sweep.spec import (
    DEFAULT_CONSTANT_DURATION_S,
    IdentifySettings,
    Scenario,
    SweepSpec,
)
from acid.units import K2C


@dataclass(frozen=True)
class ScenarioTask:
    """Everything a worker needs for one scenario (picklable, no open files).

    Attributes
    ----------
    key : the scenario's hash (spec + acid version); names its result file.
    index : position in the spec's scenario list.
    scenario : conditions, drive, warm-up and tail.
    plant_config : the high-fidelity plant's configuration (built and checked by the spec).
    controllers : the spec's controllers (spec order: the order of the rows).
    run_order : their labels in the order to run them (a ``match`` after its target).
    baseline : label of the controller savings are measured against.
    params_kind : ``"paper"``, ``"file"`` or ``"identify"``.
    params : the model parameters (None when identified: passed to :func:`run_scenario`).
    """

    key: str
    index: int
    scenario: Scenario
    plant_config: PlantConfig
    controllers: tuple
    run_order: tuple
    baseline: str
    params_kind: str
    params: ModelParams | None = None


def one_line(exc: BaseException) -> str:
    """``Type: first line of the message`` (acid's own errors: the message alone)."""
    from acid.errors import AcidError

    msg = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    if isinstance(exc, AcidError):
        return msg or type(exc).__name__
    return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__


def speed_profiles(scenario: Scenario, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    """``(v_step, v_preview)``: the run's mean speed per step and the same continued by
    ``PREVIEW_SAMPLES`` steps (the cycle's next pass, or the constant speed), m/s."""
    from acid.signals import constant_speed, drive_cycle

    if isinstance(scenario.cycle, str):
        if scenario.duration_s > 0:
            n = int(round(scenario.duration_s / Ts))
        else:
            n = drive_cycle(scenario.cycle, Ts=Ts)[0].size
        v, _ = drive_cycle(scenario.cycle, n=n + PREVIEW_SAMPLES, Ts=Ts, repeat=True)
    else:
        n = int(round((scenario.duration_s or DEFAULT_CONSTANT_DURATION_S) / Ts))
        v, _ = constant_speed(n + PREVIEW_SAMPLES, Ts, scenario.cycle)
    return v[:n].copy(), v


def identify_params(plant_config: PlantConfig, settings: IdentifySettings,
                    allow_unstable: bool = False) -> ModelParams:
    """Excite the plant of ``plant_config`` (APRBS, ``acid excite``) and fit eqs. 1-3 and 5
    (``acid fit``) on the whole record: the model parameters for that configuration.
    Unstable or implausible identified parameters raise ``DataError`` (every scenario that
    needs them is recorded as an error) unless ``allow_unstable``."""
    from acid.excite import ExcitationSpec, excite
    from acid.ident.fit import fit_model, provenance
    from acid.models.params import fitted
    from acid.plant.hifi import HifiPlant

    spec = ExcitationSpec(duration=settings.duration_s, seed=settings.seed,
                          speed=settings.speed_m_s)
    ds = excite(HifiPlant(plant_config), spec)
    res = fitted(fit_model("paper", ds, settings.method))
    prov = dict(provenance(ds, settings.method), identified_in="acid sweep",
                excitation={"duration_s": settings.duration_s, "seed": settings.seed,
                            "speed_m_s": settings.speed_m_s})
    problems = [] if allow_unstable else res.stability_problems()
    if problems:
        from acid.errors import DataError

        raise DataError(f"parameters identified ({settings.method}) for this climate: "
                        f"{problems[0]} (--allow-unstable uses them anyway)")
    return res.replace(name=f"identified-{settings.method}", provenance=prov)


def warm_start(ctx: ScenarioContext, seconds: float) -> dict | None:
    """The common start: the plant after ``seconds`` of the paper NMPC on a constant bound
    at the set-point, at the cycle's mean speed, from the hot soak (None when 0)."""
    from acid.studies.mpc_check.scenarios import closed_loop

    n_w = int(round(seconds / ctx.Ts))
    if n_w <= 0:
        return None
    mpc = ctx.nmpc(COMMON_HORIZON)
    plant = ctx.make_plant()
    closed_loop(plant, mpc, None, np.full(n_w + mpc.N + 1, ctx.conditions.T_set),
                np.full(n_w, float(np.mean(ctx.v_step))), "warm-up", progress=ctx.tick)
    return plant_state(plant)


def run_metrics(r: ControllerRun, ctx: ScenarioContext) -> dict:
    """The table's numbers of one run (energies MJ, temperatures degC, times ms)."""
    run = r.run
    T = run.T_cab[1:]
    c = ctx.conditions
    out = np.maximum.reduce([np.zeros_like(T), T - c.T_high, c.T_low - T])
    ms = run.step_ms[np.isfinite(run.step_ms)]
    km = float(np.sum(run.v_veh) * run.Ts / 1000.0)
    E = run.energy_J() / 1e6

    def stat(f):
        return float(f(ms)) if ms.size else float("nan")

    return {"energy_MJ": E, "energy_with_fan_MJ": run.energy_J(include_fan=True) / 1e6,
            "energy_MJ_per_km": E / km if km > 0 else float("nan"),
            "mean_T_cab_C": float(K2C(np.mean(T))), "max_T_cab_C": float(K2C(np.max(T))),
            "min_T_cab_C": float(K2C(np.min(T))), "end_T_cab_C": float(K2C(run.T_cab[-1])),
            "comfort_violation_Ks": float(np.sum(out) * run.Ts),
            "max_comfort_violation_K": float(np.max(out, initial=0.0)),
            "max_state_violation_K": run.max_violation_K,
            "mean_T_evap_set_C": float(K2C(np.mean(run.T_evap_set))),
            "mean_W_bl_kg_s": float(np.mean(run.W_bl)),
            "solve_ms_median": stat(np.median),
            "solve_ms_p95": stat(lambda a: np.percentile(a, 95)),
            "solve_ms_max": stat(np.max), "fallbacks": int(np.sum(run.fallback)),
            "steps": run.n_steps, "duration_s": run.n_steps * run.Ts, "distance_km": km}


def _pct(ref: float, x: float) -> float:
    return 100.0 * (ref - x) / ref if ref > 0 and np.isfinite(ref) and np.isfinite(x) \
        else float("nan")


def run_scenario(task: ScenarioTask, params: ModelParams | None = None,
                 tick=None) -> dict:
    """Run one scenario (worker side); see the module docstring. Returns its record:
    ``{"key", "index", "status" ("ok" | "error"), "error", "rows", "tracebacks",
    "elapsed_s", "cpu_s", "worker", "acid_version", "params"}`` (``cpu_s``: the CPU time of
    the process while it ran, s).

    Solver fallbacks are counted in the rows (``fallbacks``), not printed as warnings.
    """
    import warnings

    from acid.errors import SolverWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SolverWarning)
        return _run_scenario(task, params, tick)


def _run_scenario(task: ScenarioTask, params: ModelParams | None, tick) -> dict:
    t0, c0 = time.perf_counter(), time.process_time()
    s = task.scenario
    params = params if params is not None else task.params
    base = {"scenario_key": task.key, "scenario": task.index, "label": s.label,
            **{k: (json.dumps(v, sort_keys=True) if k == "plant" else v)
               for k, v in s.to_dict().items()}}
    rows: dict[str, dict] = {}
    errors: dict[str, str] = {}
    tracebacks: dict[str, str] = {}
    runs: dict[str, ControllerRun] = {}
    tails: dict[str, float] = {}

    def fail(label: str, exc: BaseException) -> None:
        errors[label] = one_line(exc)
        tracebacks[label] = "".join(traceback.format_exception(exc)[-6:])

    try:
        v_step, v_preview = speed_profiles(s, params.Ts)
        ctx = ScenarioContext(conditions=s.conditions, plant_config=task.plant_config,
                              params=params, v_step=v_step, v_preview=v_preview, tick=tick,
                              tail_s=s.tail_s)
        ctx.start = warm_start(ctx, s.warmup_s)
    except Exception as exc:  # the scenario cannot start: every controller fails with it
        for c in task.controllers:
            fail(c.label, exc)
        ctx = None
    if ctx is not None:
        by_label = {c.label: c for c in task.controllers}
        for c in (by_label[label] for label in task.run_order):
            target = getattr(c.config, "match", "")
            if target and target not in runs:
                errors[c.label] = f"not run: {target!r}, which it matches, failed"
                continue
            try:
                r = c.constructor(c.config).run(ctx)
                runs[c.label] = ctx.completed[c.label] = r
                tails[c.label] = tail_energy_J(ctx, r.end_state, s.tail_s)
            except Exception as exc:  # recorded; the other controllers still run
                fail(c.label, exc)
    for c in task.controllers:
        row = {**base, "controller": c.label, "controller_type": c.kind,
               "baseline": task.baseline, "status": "ok" if c.label in runs else "error",
               "error": errors.get(c.label)}
        if c.label in runs:
            row.update(run_metrics(runs[c.label], ctx))
            row["tail_energy_MJ"] = tails[c.label] / 1e6
            row["info"] = json.dumps(runs[c.label].info, sort_keys=True, default=float)
        rows[c.label] = row
    b = runs.get(task.baseline)
    for label, row in rows.items():
        if b is None or label not in runs:
            row["saving_pct"] = row["saving_tail_corrected_pct"] = float("nan")
            continue
        if label == task.baseline:
            row["saving_pct"] = 0.0
            row["saving_tail_corrected_pct"] = 0.0 if s.tail_s > 0 else float("nan")
            continue
        E_b, E_x = b.run.energy_J(), runs[label].run.energy_J()
        row["saving_pct"] = _pct(E_b, E_x)
        row["saving_tail_corrected_pct"] = _pct(E_b, E_x + tails[label] - tails[task.baseline])
    elapsed = time.perf_counter() - t0
    worker = f"{socket.gethostname()}:{os.getpid()}"
    for row in rows.values():
        row.update(params=getattr(params, "name", None), scenario_elapsed_s=elapsed,
                   worker=worker, acid_version=__version__)
    first = next(iter(errors.values()), None)
    return {"key": task.key, "index": task.index, "label": s.label,
            "status": "error" if errors else "ok", "error": first,
            "rows": list(rows.values()), "tracebacks": tracebacks, "elapsed_s": elapsed,
            "cpu_s": time.process_time() - c0, "worker": worker, "acid_version": __version__,
            "params": params.to_json_dict() if task.params_kind == "identify" and params
            else {"name": getattr(params, "name", None)}}


__all__ = ["ScenarioTask", "run_scenario", "identify_params", "speed_profiles", "run_metrics"]


def scenario_tasks(spec: SweepSpec) -> list[ScenarioTask]:
    """One :class:`ScenarioTask` per scenario of ``spec``, in spec order."""
    return [ScenarioTask(key=spec.scenario_key(s), index=i, scenario=s,
                         plant_config=s.plant_config(), controllers=spec.controllers,
                         run_order=spec.run_order, baseline=spec.baseline,
                         params_kind=spec.params[s.params].kind,
                         params=spec.params[s.params].params)
            for i, s in enumerate(spec.scenarios)]
