"""Identification of the economic model (:mod:`acid.econ.model`) from excitation data.

``EconFitter().fit(dataset)`` (``acid fit --model econ``) identifies every parameter from the
recorded channels; nothing comes from the plant's configuration. Stages:

1. **Start values** from linear regressions of the balances (trapezoidal derivatives, mid-step
   states) and a small nonlinear fit of the supply-air temperature (air side).
2. **Dynamics** (the 20 parameters of ``PARAMETER_TABLE``): one joint nonlinear least-squares
   fit of the one-interval predictions of all five states and of the interval-mean supply
   air, ``x(k+1) = F(x(k), u(k), d(k))`` integrated by the model's own RK4 step from the
   measured ``x(k)``. Residuals are weighted by each channel's residual standard deviation
   (from the start values; re-estimated while it moves by more than 3x); the Jacobian comes
   from CasADi (the same model functions). Bounds keep capacities, conductances and time
   constants positive, ``r_max`` and ``RH_amb`` in [0, 1].
3. **Blower** (paper eq. 5) by linear least squares on P_bl.
4. **Power map and C_ew**: ``P_comp(k) = Q_e(k) f(...)``, ``Q_e = Q_coil - C_ew dT_evap/dt``
   with the model's interval-mean coil load from the measured state; ``f`` is linear in its 15
   coefficients, ``C_ew`` is found by a bounded scalar search on the profiled residual
   (variable projection).

Standard errors: ``"hac"`` (default) the Newey-West sandwich over the scores of each instant
(lags inside experiments, :mod:`acid.fit`'s estimator), ``"white"`` ``sigma^2 (J^T J)^-1``.
With model mismatch (any real plant) the residuals are autocorrelated and the white errors
are too small. The hot-soak start of every experiment (``skip_s``) is left out: the cabin is
then warmer than ambient, which a constant recirculated share does not describe.

Fit quality (``EconFitResult``): one-step fit % per channel, the fit % of ``sim_window``-step
open-loop simulations from measured states, and the power map's RMS error (all samples and
near-steady ones).
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace

import casadi as ca
import numpy as np
import scipy.optimize
import scipy.stats

from acid import __version__
from acid._io import file_sha256, json_safe
from acid.data import Dataset
from acid.econ import model
from acid.econ.params import (
    MAP_INPUTS,
    MAP_TERMS,
    NAMES,
    UNITS,
    EconParams,
    PowerMap,
)
from acid.errors import ConfigError, DataError, IdentifiabilityWarning, SolverWarning
from acid.hac import hac_meat, resolve_bandwidth, segment_ids
from acid.ident.fit import COVARIANCES, DEFAULT_COVARIANCE
from acid.metrics import fit_percent
from acid.psychro import H_FG

#: Channels the identification needs (P_bl optional: eq. 5 kept at the paper's values).
REQUIRED = ("T_cab", "T_evap", "T_int", "T_shell", "w_cab", "W_bl", "T_evap_set", "v_veh",
            "T_amb", "T_ain", "P_comp")
#: Channels of the one-step residual: the five states and the supply air.
CHANNELS = model.STATES + ("T_ain",)

#: Bounds of the dynamic parameters (physical signs; wide otherwise).
_BOUNDS = {"r_max": (0.0, 0.99), "k_rec": (1e-3, 10.0), "ntu_ref": (1e-3, 50.0),
           "ntu_exp": (-1.0, 2.0),
           "kappa_bl": (0.0, 1.0), "C_cab": (100.0, 1e6), "hA_int": (0.0, 1e4),
           "hA_sh": (0.0, 1e4), "Q_cab": (-1e4, 1e4), "C_int": (1e3, 1e8),
           "Q_int": (-1e4, 1e4), "C_sh": (1e3, 1e8), "hA_ext0": (0.0, 1e4),
           "hA_ext_v": (0.0, 1e4), "Q_sh": (-1e4, 1e4), "tau_ew": (0.5, 1e3),
           "dT_ew": (-10.0, 10.0), "M_cab": (0.1, 1e3), "m_w": (-1e-3, 1e-3),
           "RH_amb": (0.0, 1.0)}
_C_EW_MAX = 5e4          # J/K, upper end of the C_ew search
_STEADY_RATE = 0.02      # K/s: |dT_cab/dt| and |dT_evap/dt| below this count as near-steady


# --------------------------------------------------------------------------- result
@dataclass(frozen=True)
class EconFitResult:
    """What the econ identification found, with the evidence to judge it.

    Attributes
    ----------
    params : the identified :class:`EconParams`.
    names, units : parameter names and units of ``estimates`` (20 dynamic + C_ew + beta).
    estimates, stderr : values and standard errors.
    ci95 : (n, 2) 95 % t-intervals.
    covariance : {"dynamics": (20, 20), "power_map": (16, 16) over C_ew and the 15 map
        coefficients, "eq5": (3, 3)}.
    fit_percent_one_step : {channel: MATLAB ``compare`` fit %} of one-interval predictions
        (states, T_ain, P_comp, P_bl).
    fit_percent_simulation : {channel: fit %} of ``sim_window``-step simulations.
    residual_std : {channel: one-step residual std} (K, kg/kg, W).
    power_map_quality : the map's RMS errors (W and % of the mean power, all and near-steady
        samples), its R^2 and sample count.
    solver_status : {stage: status}.
    warnings, notes : one line each.
    n_samples, n_rows : samples in the data and rows used.
    covariance_kind : "white" or "hac"; ``hac_bandwidth`` {block: lag}.
    elapsed_s : wall time, s.
    """

    params: EconParams
    names: tuple[str, ...]
    units: tuple[str, ...]
    estimates: np.ndarray
    stderr: np.ndarray
    ci95: np.ndarray
    covariance: dict
    fit_percent_one_step: dict
    fit_percent_simulation: dict
    residual_std: dict
    power_map_quality: dict
    solver_status: dict
    warnings: tuple[str, ...]
    notes: tuple[str, ...]
    n_samples: int
    n_rows: int
    covariance_kind: str
    hac_bandwidth: dict = field(default_factory=dict)
    elapsed_s: float = field(default=float("nan"), compare=False)
    method: str = "one-step"

    def table(self) -> list[tuple[str, str, float, float, float, float]]:
        """Rows (name, unit, estimate, stderr, ci_low, ci_high)."""
        return [(n, u, float(e), float(s), float(lo), float(hi))
                for n, u, e, s, (lo, hi) in zip(self.names, self.units, self.estimates,
                                                self.stderr, self.ci95, strict=True)]

    def equations(self) -> list[str]:
        """The identified model in words and numbers (SI, K)."""
        v = self.params.values
        pm = self.params.power_map
        return [
            f"r = {v['r_max']:.4g} sat({v['k_rec']:.4g} (T_amb - T_cab) / {v['r_max']:.4g});  "
            f"T_mix = r T_cab + (1 - r) T_amb;  eps = 1 - exp(-"
            f"{v['ntu_ref']:.4g} (W_bl/0.1)^-{v['ntu_exp']:.3g});  T_ain = T_mix - eps (T_mix"
            f" - T_evap) + {v['kappa_bl']:.3g} P_bl/(W_bl c_p)",
            f"{v['C_cab']:.4g} dT_cab/dt = {v['hA_int']:.4g} (T_int - T_cab) + "
            f"{v['hA_sh']:.4g} (T_shell - T_cab) + W_bl c_p (T_ain - T_cab) + {v['Q_cab']:.4g}",
            f"{v['C_int']:.4g} dT_int/dt = {v['hA_int']:.4g} (T_cab - T_int) + "
            f"{v['Q_int']:.4g}",
            f"{v['C_sh']:.4g} dT_shell/dt = {v['hA_sh']:.4g} (T_cab - T_shell) + "
            f"({v['hA_ext0']:.4g} + {v['hA_ext_v']:.4g} v^0.8) (T_amb - T_shell) + "
            f"{v['Q_sh']:.4g}",
            f"dT_evap/dt = (T_evap_set + {v['dT_ew']:.3g} - T_evap) / {v['tau_ew']:.4g}",
            f"{v['M_cab']:.4g} dw_cab/dt = W_bl (w_ain - w_cab) + {v['m_w']:.4g};  "
            f"w_amb at RH {v['RH_amb']:.3g}",
            f"Q_e = Q_coil - {self.params.C_ew:.4g} dT_evap/dt;  P_comp = Q_e f(q, t, s, a), "
            f"f = " + " + ".join(f"{c:.4g} {t}" if t != "1" else f"{c:.4g}"
                                 for c, t in zip(pm.coef, MAP_TERMS, strict=True)),
        ]

    def to_json_dict(self) -> dict:
        params = [{"name": n, "unit": u, "estimate": e, "stderr": s, "ci95_low": lo,
                   "ci95_high": hi} for n, u, e, s, lo, hi in self.table()]
        return json_safe({
            "model": "econ", "method": self.method, "n_samples": self.n_samples,
            "n_rows": self.n_rows, "covariance_kind": self.covariance_kind,
            "hac_bandwidth": self.hac_bandwidth, "elapsed_s": self.elapsed_s,
            "parameters": params, "equations": self.equations(),
            "covariance": {k: {"names": list(n), "matrix": m}
                           for k, (n, m) in self.covariance.items()},
            "fit_percent_one_step": self.fit_percent_one_step,
            "fit_percent_simulation": self.fit_percent_simulation,
            "residual_std": self.residual_std, "power_map_quality": self.power_map_quality,
            "solver_status": self.solver_status, "warnings": list(self.warnings),
            "notes": list(self.notes)})


# ------------------------------------------------------------------------ the data
@dataclass(frozen=True)
class _Data:
    """Estimation data in model units, and the rows k (k -> k+1 inside one experiment)."""

    x: np.ndarray          # (N, 5) states
    u: np.ndarray          # (N, 2)
    d: np.ndarray          # (N, 2)
    T_ain: np.ndarray      # (N,)
    P_comp: np.ndarray     # (N,)
    P_bl: np.ndarray | None
    rows: np.ndarray       # indices k used as one-step rows
    segments: tuple
    Ts: float

    @classmethod
    def of(cls, ds: Dataset, skip_s: float) -> _Data:
        ds.validate(require=REQUIRED, min_samples=20)
        temps = ("T_cab", "T_int", "T_shell", "T_evap", "T_evap_set", "T_amb", "T_ain")
        g = {n: ds.get(n, "K") for n in temps}
        x = np.column_stack([g["T_cab"], g["T_int"], g["T_shell"], g["T_evap"],
                             ds.get("w_cab", "kg/kg")])
        u = np.column_stack([ds.get("W_bl", "kg/s"), g["T_evap_set"]])
        d = np.column_stack([ds.get("v_veh", "m/s"), g["T_amb"]])
        skip = int(round(skip_s / ds.Ts))
        trans = ds.transition_mask()
        keep = np.zeros(len(ds) - 1, dtype=bool)
        for a, b in ds.segments():
            keep[a + skip: b - 1] = True
        rows = np.flatnonzero(trans & keep)
        if rows.size < 60:
            raise DataError(f"{ds.source}: only {rows.size} usable samples after leaving out "
                            f"the first {skip_s:g} s of each experiment; the econ model needs "
                            "at least 60 (record longer, e.g. `acid excite --model econ`)")
        if np.any(u[:, 0] <= 0):
            raise DataError(f"{ds.source}: channel 'W_bl' must be positive (kg/s)")
        return cls(x=x, u=u, d=d, T_ain=g["T_ain"], P_comp=ds.get("P_comp", "W"),
                   P_bl=ds.get("P_bl", "W") if "P_bl" in ds else None, rows=rows,
                   segments=tuple(ds.segments()), Ts=float(ds.Ts))


def _namespace(values: dict, beta, C_ew: float = 0.0, power_map=None) -> SimpleNamespace:
    """An object with the attributes the model functions read (numbers or CasADi symbols)."""
    return SimpleNamespace(**values, beta=tuple(beta), C_ew=C_ew, power_map=power_map,
                           c_p=EconParams.c_p, h_fg=H_FG, p_atm=EconParams.p_atm)


def _excitation_checks(D: _Data, source: str) -> list[str]:
    """Refuse data that cannot identify the model; warn where it is thin."""
    k = D.rows
    out = []
    for j, (name, unit, need) in enumerate((("v_veh", "m/s", 5.0), ("T_amb", "K", 2.0))):
        span = float(np.ptp(D.d[k, j]))
        if span < need:
            out.append(f"{name} varies by only {span:.3g} {unit} in the data: the power map "
                       f"and the shell balance are not identified in {name} "
                       f"(use `acid excite --model econ`)")
    if float(np.ptp(D.u[k, 0])) < 0.02:
        raise DataError(f"{source}: W_bl is (nearly) constant: the air side is not "
                        "identifiable; excite the blower")
    if float(np.ptp(D.u[k, 1])) < 1.0:
        raise DataError(f"{source}: T_evap_set is (nearly) constant: the evaporator is not "
                        "identifiable; excite the set-point")
    return out


# --------------------------------------------------------------------- start values
def _start_values(D: _Data, beta) -> dict:
    """Start values from linear regressions of the balances (module docstring, stage 1)."""
    k, Ts = D.rows, D.Ts
    x0, x1 = D.x[k], D.x[k + 1]
    mid = 0.5 * (x0 + x1)
    rate = (x1 - x0) / Ts
    W, Tset = D.u[k, 0], D.u[k, 1]
    v, Ta = D.d[k, 0], D.d[k, 1]
    cp = EconParams.c_p
    one = np.ones(k.size)

    def lsq(cols, y):
        return np.linalg.lstsq(np.column_stack(cols), y, rcond=None)[0]

    # air side: T_ain with mid-interval states
    def ain_resid(th):
        p = _namespace(dict(r_max=th[0], k_rec=th[1], ntu_ref=th[2], ntu_exp=th[3],
                            kappa_bl=th[4], RH_amb=0.5), beta)
        return model.air_side(mid[:, 0], mid[:, 3], mid[:, 4], W, Ta, p).T_ain - D.T_ain[k]

    names = ("r_max", "k_rec", "ntu_ref", "ntu_exp", "kappa_bl")
    air = scipy.optimize.least_squares(ain_resid, [0.7, 0.2, 2.0, 0.4, 0.0],
                                       bounds=([_BOUNDS[n][0] for n in names],
                                               [_BOUNDS[n][1] for n in names])).x
    v0 = dict(zip(names, air, strict=True))
    Tc, Ti, Tsh, Tev = mid[:, 0], mid[:, 1], mid[:, 2], mid[:, 3]
    a = lsq([Ti - Tc, Tsh - Tc, W * (D.T_ain[k] - Tc), one], rate[:, 0])
    C_cab = cp / max(a[2], 1e-6)
    v0.update(C_cab=C_cab, hA_int=max(a[0], 1e-6) * C_cab, hA_sh=max(a[1], 1e-6) * C_cab,
              Q_cab=a[3] * C_cab)
    b = lsq([Tc - Ti, one], rate[:, 1])
    v0.update(C_int=v0["hA_int"] / max(b[0], 1e-7))
    v0.update(Q_int=b[1] * v0["C_int"])
    c = lsq([Tc - Tsh, Ta - Tsh, model.speed_factor(v) * (Ta - Tsh), one], rate[:, 2])
    C_sh = v0["hA_sh"] / max(c[0], 1e-7)
    v0.update(C_sh=C_sh, hA_ext0=max(c[1], 1e-7) * C_sh, hA_ext_v=max(c[2], 0.0) * C_sh,
              Q_sh=c[3] * C_sh)
    e = lsq([Tset - Tev, one], rate[:, 3])
    v0.update(tau_ew=1.0 / max(e[0], 1e-3), dT_ew=e[1] / max(e[0], 1e-3))
    best = None
    for RH in np.linspace(0.05, 0.95, 19):  # humidity: profile RH_amb on a grid
        p = _namespace({**v0, "RH_amb": RH}, beta)
        air_k = model.air_side(Tc, Tev, mid[:, 4], W, Ta, p)
        h = lsq([W * (air_k.w_ain - mid[:, 4]), one], rate[:, 4])
        r = rate[:, 4] - np.column_stack([W * (air_k.w_ain - mid[:, 4]), one]) @ h
        if h[0] > 0 and (best is None or r @ r < best[0]):
            best = (float(r @ r), RH, h)
    if best is None:
        best = (0.0, 0.5, np.array([1.0 / 4.0, 0.0]))
    _, RH, h = best
    v0.update(RH_amb=RH, M_cab=1.0 / h[0], m_w=h[1] / h[0])
    lo = {n: b_[0] for n, b_ in _BOUNDS.items()}
    hi = {n: b_[1] for n, b_ in _BOUNDS.items()}
    return {n: float(np.clip(v0[n], lo[n] + 1e-9 * (hi[n] - lo[n]),
                             hi[n] - 1e-9 * (hi[n] - lo[n]))) for n in NAMES}


# ------------------------------------------------------------------------- dynamics
class _OneStep:
    """Weighted one-interval residuals of the five states and T_ain, with CasADi Jacobian."""

    def __init__(self, D: _Data, beta):
        th = ca.SX.sym("theta", len(NAMES))
        p = _namespace(dict(zip(NAMES, ca.vertsplit(th), strict=True)), beta)
        x = ca.SX.sym("x", model.NX)
        u = ca.SX.sym("u", model.NU)
        d = ca.SX.sym("d", model.ND)
        r = model.step(ca.vertsplit(x), ca.vertsplit(u), ca.vertsplit(d), p, D.Ts)
        out = ca.vertcat(*r.x, r.T_ain)
        f = ca.Function("pred", [th, x, u, d], [out, ca.jacobian(out, th)])
        k = D.rows
        self.n = k.size
        self.F = f.map(self.n, "serial")
        self.X, self.U, self.Dx = D.x[k].T, D.u[k].T, D.d[k].T
        self.Y = np.vstack([D.x[k + 1].T, D.T_ain[k][None, :]])   # (6, n)
        self.weights = np.ones(len(CHANNELS))
        self._cache: tuple[bytes, np.ndarray, np.ndarray] | None = None

    def predict(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """(6, n) predictions and (6, n, p) Jacobian (channel-major), unweighted.

        The last evaluation is cached: the solver asks for residuals and Jacobian at the same
        point, and one CasADi call gives both.
        """
        key = np.asarray(theta, dtype=float).tobytes()
        if self._cache is None or self._cache[0] != key:
            out, jac = self.F(theta, self.X, self.U, self.Dx)
            J = np.asarray(jac).reshape(len(CHANNELS), self.n, len(NAMES))
            self._cache = (key, np.asarray(out), J)
        return self._cache[1], self._cache[2]

    def channel_std(self, theta) -> np.ndarray:
        """(6,) standard deviation of each channel's one-step residual."""
        out, _ = self.predict(theta)
        return np.maximum((out - self.Y).std(axis=1), 1e-12)

    def residuals(self, theta) -> np.ndarray:
        out, _ = self.predict(theta)
        return ((out - self.Y) / self.weights[:, None]).ravel()

    def jacobian(self, theta) -> np.ndarray:
        _, J = self.predict(theta)
        return (J / self.weights[:, None, None]).reshape(-1, len(NAMES))


