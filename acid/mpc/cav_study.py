"""A fair drive-cycle study of speed preview for the A/C of a connected and automated vehicle.

The paper's CAV comparison (scenario (c) of :mod:`acid.mpc.scenarios`) compares energy over
a short window that ends with the ICM case's cabin warmer: part of the "saving" is heat not
yet removed. This study compares three controllers on the high-fidelity plant over a whole
standard drive cycle, under conditions that make the energies comparable:

* **(A) constant bound** -- the paper's NMPC with a constant upper bound on T_cab (the
  conventional A/C), the bound tuned (secant iteration) so that the mean cabin temperature
  over the cycle equals that of (B);
* **(B) ICM bound** -- the paper's NMPC following the speed-coordinated bound of
  :mod:`acid.mpc.icm` (comfort band ``[T_low, T_high]``, built from the previewed cycle); no
  open-loop compressor shut-off (the NMPC decides);
* **(C) speed-aware NMPC** -- :class:`acid.mpc.speed_model.SpeedAwareNMPC`, eq. 4 with the
  identified ``eta_cop(v(i|k))`` over the previewed speed; lower bound ``T_low``, a constant
  upper bound tuned like (A) to the same mean T_cab as (B): the optimiser itself decides
  when to cool below it.

Fairness
--------
* **Same start.** Each plant is first warmed up to a steady condition (``warmup_s`` at the
  cycle's mean speed with the paper's NMPC on a constant bound ``warmup_bound``); every case
  starts from that full plant state (T_cab, T_evap, T_int, T_shell, T_cw, w_cab).
* **Same comfort.** (A) and (C) have the mean T_cab of (B) over samples 1 .. n (within
  ``tol_K``); the comfort violation (K s outside ``[T_low, T_high]``) is reported.
* **Same end state.** The cases end in different states; the heat left in the cabin is
  charged back. Heat content ``H = C_cab T_cab + C_int T_int + w_sh C_sh T_shell + C_ew T_ew
  + L_cab w_cab`` (J, capacities from :class:`acid.plant.config.PlantConfig`; ``w_sh = hA_sh /
  (hA_sh + hA_ext(v_mean))`` is the share of the shell's surplus that flows into the cabin
  rather than to ambient; ``L_cab = M_cab h_fg`` the latent heat of the cabin moisture, which
  matters: a case that ends with a warm evaporator ends with humid air), and the correction
  of case X is ``(H_X - H_A) / COP_A`` with ``COP_A`` the evaporator heat per compressor
  energy of (A) over the cycle (so (A)'s correction is 0). This lumped correction uses the
  *average* COP and no blower energy, so it underestimates the cost of a pull-down. A second,
  model-free correction (``tail_s`` > 0): every case continues from its end state for
  ``tail_s`` under the same controller (paper NMPC, constant bound = the target mean, cycle
  mean speed); the tail energies' differences to (A)'s are the measured cost of the
  different end states (the most trustworthy number; 1200 s lets the interior settle).
  Savings are reported raw, C_eff-corrected and tail-corrected.
* **Speed-blind twin.** The whole study is repeated on the plant with speed removed from its
  physics (:func:`acid.mpc.scenarios._speed_blind_hifi`); what (B) or (C) save there owes
  nothing to speed (the controllers still believe in it).

Energy is compressor + blower (the NMPC's objective), ``sum(P) Ts`` over the cycle; the
constant condenser fan is left out. Temperatures in K, energies in J inside.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from acid._io import json_safe
from acid.errors import ConfigError
from acid.mpc.icm import ICMConfig, icm_upper_bound
from acid.mpc.nmpc import NMPC, NMPCConfig
from acid.mpc.scenarios import ClosedLoopRun, closed_loop, solve_stats_ms
from acid.mpc.speed_model import SpeedAwareNMPC, SpeedEfficiency
from acid.params import ModelParams
from acid.units import C2K

CASES = ("A", "B", "C")
CASE_LABELS = {"A": "A: constant bound", "B": "B: ICM bound",
               "C": "C: speed-aware NMPC"}
#: full plant state carried from the warm-up / the cycle into the next run
STATE_KEYS = ("T_cab", "T_evap", "T_int", "T_shell", "T_cw", "w_cab")


@dataclass(frozen=True)
class StudyConfig:
    """Options of the study (temperatures in K, times in s).

    Attributes
    ----------
    cycle : drive cycle name from ``datasets/drive_cycles``.
    horizon : NMPC horizon N for all three controllers (paper: 6 = 30 s).
    T_low, T_high : comfort band, K (ICM band; (C)'s lower bound is ``T_low``).
    warmup_s : warm-up length before the cycle, s.
    warmup_bound : constant upper bound during the warm-up, K.
    tol_K : tolerance on the mean-T_cab match of (A) and (C) to (B), K.
    max_iter : iterations of the bound tuning.
    tail_s : length of the common continuation that measures the end-state cost, s (0: none).
    icm : rule of case (B).
    speed_blind : also run the study on the speed-blind twin plant.
    """

    cycle: str = "udds"
    horizon: int = 6
    T_low: float = C2K(22.0)
    T_high: float = C2K(26.0)
    warmup_s: float = 1800.0
    warmup_bound: float = C2K(24.0)
    tol_K: float = 0.02
    max_iter: int = 8
    tail_s: float = 1200.0
    icm: ICMConfig = field(default_factory=ICMConfig)
    speed_blind: bool = True

    def __post_init__(self):
        if int(self.horizon) < 2:
            raise ConfigError(f"--horizon must be at least 2, got {self.horizon}")
        if not self.T_low < self.T_high:
            raise ConfigError("comfort band: T_low must be below T_high")
        if self.warmup_s < 0 or self.tail_s < 0:
            raise ConfigError("warm-up and tail lengths must be >= 0 s")

    def nmpc_config(self) -> NMPCConfig:
        """The NMPC options shared by all cases (Table II, horizon and lower bound here)."""
        return NMPCConfig(N=int(self.horizon), T_cab_min=self.T_low)

    def to_json_dict(self) -> dict:
        return {"cycle": self.cycle, "horizon": int(self.horizon), "T_low_K": self.T_low,
                "T_high_K": self.T_high, "warmup_s": self.warmup_s,
                "warmup_bound_K": self.warmup_bound, "tol_K": self.tol_K,
                "max_iter": self.max_iter, "tail_s": self.tail_s,
                "icm": self.icm.to_json_dict(), "speed_blind": self.speed_blind}


class _RecordingPlant:
    """Delegates to a plant and keeps every step row (for Q_evap and the end state)."""

    def __init__(self, plant):
        self.plant = plant
        self.Ts = plant.Ts
        self.name = getattr(plant, "name", "plant")
        self.rows: list[dict] = []

    def reset(self, initial=None):
        self.rows = []
        return self.plant.reset(initial)

    def step(self, W_bl, T_evap_set, v_veh=0.0, **kw):
        row = self.plant.step(W_bl, T_evap_set, v_veh, **kw)
        self.rows.append(row)
        return row

    def measure(self) -> dict:
        return dict(self.plant.measure())

    def end_state(self) -> dict:
        s = self.measure()
        return {k: float(s[k]) for k in STATE_KEYS}

    def q_evap_J(self) -> float:
        return float(sum(r.get("Q_evap", 0.0) for r in self.rows) * self.Ts)


# ----------------------------------------------------------------------------- results
@dataclass(frozen=True)
class CaseResult:
    """One case on one plant (K, J, s).

    Attributes
    ----------
    key, label : ``"A"``, ``"B"``, ``"C"`` and a description.
    run : the closed-loop run over the cycle.
    upper_bound_K : the constant upper bound of (A)/(C) after tuning (None for (B)).
    tuning : [(bound K, mean T_cab K)] of the tuning iterations (empty for (B)).
    end_state : plant state at the end of the cycle, K (w_cab kg/kg).
    heat_content_J : H of the end state (module docstring), J.
    q_evap_J : evaporator heat removed over the cycle, J.
    correction_J : C_eff end-state correction relative to (A), J (0 for (A)).
    tail_energy_J : energy of the common continuation, J (NaN without a tail).
    T_low, T_high : comfort band, K.
    """

    key: str
    label: str
    run: ClosedLoopRun
    upper_bound_K: float | None
    tuning: tuple
    end_state: dict
    heat_content_J: float
    q_evap_J: float
    correction_J: float
    tail_energy_J: float
    T_low: float
    T_high: float

    @property
    def energy_J(self) -> float:
        """Compressor + blower energy over the cycle, sum((P_comp + P_bl) Ts), J."""
        return self.run.energy_J()

    @property
    def corrected_energy_J(self) -> float:
        """Energy plus the C_eff end-state correction, J."""
        return self.energy_J + self.correction_J

    @property
    def mean_T_cab(self) -> float:
        """Mean cabin temperature over samples 1 .. n, K."""
        return float(np.mean(self.run.T_cab[1:]))

    @property
    def max_T_cab(self) -> float:
        return float(np.max(self.run.T_cab[1:]))

    @property
    def comfort_violation_Ks(self) -> float:
        """Integral of the distance outside ``[T_low, T_high]`` over samples 1 .. n, K s."""
        T = self.run.T_cab[1:]
        d = np.maximum.reduce([np.zeros_like(T), T - self.T_high, self.T_low - T])
        return float(np.sum(d) * self.run.Ts)

    def to_json_dict(self) -> dict:
        return {
            "label": self.label, "energy_MJ": self.energy_J / 1e6,
            "corrected_energy_MJ": self.corrected_energy_J / 1e6,
            "correction_MJ": self.correction_J / 1e6,
            "tail_energy_MJ": self.tail_energy_J / 1e6,
            "mean_T_cab_K": self.mean_T_cab, "max_T_cab_K": self.max_T_cab,
            "min_T_cab_K": float(np.min(self.run.T_cab[1:])),
            "comfort_violation_Ks": self.comfort_violation_Ks,
            "upper_bound_K": self.upper_bound_K,
            "tuning": [[float(b), float(m)] for b, m in self.tuning],
            "end_state_K": self.end_state, "heat_content_J": self.heat_content_J,
            "q_evap_MJ": self.q_evap_J / 1e6, "solve_ms": solve_stats_ms([self.run]),
            "fallbacks": int(np.sum(self.run.fallback)),
        }


def _pct(ref: float, x: float) -> float | None:
    return 100.0 * (ref - x) / ref if ref > 0 and np.isfinite(ref) and np.isfinite(x) else None


@dataclass(frozen=True)
class PlantStudy:
    """The three cases on one plant.

    Attributes
    ----------
    plant : ``"hifi"`` or ``"speed-blind twin"``.
    cases : {"A", "B", "C"} -> CaseResult.
    start_state : the common warmed-up start, K.
    target_mean_K : (B)'s mean T_cab, which (A) and (C) are tuned to, K.
    cop_ref : (A)'s evaporator heat per compressor energy, used by the correction.
    capacities : {"C_cab", "C_int", "C_sh", "C_ew" (J/K), "w_sh" (1), "L_cab" (J per kg/kg)}
        of the heat content.
    """

    plant: str
    cases: dict
    start_state: dict
    target_mean_K: float
    cop_ref: float
    capacities: dict

    def savings_pct(self, key: str) -> dict:
        """Saving of case ``key`` vs (A): raw, C_eff-corrected and tail-corrected, %.

        Tail-corrected: ``E_X + (tail_X - tail_A)`` against ``E_A``.
        """
        a, x = self.cases["A"], self.cases[key]
        out = {"raw": _pct(a.energy_J, x.energy_J),
               "corrected": _pct(a.corrected_energy_J, x.corrected_energy_J)}
        if np.isfinite(a.tail_energy_J):
            # the tail's extra energy is charged to the cycle (A's tail is the reference)
            out["tail_corrected"] = _pct(a.energy_J,
                                         x.energy_J + x.tail_energy_J - a.tail_energy_J)
            out["tail_correction_MJ"] = (x.tail_energy_J - a.tail_energy_J) / 1e6
        return out

    def to_json_dict(self) -> dict:
        return {"plant": self.plant, "start_state_K": self.start_state,
                "target_mean_T_cab_K": self.target_mean_K, "cop_ref": self.cop_ref,
                "capacities": self.capacities,
                "cases": {k: c.to_json_dict() for k, c in self.cases.items()},
                "savings_pct": {k: self.savings_pct(k) for k in ("B", "C")}}


@dataclass(frozen=True)
class CavStudyResult:
    """Everything ``acid cav-study`` reports.

    Attributes
    ----------
    config : the study options.
    efficiency : the ``eta_cop(v)`` used by (C).
    v_step : (n,) cycle speed per sample, m/s.
    main : study on the high-fidelity plant.
    blind : study on the speed-blind twin (None when not run).
    params_name : model parameters of the NMPCs.
    elapsed_s : wall time, s.
    """

    config: StudyConfig
    efficiency: SpeedEfficiency
    v_step: np.ndarray
    main: PlantStudy
    blind: PlantStudy | None
    params_name: str
    elapsed_s: float

    def to_json_dict(self) -> dict:
        """Strict-JSON summary (non-finite numbers become null; temperatures in K)."""
        return json_safe(self._json())

    def _json(self) -> dict:
        d = {"config": self.config.to_json_dict(), "efficiency": self.efficiency.to_json_dict(),
             "params": self.params_name, "elapsed_s": self.elapsed_s,
             "cycle_mean_speed_m_s": float(np.mean(self.v_step)),
             "cycle_duration_s": float(self.v_step.size * self.main.cases["A"].run.Ts),
             "hifi": self.main.to_json_dict()}
        if self.blind is not None:
            d["speed_blind_twin"] = self.blind.to_json_dict()
            d["saving_from_speed_pct"] = {
                k: {m: (self.main.savings_pct(k)[m] - self.blind.savings_pct(k)[m]
                        if self.main.savings_pct(k).get(m) is not None
                        and self.blind.savings_pct(k).get(m) is not None else None)
                    for m in ("raw", "corrected", "tail_corrected")
                    if m in self.main.savings_pct(k)}
                for k in ("B", "C")}
        return d


# ------------------------------------------------------------------------------ study
def _capacities(plant, v_mean: float) -> dict:
    c = getattr(plant, "cfg", None)
    if c is None:
        from acid.plant.config import PlantConfig

        c = PlantConfig()
    hA_ext = c.hA_ext0 + c.hA_ext_v * v_mean ** 0.8
    return {"C_cab": c.C_cab, "C_int": c.C_int, "C_sh": c.C_sh, "C_ew": c.C_ew,
            "w_sh": c.hA_sh / (c.hA_sh + hA_ext), "L_cab": c.C_cab / c.c_p_air * c.h_fg}


def heat_content(state: dict, cap: dict) -> float:
    """``H = C_cab T_cab + C_int T_int + w_sh C_sh T_shell + C_ew T_evap + L_cab w_cab``, J.

    Temperatures in K, ``w_cab`` in kg/kg; ``L_cab = (C_cab / c_p) h_fg`` (J per kg/kg) is
    the latent heat of the cabin air's moisture (0 when the state has no ``w_cab``).
    """
    return float(cap["C_cab"] * state["T_cab"] + cap["C_int"] * state["T_int"]
                 + cap["w_sh"] * cap["C_sh"] * state["T_shell"]
                 + cap["C_ew"] * state["T_evap"] + cap["L_cab"] * state.get("w_cab", 0.0))


def end_state_correction(H_case: float, H_ref: float, cop_ref: float) -> float:
    """Electric energy to remove the extra heat ``H_case - H_ref`` at ``cop_ref``, J."""
    return (H_case - H_ref) / cop_ref


def _tune(run_fn: Callable[[float], tuple], target: float, lo: float, hi: float,
          tol: float, max_iter: int):
    """Constant bound b in [lo, hi] whose run has mean T_cab = ``target`` (secant steps).

    ``run_fn(b)`` returns ``(mean_T_cab, payload)``. Returns ``(b, payload, history)`` of
    the iterate closest to the target.
    """
    hist, best = [], None
    b_prev = f_prev = None
    b = float(np.clip(target, lo, hi))
    for _ in range(max(1, int(max_iter))):
        m, payload = run_fn(b)
        f = m - target
        hist.append((b, m))
        if best is None or abs(f) < abs(best[2]):
            best = (b, payload, f)
        if abs(f) <= tol:
            break
        slope = 1.0
        if b_prev is not None and abs(b - b_prev) > 1e-6:
            s = (f - f_prev) / (b - b_prev)
            if 0.2 < s < 5.0:
                slope = s
        b_new = float(np.clip(b - f / slope, lo, hi))
        if abs(b_new - b) < 1e-6:
            break
        b_prev, f_prev, b = b, f, b_new
    return best[0], best[1], tuple(hist)


def _run(plant_factory, mpc, init, ub, v, label):
    plant = _RecordingPlant(plant_factory())
    run = closed_loop(plant, mpc, init, ub, v, label)
    return run, plant


def run_plant_study(params: ModelParams, config: StudyConfig, efficiency: SpeedEfficiency,
                    v_step: np.ndarray, plant_factory: Callable, plant_label: str = "hifi",
                    progress: Callable[[int], None] | None = None) -> PlantStudy:
    """Warm-up, then (B), (A) tuned and (C) tuned on one plant; see the module docstring.

    ``progress(steps)`` is called after each closed-loop run with its number of steps.
    """
    tick = progress or (lambda steps: None)
    ncfg = config.nmpc_config()
    paper_mpc = NMPC(params, ncfg)
    aware = SpeedAwareNMPC(params, efficiency, ncfg)
    Ts, N = params.Ts, ncfg.N
    n = int(v_step.size)
    v_mean = float(np.mean(v_step))
    v_pad = np.concatenate((v_step, np.full(N + 1, v_step[-1])))
    t_all = np.arange(n + N + 1) * Ts

    # warm-up to a steady condition (same for every case)
    n_w = int(round(config.warmup_s / Ts))
    probe = plant_factory()
    start = {k: float(v) for k, v in probe.reset().items() if k in STATE_KEYS}
    if n_w > 0:
        rec = _RecordingPlant(probe)
        closed_loop(rec, paper_mpc, None, np.full(n_w + N + 1, config.warmup_bound),
                    np.full(n_w, v_mean), "warm-up")
        start = rec.end_state()
        tick(n_w)
    cap = _capacities(probe, v_mean)

    def finish(key, run, plant, bound, hist):
        return key, run, plant, bound, hist

    # (B) ICM bound from the previewed cycle
    ub_B = icm_upper_bound(t_all, v_pad, config.icm, initial=start["T_cab"])
    run_B, pl_B = _run(plant_factory, paper_mpc, start, ub_B, v_step, CASE_LABELS["B"])
    tick(n)
    target = float(np.mean(run_B.T_cab[1:]))
    lo, hi = config.T_low - 2.0, config.T_high

    def tuned(mpc, key):
        def run_fn(b):
            if isinstance(mpc, SpeedAwareNMPC):
                mpc.set_speed_profile(v_step)
            r, p = _run(plant_factory, mpc, start, np.full(n + N + 1, b), v_step,
                        CASE_LABELS[key])
            tick(n)
            return float(np.mean(r.T_cab[1:])), (r, p)

        b, (r, p), hist = _tune(run_fn, target, lo, hi, config.tol_K, config.max_iter)
        return r, p, b, hist

    run_A, pl_A, b_A, h_A = tuned(paper_mpc, "A")
    run_C, pl_C, b_C, h_C = tuned(aware, "C")

    raw = {"A": (run_A, pl_A, b_A, h_A), "B": (run_B, pl_B, None, ()),
           "C": (run_C, pl_C, b_C, h_C)}
    P_A = float(np.sum(run_A.P_comp) * Ts)
    cop_ref = pl_A.q_evap_J() / P_A if P_A > 0 else float("nan")
    H = {k: heat_content(v[1].end_state(), cap) for k, v in raw.items()}

    # common continuation from each end state: measures the end-state cost directly
    n_t = int(round(config.tail_s / Ts))
    tails = {}
    for key, (_run_k, pl, _b, _h) in raw.items():
        if n_t > 0:
            rec = _RecordingPlant(plant_factory())
            tr = closed_loop(rec, paper_mpc, pl.end_state(), np.full(n_t + N + 1, target),
                             np.full(n_t, v_mean), f"{key} tail")
            tails[key] = tr.energy_J()
            tick(n_t)
        else:
            tails[key] = float("nan")

    cases = {}
    for key in CASES:
        run, pl, b, hist = raw[key]
        cases[key] = CaseResult(
            key=key, label=CASE_LABELS[key], run=run, upper_bound_K=b, tuning=hist,
            end_state=pl.end_state(), heat_content_J=H[key], q_evap_J=pl.q_evap_J(),
            correction_J=0.0 if key == "A" else end_state_correction(H[key], H["A"], cop_ref),
            tail_energy_J=tails[key], T_low=config.T_low, T_high=config.T_high)
    return PlantStudy(plant=plant_label, cases=cases, start_state=start,
                      target_mean_K=target, cop_ref=cop_ref, capacities=cap)


def _default_factories():
    from acid.mpc.scenarios import _make_hifi, _speed_blind_hifi

    return _make_hifi, _speed_blind_hifi


def estimated_steps(config: StudyConfig, n: int, Ts: float = 5.0) -> int:
    """Closed-loop steps the study will take (for a progress bar; tuning may stop early)."""
    per = (int(round(config.warmup_s / Ts)) + n * (1 + 2 * 3)
           + 3 * int(round(config.tail_s / Ts)))
    return per * (2 if config.speed_blind else 1)


def cav_study(params: ModelParams, config: StudyConfig | None = None,
              efficiency: SpeedEfficiency | None = None,
              plant_factory: Callable | None = None,
              blind_factory: Callable | None = None,
              progress: Callable[[int, int], None] | None = None) -> CavStudyResult:
    """Run the study on one drive cycle (see the module docstring).

    Parameters
    ----------
    params : model parameters of all three NMPCs.
    config : study options (default ``StudyConfig()``: UDDS, N = 6, band 22-26 degC).
    efficiency : ``eta_cop(v)`` of (C); default: identified from the high-fidelity plant
        (:func:`acid.mpc.speed_model.identify_from_plant`, UDDS, 7200 s, seed 0).
    plant_factory, blind_factory : plant constructors (default: ``HifiPlant()`` and its
        speed-blind twin).
    progress : ``progress(done, total)`` in closed-loop steps.
    """
    from acid.signals import drive_cycle

    config = config or StudyConfig()
    t0 = time.perf_counter()
    v_step, _ = drive_cycle(config.cycle, Ts=params.Ts)
    if plant_factory is None:
        plant_factory, blind_default = _default_factories()
        blind_factory = blind_factory or blind_default
    if efficiency is None:
        from acid.mpc.speed_model import identify_from_plant

        efficiency = identify_from_plant()
    total = estimated_steps(config, int(v_step.size), params.Ts)
    done = [0]

    def tick(steps):
        done[0] += steps
        if progress is not None:
            progress(min(done[0], total), total)

    main = run_plant_study(params, config, efficiency, v_step, plant_factory, "hifi", tick)
    blind = None
    if config.speed_blind and blind_factory is not None:
        blind = run_plant_study(params, config, efficiency, v_step, blind_factory,
                                "speed-blind twin", tick)
    if progress is not None:
        progress(total, total)
    return CavStudyResult(config=config, efficiency=efficiency, v_step=np.asarray(v_step),
                          main=main, blind=blind, params_name=params.name,
                          elapsed_s=time.perf_counter() - t0)
