"""The real car's A/C under economic NMPC: the study.

Three steps, each returning a result object (no printing):

1. :func:`fit_power`: the A/C power output of ``acid.models.car_ac`` fitted by least squares
   on estimation trips (the cabin rows held at their prediction-error fit), scored on
   held-out trips (R^2 and RMSE per sample, R^2 of each trip's mean power, total energy).
2. :func:`closed_loop`: one controller on the identified model as the plant
   (:class:`acid.plant.declared.DeclaredPlant`) over a logged trip's ambient and speed:
   the economic NMPC (:class:`acid.control.car_ac.CarEconNMPC`, state from the filter),
   a PI loop (:class:`acid.control.car_ac.CabinPI`), or the car's own logged set-point
   replayed.
3. :func:`compare_on_trip`: the NMPC against the PI tuned to the same mean cabin air
   (its set-point by bisection, its gains the least energy among those that hold the band
   as well as the NMPC), and the logged car's set-point replayed on the same model.

Temperatures in K inside, energies in J, powers in W.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np

from acid.control.car_ac import CabinFilter, CabinPI, CarACConfig, CarEconNMPC
from acid.data import Dataset
from acid.errors import DataError
from acid.models.car_ac import POWER_NAMES
from acid.models.car_ac import model as CAR_AC
from acid.models.car_cabin import Q_SOL_PRIOR
from acid.models.declaration import Model
from acid.plant.declared import DeclaredPlant


# ----------------------------------------------------------------- 1. the power output
def car_ac_values(cabin_values, model: Model = CAR_AC) -> np.ndarray:
    """car_ac's table: the cabin rows given (car_cabin's table order), the power rows as
    declared."""
    cabin = np.asarray(cabin_values, dtype=float)
    values = model.values.copy()
    values[:cabin.size] = cabin
    return values


def power_function(model: Model = CAR_AC) -> ca.Function:
    """``(T_cab, T_evap, T_amb, v_veh, p) -> P_comp``: the declaration's power output on
    logged channels (it must read no latent state), vectorised by ``.map``."""
    k = model.output_names.index("P_comp")
    y = model.h(model._x, model._u, model._d, model._p)[k]
    latent = [i for i, s in enumerate(model.states) if not s.measured]
    if any(ca.depends_on(y, model._x[i]) for i in latent):
        raise DataError(f"model {model.name!r}: P_comp reads a latent state; it cannot be "
                        "fitted on logged channels alone")
    return ca.Function("P_comp", [model._x, model._u, model._d, model._p], [y])


@dataclass(frozen=True)
class PowerScore:
    """How the power output predicts one set of trips.

    r2 : 1 - mean squared error / variance of the logged power, per 5 s sample.
    rmse_W, bias_W : root mean square and mean of logged - predicted, W.
    trip_r2 : the same R^2 over each trip's mean power.
    energy_ratio : predicted / logged total A/C energy.
    n : samples.
    """

    r2: float
    rmse_W: float
    bias_W: float
    trip_r2: float
    energy_ratio: float
    n: int


@dataclass(frozen=True)
class PowerFit:
    """The power rows fitted (``values``: name -> value) and their scores."""

    values: dict
    estimation: PowerScore
    held_out: PowerScore
    status: str


def _logged(ds: Dataset, model: Model):
    names = {"T_cab", "T_evap", "T_amb", "v_veh", "P_comp"}
    missing = sorted(n for n in names if n not in ds)
    if missing:
        raise DataError(f"{ds.source}: missing channel(s) {', '.join(map(repr, missing))}")
    X = np.zeros((len(ds), model.nx))
    X[:, model.state_names.index("T_cab")] = ds.get("T_cab", "K")
    U = ds.get("T_evap", "K")[:, None]
    D = np.column_stack([ds.get(s.name, s.unit) for s in model.disturbances])
    return X, U, D, ds.get("P_comp", "W")


def _predict_power(fn, X, U, D, values) -> np.ndarray:
    return _power_on(fn, X, U, D)(values)


def _power_on(fn, X, U, D) -> Callable[[np.ndarray], np.ndarray]:
    """``values -> P_comp`` on fixed logged channels: the map and the channels converted to
    CasADi once (a least-squares fit calls it hundreds of times; the same numbers)."""
    mapped = fn.map(len(X))
    args = [ca.DM(X.T), ca.DM(U.T), ca.DM(D.T)]
    return lambda values: np.asarray(mapped(*args, values)).ravel()


def _score(ds: Dataset, P: np.ndarray, Ph: np.ndarray) -> PowerScore:
    r = P - Ph
    trips = ds.segments()
    pm = np.array([P[a:b].mean() for a, b in trips])
    ph = np.array([Ph[a:b].mean() for a, b in trips])
    return PowerScore(r2=float(1 - np.mean(r ** 2) / P.var()), rmse_W=float(np.sqrt(np.mean(
        r ** 2))), bias_W=float(r.mean()), trip_r2=float(1 - np.mean((pm - ph) ** 2) /
                                                          pm.var()),
        energy_ratio=float(Ph.sum() / P.sum()), n=len(P))


def fit_power(est: Dataset, held_out: Dataset, cabin_values, model: Model = CAR_AC
              ) -> PowerFit:
    """Least squares of the logged A/C power on the declaration's ``P_comp`` output over the
    estimation trips (its free power rows within their declared bounds, from their declared
    values), scored on both sets."""
    from scipy.optimize import least_squares

    fn = power_function(model)
    values = car_ac_values(cabin_values, model)
    idx = [model.parameter_names.index(n) for n in POWER_NAMES]
    lo = [model.parameters[i].min for i in idx]
    hi = [model.parameters[i].max for i in idx]
    Xe, Ue, De, Pe = _logged(est, model)
    power_e = _power_on(fn, Xe, Ue, De)

    def residual(z):
        v = values.copy()
        v[idx] = z
        return power_e(v) - Pe

    res = least_squares(residual, values[idx], bounds=(lo, hi))
    values[idx] = res.x
    Xv, Uv, Dv, Pv = _logged(held_out, model)
    return PowerFit(values={n: float(v) for n, v in zip(POWER_NAMES, res.x, strict=True)},
                    estimation=_score(est, Pe, power_e(values)),
                    held_out=_score(held_out, Pv, _predict_power(fn, Xv, Uv, Dv, values)),
                    status=str(res.message))


# ----------------------------------------------------------------- 2. closed loop
@dataclass(frozen=True)
class Trip:
    """A logged trip's disturbances (the declaration's order: T_amb K, v_veh m/s), its
    logged cabin air, set-point and A/C power, and its name."""

    name: str
    d: np.ndarray
    T_cab: np.ndarray
    T_evap: np.ndarray
    P_comp: np.ndarray
    Ts: float

    @classmethod
    def of(cls, ds: Dataset, experiment: int, model: Model = CAR_AC) -> Trip:
        ids = np.unique(ds.experiment)
        if experiment not in ids:
            raise DataError(f"{ds.source}: no experiment {experiment} (has {ids.min()}-"
                            f"{ids.max()})")
        a, b = ds.segments()[list(ids).index(experiment)]
        w = ds.window(a, b)
        X, U, D, P = _logged(w, model)
        return cls(name=ds.experiment_names()[list(ids).index(experiment)], d=D,
                   T_cab=w.get("T_cab", "K"), T_evap=U[:, 0], P_comp=P, Ts=ds.Ts)

    def preview(self, k: int, N: int) -> np.ndarray:
        """(N, nd): the disturbances from sample k on, the last row repeated past the end."""
        return self.d[np.minimum(np.arange(k, k + N), len(self.d) - 1)]


@dataclass(frozen=True)
class ClosedLoop:
    """One controller over one trip.

    T_cab : (n,) cabin air at each sample, K; T_evap : (n,) set-point applied, K;
    P_comp : (n,) A/C power over each sample, W; energy_J : sum P_comp Ts;
    mean_T_cab_K : mean cabin air over the samples scored (after ``settle`` s);
    violation_Ks : integral of the cabin air outside the band over them, K s;
    max_violation_K : largest excursion outside the band over them, K;
    fallbacks : solver failures (NMPC).
    """

    name: str
    T_cab: np.ndarray
    T_evap: np.ndarray
    P_comp: np.ndarray
    energy_J: float
    mean_T_cab_K: float
    violation_Ks: float
    max_violation_K: float
    fallbacks: int = 0

    def summary(self) -> dict:
        return {"controller": self.name, "energy_kJ": self.energy_J / 1e3,
                "mean_T_cab_C": self.mean_T_cab_K - 273.15,
                "violation_Ks": self.violation_Ks, "max_violation_K": self.max_violation_K,
                "mean_P_comp_W": float(self.P_comp.mean()), "fallbacks": self.fallbacks}


def initial_state(model: Model, values, T_cab: float, d0) -> np.ndarray:
    """A trip's start: cabin air as logged, interior at it, shell between it and the
    ambient, the load at its typical value ``Q_bar`` (the plant's truth)."""
    v = dict(zip(model.parameter_names, values, strict=True))
    T_amb = float(d0[[s.name for s in model.disturbances].index("T_amb")])
    x = {"T_cab": T_cab, "T_int": T_cab, "T_shell": 0.5 * (T_cab + T_amb),
         "Q_sol": v["Q_bar"]}
    return np.array([x[n] for n in model.state_names])


class ModelPlant:
    """The identified declaration as the plant (:class:`DeclaredPlant`), from a trip's
    start (:func:`initial_state`)."""

    def __init__(self, model: Model, values, trip: Trip):
        self.model = model
        x0 = initial_state(model, values, float(trip.T_cab[0]), trip.d[0])
        self.plant = DeclaredPlant(model, values,
                                   initial=dict(zip(model.state_names, x0, strict=True)))
        self._d = [s.name for s in model.disturbances]

    def T_cab(self) -> float:
        return float(self.plant.measure()["T_cab"])

    def step(self, T_evap: float, d) -> float:
        """Apply ``T_evap`` over one sample under ``d``; the A/C power over it, W."""
        row = self.plant.step(W_bl=0.0, T_evap_set=0.0, T_evap=T_evap,
                              **dict(zip(self._d, d, strict=True)))
        return float(row["P_comp"])


def closed_loop(name: str, trip: Trip, plant, control: Callable, band: tuple[float, float],
                *, settle_s: float = 0.0, fallbacks=lambda: 0) -> ClosedLoop:
    """``plant`` (``T_cab()``, ``step(T_evap, d) -> P_comp``) over ``trip``;
    ``control(k, T_cab) -> T_evap`` each sample (it sees the measured cabin air only).
    Scores from ``settle_s`` on."""
    n = len(trip.d)
    T, U, P = np.empty(n), np.empty(n), np.empty(n)
    for k in range(n):
        T[k] = plant.T_cab()
        U[k] = control(k, T[k])
        P[k] = plant.step(U[k], trip.d[k])
    k0 = min(int(round(settle_s / trip.Ts)), n - 1)
    lo, hi = band
    excess = np.maximum(T[k0:] - hi, 0.0) + np.maximum(lo - T[k0:], 0.0)
    return ClosedLoop(name, T, U, P, energy_J=float(P.sum() * trip.Ts),
                      mean_T_cab_K=float(T[k0:].mean()),
                      violation_Ks=float(excess.sum() * trip.Ts),
                      max_violation_K=float(excess.max()), fallbacks=int(fallbacks()))


def run_nmpc(trip: Trip, values, plant, config: CarACConfig | None = None, *,
             model: Model = CAR_AC, settle_s: float = 0.0,
             Q_sol0: float = Q_SOL_PRIOR) -> ClosedLoop:
    """The economic NMPC (on ``model`` with ``values``) in closed loop on ``plant``; its
    state from :class:`CabinFilter`, started from the measured cabin air and the load
    ``Q_sol0`` (W; default the filter's prior, not the plant's truth)."""
    cfg = config or CarACConfig()
    nmpc = CarEconNMPC(model, values, cfg)
    x0 = initial_state(model, values, plant.T_cab(), trip.d[0])
    x0[model.state_names.index("Q_sol")] = Q_sol0
    filt = CabinFilter(model, values, x0)

    def control(k, T_cab):
        xhat = filt.update(T_cab)
        u = nmpc.make_step(xhat, trip.preview(k, cfg.N))
        filt.predict([u], trip.d[k])
        return u

    return closed_loop("economic NMPC", trip, plant, control, (cfg.T_cab_min, cfg.T_cab_max),
                       settle_s=settle_s, fallbacks=lambda: nmpc.fallbacks)


def run_pi(trip: Trip, plant, pi: CabinPI, band: tuple[float, float], *,
           settle_s: float = 0.0) -> ClosedLoop:
    """The PI baseline in closed loop on ``plant``."""
    step = pi.run()
    return closed_loop(f"PI (set-point {pi.T_set - 273.15:.2f} degC, Kp {pi.Kp:g}, "
                       f"Ki {pi.Ki:g})", trip, plant, lambda k, T: step(T, trip.Ts), band,
                       settle_s=settle_s)


def run_logged(trip: Trip, plant, band: tuple[float, float], *,
               settle_s: float = 0.0) -> ClosedLoop:
    """The car's own logged set-point replayed on ``plant`` (what the car did, on the same
    plant: comparable in energy, not in the cabin air it reached)."""
    return closed_loop("logged car (set-point replayed)", trip, plant,
                       lambda k, T: float(trip.T_evap[k]), band, settle_s=settle_s)


#: the PI gains tried (Kp K/K, Ki K/(K s)): slow to fast against the cabin's ~30 min
PI_GAINS = ((1.0, 0.003), (3.0, 0.01), (6.0, 0.02), (10.0, 0.05))


def _bisect_setpoint(run: Callable, lo: float, hi: float, above: Callable, n: int = 25):
    """The set-point in [lo, hi] where ``above(result)`` changes (True at hi), and its run."""
    r_lo = None
    for _ in range(n):
        mid = 0.5 * (lo + hi)
        r = run(mid)
        if above(r):
            hi = mid
        else:
            lo, r_lo = mid, r
    return lo, (r_lo if r_lo is not None else run(lo))


def tune_pi(trip: Trip, make_plant: Callable, band: tuple[float, float], *,
            target_mean_K: float | None = None, max_violation_K: float = 0.05,
            gains=PI_GAINS, settle_s: float = 0.0) -> tuple[ClosedLoop, list[ClosedLoop]]:
    """The best PI baseline: per ``(Kp, Ki)`` the set-point by bisection, then the least
    energy over the gains. With ``target_mean_K``: the set-point whose mean cabin air
    equals it (within 0.01 K; at a band edge a PI then leaves the band about half the
    time). Without: the warmest set-point whose cabin air stays within ``max_violation_K``
    of the band (comfort held; its mean cabin air is then what it is)."""
    runs = []
    for Kp, Ki in gains:
        def run(T_set, Kp=Kp, Ki=Ki):
            return run_pi(trip, make_plant(), CabinPI(T_set, Kp, Ki), band,
                          settle_s=settle_s)
        if target_mean_K is not None:
            _, r = _bisect_setpoint(run, target_mean_K - 15.0, target_mean_K + 15.0,
                                    lambda r: r.mean_T_cab_K > target_mean_K)
        else:
            _, r = _bisect_setpoint(run, band[0] - 10.0, band[1],
                                    lambda r: r.max_violation_K > max_violation_K)
        runs.append(r)
    return min(runs, key=lambda r: r.energy_J), runs


@dataclass(frozen=True)
class TripComparison:
    """NMPC, the PI baselines and the logged car's set-point on one trip (same plant, same
    band): ``pi_equal_mean`` at the NMPC's mean cabin air, ``pi_band`` the warmest PI that
    holds the band."""

    trip: str
    plant: str
    nmpc: ClosedLoop
    pi_equal_mean: ClosedLoop
    pi_band: ClosedLoop
    pi_candidates: tuple
    logged: ClosedLoop
    logged_energy_J: float        # the A/C energy the car logged on this trip
    logged_mean_T_cab_K: float    # the cabin air the car logged (after settle_s)
    band_K: tuple[float, float]
    settle_s: float

    def summary(self) -> dict:
        return {"trip": self.trip, "plant": self.plant,
                "band_C": [b - 273.15 for b in self.band_K], "settle_s": self.settle_s,
                "nmpc": self.nmpc.summary(), "pi_equal_mean": self.pi_equal_mean.summary(),
                "pi_band": self.pi_band.summary(),
                "logged_replayed": self.logged.summary(),
                "logged": {"energy_kJ": self.logged_energy_J / 1e3,
                           "mean_T_cab_C": self.logged_mean_T_cab_K - 273.15},
                "nmpc_vs_pi_equal_mean_energy_percent":
                    100 * (self.nmpc.energy_J / self.pi_equal_mean.energy_J - 1),
                "nmpc_vs_pi_band_energy_percent":
                    100 * (self.nmpc.energy_J / self.pi_band.energy_J - 1)}


def compare_on_trip(trip: Trip, values, make_plant: Callable | None = None,
                    config: CarACConfig | None = None, *, model: Model = CAR_AC,
                    plant_name: str = "identified model", settle_s: float = 600.0
                    ) -> TripComparison:
    """The NMPC (on ``model`` with ``values``), the PI baselines and the logged set-point
    replayed, each on a fresh ``make_plant()`` (default: the identified model itself).
    Comfort is scored after ``settle_s`` (a hot start's pull-down is not comfort)."""
    cfg = config or CarACConfig()
    make_plant = make_plant or (lambda: ModelPlant(model, values, trip))
    band = (cfg.T_cab_min, cfg.T_cab_max)
    nm = run_nmpc(trip, values, make_plant(), cfg, model=model, settle_s=settle_s)
    eq, cands = tune_pi(trip, make_plant, band, target_mean_K=nm.mean_T_cab_K,
                        settle_s=settle_s)
    held, cands_b = tune_pi(trip, make_plant, band, max_violation_K=max(
        nm.max_violation_K, 0.05), settle_s=settle_s)
    k0 = min(int(round(settle_s / trip.Ts)), len(trip.T_cab) - 1)
    return TripComparison(trip.name, plant_name, nm, eq, held, tuple(cands + cands_b),
                          run_logged(trip, make_plant(), band, settle_s=settle_s),
                          float(trip.P_comp.sum() * trip.Ts), float(trip.T_cab[k0:].mean()),
                          band, settle_s)


# ----------------------------------------------------------------- 3. acid's plant near it
@dataclass(frozen=True)
class MappedField:
    """One row of the mapping onto :class:`acid.plant.config.PlantConfig`: the plant field,
    the value set (SI), what it comes from, or why it is left as configured."""

    field: str
    value: float | None
    source: str


def hifi_mapping(values, model: Model = CAR_AC) -> tuple[dict, tuple[MappedField, ...]]:
    """The high-fidelity plant's fields set from the identified ``car_ac`` values as far as
    its structure allows (``{field: value}`` for ``PlantConfig.replace``, and every row,
    mapped or not, with its reason). The A/C power is the plant's own cycle, not mapped."""
    v = dict(zip(model.parameter_names, values, strict=True))
    c_p = 1006.0   # J/(kg K), air near 20 degC
    W_bl = v["G_sup"] / c_p
    A_glass_tau = 0.9 * 0.5          # PlantConfig defaults A_glass_sun x tau_glass, m^2
    rows = (
        MappedField("C_cab", 1e3 * v["C_cab"], "C_cab (cabin air + trims; at its bound)"),
        MappedField("C_int", 1e3 * v["C_int"], "C_int (at its bound)"),
        MappedField("hA_int", v["UA_int"], "UA_int (at its bound)"),
        MappedField("hA_int_slow", 0.1, "none: the car model has no slow interior (the "
                    "plant's slow node decoupled at its lowest conductance)"),
        MappedField("C_sh", 1e3 * v["C_shell"], "C_shell (+/- 550 kJ/K: barely fixed)"),
        MappedField("hA_sh", v["UA_shell"], "UA_shell"),
        MappedField("h_ext_nat", v["UA_out"] / 9.0, "UA_out / A_shell (9 m^2); the plant's "
                    "speed dependence is its own correlation (UA_out_v 9 +/- 28 W s/(K m) "
                    "is not fixed by the data)"),
        MappedField("W_bl_min", min(0.02, W_bl), "lowered so that the blower can run at "
                    "G_sup / c_p"),
        MappedField("G_solar", max(v["Q_bar"] - 80.0, 0.0) / A_glass_tau,
                    "Q_bar (the load's typical value) less one occupant (Q_pass 80 W), "
                    "through the glazing onto the interior"),
        MappedField("alpha_shell", 0.0, "the identified load enters the interior only (no "
                    "solar term on the shell)"),
        MappedField("r_max", 1.0 - v["f_fresh"], "1 - f_fresh of the power map (0.38 on the "
                    "estimation trips, 0 with the split reversed: not fixed)"),
        MappedField("k_rec", 10.0, "recirculation held at r_max (the car's flap is not "
                    "logged)"),
        MappedField("W_bl (input)", W_bl, "G_sup / c_p, held (blower level 1 in the logs)"),
        MappedField("compressor, cycle, COP", None, "not mapped: the plant computes its "
                    f"cycle (COP 2.4-3.7); the logs give k_ac {v['k_ac']:.1f} W/K, i.e. COP "
                    f"{v['G_sup'] / v['k_ac']:.2f} with G_sup as the evaporator's flow"),
        MappedField("humidity, infiltration", None, "not mapped: the logs carry neither; "
                    "the plant keeps its own"),
    )
    fields = {r.field: r.value for r in rows if r.value is not None and "(" not in r.field}
    return fields, rows


class HifiCarPlant:
    """acid's high-fidelity plant configured by :func:`hifi_mapping`, driven like the car:
    the blower held at ``G_sup / c_p``, the evaporator set-point the controller's
    ``T_evap``, from a trip's start (cabin, interior, shell as :func:`initial_state`)."""

    def __init__(self, values, trip: Trip, model: Model = CAR_AC):
        from acid.plant.config import PlantConfig
        from acid.plant.hifi import HifiPlant

        fields, rows = hifi_mapping(values, model)
        self.W_bl = next(r.value for r in rows if r.field == "W_bl (input)")
        T_amb0 = float(trip.d[0][[s.name for s in model.disturbances].index("T_amb")])
        self.plant = HifiPlant(PlantConfig().replace(T_amb=T_amb0, **fields), mode="direct")
        x0 = dict(zip(model.state_names, initial_state(model, values, float(trip.T_cab[0]),
                                                       trip.d[0]), strict=True))
        self.plant.reset({"T_cab": x0["T_cab"], "T_int": x0["T_int"],
                          "T_int_slow": x0["T_int"], "T_shell": x0["T_shell"],
                          "T_evap": x0["T_cab"]})
        self._d = [s.name for s in model.disturbances]

    def T_cab(self) -> float:
        return float(self.plant.measure()["T_cab"])

    def step(self, T_evap: float, d) -> float:
        dd = dict(zip(self._d, d, strict=True))
        row = self.plant.step(W_bl=self.W_bl, T_evap_set=T_evap, v_veh=dd["v_veh"],
                              T_amb=dd["T_amb"])
        return float(row["P_comp"])