def _sandwich(J: np.ndarray, r: np.ndarray, n_ch: int, sample: np.ndarray, segments,
              kind: str, bandwidth_spec) -> tuple[np.ndarray, int | None]:
    """Covariance of least-squares estimates: white ``s^2 (J^T J)^-1`` or Newey-West HAC.

    ``J`` (n_ch n, p) and ``r`` (n_ch n,) are channel-major; the HAC score of one instant sums
    its channels; ``sample`` (n,) are the instants (time order), ``segments`` the experiments.
    """
    m, p = J.shape
    n = m // n_ch
    dof = max(m - p, 1)
    colnorm = np.linalg.norm(J, axis=0)
    colnorm[colnorm == 0] = 1.0
    _, s, Vt = np.linalg.svd(J / colnorm, full_matrices=False)
    s_inv2 = np.where(s > 1e-12 * s[0], 1.0 / s**2, 0.0)
    bread = ((Vt.T * s_inv2) @ Vt) / np.outer(colnorm, colnorm)
    if kind == "white":
        return float(r @ r) / dof * bread, None
    h = (J * r[:, None]).reshape(n_ch, n, p).sum(axis=0)
    groups = segment_ids(sample, segments)
    lag = resolve_bandwidth(bandwidth_spec, h, groups)
    return m / dof * (bread @ hac_meat(h, groups, lag) @ bread), lag


# ------------------------------------------------------------------------ estimator
class EconFitter:
    """Identify the economic model from a dataset (see the module docstring).

    Parameters
    ----------
    covariance : ``"hac"`` (Newey-West, default) or ``"white"``.
    hac_bandwidth : ``"auto"``, ``"nw"`` or an integer lag (as :class:`acid.fit.ModelFitter`).
    skip_s : seconds left out at the start of every experiment (hot-soak pull-down).
    sim_window : samples per open-loop simulation of ``fit_percent_simulation``.
    fit_blower : fit eq. 5 from P_bl (kept at the paper's values when False or absent).
    """

    def __init__(self, covariance: str = DEFAULT_COVARIANCE, hac_bandwidth="auto",
                 skip_s: float = 600.0, sim_window: int = 300,
                 fit_blower: bool = True):
        self.covariance = covariance
        self.hac_bandwidth = hac_bandwidth
        self.skip_s = skip_s
        self.sim_window = sim_window
        self.fit_blower = fit_blower

    def _check_options(self) -> None:
        if self.covariance not in COVARIANCES:
            raise ConfigError(f"--covariance: unknown covariance {self.covariance!r} (choose "
                              f"from {', '.join(COVARIANCES)})")
        if not (math.isfinite(self.skip_s) and self.skip_s >= 0):
            raise ConfigError(f"skip_s must be >= 0 s, got {self.skip_s}")
        if int(self.sim_window) < 2:
            raise ConfigError(f"sim_window must be >= 2 samples, got {self.sim_window}")

    def fit(self, ds: Dataset) -> EconFitResult:
        """Fit the econ model to ``ds`` (channels ``REQUIRED``; P_bl optional)."""
        self._check_options()
        t0 = time.perf_counter()
        D = _Data.of(ds, self.skip_s)
        warn_lines = _excitation_checks(D, ds.source)
        for msg in warn_lines:
            warnings.warn(msg, IdentifiabilityWarning, stacklevel=2)
        notes: list[str] = []
        status: dict[str, str] = {}
        cov: dict[str, tuple] = {}
        lags: dict[str, int] = {}

        beta, beta_se, beta_cov = self._fit_blower(D, notes, lags)
        theta0 = _start_values(D, beta)
        prob = _OneStep(D, beta)
        lo = np.array([_BOUNDS[n][0] for n in NAMES])
        hi = np.array([_BOUNDS[n][1] for n in NAMES])
        th = np.array([theta0[n] for n in NAMES])
        res = None
        prob.weights = prob.channel_std(th)   # weights from the start values' residuals
        for _ in range(3):  # again only while a channel's residual std moves by > 3x
            res = scipy.optimize.least_squares(prob.residuals, th, jac=prob.jacobian,
                                               bounds=(lo, hi), x_scale="jac", ftol=1e-9,
                                               xtol=1e-9, gtol=1e-9, max_nfev=200)
            th = res.x
            std = prob.channel_std(th)
            moved = np.max(np.abs(np.log(std / prob.weights)))
            prob.weights = std
            if moved < np.log(3.0):
                break
        r = prob.residuals(th)
        J = prob.jacobian(th)
        status["dynamics"] = str(res.message)
        if not res.success:
            msg = f"dynamics fit did not converge ({res.message})"
            warnings.warn(msg, SolverWarning, stacklevel=2)
            warn_lines.append(msg)
        at_bound = [n for n, v, a, b in zip(NAMES, th, lo, hi, strict=True)
                    if min(v - a, b - v) <= 1e-6 * (b - a)]
        if at_bound:
            notes.append("at a bound (physical sign or range): " + ", ".join(at_bound))
        cov_th, lag = _sandwich(J, r, len(CHANNELS), D.rows, D.segments, self.covariance,
                                self.hac_bandwidth)
        cov["dynamics"] = (NAMES, cov_th)
        if lag is not None:
            lags["dynamics"] = lag
        values = dict(zip(NAMES, th, strict=True))

        # power map and C_ew on the model's own coil load
        p_num = _namespace(values, beta)
        k = D.rows
        one = model.step(tuple(D.x[k].T), tuple(D.u[k].T), tuple(D.d[k].T), p_num, D.Ts)
        pm, C_ew, pm_cov, pm_lag = self._fit_power_map(D, one, status)
        cov["power_map"] = (("C_ew",) + tuple(f"f[{t}]" for t in MAP_TERMS), pm_cov)
        if pm_lag is not None:
            lags["power_map"] = pm_lag
        if beta_cov is not None:
            cov["eq5"] = (("beta1", "beta2", "beta3"), beta_cov)

        se = np.sqrt(np.clip(np.diag(cov_th), 0, None))
        stderr = {n: float(s) for n, s in zip(NAMES, se, strict=True)}
        stderr["C_ew"] = float(math.sqrt(max(pm_cov[0, 0], 0.0)))
        provenance = {"data_file": ds.source, "method": "one-step (RK4) nonlinear least "
                      "squares + power-map regression", "n_samples": len(ds),
                      "skip_s": self.skip_s, "acid_version": __version__}
        if Path(ds.source).is_file():
            provenance["data_sha256"] = file_sha256(ds.source)
        if "seed" in ds.metadata:
            provenance["data_seed"] = ds.metadata["seed"]
        params = EconParams(values=values, C_ew=C_ew, power_map=pm, beta=beta, stderr=stderr,
                            Ts=D.Ts, name="econ-fit", provenance=provenance)

        names = NAMES + ("C_ew", "beta1", "beta2", "beta3")
        units = tuple(UNITS[n] for n in NAMES) + ("J/K", "W s^2/kg^2", "W s/kg", "W")
        est = np.concatenate([th, [C_ew], beta])
        se_all = np.concatenate([se, [stderr["C_ew"]], beta_se])
        dof = max(r.size - len(NAMES), 1)
        q = scipy.stats.t.ppf(0.975, dof)
        ci = np.column_stack([est - q * se_all, est + q * se_all])
        one_step = self._one_step_fit(D, prob, th, one, params)
        result = EconFitResult(
            params=params, names=names, units=units, estimates=est, stderr=se_all, ci95=ci,
            covariance=cov, fit_percent_one_step=one_step,
            fit_percent_simulation=_simulation_fit(D, params, int(self.sim_window)),
            residual_std={c: float(w) for c, w in zip(CHANNELS, prob.weights, strict=True)},
            power_map_quality=pm.quality, solver_status=status, warnings=tuple(warn_lines),
            notes=tuple(notes), n_samples=len(ds), n_rows=int(D.rows.size),
            covariance_kind=self.covariance, hac_bandwidth=lags,
            elapsed_s=time.perf_counter() - t0)
        self.params_ = params
        self.result_ = result
        return result

    # ------------------------------------------------------------------ blower
    def _fit_blower(self, D: _Data, notes, lags):
        from acid.params import PAPER_BETA

        if not self.fit_blower or D.P_bl is None:
            notes.append("beta kept at the paper's values: " + (
                "blower fit disabled" if not self.fit_blower else "the data have no P_bl"))
            return tuple(PAPER_BETA), np.full(3, np.nan), None
        W = D.u[:, 0]
        X = np.column_stack([W * W, W, np.ones_like(W)])
        beta = np.linalg.lstsq(X, D.P_bl, rcond=None)[0]
        r = D.P_bl - X @ beta
        cov, lag = _sandwich(X, r, 1, np.arange(W.size), D.segments, self.covariance,
                             self.hac_bandwidth)
        if lag is not None:
            lags["eq5"] = lag
        return tuple(float(b) for b in beta), np.sqrt(np.clip(np.diag(cov), 0, None)), cov

    # ---------------------------------------------------------------- power map
    def _fit_power_map(self, D: _Data, one: model.StepResult, status: dict):
        """C_ew by bounded scalar search, the 15 coefficients by linear least squares."""
        k, Ts = D.rows, D.Ts
        P = D.P_comp[k]
        dT = D.x[k + 1, 3] - D.x[k, 3]
        v, Ta = D.d[k, 0], D.d[k, 1]

        def design(C_ew):
            Q_e = one.Q_coil - C_ew * dT / Ts
            F = np.column_stack(np.broadcast_arrays(*model.map_features(Q_e, one.T_evap, v,
                                                                        Ta)))
            return Q_e, F * Q_e[:, None]

        def profiled(C_ew):
            _, X = design(C_ew)
            c = np.linalg.lstsq(X, P, rcond=None)[0]
            e = P - X @ c
            return float(e @ e)

        opt = scipy.optimize.minimize_scalar(profiled, bounds=(0.0, _C_EW_MAX),
                                             method="bounded", options={"xatol": 1.0})
        C_ew = float(opt.x)
        Q_e, X = design(C_ew)
        coef = np.linalg.lstsq(X, P, rcond=None)[0]
        e = P - X @ coef
        status["power_map"] = f"C_ew by bounded search ({opt.message}); coefficients lstsq"
        # covariance over (C_ew, coef): Jacobian of the residual P - Q_e f
        h = 1.0
        dX = (design(C_ew + h)[1] - design(C_ew - h)[1]) / (2 * h)
        J = np.column_stack([dX @ coef, X])
        cov, lag = _sandwich(J, e, 1, k, D.segments, self.covariance, self.hac_bandwidth)
        steady = (np.abs(D.x[k + 1, 0] - D.x[k, 0]) / Ts < _STEADY_RATE) & \
                 (np.abs(dT) / Ts < _STEADY_RATE) & (P > 0.05 * P.max())
        mean_P = float(np.mean(P))
        quality = {
            "n": int(P.size), "rms_W": float(np.sqrt(np.mean(e**2))),
            "rms_pct": 100.0 * float(np.sqrt(np.mean(e**2))) / mean_P,
            "max_abs_W": float(np.max(np.abs(e))),
            "r2": 1.0 - float(e @ e) / float(np.sum((P - mean_P) ** 2)),
            "mean_P_W": mean_P, "n_steady": int(steady.sum()),
        }
        if steady.sum() >= 10:
            es, Ps = e[steady], P[steady]
            quality.update(steady_rms_pct=100.0 * float(np.sqrt(np.mean((es / Ps) ** 2))),
                           steady_max_pct=100.0 * float(np.max(np.abs(es / Ps))))
        domain = {"Q_e": (float(Q_e.min()), float(Q_e.max())),
                  "T_evap": (float(one.T_evap.min()), float(one.T_evap.max())),
                  "v_veh": (float(v.min()), float(v.max())),
                  "T_amb": (float(Ta.min()), float(Ta.max()))}
        assert tuple(domain) == tuple(n for n, _ in MAP_INPUTS)
        pm = PowerMap(coef=tuple(coef), stderr=tuple(np.sqrt(np.clip(np.diag(cov)[1:], 0,
                                                                     None))),
                      domain=domain, quality=quality)
        return pm, C_ew, cov, lag

    # ------------------------------------------------------------------ quality
    def _one_step_fit(self, D: _Data, prob: _OneStep, th, one, params) -> dict:
        out, _ = prob.predict(th)
        fits = {c: float(fit_percent(prob.Y[i], out[i])) for i, c in enumerate(CHANNELS)}
        k = D.rows
        Q_e = model.refrigerant_heat(one.Q_coil, D.x[k, 3], D.x[k + 1, 3], D.Ts, params)
        P_hat = model.compressor_power(Q_e, one.T_evap, D.d[k, 0], D.d[k, 1],
                                       params.power_map)
        fits["P_comp"] = float(fit_percent(D.P_comp[k], P_hat))
        if D.P_bl is not None:
            fits["P_bl"] = float(fit_percent(D.P_bl[k], model.blower_power(D.u[k, 0], params)))
        return fits


def _windows(D: _Data, window: int) -> np.ndarray:
    """(n_windows, window + 1) sample indices of consecutive windows inside the used rows."""
    used = np.zeros(D.x.shape[0], dtype=bool)
    used[D.rows] = True
    used[D.rows + 1] = True
    out = []
    for a, b in D.segments:
        idx = np.flatnonzero(used[a:b]) + a
        for s in range(0, idx.size - window, window):
            w = idx[s: s + window + 1]
            if w[-1] - w[0] == window:
                out.append(w)
    return np.array(out, dtype=int).reshape(-1, window + 1)


def _simulation_fit(D: _Data, p: EconParams, window: int) -> dict:
    """Fit % of ``window``-step open-loop simulations from the measured states."""
    idx = _windows(D, window)
    if idx.shape[0] == 0:
        return {}
    tr = simulate_windows(D.x, D.u, D.d, idx, p)
    out = {}
    for j, name in enumerate(model.STATES):
        out[name] = float(fit_percent(D.x[idx][..., j].ravel(), tr.x[..., j].ravel()))
    out["T_ain"] = float(fit_percent(D.T_ain[idx[:, :-1]].ravel(), tr.T_ain.ravel()))
    out["P_comp"] = float(fit_percent(D.P_comp[idx[:, :-1]].ravel(), tr.P_comp.ravel()))
    return out


def simulate_windows(x, u, d, idx: np.ndarray, p: EconParams) -> model.Trajectory:
    """Simulate every window ``idx`` (S, H + 1) from its measured first state (numpy)."""
    k = idx[:, :-1]
    return model.simulate(x[idx[:, 0]], u[k, 0], u[k, 1], d[k, 0], d[k, 1], p)

